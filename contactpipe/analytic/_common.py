"""Shared pieces of the closed forms: composite moduli, cell averages, argument checks.

Units: SI (m, Pa). See :mod:`contactpipe.analytic` for the references.
"""
from __future__ import annotations

import numpy as np
from scipy import special

__all__ = ["composite_modulus", "tangential_compliance_sum", "cell_average"]


def composite_modulus(young1, poisson1, young2, poisson2) -> float:
    """Hertz composite (plane-strain) modulus E*.

    ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2`` ([J85]_ §4.2); an infinite Young
    modulus stands for a rigid body.

    Parameters
    ----------
    young1, young2 : float
        Young moduli of the two bodies [Pa]; ``np.inf`` for a rigid body.
    poisson1, poisson2 : float
        Poisson ratios [1].

    Returns
    -------
    float
        E* [Pa]; ``inf`` when both bodies are rigid.
    """
    c = 0.0
    for e, nu in ((young1, poisson1), (young2, poisson2)):
        if not np.isinf(e):
            if e <= 0:
                raise ValueError(f"Young modulus must be > 0 [Pa], got {e!r}")
            c += (1.0 - nu ** 2) / e
    return np.inf if c == 0.0 else 1.0 / c


def tangential_compliance_sum(young1, poisson1, young2, poisson2) -> float:
    """Mindlin's tangential compliance sum ``(2 - nu1)/G1 + (2 - nu2)/G2``.

    ``G = E / (2 (1 + nu))``; a rigid body (``E = inf``) contributes 0.

    Parameters
    ----------
    young1, young2 : float
        Young moduli [Pa]; ``np.inf`` for a rigid body.
    poisson1, poisson2 : float
        Poisson ratios [1].

    Returns
    -------
    float
        Compliance sum [1/Pa] used by :func:`tangential_displacement` and
        :func:`energy_per_cycle`.
    """
    c = 0.0
    for e, nu in ((young1, poisson1), (young2, poisson2)):
        if not np.isinf(e):
            g = e / (2.0 * (1.0 + nu))
            c += (2.0 - nu) / g
    return c


def check_positive(name, value):
    if not np.all(np.asarray(value) > 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")


def cell_average(f, x1, x2, d1, d2, order: int = 8, radial: bool = False):
    """Average of a closed-form field over rectangular grid cells.

    Each cell ``[x1 - d1/2, x1 + d1/2] x [x2 - d2/2, x2 + d2/2]`` is integrated with an
    ``order x order`` tensor Gauss-Legendre rule and divided by its area ``d1 d2``.
    This is what a piecewise-constant numerical traction should be compared with.
    Do not use it for fields with an integrable singularity inside a cell (see
    :meth:`FlatPunch.cell_average_pressure`); fields with a square-root edge
    (Hertz, Cattaneo) converge, more slowly, in the cells cut by the edge.

    Parameters
    ----------
    f : callable
        Vectorised field ``f(x1, x2)`` (positions [m]) or, with ``radial=True``,
        ``f(r)`` with ``r = hypot(x1, x2)`` [m]. Any units; the average has the same.
    x1, x2 : array_like
        Cell-centre coordinates [m], broadcast against each other (for a grid pass
        ``x1[:, None], x2[None, :]`` or the output of ``np.meshgrid(..., indexing="ij")``).
    d1, d2 : float
        Cell side lengths along x1, x2 [m].
    order : int, optional
        Number of Gauss-Legendre points per direction (default 8).
    radial : bool, optional
        Whether ``f`` takes the radius only.

    Returns
    -------
    ndarray
        Cell averages, shape ``broadcast(x1, x2).shape``.
    """
    x1, x2 = np.broadcast_arrays(np.asarray(x1, float), np.asarray(x2, float))
    nodes, weights = special.roots_legendre(order)
    g1 = x1[..., None, None] + 0.5 * d1 * nodes[:, None]
    g2 = x2[..., None, None] + 0.5 * d2 * nodes[None, :]
    g1, g2 = np.broadcast_arrays(g1, g2)
    vals = f(np.hypot(g1, g2)) if radial else f(g1, g2)
    w = 0.25 * weights[:, None] * weights[None, :]
    return np.sum(np.asarray(vals) * w, axis=(-2, -1))


def sqrt_plus(c, r):
    return np.sqrt(np.clip(c * c - r * r, 0.0, None))


def masing_loop(history, virgin, slide=None) -> np.ndarray:
    """A force (or moment) at every sample of a displacement (or rotation) history by
    Masing's rules on a virgin curve, from rest at 0.

    From the last remembered reversal (x_r, F_r) the branch is
    ``F = F_r + s 2 virgin(|x − x_r| / 2)`` (s the direction); a branch that reaches the
    one it left wipes both reversals, and one that passes the mirror of the first reversal
    rejoins the virgin curve about the current centre.

    Parameters
    ----------
    history : array_like
        Displacement samples x, linear between samples.
    virgin : callable
        ``virgin(x) -> F``, odd in x: the virgin curve.
    slide : (float, float), optional
        (F_s, x_s): where |F| reaches F_s the contact slides as a whole: F stays at s F_s,
        every memory is erased and the state is the virgin curve's at x_s about the new
        centre ``x − s x_s``. None: the curve never reaches sliding.

    Returns
    -------
    ndarray
        F at each sample.
    """
    centre, stack, F, prev, direction = 0.0, [], 0.0, 0.0, 0
    out = []
    for x in np.atleast_1d(np.asarray(history, float)).ravel():
        x = float(x)
        if x != prev:
            s = 1 if x > prev else -1
            if direction and s != direction:
                stack.append((prev, F))
            direction = s
            while True:
                if len(stack) >= 2 and s * (x - stack[-2][0]) >= 0.0:
                    del stack[-2:]
                elif len(stack) == 1 and s * (x - (2.0 * centre - stack[0][0])) >= 0.0:
                    stack.pop()
                else:
                    break
            if stack:
                x_r, F_r = stack[-1]
                F = F_r + s * 2.0 * float(virgin(abs(x - x_r) / 2.0))
            else:
                F = float(virgin(x - centre))
            if slide is not None and abs(F) >= slide[0]:
                F, stack, centre = s * slide[0], [], x - s * slide[1]
            prev = x
        out.append(F)
    return np.array(out)
