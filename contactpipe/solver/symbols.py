"""Model symbols of the contact operator's blocks on the unpadded grid taken as periodic:
what the preconditioners' filters invert (:meth:`ContactOperator.normal_preconditioner`,
``joint_preconditioner``, ``shear_preconditioner``, ``tangential_preconditioner``).

A half-space's surface compliance behaves as 1/|ξ| (Boussinesq, Cerruti; Johnson 1985,
§3.2–3.5): in Fourier space, with ξ̂ = ξ/|ξ|,

    K̂33 = c33 / |ξ|,    K̂_ab = λ_F (δ_ab − ν_e ξ̂_a ξ̂_b) / |ξ|    (a, b in-plane),

ν_e the pair's effective Poisson ratio (the in-plane block's eigenvalues are λ_F/|ξ| and
(1 − ν_e) λ_F/|ξ|: K11 is 1/(1 − ν_e) times stiffer across its own axis than along it,
1.48 for steel on aluminium). On the grid, |ξ| is replaced by σ, the symbol of the discrete
(−Δ)^½, times a radial profile g(σ) read from the grid's own K33 spectrum:

    K̂33 ≈ c33 g(σ) / σ,    K̂_ab ≈ λ_F g(σ) (δ_ab − ν_e ξ̂_a ξ̂_b) / σ,

ξ̂ the direction of the discrete frequency (2 sin(θ1/2)/Δ1, 2 sin(θ2/2)/Δ2). The scales c33,
λ_F are matched at the grid's Nyquist corner (the padded spectra there), ν_e is read from
the grid's K11 in real space, far from the cell (K11(0, x2)·|x2| / (K11(x1, 0)·|x1|) =
1 − ν_e exactly for a point load, 6 cells or more out), and g is the median of the sampled
K̂33 · σ / c33 over rings of σ (1.21 at the lowest frequencies, 1 at the corner, on the
bench's grids). The off-diagonal K̂12 is left out: on the grid it fades to a fifth of
the continuous value over the top quarter of the frequencies (aliasing), and a filter
that inverted it measured no better (docs/design-choices.md).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft

__all__ = ["PlaneModel", "plane_model", "radial_profile", "root_laplacian"]

#: rings of σ over which the radial profile's median is taken
RINGS = 24


def _angles(n1, n2):
    """The grid's angular frequencies θ1 (n1, 1) and θ2 (1, n2//2 + 1) [rad], real-FFT
    layout."""
    return (2.0 * np.pi * np.fft.fftfreq(n1)[:, None],
            2.0 * np.pi * np.fft.rfftfreq(n2)[None, :])


def root_laplacian(n1, n2, cell):
    """The symbol σ [1/m] of (−Δ)^½ on the n1 x n2 grid taken as periodic (real-FFT
    layout): sqrt((2 − 2 cos θ1)/Δ1² + (2 − 2 cos θ2)/Δ2²), θ the grid's angular
    frequencies, the zero mode set to the smallest other value; cells of unknown sides
    (``cell`` None) taken square of side 1."""
    d1, d2 = cell if cell is not None else (1.0, 1.0)
    t1, t2 = _angles(n1, n2)
    sigma = np.sqrt((2.0 - 2.0 * np.cos(t1)) / d1 ** 2 + (2.0 - 2.0 * np.cos(t2)) / d2 ** 2)
    sigma[0, 0] = sigma[sigma > 0].min() if sigma.size > 1 else 1.0
    return sigma


def radial_profile(k33_sampled, c33, sigma):
    """g(σ) [1]: the median of k33_sampled · σ / c33 over :data:`RINGS` rings of σ,
    interpolated linearly between the rings' medians and clipped to [0.5, 2];
    ``k33_sampled`` the padded K33 spectrum at the unpadded grid's frequencies [m/Pa],
    ``c33`` = K̂33 σ at the Nyquist corner [1/Pa]. All ones where the grid is too small
    for rings of four modes or more, or the spectrum is not positive."""
    ratio = np.real(k33_sampled) * sigma / c33
    r = sigma / float(sigma.max())
    edges = np.linspace(float(r.min()), 1.0 + 1e-12, RINGS + 1)
    ring = np.clip(np.searchsorted(edges, r, side="right") - 1, 0, RINGS - 1)
    mid, med = [], []
    for i in range(RINGS):
        sel = ring == i
        if np.count_nonzero(sel) >= 4:
            mid.append(float(np.median(r[sel])))
            med.append(float(np.median(ratio[sel])))
    if len(mid) < 2 or not np.all(np.isfinite(med)) or min(med) <= 0.0:
        return np.ones_like(sigma)
    return np.clip(np.interp(r, mid, med), 0.5, 2.0)


@dataclass(frozen=True)
class PlaneModel:
    """The in-plane model symbol's pieces on one grid (real-FFT layout).

    Attributes
    ----------
    nu : float
        ν_e [1], in [0, 0.5].
    lam : float
        λ_F [1/Pa]: K̂_ab σ/g at ν_e = 0 (the block's stiffer eigenvalue).
    cc, ss, cs : ndarray
        ξ̂1², ξ̂2², ξ̂1 ξ̂2 of the discrete frequencies (cs zero on the Nyquist row and
        column, where the filter must stay real and even, and at the zero mode).
    """

    nu: float
    lam: float
    cc: np.ndarray
    ss: np.ndarray
    cs: np.ndarray

    def along(self, axis):
        """(1 − ν_e (ξ̂·e)²) for the unit in-plane vector(s) ``axis`` (2,) or (k, 2), the
        latter stacked (k, n1, n2//2 + 1)."""
        e = np.asarray(axis, dtype=float)
        if e.ndim == 2:
            e0, e1 = e[:, 0, None, None], e[:, 1, None, None]
        else:
            e0, e1 = e[0], e[1]
        return 1.0 - self.nu * (self.cc * e0 * e0 + self.ss * e1 * e1
                                + 2.0 * self.cs * e0 * e1)


def plane_model(k11_padded, corner11, n1, n2, cell, periodic=False) -> PlaneModel:
    """The in-plane model of a grid from its padded K11 spectrum (``k11_padded``, scaled
    as the operator keeps it: the inverse FFT's 1/(m1 m2) folded in) and its value at the
    Nyquist corner times σ there, ``corner11`` [1/Pa]. ``periodic``: the spectrum is the
    unpadded one of a periodic grid, whose kernel in real space has no point-load tail;
    ν_e is then read from the spectrum at the lowest frequency along each axis, where
    K̂11 |ξ| is λ_F (1 − ν_e) along x1 and λ_F along x2."""
    d1, d2 = cell if cell is not None else (1.0, 1.0)
    m1, m2 = (n1, n2) if periodic else (2 * n1, 2 * n2)
    R = min(16, n1 // 4, n2 // 4)
    nu = 0.0
    if periodic:
        along = float(np.real(k11_padded[1, 0])) * (2.0 * np.pi / (n1 * d1))
        across = float(np.real(k11_padded[0, 1])) * (2.0 * np.pi / (n2 * d2))
        if along > 0.0 and across > 0.0:
            nu = float(np.clip(1.0 - along / across, 0.0, 0.5))
    elif R >= 2:    # one inverse transform, set-up work; not the operator's kept kernels
        k11 = scipy.fft.irfft2(k11_padded * (m1 * m2), s=(m1, m2))
        along, across = float(k11[R, 0]) * d1, float(k11[0, R]) * d2
        if along > 0.0 and across > 0.0:
            nu = float(np.clip(1.0 - across / along, 0.0, 0.5))
    t1, t2 = _angles(n1, n2)
    x1 = np.broadcast_to(2.0 * np.sin(t1 / 2.0) / d1, (n1, t2.size))
    x2 = np.broadcast_to(2.0 * np.sin(t2 / 2.0) / d2, (n1, t2.size))
    norm2 = x1 * x1 + x2 * x2
    norm2[0, 0] = 1.0
    cc, ss, cs = x1 * x1 / norm2, x2 * x2 / norm2, x1 * x2 / norm2
    cc[0, 0] = ss[0, 0] = 0.5
    cs[0, 0] = 0.0
    if n1 % 2 == 0:
        cs[n1 // 2, :] = 0.0
    if n2 % 2 == 0:
        cs[:, -1] = 0.0
    corner_cc = (1.0 / d1 ** 2) / (1.0 / d1 ** 2 + 1.0 / d2 ** 2)
    return PlaneModel(nu, corner11 / (1.0 - nu * corner_cc), cc, ss, cs)
