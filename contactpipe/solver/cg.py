"""Bound-constrained conjugate gradients with a force constraint.

Both uncoupled contact problems of the paper's inner loop have the structure of the
frictionless normal contact problem (paper §4): with the other traction and the history
known, find the cell tractions ``x`` that solve

    minimise  ½ xᵀ A x + bᵀ x   subject to   lo ≤ x ≤ hi  (per cell),   Σ x = S,

where ``A`` is a symmetric positive definite influence operator (a DC-FFT convolution),
``b`` the known part (gap, or known relative displacement), and ``S`` the imposed force
divided by the cell area. The Lagrange multiplier λ of the force constraint is the rigid
motion (the approach ω3, or the rigid shift increment Δω1). The optimality conditions are
exactly the contact laws: with the residual ``r = A x + b − λ``,

    r = 0 where lo < x < hi,   r ≥ 0 where x = lo,   r ≤ 0 where x = hi,

i.e. zero gap under pressure and a non-negative gap elsewhere (normal problem, lo = 0,
hi = ∞); zero slip increment in stick and a slip increment opposite to the residual, so
aligned with q, where |q| = μp (tangential problem, lo = −μp, hi = μp).

The iteration is Polonsky & Keer's (1999, Wear 231, 206-219): conjugate directions on the
working set (free cells plus those whose residual points into the admissible interval,
which re-enter and reset the conjugacy), exact line search, projection onto the bounds,
and restoration of the force by scaling (one-sided problem, as in Polonsky-Keer) or by a
shift of the free cells (two-sided problem, Vollebregt's BCCG idea). Every iteration costs
one FFT pair (``A t``); a second one is spent only when the projection changed the
iterate, which near convergence it no longer does.

General constraint rows (:class:`Constraints`): the force row Σx = S generalises to up to
three rows ``C x = f`` (paper eqs. 1-2: the force and the moments of the pressure, or the
shear's forces and torque), whose multipliers are the rigid motions (ω3, φ1, φ2) or
(Δω1, Δω2, Δφ3) (docs/conventions.md, the six freedoms). Each iteration fits the
multipliers to the working set by least squares (an m x m system, m <= 3), so the search
direction keeps C x fixed, and
the constraints are restored after a projection by the Euclidean projection of the free
cells onto {bounds, C x = f}: a damped dual Newton iteration on the m multipliers
(:func:`project_rows`). With no row at all
(displacement control: the rigid motion is known and sits in ``b``) the problem is a plain
bound-constrained QP and no multiplier is fitted.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .fallback import Outcome, cg_with_fallback, fista
from .ledger import Ledger, Move
from .ledger import dot as _dot
from .projection import (  # noqa: F401
    DAMPING,
    POLISH,
    _polish,
    _project_cells,
    _restore_by_shift,
    _shift_root,
    box_jacobian,
    box_project,
    disk_jacobian,
    disk_project,
    project_box_sum,
    project_rows,
)

__all__ = ["BlockSums", "BoxOptions", "BoxResult", "Outcome", "Start", "ComponentSums",
           "Constraints", "box_cg", "cg_with_fallback", "feasible_start", "fista",
           "project_box_sum", "project_rows", "box_jacobian", "box_project", "disk_jacobian",
           "disk_project"]


@dataclass
class BoxResult:
    """Outcome of :func:`box_cg`: ``Ax`` is A times this result's own ``x``."""

    x: np.ndarray          # the solution, or ``follow``'s point where it moved on
    multiplier: float | np.ndarray   # λ of the force row (an (m,) array with Constraints)
    Ax: np.ndarray | None  # A x (None only where ``exact`` False let corrections wait)
    iterations: int
    residual: float        # last relative change Σ|Δx| / scale
    converged: bool
    iterate: np.ndarray | None = None   # the CG's last iterate (x unless follow moved)
    move: Move | None = None            # what ``follow`` decided, where it was called


class Constraints:
    """Equality rows ``C x = f`` of an inner problem (at most three), on cell arrays.

    Parameters
    ----------
    rows : array_like (m, *shape)
        One array per row, the shape of the unknown x (e.g. (N1, N2), or (2, N1, N2) for
        the two shear components). Normalise them to entries of order 1 (a moment arm
        divided by the grid's half length) so that the force error of every row is
        measured in the same unit.
    target : array_like (m,)
        The row sums f, in the unit of x (a force divided by the cell area).
    sums : bool
        The rows are plain sums of disjoint components (the force rows): the multipliers
        are then fitted as plain means, the arithmetic of the one-row solver.
    """

    def __init__(self, rows, target, sums: bool = False):
        rows = np.asarray(rows, dtype=float)
        #: the row arrays (m, *shape); None in :class:`BlockSums`, which has none
        self.rows: np.ndarray | None = rows
        self.target = np.atleast_1d(np.asarray(target, dtype=float))
        self.m = int(rows.shape[0])
        self.sums = bool(sums)
        if self.target.shape != (self.m,):
            raise ValueError(f"{self.m} rows need {self.m} targets, got {self.target.shape}")

    @classmethod
    def none(cls, shape) -> Constraints:
        """No row: displacement control (a plain bound-constrained problem)."""
        return cls(np.zeros((0,) + tuple(shape)), np.zeros(0))

    def field(self, lam) -> np.ndarray | float:
        """Cᵀλ, the rigid motion of the multipliers (shape of x; 0.0 without rows)."""
        if self.m == 0:
            return 0.0
        assert self.rows is not None
        return np.tensordot(np.asarray(lam, dtype=float), self.rows, axes=1)

    def sums_of(self, x) -> np.ndarray:
        """C x (m,)."""
        assert self.rows is not None
        if self.sums:
            return np.array([float(x[r != 0].sum()) for r in self.rows])
        return np.array([float(np.sum(r * x)) for r in self.rows])

    def residual(self, x) -> np.ndarray:
        """C x − f (m,)."""
        return self.sums_of(x) - self.target

    def _on(self, cells):
        """The rows on ``cells`` (a mask over the last two axes), as an (m, k) matrix."""
        assert self.rows is not None
        return self.rows[..., cells].reshape(self.m, -1)

    def fit(self, g, cells) -> np.ndarray:
        """The multipliers λ (m,) that make g − Cᵀλ orthogonal to the rows on ``cells``
        (a mask over the grid: least squares over those cells; a plain mean per row for
        force rows)."""
        if self.m == 0 or not np.any(cells):
            return np.zeros(self.m)
        Cw = self._on(cells)
        gw = g[..., cells].reshape(-1)
        if self.sums:
            return np.array([gw[c != 0].mean() if np.any(c != 0) else 0.0 for c in Cw])
        return np.linalg.lstsq(Cw @ Cw.T, Cw @ gw, rcond=None)[0]

    def keep(self, z, cells) -> np.ndarray:
        """z changed on ``cells`` (a mask over the grid) only, so that C z = 0: a direction
        that keeps C x."""
        if self.m == 0 or not np.any(cells):
            return z
        Cw = self._on(cells)
        if self.sums:
            mu = self.sums_of(z) / np.count_nonzero(cells)
        else:
            mu = np.linalg.lstsq(Cw @ Cw.T, self.sums_of(z), rcond=None)[0]
        out = z.copy()
        lead = z.shape[:-2]
        out[..., cells] -= (mu @ Cw).reshape(lead + (-1,))
        return out

    def shift(self, y, cells, rho):
        """The disk projection of :func:`project_rows` in closed form where the rows admit
        one (:meth:`ComponentSums.shift`); None here: general rows need the dual solve."""
        return None

    def restore(self, x, lo, hi, free, movable):
        """x with C x = f again, by projecting the free cells (then, when they cannot carry
        the rows, every movable cell) onto {bounds, C x = f} (:func:`project_rows`)."""
        out = x
        for cells in (free, movable):
            if not cells.any():
                continue
            out = project_rows(x, self, cells, "box", lo=lo, hi=hi)
            tol = 1e-12 * (np.abs(self.target).max(initial=0.0) + np.abs(out).sum())
            if np.abs(self.residual(out)).max(initial=0.0) <= tol:
                return out
        return out


class ComponentSums(Constraints):
    """The force rows of a vector unknown x (m, N1, N2): Σ x[k] = f[k] over the grid, one
    row per component, with masks over the grid as in :class:`Constraints` (the vector
    form's Σq1 = T1/Δ, Σq2 = T2/Δ). The row arrays are kept for the callers that read
    them; the methods work component by component, with the arithmetic of the dense rows
    (a 1 or a 0 times each multiplier), so the results are the same bit for bit at a
    fraction of the element-wise work (the dense rows cost a boolean-indexed copy per row
    in every fit, keep and sum of the vector CG's iterations)."""

    def __init__(self, target, shape):
        target = np.atleast_1d(np.asarray(target, dtype=float))
        rows = np.zeros((target.size, target.size) + tuple(shape))
        for k in range(target.size):
            rows[k, k] = 1.0
        super().__init__(rows, target, sums=True)

    def field(self, lam):
        return np.asarray(lam, dtype=float).reshape(self.m, 1, 1)

    def sums_of(self, x):
        return x.reshape(self.m, -1).sum(axis=1)

    def fit(self, g, cells):
        if not np.any(cells):
            return np.zeros(self.m)
        return np.array([g[k][cells].mean() for k in range(self.m)])

    def keep(self, z, cells):
        if not np.any(cells):
            return z
        mu = self.sums_of(z) / np.count_nonzero(cells)
        return z - np.multiply(cells, mu.reshape(self.m, 1, 1))

    def shift(self, y, cells, rho):
        """The projection of y's ``cells`` onto {|x| <= rho, C x = f} (:func:`project_rows`,
        kind "disk", two components) when a uniform shift of those cells meets the rows
        inside their disks (then it is that shift, the multipliers' closed form); None
        otherwise."""
        n = np.count_nonzero(cells)
        if n == 0:
            return None
        d = (self.target - self.sums_of(y)) / n
        x = y + np.multiply(cells, d.reshape(self.m, 1, 1))
        m = x[0] * x[0]
        m += x[1] * x[1]
        out = m > rho * rho               # outside its disk (squared: no root needed)
        out &= cells
        return None if out.any() else x


class BlockSums(Constraints):
    """Force rows over the blocks of a stacked unknown x (m, N1, N2): Σ x[k] = f[k], one row
    per block, each with its own cells. The cell masks are then masks of x's whole shape
    (a pressure cell and a shear cell of one grid point may be free apart), unlike
    :class:`Constraints`, whose masks are over the grid. The rows are restored after a
    projection by a clipped shift of each block's free cells, as the one-row solver does.

    Used by the joint solve of a coupled instant (:mod:`contactpipe.solver.joint`): the
    pressure carries W, the shear T1, and the multipliers are (ω3, Δω1).
    """

    def __init__(self, target):
        self.target = np.atleast_1d(np.asarray(target, dtype=float))
        self.m = int(self.target.size)
        self.rows = None            # no row arrays: every method works block by block
        self._buf = None            # scratch of x's shape for the masked sums
        self._cells = None          # the last mask given, its 0/1 weights and counts
        self._weights = self._counts = None

    def field(self, lam):
        return np.asarray(lam, dtype=float).reshape(self.m, 1, 1)

    def sums_of(self, x):
        return x.reshape(self.m, -1).sum(axis=1)

    def weights(self, cells) -> np.ndarray:
        """``cells`` (a boolean mask of x's shape, not changed after it is given) as 0/1
        floats, cast once per mask: a product with a boolean mask casts it each time, at
        about twice a float product's cost, and box_cg takes several products with one
        working set (docs/design-choices.md, D36)."""
        if cells is not self._cells:
            if self._weights is None or self._weights.shape != cells.shape:
                self._weights = np.empty(cells.shape)
            np.copyto(self._weights, cells)
            self._counts = np.array([max(np.count_nonzero(c), 1)
                                     for c in cells.reshape(self.m, -1)])
            self._cells = cells
        assert self._weights is not None
        return self._weights

    def _means(self, v, cells):
        """The mean of v[k] over block k's cells (m, 1, 1), 0 where a block has none: by a
        product with the mask's weights in a kept scratch array (a boolean-indexed copy
        per block cost more). The cells are counted block by block: ``count_nonzero``
        along an axis sums a cast copy, slower (docs/design-choices.md, D22)."""
        if self._buf is None or self._buf.shape != v.shape:
            self._buf = np.empty(v.shape)
        w = self.weights(cells)
        sums = np.multiply(v, w, out=self._buf).reshape(self.m, -1).sum(axis=1)
        return (sums / self._counts).reshape(self.m, 1, 1)

    def fit(self, g, cells):
        return self._means(g, cells).ravel()

    def keep(self, z, cells):
        means = self._means(z, cells)
        return z - np.multiply(self.weights(cells), means, out=self._buf)

    def restore(self, x, lo, hi, free, movable=None):
        """Σ x[k] = f[k] again by a clipped shift of block k's free cells (then of every
        cell with room); a block whose sum already holds is kept as it is
        (:func:`_restore_by_shift`), so that the update of A x after a projection that
        clipped the shear alone skips the pressure block (1.5 FFT pairs instead of 2 in
        the joint solve)."""
        return np.stack([_restore_by_shift(x[k], lo[k], hi[k], self.target[k], free[k])
                         for k in range(self.m)])


# --------------------------------------------------------------------------- projections
def _start(start, lo, hi, target, restore, con, movable, apply):
    """The first iterate (``start.x`` with the constraints restored) and its A x.

    ``start.Ax`` is A of ``start.of`` when that is given, else of ``start.x``. Where the
    iterate differs from it, A x is recomputed; with ``start.of`` given it is updated
    instead, A x = Ax + A (x − of), which costs less when ``apply`` skips the blocks of
    the difference that are zero (the joint solve's pressure, when only slip cells moved).
    """
    Ax0 = start.Ax
    x, changed, factor = _restored(start.x, lo, hi, target, restore, con, movable)
    if Ax0 is None:
        return x, apply(x)
    if start.of is not None:
        return x, Ax0 + apply(x - start.of)
    if changed:
        return x, apply(x)
    return x, (Ax0 if factor == 1.0 else Ax0 * factor)


def feasible_start(x0, lo, hi, target, restore="scale"):
    """The start :func:`box_cg` makes of x0: clipped to its bounds and the force (or the
    rows) restored as ``restore`` says. A caller that hands box_cg this, with its A x,
    spends no product on the start."""
    con = target if isinstance(target, Constraints) else None
    return _restored(x0, lo, hi, target, restore, con, lo < hi)[0]


def _restored(x0, lo, hi, target, restore, con, movable):
    """The warm start projected onto the bounds and the rows: (x, changed, factor), with
    ``changed`` False where x is x0 or, for a pure rescaling, ``factor`` x0 (then
    A x = factor A x0)."""
    x0 = np.asarray(x0, dtype=float)
    x = np.clip(x0, lo, hi)
    clipped = not np.array_equal(x, x0)
    if con is not None:
        before = x.copy()
        if con.m:
            if restore == "scale" and not np.any(x > lo):
                x = np.where(movable, 1.0, 0.0)     # a uniform start, as Polonsky-Keer's
            x = con.restore(x, lo, hi, (x > lo) & (x < hi), movable)
        return x, clipped or not np.array_equal(before, x), 1.0
    if restore == "scale":
        s = x.sum()
        if s <= 0:
            x = np.where(lo < hi, 1.0, 0.0)
            s = x.sum()
            clipped = True
        factor = target / s
        # a pure rescaling is linear: A x = factor * A x0
        return x * factor, clipped, factor
    before = x.copy()
    x = _restore_by_shift(x, lo, hi, target, (x > lo) & (x < hi))
    return x, clipped or not np.array_equal(before, x), 1.0


class _Bounds:
    """The cellwise bounds of :func:`box_cg`, with what is known of them once: whether
    every cell can move and whether any upper bound is finite (the normal problem has
    none, which saves most of the element-wise tests)."""

    def __init__(self, lo, hi):
        self.lo, self.hi = lo, hi
        self.movable = lo < hi
        self.every = bool(self.movable.all())
        self.upper = bool(np.isfinite(hi).any())

    def free(self, x):
        """Cells strictly inside their bounds."""
        f = x > self.lo
        if self.upper:
            f &= x < self.hi
        return f

    def released(self, x, gr, free):
        """Cells at a bound whose reduced gradient points into the interval (x is always
        within its bounds, so without upper bounds a cell that is not free is at lo)."""
        rel = gr < 0
        if self.upper:
            rel &= x <= self.lo
            rel |= (x >= self.hi) & (gr > 0)
        else:
            rel &= ~free
        if not self.every:
            rel &= self.movable
        return rel

    def outside(self, x) -> bool:
        """Whether any cell of x left its bounds."""
        return bool((x < self.lo).any()) or (self.upper and bool((x > self.hi).any()))


def _project_iterate(x_new, lo, hi, target, restore, con, movable):
    """The step that left the bounds clipped back, and the force (rows) restored."""
    x_new = np.clip(x_new, lo, hi)
    if con is not None:
        if con.m:
            x_new = con.restore(x_new, lo, hi, (x_new > lo) & (x_new < hi), movable)
    elif restore == "scale":
        x_new *= target / x_new.sum()
    else:
        x_new = _restore_by_shift(x_new, lo, hi, target, (x_new > lo) & (x_new < hi))
    return x_new


def _reduce(g, lam, con, out):
    """out = g − Cᵀλ (the reduced gradient), in place."""
    np.subtract(g, lam if con is None else con.field(lam), out=out)


def _fit(con, g, free, movable, cells=None, buf=None):
    """Multipliers of the working cells: the legacy mean (one force row, or the median
    when nothing is free), or a least-squares fit to the rows. ``buf``: scratch of g's
    shape for the masked mean (a boolean-indexed copy costs 5x more)."""
    if con is None:
        use = cells if cells is not None else (free if free.any() else None)
        if use is None:
            return float(np.median(g[movable])) if movable.any() else 0.0
        if buf is None:
            return g[use].mean()
        return float(np.multiply(g, use, out=buf).sum()) / np.count_nonzero(use)
    use = cells if cells is not None else (free if free.any() else movable)
    return con.fit(g, use)


def _change(x_new, x, scale) -> float:
    """Σ|x_new − x| / scale, or relative to Σ|x_new| when ``scale`` is None (0 when
    nothing moved)."""
    d = float(np.abs(x_new - x).sum())
    if scale is None:
        return 0.0 if d == 0.0 else d / max(float(np.abs(x_new).sum()), 1e-300)
    return d / scale


def _precondition(M, gr, working, con, weights=None):
    """The preconditioned gradient z = P M P gr on the working set: M applied to gr (zero off the
    working cells), cut back to them, and projected so that the direction
    keeps the constraint rows (P: the mean removed for the one force row, the rows' null
    space with :class:`Constraints`). P M P is symmetric positive semi-definite on that
    subspace, so the iteration is preconditioned CG there. ``weights``: the working set
    as 0/1 floats where the caller has them (:meth:`BlockSums.weights`)."""
    z = M(gr)                          # gr: already 0 off the working set
    z *= working if weights is None else weights
    if con is None:
        z -= z.sum() / np.count_nonzero(working)
        z *= working
    elif con.m:
        z = con.keep(z, working)
    return z


@dataclass(frozen=True)
class Start:
    """A CG's start: ``x`` [Pa], and its product ``Ax`` [m] where known (saves one FFT
    pair); ``of`` the point ``Ax`` belongs to where that is not x (A x is then updated,
    A x = Ax + A (x − of): :func:`_start`)."""

    x: np.ndarray
    Ax: np.ndarray | None = None
    of: np.ndarray | None = None


@dataclass(frozen=True)
class BoxOptions:
    """The options of :func:`box_cg`.

    Attributes
    ----------
    tol : float
        Stop when Σ|x_new − x_old| / scale < tol.
    max_iter : int
        Iterations allowed.
    restore : {"scale", "shift"}
        How the force is restored after a projection: Polonsky-Keer scaling (only for
        lo = 0, hi = ∞) or a clipped shift of the free cells (two-sided bounds). With
        :class:`Constraints` the rows are always restored by projecting the free cells
        (:func:`project_rows`); "scale" then only asks for a uniform start when nothing
        is loaded.
    scale : float, optional
        Normaliser of the convergence measure [Pa]; default |target| (with
        :class:`Constraints`: Σ|x| of the iterate, so that the change is relative, and a
        contact that opens entirely, x = 0, converges).
    precondition : callable, optional
        ``M(v) -> z``, a symmetric positive definite approximation of A⁻¹ (one FFT pair
        per call for a spectral one). The search directions are then built from the
        preconditioned gradient on the working set (:func:`_precondition`); the bounds,
        the rows and the stopping rule are unchanged. None: plain Polonsky-Keer CG.
    """

    tol: float = 1e-9
    max_iter: int = 1000
    restore: str = "scale"
    scale: float | None = None
    precondition: Callable | None = None


def box_cg(apply, b, lo, hi, target, start, options=BoxOptions(),
           ledger: Ledger | None = None) -> BoxResult:
    """Solve the bound- and force-constrained quadratic problem described in the module doc.

    Parameters
    ----------
    apply : callable
        ``apply(x) -> A x`` (one FFT pair per call); a
        :class:`~contactpipe.solver.blocks.BlockOperator` is applied in halves where the
        ledger updates A x (a projection's correction then costs its forward transforms
        only).
    b : ndarray
        Known linear term (same shape as x) [m].
    lo, hi : ndarray
        Per-cell bounds [Pa]; ``lo == hi`` fixes a cell. ``hi`` may be ``inf``.
    target : float or Constraints
        Required Σx [Pa] (force / cell area); or general rows C x = f (up to three, none
        for displacement control), whose multipliers are returned as an (m,) array.
    start : Start or ndarray
        Warm start [Pa] (with its A x where known); projected onto the constraints first.
    options : BoxOptions
        Tolerance, iterations, how the force is restored, the scale, the preconditioner.
    ledger : Ledger, optional
        A x updated, not recomputed (:class:`~.ledger.Ledger`): projections moving x by
        less than its ``defer`` x ``tol`` in all wait until a larger one, or the
        converged last step (``exact``), takes them in; its ``follow(x) -> Move`` where
        it converges: the result's x is then the move's point, its A x that point's,
        the multipliers fitted to it, ``iterate`` the converged iterate and ``move`` the
        decision. Without ``exact`` a result with corrections still waiting has ``Ax``
        None. None: A x recomputed after each projection.

    Returns
    -------
    BoxResult
        ``Ax`` is A times its own ``x``; ``converged`` is False whenever the residual or
        the iterate is not finite.
    """
    solve = _BoxSolve(apply, b, lo, hi, target, start if isinstance(start, Start)
                      else Start(start), options, ledger if ledger is not None else Ledger())
    return solve.result(*solve.run())


class _BoxSolve:
    """One :func:`box_cg` solve: its iterate x, A x, the last direction t and the
    scratch fields its element-wise work runs in place in."""

    def __init__(self, apply, b, lo, hi, target, start, opt, ledger):
        self.apply, self.b, self.lo, self.hi, self.target, self.opt = \
            apply, b, lo, hi, target, opt
        self.con = con = target if isinstance(target, Constraints) else None
        self.bounds = _Bounds(lo, hi)
        x, Ax = _start(start, lo, hi, target, opt.restore, con, self.bounds.movable, apply)
        if Ax is start.Ax:
            Ax = np.array(Ax, dtype=float)            # updated in place below
        self.x, self.Ax = x, Ax
        self.relative = opt.scale is None and con is not None
        self.scale = max(abs(target), 1e-300) if opt.scale is None and con is None \
            else opt.scale
        self.t = np.zeros_like(x)
        self.g, self.gr, self.grw, self.buf, self.x_new = (np.empty_like(x) for _ in range(5))
        self.lam = 0.0 if con is None else np.zeros(con.m)
        self.book = ledger.bind(apply, opt.tol)

    def run(self):
        """The iteration: (the last relative step, or 0 / inf where it ended early;
        the iterations)."""
        t, grw, M, tol = self.t, self.grw, self.opt.precondition, self.opt.tol
        G_old, working_old, err, it = 1.0, None, np.inf, 0
        for it in range(1, self.opt.max_iter + 1):
            working, moved = self._working_set()
            if not working.any():
                return 0.0, it
            w = self.con.weights(working) if isinstance(self.con, BlockSums) else working
            np.multiply(self.gr, w, out=grw)        # the reduced gradient on the working set
            z = grw if M is None else _precondition(M, grw, working, self.con, w)
            G = _dot(grw, z)
            if not np.isfinite(G):
                return np.inf, it
            if moved or working_old is None or not np.array_equal(working, working_old):
                np.copyto(t, z)                     # conjugacy reset
            else:                                   # t is already 0 off the working set
                t *= G / G_old
                t += z
            G_old, working_old = max(G, 1e-300), working
            r, denom = self.book.curvature(t)
            if denom <= 0.0:
                return 0.0, it
            err = self._step(r, _dot(grw, t) / denom)
            if not err >= 0.0:                      # NaN: the iterate is lost
                return np.inf, it
            if err < tol:
                break
        return err, it

    def _working_set(self):
        """(the working set, whether a cell re-entered it): the free cells and those at a
        bound whose reduced gradient (left in ``gr``) points inwards, the multipliers
        fitted to them."""
        g, gr, con, bounds, movable = self.g, self.gr, self.con, self.bounds, \
            self.bounds.movable
        np.add(self.Ax, self.b, out=g)
        free = bounds.free(self.x)
        lam = _fit(con, g, free, movable, buf=self.buf)
        _reduce(g, lam, con, gr)
        released = bounds.released(self.x, gr, free)
        moved = bool(released.any())
        working = (free | released) if moved else free
        if moved:                               # λ on the whole working set: Σ_W gr = 0
            lam = _fit(con, g, free, movable, cells=working, buf=self.buf)
            _reduce(g, lam, con, gr)
        self.lam = lam
        return working, moved

    def _step(self, r, tau):
        """x − τ t, projected where it left the bounds, and A x with it (``r``: A t, or
        None where the ledger keeps it in spectra); returns the step's relative size."""
        x, t, buf, x_new, book = self.x, self.t, self.buf, self.x_new, self.book
        done = self.opt.tol
        np.subtract(x, np.multiply(t, tau, out=buf), out=x_new)
        if self.bounds.outside(x_new):
            projected = _project_iterate(x_new, self.lo, self.hi, self.target,
                                         self.opt.restore, self.con, self.bounds.movable)
            norm = max(float(np.abs(projected).sum()), 1e-300) if self.relative \
                else self.scale
            err = _change(projected, x, norm)
            if book.update:                     # A x += A(−τ t + d), d the correction
                book.advance(self.Ax, r, tau, buf, projected, err < done,
                             np.subtract(projected, x_new, out=x_new), norm)
            self.x = projected
            if not book.update:
                self.Ax = self.apply(projected)
        else:                                   # x_new − x = −τ t exactly
            err = _step_change(tau, t, x_new, None if self.relative else self.scale, buf)
            self.x, self.x_new = x_new, x
            book.advance(self.Ax, r, tau, buf, x_new, err < done)
        return err

    def result(self, err, it) -> BoxResult:
        """The result (:func:`_finish`), A x moved to ``follow``'s point where it moved."""
        x, tol = self.x, self.opt.tol
        Ax = self.book.close(x, self.Ax, err < tol)
        res = _finish(x, Ax, self.b, self.lo, self.hi, self.target, self.con, self.lam, err,
                      tol, it, self.relative, self.scale)
        res.iterate, res.move = x, self.book.move
        res.x, res.Ax = self.book.outcome(x, Ax)
        return res


def _step_change(tau, t, x_new, scale, buf) -> float:
    """:func:`_change` of an unprojected step x_new = x − τ t, from |τ| Σ|t| (``buf``:
    scratch of x's shape)."""
    moved_by = abs(tau) * float(np.abs(t, out=buf).sum())
    if scale is not None:
        return moved_by / scale
    if moved_by == 0.0:
        return 0.0
    return moved_by / max(float(np.abs(x_new, out=buf).sum()), 1e-300)


def _finish(x, Ax, b, lo, hi, target, con, lam, err, tol, it, relative, scale) -> BoxResult:
    """The result of :func:`box_cg`: the multipliers fitted to the final free cells, and
    convergence judged with the force balance."""
    g = Ax + b
    free = (x > lo) & (x < hi)
    if con is None:
        if free.any():
            lam = g[free].mean()
        force_err = abs(float(x.sum()) - target) / scale
    else:
        if free.any():
            lam = con.fit(g, free)
        size = max(float(np.abs(x).sum()), float(np.abs(con.target).max(initial=0.0)),
                   1e-300) if relative else scale
        force_err = float(np.abs(con.residual(x)).max(initial=0.0)) / size
    # the force balance is part of convergence: a state with every cell at a bound may
    # satisfy the sign conditions and still carry the wrong force
    err = max(float(err), force_err)
    ok = bool(err < tol) and bool(np.all(np.isfinite(x)))
    return BoxResult(x=x, multiplier=lam if con is not None else float(lam), Ax=Ax,
                     iterations=it, residual=err, converged=ok)
