"""The influence operator of a body pair on one grid: cached kernel spectra, applied by DC-FFT.

``u = K ⊛ [q1, q2, p]`` with the pair kernels of paper eq. (8) (docs/conventions.md).
Each body's kernel spectra are computed once per (grid, body) and cached for the process;
the operator of a time step is a linear combination of them, weighted by the creep
factors of the time rule (paper eq. 9), formed once per run in spectral space.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .convolution import Convolver
from .influence import body_kernels, pair_kernels

__all__ = ["BodySpectra", "ContactOperator", "body_spectra", "convolver", "history_kernels",
           "history_displacement"]

class BodySpectra(dict):
    """Kernel spectra (scaled for the inverse FFT) of one body on one grid: key 'ij'."""


@lru_cache(maxsize=16)
def _body_spectra_cached(n1, n2, d1, d2, young, poisson, backend, threads):
    conv = convolver(n1, n2, backend, threads)
    kernels = body_kernels(n1, n2, d1, d2, young, poisson)
    return BodySpectra({k: conv.kernel_spectrum(v) for k, v in kernels.items()})


@lru_cache(maxsize=8)
def convolver(n1, n2, backend="auto", threads=1):
    """The process's DC-FFT engine for an n1 x n2 grid (FFT plans made once, then reused)."""
    return Convolver(n1, n2, backend=backend, threads=threads)


def body_spectra(body, n1, n2, d1, d2, backend="auto", threads=1):
    """Spectra of one body's nine kernels, or None for a rigid body (cached)."""
    if body.rigid:
        return None
    return _body_spectra_cached(int(n1), int(n2), float(d1), float(d2), float(body.young),
                                float(body.poisson), backend, int(threads))


class ContactOperator:
    """Relative displacement of a body pair from cell tractions, on one grid.

    Parameters
    ----------
    spectra1, spectra2 : BodySpectra or None
        Spectra of the indenter (body 1) and half-space (body 2); None when rigid.
    w1, w2 : float
        Creep weights of the current traction increment for each body [1]
        (1 for elastic bodies).
    conv : Convolver
        The convolution engine of the grid (it counts the FFT pairs).
    """

    def __init__(self, spectra1, spectra2, w1, w2, conv: Convolver):
        self.conv = conv
        self.w1, self.w2 = float(w1), float(w2)
        s1 = spectra1 if (spectra1 is not None and self.w1 != 0.0) else None
        s2 = spectra2 if (spectra2 is not None and self.w2 != 0.0) else None
        self.rigid = s1 is None and s2 is None
        self.k = pair_kernels(s1, s2, self.w1, self.w2) if not self.rigid else None
        self._derived = {}          # constants derived from the spectra, computed once

    # -- the pieces the inner problems need -------------------------------------------
    def normal(self, p):
        """u3 [m] from the pressure p [Pa] (one FFT pair)."""
        return self.conv.convolve(self.k["33"], p)

    def tangential_scalar(self, q1):
        """u1 [m] from q1 [Pa] (one FFT pair; the Cattaneo-Mindlin form, q2 = 0)."""
        return self.conv.convolve(self.k["11"], q1)

    def tangential_vector(self, q):
        """(u1, u2) [m] from (q1, q2) [Pa] (two FFT pairs)."""
        k = self.k
        return self.conv.convolve_matrix([[k["11"], k["12"]], [k["21"], k["22"]]], [q[0], q[1]])

    def coupling_to_normal(self, q1, q2=None):
        """u3 [m] from the shear tractions (K31, K32)."""
        k = self.k
        return self.conv.convolve_matrix([[k["31"], k["32"]]], [q1, q2])[0]

    def coupling_to_tangential(self, p, two_components=True):
        """(u1, u2) [m] (or u1 alone) from the pressure (K13, K23)."""
        k = self.k
        rows = [[k["13"]], [k["23"]]] if two_components else [[k["13"]]]
        return self.conv.convolve_matrix(rows, [p])

    def in_plane(self, q1=None, q2=None, p=None):
        """(u1, u2) [m] from all tractions (2 inverse transforms)."""
        k = self.k
        rows = [[k[f"{i}1"], k[f"{i}2"], k[f"{i}3"]] for i in (1, 2)]
        return self.conv.convolve_matrix(rows, [q1, q2, p])

    def self_influence(self, component="11"):
        """Displacement of a cell under its own unit traction, K_ij(0, 0) [m/Pa] (cached)."""
        key = ("self", component)
        if key not in self._derived:
            k = self.k[component]
            m2 = self.conv.m2
            total = k[:, 0].sum() + 2.0 * k[:, 1:m2 // 2].sum() + k[:, m2 // 2].sum()
            self._derived[key] = float(np.real(total))
        return self._derived[key]

    def tangential_norm(self, components=2):
        """Largest eigenvalue of the tangential kernel block over the padded spectrum, an
        upper bound of the operator's norm (the projected-gradient step; cached)."""
        key = ("norm", components)
        if key not in self._derived:
            k = self.k
            m = self.conv.m1 * self.conv.m2
            a = np.real(k["11"]) * m
            if components == 1:
                value = float(np.max(a))
            else:
                c, d = np.real(k["12"]) * m, np.real(k["22"]) * m
                value = float(np.max(0.5 * (a + d) + np.sqrt(0.25 * (a - d) ** 2 + c ** 2)))
            self._derived[key] = value
        return self._derived[key]

    def full(self, p, q1=None, q2=None):
        """(u1, u2, u3) [m] from all tractions (3 forward, 3 inverse transforms at most)."""
        k = self.k
        rows = [[k[f"{i}1"], k[f"{i}2"], k[f"{i}3"]] for i in (1, 2, 3)]
        return self.conv.convolve_matrix(rows, [q1, q2, p])


def history_kernels(spectra1, spectra2):
    """Each body's kernel spectra with the signs of eq. (8) (body 1: coupling negative), for
    :func:`history_displacement`; built once per run. None for a body without spectra."""
    return (None if spectra1 is None else pair_kernels(spectra1, None),
            None if spectra2 is None else pair_kernels(None, spectra2))


def history_displacement(kernels, h1, h2, conv: Convolver, outputs=(1, 2, 3)):
    """Known displacement from the bodies' Boltzmann history tractions (weights already in).

    Parameters
    ----------
    kernels : tuple
        (body 1, body 2) signed kernel spectra from :func:`history_kernels`; an entry may be
        None (rigid, or no history).
    h1, h2 : sequence of 3 arrays or None
        History tractions [Pa] for (q1, q2, p) of each body; an entry may be None (zero).
    outputs : tuple of int
        Which displacement components to return (1, 2, 3).

    Returns
    -------
    ndarray (len(outputs), n1, n2)
        Relative displacement [m] with the signs of eq. (8).
    """
    out = np.zeros((len(outputs), conv.n1, conv.n2))
    for k, h in zip(kernels, (h1, h2)):
        if k is None or h is None:
            continue
        rows = [[k[f"{i}{j}"] for j in (1, 2, 3)] for i in outputs]
        xs = [None if (hj is None or not np.any(hj)) else hj for hj in h]
        out += conv.convolve_matrix(rows, xs)
    return out
