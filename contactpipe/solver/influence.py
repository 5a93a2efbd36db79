"""Influence coefficients of an elastic half-space for uniform tractions on rectangular cells.

A cell of size ``d1 x d2`` centred at the origin carries a uniform unit traction [1 Pa]
along direction j.  ``K_ij(x1, x2)`` is the surface displacement along i at the relative
position (x1, x2) = field point minus cell centre [m/Pa].  Indices 1, 2 are in-plane, 3 is
the normal, pointing **into** the body (docs/conventions.md).

Point-load Green's functions
----------------------------
With ``r^2 = X^2 + Y^2`` (Boussinesq 1885, Cerruti 1882; Johnson 1985, §3.2-3.5), a point
force F [N] on the surface gives

=========  ===========================================================
normal F   ``u3 = (1 - nu^2) F / (pi E r)``,
           ``u_a = -(1 - 2 nu)(1 + nu) F X_a / (2 pi E r^2)``
F along 1  ``u1 = (1 + nu) F / (pi E r) * [(1 - nu) + nu X^2 / r^2]``,
           ``u2 = (1 + nu) F / (pi E r) * nu X Y / r^2``,
           ``u3 = +(1 - 2 nu)(1 + nu) F X / (2 pi E r^2)``
=========  ===========================================================

(F along 2 by exchanging the in-plane axes.)  Every component is a combination of six
kernels ``g`` = 1/r, X^2/r^3, Y^2/r^3, XY/r^3, X/r^2, Y/r^2.

Rectangle integrals
-------------------
The displacement at (x1, x2) from the cell [-a, a] x [-b, b] (a = d1/2, b = d2/2) is the
integral of g(X, Y) over X in [x1 - a, x1 + a], Y in [x2 - b, x2 + b].  With an
antiderivative P (d^2 P / dX dY = g) it is the corner sum

    I[g] = P(x1 + a, x2 + b) - P(x1 + a, x2 - b) - P(x1 - a, x2 + b) + P(x1 - a, x2 - b).

The antiderivatives used (each checked symbolically with sympy and against quadrature in
``tests/test_influence.py``; terms depending on X alone or Y alone are dropped, they cancel
in the corner sum):

==========  ================================================
g           P(X, Y)
==========  ================================================
1/r         ``X asinh(Y/|X|) + Y asinh(X/|Y|)``   (Love 1929)
X^2/r^3     ``Y asinh(X/|Y|)``
Y^2/r^3     ``X asinh(Y/|X|)``
X Y/r^3     ``-r``
X/r^2       ``Y ln r + X atan(Y/X)``
Y/r^2       ``X ln r + Y atan(X/Y)``
==========  ================================================

Each P is continuous, and its limit where a factor vanishes is 0 (``X asinh(Y/|X|) -> 0``
as X -> 0, ``Y ln r -> 0`` as r -> 0, ``X atan(Y/X) -> 0`` as X -> 0); those limits are
used explicitly, so the kernels are finite everywhere, on cell edges and corners and at
the cell's own centre included.  The asinh form (rather than ``X ln(Y + r)``) avoids the
cancellation of ``Y + r`` for Y < 0.

With ``c = (1 + nu) / (pi E)`` and ``c' = (1 - 2 nu)(1 + nu) / (2 pi E)``:

    K33 = (1 - nu^2)/(pi E) I[1/r]
    K11 = c [(1 - nu) I[1/r] + nu I[X^2/r^3]],   K22 = c [(1 - nu) I[1/r] + nu I[Y^2/r^3]]
    K12 = K21 = c nu I[XY/r^3]
    K13 = -c' I[X/r^2],  K23 = -c' I[Y/r^2],  K31 = +c' I[X/r^2],  K32 = +c' I[Y/r^2]

so the reciprocal theorem K_ij(x) = K_ji(-x) holds exactly and the coupling terms vanish
for nu = 1/2.

Accuracy: the corner sum cancels digits far from the cell; the rounding error is about
1e-16 (R/d)^2 relative at R cells (measured against 50-digit arithmetic: 3e-11 at 511
cells, 3e-10 at 1000), far below the O((d/R)^2) difference from a point load.

References
----------
.. [1] A. E. H. Love, "The stress produced in a semi-infinite solid by pressure on part of
   the boundary", Phil. Trans. R. Soc. A 228 (1929) 377-420. doi:10.1098/rsta.1929.0009
.. [2] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, §3.2-3.5.
   doi:10.1017/CBO9781139171731
.. [3] S. Liu, Q. Wang, G. Liu, "A versatile method of discrete convolution and FFT
   (DC-FFT) for contact analyses", Wear 243 (2000) 101-111.
   doi:10.1016/S0043-1648(00)00427-0
.. [4] J. J. Kalker, *Three-Dimensional Elastic Bodies in Rolling Contact*, Kluwer, 1990.
   doi:10.1007/978-94-015-7889-9
"""
from __future__ import annotations

import numpy as np

from ..exceptions import SceneError

__all__ = ["KEYS", "IN_PLANE_KEYS", "NORMAL_KEYS", "COUPLING_KEYS", "cell_influence",
           "offset_grid", "body_kernels", "pair_kernels", "cell_influence_parts",
           "body_kernel_parts"]

#: The nine kernel names, "ij" = displacement along i from traction along j.
KEYS = ("11", "12", "13", "21", "22", "23", "31", "32", "33")
#: Terms that add in the two-body sum (paper eq. 8).
IN_PLANE_KEYS = ("11", "12", "21", "22")
NORMAL_KEYS = ("33",)
#: Terms that subtract in the two-body sum (paper eq. 8).
COUPLING_KEYS = ("13", "23", "31", "32")

# |ratio| cap inside asinh: only reached when |X| is subnormal relative to |Y|, where
# X asinh(Y/|X|) is 0 to within ~1e-305 anyway.  Keeps inf out of 0 * inf.
_RATIO_CAP = 1e300

# Parity of each kernel in x1 and in x2 (+1 even, -1 odd).
_PARITY = {"11": (1.0, 1.0), "22": (1.0, 1.0), "33": (1.0, 1.0),
           "12": (-1.0, -1.0), "21": (-1.0, -1.0),
           "13": (-1.0, 1.0), "31": (-1.0, 1.0),
           "23": (1.0, -1.0), "32": (1.0, -1.0)}


def _x_asinh(x, y):
    """``x * asinh(y / |x|)`` with its limit 0 at x = 0 [m]."""
    ax = np.abs(x)
    t = np.clip(y / np.where(ax > 0.0, ax, 1.0), -_RATIO_CAP, _RATIO_CAP)
    return x * np.arcsinh(t)  # x = 0 gives 0 * finite = 0


def _x_atan(x, y):
    """``x * atan(y / x)`` with its limit 0 at x = 0 [m]."""
    return x * np.arctan(y / np.where(x != 0.0, x, 1.0))


def _corner_integrals(x1, x2, a, b):
    """Rectangle integrals of the six point-load kernels by the corner sum.

    Parameters
    ----------
    x1, x2 : ndarray
        Relative position of the field point [m] (broadcast already).
    a, b : float
        Half sides of the cell [m].

    Returns
    -------
    tuple of ndarray
        I[1/r], I[X^2/r^3], I[Y^2/r^3], I[XY/r^3] [m]; I[X/r^2], I[Y/r^2] [m].
    """
    shape = x1.shape
    i_xx = np.zeros(shape)
    i_yy = np.zeros(shape)
    i_xy = np.zeros(shape)
    i_x = np.zeros(shape)
    i_y = np.zeros(shape)
    for sx, big_x in ((1.0, x1 + a), (-1.0, x1 - a)):
        for sy, big_y in ((1.0, x2 + b), (-1.0, x2 - b)):
            s = sx * sy
            r = np.hypot(big_x, big_y)
            ln_r = np.log(np.where(r > 0.0, r, 1.0))  # multiplied by X or Y: 0 at r = 0
            p_x = _x_asinh(big_x, big_y)  # X asinh(Y/|X|): primitive of Y^2/r^3
            p_y = _x_asinh(big_y, big_x)  # Y asinh(X/|Y|): primitive of X^2/r^3
            if s > 0:
                i_xx += p_y
                i_yy += p_x
                i_xy -= r
                i_x += big_y * ln_r + _x_atan(big_x, big_y)
                i_y += big_x * ln_r + _x_atan(big_y, big_x)
            else:
                i_xx -= p_y
                i_yy -= p_x
                i_xy += r
                i_x -= big_y * ln_r + _x_atan(big_x, big_y)
                i_y -= big_x * ln_r + _x_atan(big_y, big_x)
    i_r = i_xx + i_yy
    return i_r, i_xx, i_yy, i_xy, i_x, i_y


def cell_influence(x1, x2, d1, d2, young, poisson):
    """Influence coefficients of one rectangular cell under uniform unit tractions.

    Closed-form rectangle integrals of the Boussinesq and Cerruti point-load solutions
    (Love 1929 for the normal term; Johnson 1985 §3.2-3.5; see the module docstring for
    the antiderivatives).

    Parameters
    ----------
    x1, x2 : array_like
        Relative position of the field point, field point minus cell centre [m].
        Broadcastable against each other.
    d1, d2 : float
        Cell sides along x1 and x2 [m].
    young : float
        Young modulus E of the body [Pa].
    poisson : float
        Poisson ratio nu of the body [1].

    Returns
    -------
    dict of str to ndarray
        Keys ``"11", "12", "13", "21", "22", "23", "31", "32", "33"``: ``K_ij`` is the
        surface displacement along i [m] per unit traction [Pa] along j, i.e. [m/Pa], with
        the broadcast shape of ``x1, x2``, float64.  Finite everywhere (own cell, edges and
        corners included).

    Notes
    -----
    Sign convention (docs/conventions.md): x3 points into the body; a pressure (traction
    along +3) pulls surface points radially inwards (``K13 < 0`` for x1 > 0), and a shear
    along +1 lifts the surface ahead of it in +3 (``K31 > 0`` for x1 > 0).  The reciprocal
    theorem ``K_ij(x) = K_ji(-x)`` holds exactly.
    """
    x1 = np.asarray(x1, dtype=np.float64)
    x2 = np.asarray(x2, dtype=np.float64)
    x1, x2 = np.broadcast_arrays(x1, x2)
    a = 0.5 * float(d1)
    b = 0.5 * float(d2)
    e = float(young)
    nu = float(poisson)
    i_r, i_xx, i_yy, i_xy, i_x, i_y = _corner_integrals(x1, x2, a, b)

    c = (1.0 + nu) / (np.pi * e)
    c_couple = (1.0 - 2.0 * nu) * (1.0 + nu) / (2.0 * np.pi * e)
    k12 = (c * nu) * i_xy
    return {
        "11": c * ((1.0 - nu) * i_r + nu * i_xx),
        "12": k12,
        "13": -c_couple * i_x,
        "21": k12.copy(),
        "22": c * ((1.0 - nu) * i_r + nu * i_yy),
        "23": -c_couple * i_y,
        "31": c_couple * i_x,
        "32": c_couple * i_y,
        "33": ((1.0 - nu * nu) / (np.pi * e)) * i_r,
    }


def offset_grid(n1, n2, d1, d2):
    """Cell offsets of a linear convolution on an n1 x n2 grid, in DC-FFT order.

    Parameters
    ----------
    n1, n2 : int
        Number of cells along x1 and x2 [1].
    d1, d2 : float
        Cell sides [m].

    Returns
    -------
    X1, X2 : ndarray
        Shape ``(2*n1, 2*n2)``, ``indexing='ij'`` [m].  Index i holds the offset
        ``i*d1`` for i < n1 and ``(i - 2*n1)*d1`` for i > n1 (wrap-around order, Liu, Wang
        & Liu 2000).  Index n1 is no physical offset; it holds ``-n1*d1`` (finite), and
        :func:`body_kernels` zeroes the kernel there.  Likewise along x2.
    """
    i = np.arange(2 * n1)
    j = np.arange(2 * n2)
    s1 = np.where(i < n1, i, i - 2 * n1) * float(d1)
    s2 = np.where(j < n2, j, j - 2 * n2) * float(d2)
    return np.meshgrid(s1, s2, indexing="ij")


def body_kernels(n1, n2, d1, d2, young, poisson):
    """All nine influence kernels of one body on the zero-padded DC-FFT grid.

    Parameters
    ----------
    n1, n2 : int
        Number of cells along x1 and x2 [1].
    d1, d2 : float
        Cell sides [m].
    young : float
        Young modulus [Pa] (for a viscoelastic body, the one its creep function is
        normalised by).
    poisson : float
        Poisson ratio [1].

    Returns
    -------
    dict of str to ndarray
        :func:`cell_influence` on :func:`offset_grid` [m/Pa], shape ``(2*n1, 2*n2)``,
        float64, wrap-around order, with row n1 and column n2 set to exactly 0.

    Notes
    -----
    The closed form is evaluated on the offsets ``x1, x2 >= 0`` only; the other
    quadrants follow from the parities of the kernels (even-even: 11, 22, 33; odd-odd:
    12, 21; odd in x1, even in x2: 13, 31; even in x1, odd in x2: 23, 32), which makes
    them exactly symmetric and agrees with :func:`cell_influence` at the negative offsets
    to rounding (relative ~1e-16 (r/d)^2, r the offset, d the cell side).
    """
    # Evaluate the closed form on the non-negative quadrant only (4x fewer corner sums)
    # and fill the other three by the exact parities of the kernels in x1 and x2.
    s1 = np.arange(n1) * float(d1)
    s2 = np.arange(n2) * float(d2)
    quadrant = cell_influence(s1[:, None], s2[None, :], d1, d2, young, poisson)
    return _unfold(quadrant, n1, n2)


def _unfold(quadrant, n1, n2):
    """Kernels on the padded grid from their values on the offsets x1, x2 >= 0, by their
    parities (:func:`body_kernels`)."""
    kernels = {}
    for key, q in quadrant.items():
        p1, p2 = _PARITY[key]
        k = np.zeros((2 * n1, 2 * n2))
        k[:n1, :n2] = q
        k[n1 + 1:, :n2] = p1 * q[:0:-1, :]
        k[:n1, n2 + 1:] = p2 * q[:, :0:-1]
        k[n1 + 1:, n2 + 1:] = (p1 * p2) * q[:0:-1, :0:-1]
        kernels[key] = k
    return kernels


def cell_influence_parts(x1, x2, d1, d2, shear_modulus):
    """The influence coefficients of one cell split by their dependence on nu at fixed G.

    With c_G = 1/(2 pi G) the coefficients of :func:`cell_influence` are linear in nu at a
    fixed shear modulus (c = (1 + nu)/(pi E) = c_G, c' = (1 - 2 nu) c_G / 2,
    (1 - nu^2)/(pi E) = (1 - nu) c_G)::

        K11 = c_G (I[1/r] - nu I[Y^2/r^3]),   K22 = c_G (I[1/r] - nu I[X^2/r^3]),
        K33 = c_G (1 - nu) I[1/r],            K12 = K21 = c_G nu I[XY/r^3],
        K13 = -c_G (1/2 - nu) I[X/r^2],       K31 = -K13 (and 23, 32 with Y)

    (I[1/r] = I[X^2/r^3] + I[Y^2/r^3]). So K = K_shear + nu K_poisson, the *shear part*
    scaling with 1/G and the *Poisson part* with nu/G: a body whose Poisson ratio varies
    in time gives each part its own creep function (1/G(t) and nu(t)/G(t); their
    differences are the normal compliance (1 - nu)/G and the coupling one (1 - 2 nu)/G).

    Parameters
    ----------
    x1, x2 : array_like
        Relative position of the field point [m].
    d1, d2 : float
        Cell sides [m].
    shear_modulus : float
        G [Pa].

    Returns
    -------
    (dict, dict)
        K_shear and K_poisson [m/Pa], keys as :func:`cell_influence`.
    """
    x1 = np.asarray(x1, dtype=np.float64)
    x2 = np.asarray(x2, dtype=np.float64)
    x1, x2 = np.broadcast_arrays(x1, x2)
    i_r, i_xx, i_yy, i_xy, i_x, i_y = _corner_integrals(x1, x2, 0.5 * float(d1),
                                                        0.5 * float(d2))
    cg = 1.0 / (2.0 * np.pi * float(shear_modulus))
    zero = np.zeros_like(i_r)
    shear = {"11": cg * i_r, "12": zero, "13": -0.5 * cg * i_x, "21": zero.copy(),
             "22": cg * i_r, "23": -0.5 * cg * i_y, "31": 0.5 * cg * i_x,
             "32": 0.5 * cg * i_y, "33": cg * i_r}
    poisson = {"11": -cg * i_yy, "12": cg * i_xy, "13": cg * i_x, "21": cg * i_xy,
               "22": -cg * i_xx, "23": cg * i_y, "31": -cg * i_x, "32": -cg * i_y,
               "33": -cg * i_r}
    return shear, poisson


def body_kernel_parts(n1, n2, d1, d2, shear_modulus):
    """The shear and Poisson parts of a body's nine kernels on the padded DC-FFT grid
    (:func:`cell_influence_parts`; laid out as :func:`body_kernels`): the kernels of a
    Poisson ratio nu are ``shear + nu * poisson``.

    Parameters
    ----------
    n1, n2 : int
        Number of cells along x1 and x2 [1].
    d1, d2 : float
        Cell sides [m].
    shear_modulus : float
        G [Pa] (for a viscoelastic body, where its creep function is 1).

    Returns
    -------
    (dict, dict)
        The two parts [m/Pa], each of shape ``(2*n1, 2*n2)`` per key.
    """
    s1 = np.arange(n1) * float(d1)
    s2 = np.arange(n2) * float(d2)
    shear, poisson = cell_influence_parts(s1[:, None], s2[None, :], d1, d2, shear_modulus)
    return _unfold(shear, n1, n2), _unfold(poisson, n1, n2)


def pair_kernels(k1, k2, w1=1.0, w2=1.0):
    """Kernels of the relative surface displacement of two bodies (paper eq. 8).

    ``u`` = displacement of body 2 minus displacement of body 1, in global axes (x3 into
    body 2), under the tractions exerted by body 1 on body 2 (docs/conventions.md).
    Body 1 is described in the mirrored frame, so in-plane (11, 12, 21, 22) and normal (33)
    terms add and the coupling terms (13, 23, 31, 32) subtract::

        K_ij = w1 K1_ij + w2 K2_ij        (ij in-plane or 33)
        K_ij = w2 K2_ij - w1 K1_ij        (ij = 13, 23, 31, 32)

    Parameters
    ----------
    k1, k2 : dict of str to ndarray or None
        Kernels of body 1 (indenter) and body 2 (half-space) [m/Pa], e.g. from
        :func:`body_kernels`; ``None`` for a rigid body, which contributes nothing.
    w1, w2 : float
        Scalar weights [1] (creep-function factors phi) of the two bodies.

    The combination is linear, so it applies unchanged to kernel *spectra* (complex
    arrays): the dtype of the inputs is kept.

    Returns
    -------
    dict of str to ndarray
        The nine combined kernels [m/Pa], new arrays.

    Raises
    ------
    SceneError
        If both bodies are rigid (no compliance to compute).
    """
    if k1 is None and k2 is None:
        raise SceneError("both bodies are rigid: the contact has no compliance. "
                         "Make the indenter or the half-space elastic or viscoelastic.")
    out = {}
    for key in KEYS:
        sign1 = -1.0 if key in COUPLING_KEYS else 1.0
        if k1 is None:
            out[key] = w2 * np.asarray(k2[key])
        elif k2 is None:
            out[key] = (sign1 * w1) * np.asarray(k1[key])
        elif sign1 < 0:
            out[key] = w2 * np.asarray(k2[key]) - w1 * np.asarray(k1[key])
        else:
            out[key] = w1 * np.asarray(k1[key]) + w2 * np.asarray(k2[key])
    return out
