"""Euclidean projections of the CGs (:mod:`contactpipe.solver.cg`,
:mod:`contactpipe.solver.disk_cg`): onto a box or disks per cell, and onto those sets
under equality rows C x = f (:func:`project_rows`, by a damped dual Newton iteration on
the rows' multipliers), or under one sum (:func:`project_box_sum`, by a bracketed shift).
"""
from __future__ import annotations

import numpy as np

__all__ = ["DAMPING", "POLISH", "PROJECTED", "RECOGNISED", "on_bound", "box_jacobian",
           "box_project", "disk_jacobian", "disk_project", "project_box_sum", "project_rows"]

#: A cell a projection put on its friction bound |q| = mu p lies within this relative
#: distance of it (the projection's rounding) [1].
PROJECTED = 1e-12
#: A cell read from outside a solve (a warm start's old bound, the archive's stick/slip
#: status) counts as on its bound within this relative distance [1].
RECOGNISED = 1e-9


def on_bound(mag, bound, margin=PROJECTED):
    """Cells whose traction magnitude ``mag`` [Pa] is on its bound ``bound`` [Pa] (mu p)
    within the relative ``margin``: mag >= bound (1 - margin). A cell with a zero bound
    is on it (mag >= 0); callers that mean contact cells only add ``bound > 0``."""
    return mag >= bound * (1.0 - margin)

#: Levenberg-Marquardt damping of the dual Newton step of :func:`project_rows`, relative
#: to the Lipschitz constant of the dual's gradient: from the first value (a plain Newton
#: step, kept where it ascends) up to the last (a gradient step, which always ascends) [1].
DAMPING = (1e-12, 1e4)
#: A projection whose rows are off by more than this fraction of the result's size is
#: corrected on its inside cells (:func:`_polish`) [1].
POLISH = 1e-13


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


def project_rows(y, C, cells, kind="box", lo=None, hi=None, rho=None,
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
    cset = _CellSet(kind, Cs, C.m, lo, hi, rho, cells)
    xs, flag = _dual_newton(ys, Cs, f, cset, max_iter)
    x[..., cells] = _polish(xs, Cs, f, flag if kind == "box" else ~flag, kind, cset.ls,
                            cset.hs, cset.rs)
    return x


class _CellSet:
    """The moving cells' set of :func:`project_rows` (lo <= x <= hi, or |x| <= rho, per
    cell): its projection, its support function along the rows and the generalised
    Jacobian C J Cᵀ of the projection."""

    def __init__(self, kind, Cs, m, lo, hi, rho, cells):
        self.box, self.Cs, self.m = kind == "box", Cs, m
        self.ls = self.hs = self.rs = None
        if self.box:
            self.ls, self.hs = lo[cells], hi[cells]
        else:
            self.rs = rho[cells]

    def proj(self, z):
        if self.box:
            return box_project(z, self.ls, self.hs)
        return disk_project(z, self.rs)

    def support(self, u):
        ls, hs, rs = self.ls, self.hs, self.rs
        if self.box:
            assert ls is not None and hs is not None          # set for a box
            v = u @ self.Cs                                   # (k,)
            return float(np.sum(np.maximum(ls * v, np.where(np.isfinite(hs), hs * v,
                                                            np.where(v > 0, np.inf, 0.0)))))
        v = (u @ self.Cs).reshape(2, -1)                      # (2, k)
        return float(np.sum(rs * np.hypot(v[0], v[1])))

    def jac(self, z, flag):
        Cs = self.Cs
        if self.box:
            d = box_jacobian(z, self.ls, self.hs, flag)
            return (Cs * d) @ Cs.T
        J = disk_jacobian(z, self.rs, flag)
        A = Cs.reshape(self.m, 2, -1)
        return np.einsum("aik,ijk,bjk->ab", A, J, A)


def _dual_newton(ys, Cs, f, cset, max_iter):
    """:func:`project_rows`' damped dual Newton iteration on the multipliers ν: the
    projected cells (xs) and their flags (inside the box, or over the rim)."""
    def dual(nu):
        z = ys - (nu @ Cs).reshape(ys.shape)
        xs, flag = cset.proj(z)
        F = Cs @ xs.reshape(-1) - f
        return z, xs, flag, F, 0.5 * float(np.sum((xs - ys) ** 2)) + float(nu @ F)

    m = cset.m
    scale = float(np.abs(f).max() + np.abs(ys).sum() + np.abs(Cs).max()) + 1e-300
    lipschitz = max(float(np.linalg.eigvalsh(Cs @ Cs.T).max()), 1e-300)
    nu = np.zeros(m)
    z, xs, flag, F, d = dual(nu)
    damping = DAMPING[0]
    for _ in range(max_iter):
        size = float(np.abs(F).max())
        if size <= 1e-14 * scale:
            break
        u = -F / np.linalg.norm(F)
        if float(u @ f) > cset.support(u) + 1e-12 * scale:
            break                     # beyond what the cells can carry: no projection
        J = cset.jac(z, flag)
        while damping <= DAMPING[1]:
            step = np.linalg.solve(J + damping * lipschitz * np.eye(m), F)
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
    return xs, flag


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


def project_box_sum(y, lo, hi, target):
    """Euclidean projection of y onto {lo ≤ x ≤ hi, Σx = target}: x = clip(y + c) with the
    scalar c from the bracketed root-finder :func:`_shift_root`."""
    movable = lo < hi
    out = np.clip(y, lo, hi)
    ys, ls, hs = y[movable], lo[movable], hi[movable]
    c = _shift_root(ys, ls, hs, target - float(out[~movable].sum()))
    out[movable] = np.clip(ys + c, ls, hs)
    return out
