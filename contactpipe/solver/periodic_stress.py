"""Stresses inside a periodic elastic half-space from piecewise-constant cell tractions: the
spectra of one depth's 18 kernels on one period, for plain (unpadded) FFT convolution.

The potentials of :mod:`.subsurface` (Love 1929; Johnson 1985, §3.2), H = ∫∫ p ln(ρ + z),
F = ∫∫ q1 ln(ρ + z), F1 = ∫∫ q1 Ω, are in Fourier space (f̂(k) = ∫ f e^(−i k·x) dx, at a
wavevector k of norm κ > 0, per unit traction)

    Ĥ = F̂ = −2π e^(−κz)/κ²,    F̂1 = 2π e^(−κz)/κ³

(from ∂h/∂z = 1/R, whose transform at depth z is 2π e^(−κz)/κ, and ∂Ω/∂z = h), and a
derivative is a factor: ∂/∂x1 → i k1, ∂/∂x2 → i k2, ∂/∂z → −κ. The table of
:mod:`.subsurface` then gives each stress's symbol, e.g. s33 = −(1 + κz) e^(−κz) under a
pressure, s11 = −(1 − κz) e^(−κz) and s22 = −2ν e^(−κz) for k along x1 (Johnson §2.8's
plane-strain field of a sinusoidal pressure). The periodic kernel of a cell's uniform
traction is the alias sum Σ_a symbol(k_a) S(k_a) of :mod:`.periodic` (the cell's sinc
factor S); below the surface the terms fall as e^(−κz), so the sum stops where
e^(−κz) < 1e-13, at most :data:`MAX_ALIASES` shells (outer shell halved, as the surface
kernels' sums: near z = 0 the error falls as the surface's does).

The zero mode is the stress of a uniform traction on a periodic half-space, whose
displacement stays periodic (no mean in-plane strain): a mean pressure p̄ gives
s33 = −p̄ and s11 = s22 = −ν p̄/(1 − ν) (uniaxial strain), a mean shear q̄1 gives s13 = −q̄1
(simple shear), at every depth.
"""
from __future__ import annotations

import math

import numpy as np

from .periodic import _angles, _sinc_factor

__all__ = ["MAX_ALIASES", "depth_symbols", "periodic_depth_spectra"]

#: The most alias shells of one depth's sums (reached within a few cells of the surface).
MAX_ALIASES = 32
_TWO_PI = 2.0 * math.pi
# Parity of each kernel in (x1, x2), as :data:`.subsurface.PARITY` (not imported from
# there: that module builds on this one).
_BASE = {"s11": (1, 1), "s22": (1, 1), "s33": (1, 1), "s12": (-1, -1), "s13": (-1, 1),
         "s23": (1, -1)}
_FLIP = {"p": (1, 1), "q1": (-1, 1), "q2": (1, -1)}
PARITY = {(t, c): (_BASE[c][0] * _FLIP[t][0], _BASE[c][1] * _FLIP[t][1])
          for t in _FLIP for c in _BASE}


def depth_symbols(k1, k2, z, nu):
    """The 18 stress symbols at wavevectors (k1, k2) [1/m] (κ > 0) and depth z [m]:
    {(traction, component): complex array} [Pa/Pa per unit area], traction in
    ("q1", "q2", "p"), component in ("s11", "s22", "s33", "s12", "s13", "s23")."""
    kap = np.hypot(k1, k2)
    e = np.exp(-kap * z)
    D = {"x": 1j * k1, "y": 1j * k2, "z": -kap}
    H = -_TWO_PI * e / (kap * kap)                 # Ĥ = F̂ = Ĝ per unit traction
    H1 = _TWO_PI * e / (kap * kap * kap)           # F̂1 = Ĝ1

    def d(base, axes):
        out = base
        for a in axes:
            out = out * D[a]
        return out

    s = {}
    s[("p", "s11")] = 2 * nu * d(H, "zz") - (1 - 2 * nu) * d(H, "xx") - z * d(H, "xxz")
    s[("p", "s22")] = 2 * nu * d(H, "zz") - (1 - 2 * nu) * d(H, "yy") - z * d(H, "yyz")
    s[("p", "s33")] = d(H, "zz") - z * d(H, "zzz")
    s[("p", "s12")] = -(1 - 2 * nu) * d(H, "xy") - z * d(H, "xyz")
    s[("p", "s13")] = -z * d(H, "xzz")
    s[("p", "s23")] = -z * d(H, "yzz")
    for t, a, b in (("q1", "x", "y"), ("q2", "y", "x")):
        c_aa, c_bb = ("s11", "s22") if a == "x" else ("s22", "s11")
        c_a3, c_b3 = ("s13", "s23") if a == "x" else ("s23", "s13")
        s[(t, c_aa)] = (2 * (1 + nu) * d(H, a + "z") + 2 * nu * d(H1, a * 3)
                        - z * d(H, a * 3))
        s[(t, c_bb)] = 2 * nu * d(H, a + "z") + 2 * nu * d(H1, a + b + b) - z * d(H, a + b + b)
        s[(t, "s33")] = -z * d(H, a + "zz")
        s[(t, "s12")] = d(H, b + "z") + 2 * nu * d(H1, a + a + b) - z * d(H, a + a + b)
        s[(t, c_a3)] = d(H, "zz") - z * d(H, a + a + "z")
        s[(t, c_b3)] = -z * d(H, a + b + "z")
    return {key: v / _TWO_PI for key, v in s.items()}


def _mean_mode(nu):
    """The stress of a uniform unit traction on a periodic half-space [Pa/Pa]."""
    lateral = -nu / (1.0 - nu) if nu < 1.0 else 0.0
    out = {}
    for t in ("q1", "q2", "p"):
        for c in ("s11", "s22", "s33", "s12", "s13", "s23"):
            out[(t, c)] = 0.0
    out[("p", "s33")] = -1.0
    out[("p", "s11")] = out[("p", "s22")] = lateral
    out[("q1", "s13")] = out[("q2", "s23")] = -1.0
    return out


def _shells(z, d1, d2):
    """Alias shells needed at depth z: e^(−κz) < 1e-13 beyond them (at most
    :data:`MAX_ALIASES`)."""
    if z <= 0.0:
        return MAX_ALIASES
    need = 30.0 * max(d1, d2) / (2.0 * math.pi * z) + 1.0
    return int(min(MAX_ALIASES, math.ceil(need)))


def periodic_depth_spectra(n1, n2, d1, d2, nu, z):
    """The 18 kernel spectra of depth z on an n1 x n2 periodic grid, scaled for the
    unpadded inverse FFT (1/(n1 n2) folded in), real-FFT layout, complex:
    {(traction, component): array}."""
    t1, t2 = _angles(n1, n2)
    outer = _shells(float(z), float(d1), float(d2))
    a = np.arange(-outer, outer + 1)
    w = np.where(np.abs(a) == outer, 0.5, 1.0) if outer > 0 else np.ones(1)
    f2, k2 = _sinc_factor(t2, d2, a[:, None, None])                 # (A, 1, m)
    out = None
    for i, a1 in enumerate(a):
        f1, k1 = _sinc_factor(t1, d1, a1)                            # (n1, 1)
        kk = k1[None] * k1[None] + k2 * k2
        zero = kk == 0.0
        safe1 = np.where(zero, 1.0, k1[None] + 0.0 * k2)
        safe2 = np.where(zero, 0.0, k2 + 0.0 * k1[None])
        weight = np.where(zero, 0.0, w[i] * w[:, None, None] * f1[None] * f2)
        sym = depth_symbols(safe1, safe2, float(z), float(nu))
        terms = {key: (v * weight).sum(axis=0) for key, v in sym.items()}
        if out is None:
            out = terms
        else:
            for key, v in terms.items():
                out[key] += v
    assert out is not None
    mean = _mean_mode(float(nu))
    scale = 1.0 / (n1 * n2)
    for key, v in out.items():
        v[0, 0] = mean[key]
        v *= scale
        p1, p2 = PARITY[key]            # a real kernel odd in an axis: 0 at its Nyquist
        if p1 < 0 and n1 % 2 == 0:
            v[n1 // 2, :] = 0.0
        if p2 < 0 and n2 % 2 == 0:
            v[:, -1] = 0.0
    return out
