"""Projected conjugate gradients over the friction disks |q| ≤ ρ (the vector form's CG),
optionally with a pressure block.

The unknown is the shear q (2, N1, N2) — or, for a coupled instant solved as one problem
(:func:`contactpipe.solver.joint.solve_joint_vector`), the stacked x = (p, s1, s2) with
s = q/μ — and the problem

    minimise  ½ xᵀ A x + bᵀ x   subject to  |s_i| ≤ ρ_i per cell,  C s = f,
                                           (and p ≥ 0, Σp = W/Δ with a pressure block),

A symmetric positive definite (DC-FFT block convolutions), C the shear's rows
(:class:`~contactpipe.solver.cg.Constraints`: forces, torque, or none).

Its optimality conditions are the contact laws: with the residual r = A x + b less the
rows' multipliers (Cᵀλ on the shear, ω3 on the pressure),

    r_i = 0 where |s_i| < ρ_i (stick),   r_i = −κ_i s_i, κ_i ≥ 0, where |s_i| = ρ_i (slip),
    r_p = 0 where p > 0,   r_p ≥ 0 where p = 0,

i.e. no slip increment in stick, a slip increment (−r) along the shear on the rim, and
the normal contact laws of :mod:`contactpipe.solver.cg`. Tests: the exact active-set
solution where the disks act as boxes, the conditions and scipy's SLSQP
(tests/test_tangential_solvers.py).

The iteration, over all contact cells at once:

* stick cells (|s| < ρ), and slip cells whose residual points into the disk (they
  re-enter), move along the residual;
* the other slip cells may only turn on their circle |s| = ρ: the variable is their slip
  angle θ (Zhao, Vollebregt & Oosterlee 2014, "A fast nonlinear conjugate gradient based
  method for 3D frictional contact problems"); the previous direction is transported to
  the current tangents;
* the direction is the residual filtered by the (−Δ)^½ filter shifted by the circles'
  curvature along the turning cells' tangents (:func:`direction`, :func:`slip_axes`) — in
  two frequency bands, each scaled by the cells' own diagonal at its stiffness, where the
  shift is large — or without a filter TangCG's diagonal scaling;
* the line search measures the step's curvature along the circles, not only along their
  tangents (:func:`curved`): a turning cell's Hessian is the operator's plus the circle's
  curvature |r·q̂|/ρ;
* no turning cell turns by more than ``Tuning.spin`` in one step: a cell that would has its
  own step shortened (the others take the full one);
* after the step, stick cells pushed past the disk are projected radially (they join the
  slip set), turning cells put back on their circles, the rows restored by projecting the
  stick cells (:func:`restore_rows`);
* the pressure block, when given, is Polonsky & Keer's: p clipped at 0, its row restored
  by a clipped shift of the free cells, its direction the (−Δ)^½ filter scaled to K33;
* the conjugate sequence restarts where a set changes.

Each iteration costs one operator application, applied in its halves
(:class:`contactpipe.solver.blocks.BlockOperator`): the direction's spectra give the line
search's curvature tᵀA t by Parseval's theorem, and A x follows the projected step through
one set of inverse transforms of −τ A t plus the projection's correction d, which so costs
its forward transforms only (a block that did not move costs none). A correction is left
out of A x while the corrections summed stay below ``Tuning.defer`` x tol; where the solve
converges, what is left out and the caller's next point (``follow``: the next coupling
pass's start, the instant's final state) ride on the last step the same way.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .cg import BlockSums, disk_project, project_rows
from .ledger import Ledger, Move
from .options import TUNING, Tuning
from .projection import on_bound

__all__ = ["DiskOptions", "DiskResult", "PressureBlock", "curvature", "curved", "direction",
           "disk_cg", "disk_start", "magnitude", "restore_rows", "shortened", "slip_axes"]

@dataclass
class DiskResult:
    """Outcome of :func:`disk_cg`: ``Ax`` is A times this result's own ``x``."""

    x: np.ndarray               # the iterate, or ``follow``'s point where it moved on
    Ax: np.ndarray | None       # A x [m]; None only where ``exact`` False let some wait
    iterations: int
    residual: float             # the last step's size, or the rows' miss, relative
    converged: bool
    iterate: np.ndarray | None = None   # the CG's last iterate (x unless follow moved)
    move: Move | None = None            # what ``follow`` decided, where it was called


@dataclass
class _Residual:
    """An iteration's reduced residual and its preconditioned direction (:func:`_residual`)."""

    gr: np.ndarray      # the residual less the rows' multipliers
    gt: np.ndarray      # gr cut to the tangents on turning cells
    z: np.ndarray       # the preconditioned direction on the working sets
    curv: np.ndarray    # the circles' curvature (:func:`curvature`)
    qhat: np.ndarray    # the slip directions q̂ of the cells at their bound
    cells: tuple        # (movable, stick, turning)
    sets: tuple         # the sets whose change restarts the conjugate sequence
    entered: bool       # a cell re-entered its disk (or the pressure's working set)
    lam: np.ndarray     # the rows' multipliers


@dataclass
class PressureBlock:
    """The pressure block of a joint solve: p ≥ 0 and Σp = ``target`` [Pa] (W/Δ); its
    direction is the (−Δ)^½ filter of the shear block, unshifted, times ``ratio``
    (K11 : K33 at the grid's Nyquist corner, so that it approximates K33⁻¹)."""

    target: float
    ratio: float

    def __post_init__(self):
        self.row = BlockSums([self.target])

    def residual(self, g, p):
        """(reduced residual, working set, whether a cell re-entered, multiplier ω3 [m])
        of Polonsky-Keer's iteration: the free cells p > 0, and the cells at 0 whose
        residual points inwards."""
        free = p > 0
        lam = float(g[free].mean()) if free.any() else 0.0
        gr = g - lam
        released = ~free & (gr < 0)
        work = free | released
        if released.any():
            lam = float(g[work].mean())
            gr = g - lam
        return np.where(work, gr, 0.0), work, bool(released.any()), lam

    def direction(self, M, gr, work):
        """The filtered residual on the working set, Σ over it kept at zero [Pa]."""
        if not work.any():
            return np.zeros_like(gr)
        z = self.ratio * M(gr, 0.0) if M is not None else gr.copy()
        z *= work
        z -= z.sum() / np.count_nonzero(work)
        z *= work
        return z

    def restore(self, p):
        """p clipped at 0 and Σp restored by a clipped shift of the cells in contact."""
        p = np.maximum(p, 0.0)
        zero, inf = np.zeros_like(p), np.full_like(p, np.inf)
        return self.row.restore(p[None], zero[None], inf[None], (p > 0)[None])[0]


def magnitude(v):
    """|v| per cell of a vector field v (2, N1, N2), as sqrt(v1² + v2²): a third of
    ``np.hypot``'s time, which guards against overflow that shear in Pa never reaches (the
    CG takes three magnitudes per iteration) [unit of v]."""
    m = v[0] * v[0]
    m += v[1] * v[1]
    return np.sqrt(m, out=m)


def restore_rows(q, rho, con, stick):
    """Meet the rows again by projecting the stick cells (then, when they cannot carry
    them, every contact cell) onto their disks and the rows: one shift vector, found by
    a dual Newton solve (:func:`contactpipe.solver.cg.project_rows`). Under the force rows
    alone the shift is first had in closed form, uniform over the cells
    (:meth:`~contactpipe.solver.cg.Constraints.shift`): where it keeps them in their disks
    it is the projection (the CG restores its rows after nearly every step; the dual
    Newton solve cost a fifth of a fretting step's time)."""
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


def disk_start(q0, rho, con, tol, snap=TUNING.snap):
    """A warm start within the disks (zero off the contact), its cells within ``snap``
    x tol of their bound put on it (else a bound raised by rounding turns slip cells into
    stick cells, which slide back in tens of iterations), the rows met."""
    movable = rho > 0
    q, _ = disk_project(np.where(movable, q0, 0.0), rho)
    mag = magnitude(q)
    near = movable & (mag >= rho * (1.0 - snap * tol)) & (mag > 0)
    q[:, near] *= rho[near] / mag[near]
    return restore_rows(q, rho, con, movable & ~near)


def curvature(radial, rho, turning):
    """The circles' curvature |r·q̂|/ρ on turning cells, 0 elsewhere: ``radial`` the
    residual along q̂, ``rho`` the bound with 1 off the contact.

    A turning cell q = ρ(cos θ, sin θ) has d²f/dθ² = ρ² e_θ·A e_θ − ρ r·q̂: along the
    tangent its Hessian is the operator's plus this diagonal, which the line search
    (:func:`curved`) and the filter's shift (:func:`direction`) both take in."""
    return np.where(turning, np.abs(radial) / rho, 0.0)


def curved(tAt, t, curv) -> float:
    """tᵀ(A + D) t: the curvature of the objective along the step t (``tAt`` = tᵀA t;
    the shear is t's last two components), D the circles' curvature on turning cells
    (:func:`curvature`; t is tangent there).

    The step along a tangent alone, tᵀA t, overshoots where the circle bends away, and a
    CG whose every set is fixed then converges linearly, each iteration gaining little;
    with this curvature the same solves take a fraction of the FFT pairs
    (docs/design-choices.md, D17)."""
    return float(tAt) + float(np.sum(curv * (t[-2] * t[-2] + t[-1] * t[-1])))


def slip_axes(qhat, turning):
    """The turning cells' principal tangent axes and the share of their tangents along
    each.

    Returns
    -------
    axes : ndarray (2, 2)
        Orthonormal rows e_c: the eigenvectors of Σ t̂ t̂ᵀ over the turning cells, t̂ the
        tangent of each circle (q̂ turned by 90°).
    share : ndarray (2,)
        Σ (t̂·e_c)² over the cells' count [1], summing to 1: (0, 1) when every cell slips
        along ±e_0 (a fretting load, its tangents across it), (½, ½) when the directions
        spread evenly."""
    t1, t2 = -qhat[1][turning], qhat[0][turning]
    J = np.array([[t1 @ t1, t1 @ t2], [t1 @ t2, t2 @ t2]])
    w, V = np.linalg.eigh(J)
    total = float(w.sum())
    return V.T, (np.maximum(w, 0.0) / total if total > 0.0 else np.full(2, 0.5))


def direction(M, gt, curv, qhat, a_self, free, turning, tuning=TUNING):
    """The preconditioned shear residual z (before the rows are kept) [Pa]: ``gt`` the
    residual (tangential on turning cells) [m], ``curv`` the circles' curvature [m/Pa]
    (:func:`curvature`), ``a_self`` the self-influence [m/Pa], all in q units.

    ``M`` None: TangCG's diagonal scaling, relative to a stick cell. Else the operator's
    ``tangential_preconditioner``, on the components along the turning cells' axes e_c
    (:func:`slip_axes`): z_c = S_c M(S_c gt_c, d̄_c) [Pa], M ≈ (K_cc + d̄_c)⁻¹ the
    inverse of the block's model symbol along e_c (anisotropic: K_cc is 1/(1 − ν_e)
    times stiffer for modes varying across e_c than along it) shifted by
    d̄_c = ``tuning.curvature_shift`` x the turning cells' median circle curvature x the
    share of their tangents along e_c, S_c = √((a + d̄_c)/(a + d_i)) each cell's own
    diagonal (d_i = 0 on free cells); z turned back to x1, x2 and cut back
    to the tangents on turning cells.

    Where d̄_c > ``tuning.band_gate`` x a, the component is filtered in two bands instead
    (``M``'s ``band``, which sum to the unshifted filter):
    z_c = H_c M_high(H_c gt_c, d̄_c) + L_c M_low(L_c gt_c, d̄_c), H_c = √(K̂_f/(K̂_f + d_i))
    the cells' diagonal at the finest mode's stiffness K̂_f, L_c = √(k/(k + d_i)) at
    k = ``tuning.low_band`` x d̄_c (1 on free cells in both). A stick cell then keeps the
    unshifted filter at every frequency, where one band over-weighted its smooth shear
    (a + d̄_c)/a times (the top eigenvalue of the preconditioned Hessian, which grows as
    the grid is refined), and a turning cell is scaled by its own curvature where the
    curvature outweighs K̂. One more field filtered (a quarter of an FFT pair) buys a
    smaller condition number and iterations that grow far less with the grid than one
    band's (docs/design-choices.md, D16).

    The curvature outweighs the self-influence 2-10 times on a fretting step's slip
    annulus, so the unshifted filter (the scalar CG's) is no better than the diagonal;
    shifted, the iterations fall by a third. It acts only along the tangents: under a
    fretting load the turning cells slip along ±x1 and turn along x2, so shifting x1 too
    mis-scaled the stick cells' x1 shear for nothing (shifting along the tangents alone
    lowered the preconditioned Hessian's condition number; docs/design-choices.md, D16)."""
    if M is None:
        return np.where(free | turning, gt * (a_self / (a_self + curv)), 0.0)
    if turning.any():
        axes, share = (slip_axes(qhat, turning) if tuning.shift_along_tangents
                       else (np.eye(2), np.ones(2)))
        shift = tuning.curvature_shift * float(np.median(curv[turning])) * share
    else:
        axes, shift = np.eye(2), np.zeros(2)
    g = np.einsum("ci,i...->c...", axes, gt)
    act = free | turning
    banded = shift > tuning.band_gate * a_self
    one = ~banded
    z = np.empty_like(g)
    if one.any():
        S = np.sqrt(np.where(act, 1.0 / (a_self + curv), 0.0))   # one field's root
        Sc = np.sqrt(a_self + shift[one])[:, None, None] * S
        z[one] = M(Sc * g[one], shift[one], axis=axes[one])
        z[one] *= Sc
    for c in np.flatnonzero(banded):
        d = shift[c]
        z[c] = 0.0
        for band, k in (("high", M.finest), ("low", tuning.low_band * d)):
            B = np.sqrt(np.where(turning, k / (k + curv), act))
            z[c] += B * M(B * g[c], d, band=band, axis=axes[c])
    z = np.einsum("ci,c...->i...", axes, z)
    along = qhat[0] * z[0]                  # z's part along q̂, cut off turning cells
    along += qhat[1] * z[1]
    along *= turning
    z -= along * qhat
    return z


def shortened(t, tau, rho, turning, limit=TUNING.spin):
    """Per cell, the fraction of the step τ t that a turning cell may take without turning
    by more than ``limit`` [rad] (its tangent step τ |t| at most limit ρ), 1 elsewhere; None
    where every cell takes the whole step. Shortening the cells that would turn too far,
    and not the step of all, keeps the others' progress: capping τ on the first
    tangential step of the bench's fretting (the preload's radial shear turned round to
    the load) made every step of its second pass a restart, several times the iterations
    (docs/design-choices.md, D17)."""
    if not turning.any():
        return None
    spin = magnitude(t[-2:])
    spin *= tau / rho
    if not float(spin.max(where=turning, initial=0.0)) > limit:
        return None
    return np.where(turning & (spin > limit), limit / np.maximum(spin, limit), 1.0)


def _conjugate(t, z, rz, rz_old, gr, qhat, turning):
    """The next direction from the last one ``t``: its shear (the last two components)
    transported onto the current tangents of turning cells, conjugated with z
    (rz = gt·z); or z itself, a new conjugate sequence, where that would not descend."""
    tr = qhat[0] * t[-2] + qhat[1] * t[-1]
    moved = t.copy()
    moved[-2:] = np.where(turning, t[-2:] - tr * qhat, t[-2:])
    t_new = z + (rz / rz_old) * moved
    return t_new if float(np.sum(gr * t_new)) > 0.0 else z


def _change(x_new, x, scale) -> float:
    """Σ|x_new − x| over ``scale`` [1]."""
    return float(np.abs(x_new - x).sum()) / scale


def _step(x, tau, t, rho, con, cells, pressure, scale, short=None):
    """One step x − τ t projected: p clipped at 0 and its row restored; the shear of a
    cell that would turn too far moved by τ ``short`` t only (``short`` per cell, 1 where
    the step is whole; None: none), stick cells pushed past their disk projected
    radially, turning cells put back on their circles, the rows restored.
    Returns (x_new, d, the step's size, its normaliser): d = x_new − (x − τ t) the
    projection's correction (None where nothing moved), the size relative (Σ|x_new − x|
    over the normaliser: ``scale``, or Σ|x_new| where it is None)."""
    movable, stick, turning = cells
    x_new = x - tau * t
    s = x_new[-2:] if short is None else x[-2:] - (tau * short) * t[-2:]
    m = magnitude(s)
    over = movable & (m > rho)
    fix = over | (turning & (m > 0))
    clipped = pressure is not None and bool((x_new[0] < 0).any())
    projected = clipped or bool(fix.any())
    stepped = x_new.copy() if projected else x_new
    if clipped:
        x_new[0] = pressure.restore(x_new[0])
    if fix.any():
        onto = np.divide(rho, m, out=np.ones_like(m), where=fix)   # 1 where nothing moves
        x_new[-2:] = restore_rows(s * onto, rho, con, stick & ~over)
    if scale is None:               # the stacked measure, over the projected iterate
        scale = max(float(np.abs(x_new).sum()), 1e-300)
    err = _change(x_new, x, scale)
    if not projected:
        return x_new, None, err, scale
    d = x_new - stepped
    return x_new, (d if d.any() else None), err, scale


def _residual(x, g, rho, rho_safe, movable, con, lam, M, a_self, unit, pressure, tuning):
    """An iteration's :class:`_Residual`: ``g`` = A x + b; the direction z is
    :func:`direction`'s on the shear, the pressure block's own on p."""
    s = x[-2:]
    mag = magnitude(s)
    at_bound = on_bound(mag, rho)
    at_bound &= movable
    stick = movable & ~at_bound
    if stick.any():
        lam = con.fit(g[-2:], stick)
    gr = g                                  # the caller's A x + b, reduced in place
    gr[-2:] -= con.field(lam)
    qhat = np.zeros_like(s)                 # s / |s| on the cells at their bound
    np.divide(s, mag, out=qhat, where=at_bound & (mag > 0))
    radial = qhat[0] * gr[-2]
    radial += qhat[1] * gr[-1]
    released = radial > 0
    released &= at_bound
    turning = at_bound & ~released
    free = stick | released
    gt = gr.copy()
    cut = radial * qhat                     # the radial part, taken off turning cells
    cut *= turning
    gt[-2:] -= cut
    curv = curvature(radial, rho_safe, turning)
    z = np.empty_like(x)
    zs = direction(M, gt[-2:], curv / (unit * unit), qhat, a_self, free, turning, tuning)
    zs *= 1.0 / (unit * unit)               # direction is linear in the residual
    z[-2:] = con.keep(zs, free)
    sets: tuple[np.ndarray, ...] = (free, turning)
    entered = bool(released.any())
    if pressure is not None:
        gr[0], work, back, _ = pressure.residual(g[0], x[0])
        gt[0] = gr[0]
        z[0] = pressure.direction(M, gr[0], work)
        sets, entered = sets + (work,), entered or back
    return _Residual(gr, gt, z, curv, qhat, (movable, stick, turning), sets, entered, lam)


@dataclass(frozen=True)
class DiskOptions:
    """The options of :func:`disk_cg`.

    Attributes
    ----------
    tol, max_iter :
        Relative step size at which it stops; iterations allowed.
    M : callable, optional
        The operator's ``tangential_preconditioner`` (in q units); None: diagonal scaling.
    a_self : float
        K11's self-influence [m/Pa].
    unit : float
        q per unit of the shear variable (μ for s = q/μ, 1 for q) [Pa/unit].
    scale : float, optional
        The step's size is Σ|Δx| over it; None: over Σ|x| (the stacked joint measure).
    tuning : Tuning
        ``defer`` (the default ledger's deferral), ``stall``, ``spin``,
        ``curved_line_search`` and the filter's constants (:func:`direction`).
    """

    tol: float
    max_iter: int
    M: Callable | None = None
    a_self: float = 0.0
    unit: float = 1.0
    scale: float | None = None
    tuning: Tuning = TUNING


def disk_cg(A, b, start, rho, con, options: DiskOptions, ledger: Ledger | None = None,
            pressure: PressureBlock | None = None) -> DiskResult:
    """The projected CG (module notes) from a feasible start.

    Parameters
    ----------
    A : BlockOperator
        x ↦ A x, applied in halves (:class:`contactpipe.solver.blocks.BlockOperator`).
    b : ndarray
        The linear term, x's shape [m].
    start : Start
        x (2, N1, N2), or (3, N1, N2) with a pressure block first: the shear within its
        disks and on its rows (:func:`disk_start`), the pressure ≥ 0 on its row; and its
        A x [m].
    rho : ndarray (N1, N2)
        The shear's bound, in its unit (μp for q, p_lag for s = q/μ).
    con : Constraints
        The shear's rows on (2, N1, N2).
    options : DiskOptions
        Tolerance, iterations, the filter, the scale, the tuning.
    ledger : Ledger, optional
        A x's bookkeeping (default: corrections deferred by ``options.tuning.defer``,
        exact). Its ``follow(x) -> Move`` gives, where the solve converges, the point the
        caller moves to next, whose A x′ rides on the last step's inverse transforms.
    pressure : PressureBlock, optional
        x[0] is the pressure.

    Returns
    -------
    DiskResult
        ``x`` is ``follow``'s point where it moved the solve on (``iterate`` the converged
        iterate, ``move`` the decision), ``Ax`` its product; a solve that did not
        converge takes in what its A x left out by one product.
    """
    if ledger is None:
        ledger = Ledger(update=True, defer=options.tuning.defer)
    x, tol, max_iter, tuning = start.x, options.tol, options.max_iter, options.tuning
    M, a_self, unit, scale = options.M, options.a_self, options.unit, options.scale
    movable = rho > 0
    rho_safe = np.where(movable, rho, 1.0)      # divides where only contact cells count
    Ax = np.array(start.Ax, dtype=float)        # updated in place
    t = np.zeros_like(x)
    rz_old, sets_old = 1.0, None
    err, best, best_it = np.inf, np.inf, 0
    lam = np.zeros(con.m)
    book, it = ledger.bind(A, tol), 0
    for it in range(1, max_iter + 1):
        if it - best_it > tuning.stall:    # no progress: leave it to the caller's fallback
            break
        res = _residual(x, Ax + b, rho, rho_safe, movable, con, lam, M, a_self, unit,
                        pressure, tuning)
        lam, turning = res.lam, res.cells[2]
        rz = float(np.sum(res.gt * res.z))
        if not rz > 0.0:
            err = 0.0 if rz <= 0.0 else np.inf
            break
        reset = (res.entered or sets_old is None
                 or not all(np.array_equal(a, c) for a, c in zip(res.sets, sets_old, strict=True)))
        t = res.z if reset else _conjugate(t, res.z, rz, rz_old, res.gr, res.qhat, turning)
        rz_old, sets_old = rz, res.sets
        tAt = book.curvature(t)[1]
        denom = curved(tAt, t, res.curv) if tuning.curved_line_search else float(tAt)
        if denom <= 0.0:
            err = 0.0
            break
        tau = float(np.sum(res.gr * t)) / denom
        short = shortened(t, tau, rho_safe, turning, tuning.spin)
        x_new, d, err, norm = _step(x, tau, t, rho, con, res.cells, pressure, scale, short)
        if not err >= 0.0:      # NaN: the iterate is lost
            err = np.inf
            break
        book.advance(Ax, None, tau, None, x_new, err < tol, d, norm)   # A x += A(−τ t + d)
        x = x_new
        if err < tol:
            break
        if err < 0.5 * best:
            best, best_it = err, it
    return _result(book, x, Ax, rho, con, pressure, err, tol, it)


def _result(book, x, Ax, rho, con, pressure, err, tol, it):
    """:func:`disk_cg`'s result: converged where the last step and the rows' miss are
    within tol; a converged solve that took no step to fold its end into (no descent was
    left) moves to ``follow``'s point, or takes in what it left out, by one product
    (:meth:`~contactpipe.solver.ledger.Ledger.close`)."""
    # relative to what the disks carry, or where they carry less than the rows ask (an
    # open contact: rho = 0), to the rows' targets, so that it stays finite
    miss = float(np.abs(con.residual(x[-2:])).max(initial=0.0)) / max(
        float(rho.sum()), float(np.abs(con.target).max(initial=0.0)), 1e-300)
    if pressure is not None:
        miss = max(miss, abs(float(x[0].sum()) - pressure.target) / max(pressure.target,
                                                                         1e-300))
    err = max(float(err), miss)
    ok = bool(err < tol) and bool(np.all(np.isfinite(x)))
    Ax = book.close(x, Ax, ok)
    y, Ay = book.outcome(x, Ax)
    return DiskResult(y, Ay, it, err, ok, x, book.move)
