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
