"""Generated self-affine surfaces: random phases under an isotropic power spectrum.

The spectrum is C(q) = C0 (q / q_r)^(-2 (1 + H)) between the roll-off wavenumber
q_r = 2 pi / lambda_r and the short cut-off q_s = 2 pi / lambda_s, flat at C0 below q_r
and 0 above q_s (and at q = 0: the mean height is 0). Each Fourier mode of the scene's
grid gets the amplitude sqrt(C(|q|)) and a random phase from ``numpy.random.default_rng(
seed)`` (the phases of the FFT of white noise, so that the heights are real), so the
surface is periodic on the grid by construction and the same seed gives the same surface.
C0 is set by the rms height, or by the rms slope sqrt(<|grad h|^2>) of the band-limited
surface (the spectral derivative, summed by Parseval's theorem).

Units: metres; wavenumbers in rad/m.
"""
from __future__ import annotations

import numpy as np

__all__ = ["self_affine", "wavenumbers", "rms_slope", "radial_psd", "rough_problems"]


def wavenumbers(n1: int, n2: int, l1: float, l2: float):
    """Wavenumber magnitudes |q| (n1, n2) [rad/m] of the full FFT of an n1 x n2 grid of
    sides l1, l2 [m], with the components (q1 column, q2 row)."""
    q1 = 2 * np.pi * np.fft.fftfreq(n1, d=l1 / n1).reshape(-1, 1)
    q2 = 2 * np.pi * np.fft.fftfreq(n2, d=l2 / n2).reshape(1, -1)
    return np.hypot(q1, q2), q1, q2


def rms_slope(h, l1: float, l2: float) -> float:
    """rms of |grad h| [1] of the band-limited periodic surface ``h`` (n1, n2) [m] of
    sides l1, l2 [m], by Parseval: sqrt(sum |q|^2 |H(q)|^2) / (n1 n2)."""
    n1, n2 = h.shape
    q = wavenumbers(n1, n2, l1, l2)[0]
    spec = np.fft.fft2(h)
    return float(np.sqrt(np.sum(q ** 2 * np.abs(spec) ** 2)) / (n1 * n2))


def self_affine(n1: int, n2: int, l1: float, l2: float, hurst: float, wavelengths,
                seed: int, rms_slope_: float | None = None,
                rms_height: float | None = None):
    """A self-affine random surface on an n1 x n2 grid of sides l1, l2 [m].

    Parameters
    ----------
    hurst : float
        Hurst exponent H, 0 < H < 1.
    wavelengths : (float, float)
        Roll-off and short cut-off wavelengths [m], roll-off > cut-off.
    seed : int
        Seed of the phases (``numpy.random.default_rng``).
    rms_slope_, rms_height : float
        Exactly one: the rms slope [1] (:func:`rms_slope`) or rms height [m] to scale to.

    Returns
    -------
    numpy.ndarray, shape (n1, n2)
        Heights [m], mean 0, ``h[i, j]`` at the i-th x1 and j-th x2 cell centre.
    """
    q, _, _ = wavenumbers(n1, n2, l1, l2)
    q_r, q_s = (2 * np.pi / float(w) for w in wavelengths)
    with np.errstate(divide="ignore"):
        amp = np.where(q < q_r, 1.0, (q / q_r) ** (-(1.0 + hurst)))
    amp[(q > q_s * (1 + 1e-12)) | (q == 0)] = 0.0
    noise = np.fft.fft2(np.random.default_rng(seed).standard_normal((n1, n2)))
    mag = np.abs(noise)
    phase = np.divide(noise, mag, out=np.ones_like(noise), where=mag > 0)
    h = np.fft.ifft2(amp * phase).real
    if rms_height is not None:
        scale = rms_height / float(np.sqrt(np.mean(h ** 2)))
    elif rms_slope_ is not None:
        scale = rms_slope_ / rms_slope(h, l1, l2)
    else:
        raise ValueError("self_affine: give rms_slope_ or rms_height")
    return h * scale


def radial_psd(h, l1: float, l2: float, bins: int = 24):
    """Radially averaged power spectrum of ``h`` (n1, n2) [m]: (q [rad/m], C [m^4]) at
    logarithmically spaced bins between the grid's fundamental and its Nyquist
    wavenumber; empty bins are left out. C is |H(q)|^2 l1 l2 / (n1 n2)^2, so that
    sum C dq1 dq2 / (2 pi)^2 is the mean square height."""
    n1, n2 = h.shape
    q = wavenumbers(n1, n2, l1, l2)[0].ravel()
    c = (np.abs(np.fft.fft2(h)) ** 2).ravel() * l1 * l2 / (n1 * n2) ** 2
    lo, hi = 2 * np.pi / max(l1, l2), np.pi * min(n1 / l1, n2 / l2)
    edges = np.geomspace(lo, hi, bins + 1)
    which = np.digitize(q, edges) - 1
    keep = (which >= 0) & (which < bins)
    count = np.bincount(which[keep], minlength=bins)
    qs = np.bincount(which[keep], weights=q[keep], minlength=bins)
    cs = np.bincount(which[keep], weights=c[keep], minlength=bins)
    has = count > 0
    return qs[has] / count[has], cs[has] / count[has]


def rough_problems(wavelengths, x1, x2) -> list:
    """Problems of a rough surface's wavelengths on the scene's grid (cell centres
    ``x1``, ``x2`` [m]): the short cut-off must span at least two cells (the grid's
    Nyquist wavelength, the larger cell), the roll-off at most the shorter side (a longer
    one is not on the grid: the surface would lack the wavelengths its rms describes)."""
    out, slack = [], 1e-9                 # of rounding in the grid's coordinates
    steps = [float(x[1] - x[0]) for x in (x1, x2)]
    sides = [d * len(x) for d, x in zip(steps, (x1, x2), strict=True)]
    roll, short = (float(w) for w in wavelengths)
    if short < 2 * max(steps) * (1 - slack):
        out.append(f"geometry.wavelengths: the short cut-off {short:.6g} m is below two "
                   f"cells of the grid (2 x {max(steps):.6g} m = {2 * max(steps):.6g} m); "
                   f"raise it or refine grid.points")
    if roll > min(sides) * (1 + slack):
        out.append(f"geometry.wavelengths: the roll-off {roll:.6g} m is longer than the "
                   f"grid's side {min(sides):.6g} m, so the surface cannot hold it; "
                   f"lower it or enlarge grid.size")
    return out
