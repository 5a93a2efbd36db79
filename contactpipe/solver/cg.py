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

from dataclasses import dataclass

import numpy as np

from .fallback import Outcome, cg_with_fallback, fista
from .ledger import Ledger, Move, dot as _dot

#: Levenberg-Marquardt damping of the dual Newton step of :func:`project_rows`, relative
#: to the Lipschitz constant of the dual's gradient: from the first value (a plain Newton
#: step, kept where it ascends) up to the last (a gradient step, which always ascends) [1].
DAMPING = (1e-12, 1e4)
#: A projection whose rows are off by more than this fraction of the result's size is
#: corrected on its inside cells (:func:`_polish`) [1].
POLISH = 1e-13

__all__ = ["BlockSums", "BoxResult", "Outcome", "ComponentSums", "Constraints", "box_cg",
           "cg_with_fallback", "feasible_start", "fista", "project_box_sum", "project_rows",
           "box_jacobian", "box_project", "disk_jacobian", "disk_project"]


@dataclass
class BoxResult:
    """Outcome of :func:`box_cg`: ``Ax`` is A times this result's own ``x``."""

    x: np.ndarray          # the solution, or ``follow``'s point where it moved on
    multiplier: float      # λ of the force constraint (an (m,) array with Constraints)
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
        self.rows = np.asarray(rows, dtype=float)
        self.target = np.atleast_1d(np.asarray(target, dtype=float))
        self.m = int(self.rows.shape[0])
        self.sums = bool(sums)
        if self.target.shape != (self.m,):
            raise ValueError(f"{self.m} rows need {self.m} targets, got {self.target.shape}")

    @classmethod
    def none(cls, shape) -> "Constraints":
        """No row: displacement control (a plain bound-constrained problem)."""
        return cls(np.zeros((0,) + tuple(shape)), np.zeros(0))

    def field(self, lam) -> np.ndarray | float:
        """Cᵀλ, the rigid motion of the multipliers (shape of x; 0.0 without rows)."""
        if self.m == 0:
            return 0.0
        return np.tensordot(np.asarray(lam, dtype=float), self.rows, axes=1)

    def sums_of(self, x) -> np.ndarray:
        """C x (m,)."""
        if self.sums:
            return np.array([float(x[r != 0].sum()) for r in self.rows])
        return np.array([float(np.sum(r * x)) for r in self.rows])

    def residual(self, x) -> np.ndarray:
        """C x − f (m,)."""
        return self.sums_of(x) - self.target

    def _on(self, cells):
        """The rows on ``cells`` (a mask over the last two axes), as an (m, k) matrix."""
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

    def field(self, lam):
        return np.asarray(lam, dtype=float).reshape(self.m, 1, 1)

    def sums_of(self, x):
        return x.reshape(self.m, -1).sum(axis=1)

    def _means(self, v, cells):
        """The mean of v[k] over block k's cells (m, 1, 1), 0 where a block has none: by a
        product with the mask in a kept scratch array (a boolean-indexed copy per block
        cost more). The cells are counted block by block: ``count_nonzero`` along an axis
        sums a cast copy, slower (docs/design-choices.md, D22)."""
        if self._buf is None or self._buf.shape != v.shape:
            self._buf = np.empty(v.shape)
        sums = np.multiply(v, cells, out=self._buf).reshape(self.m, -1).sum(axis=1)
        counts = np.array([max(np.count_nonzero(c), 1) for c in cells.reshape(self.m, -1)])
        return (sums / counts).reshape(self.m, 1, 1)

    def fit(self, g, cells):
        return self._means(g, cells).ravel()

    def keep(self, z, cells):
        return z - np.multiply(cells, self._means(z, cells), out=self._buf)

    def restore(self, x, lo, hi, free, movable=None):
        """Σ x[k] = f[k] again by a clipped shift of block k's free cells (then of every
        cell with room); a block whose sum already holds is kept as it is
        (:func:`_restore_by_shift`), so that the update of A x after a projection that
        clipped the shear alone skips the pressure block (1.5 FFT pairs instead of 2 in
        the joint solve)."""
        return np.stack([_restore_by_shift(x[k], lo[k], hi[k], self.target[k], free[k])
                         for k in range(self.m)])


# --------------------------------------------------------------------------- projections
def box_project(z, lo, hi):
    """Clip z to [lo, hi] (the cellwise projection of the box problems); (x, inside)."""
    x = np.clip(z, lo, hi)
    return x, (z > lo) & (z < hi)


def box_jacobian(z, lo, hi, inside):
    """Cellwise derivative of the clip: 1 inside, 0 at a bound (shape of z)."""
    return inside.astype(float)


def disk_project(z, rho):
    """Radial projection of each cell's vector z (2, N1, N2) onto the disk |z| <= rho.
    Returns (x, over) with ``over`` the cells that were outside."""
    mag = np.hypot(z[0], z[1])
    over = mag > rho
    if over.any():
        f = np.where(over, rho / np.where(mag > 0, mag, 1.0), 1.0)
        z = z * f
    return z, over


def disk_jacobian(z, rho, over):
    """Cellwise Jacobian (2, 2, N1, N2) of :func:`disk_project`: I inside the disk,
    (rho/|z|)(I − ẑẑᵀ) outside."""
    mag = np.hypot(z[0], z[1])
    safe = np.where(mag > 0, mag, 1.0)
    zh = z / safe
    f = np.where(over, rho / safe, 1.0)
    J = np.zeros((2, 2) + z.shape[1:])
    for i in range(2):
        for j in range(2):
            J[i, j] = f * ((1.0 if i == j else 0.0) - np.where(over, zh[i] * zh[j], 0.0))
    return J


def project_rows(y, C: Constraints, cells, kind="box", lo=None, hi=None, rho=None,
                 max_iter=100):
    """Euclidean projection of y on ``cells`` onto {the cellwise set, C x = f}, the other
    cells held: x = P(y − Cᵀν) on the cells, with the multipliers ν (m,) from a dual
    Newton iteration.

    The dual ``d(ν) = ½|x(ν) − y|² + νᵀ(C x(ν) − f')`` (f' = f less what the held cells
    carry) is concave with gradient C x(ν) − f'; each Newton step on it is damped by an
    Levenberg-Marquardt damping, raised until the step ascends (a damped step tends to a
    gradient step of length 1/L, which always does), so the iteration cannot run away
    where the generalised Jacobian is near-singular (every cell on its bound or rim); a
    step is also taken where it lowers the residual while the dual's change is below
    rounding. Near the solution the damping falls away and the convergence is quadratic.

    Parameters
    ----------
    y : ndarray
        (N1, N2) for ``kind = "box"``, (2, N1, N2) for ``"disk"``.
    C : Constraints
    cells : ndarray of bool (N1, N2)
        The cells that move.
    kind : {"box", "disk"}
        lo <= x <= hi per cell, or |x| <= rho per cell.

    Returns
    -------
    ndarray
        The projection (y where ``cells`` is False). When no point of the set meets the
        rows (the target lies beyond a supporting plane of what the cells can carry,
        checked at every step along the residual) the iteration stops with the best it
        reached.
    """
    x = y.copy()
    if C.m == 0 or not np.any(cells):
        return _project_cells(x, cells, kind, lo, hi, rho)
    ys = y[..., cells]
    Cs = C._on(cells)                                        # (m, k)
    held = ~cells
    f = C.target - C.sums_of(np.where(held, y, 0.0))
    if kind == "box":
        ls, hs = lo[cells], hi[cells]

        def proj(z):
            return box_project(z, ls, hs)

        def support(u):
            v = u @ Cs                                        # (k,)
            return float(np.sum(np.maximum(ls * v, np.where(np.isfinite(hs), hs * v,
                                                            np.where(v > 0, np.inf, 0.0)))))

        def jac(z, inside):
            d = box_jacobian(z, ls, hs, inside)
            return (Cs * d) @ Cs.T
    else:
        rs = rho[cells]

        def proj(z):
            return disk_project(z, rs)

        def support(u):
            v = (u @ Cs).reshape(2, -1)                       # (2, k)
            return float(np.sum(rs * np.hypot(v[0], v[1])))

        def jac(z, over):
            J = disk_jacobian(z, rs, over)
            A = Cs.reshape(C.m, 2, -1)
            return np.einsum("aik,ijk,bjk->ab", A, J, A)

    def dual(nu):
        z = ys - (nu @ Cs).reshape(ys.shape)
        xs, flag = proj(z)
        F = Cs @ xs.reshape(-1) - f
        return z, xs, flag, F, 0.5 * float(np.sum((xs - ys) ** 2)) + float(nu @ F)

    scale = float(np.abs(f).max() + np.abs(ys).sum() + np.abs(Cs).max()) + 1e-300
    lipschitz = max(float(np.linalg.eigvalsh(Cs @ Cs.T).max()), 1e-300)
    nu = np.zeros(C.m)
    z, xs, flag, F, d = dual(nu)
    damping = DAMPING[0]
    for _ in range(max_iter):
        size = float(np.abs(F).max())
        if size <= 1e-14 * scale:
            break
        u = -F / np.linalg.norm(F)
        if float(u @ f) > support(u) + 1e-12 * scale:
            break                     # beyond what the cells can carry: no projection
        J = jac(z, flag)
        while damping <= DAMPING[1]:
            step = np.linalg.solve(J + damping * lipschitz * np.eye(C.m), F)
            trial = dual(nu + step)
            # ascent of the dual, or (where its change is below rounding) of the residual
            flat = abs(trial[4] - d) <= 1e-13 * (abs(d) + abs(trial[4]))
            if trial[4] >= d + 1e-4 * float(F @ step) or \
                    (flat and float(np.abs(trial[3]).max()) <= (1.0 - 1e-4) * size):
                damping = max(damping / 10.0, DAMPING[0])
                break
            damping *= 10.0
        else:
            break
        nu = nu + step
        z, xs, flag, F, d = trial
    x[..., cells] = _polish(xs, Cs, f, flag if kind == "box" else ~flag, kind, ls
                            if kind == "box" else None, hs if kind == "box" else None,
                            rs if kind != "box" else None)
    return x


def _polish(xs, Cs, f, inside, kind, ls, hs, rs):
    """xs with the rows' residual C xs − f taken off its cells strictly inside their
    sets by the least-norm correction, where that keeps them inside.

    The dual iteration computes xs = P(ys − Cᵀν): where the step that made ys overshot
    far (ys a million times the rows' targets, as after the first step of a cold start),
    its rounding and its stopping rule, both relative to |ys|, leave the rows off by
    1e-8 of the target, which the CG's directions then keep (they do not change C x)
    and the solve cannot converge. The correction is relative to xs itself."""
    F = Cs @ xs.reshape(-1) - f
    size = float(np.abs(F).max())
    if size <= POLISH * (float(np.abs(f).max()) + float(np.abs(xs).sum())):
        return xs                      # as exact as xs allows: kept bit for bit
    mask = np.broadcast_to(inside, xs.shape).reshape(-1)
    if not mask.any():
        return xs
    Ci = Cs[:, mask]
    corr = Ci.T @ np.linalg.lstsq(Ci @ Ci.T, F, rcond=None)[0]
    out = xs.reshape(-1).copy()
    out[mask] -= corr
    out = out.reshape(xs.shape)
    if kind == "box":
        ok = np.all((out[inside] > ls[inside]) & (out[inside] < hs[inside]))
    else:
        ok = np.all(np.hypot(out[0], out[1])[inside] < rs[inside])
    if not ok or not np.all(np.isfinite(out)):
        return xs
    return out if float(np.abs(Cs @ out.reshape(-1) - f).max()) < size else xs


def _project_cells(x, cells, kind, lo, hi, rho):
    """The cellwise projection of ``cells`` (no row to keep)."""
    if kind == "box":
        x[cells] = np.clip(x[cells], lo[cells], hi[cells])
    else:
        x[:, cells] = disk_project(x[:, cells], rho[cells])[0]
    return x

def _shift_root(xs, ls, hs, need):
    """c with Σ clip(xs + c, ls, hs) = need (clipped to the attainable range).

    The function is monotone and piecewise linear in c: Newton steps (slope = the number
    of cells strictly inside their bounds) inside a bracket, bisection when a step leaves
    it or no cell is inside. Finite termination up to rounding.
    """
    lo_sum, hi_sum = ls.sum(), hs.sum()
    if need <= lo_sum:
        return -np.inf
    if need >= hi_sum:
        return np.inf
    c_lo = float(np.min(ls - xs))                     # every cell at its lower bound
    finite_hi = np.isfinite(hs)
    if finite_hi.all():
        c_hi = float(np.max(hs - xs))                 # every cell at its upper bound
    else:                                             # one-sided: grow until enough
        c_hi = max(1.0, float(np.abs(xs).max()))
        while np.clip(xs + c_hi, ls, hs).sum() < need:
            c_hi *= 2.0
    c = min(max(0.0, c_lo), c_hi)
    for _ in range(200):
        y = np.clip(xs + c, ls, hs)
        f = y.sum() - need
        # relative to the clipped values: xs may be far outside the bounds (a projection)
        if abs(f) <= 1e-14 * (abs(need) + np.abs(y).sum() + 1e-300):
            break
        if f > 0:
            c_hi = c
        else:
            c_lo = c
        inside = np.count_nonzero((xs + c > ls) & (xs + c < hs))
        c_new = c - f / inside if inside else np.nan
        if not (c_lo < c_new < c_hi):
            c_new = 0.5 * (c_lo + c_hi)
        if c_new == c:
            break
        c = c_new
    return c


def _restore_by_shift(x, lo, hi, target, free):
    """Shift the free cells by one constant (clipped to their bounds) so that Σx = target;
    when the free cells cannot carry it, every cell with room is shifted. An x whose sum
    already holds to the shift's own acceptance (1e-12 of Σ|x|: off by the rounding of
    the steps only) is returned as it is, so that its A x needs no update."""
    def holds(y):
        return abs(float(y.sum()) - target) <= 1e-12 * (abs(target) + float(np.abs(y).sum()))

    if holds(x):
        return x
    out = x
    for cells in (free, lo < hi):
        if not cells.any():
            continue
        xs, ls, hs = x[cells], lo[cells], hi[cells]
        need = target - (x.sum() - xs.sum())
        # the plain shift first: where it leaves every cell strictly inside its bounds it
        # is the root itself (Σ(xs + c) = need), and the root-finder is not needed
        ys = xs + (need - xs.sum()) / xs.size
        if not ((ys > ls).all() and (ys < hs).all()):
            ys = np.clip(xs + _shift_root(xs, ls, hs, need), ls, hs)
        out = x.copy()
        out[cells] = ys
        if holds(out):
            return out
    return out


def _start(x0, lo, hi, target, restore, con, movable, apply, Ax0, Ax0_of=None):
    """The first iterate (the constraints restored) and its A x.

    ``Ax0`` is A of ``Ax0_of`` when that is given, else of ``x0``. Where the iterate
    differs from it, A x is recomputed; with ``Ax0_of`` given it is updated instead,
    A x = Ax0 + A (x − Ax0_of), which costs less when ``apply`` skips the blocks of the
    difference that are zero (the joint solve's pressure, when only slip cells moved).
    """
    x, changed, factor = _restored(x0, lo, hi, target, restore, con, movable)
    if Ax0 is None:
        return x, apply(x)
    if Ax0_of is not None:
        return x, Ax0 + apply(x - Ax0_of)
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


def _precondition(M, gr, working, con):
    """The preconditioned gradient z = P M P gr on the working set: M applied to gr (zero off the
    working cells), cut back to them, and projected so that the direction
    keeps the constraint rows (P: the mean removed for the one force row, the rows' null
    space with :class:`Constraints`). P M P is symmetric positive semi-definite on that
    subspace, so the iteration is preconditioned CG there."""
    z = M(gr)                          # gr: already 0 off the working set
    z *= working
    if con is None:
        z -= z.sum() / np.count_nonzero(working)
        z *= working
    elif con.m:
        z = con.keep(z, working)
    return z


def box_cg(apply, b, lo, hi, target, x0, tol=1e-9, max_iter=1000, restore="scale",
           scale=None, Ax0=None, precondition=None, Ax0_of=None,
           update=False, defer=0.0, follow=None, exact=False) -> BoxResult:
    """Solve the bound- and force-constrained quadratic problem described in the module doc.

    Parameters
    ----------
    apply : callable
        ``apply(x) -> A x`` (one FFT pair per call); a
        :class:`~contactpipe.solver.blocks.BlockOperator` is applied in halves with
        ``update`` (a projection's correction then costs its forward transforms only).
    b : ndarray
        Known linear term (same shape as x) [m].
    lo, hi : ndarray
        Per-cell bounds [Pa]; ``lo == hi`` fixes a cell. ``hi`` may be ``inf``.
    target : float or Constraints
        Required Σx [Pa] (force / cell area); or general rows C x = f (up to three, none
        for displacement control), whose multipliers are returned as an (m,) array.
    x0 : ndarray
        Warm start [Pa]; projected onto the constraints first.
    tol : float
        Stop when Σ|x_new − x_old| / scale < tol.
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
    Ax0 : ndarray, optional
        ``A x0`` if already known (saves one FFT pair).
    Ax0_of : ndarray, optional
        The x that ``Ax0`` belongs to, if not ``x0`` (A x then updated: :func:`_start`).
    update, defer, follow, exact :
        A x updated, not recomputed (:class:`~.ledger.Ledger`): projections moving x by
        less than ``defer`` x ``tol`` in all wait until a larger one, or the converged
        last step (``exact``), takes them in; ``follow(x) -> Move`` where it converges:
        the result's x is then the move's point, its A x that point's, the multipliers
        fitted to it, ``iterate`` the converged iterate and ``move`` the decision.
        Without ``exact`` a result with corrections still waiting has ``Ax`` None.
    precondition : callable, optional
        ``M(v) -> z``, a symmetric positive definite approximation of A⁻¹ (one FFT pair
        per call for a spectral one). The search directions are then built from the
        preconditioned gradient on the working set (:func:`_precondition`); the bounds,
        the rows and the stopping rule are unchanged. None: plain Polonsky-Keer CG.

    ``converged`` is False whenever the residual or the iterate is not finite.
    """
    con = target if isinstance(target, Constraints) else None
    bounds = _Bounds(lo, hi)
    movable = bounds.movable
    x, Ax = _start(x0, lo, hi, target, restore, con, movable, apply, Ax0, Ax0_of)
    if Ax is Ax0:
        Ax = np.array(Ax, dtype=float)            # updated in place below
    relative = scale is None and con is not None
    if scale is None and con is None:
        scale = max(abs(target), 1e-300)
    t = np.zeros_like(x)            # preallocated: the element-wise work runs in place
    g, gr, grw, step, x_new = (np.empty_like(x) for _ in range(5))
    G_old, working_old, err = 1.0, None, np.inf
    lam = 0.0 if con is None else np.zeros(con.m)
    book, it = Ledger(update, defer, follow, exact).bind(apply, tol), 0
    for it in range(1, max_iter + 1):
        np.add(Ax, b, out=g)
        free = bounds.free(x)
        lam = _fit(con, g, free, movable, buf=step)
        _reduce(g, lam, con, gr)
        released = bounds.released(x, gr, free)
        moved = bool(released.any())
        working = (free | released) if moved else free
        if moved:                               # λ on the whole working set: Σ_W gr = 0
            lam = _fit(con, g, free, movable, cells=working, buf=step)
            _reduce(g, lam, con, gr)
        if not working.any():
            err = 0.0
            break
        np.multiply(gr, working, out=grw)       # the reduced gradient on the working set
        z = grw if precondition is None else _precondition(precondition, grw, working, con)
        G = _dot(grw, z)
        if not np.isfinite(G):
            err = np.inf
            break
        if moved or working_old is None or not np.array_equal(working, working_old):
            np.copyto(t, z)                     # conjugacy reset
        else:                                   # t is already 0 off the working set
            t *= G / G_old
            t += z
        G_old = max(G, 1e-300)
        working_old = working
        r, denom = book.curvature(t)
        if denom <= 0.0:
            err = 0.0
            break
        tau = _dot(grw, t) / denom
        np.subtract(x, np.multiply(t, tau, out=step), out=x_new)
        if bounds.outside(x_new):
            projected = _project_iterate(x_new, lo, hi, target, restore, con, movable)
            norm = max(float(np.abs(projected).sum()), 1e-300) if relative else scale
            err = _change(projected, x, norm)
            if update:                          # A x += A(−τ t + d), d the correction
                book.advance(Ax, r, tau, step, projected, err < tol,
                             np.subtract(projected, x_new, out=x_new), norm)
            x, Ax = projected, (Ax if update else apply(projected))
        else:                                   # x_new − x = −τ t exactly
            err = _step_change(tau, t, x_new, None if relative else scale, step)
            x, x_new = x_new, x
            book.advance(Ax, r, tau, step, x, err < tol)
        if not err >= 0.0:                      # NaN: the iterate is lost
            err = np.inf
            break
        if err < tol:
            break
    Ax = book.close(x, Ax, err < tol)
    res = _finish(x, Ax, b, lo, hi, target, con, lam, err, tol, it, relative, scale)
    res.iterate, res.move = x, book.move
    res.x, res.Ax = book.outcome(x, Ax)
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


def project_box_sum(y, lo, hi, target):
    """Euclidean projection of y onto {lo ≤ x ≤ hi, Σx = target}: x = clip(y + c) with the
    scalar c from the bracketed root-finder :func:`_shift_root`."""
    movable = lo < hi
    out = np.clip(y, lo, hi)
    ys, ls, hs = y[movable], lo[movable], hi[movable]
    c = _shift_root(ys, ls, hs, target - float(out[~movable].sum()))
    out[movable] = np.clip(ys + c, ls, hs)
    return out
