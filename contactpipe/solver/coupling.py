"""The instantaneous contact (paper §4, middle loop): normal ↔ tangential until both hold.

With the history known, the current pressure p and shear q are found by alternating the
uncoupled normal problem (UNC, shear known) and the uncoupled tangential problem (UTC,
pressure known) — block Gauss-Seidel — until the pressure changes by less than the
tolerance relative to W. The loop always ends on a tangential solve, so Coulomb's law
holds exactly against the final pressure. When the pair does not couple (Dundurs β = 0)
one normal and one tangential solve are exact and no loop runs.

Inexact passes: while the pressure still moves by much more than the tolerance, the inner
solves stop at a thousandth of that change (never looser than 1e-4, never tighter than the
tolerance); the last passes run at the full tolerance. Warm starts carry their operator
products (A p, A q) from pass to pass. This cuts the FFT pairs of a coupled
step without changing its converged answer.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .normal import NormalResult, solve_normal
from .tangential import solve_scalar, solve_vector

__all__ = ["InstantResult", "solve_instant"]


@dataclass
class InstantResult:
    p: np.ndarray            # (N1, N2) [Pa]
    q: np.ndarray            # (2, N1, N2) [Pa]
    u: np.ndarray            # (3, N1, N2) relative displacement [m]
    omega3: float            # [m]
    domega: np.ndarray       # (2,) rigid shift increment [m]
    iterations: int          # inner iterations, all solves
    passes: int              # normal-tangential passes (1 without coupling)
    converged: bool
    residual: float          # worst inner residual, or the last pressure change
    failed: str = ""         # which solve failed, if any
    normal: NormalResult | None = None   # the last normal solve (reusable by the caller)


def solve_instant(op, gap, U, W, T, cell_area, mu, q_prev, u_prev, p_guess, plan, tol,
                  max_iter, max_passes, normal=None) -> InstantResult:
    """Solve one instant of the coupled contact.

    Parameters
    ----------
    op : ContactOperator
        Operator of the current traction (creep weight of the instant included).
    gap : ndarray
        Initial composite gap hi [m].
    U : ndarray (3, N1, N2)
        Known relative displacement (viscoelastic history) [m].
    W : float
        Normal force [N].
    T : array_like (2,)
        Tangential force [N].
    mu : float
        Friction coefficient [1].
    q_prev, u_prev : ndarray
        Shear [Pa] and relative displacement [m] of the previous instant (path memory).
    p_guess : ndarray
        Warm start of the pressure [Pa].
    plan : Plan
    normal : NormalResult, optional
        The previous instant's normal solution, reused as it is when the caller knows the
        normal problem has not changed (no coupling, no memory, same W).
    """
    tang, coupled = plan.tangential, plan.coupling != "none"
    vector = tang == "vector"
    T = np.asarray(T, dtype=float)
    q = q_prev.copy() if tang != "none" else np.zeros_like(q_prev)
    its, passes, worst, change = 0, 1, 0.0, np.inf

    def normal_solve(q, p_start, tol_n, Ap0=None):
        u3q = (op.coupling_to_normal(q[0], q[1] if vector else None)
               if coupled and np.any(q) else 0.0)
        return solve_normal(op, gap + U[2] + u3q, W, cell_area, p_start, tol_n, max_iter,
                            Ap0=Ap0)

    def tangential_solve(p, q, tol_t, Aq0=None):
        up = op.coupling_to_tangential(p) if coupled else None     # (u1, u2) from p
        bound = mu * p
        if vector:
            b = U[:2] - u_prev[:2] + (up if up is not None else 0.0)
            return solve_vector(op, b, bound, T, cell_area, q, tol_t, max_iter, Aq0), up
        b = U[0] - u_prev[0] + (up[0] if up is not None else 0.0)
        return solve_scalar(op, b, bound, T[0], cell_area, q[0], tol_t, max_iter,
                            None if Aq0 is None else Aq0[0]), up

    def failure(what, res, p_, q_, dom):
        return InstantResult(p_, q_, U, res.omega3 if hasattr(res, "omega3") else 0.0, dom,
                             its, passes, False, res.residual, what)

    # -- normal -------------------------------------------------------------------------
    n = normal if normal is not None else normal_solve(q, p_guess, tol)
    if normal is None:
        its += n.iterations
        worst = n.residual
    if not n.converged:
        return failure("normal", n, n.p, q, np.zeros(2))
    p = n.p
    domega = np.zeros(2)
    t_res, up = None, None

    # -- tangential, and the coupling loop ------------------------------------------------
    if tang != "none" and op.rigid:
        # no compliance: any q within the bounds carrying T; take q ∝ p
        if W > 0:
            q = np.stack([p * (T[0] / W), p * (T[1] / W)])
    elif tang != "none":
        inner = max(tol, 1e-4) if coupled else tol
        t_res, up = tangential_solve(p, q, inner)
        its += t_res.iterations
        if not t_res.converged:
            return failure("tangential", t_res, p, t_res.q, t_res.domega)
        q, domega = t_res.q, t_res.domega
        while coupled:
            passes += 1
            if passes > max_passes:
                return InstantResult(p, q, U, n.omega3, domega, its, passes - 1, False,
                                     change, "coupling", n)
            n = normal_solve(q, p, inner, Ap0=n.Ap)
            its += n.iterations
            if not n.converged:
                return failure("normal", n, n.p, q, domega)
            change = float(np.abs(n.p - p).sum()) * cell_area / max(W, 1e-300)
            p = n.p
            last = inner == tol
            inner = min(inner, max(tol, 1e-3 * change))
            t_res, up = tangential_solve(p, q, inner, Aq0=t_res.Aq)
            its += t_res.iterations
            if not t_res.converged:
                return failure("tangential", t_res, p, t_res.q, t_res.domega)
            q, domega = t_res.q, t_res.domega
            if change < tol and last:
                break
        worst = max(worst, t_res.residual)

    # -- the relative displacement from what the solves computed (few extra FFTs) ----------
    u = U.copy()
    if op.rigid:
        return InstantResult(p, q, u, n.omega3, domega, its, passes, True, worst, normal=n)
    u[2] += n.Ap
    if tang != "none":
        if coupled:
            u[2] += op.coupling_to_normal(q[0], q[1] if vector else None)
            u[:2] += up
        if vector:
            u[:2] += t_res.Aq                                # [K11 K12; K21 K22] q
        else:
            u[0] += t_res.Aq[0]                              # K11 q1
            k = op.k
            u[1] += op.conv.convolve(k["21"], q[0])          # K21 q1
    return InstantResult(p, q, u, n.omega3, domega, its, passes, True, worst, normal=n)
