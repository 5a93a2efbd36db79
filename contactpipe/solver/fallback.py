"""The fallback of the projected CGs: the accelerated projected gradient
(:func:`fista`), which always converges, and the CG/projected-gradient alternation
(:func:`cg_with_fallback`) on their common :class:`Outcome`."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Outcome", "cg_with_fallback", "fista"]


@dataclass
class Outcome:
    """One solve of :func:`cg_with_fallback`'s protocol: ``Ax`` is A x [m]."""

    x: np.ndarray
    Ax: np.ndarray | None
    iterations: int
    residual: float
    converged: bool
    multiplier: object = None   # the rows' multipliers, where the solve fitted them


def cg_with_fallback(cg, pg, x0, Ax0, tol, max_iter, sliding=None) -> Outcome:
    """CG first; where it stalls, the projected gradient to a loose tolerance (it finds the
    slip/stick pattern that pins the multiplier), then CG again from there; the projected
    gradient, which always converges, finishes if CG stalls a second time.

    ``cg`` and ``pg`` take (x0, Ax0, tol, budget) and return an :class:`Outcome`. Returns
    the last one, iterations summed. ``sliding(x)``, when given, says that no cell of x
    sticks: the projected gradient then runs alone (the projected CG stalls where every
    cell turns on its circle, as in gross slip, while the projected gradient converges in
    a few dozen iterations there).
    """
    budget = max(1, max_iter // 4)
    if sliding is not None and np.any(x0) and sliding(x0):
        return pg(x0, Ax0, tol, max_iter)
    first = cg(x0, Ax0, tol, budget)
    if first.converged:
        return first
    its, out = first.iterations, pg(first.x, first.Ax, max(tol, 1e-6), budget)
    its += out.iterations
    if sliding is not None and sliding(out.x):
        out = pg(out.x, out.Ax, tol, max(1, max_iter - its))
        out.iterations += its
        return out
    out = cg(out.x, out.Ax, tol, budget)
    its += out.iterations
    if out.converged:
        out.iterations = its
        return out
    out = pg(out.x, out.Ax, tol, max(1, max_iter - its))
    out.iterations += its
    return out


def fista(apply, b, project, x0, lipschitz, tol, max_iter, scale, Ax0=None):
    """Accelerated projected gradient with adaptive restart, for a convex quadratic.

    minimise ½ xᵀAx + bᵀx over a convex set given by its Euclidean ``project``ion
    (Beck & Teboulle 2009; restart on objective increase, O'Donoghue & Candès 2015).
    Always converges; used where the active-set CG cannot pin the force multiplier (every
    cell, or nearly, at its bound). Stops on the natural residual Σ|y − P(y − ∇f/L)|/scale.

    Returns an :class:`Outcome`.
    """
    x = project(x0)
    Ax = apply(x) if (Ax0 is None or not np.array_equal(x, x0)) else Ax0
    y, Ay, tk = x, Ax, 1.0
    f_old = np.inf
    err = np.inf
    it = 0
    for it in range(1, max_iter + 1):
        x_new = project(y - (Ay + b) / lipschitz)
        err = float(np.abs(x_new - y).sum()) / scale
        Ax_new = apply(x_new)
        if err < tol:
            return Outcome(x_new, Ax_new, it, err, True)
        f_new = 0.5 * float(np.sum(x_new * Ax_new)) + float(np.sum(b * x_new))
        if f_new > f_old:
            tk = 1.0
        t_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * tk * tk))
        w = (tk - 1.0) / t_next
        y = x_new + w * (x_new - x)
        Ay = Ax_new + w * (Ax_new - Ax)
        x, Ax, tk, f_old = x_new, Ax_new, t_next, f_new
    return Outcome(x, Ax, it, err, False)
