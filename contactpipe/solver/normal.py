"""The uncoupled normal contact problem (UNC): pressure and contact area.

With every tangential traction and the viscoelastic history known (added to the gap), find
the pressure p >= 0 such that the gap (paper eq. 3)

    h = hi + u3 − ω3 − φ1 x2 − φ2 x1

closes where p > 0 and stays open elsewhere (eq. 5), and the pressure carries what is
force-controlled of W = Δ Σ p, M1 = Δ Σ p x2, M2 = Δ Σ p x1 (eq. 1). The solver is
Polonsky & Keer's conjugate-gradient method (:func:`contactpipe.solver.cg.box_cg` with
lo = 0, hi = inf): a force-controlled freedom is a constraint row whose multiplier is its
rigid motion (ω3, φ1, φ2: the gap is affine in them); a displacement-controlled one is a
known rigid motion in the linear term. Under force control of W alone with the rotations
held at zero (:class:`NormalControl` absent) it is the one-row solver of before.

Two accelerations keep the iterations per solve nearly flat as the grid is refined
(docs/design-choices.md, "Iterations flat in the grid"):

- *preconditioning*: the CG directions come from the gradient filtered by the symbol of
  (−Δ)^½ on the unpadded grid (:meth:`ContactOperator.normal_preconditioner`, a quarter
  of an FFT pair per iteration), which undoes the operator's 1/|ξ| smoothing;
- *a multilevel start* for a cold solve (no warm start): the same problem on the grid
  coarsened by two (recursively, down to :data:`COARSEST` cells a side), solved to
  :data:`COARSE_TOL`, prolonged bilinearly as the first iterate. The coarse work is
  charged to the fine grid's FFT-pair count at the ratio of the cell counts (1/4 per
  level; the true cost ratio of a transform of a quarter the size is lower).

The fine solve still runs to the caller's tolerance from that start, so the answer is the
plain solver's to within the tolerance.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .cg import (
    BoxOptions,
    Constraints,
    Outcome,
    Start,
    box_cg,
    cg_with_fallback,
    fista,
    project_rows,
)

__all__ = ["COARSE_TOL", "COARSEST", "NormalControl", "NormalResult", "prolong", "restrict",
           "solve_normal"]

#: The multilevel start coarsens while every side stays at or above this many cells [1].
COARSEST = 16
#: Relative tolerance of the coarse solves of the multilevel start [1] (the caller's where
#: that is looser): a start needs no more than the coarse grid's own accuracy, and 1e-3 to
#: 1e-5 cost the same to within 10 % (docs/design-choices.md).
COARSE_TOL = 1e-3


@dataclass
class NormalResult:
    p: np.ndarray          # pressure [Pa]
    omega3: float          # normal approach [m]
    Ap: np.ndarray         # K33 ⊛ p [m]
    iterations: int
    residual: float
    converged: bool
    phi: np.ndarray = field(default_factory=lambda: np.zeros(2))   # (φ1, φ2) [rad]


@dataclass(frozen=True)
class NormalControl:
    """How the normal sub-problem's three freedoms are held at one instant.

    Attributes
    ----------
    force : ndarray (3,)
        W [N], M1, M2 [N m]; NaN where the freedom is displacement-controlled.
    motion : ndarray (3,)
        ω3 [m], φ1, φ2 [rad]; NaN where the freedom is force-controlled.
    x1, x2 : ndarray or None
        Cell centres (N1,), (N2,) [m]: the moment arms (None where W alone is held).
    """

    force: np.ndarray
    motion: np.ndarray
    x1: np.ndarray | None       # None only where W alone is held (``legacy``)
    x2: np.ndarray | None

    @property
    def legacy(self) -> bool:
        """W force-controlled and both rotations held at zero: the one-row problem."""
        return bool(not np.isnan(self.force[0]) and np.isnan(self.force[1:]).all()
                    and np.all(self.motion[1:] == 0.0))

    def arms(self):
        """(x1, x2) on the grid (N1, N2) and the normalising length L [m]."""
        assert self.x1 is not None and self.x2 is not None, "moment arms x1, x2 needed"
        X1, X2 = np.meshgrid(self.x1, self.x2, indexing="ij")
        L = max(float(np.abs(self.x1).max()), float(np.abs(self.x2).max()), 1e-300)
        return X1, X2, L


def restrict(a):
    """The mean of each 2 x 2 block of cells: a field (N1, N2) on the grid coarsened by
    two (N1, N2 even); a linear field keeps its values at the coarse cell centres."""
    return 0.25 * (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2])


def prolong(a):
    """Cell-centred bilinear interpolation of a coarse pressure (n1, n2) onto the grid
    refined by two (2 n1, 2 n2): weights 9/16, 3/16, 3/16, 1/16 of the nearest coarse
    cells, the edge cells continued outwards; zero in the fine cells of a coarse cell
    without pressure (the start then lies inside the contact: a cell that must join it
    is released by the CG at no cost, one that must leave it costs a projection and an
    FFT pair)."""
    n1, n2 = a.shape
    e = np.pad(a, 1, mode="edge")
    out = np.empty((2 * n1, 2 * n2))
    for i, di in ((0, -1), (1, 1)):
        for j, dj in ((0, -1), (1, 1)):
            out[i::2, j::2] = np.where(
                a > 0.0, (9.0 * a + 3.0 * e[1 + di:n1 + 1 + di, 1:-1]
                          + 3.0 * e[1:-1, 1 + dj:n2 + 1 + dj]
                          + e[1 + di:n1 + 1 + di, 1 + dj:n2 + 1 + dj]) / 16.0, 0.0)
    return out


def _coarse_start(op, gap0, W, cell_area, tol, max_iter, control, precondition):
    """(the first iterate from the solve on the grid coarsened by two, its iterations), or
    (None, 0) where the grid cannot be coarsened. The coarse FFT pairs are charged to
    ``op.conv`` at the ratio of the cell counts."""
    n1, n2 = gap0.shape
    if n1 % 2 or n2 % 2 or min(n1, n2) < 2 * COARSEST:
        return None, 0
    coarse = op.coarse_normal()
    if coarse is None:
        return None, 0
    ctl = None
    if control is not None:
        ctl = NormalControl(control.force, control.motion,
                            0.5 * (control.x1[0::2] + control.x1[1::2]),
                            0.5 * (control.x2[0::2] + control.x2[1::2]))
    before = coarse.conv.pairs
    res = solve_normal(coarse, restrict(gap0), W, 4.0 * cell_area,
                       np.zeros((n1 // 2, n2 // 2)), max(tol, COARSE_TOL), max_iter,
                       control=ctl, precondition=precondition)
    op.conv.charge((coarse.conv.pairs - before) * 0.25)
    if not np.all(np.isfinite(res.p)):
        return None, res.iterations
    return prolong(res.p), res.iterations


def solve_normal(op, gap0, W, cell_area, p0, tol, max_iter, Ap0=None,
                 control: NormalControl | None = None, precondition: bool = True,
                 multilevel: bool = True) -> NormalResult:
    """Normal problem (Polonsky & Keer 1999), with up to three multipliers.

    Parameters
    ----------
    op : ContactOperator
    gap0 : ndarray
        Initial gap plus every known normal displacement [m].
    W : float
        Normal force [N] (ignored when ``control`` is given).
    p0 : ndarray
        Warm start [Pa].
    Ap0 : ndarray, optional
        K33 ⊛ p0 when known (saves one FFT pair).
    control : NormalControl, optional
        Force or displacement control of each of (W, M1, M2) / (ω3, φ1, φ2). Absent: W
        force-controlled and the rotations held at zero.
    precondition : bool
        Preconditioned CG (the spectral inverse of K33); False: plain Polonsky-Keer.
    multilevel : bool
        A cold solve (p0 = 0 everywhere) starts from the solve on the coarsened grid.

    Returns
    -------
    NormalResult
        ``iterations`` counts those of every grid of a multilevel start. ``omega3`` and
        ``phi`` are the multipliers of the force-controlled freedoms and the
        given values of the others. Under displacement control the contact may open
        entirely: p = 0 everywhere is then the (converged) answer.
    """
    if control is not None and control.legacy:
        W, control = float(control.force[0]), None
    if op.rigid or (control is None and W <= 0.0):
        if control is None:
            return _force_only(op, gap0, W, cell_area, p0, tol, max_iter, Ap0)
        # no compliance for this increment: only a force-controlled W has a meaning
        # there, or nothing at all asked (no force, a motion that closes no gap)
        return _rigid_rest(gap0, control)
    fast = {"precondition": op.normal_preconditioner() if precondition else None}
    coarse_its = 0
    if multilevel and not np.any(p0):
        start, coarse_its = _coarse_start(op, gap0, W, cell_area, tol, max_iter, control,
                                          precondition)
        if start is not None:
            p0, Ap0 = start, None
    if control is None:
        res = _force_only(op, gap0, W, cell_area, p0, tol, max_iter, Ap0, **fast)
        res.iterations += coarse_its
        return res
    X1, X2, L = control.arms()
    force, motion = np.asarray(control.force, float), np.asarray(control.motion, float)
    arms = (np.ones_like(gap0), X2 / L, X1 / L)     # rows of W, M1, M2 (normalised)
    fields = (np.ones_like(gap0), X2, X1)           # the gap's change per ω3, φ1, φ2
    b = np.array(gap0, dtype=float)
    rows, targets, which = [], [], []
    for i in range(3):
        if np.isnan(force[i]):
            if motion[i] != 0.0:
                b = b - motion[i] * fields[i]
        else:
            rows.append(arms[i])
            targets.append(force[i] / cell_area / (1.0 if i == 0 else L))
            which.append(i)
    con = Constraints(np.array(rows).reshape((len(rows),) + gap0.shape), targets)
    o = _with_rows(op, b, con, p0, Ap0, tol, max_iter, fast)
    reached = motion.copy()
    for j, i in enumerate(which):
        reached[i] = o.multiplier[j] / (1.0 if i == 0 else L)
    return NormalResult(o.x, float(reached[0]), o.Ax, o.iterations + coarse_its, o.residual,
                        o.converged, phi=reached[1:].copy())


def _with_rows(op, b, con, p0, Ap0, tol, max_iter, fast):
    """The normal problem under general rows: the CG first; where it stalls, the
    projected gradient onto {p >= 0, C p = f} (:func:`~contactpipe.solver.cg.fista`) and
    the CG again (:func:`~contactpipe.solver.cg.cg_with_fallback`). The CG's active set
    can cycle where the rows pin the few free cells (a contact one cell wide under a
    force-controlled moment: two free cells for two rows, the pressure jumping between
    cell pairs, Σ|Δp| = 2 Σp at every step for 2000 iterations); the projected gradient
    always converges. Returns an :class:`~contactpipe.solver.cg.Outcome` (p, K33 p),
    its ``multiplier`` the rows' multipliers: the CG's, or fitted to the free cells of the
    projected gradient's p."""
    lo, hi = np.zeros_like(b), np.full_like(b, np.inf)
    everywhere = np.ones(b.shape, dtype=bool)

    def cg(x0, Ax0, tol_, budget):
        r = box_cg(op.normal, b, lo, hi, con, Start(x0, Ax0),
                   BoxOptions(tol_, budget, "scale", precondition=fast["precondition"]))
        return Outcome(r.x, r.Ax, r.iterations, r.residual, r.converged, r.multiplier)

    def pg(x0, Ax0, tol_, budget):
        scale = max(float(np.abs(x0).sum()), float(np.abs(con.target).max(initial=0.0)),
                    1e-300)
        o = fista(op.normal, b, lambda y: project_rows(y, con, everywhere, "box", lo=lo, hi=hi),
                  x0, op.normal_norm(), tol_, budget, scale, Ax0=Ax0)
        size = max(float(np.abs(o.x).sum()), float(np.abs(con.target).max(initial=0.0)),
                   1e-300)
        miss = float(np.abs(con.residual(o.x)).max(initial=0.0)) / size
        return Outcome(o.x, o.Ax, o.iterations, max(o.residual, miss),
                       o.converged and miss < tol_)

    o = cg_with_fallback(cg, pg, p0, Ap0, tol, max_iter)
    if o.multiplier is None:
        free = o.x > 0.0
        o.multiplier = con.fit(o.Ax + b, free) if free.any() else np.zeros(con.m)
    return o


def _rigid_rest(gap0, control: NormalControl) -> NormalResult:
    """The normal problem of an instant without compliance under general controls: p = 0
    (converged) where every force-controlled freedom asks zero and the known motions
    leave every gap open (a free ω3 then touches: the least gap); else no pressure can
    answer (any closed gap asks an infinite one): not converged, with no residual
    (NaN), the caller naming the cause."""
    X1, X2, _ = control.arms()
    force, motion = np.asarray(control.force, float), np.asarray(control.motion, float)
    known = np.where(np.isnan(motion), 0.0, motion)
    h = gap0 - known[1] * X2 - known[2] * X1
    free_approach = np.isnan(motion[0])
    h_min = float(h.min())
    zero = np.zeros_like(gap0)
    asked = np.nan_to_num(force, nan=0.0)
    scale = max(float(np.abs(gap0).max()), abs(float(known[0])), 1e-300)
    if not np.any(asked) and (free_approach or h_min - known[0] >= -1e-12 * scale):
        reached = np.where(np.isnan(motion), 0.0, motion)
        reached[0] = h_min if free_approach else known[0]
        return NormalResult(zero, float(reached[0]), zero, 0, 0.0, True,
                            phi=reached[1:].copy())
    return NormalResult(zero, np.nan, zero, 0, np.nan, False)


def _force_only(op, gap0, W, cell_area, p0, tol, max_iter, Ap0, precondition=None):
    """W force-controlled, rotations held at zero (the one-row problem)."""
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
                 W / cell_area, Start(p0, Ap0),
                 BoxOptions(tol, max_iter, "scale", precondition=precondition))
    assert res.Ax is not None                  # the default ledger is exact
    return NormalResult(res.x, float(res.multiplier), res.Ax, res.iterations, res.residual,
                        res.converged)
