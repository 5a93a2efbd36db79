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

from .blocks import DirectOperator
from .cg import (
    BoxOptions,
    ComponentSums,
    Constraints,
    Outcome,
    Start,
    box_cg,
    disk_project,
    fista,
    project_box_sum,
    project_rows,
)
from .cg import cg_with_fallback as _cg_with_fallback
from .disk_cg import DiskOptions, disk_cg, disk_start
from .ledger import Ledger
from .options import TUNING
from .projection import RECOGNISED, on_bound

__all__ = ["TangentialResult", "follow_bound", "solve_scalar", "solve_vector", "disk_project",
           "project_disks_sum", "force_rows", "sliding", "slip_multipliers"]


@dataclass
class TangentialResult:
    q: np.ndarray            # (2, N1, N2) shear traction [Pa]
    domega: np.ndarray       # (2,) rigid shift increment Δω [m]
    Aq: np.ndarray | None    # (2, N1, N2) A q [m] (u1 only, u2 = 0 for the scalar form);
                             # None: a vector pass that let it go (``exact`` False)
    iterations: int
    residual: float
    converged: bool
    multipliers: np.ndarray | None = None   # (m,) of the rows given (general rows only)


def force_rows(shape, T, cell_area) -> Constraints:
    """The force rows Σq1 = T1/Δ, Σq2 = T2/Δ of the vector form on a grid of ``shape``."""
    return ComponentSums(np.asarray(T, dtype=float) / cell_area, shape)


def follow_bound(q, old, new):
    """The warm start of a tangential solve whose bound moved from ``old`` to ``new``
    [Pa]: the cells on their old bound (within :data:`RECOGNISED`) stay on it, scaled with
    it; the others as they were. ``q`` is (2, N1, N2), or (N1, N2) for one component.

    A slip cell lands on the new bound as exactly as rounding allows, and with one
    component (q2 = 0) on ±new itself: a ratio new/old rounds about half of them just
    inside, where the CG would take them for stick cells."""
    if q.ndim == 2:
        slip = (old > 0) & on_bound(np.abs(q), old, RECOGNISED)
        return np.where(slip, np.copysign(new, q), q)
    if not q[1].any():
        return np.stack([follow_bound(q[0], old, new), q[1]])
    mag = np.hypot(q[0], q[1])
    slip = (old > 0) & on_bound(mag, old, RECOGNISED)
    return q * np.where(slip, new / np.where(mag > 0, mag, 1.0), 1.0)


def scalar_multiplier(g, q1, bound) -> float:
    """Δω1 [m], the force row's multiplier of a one-component solution ``q1`` [Pa] under
    the bound μp [Pa], g = K11 q1 + b1 [m]: fitted to the stick cells, or where no cell
    sticks clearly, to the slip directions (:func:`slip_multipliers`)."""
    stick = (bound > 0) & ~on_bound(np.abs(q1), bound)
    if _pinned(stick, np.abs(q1), bound):
        return float(_multiplier(g[None], stick)[0])
    return float(slip_multipliers(g, q1, bound, None)[0])


def _miss(x, con, target, scale) -> float:
    """How far the rows are from met, relative to ``scale`` (not within the tolerance:
    a force beyond what the bounds can carry)."""
    if con is None:
        return abs(float(x.sum()) - target) / scale
    return float(np.abs(con.residual(x)).max(initial=0.0)) / scale


def solve_scalar(op, b1, bound, T1, cell_area, q0, tol, max_iter, Aq0=None,
                 precondition=TUNING.precondition):
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
        Preconditioned CG with the inverse of K11's model symbol
        (:meth:`ContactOperator.shear_preconditioner`; K11, like K33, behaves as 1/|ξ|,
        1/(1 − ν_e) times stiffer across x1 than along it):
        1.25 FFT pairs per iteration instead of one, in far fewer iterations, the more so
        on finer grids (docs/design-choices.md, D4). False, or an operator
        without the filter: plain CG.

    Notes
    -----
    ``converged`` is False when the bounds cannot carry T1 (|T1| > Σμp Δ), whichever of
    the CG or its projected-gradient fallback ran last.
    """
    # Σμp, or |T1|/Δ where the bounds carry less (then no solution: finite residuals)
    scale = max(float(bound.sum()), abs(T1) / cell_area if T1 is not None else 0.0, 1e-300)
    con = Constraints.none(b1.shape) if T1 is None else None
    make = getattr(op, "shear_preconditioner", None) if precondition else None
    M = make() if make is not None else None
    target = con if con is not None else T1 / cell_area

    def cg(x0, Ax0, tol_, budget):
        r = box_cg(op.tangential_scalar, b1, -bound, bound, target, Start(x0, Ax0),
                   BoxOptions(tol_, budget, "shift", scale, M))
        return Outcome(r.x, r.Ax, r.iterations, r.residual, r.converged)

    def pg(x0, Ax0, tol_, budget):
        if con is not None:
            project = lambda y: np.clip(y, -bound, bound)            # noqa: E731
        else:
            project = lambda y: project_box_sum(y, -bound, bound, target)  # noqa: E731
        o = fista(op.tangential_scalar, b1, project, x0, op.tangential_norm(1), tol_,
                  budget, scale, Ax0=Ax0)
        return _with_miss(o, _miss(o.x, con, target, scale), tol_)

    o = _cg_with_fallback(cg, pg, q0, Aq0, tol, max_iter)
    lam = 0.0 if con is not None else scalar_multiplier(o.Ax + b1, o.x, bound)
    q = np.zeros((2,) + b1.shape)
    q[0] = o.x
    Aq = np.zeros_like(q)
    Aq[0] = o.Ax
    return TangentialResult(q=q, domega=np.array([lam, 0.0]), Aq=Aq, iterations=o.iterations,
                            residual=o.residual, converged=o.converged,
                            multipliers=np.zeros(0) if con is not None else None)


def _with_miss(o, miss, tol) -> Outcome:
    """The projected gradient's outcome judged with the rows' miss as well."""
    return Outcome(o.x, o.Ax, o.iterations, max(o.residual, miss), o.converged and miss < tol)


def _vector_cg(op, b, bound, con, q0, tol, max_iter, Aq0=None, exact=True, tuning=TUNING):
    """Full vector form by the projected CG of :func:`contactpipe.solver.disk_cg.disk_cg`
    (the fast path of :func:`solve_vector`; ``con`` the rows,
    :class:`~contactpipe.solver.cg.Constraints` on (2, N1, N2)): stick cells move freely,
    slip cells turn on their circles, the direction is the (−Δ)^½ filter shifted by the
    circles' curvature (``tuning.precondition``; else TangCG's diagonal scaling), the line
    search takes that curvature in.

    Each iteration costs one operator application (two FFT pairs; the filter half a pair
    more, and the projection's correction, where it adds up, its forward transforms:
    :func:`~contactpipe.solver.disk_cg.disk_cg`). The warm
    start's cells within ``tuning.snap`` x tol of their bound
    start on it (:func:`~contactpipe.solver.disk_cg.disk_start`). It stops, not
    converged, when ``tuning.stall`` iterations pass without
    halving its best step. With ``exact`` False a converged result whose last corrections
    (summed, below ``tuning.defer`` x tol) were left out of A q has no A q (None): for a
    pass whose product the caller discards, this saves their forward transforms (one FFT
    pair). Returns an :class:`~contactpipe.solver.cg.Outcome` (q, A q).
    """
    rho = bound
    make = getattr(op, "tangential_preconditioner", None) if tuning.precondition else None
    M = make() if make is not None else None
    blocks = getattr(op, "tangential_blocks", None)
    A = blocks() if blocks is not None else DirectOperator(op.tangential_vector)
    q = disk_start(q0, rho, con, tol, tuning.snap)
    Aq = A(q) if (Aq0 is None or not np.array_equal(q, q0)) else Aq0
    scale = max(float(rho.sum()), float(np.abs(con.target).max(initial=0.0)), 1e-300)
    res = disk_cg(A, b, Start(q, Aq), rho, con,
                  DiskOptions(tol, max_iter, M, op.self_influence("11"), scale=scale,
                              tuning=tuning),
                  Ledger(update=True, defer=tuning.defer, exact=exact))
    return Outcome(res.x, res.Ax, res.iterations, res.residual, res.converged)


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


def _multiplier(g, stick):
    return g[..., stick].mean(axis=-1) if stick.any() else np.zeros(g.shape[:-2])


def multipliers(con, g, q, bound):
    """The rows' multipliers of a vector solution: fitted to the stick cells, or where
    no cell sticks, to the slip directions (:func:`slip_multipliers`)."""
    mag = np.hypot(q[0], q[1])
    stick = (bound > 0) & ~on_bound(mag, bound)
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


def sliding(q, bound) -> bool:
    """No cell of the shear q (2, N1, N2) [Pa] sticks clearly inside its bound μp [Pa]
    while some are in contact: the contact slides (nearly) as a whole, where the vector
    CG stalls and the projected gradient converges (:func:`_cg_with_fallback`)."""
    mag = np.hypot(q[0], q[1])
    stick = (bound > 0) & ~on_bound(mag, bound)
    return bool((bound > 0).any()) and not _pinned(stick, mag, bound)


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
    assert con.rows is not None                                # force rows, not BlockSums
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
                 exact=True, tuning=TUNING):
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
    exact : bool
        False: a converged result whose last circle corrections (up to ``tuning.defer``
        x tol) were left out has ``Aq`` None and no multipliers
        (:func:`_vector_cg`), for a coupling pass that is not the last (the next pass
        recomputes its start's product anyway).
    tuning : Tuning
        ``precondition``: the CG's direction filtered by the operator's
        ``tangential_preconditioner`` (:func:`_vector_cg`; False, or an operator without
        it: TangCG's diagonal scaling alone); the vector CG's constants.

    Notes
    -----
    The preconditioned projected CG (:func:`_vector_cg`) runs first; where it stalls —
    typically when (almost) every cell slips and the multipliers are not pinned by stick
    cells — see :func:`_cg_with_fallback`. ``converged`` is False when the rows cannot be
    met within the disks (|T| > Σμp Δ).
    """
    con = rows if rows is not None else force_rows(bound.shape, T, cell_area)
    # Σμp, or the rows' targets where the disks carry less (no solution: finite residuals)
    scale = max(float(bound.sum()), float(np.abs(con.target).max(initial=0.0)), 1e-300)

    def cg(x0, Ax0, tol_, budget):
        return _vector_cg(op, b, bound, con, x0, tol_, budget, Ax0, exact, tuning)

    def pg(x0, Ax0, tol_, budget):
        cells = bound > 0
        o = fista(op.tangential_vector, b,
                  lambda y: project_rows(np.where(cells, y, 0.0), con, cells, "disk",
                                         rho=bound),
                  x0, op.tangential_norm(2), tol_, budget, scale, Ax0=Ax0)
        return _with_miss(o, _miss(o.x, con, None, scale), tol_)

    o = _cg_with_fallback(cg, pg, q0, Aq0, tol, max_iter, lambda q: sliding(q, bound))
    # a pass whose product was let go (``exact`` False: not the instant's last) reports
    # zero multipliers, which the next pass replaces
    lam = np.zeros(con.m) if o.Ax is None else multipliers(con, o.Ax + b, o.x, bound)
    if rows is not None:
        return TangentialResult(q=o.x, domega=np.zeros(2), Aq=o.Ax, iterations=o.iterations,
                                residual=o.residual, converged=o.converged, multipliers=lam)
    return TangentialResult(q=o.x, domega=lam, Aq=o.Ax,
                            iterations=o.iterations, residual=o.residual,
                            converged=o.converged)
