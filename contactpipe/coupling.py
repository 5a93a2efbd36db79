"""The instantaneous contact (paper §4, middle loop): normal ↔ tangential until both hold.

With the history known, the current pressure p and shear q are found by alternating the
uncoupled normal problem (UNC, shear known) and the uncoupled tangential problem (UTC,
pressure known) — block Gauss-Seidel — until the pressure changes by less than the
tolerance relative to W. The loop always ends on a tangential solve, so Coulomb's law
holds exactly against the final pressure. When the pair does not couple (Dundurs β = 0)
one normal and one tangential solve are exact and no loop runs.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cg import box_cg
from .tangential import solve_scalar, solve_vector

__all__ = ["NormalResult", "InstantResult", "solve_normal", "solve_instant"]


@dataclass
class NormalResult:
    p: np.ndarray          # pressure [Pa]
    omega3: float          # normal approach [m]
    Ap: np.ndarray         # K33 ⊛ p [m]
    iterations: int
    residual: float
    converged: bool


def solve_normal(op, gap0, W, cell_area, p0, tol, max_iter) -> NormalResult:
    """Frictionless normal problem under force control (Polonsky & Keer 1999).

    Parameters
    ----------
    op : ContactOperator
    gap0 : ndarray
        Initial gap plus every known normal displacement [m].
    W : float
        Normal force [N].
    p0 : ndarray
        Warm start [Pa].
    """
    if W <= 0.0:
        return NormalResult(np.zeros_like(gap0), float(gap0.min()), np.zeros_like(gap0), 0,
                            0.0, True)
    if op.rigid:
        # no compliance for this increment (e.g. Kelvin-Voigt at the instant of a step load):
        # the load goes to the cells of least gap, the discrete form of a concentrated force
        lowest = gap0 <= gap0.min() + 1e-12 * max(np.ptp(gap0), 1e-300)
        p = np.where(lowest, W / (cell_area * np.count_nonzero(lowest)), 0.0)
        return NormalResult(p, float(gap0.min()), np.zeros_like(gap0), 0, 0.0, True)
    res = box_cg(op.normal, gap0, np.zeros_like(gap0), np.full_like(gap0, np.inf),
                 W / cell_area, p0, tol=tol, max_iter=max_iter, restore="scale")
    return NormalResult(res.x, res.multiplier, res.Ax, res.iterations, res.residual,
                        res.converged)


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


def solve_instant(op, gap, U, W, T, cell_area, mu, q_prev, u_prev, p_guess, plan, tol,
                  max_iter, max_passes, want_u=True) -> InstantResult:
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
    want_u : bool
        Unused (kept for callers); u is always assembled from what the solves computed,
        in-plane components only when a tangential model runs.
    """
    tang, coupled = plan.tangential, plan.coupling != "none"
    vector = tang == "vector"
    T = np.asarray(T, dtype=float)
    its = 0
    q = q_prev.copy() if tang != "none" else np.zeros_like(q_prev)

    def normal(q):
        u3q = op.coupling_to_normal(q[0], q[1] if vector else None) \
            if (coupled and np.any(q)) else 0.0
        n = solve_normal(op, gap + U[2] + u3q, W, cell_area, p_guess_[0], tol, max_iter)
        return n, u3q

    p_guess_ = [p_guess]
    n, u3q = normal(q)
    its += n.iterations
    worst = n.residual
    if not n.converged:
        return InstantResult(n.p, q, U, n.omega3, np.zeros(2), its, 1, False, n.residual,
                             "normal")
    p = n.p
    domega = np.zeros(2)
    t_res = None
    passes = 1
    if tang != "none":
        passes = 0
        while True:
            passes += 1
            up = op.coupling_to_tangential(p, two_components=vector) if coupled else None
            if op.rigid:
                # no compliance: any q within the bounds carrying T; take q ∝ p
                q = np.zeros_like(q_prev)
                if W > 0:
                    q[0], q[1] = p * (T[0] / W), p * (T[1] / W)
                t_res = None
            elif vector:
                b = U[:2] - u_prev[:2] + (up if up is not None else 0.0)
                t_res = solve_vector(op, b, mu * p, T, cell_area, q, tol, max_iter)
            else:
                b = U[0] - u_prev[0] + (up[0] if up is not None else 0.0)
                t_res = solve_scalar(op, b, mu * p, T[0], cell_area, q[0], tol, max_iter)
            if t_res is not None:
                its += t_res.iterations
                worst = max(worst, t_res.residual)
                if not t_res.converged:
                    return InstantResult(p, t_res.q, U, n.omega3, t_res.domega, its, passes,
                                         False, t_res.residual, "tangential")
                q, domega = t_res.q, t_res.domega
            if not coupled:
                break
            p_guess_[0] = p
            n, u3q = normal(q)
            its += n.iterations
            if not n.converged:
                return InstantResult(n.p, q, U, n.omega3, domega, its, passes, False,
                                     n.residual, "normal")
            change = np.abs(n.p - p).sum() * cell_area / max(W, 1e-300)
            p = n.p
            if change < tol:
                # final tangential solve against the final pressure (Coulomb exact)
                up = op.coupling_to_tangential(p, two_components=vector)
                if not op.rigid:
                    if vector:
                        b = U[:2] - u_prev[:2] + up
                        t_res = solve_vector(op, b, mu * p, T, cell_area, q, tol, max_iter)
                    else:
                        t_res = solve_scalar(op, U[0] - u_prev[0] + up[0], mu * p, T[0],
                                             cell_area, q[0], tol, max_iter)
                    its += t_res.iterations
                    q, domega = t_res.q, t_res.domega
                break
            if passes >= max_passes:
                return InstantResult(p, q, U, n.omega3, domega, its, passes, False, change,
                                     "coupling")

    u = U.copy()
    if op.rigid:            # no compliance for this increment: the known part is all
        return InstantResult(p, q, u, n.omega3, domega, its, passes, True, worst)
    u[2] += n.Ap
    if tang != "none":
        if coupled:
            u[2] += op.coupling_to_normal(q[0], q[1] if vector else None)
        if vector and t_res is not None:
            u[:2] += t_res.Aq                      # reuse the solver's A q
            if coupled:
                u[:2] += op.coupling_to_tangential(p)
        else:
            u[:2] += op.in_plane(q[0], q[1] if vector else None, p if coupled else None)
    return InstantResult(p, q, u, n.omega3, domega, its, passes, True, worst)
