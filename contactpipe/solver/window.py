"""An instant solved on the block of cells that holds its contact.

Every traction of an instant lies in its contact, and the displacements its solve needs
are those of the contact's cells, so the instant may be solved on a block (window) of
cells around the contact, with the same influence coefficients
(:meth:`ContactOperator.window`) padded to twice the block: the discrete problem is the
same, only the cells that can carry no traction are left out. An FFT pair of a c1 x c2
window costs about c1 c2 / (N1 N2) of the grid's (a little less, N log N), and is counted
so (:meth:`Convolver.charge`). Two kinds of instant gain:

- the sub-steps of a frictional preload (graded load fractions (k/n)²,
  docs/time-integration.md §7), which carry the contact from nothing to its full size: at
  the first of eight its radius is a quarter of the final one;
- every step of the march on a grid larger than its contact: ``grid.size = "auto"`` spans
  three contact radii, so the contact covers about half the grid's cells.

That the left-out cells carry nothing is checked, not assumed. After the window's solve
the displacement of the whole grid is formed from its tractions (the archive's u and the
next instant's slip need it; 1 to 3.5 FFT pairs of the grid); the result stands when no
contact cell lies on the window's outer ring and no cell outside the window would close
(hi + u3 − ω3 below −tol × max u3). Otherwise the window takes those cells in, its margin
doubles and the instant is solved again (from the window's pressure); a window that would
cover more than :data:`LARGEST_SHARE` of the grid gives way to the grid. Under general
controls (moments, rotations, displacement control) the window's cells keep their moment
arms, and the check takes the rotations into the gap (− φ1 x2 − φ2 x1).

The window is taken from the instant's start: the pressure and shear of the last instant
(for a preload sub-step, stretched self-similarly, :mod:`.warm_start`), or, with nothing in
contact yet, the pressure of the frictionless normal problem on the grid coarsened by two
(solved to 1e-3), enlarged by :data:`MARGIN` of its extent on each side.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .coupling import InstantResult, Previous, solve_instant
from .normal import COARSE_TOL, COARSEST, NormalResult, prolong, restrict, solve_normal

__all__ = ["LARGEST_SHARE", "MARGIN", "SIDE_STEP", "SMALLEST_GRID", "solve_in_window"]

#: Cells added on each side of the predicted contact, as a fraction of its extent [1]
#: (at least two cells).
MARGIN = 0.05
#: Grids with fewer cells a side than this are solved whole [1].
SMALLEST_GRID = 32
#: A window holding more than this share of the grid's cells gives way to the grid [1].
LARGEST_SHARE = 0.8
#: Window sides are multiples of this many cells (few distinct FFT sizes) [1].
SIDE_STEP = 8


def solve_in_window(op, gap, U, W, T, cell_area, mu, plan, previous: Previous,
                    limits, controls=None) -> InstantResult:
    """One instant solved on a window of cells around its predicted contact when that
    saves work, else on the whole grid; the arguments are those of
    :func:`.coupling.solve_instant` (``controls``, where given, cut to the window: the
    moment arms of its cells). A normal solution given in ``previous.normal`` is reused as
    it is, cut to the window (its K33 p of the whole grid then spares that product). The
    whole grid serves grids under :data:`SMALLEST_GRID` cells a side, and an instant under
    ``controls`` with nothing in contact yet (no load to estimate the contact from).

    Returns
    -------
    InstantResult
        On the whole grid: p and q are zero outside the window, u is the displacement of
        every cell, ``normal`` the normal solution with its K33 p of the whole grid.
    """
    n1, n2 = gap.shape
    def whole():
        return solve_instant(op, gap, U, W, T, cell_area, mu, plan, previous, limits,
                             controls=controls)
    if op.rigid or min(n1, n2) < SMALLEST_GRID:
        return whole()
    support = _support(previous)
    if support is None and controls is None:
        support = _coarse_contact(op, gap + U[2], W, cell_area, limits)
    if support is None:
        return whole()
    start = previous
    for attempt in range(3):
        window = _window(support, (n1, n2), MARGIN * 2 ** attempt)
        if window is None:
            return whole()
        res = _solve_on(op, window, gap, U, W, T, cell_area, mu, plan, start, limits,
                        controls)
        if res is None:
            return whole()
        grown = _outside(res, window, gap, limits.tol, controls)
        if grown is None:
            return res
        # the contact reached the window's edge or closes outside it: take those cells
        # in, double the margin and solve again
        support = support | grown
        start = replace(previous, p_guess=res.p)
    return whole()


def _support(previous):
    """The cells the start holds in contact or shear (a boolean grid), None if none."""
    s = (previous.p_guess > 0.0) | np.any(previous.q != 0.0, axis=0)
    return s if s.any() else None


def _coarse_contact(op, gap0, W, cell_area, limits):
    """The contact of the frictionless normal problem on the grid coarsened by two, on
    the grid (its pairs charged at a quarter), or None where it cannot be had."""
    n1, n2 = gap0.shape
    coarse = op.coarse_normal() if not (n1 % 2 or n2 % 2) and min(n1, n2) >= 2 * COARSEST \
        else None
    if coarse is None or not W > 0.0:
        return None
    before = coarse.conv.pairs
    res = solve_normal(coarse, restrict(gap0), W, 4.0 * cell_area,
                       np.zeros((n1 // 2, n2 // 2)), max(limits.tol, COARSE_TOL),
                       limits.max_iter)
    op.conv.charge((coarse.conv.pairs - before) * 0.25)
    if not res.converged or not np.all(np.isfinite(res.p)):
        return None
    s = prolong(res.p) > 0.0
    return s if s.any() else None


def _window(support, shape, margin):
    """(rows, columns) slices of the window around ``support``, or None when it would
    hold more than :data:`LARGEST_SHARE` of the grid."""
    sides = []
    for axis, n in enumerate(shape):
        idx = np.flatnonzero(support.any(axis=1 - axis))
        lo, hi = int(idx[0]), int(idx[-1]) + 1
        pad = max(2, int(np.ceil(margin * (hi - lo))))
        c = min(n, SIDE_STEP * int(np.ceil((hi - lo + 2 * pad) / SIDE_STEP)))
        start = min(max(0, (lo + hi - c) // 2), n - c)
        sides.append((start, c))
    if sides[0][1] * sides[1][1] > LARGEST_SHARE * shape[0] * shape[1]:
        return None
    return tuple(slice(s, s + c) for s, c in sides)


def _solve_on(op, window, gap, U, W, T, cell_area, mu, plan, previous, limits, controls):
    """The instant solved on ``window``, put back on the grid; None if it failed there."""
    r, c = window
    if controls is not None:              # the moment arms of the window's cells
        controls = replace(controls, x1=controls.x1[r], x2=controls.x2[c])
    sub = op.window(r.stop - r.start, c.stop - c.start)
    before = sub.conv.pairs
    reused = previous.normal
    cut = None if reused is None else replace(reused, p=reused.p[r, c], Ap=reused.Ap[r, c])
    prev = Previous(previous.q[:, r, c], previous.u[:, r, c], previous.p_guess[r, c],
                    cut, previous.motion,
                    None if previous.p_start is None else previous.p_start[r, c])
    m = mu if np.ndim(mu) == 0 else mu[r, c]
    res = solve_instant(sub, gap[r, c], U[:, r, c], W, T, cell_area, m, plan, prev, limits,
                        controls=controls)
    share = sub.conv.n1 * sub.conv.n2 / (op.conv.n1 * op.conv.n2)
    op.conv.charge((sub.conv.pairs - before) * share)
    if not res.converged:
        return None
    p = np.zeros(gap.shape)
    q = np.zeros((2,) + gap.shape)
    p[r, c], q[:, r, c] = res.p, res.q
    u, Ap = _displacement(op, plan, U, p, q, None if reused is None else reused.Ap)
    normal = reused if reused is not None else \
        NormalResult(p, res.omega3, Ap, res.iterations, res.residual, True)
    return InstantResult(p, q, u, res.omega3, res.domega, res.iterations, res.passes, True,
                         res.residual, normal=normal, phi=np.asarray(res.phi, float).copy(),
                         dphi3=res.dphi3)


def _displacement(op, plan, U, p, q, Ap=None):
    """(u, K33 p) of the whole grid, with the terms :func:`.coupling.solve_instant` puts in
    u: K33 p alone without shear (1 FFT pair); else the in-plane ones from the shear, and
    the coupling ones of a coupled pair (at most 3 forward, 4 inverse transforms). A
    given K33 p (``Ap``, a reused normal solution's) is not formed again."""
    k = op.k
    if plan.tangential == "none":
        Ap = op.normal(p) if Ap is None else Ap
        u = U.copy()
        u[2] += Ap
        return u, Ap
    c = (lambda key: k[key]) if plan.coupling != "none" else (lambda key: None)
    rows = [[k["11"], k["12"], c("13")], [k["21"], k["22"], c("23")], [c("31"), c("32"), None]]
    if Ap is None:
        rows.append([None, None, k["33"]])
    uses_p = Ap is None or plan.coupling != "none"
    out = op.conv.convolve_matrix(rows, [q[0], q[1] if np.any(q[1]) else None,
                                         p if uses_p else None])
    Ap = out[3] if Ap is None else Ap
    u = U + out[:3]
    u[2] += Ap
    return u, Ap


def _outside(res, window, gap, tol, controls=None):
    """None when the window held the contact; else the cells it must take in as well (the
    contact's cells on the window's outer ring, the cells outside that would close: the
    gap hi + u3 − ω3 − φ1 x2 − φ2 x1 below −tol × max u3)."""
    r, c = window
    n1, n2 = gap.shape
    inner = np.zeros(gap.shape, bool)
    inner[r.start + (r.start > 0):r.stop - (r.stop < n1),
          c.start + (c.start > 0):c.stop - (c.stop < n2)] = True
    inside = np.zeros(gap.shape, bool)
    inside[r, c] = True
    u3 = res.u[2]
    scale = float(np.abs(u3[inside]).max()) if inside.any() else 0.0
    h = gap + u3 - res.omega3
    if controls is not None and np.any(res.phi):
        h = h - res.phi[0] * controls.x2[None, :] - res.phi[1] * controls.x1[:, None]
    closing = ~inside & (h < -tol * scale)
    edge = inside & ~inner & (res.p > 0.0)
    grow = closing | edge
    return grow if grow.any() else None
