"""Influence coefficients of a periodic half-space: the spectra of piecewise-constant tractions
on one period of an infinite surface, for plain (unpadded) FFT convolution.

The grid of n1 x n2 cells of sides d1 x d2 is one period (L1, L2) = (n1 d1, n2 d2). A cell
carries a uniform unit traction, and so does every image of it; the displacement at the
cell centres is a circular convolution whose kernel, sampled at the cell offsets, has the
discrete Fourier transform (angular frequencies θ_a = 2π m_a / n_a in (−π, π])

    K̃_ij(θ) = Σ_{a ∈ Z²} K̂_ij(k_a) S(k_a),   k_a = ((θ1 + 2π a1)/d1, (θ2 + 2π a2)/d2),

S(k) = sinc(k1 d1/2) sinc(k2 d2/2) the transform of the cell's indicator over its area, and
K̂_ij the exact Fourier transforms of the Boussinesq and Cerruti point-load kernels
(:mod:`.influence`; f̂(k) = ∫ f(x) e^(−i k·x) dx), which at a fixed shear modulus G split
into a shear part and a Poisson part, K̂ = (K̂_shear + ν K̂_Poisson)/G, with

    shear:    11 = 22 = 33 = 1/|k|,  13 = −31 = i k1/(2|k|²),  23 = −32 = i k2/(2|k|²)
    Poisson:  11 = −k1²/|k|³, 22 = −k2²/|k|³, 12 = 21 = −k1 k2/|k|³, 33 = −1/|k|,
              13 = −31 = −i k1/|k|², 23 = −32 = −i k2/|k|²

(from FT[1/r] = 2π/|k|, FT[X/r²] = −2πi k1/|k|², FT[X²/r³] = 2π k2²/|k|³,
FT[XY/r³] = −2π k1 k2/|k|³; so K̂33 = 2(1 − ν²)/(E|k|), the contact compliance 2/(E*|k|)
of Westergaard's and Johnson's periodic solutions).

The alias sum (the Poisson-summation form of the sum over periodic images) is split in two:
the a = 0 term, which holds the 1/|k| singularity, is evaluated on the grid's own
frequencies; the rest, R(θ) = Σ_{a≠0}, is analytic on the closed square (|k_a| ≥ π/d there)
and depends on the cells' aspect ratio alone (each term is homogeneous of degree −1 in k,
so R scales with d1 at a fixed d2/d1). R is therefore computed once per aspect ratio on a
fixed grid of 33 x 33 θ nodes over [0, π]² and interpolated to any grid's frequencies
(bicubic splines; the other quadrants by parity). At the nodes the sum over
|a1|, |a2| ≤ A is taken with half weights on its outer shell (the terms alternate in sign,
as sin(θ/2 + π a) = (−1)^a sin(θ/2): the error falls as A⁻⁴) and extrapolated from A = 24
and 48 (Richardson, A⁻⁴). The result matches the direct sum to A = 128 within 3e-7 of the
largest coefficient (``tests/test_periodic.py``), and the image sum in real space (square
shells, extrapolated) converges to it, the coupling kernels' to it plus the uniform field
of the neutral background that the zero mode removes.

The zero mode: a uniform traction on an infinite surface has no finite displacement, so the
mean of each displacement is left undetermined and set to zero (K̃_ij(0) = 0): the normal
problem fixes the mean pressure W/(L1 L2) instead, and the approach ω3 is measured from the
mean of the elastic displacement (docs/conventions.md, "Periodic contact").

References
----------
.. [1] H. M. Westergaard, "Bearing pressures and cracks", J. Appl. Mech. 6 (1939) A49-A53.
.. [2] K. L. Johnson, J. A. Greenwood, J. G. Higginson, "The contact of elastic regular
   wavy surfaces", Int. J. Mech. Sci. 27 (1985) 383-396. doi:10.1016/0020-7403(85)90029-3
.. [3] H. M. Stanley, T. Kato, "An FFT-based method for rough surface contact", J. Tribol.
   119 (1997) 481-485. doi:10.1115/1.2833523
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.fft

from .influence import KEYS

__all__ = ["BASES", "alias_sum", "periodic_bases", "periodic_body_spectra",
           "periodic_part_spectra", "periodic_kernels"]

#: The six basis symbols every kernel combines: 1/|k|, k1²/|k|³, k2²/|k|³, k1k2/|k|³,
#: k1/|k|², k2/|k|² (the last two enter the kernels times i).
BASES = ("r", "11", "22", "12", "1", "2")
#: Bases odd in θ1 (the others are even in θ1); θ2 >= 0 only is needed (real FFT).
ODD_IN_1 = ("12", "1")
#: θ nodes of the remainder's interpolation table: θ1 over [0, π] (θ1 < 0 by parity),
#: θ2 over [0, π].
NODES = (33, 33)
#: Outer shell of the coarser of the two alias sums that are extrapolated (A and 2A).
ALIASES = 24


def _sinc_factor(theta, d, a):
    """(sinc(k d/2), k) at the aliases ``a`` of the angular frequencies θ [rad]:
    ((−1)^a sin(θ/2)/(θ/2 + πa), 1 where θ/2 + πa = 0; (θ + 2πa)/d [1/m])."""
    y = 0.5 * theta + np.pi * a
    safe = np.where(y != 0.0, y, 1.0)
    sign = 1.0 - 2.0 * (np.abs(a) % 2)
    return np.where(y != 0.0, np.sin(0.5 * theta) * sign / safe, 1.0), 2.0 * y / d


def alias_sum(theta1, theta2, d1, d2, outer, skip_zero=False, half_shell=True):
    """Σ over aliases |a1|, |a2| <= ``outer`` of each basis symbol times S (module
    docstring) at the angular frequencies θ1 (n1, 1) and θ2 (1, m) [rad]: {basis: (n1, m)}
    [m], real. The outer shell is weighted by 1/2 (``half_shell``, where ``outer`` > 0), the
    a = 0 term left out with ``skip_zero``; a zero wavevector contributes nothing."""
    theta1 = np.asarray(theta1, float).reshape(-1, 1)
    theta2 = np.asarray(theta2, float).reshape(1, -1)
    a = np.arange(-outer, outer + 1)
    w = np.where((np.abs(a) == outer) & half_shell & (outer > 0), 0.5, 1.0)
    f2, k2 = _sinc_factor(theta2[None, :, :], d2, a[:, None, None])    # (A2, 1, m)
    f2 = f2 * w[:, None, None]
    out = {b: np.zeros((theta1.shape[0], theta2.shape[1])) for b in BASES}
    for i, a1 in enumerate(a):
        f1, k1 = _sinc_factor(theta1, d1, a1)                            # (n1, 1)
        weight = (w[i] * f1)[None] * f2                                   # (A2, n1, m)
        if skip_zero and a1 == 0:
            weight = weight * (a != 0)[:, None, None]
        kk = k1[None] * k1[None] + k2 * k2
        zero = kk == 0.0
        inv2 = np.where(zero, 0.0, 1.0 / np.where(zero, 1.0, kk))
        inv = np.sqrt(inv2)
        wr = weight * inv                                                  # S/|k|
        w3 = wr * inv2                                                     # S/|k|³
        w2 = weight * inv2                                                 # S/|k|²
        out["r"] += wr.sum(axis=0)
        out["11"] += (w3 * (k1 * k1)[None]).sum(axis=0)
        out["22"] += (w3 * (k2 * k2)).sum(axis=0)
        out["12"] += (w3 * k1[None] * k2).sum(axis=0)
        out["1"] += (w2 * k1[None]).sum(axis=0)
        out["2"] += (w2 * k2).sum(axis=0)
    return out


@lru_cache(maxsize=8)
def _remainder_table(ratio):
    """Splines of R(θ) (the aliases a ≠ 0) of each basis for cells of sides 1 x ``ratio``
    [m] over θ1, θ2 in [0, π]: {basis: spline}."""
    # here, not at the top: scipy.interpolate pulls scipy.optimize, .linalg, .sparse and
    # .spatial (0.13-0.17 s) into every run, and only a periodic grid needs it
    from scipy.interpolate import RectBivariateSpline

    t1 = np.linspace(0.0, np.pi, NODES[0])
    t2 = np.linspace(0.0, np.pi, NODES[1])
    coarse = alias_sum(t1, t2, 1.0, ratio, ALIASES, skip_zero=True)
    fine = alias_sum(t1, t2, 1.0, ratio, 2 * ALIASES, skip_zero=True)
    return {b: RectBivariateSpline(t1, t2, (16.0 * fine[b] - coarse[b]) / 15.0)  # A⁻⁴ error
            for b in BASES}


def _angles(n1, n2):
    """The grid's angular frequencies θ1 (n1, 1) and θ2 (1, n2//2 + 1) [rad], real-FFT
    layout."""
    return (2.0 * np.pi * np.fft.fftfreq(n1)[:, None],
            2.0 * np.pi * np.fft.rfftfreq(n2)[None, :])


def periodic_bases(n1, n2, d1, d2):
    """The alias-summed basis symbols on an n1 x n2 periodic grid of cells d1 x d2 [m],
    real-FFT layout (n1, n2//2 + 1), real; zero at the zero mode (and, for a basis odd in
    an axis, at that axis's Nyquist frequency)."""
    t1, t2 = _angles(n1, n2)
    out = alias_sum(t1, t2, d1, d2, 0, half_shell=False)   # a = 0: the grid's own term
    table = _remainder_table(float(d2) / float(d1))
    u1, inverse = np.unique(np.abs(t1.ravel()), return_inverse=True)
    sign1 = np.sign(t1)
    for b in BASES:
        rest = table[b](u1, t2.ravel())[inverse]          # the tensor grid, |θ1|
        if b in ODD_IN_1:
            rest = rest * sign1
        out[b] += float(d1) * rest
        out[b][0, 0] = 0.0
    if n1 % 2 == 0:                  # odd in x1: real kernels vanish at Nyquist
        for b in ("12", "1"):
            out[b][n1 // 2, :] = 0.0
    if n2 % 2 == 0:                  # odd in x2
        for b in ("12", "2"):
            out[b][:, -1] = 0.0
    return out


#: Each kernel as (real or imaginary, [(basis, weight of the shear part, weight of the
#: Poisson part), ...]): K̂ = Σ (w_shear/G + ν w_Poisson/G) basis (module docstring).
_TERMS = {
    "11": ("real", [("r", 1.0, 0.0), ("11", 0.0, -1.0)]),
    "22": ("real", [("r", 1.0, 0.0), ("22", 0.0, -1.0)]),
    "33": ("real", [("r", 1.0, -1.0)]),
    "12": ("real", [("12", 0.0, -1.0)]),
    "21": ("real", [("12", 0.0, -1.0)]),
    "13": ("imag", [("1", 0.5, -1.0)]),
    "31": ("imag", [("1", -0.5, 1.0)]),
    "23": ("imag", [("2", 0.5, -1.0)]),
    "32": ("imag", [("2", -0.5, 1.0)]),
}


def _spectra(bases, shear, poisson, n1, n2):
    """The nine kernel spectra with the shear part weighted by ``shear`` and the Poisson
    part by ``poisson`` [1/Pa], scaled for the inverse FFT (1/(n1 n2) folded in), complex
    (a purely real or purely imaginary array each), as the Convolver keeps them."""
    scale = 1.0 / (n1 * n2)
    out = {}
    for key in KEYS:
        part, terms = _TERMS[key]
        spec = np.zeros(bases["r"].shape, dtype=complex)
        target = spec.real if part == "real" else spec.imag
        for basis, ws, wp in terms:
            weight = (ws * shear + wp * poisson) * scale
            if weight != 0.0:
                target += weight * bases[basis]
        out[key] = spec
    return out


def periodic_body_spectra(n1, n2, d1, d2, young, poisson):
    """The nine kernel spectra of one body on an n1 x n2 periodic grid, scaled for the
    unpadded inverse FFT [m/Pa], real-FFT layout: the periodic counterpart of
    :func:`~contactpipe.solver.influence.body_kernels` after
    :meth:`~contactpipe.solver.convolution.Convolver.kernel_spectrum`."""
    nu = float(poisson)
    g = float(young) / (2.0 * (1.0 + nu))
    return _spectra(periodic_bases(n1, n2, d1, d2), 1.0 / g, nu / g, n1, n2)


def periodic_part_spectra(n1, n2, d1, d2, shear_modulus):
    """The shear and Poisson parts of a body's kernel spectra on a periodic grid (the
    periodic counterpart of :func:`~contactpipe.solver.influence.body_kernel_parts`)."""
    g = float(shear_modulus)
    bases = periodic_bases(n1, n2, d1, d2)
    return _spectra(bases, 1.0 / g, 0.0, n1, n2), _spectra(bases, 0.0, 1.0 / g, n1, n2)


def periodic_kernels(n1, n2, d1, d2, young, poisson):
    """The nine periodic kernels in real space, (n1, n2) in wrap-around order [m/Pa]: the
    displacement at the cell offset (i d1, j d2) (mod the period) per unit traction on a
    cell and all its images, each of mean zero."""
    spectra = periodic_body_spectra(n1, n2, d1, d2, young, poisson)
    return {k: scipy.fft.irfft2(v * (n1 * n2), s=(n1, n2)) for k, v in spectra.items()}
