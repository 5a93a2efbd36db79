"""The uncoupled tangential contact problem (UTC): stick and slip under force control.

Given the pressure p (so the traction bound μp), the known part of the relative in-plane
displacement and the state of the previous instant, find the shear traction q and the
rigid shift increment Δω such that (paper eqs. 2, 4, 6; docs/conventions.md)

    Σ q Δ = T,
    stick (|q| < μp):  Δs = Δω − Δu = 0,
    slip  (|q| = μp):  q ∥ Δs and q·Δs ≥ 0 (friction dissipates).

Working on the slip *increment* is what remembers the path: a fretting loop's unloading
branch differs from its loading branch. This is the minimisation of
½ qᵀAq + (u_known − u_prev)ᵀq under |q| ≤ μp and Σq = T/Δ, whose multiplier is Δω and
whose residual is −Δs.

Two forms:

* ``scalar`` — the Cattaneo-Mindlin form: q2 = 0, a two-sided bound −μp ≤ q1 ≤ μp, solved
  by the bound-constrained CG of :mod:`contactpipe.solver.cg` (one FFT pair per iteration).
  An approximation (it neglects the x2 slip condition, so s2 = 0 by construction): the
  neglected q2 is small when the load is along x1 (test_tangential measures it).
* ``vector`` — the full problem with a disk |q| ≤ μp per cell: projected conjugate
  gradients in the spirit of Vollebregt's TangCG (2014): conjugate directions on the
  stick cells and on slip cells whose residual points inwards; slip cells keep |q| = μp
  and turn towards the slip direction; the force is restored by projecting the stick
  cells onto their disks and the force rows (a dual Newton solve for the shift vector,
  :func:`contactpipe.solver.cg.project_rows`). Two FFT pairs per operator application.

General rows (:class:`~contactpipe.solver.cg.Constraints`): besides the force rows
Σq1 = T1/Δ, Σq2 = T2/Δ, the vector form takes the torque row Σ(q2 x1 − q1 x2) = M3/Δ (its
multiplier is the rotation increment Δφ3), or no row at all under displacement control
(the known rigid motion is then part of ``b``, and full sliding, every cell on its bound,
is a valid solution). When no cell sticks, the multipliers are those that best align each
slip increment with its traction (:func:`slip_multipliers`), so that a rigid shift of the
known displacement shifts them alike.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cg import (ComponentSums, Constraints, box_cg, disk_project, fista, project_box_sum,
                 project_rows)

__all__ = ["TangentialResult", "follow_bound", "solve_scalar", "solve_vector", "disk_project",
           "project_disks_sum", "force_rows", "slip_multipliers"]


@dataclass
class TangentialResult:
    q: np.ndarray            # (2, N1, N2) shear traction [Pa]
    domega: np.ndarray       # (2,) rigid shift increment Δω [m]
    Aq: np.ndarray           # (2, N1, N2) A q [m] (u1 only, u2 = 0 for the scalar form)
    iterations: int
    residual: float
    converged: bool
    multipliers: np.ndarray | None = None   # (m,) of the rows given (general rows only)


def force_rows(shape, T, cell_area) -> Constraints:
    """The force rows Σq1 = T1/Δ, Σq2 = T2/Δ of the vector form on a grid of ``shape``."""
    return ComponentSums(np.asarray(T, dtype=float) / cell_area, shape)


#: A warm start's cell counts as on its bound within this relative distance [1].
ON_BOUND = 1e-9


def follow_bound(q, old, new):
    """The warm start of a tangential solve whose bound moved from ``old`` to ``new``
    [Pa]: the cells on their old bound (within :data:`ON_BOUND`) stay on it, scaled with
    it; the others as they were. ``q`` is (2, N1, N2), or (N1, N2) for one component.

    A slip cell lands on the new bound as exactly as rounding allows, and with one
    component (q2 = 0) on ±new itself: a ratio new/old rounds about half of them just
    inside, where the CG would take them for stick cells."""
    if q.ndim == 2:
        slip = (old > 0) & (np.abs(q) >= old * (1.0 - ON_BOUND))
        return np.where(slip, np.copysign(new, q), q)
    if not q[1].any():
        return np.stack([follow_bound(q[0], old, new), q[1]])
    mag = np.hypot(q[0], q[1])
    slip = (old > 0) & (mag >= old * (1.0 - ON_BOUND))
    return q * np.where(slip, new / np.where(mag > 0, mag, 1.0), 1.0)


def scalar_multiplier(g, q1, bound) -> float:
    """Δω1 [m], the force row's multiplier of a one-component solution ``q1`` [Pa] under
    the bound μp [Pa], g = K11 q1 + b1 [m]: fitted to the stick cells, or where no cell
    sticks clearly, to the slip directions (:func:`slip_multipliers`)."""
    stick = (bound > 0) & (np.abs(q1) < bound * (1.0 - 1e-12))
    if _pinned(stick, np.abs(q1), bound):
        return float(_multiplier(g[None], stick)[0])
    return float(slip_multipliers(g, q1, bound, None)[0])


def _infeasible(x, con, target, scale, tol) -> bool:
    """The rows are not met (a force beyond what the bounds can carry)."""
    if con is None:
        return abs(float(x.sum()) - target) / scale >= tol
    return float(np.abs(con.residual(x)).max(initial=0.0)) / scale >= tol


def solve_scalar(op, b1, bound, T1, cell_area, q0, tol, max_iter, Aq0=None,
                 precondition=True):
    """Cattaneo-Mindlin form (q2 = 0).

    Parameters
    ----------
    op : ContactOperator
        Provides ``tangential_scalar`` (K11 ⊛ q1).
    b1 : ndarray
        Known in-plane displacement minus the previous one, u1_known − u1(k−1) [m]; under
        displacement control also minus the known rigid shift increment Δω1.
    bound : ndarray
        μp [Pa] (zero outside the contact).
    T1 : float or None
        Tangential force [N]; None under displacement control (no force row: the
        returned ``domega`` is then 0, the caller knows the shift).
    q0 : ndarray
        Warm start for q1 [Pa]. A slip cell should sit exactly on its bound
        (:func:`follow_bound`): one rounded inside counts as
        stick, and the preconditioned direction, which is not local, then carries the
        whole field off before the projection puts it back.
    precondition : bool
        Preconditioned CG with the (−Δ)^½ filter of the normal solve
        (:meth:`ContactOperator.normal_preconditioner`; K11, like K33, behaves as 1/|ξ|):
        1.25 FFT pairs per iteration instead of one, in about half the iterations at 128²
        and fewer still on finer grids (docs/design-choices.md). False, or an operator
        without the filter: plain CG.

    Notes
    -----
    ``converged`` is False when the bounds cannot carry T1 (|T1| > Σμp Δ), whichever of
    the CG or its projected-gradient fallback ran last.
    """
    scale = max(float(bound.sum()), 1e-300)
    con = Constraints.none(b1.shape) if T1 is None else None
    make = getattr(op, "normal_preconditioner", None) if precondition else None
    M = make() if make is not None else None
    target = con if con is not None else T1 / cell_area

    def cg(x0, Ax0, tol_, budget):
        r = box_cg(op.tangential_scalar, b1, -bound, bound, target, x0, tol=tol_,
                   max_iter=budget, restore="shift", scale=scale, Ax0=Ax0, precondition=M)
        return r.x, r.Ax, r.iterations, r.residual, r.converged

    def pg(x0, Ax0, tol_, budget):
        if con is not None:
            project = lambda y: np.clip(y, -bound, bound)            # noqa: E731
        else:
            project = lambda y: project_box_sum(y, -bound, bound, target)  # noqa: E731
        x, Ax, its, err, ok = fista(op.tangential_scalar, b1, project, x0,
                                    op.tangential_norm(1), tol_, budget, scale, Ax0=Ax0)
        return x, Ax, its, err, ok and not _infeasible(x, con, target, scale, tol_)

    x, Ax, its, err, ok = _cg_with_fallback(cg, pg, q0, Aq0, tol, max_iter)
    lam = 0.0 if con is not None else scalar_multiplier(Ax + b1, x, bound)
    q = np.zeros((2,) + b1.shape)
    q[0] = x
    Aq = np.zeros_like(q)
    Aq[0] = Ax
    return TangentialResult(q=q, domega=np.array([lam, 0.0]), Aq=Aq, iterations=its,
                            residual=err, converged=ok,
                            multipliers=np.zeros(0) if con is not None else None)


def _restore_vector(q, rho, con, stick):
    """Meet the rows again by projecting the stick cells (then, when they cannot carry
    them, every contact cell) onto their disks and the rows: one shift vector, found by
    a dual Newton solve (:func:`contactpipe.solver.cg.project_rows`). Under the force rows
    alone the shift is first had in closed form, uniform over the cells
    (:meth:`~contactpipe.solver.cg.Constraints.shift`): where it keeps them in their disks
    it is the projection (the vector CG restores its rows after nearly every step; the
    dual Newton solve cost a fifth of a fretting step's time)."""
    if con.m == 0:
        return q
    for cells in (stick, rho > 0):
        if not cells.any():
            continue
        out = con.shift(q, cells, rho)
        if out is None:
            out = project_rows(q, con, cells, "disk", rho=rho)
        tol = 1e-11 * (np.abs(con.target).max(initial=0.0) + rho.sum())
        if np.abs(con.residual(out)).max() <= tol:
            return out
        q = out
    return q


#: A warm start's cell within SNAP x tol (relative) of its bound starts on it [1].
SNAP = 0.1

#: The circle corrections a vector CG may leave out of A q, summed, as a fraction of
#: its tolerance (A q is recomputed once they would exceed it, and at the end) [1].
LAG = 0.1

#: The vector CG's filter is shifted by this fraction of the turning cells' median circle
#: curvature (0.1 / 0.3 / 0.5 / 1: 1156 / 1008 / 1073 / 1154 iterations over a 12-step
#: steel-on-aluminium fretting at 64²; 0: 3019, unpreconditioned: 1554) [1].
CURVATURE_SHIFT = 0.3

#: The vector CG restarts its conjugate sequence when |g_k·z_(k-1)| ≥ this x g_k·z_k
#: (Powell 1977, "Restart procedures for the conjugate gradient method"): its turning
#: cells make it a nonlinear CG. Without it a 12-step steel-on-steel fretting at 128²
#: spent 223 FFT pairs a step, solves of 200-285 iterations converging linearly with
#: every set fixed; with it 78 (docs/design-choices.md) [1].
POWELL_RESTART = 0.2

#: Iterations of the vector CG without halving its best step before it hands over to
#: the projected gradient (it stalls where nearly every cell turns on its circle) [1].
STALL = 50


def _magnitude(v):
    """|v| per cell of a vector field v (2, N1, N2), as sqrt(v1² + v2²): a third of
    ``np.hypot``'s time, which guards against overflow that shear in Pa never reaches (the
    vector CG takes three magnitudes per iteration) [unit of v]."""
    m = v[0] * v[0]
    m += v[1] * v[1]
    return np.sqrt(m, out=m)


def _vector_step(op, q, Aq, tau, t, r, rho, con, cells, scale, lag, tol):
    """One step q - tau t of :func:`_vector_cg` (r = A t): stick cells pushed past their
    disk are projected radially, turning cells put back on their circles, the rows
    restored. Returns (q, A q, the step's size over ``scale``, the lag).

    The correction back onto the circles is second order in the step: while the
    corrections summed (``lag``, over ``scale``) stay below :data:`LAG` x ``tol``, A q
    follows the step alone; beyond that, or when a stick cell left its disk, A q is
    recomputed (two FFT pairs) and the lag is cleared."""
    movable, stick, turning = cells
    q_new = q - tau * t
    m = _magnitude(q_new)
    over = movable & (m > rho)
    fix = over | (turning & (m > 0))
    if not fix.any():
        return q_new, Aq - tau * r, np.abs(q_new - q).sum() / scale, lag
    stepped = q_new.copy()
    onto = np.divide(rho, m, out=np.ones_like(m), where=fix)   # 1 where nothing moves
    q_new *= onto
    q_new = _restore_vector(q_new, rho, con, stick & ~over)
    err = np.abs(q_new - q).sum() / scale
    lag_step = float(np.abs(q_new - stepped).sum()) / scale
    if not (over & ~turning).any() and lag + lag_step <= LAG * tol:
        return q_new, Aq - tau * r, err, lag + lag_step
    return q_new, op.tangential_vector(q_new), err, 0.0


def _vector_direction(M, gt, radial, qhat, rho, a_self, free, turning):
    """The preconditioned residual z of :func:`_vector_cg` (before the rows are kept):
    ``gt`` the residual (tangential on turning cells) [m], ``radial`` its part along
    q̂ [m], ``rho`` the bound μp with 1 off the contact [Pa] (only turning cells, in
    contact, read it), ``a_self`` the self-influence [m/Pa].

    ``M`` None: TangCG's diagonal scaling, relative to a stick cell. Else the operator's
    ``tangential_preconditioner``: z = S M(S gt, d̄) [Pa], M ≈ (K_t + d̄ I)⁻¹ the
    (−Δ)^½ filter shifted by d̄ = :data:`CURVATURE_SHIFT` x the turning cells' median
    circle curvature |r·q̂|/ρ, S = √((a + d̄)/(a + d_i)) each cell's own diagonal (d_i = 0
    on free cells), then cut back to the tangents on turning cells. The curvature
    outweighs the self-influence 2-10 times on a fretting step's slip annulus, so the
    unshifted filter (the scalar CG's) is no better than the diagonal; shifted, the
    iterations fall by a third (docs/design-choices.md)."""
    if M is None:
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.where(turning, rho * a_self / (rho * a_self + np.abs(radial)), 1.0)
        return np.where(free | turning, gt * w, 0.0)
    # curvature of the circles [m/Pa]: |r·q̂|/ρ on turning cells, 0 on free ones
    curv = np.where(turning, np.abs(radial) / rho, 0.0)
    shift = CURVATURE_SHIFT * float(np.median(curv[turning])) if turning.any() else 0.0
    S = np.where(free | turning, np.sqrt((a_self + shift) / (a_self + curv)), 0.0)
    z = M(S * gt, shift)
    z *= S
    along = qhat[0] * z[0] + qhat[1] * z[1]
    return np.where(turning, z - along * qhat, z)


def _conjugate(t, z, z_old, rz, rz_old, gt, gr, qhat, turning):
    """The vector CG's next direction from its last one ``t``: the last transported onto
    the current tangents of turning cells, conjugated with z (rz = gt·z [m Pa]); or z
    itself, a new conjugate sequence, by Powell's restart: the turning cells'
    projections back onto their circles spoil conjugacy without changing any set, so a
    residual no longer nearly orthogonal to the last one (|gt·z_old| ≥
    :data:`POWELL_RESTART` rz), or a direction that does not descend, restarts."""
    if abs(float(np.sum(gt * z_old))) >= POWELL_RESTART * rz:
        return z
    tr = qhat[0] * t[0] + qhat[1] * t[1]
    t_new = z + (rz / rz_old) * np.where(turning, t - tr * qhat, t)
    return t_new if float(np.sum(gr * t_new)) > 0.0 else z


def _vector_cg(op, b, bound, con, q0, tol, max_iter, Aq0=None, precondition=True,
               exact=True):
    """Full vector form by projected CG (the fast path of :func:`solve_vector`; ``con``
    the rows, :class:`~contactpipe.solver.cg.Constraints` on (2, N1, N2)).

    Notes
    -----
    Preconditioned projected conjugate gradients over all contact cells at once:

    * stick cells (|q| < μp), and slip cells whose residual points into the disk (they
      re-enter), move along the residual;
    * the other slip cells may only turn on their circle |q| = μp: the variable is their
      slip angle θ (Zhao, Vollebregt & Oosterlee 2014, "A fast nonlinear conjugate
      gradient based method for 3D frictional contact problems"), with the diagonal
      preconditioner 1/(ρ²a + ρ|r·q̂|) — a the self-influence, r the residual; the second
      term is the curvature of the circle — which in q-space scales the tangential residual
      by ρa/(ρa + |r·q̂|) relative to a stick cell; the previous direction is transported
      to the current tangents;
    * ``precondition``: the direction filtered as a whole instead
      (:func:`_vector_direction`), a third fewer iterations for half a pair more each;
    * after the exact line search, stick cells pushed past the disk are projected radially
      (they join the slip set) and turning cells are put back on their circles; the rows
      are restored by projecting the stick cells (:func:`_restore_vector`).
    * the conjugate sequence restarts where a set changes, and by Powell's test where
      the projections onto the circles have spoiled conjugacy (:func:`_conjugate`).

    Each iteration costs one operator application (two FFT pairs; the filter half a pair
    more), and a second one only when a stick cell left its disk or the circle corrections
    add up (:func:`_vector_step`).
    A warm start's cells within :data:`SNAP` x tol of their bound start on it (else a
    bound raised by rounding turns slip cells into stick cells, which slide back in tens
    of iterations). It stops, not converged, when :data:`STALL` iterations pass without
    halving its best step. With ``exact`` False a converged result's A q may leave out
    the last circle corrections (summed, below :data:`LAG` x tol; so may the multipliers
    fitted to it): for a pass whose product the caller discards, this saves the final
    recomputation (two FFT pairs).
    """
    rho = bound
    movable = rho > 0
    a_self = op.self_influence("11")
    make = getattr(op, "tangential_preconditioner", None) if precondition else None
    M = make() if make is not None else None
    q, _ = disk_project(np.where(movable, q0, 0.0), rho)
    mag = _magnitude(q)
    near = movable & (mag >= rho * (1.0 - SNAP * tol)) & (mag > 0)
    q[:, near] *= rho[near] / mag[near]
    q = _restore_vector(q, rho, con, movable & ~near)
    Aq = op.tangential_vector(q) if (Aq0 is None or not np.array_equal(q, q0)) else Aq0
    scale = max(float(rho.sum()), 1e-300)
    rho_safe = np.where(movable, rho, 1.0)      # divides where only contact cells count
    t = np.zeros_like(q)
    rz_old = 1.0
    sets_old = None
    z_old = None
    err = np.inf
    lam = np.zeros(con.m)
    best, best_it = np.inf, 0
    lag = 0.0                   # corrections not yet in A q, summed, over scale [1]
    it = 0
    for it in range(1, max_iter + 1):
        if it - best_it > STALL:    # no progress: leave it to the projected gradient
            break
        g = Aq + b
        mag = _magnitude(q)
        at_bound = movable & (mag >= rho * (1.0 - 1e-12))
        stick = movable & ~at_bound
        if stick.any():
            lam = con.fit(g, stick)
        gr = g - con.field(lam)
        qhat = np.where(at_bound, q / np.where(mag > 0, mag, 1.0), 0.0)
        radial = qhat[0] * gr[0] + qhat[1] * gr[1]
        released = at_bound & (radial > 0)
        turning = at_bound & ~released
        free = stick | released
        gt = np.where(turning, gr - radial * qhat, gr)
        z = _vector_direction(M, gt, radial, qhat, rho_safe, a_self, free, turning)
        z = con.keep(z, free)   # the rows stay put along the direction
        rz = float(np.sum(gt * z))
        if not rz > 0.0:
            err = 0.0 if rz <= 0.0 else np.inf
            break
        sets = (free, turning)
        reset = (released.any() or sets_old is None
                 or not (np.array_equal(free, sets_old[0])
                         and np.array_equal(turning, sets_old[1])))
        t = z if reset else _conjugate(t, z, z_old, rz, rz_old, gt, gr, qhat, turning)
        rz_old, z_old = rz, z
        sets_old = sets
        r = op.tangential_vector(t)
        denom = float(np.sum(r * t))
        if denom <= 0.0:
            err = 0.0
            break
        tau = float(np.sum(gr * t)) / denom
        if turning.any():       # no cell turns by more than half a radian in one step
            spin = _magnitude(t)
            spin /= rho_safe
            spin_max = float(spin.max(where=turning, initial=0.0))
            if tau * spin_max > 0.5:
                tau = 0.5 / spin_max
                sets_old = None
        q, Aq, err, lag = _vector_step(op, q, Aq, tau, t, r, rho, con,
                                       (movable, stick, turning), scale, lag, tol)
        if not err >= 0.0:      # NaN: the iterate is lost
            err = np.inf
            break
        if err < tol:
            break
        if err < 0.5 * best:
            best, best_it = err, it
    err = max(float(err), float(np.abs(con.residual(q)).max(initial=0.0)) / scale)
    ok = bool(err < tol) and bool(np.all(np.isfinite(q)))
    if lag > 0.0 and (exact or not ok):
        Aq = op.tangential_vector(q)
    lam = multipliers(con, Aq + b, q, rho)
    return TangentialResult(q=q, domega=np.zeros(2), Aq=Aq, iterations=it, residual=err,
                            converged=ok, multipliers=lam)


def project_disks_sum(y, rho, target):
    """Euclidean projection of y (2, N1, N2) onto {|x_i| ≤ rho_i, Σ x_i = target}.

    x_i = P_disk(y_i − ν) with the multiplier ν (2,) from the damped dual Newton
    iteration of :func:`contactpipe.solver.cg.project_rows` (its Jacobian is the sum of
    the disk projections' Jacobians: I inside, (ρ/|z|)(I − ẑẑᵀ) on the rim); x = 0 where
    rho = 0.
    """
    cells = rho > 0
    con = force_rows(rho.shape, target, 1.0)
    return project_rows(np.where(cells, y, 0.0), con, cells, "disk", rho=rho)


def _cg_with_fallback(cg, pg, x0, Ax0, tol, max_iter, sliding=None):
    """CG first; where it stalls, the projected gradient to a loose tolerance (it finds the
    slip/stick pattern that pins the multiplier), then CG again from there; the projected
    gradient, which always converges, finishes if CG stalls a second time.

    ``cg`` and ``pg`` take (x0, Ax0, tol, budget) and return (x, Ax, iterations, residual,
    converged). Returns the same tuple, iterations summed. ``sliding(x)``, when given, says
    that no cell of x sticks: the projected gradient then runs alone (the projected CG
    stalls where every cell turns on its circle, as in gross slip, while the projected
    gradient converges in a few dozen iterations there).
    """
    budget = max(1, max_iter // 4)
    if sliding is not None and np.any(x0) and sliding(x0):
        return pg(x0, Ax0, tol, max_iter)
    x, Ax, its, err, ok = cg(x0, Ax0, tol, budget)
    if ok:
        return x, Ax, its, err, ok
    x, Ax, more, err, _ = pg(x, Ax, max(tol, 1e-6), budget)
    its += more
    if sliding is not None and sliding(x):
        x, Ax, more, err, ok = pg(x, Ax, tol, max(1, max_iter - its))
        return x, Ax, its + more, err, ok
    x, Ax, more, err, ok = cg(x, Ax, tol, budget)
    its += more
    if ok:
        return x, Ax, its, err, ok
    x, Ax, more, err, ok = pg(x, Ax, tol, max(1, max_iter - its))
    return x, Ax, its + more, err, ok


def _multiplier(g, stick):
    return g[..., stick].mean(axis=-1) if stick.any() else np.zeros(g.shape[:-2])


def multipliers(con, g, q, bound):
    """The rows' multipliers of a vector solution: fitted to the stick cells, or where
    no cell sticks, to the slip directions (:func:`slip_multipliers`)."""
    mag = np.hypot(q[0], q[1])
    stick = (bound > 0) & (mag < bound * (1.0 - 1e-12))
    if con.m == 0:
        return np.zeros(0)
    if _pinned(stick, mag, bound):
        return con.fit(g, stick)
    return slip_multipliers(g, q, bound, con)


#: A stick cell pins the multipliers only when |q| < mu p (1 - DEEP_STICK): a cell within
#: the solver's tolerance of its bound slips, and its slip increment is not zero [1].
DEEP_STICK = 1e-6


def _pinned(stick, mag, bound) -> bool:
    """Some cell sticks clearly inside its bound (else the contact slips everywhere, up to
    the solver's tolerance, and the multipliers follow the slip directions)."""
    return bool(np.any(stick & (mag < bound * (1.0 - DEEP_STICK))))


#: Passes of the active-set fit of :func:`slip_multipliers`.
SLIP_FIT_PASSES = 20


def slip_multipliers(g, q, bound, con):
    """Multipliers λ when every contact cell slips: the slip increments Δs = Cᵀλ − g must
    then point along q (|q| = μp, q·Δs ≥ 0), which no stick cell pins.

    Parameters
    ----------
    g : ndarray
        A q + b: (N1, N2) for the one-component form (then ``con`` is None and the row is
        Σq1), (2, N1, N2) for the vector form.
    q : ndarray
        The shear, the shape of ``g``.
    bound : ndarray (N1, N2)
        μp.
    con : Constraints or None
        The vector form's rows.

    Returns
    -------
    ndarray (m,)
        One-component form: the middle of the interval of λ1 for which every slip
        increment λ1 − g has the sign of q1 (its finite end when one side is open).
        Vector form: the λ minimising Σ dist²(Δs_i, the ray along q_i), found by an
        active-set least-squares iteration (cells whose Δs points against q count with
        both components); a rigid shift c of g then shifts λ by c.
    """
    cells = bound > 0
    if con is None:
        up, down = cells & (q > 0), cells & (q < 0)
        lo = float(g[up].max()) if up.any() else -np.inf
        hi = float(g[down].min()) if down.any() else np.inf
        if np.isfinite(lo) and np.isfinite(hi):
            return np.array([0.5 * (lo + hi)])
        return np.array([lo if np.isfinite(lo) else (hi if np.isfinite(hi) else 0.0)])
    mag = np.hypot(q[0], q[1])[cells]
    qh = q[:, cells] / np.where(mag > 0, mag, 1.0)
    nh = np.stack([-qh[1], qh[0]])
    A = con.rows[..., cells]                                   # (m, 2, k)
    gs = g[:, cells]
    perp = np.einsum("ik,mik->km", nh, A)                       # (k, m)
    perp_rhs = np.einsum("ik,ik->k", nh, gs)
    par = np.einsum("ik,mik->km", qh, A)
    par_rhs = np.einsum("ik,ik->k", qh, gs)
    against = np.zeros(mag.size, dtype=bool)
    lam = np.zeros(con.m)
    for _ in range(SLIP_FIT_PASSES):
        M = np.concatenate([perp, par[against]])
        v = np.concatenate([perp_rhs, par_rhs[against]])
        lam = np.linalg.lstsq(M, v, rcond=None)[0]
        now = par @ lam - par_rhs < 0.0                        # q·Δs < 0
        if np.array_equal(now | against, against):
            break
        against = against | now
    return lam


def solve_vector(op, b, bound, T, cell_area, q0, tol, max_iter, Aq0=None, rows=None,
                 precondition=True, exact=True):
    """Full vector form: disk constraint |q| ≤ μp per cell.

    Parameters
    ----------
    op : ContactOperator
        Provides ``tangential_vector`` ([K11 K12; K21 K22] ⊛ q).
    b : ndarray (2, N1, N2)
        Known in-plane displacement minus the previous one [m]; minus the known rigid
        motion increments of the freedoms that are displacement-controlled.
    bound : ndarray (N1, N2)
        μp [Pa].
    T : array_like (2,) or None
        Tangential force [N] (the force rows); ignored when ``rows`` is given.
    q0 : ndarray (2, N1, N2)
        Warm start [Pa].
    rows : Constraints, optional
        General rows on (2, N1, N2) in place of the force rows: the force rows, the
        torque row, both, or none (displacement control). Their multipliers are returned
        in ``multipliers``; ``domega`` is then (0, 0).
    precondition : bool
        The CG's direction filtered by the operator's ``tangential_preconditioner``
        (:func:`_vector_cg`); False, or an operator without it: TangCG's diagonal scaling
        alone.
    exact : bool
        False: a converged result's ``Aq`` and multipliers may lag the last circle
        corrections by up to :data:`LAG` x tol (:func:`_vector_cg`), for a coupling pass
        that is not the last (the next pass recomputes its start's product anyway).

    Notes
    -----
    The preconditioned projected CG (:func:`_vector_cg`) runs first; where it stalls —
    typically when (almost) every cell slips and the multipliers are not pinned by stick
    cells — see :func:`_cg_with_fallback`. ``converged`` is False when the rows cannot be
    met within the disks (|T| > Σμp Δ).
    """
    con = rows if rows is not None else force_rows(bound.shape, T, cell_area)
    scale = max(float(bound.sum()), 1e-300)

    def cg(x0, Ax0, tol_, budget):
        r = _vector_cg(op, b, bound, con, x0, tol_, budget, Ax0, precondition, exact)
        return r.q, r.Aq, r.iterations, r.residual, r.converged

    def pg(x0, Ax0, tol_, budget):
        cells = bound > 0
        x, Ax, its, err, ok = fista(
            op.tangential_vector, b,
            lambda y: project_rows(np.where(cells, y, 0.0), con, cells, "disk", rho=bound),
            x0, op.tangential_norm(2), tol_, budget, scale, Ax0=Ax0)
        return x, Ax, its, err, ok and not _infeasible(x, con, None, scale, tol_)

    def sliding(q):
        mag = np.hypot(q[0], q[1])
        stick = (bound > 0) & (mag < bound * (1.0 - 1e-12))
        return (bound > 0).any() and not _pinned(stick, mag, bound)

    q, Aq, its, err, ok = _cg_with_fallback(cg, pg, q0, Aq0, tol, max_iter, sliding)
    lam = multipliers(con, Aq + b, q, bound)
    if rows is not None:
        return TangentialResult(q=q, domega=np.zeros(2), Aq=Aq, iterations=its,
                                residual=err, converged=ok, multipliers=lam)
    return TangentialResult(q=q, domega=lam, Aq=Aq, iterations=its, residual=err,
                            converged=ok)
