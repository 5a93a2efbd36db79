"""The instantaneous contact (paper §4, middle loop): normal ↔ tangential until both hold.

With the history known, the current pressure p and shear q are found by alternating the
uncoupled normal problem (UNC, shear known) and the uncoupled tangential problem (UTC,
pressure known) — block Gauss-Seidel — until the pressure changes by less than the
tolerance relative to W. The loop ends on a tangential solve, so Coulomb's law holds
exactly against the final pressure. When the pair does not couple (Dundurs β = 0)
one normal and one tangential solve are exact and no loop runs.

Inexact passes: while the pressure still moves by much more than the tolerance, the inner
solves stop at a thousandth of that change (never looser than 1e-4, never tighter than the
tolerance); the last passes run at the full tolerance, and so does the pass before the
last one allowed (only a pass after one at the full tolerance can settle the instant; a
pass limit of one or two would otherwise never settle). Warm starts carry their operator
products (A p, A q) from pass to pass. This cuts the FFT pairs of a coupled
step without changing its converged answer.

The joint solve: a coupled instant under force control of W and T alone (uniform μ) is
solved instead as one constrained problem over (p, q1) — the scalar form — or (p, q1, q2)
— the vector form — with only the bound μp lagged between passes
(:mod:`contactpipe.solver.joint`; from nothing in contact, a normal solve starts it), its
shear put on the final pressure's bound by its last step and ended by
:func:`contactpipe.solver.joint.finish` (:func:`~contactpipe.solver.joint.finish_vector`:
Coulomb's law exact as after the passes above, without another solve): the same answer
within the tolerance, in fewer FFT pairs (docs/design-choices.md, D11 and D15; today's
figures: ``contactpipe bench fretting paper-fig3``, which writes them to
``benchmarks/results/bench-<case>.csv``).
Where it does not converge, or in the vector form where no cell sticks any more, the
block Gauss-Seidel passes take over. ``passes`` then counts the joint passes.

The caller gives the solver limits as one :class:`Tolerances` and what it knows of the
previous instant as one :class:`Previous`; :func:`solve_instant` returns an
:class:`InstantResult` whose ``failed`` names the sub-problem that stopped
(``"normal"``, ``"tangential"`` or ``"coupling"``) when ``converged`` is False.

The six freedoms of body 1 relative to body 2 (paper eqs. 1-4) reach the solver as one
:class:`Controls`: each is force-controlled (a target W, T1, T2, M1, M2, M3) or
displacement-controlled (a known ω3, ω1, ω2, φ1, φ2, φ3). The normal sub-problem carries
(W, M1, M2 | ω3, φ1, φ2), the tangential one (T1, T2, M3 | ω1, ω2, φ3): force control is a
constraint row of the inner problem whose multiplier is the rigid motion, displacement
control a known rigid motion in its linear term. Without :class:`Controls` (W and T given)
the rotations are held at zero, as the solver always did.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .cg import Constraints
from .joint import finish, finish_vector, solve_joint, solve_joint_vector
from .normal import NormalControl, NormalResult, solve_normal
from .options import TUNING, Tuning
from .tangential import TangentialResult, follow_bound, force_rows, solve_scalar, solve_vector

__all__ = ["Controls", "FREEDOMS", "InstantResult", "Previous", "Tolerances",
           "follow_bound", "solve_instant"]

#: The six freedoms, in the order of :class:`Controls`' arrays: (force, motion) names.
FREEDOMS = (("W", "omega3"), ("T1", "omega1"), ("T2", "omega2"), ("M1", "phi1"),
            ("M2", "phi2"), ("M3", "phi3"))

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
    tuning : Tuning
        The solver core's switches and constants (:class:`~.options.Tuning`), handed
        down to every solve of the instant (None: the defaults).
    """

    tol: float
    max_iter: int
    max_passes: int
    tuning: Tuning = TUNING

    def __post_init__(self):
        if self.tuning is None:
            object.__setattr__(self, "tuning", TUNING)


@dataclass(frozen=True)
class Controls:
    """How the six freedoms of body 1 relative to body 2 are held at one instant.

    Attributes
    ----------
    force : ndarray (6,)
        W [N], T1, T2 [N], M1, M2, M3 [N m] (:data:`FREEDOMS` order); NaN where the
        freedom is displacement-controlled. M1 = Δ Σ p x2, M2 = Δ Σ p x1,
        M3 = Δ Σ (q2 x1 − q1 x2).
    motion : ndarray (6,)
        ω3 [m], ω1, ω2 [m], φ1, φ2, φ3 [rad] (totals since the start); NaN where the
        freedom is force-controlled. The gap is h = hi + u3 − ω3 − φ1 x2 − φ2 x1; φ3
        moves body 1's surface point by (−φ3 x2, φ3 x1) in the slip (eq. 4).
    x1, x2 : ndarray, optional
        Cell centres (N1,), (N2,) [m]: the moment arms (needed when a moment is
        force-controlled or a rotation is not zero).
    """

    force: np.ndarray
    motion: np.ndarray
    x1: np.ndarray | None = None
    x2: np.ndarray | None = None

    @classmethod
    def forces(cls, W, T) -> Controls:
        """W and T force-controlled, the three rotations held at zero."""
        T = np.asarray(T, dtype=float)
        nan = np.nan
        return cls(np.array([float(W), T[0], T[1], nan, nan, nan]),
                   np.array([nan, nan, nan, 0.0, 0.0, 0.0]))

    def is_force(self, i: int) -> bool:
        """Freedom ``i`` (:data:`FREEDOMS` order) is force-controlled."""
        return not np.isnan(self.force[i])

    def normal(self) -> NormalControl | None:
        """The normal sub-problem's part (None: W force-controlled, φ1 = φ2 = 0)."""
        ctl = NormalControl(self.force[[0, 3, 4]], self.motion[[0, 3, 4]], self.x1, self.x2)
        return None if ctl.legacy else ctl

    @property
    def tangential_legacy(self) -> bool:
        """T force-controlled and φ3 held at zero: the force rows alone."""
        return self.is_force(1) and not self.is_force(5) and self.motion[5] == 0.0

    def arms(self):
        """(x1, x2) on the grid (N1, N2) and the normalising length L [m]."""
        assert self.x1 is not None and self.x2 is not None, "moment arms x1, x2 needed"
        X1, X2 = np.meshgrid(self.x1, self.x2, indexing="ij")
        L = max(float(np.abs(self.x1).max()), float(np.abs(self.x2).max()), 1e-300)
        return X1, X2, L


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
        problem is known to be unchanged (no coupling, no memory, the same controls).
    motion : ndarray (6,), optional
        The rigid motions reached at the previous instant (ω3, ω1, ω2, φ1, φ2, φ3) [m,
        rad]: a displacement-controlled tangential freedom moves by the difference.
        Absent: zeros (from rest).
    p_start : ndarray (N1, N2), optional
        The joint solve's pressure start [Pa] where it differs from ``p_guess``: the
        pressure continued along a straight load path
        (:func:`contactpipe.solver.warm_start.continued_start`). The normal solves of the
        block Gauss-Seidel passes start from ``p_guess`` whatever it is.
    """

    q: np.ndarray
    u: np.ndarray
    p_guess: np.ndarray
    normal: NormalResult | None = None
    motion: np.ndarray | None = None
    p_start: np.ndarray | None = None


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
    phi: np.ndarray = field(default_factory=lambda: np.zeros(2))   # (φ1, φ2) reached [rad]
    dphi3: float = 0.0       # rotation increment Δφ3 [rad]
    sliding: tuple | None = None   # failed "sliding": (W reached [N], |T| [N], the
                                   # largest |T| the bounds carry, μW or Σμp Δ [N])


class _Instant:
    """The two uncoupled solves of one instant, with what they share."""

    def __init__(self, op, gap, U, controls, cell_area, mu, plan, previous, limits):
        self.op, self.gap, self.U, self.cell = op, gap, U, cell_area
        self.ctl = controls
        self.W = float(controls.force[0])          # NaN under approach control
        self.T = np.array(controls.force[1:3], dtype=float)
        self.mu, self.prev, self.lim = mu, previous, limits
        self.tang = plan.tangential
        self.coupled = plan.coupling != "none"
        self.vector = self.tang == "vector"
        self.its, self.passes = 0, 1
        self.normal_ctl = controls.normal()
        self.rows = None if controls.tangential_legacy else self._tangential_rows()
        self.bound = None      # the bound mu p of the last tangential solve [Pa]

    def normal(self, q, p_start, tol, Ap0=None):
        """UNC: the pressure under the gap opened or closed by the shear q."""
        op = self.op
        # an instant without compliance (no body with instantaneous elasticity) moves
        # nothing: the shear opens no gap
        u3q = (op.coupling_to_normal(q[0], q[1] if self.vector else None)
               if self.coupled and not op.rigid and np.any(q) else 0.0)
        return solve_normal(op, self.gap + self.U[2] + u3q, self.W, self.cell, p_start, tol,
                            self.lim.max_iter, Ap0=Ap0, control=self.normal_ctl)

    def _tangential_rows(self):
        """(rows of the force-controlled tangential freedoms, the known rigid motion
        increment (2, N1, N2) of the displacement-controlled ones, the row meanings)."""
        ctl, shape = self.ctl, self.gap.shape
        prev = self.prev.motion if self.prev.motion is not None else np.zeros(6)
        known = np.zeros((2,) + shape)
        rows: list[np.ndarray] = []
        targets: list[float] = []
        which: list[int] = []
        if ctl.is_force(1):
            force = force_rows(shape, self.T, self.cell).rows
            assert force is not None
            rows.extend(force[: 2 if self.vector else 1])
            targets.extend((self.T / self.cell)[: 2 if self.vector else 1])
            which.extend([1, 2][: 2 if self.vector else 1])
        else:
            d = np.asarray(ctl.motion[1:3], float) - prev[1:3]
            known += d[:, None, None]
        if ctl.is_force(5) or ctl.motion[5] != prev[5]:
            X1, X2, L = ctl.arms()
            twist = np.stack([-X2, X1])
            if ctl.is_force(5):
                rows.append(twist / L)
                targets.append(ctl.force[5] / self.cell / L)
                which.append(5)
            else:
                known += (ctl.motion[5] - prev[5]) * twist
        lead = (2,) if self.vector else ()
        rows = [r if self.vector else r[0] for r in rows]
        con = Constraints(np.array(rows).reshape((len(rows),) + lead + shape), targets,
                          sums=all(w in (1, 2) for w in which))
        return con, known, which

    def tangential(self, p, q, tol, Aq0=None, final=True):
        """UTC: the shear under the bound mu p; returns it with (u1, u2) from p (or None).
        ``final`` False: a pass that is not the instant's last, whose A q the next pass
        does not use (the vector form then skips its exact recomputation)."""
        op, U, u_prev = self.op, self.U, self.prev.u
        up = op.coupling_to_tangential(p) if self.coupled else None     # (u1, u2) from p
        bound = self.mu * p
        if self.bound is not None and self.lim.tuning.follow_bound:
            # both CGs tell slip from stick by |q| = mu p: a pass keeps the slip cells on
            # their moved bound, or they start as stick cells and slide back
            # (several times the pairs of a pass: docs/design-choices.md, D18)
            q = follow_bound(q, self.bound, bound)
        if self.bound is not None:
            Aq0 = None
        self.bound = bound
        tuning = self.lim.tuning
        exact = final or not tuning.lagged_passes
        if self.vector:
            b = U[:2] - u_prev[:2] + (up if up is not None else 0.0)
            if self.rows is not None:
                con, known, _ = self.rows
                return solve_vector(op, b - known, bound, None, self.cell, q, tol,
                                    self.lim.max_iter, Aq0, rows=con, exact=exact,
                                    tuning=tuning), up
            return solve_vector(op, b, bound, self.T, self.cell, q, tol, self.lim.max_iter,
                                Aq0, exact=exact, tuning=tuning), up
        b = U[0] - u_prev[0] + (up[0] if up is not None else 0.0)
        T1 = self.T[0]
        if self.rows is not None:
            con, known, _ = self.rows
            b, T1 = b - known[0], (self.T[0] if con.m else None)
        return solve_scalar(op, b, bound, T1, self.cell, q[0], tol, self.lim.max_iter,
                            None if Aq0 is None else Aq0[0],
                            precondition=tuning.precondition), up

    def motions(self, t_res):
        """(Δω1, Δω2, Δφ3) of a tangential solution: multipliers or known increments."""
        if self.rows is None:
            return t_res.domega, 0.0
        con, _, which = self.rows
        prev = self.prev.motion if self.prev.motion is not None else np.zeros(6)
        inc = np.concatenate([[0.0], np.asarray(self.ctl.motion[1:], float) - prev[1:]])
        inc = np.where(np.isnan(inc), 0.0, inc)
        lam = t_res.multipliers if t_res.multipliers is not None else t_res.domega[:con.m]
        if 1 in which and not self.vector:
            lam = [t_res.domega[0]] + list(lam[1:])
        _, _, L = self.ctl.arms() if 5 in which else (None, None, 1.0)
        for j, i in enumerate(which):
            inc[i] = lam[j] / (L if i == 5 else 1.0)
        return inc[1:3].copy(), float(inc[5])

    def joint_applies(self) -> bool:
        """The instant can be solved as one problem over (p, q) (:mod:`.joint`): a coupled
        instant under force control of W > 0 and T alone (the scalar form: T1), with a
        uniform μ and |T| within μW; never with ``tuning.joint`` off."""
        return (self.lim.tuning.joint and self.coupled and self.tang in ("scalar", "vector")
                and not self.op.rigid
                and self.ctl.is_force(0) and self.normal_ctl is None and self.rows is None
                and np.ndim(self.mu) == 0 and self.W > 0.0
                and (float(np.hypot(*self.T)) if self.vector else abs(self.T[0]))
                <= self.mu * self.W)

    def joint(self, tol):
        """The instant by :func:`.joint.solve_joint` (:func:`.joint.solve_joint_vector`),
        its shear on the final pressure's bound, ended by :func:`.joint.finish`
        (:func:`.joint.finish_vector`); None when the joint solve did not converge (the
        block Gauss-Seidel passes then take over from the start)."""
        prev, U, op, mu, lim = self.prev, self.U, self.op, self.mu, self.lim
        p0 = prev.p_guess if prev.p_start is None else prev.p_start
        if not np.any(p0 > 0):
            # nothing in contact yet (a preload's first sub-step): the pressure of the
            # normal problem alone, by its multilevel start, begins the joint solve
            n = self.normal(prev.q, p0, max(tol, lim.tuning.cold_start_tolerance))
            self.its += n.iterations
            if not n.converged:
                return None
            p0 = n.p
        if self.vector:
            b = np.stack([self.gap + U[2], U[0] - prev.u[0], U[1] - prev.u[1]])
            j = solve_joint_vector(op, b, self.W, self.T, self.cell, mu, p0, prev.q, tol,
                                   lim.max_iter, lim.max_passes, lim.tuning)
        else:
            b = np.stack([self.gap + U[2], U[0] - prev.u[0]])
            j = solve_joint(op, b, self.W, self.T[0], self.cell, mu, p0, prev.q[0], tol,
                            lim.max_iter, lim.max_passes, lim.tuning)
        self.its += j.iterations
        if not j.converged:
            return None
        if self.vector:
            q, u_t, domega = finish_vector(j, b[1:], self.T, self.cell)
        else:
            q = np.zeros_like(prev.q)
            q[0], u_t, domega1 = finish(op, j, b[1])
            domega = np.array([domega1, 0.0])
        n = NormalResult(j.p, j.omega3, u_t[2], j.iterations, j.residual, True)
        return InstantResult(j.p, q, U + u_t, j.omega3, np.asarray(domega, dtype=float),
                             self.its, j.passes, True, j.residual, normal=n, dphi3=0.0)

    def capacity(self, p, W):
        """The largest |T| the bounds can carry: mu W, or Σ mu p Δ with a mapped mu [N]."""
        if np.ndim(self.mu) == 0:
            return self.mu * W
        return float(np.sum(self.mu * p)) * self.cell

    def rigid_shear(self, p, W, q):
        """The shear of an instant without compliance (φ(0) = 0): any q within the bounds
        that carries the force rows. Under force control of T, q ∝ p; under displacement
        control the known rigid slip decides: q = μp along it where it is not zero (the
        contact slides), else the previous shear q on its bound (nothing moves)."""
        if self.ctl.is_force(1):
            return np.stack([p * (self.T[0] / W), p * (self.T[1] / W)]) if W > 0 else q
        assert self.rows is not None     # T displacement-controlled: not the legacy rows
        _, known, _ = self.rows
        bound = self.mu * p
        mag = np.hypot(known[0], known[1])
        if np.any(mag > 0.0):
            out = np.where(mag > 0.0, bound / np.where(mag > 0.0, mag, 1.0), 0.0) * known
        else:
            out = np.where(bound > 0.0, q, 0.0)
        size = np.hypot(out[0], out[1])
        return out * np.where(size > bound, bound / np.where(size > 0.0, size, 1.0), 1.0)

    def slides(self, n, q, W):
        """The failed result "sliding" where no shear within the bounds μp of the
        pressure n.p carries a force-controlled T (|T| above μW by more than the
        tolerance): the contact slides as a whole. Its residual is the excess relative to
        |T| (> 0 here), finite also where the pressure carries nothing (an approach that
        leaves the contact open). None where the bounds carry T."""
        capacity, T = self.capacity(n.p, W), float(np.hypot(*self.T))
        excess = T - capacity
        if excess <= self.lim.tol * capacity:
            return None
        return InstantResult(n.p, q, self.U, n.omega3, np.zeros(2), self.its, self.passes,
                             False, excess / T, "sliding", n, sliding=(W, T, capacity))

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


def _pressure_change(p_new, p, W, cell_area) -> float:
    """Σ|Δp| Δ / W [1], the change of a coupling pass; where the contact opened under
    approach control (W = 0), relative to the larger pressure's force instead (0 when
    both are zero), so that it stays finite."""
    moved = float(np.abs(p_new - p).sum()) * cell_area
    if moved == 0.0:
        return 0.0
    size = W if W > 0.0 else max(float(p_new.sum()), float(p.sum())) * cell_area
    return moved / size


@dataclass
class _PassState:
    """Where the tangential solve and the coupling passes left an instant."""

    n: NormalResult             # the last normal solution
    p: np.ndarray               # its pressure [Pa]
    q: np.ndarray               # the last shear [Pa]
    t_res: TangentialResult     # the last tangential solution
    up: np.ndarray | None       # (u1, u2) from p of a coupled pair [m]
    domega: np.ndarray          # (Δω1, Δω2) [m]
    dphi3: float                # Δφ3 [rad]

    def fields(self):
        return self.n, self.p, self.q, self.t_res, self.up, self.domega, self.dphi3


def _passes(s: _Instant, n, q):
    """The tangential solve from the normal solution ``n`` and, for a coupled pair, the
    block Gauss-Seidel passes (module notes): a :class:`_PassState`, or the failed
    :class:`InstantResult` of the solve that stopped or of passes that did not settle."""
    ctl, limits, cell_area, U = s.ctl, s.lim, s.cell, s.U
    tol, tuning, p = limits.tol, limits.tuning, n.p
    # the pass before the last one allowed runs at the full tolerance, so that the
    # last can settle the step (a pass settles only after one at the full tolerance)
    inner = max(tol, tuning.passes_first_tolerance) if s.coupled and limits.max_passes > 2 \
        else tol
    t_res, up = s.tangential(p, q, inner, final=not s.coupled)
    s.its += t_res.iterations
    if not t_res.converged:
        return s.failure("tangential", t_res, p, t_res.q, t_res.domega)
    q = t_res.q
    domega, dphi3 = s.motions(t_res)
    while s.coupled:
        # the next pass's normal solve measures the change the last pass left
        n = s.normal(q, p, inner, Ap0=n.Ap)
        s.its += n.iterations
        if not n.converged:
            return s.failure("normal", n, n.p, q, domega)
        W = s.W if ctl.is_force(0) else float(n.p.sum()) * cell_area
        if ctl.is_force(1) and not ctl.is_force(0) and s.slides(n, q, W) is not None:
            return s.slides(n, q, W)        # the approach's W fell below |T| / μ
        change = _pressure_change(n.p, p, W, cell_area)
        last = inner == tol
        if s.passes >= limits.max_passes and not (change < tol and last):
            # (a pass that only confirms a settled pressure is not refused)
            return InstantResult(n.p, q, U, n.omega3, domega, s.its, s.passes, False,
                                 change, "coupling", n)
        s.passes += 1
        p = n.p
        inner = min(inner, max(tol, tuning.passes_tolerance_fraction * change))
        if s.passes >= limits.max_passes - 1:
            inner = tol
        # an open contact (p = 0: an approach that lifts it) leaves q = 0 exactly
        final = (change < tol and last) or not p.any()
        t_res, up = s.tangential(p, q, inner, Aq0=t_res.Aq, final=final)
        s.its += t_res.iterations
        if not t_res.converged:
            return s.failure("tangential", t_res, p, t_res.q, t_res.domega)
        q = t_res.q
        domega, dphi3 = s.motions(t_res)
        if final:
            break
    return _PassState(n, p, q, t_res, up, domega, dphi3)


def solve_instant(op, gap, U, W, T, cell_area, mu, plan, previous: Previous,
                  limits: Tolerances, controls: Controls | None = None) -> InstantResult:
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
        Normal force [N] (ignored when ``controls`` is given).
    T : array_like (2,)
        Tangential force [N] (ignored when ``controls`` is given).
    cell_area : float
        Area of one cell [m²].
    mu : float or ndarray (N1, N2)
        Friction coefficient [1], uniform or mapped.
    plan : Plan
        The sub-models (``tangential``: none/scalar/vector; ``coupling``).
    previous : Previous
        The previous instant's shear, displacement, pressure guess (and normal solution).
    limits : Tolerances
        Tolerance, iterations per solve, coupling passes.
    controls : Controls, optional
        Force or displacement control of each of the six freedoms; absent: W and T
        force-controlled, the rotations held at zero.

    Returns
    -------
    InstantResult
        ``converged`` False with ``failed`` naming the sub-problem that stopped: "normal",
        "tangential", "sliding" (a force-controlled |T| > mu W (1 + tol): no shear within
        the bounds carries it, gross sliding; ``residual`` is then (|T| - mu W) / |T| and
        ``sliding`` holds W, |T| and mu W, W being the one reached under approach
        control), or "coupling" (the passes did not settle in ``limits.max_passes``;
        ``residual`` is the pressure change of the pass that would have followed).
        Under displacement control of the tangential freedoms full sliding (every
        contact cell at |q| = mu p) is a valid state, and under approach control so is
        a contact that opened (p = 0).
    """
    ctl = controls if controls is not None else Controls.forces(W, T)
    s = _Instant(op, gap, U, ctl, cell_area, mu, plan, previous, limits)
    tol = limits.tol
    if s.joint_applies():
        res = s.joint(tol)
        if res is not None:
            return res
    q = previous.q.copy() if s.tang != "none" else np.zeros_like(previous.q)
    worst = 0.0
    # -- normal -------------------------------------------------------------------------
    n = previous.normal if previous.normal is not None else s.normal(q, previous.p_guess, tol)
    if previous.normal is None:
        s.its += n.iterations
        worst = n.residual
    if not n.converged:
        return s.failure("normal", n, n.p, q, np.zeros(2))
    p = n.p
    W = s.W if ctl.is_force(0) else float(p.sum()) * cell_area
    domega, dphi3 = np.zeros(2), 0.0
    t_res, up = None, None
    if ctl.is_force(1) and s.tang != "none":
        slides = s.slides(n, q, W)
        if slides is not None:
            return slides
    # -- tangential, and the coupling loop ------------------------------------------------
    if s.tang != "none" and op.rigid:
        q = s.rigid_shear(p, W, q)
    elif s.tang != "none":
        out = _passes(s, n, q)
        if isinstance(out, InstantResult):
            return out
        n, p, q, t_res, up, domega, dphi3 = out.fields()
        worst = max(worst, t_res.residual)

    u = s.displacement(n, q, t_res, up)
    return InstantResult(p, q, u, n.omega3, domega, s.its, s.passes, True, worst, normal=n,
                         phi=np.asarray(n.phi, float).copy(), dphi3=dphi3)
