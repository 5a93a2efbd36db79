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

The caller gives the solver limits as one :class:`Tolerances` and what it knows of the
previous instant as one :class:`Previous`; :func:`solve_instant` returns an
:class:`InstantResult` whose ``failed`` names the sub-problem that stopped
(``"normal"``, ``"tangential"`` or ``"coupling"``) when ``converged`` is False.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .normal import NormalResult, solve_normal
from .tangential import solve_scalar, solve_vector

__all__ = ["InstantResult", "Previous", "Tolerances", "solve_instant"]

#: Loosest inner tolerance of the first passes of a coupled instant [1].
FIRST_PASS_TOLERANCE = 1e-4
#: Inner tolerance of a later pass, as a fraction of the last relative pressure change [1].
PASS_TOLERANCE_FRACTION = 1e-3


@dataclass(frozen=True)
class Tolerances:
    """The limits of one instant's solves.

    Attributes
    ----------
    tol : float
        Relative tolerance [1] of every inner solve (force balance and complementarity)
        and of the pressure change between coupling passes (Σ|Δp|·cell / W).
    max_iter : int
        Iterations allowed to one inner solve.
    max_passes : int
        Normal-tangential passes allowed to a coupled instant.
    """

    tol: float
    max_iter: int
    max_passes: int


@dataclass(frozen=True)
class Previous:
    """What the solve of an instant takes from the instant before.

    Attributes
    ----------
    q : ndarray (2, N1, N2)
        Shear of the previous instant [Pa]: the path memory of friction and the warm start.
    u : ndarray (3, N1, N2)
        Relative displacement of the previous instant [m]: slip is measured from it.
    p_guess : ndarray (N1, N2)
        Warm start of the pressure [Pa].
    normal : NormalResult, optional
        The previous normal solution, reused as it is. Give it only when the normal
        problem is known to be unchanged (no coupling, no memory, the same W).
    """

    q: np.ndarray
    u: np.ndarray
    p_guess: np.ndarray
    normal: NormalResult | None = None


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


class _Instant:
    """The two uncoupled solves of one instant, with what they share."""

    def __init__(self, op, gap, U, W, T, cell_area, mu, plan, previous, limits):
        self.op, self.gap, self.U, self.W, self.cell = op, gap, U, W, cell_area
        self.T = np.asarray(T, dtype=float)
        self.mu, self.prev, self.lim = mu, previous, limits
        self.tang = plan.tangential
        self.coupled = plan.coupling != "none"
        self.vector = self.tang == "vector"
        self.its, self.passes = 0, 1

    def normal(self, q, p_start, tol, Ap0=None):
        """UNC: the pressure under the gap opened or closed by the shear q."""
        op = self.op
        u3q = (op.coupling_to_normal(q[0], q[1] if self.vector else None)
               if self.coupled and np.any(q) else 0.0)
        return solve_normal(op, self.gap + self.U[2] + u3q, self.W, self.cell, p_start, tol,
                            self.lim.max_iter, Ap0=Ap0)

    def tangential(self, p, q, tol, Aq0=None):
        """UTC: the shear under the bound mu p; returns it with (u1, u2) from p (or None)."""
        op, U, u_prev = self.op, self.U, self.prev.u
        up = op.coupling_to_tangential(p) if self.coupled else None     # (u1, u2) from p
        bound = self.mu * p
        if self.vector:
            b = U[:2] - u_prev[:2] + (up if up is not None else 0.0)
            return solve_vector(op, b, bound, self.T, self.cell, q, tol, self.lim.max_iter,
                                Aq0), up
        b = U[0] - u_prev[0] + (up[0] if up is not None else 0.0)
        return solve_scalar(op, b, bound, self.T[0], self.cell, q[0], tol, self.lim.max_iter,
                            None if Aq0 is None else Aq0[0]), up

    def failure(self, what, res, p, q, domega):
        return InstantResult(p, q, self.U, getattr(res, "omega3", 0.0), domega, self.its,
                             self.passes, False, res.residual, what)

    def displacement(self, n, q, t_res, up):
        """The relative displacement from what the solves computed (few extra FFTs)."""
        op, u = self.op, self.U.copy()
        if op.rigid:
            return u
        u[2] += n.Ap
        if self.tang != "none":
            if self.coupled:
                u[2] += op.coupling_to_normal(q[0], q[1] if self.vector else None)
                u[:2] += up
            if self.vector:
                u[:2] += t_res.Aq                                # [K11 K12; K21 K22] q
            else:
                u[0] += t_res.Aq[0]                              # K11 q1
                u[1] += op.conv.convolve(op.k["21"], q[0])       # K21 q1
        return u


def solve_instant(op, gap, U, W, T, cell_area, mu, plan, previous: Previous,
                  limits: Tolerances) -> InstantResult:
    """Solve one instant of the coupled contact.

    Parameters
    ----------
    op : ContactOperator
        Operator of the current traction (creep weight of the instant included).
    gap : ndarray (N1, N2)
        Initial composite gap hi [m].
    U : ndarray (3, N1, N2)
        Known relative displacement (viscoelastic history) [m].
    W : float
        Normal force [N].
    T : array_like (2,)
        Tangential force [N].
    cell_area : float
        Area of one cell [m²].
    mu : float
        Friction coefficient [1].
    plan : Plan
        The sub-models (``tangential``: none/scalar/vector; ``coupling``).
    previous : Previous
        The previous instant's shear, displacement, pressure guess (and normal solution).
    limits : Tolerances
        Tolerance, iterations per solve, coupling passes.

    Returns
    -------
    InstantResult
        ``converged`` False with ``failed`` naming the sub-problem that stopped: "normal",
        "tangential" (also when |T| > mu W (1 + tol): no shear within the bounds carries
        it; ``residual`` is then (|T| - mu W) / (mu W)), or "coupling" (the passes did not
        settle in ``limits.max_passes``).
    """
    s = _Instant(op, gap, U, W, T, cell_area, mu, plan, previous, limits)
    tol = limits.tol
    q = previous.q.copy() if s.tang != "none" else np.zeros_like(previous.q)
    worst, change = 0.0, np.inf

    # -- normal -------------------------------------------------------------------------
    n = previous.normal if previous.normal is not None else s.normal(q, previous.p_guess, tol)
    if previous.normal is None:
        s.its += n.iterations
        worst = n.residual
    if not n.converged:
        return s.failure("normal", n, n.p, q, np.zeros(2))
    p = n.p
    domega = np.zeros(2)
    t_res, up = None, None
    excess = float(np.hypot(*s.T)) - mu * W
    if s.tang != "none" and excess > tol * mu * W:
        # no shear within the bounds mu p carries T: the contact slides as a whole
        return InstantResult(p, q, U, n.omega3, domega, s.its, s.passes, False,
                             excess / max(mu * W, 1e-300), "tangential", n)

    # -- tangential, and the coupling loop ------------------------------------------------
    if s.tang != "none" and op.rigid:
        # no compliance: any q within the bounds carrying T; take q ∝ p
        if W > 0:
            q = np.stack([p * (s.T[0] / W), p * (s.T[1] / W)])
    elif s.tang != "none":
        inner = max(tol, FIRST_PASS_TOLERANCE) if s.coupled else tol
        t_res, up = s.tangential(p, q, inner)
        s.its += t_res.iterations
        if not t_res.converged:
            return s.failure("tangential", t_res, p, t_res.q, t_res.domega)
        q, domega = t_res.q, t_res.domega
        while s.coupled:
            s.passes += 1
            if s.passes > limits.max_passes:
                return InstantResult(p, q, U, n.omega3, domega, s.its, s.passes - 1, False,
                                     change, "coupling", n)
            n = s.normal(q, p, inner, Ap0=n.Ap)
            s.its += n.iterations
            if not n.converged:
                return s.failure("normal", n, n.p, q, domega)
            change = float(np.abs(n.p - p).sum()) * cell_area / max(W, 1e-300)
            p = n.p
            last = inner == tol
            inner = min(inner, max(tol, PASS_TOLERANCE_FRACTION * change))
            t_res, up = s.tangential(p, q, inner, Aq0=t_res.Aq)
            s.its += t_res.iterations
            if not t_res.converged:
                return s.failure("tangential", t_res, p, t_res.q, t_res.domega)
            q, domega = t_res.q, t_res.domega
            if change < tol and last:
                break
        worst = max(worst, t_res.residual)

    u = s.displacement(n, q, t_res, up)
    return InstantResult(p, q, u, n.omega3, domega, s.its, s.passes, True, worst, normal=n)
