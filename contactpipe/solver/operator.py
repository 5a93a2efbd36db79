"""The influence operator of a body pair on one grid: cached kernel spectra, applied by DC-FFT.

``u = K ⊛ [q1, q2, p]`` with the pair kernels of paper eq. (8) (docs/conventions.md).
Each body's kernel spectra are computed once per (grid, body) and cached for the process;
the operator of a time step is a linear combination of them, weighted by the creep
factors of the time rule (paper eq. 9), formed once per distinct tuple of weights in
spectral space. A body with a constant Poisson ratio has one set of kernels; one whose
Poisson ratio varies in time has two *parts* (shear and Poisson,
:func:`~contactpipe.solver.influence.body_kernel_parts`), each weighted by its own creep
function: the operator of an instant is then the weighted sum of the parts, formed once,
and applying it costs the same FFT pairs.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.fft

from .blocks import BlockOperator
from .convolution import Convolver
from .influence import body_kernel_parts, body_kernels, pair_kernels
from .periodic import periodic_body_spectra, periodic_part_spectra
from .symbols import plane_model, radial_profile, root_laplacian

__all__ = ["BodySpectra", "ContactOperator", "body_spectra", "body_spectra_parts",
           "convolver", "history_kernels", "history_displacement", "weighted_spectra"]


class BodySpectra(dict):
    """Kernel spectra (scaled for the inverse FFT) of one body on one grid: key 'ij'.

    Attributes
    ----------
    cell : tuple of float or None
        The cell sides (Δ1, Δ2) [m] of the grid, where known.
    """

    cell: tuple[float, float] | None = None

    @classmethod
    def on(cls, spectra, cell):
        """The spectra (a dict) with the cell sides of their grid."""
        out = cls(spectra)
        out.cell = None if cell is None else (float(cell[0]), float(cell[1]))
        return out


@lru_cache(maxsize=16)
def _body_spectra_cached(n1, n2, d1, d2, young, poisson, backend, threads, periodic=False):
    if periodic:
        return BodySpectra.on(periodic_body_spectra(n1, n2, d1, d2, young, poisson), (d1, d2))
    conv = convolver(n1, n2, backend, threads)
    kernels = body_kernels(n1, n2, d1, d2, young, poisson)
    return BodySpectra.on({k: conv.kernel_spectrum(v) for k, v in kernels.items()}, (d1, d2))


@lru_cache(maxsize=8)
def _part_spectra_cached(n1, n2, d1, d2, shear_modulus, backend, threads, periodic=False):
    if periodic:
        return tuple(BodySpectra.on(part, (d1, d2))
                     for part in periodic_part_spectra(n1, n2, d1, d2, shear_modulus))
    conv = convolver(n1, n2, backend, threads)
    return tuple(BodySpectra.on({k: conv.kernel_spectrum(v) for k, v in part.items()},
                                (d1, d2))
                 for part in body_kernel_parts(n1, n2, d1, d2, shear_modulus))


@lru_cache(maxsize=8)
def convolver(n1, n2, backend="auto", threads=1, planner="FFTW_MEASURE", periodic=False):
    """The process's DC-FFT engine for an n1 x n2 grid (FFT plans made once, then reused);
    ``periodic``: the circular convolution of a periodic grid, unpadded."""
    return Convolver(n1, n2, backend=backend, threads=threads, planner=planner,
                     periodic=periodic)


def body_spectra(body, n1, n2, d1, d2, backend="auto", threads=1, periodic=False):
    """Spectra of one body's nine kernels, or None for a rigid body (cached); ``periodic``:
    those of the periodic grid (:mod:`~contactpipe.solver.periodic`)."""
    if body.rigid:
        return None
    return _body_spectra_cached(int(n1), int(n2), float(d1), float(d2), float(body.young),
                                float(body.poisson), backend, int(threads), bool(periodic))


def body_spectra_parts(body, n1, n2, d1, d2, backend="auto", threads=1, periodic=False):
    """The spectra of a body's kernel parts, one per creep function of
    ``body.part_creeps`` (cached): ``(body_spectra(...),)`` for a constant Poisson ratio,
    (shear part, Poisson part) when it varies in time; None for a rigid body."""
    if body.rigid:
        return None
    if not body.split:
        return (body_spectra(body, n1, n2, d1, d2, backend, threads, periodic),)
    return _part_spectra_cached(int(n1), int(n2), float(d1), float(d2),
                                float(body.shear_modulus), backend, int(threads),
                                bool(periodic))


def weighted_spectra(parts, weights):
    """A body's kernel spectra and weight for :func:`pair_kernels`: (spectra, w) of a
    single part as they are (so a constant Poisson ratio computes exactly as before),
    (sum_j w_j S_j, 1) of several, (None, 0) for none or all weights 0.

    Parameters
    ----------
    parts : BodySpectra, sequence of BodySpectra, or None
    weights : float or sequence of float
        One creep weight per part [1].
    """
    if parts is None:
        return None, 0.0
    if isinstance(parts, BodySpectra):
        parts = (parts,)
    w = tuple(float(x) for x in np.atleast_1d(weights))
    if len(w) != len(parts):
        raise ValueError(f"{len(parts)} kernel parts with {len(w)} weights")
    if all(x == 0.0 for x in w):
        return None, 0.0
    if len(parts) == 1:
        return parts[0], w[0]
    total = BodySpectra.on({key: sum(wj * part[key] for wj, part in zip(w, parts, strict=True)
                                      if wj != 0.0)
                            for key in parts[0]}, parts[0].cell)
    return total, 1.0


class ContactOperator:
    """Relative displacement of a body pair from cell tractions, on one grid.

    Parameters
    ----------
    spectra1, spectra2 : BodySpectra, tuple of BodySpectra, or None
        Spectra of the indenter (body 1) and half-space (body 2), or of their kernel parts
        (:func:`body_spectra_parts`); None when rigid.
    w1, w2 : float or tuple of float
        Creep weights of the current traction increment for each body [1] (1 for elastic
        bodies), one per kernel part.
    conv : Convolver
        The convolution engine of the grid (it counts the FFT pairs).
    """

    def __init__(self, spectra1, spectra2, w1, w2, conv: Convolver):
        self.conv = conv
        self.w1, self.w2 = (float(w) if np.ndim(w) == 0 else tuple(float(x) for x in w)
                            for w in (w1, w2))
        s1, c1 = weighted_spectra(spectra1, self.w1)
        s2, c2 = weighted_spectra(spectra2, self.w2)
        self.rigid = s1 is None and s2 is None
        #: the pair's kernel spectra, key 'ij'; None for a rigid pair
        self.k: dict[str, np.ndarray] | None = (pair_kernels(s1, s2, c1, c2)
                                                 if not self.rigid else None)
        #: the cell sides (Δ1, Δ2) [m] where the spectra know them, else None
        self.cell = next((getattr(x, "cell", None) for x in (s1, s2) if x is not None), None)
        self._derived: dict = {}    # constants derived from the spectra, computed once

    def _kernels(self) -> dict[str, np.ndarray]:
        """The kernel spectra, which every piece below needs (a rigid pair has none)."""
        assert self.k is not None, "a rigid pair has no kernels"
        return self.k

    # -- the pieces the inner problems need -------------------------------------------
    def normal(self, p):
        """u3 [m] from the pressure p [Pa] (one FFT pair)."""
        return self.conv.convolve(self._kernels()["33"], p)

    def tangential_scalar(self, q1):
        """u1 [m] from q1 [Pa] (one FFT pair; the Cattaneo-Mindlin form, q2 = 0)."""
        return self.conv.convolve(self._kernels()["11"], q1)

    def tangential_vector(self, q):
        """(u1, u2) [m] from (q1, q2) [Pa] (two FFT pairs)."""
        k = self._kernels()
        return self.conv.convolve_matrix([[k["11"], k["12"]], [k["21"], k["22"]]], [q[0], q[1]])

    def tangential_blocks(self):
        """[K11 K12; K21 K22] as a :class:`~contactpipe.solver.blocks.BlockOperator`:
        applied whole, (u1, u2) [m] from (q1, q2) [Pa] as :meth:`tangential_vector`, or in
        its halves (the vector CG's steps)."""
        k = self._kernels()
        return BlockOperator(self.conv, [[k["11"], k["12"]], [k["21"], k["22"]]])

    def coupling_to_normal(self, q1, q2=None):
        """u3 [m] from the shear tractions (K31, K32)."""
        k = self._kernels()
        return self.conv.convolve_matrix([[k["31"], k["32"]]], [q1, q2])[0]

    def coupling_to_tangential(self, p, two_components=True):
        """(u1, u2) [m] (or u1 alone) from the pressure (K13, K23)."""
        k = self._kernels()
        rows = [[k["13"]], [k["23"]]] if two_components else [[k["13"]]]
        return self.conv.convolve_matrix(rows, [p])

    def in_plane(self, q1=None, q2=None, p=None):
        """(u1, u2) [m] from all tractions (2 inverse transforms)."""
        k = self._kernels()
        rows = [[k[f"{i}1"], k[f"{i}2"], k[f"{i}3"]] for i in (1, 2)]
        return self.conv.convolve_matrix(rows, [q1, q2, p])

    def self_influence(self, component="11"):
        """Displacement of a cell under its own unit traction, K_ij(0, 0) [m/Pa] (cached)."""
        key = ("self", component)
        if key not in self._derived:
            k = self._kernels()[component]
            m2 = self.conv.m2
            total = k[:, 0].sum() + 2.0 * k[:, 1:m2 // 2].sum() + k[:, m2 // 2].sum()
            self._derived[key] = float(np.real(total))
        return self._derived[key]

    def normal_norm(self):
        """Largest value of K33's padded spectrum, an upper bound of the normal operator's
        norm (the projected-gradient step; cached)."""
        if ("norm", 0) not in self._derived:
            m = self.conv.m1 * self.conv.m2
            self._derived[("norm", 0)] = float(np.max(np.real(self._kernels()["33"]))) * m
        return self._derived[("norm", 0)]

    def tangential_norm(self, components=2):
        """Largest eigenvalue of the tangential kernel block over the padded spectrum, an
        upper bound of the operator's norm (the projected-gradient step; cached)."""
        key = ("norm", components)
        if key not in self._derived:
            k = self._kernels()
            m = self.conv.m1 * self.conv.m2
            a = np.real(k["11"]) * m
            if components == 1:
                value = float(np.max(a))
            else:
                c, d = np.real(k["12"]) * m, np.real(k["22"]) * m
                value = float(np.max(0.5 * (a + d) + np.sqrt(0.25 * (a - d) ** 2 + c ** 2)))
            self._derived[key] = value
        return self._derived[key]

    def _root_laplacian(self):
        """The symbol of (−Δ)^½ on the n1 x n2 grid taken as periodic [1/m]
        (:func:`~contactpipe.solver.symbols.root_laplacian`; cached)."""
        if "root_laplacian" not in self._derived:
            self._derived["root_laplacian"] = root_laplacian(self.conv.n1, self.conv.n2,
                                                             self.cell)
        return self._derived["root_laplacian"]

    def corner(self, key):
        """K̂_key σ at the grid's Nyquist corner [1/Pa]: the padded spectrum there times
        σ_max (the self-influence times σ_max where that is not positive; cached). The
        scale of the model symbols (:mod:`~contactpipe.solver.symbols`)."""
        name = ("corner", key)
        if name not in self._derived:
            conv = self.conv
            k = self._kernels()[key]
            value = float(np.real(k[conv.m1 // 2, conv.m2 // 2])) * conv.m1 * conv.m2
            if not value > 0.0:
                value = self.self_influence(key)
            self._derived[name] = value * float(self._root_laplacian().max())
        return self._derived[name]

    def _radial(self):
        """The model symbols' radial profile g(σ) [1]
        (:func:`~contactpipe.solver.symbols.radial_profile`, from K33; cached)."""
        if "radial" not in self._derived:
            conv = self.conv
            step1, step2 = conv.m1 // conv.n1, conv.m2 // conv.n2
            sampled = self._kernels()["33"][::step1, ::step2] * (conv.m1 * conv.m2)
            self._derived["radial"] = radial_profile(sampled, self.corner("33"),
                                                     self._root_laplacian())
        return self._derived["radial"]

    def _inverse_model(self):
        """σ/g(σ) [1/m]: the inverse model symbols' common shape, before their scales
        (cached)."""
        if "inverse_model" not in self._derived:
            self._derived["inverse_model"] = self._root_laplacian() / self._radial()
        return self._derived["inverse_model"]

    def _plane(self):
        """The in-plane model (:func:`~contactpipe.solver.symbols.plane_model`; cached)."""
        if "plane" not in self._derived:
            conv = self.conv
            self._derived["plane"] = plane_model(self._kernels()["11"], self.corner("11"),
                                                 conv.n1, conv.n2, self.cell,
                                                 periodic=conv.periodic)
        return self._derived["plane"]

    def normal_preconditioner(self):
        """``M(v)``: v filtered by σ/g(σ), the inverse of the normal block's model symbol
        (:mod:`~contactpipe.solver.symbols`; its scale does not matter to CG), on the
        n1 x n2 grid itself taken as periodic (a quarter of an FFT pair per field,
        :meth:`Convolver.periodic_filter`): an approximation of the normal operator's
        inverse (K33 behaves as 1/|ξ|) for preconditioned CG. ``v`` may be one field or
        a stack of them.

        σ is the discrete (−Δ)^½ (zero mode set to the smallest other value: M is then
        symmetric positive definite) and g its radial correction, read from the grid's
        own K33 spectrum (with it the bench's Hertz solve takes fewer iterations on every
        grid: docs/design-choices.md, D4). Not the inverse of
        the padded K33 circulant itself: with rectangular cells that circulant has
        negative modes, and even clipped to positive it made a worse preconditioner; and
        not on the padded grid, which cost four times the work for the same iterations
        (docs/design-choices.md). Cells of unknown sides are taken square.
        """
        if "precondition33" not in self._derived:     # the symbol, scaled by 1/(n1 n2)
            sigma = self._inverse_model()
            self._derived["precondition33"] = sigma / (sigma.max()
                                                       * self.conv.n1 * self.conv.n2)
        sigma = self._derived["precondition33"]
        return lambda v, out=None: self.conv.periodic_filter(sigma, v, out=out)

    def joint_preconditioner(self):
        """``M(v)``: (p, q1) stacked [m] filtered by the inverses of the model symbols of
        K33 and K11 at their own scales [Pa/m], σ/(c33 g) and σ/(λ_F g (1 − ν_e ξ̂1²))
        (:mod:`~contactpipe.solver.symbols`): the scalar joint solve's block-diagonal
        preconditioner (half an FFT pair). The shear's filter is anisotropic: K11 is
        1/(1 − ν_e) times stiffer for modes varying along x2 than along x1, which the
        isotropic (−Δ)^½ filter shared with the pressure left to the iterations (fewer
        iterations a step of steel-on-aluminium fretting: docs/design-choices.md, D4).
        The coupling blocks K13, K31 are left out (in the filter they cost iterations:
        docs/design-choices.md)."""
        return self.joint_filter()

    def joint_filter(self, shear=1.0):
        """:meth:`joint_preconditioner` with its shear block's filter times ``shear`` [1]
        (the joint solve's s = q/μ takes 1/μ²: folded into the symbol, no pass of its
        own)."""
        symbol = self._joint_symbols()
        if shear != 1.0:
            symbol = np.stack([symbol[0], symbol[1] * shear])
        return lambda v, out=None: self.conv.periodic_filter(symbol, v, out=out)

    def shear_preconditioner(self):
        """``M(v)``: q1 [m] filtered by the inverse of K11's model symbol (the shear block of
        :meth:`joint_preconditioner`): the scalar tangential CG's preconditioner (a
        quarter of an FFT pair)."""
        symbol = self._joint_symbols()[1]
        return lambda v, out=None: self.conv.periodic_filter(symbol, v, out=out)

    def _joint_symbols(self):
        """The symbols of :meth:`joint_preconditioner` (2, n1, n2//2 + 1) [Pa/m], scaled
        for the inverse FFT (cached)."""
        if "precondition_j" not in self._derived:
            sigma = self._inverse_model()
            plane = self._plane()
            scale = 1.0 / (self.conv.n1 * self.conv.n2)
            self._derived["precondition_j"] = np.stack([
                sigma * (scale / self.corner("33")),
                sigma * (scale / plane.lam) / plane.along((1.0, 0.0))])
        return self._derived["precondition_j"]

    def tangential_preconditioner(self):
        """``M(v, d, axis=e)``: v [m] (in-plane fields) filtered by the symbol
        1/(K̂ + d) [Pa/m], an approximation of (K_ee + d)⁻¹ on the n1 x n2 grid taken as
        periodic (a quarter of an FFT pair per field, as :meth:`normal_preconditioner`).

        K̂ = λ_F (1 − ν_e (ξ̂·e)²)/σ is the model of the block along the unit in-plane
        vector ``e`` (:mod:`~contactpipe.solver.symbols`; one per stacked field, (k, 2),
        or one for all, (2,)); without ``axis`` K̂ = λ/σ, the isotropic model matched to
        the block's finest mode (the padded K11 spectrum at the grid's Nyquist corner,
        where K11 = K22 and K12 vanishes on square cells), as the pressure block of the
        joint vector solve uses it. d [m/Pa] ≥ 0 is a uniform shift of the diagonal: the
        curvature of the slip cells' circles in the vector CG
        (:func:`contactpipe.solver.disk_cg.direction`), which there outweighs the
        self-influence 2-10 times and makes the plain (−Δ)^½ filter useless. ``d`` is one
        number, or one per stacked field of ``v`` (the CG shifts the component along the
        turning cells' tangents, not the one across them). The radial profile g of the
        other filters is left out here: in the vector CG it measured no gain
        (docs/design-choices.md).

        ``M(v, d, band="high")`` and ``M(v, d, band="low")`` split the unshifted filter
        1/K̂ into two bands, K̂_f = λ/σ_max the finest-mode value (``M.finest`` [m/Pa]):

            high: (K̂_f + d) / (K̂ (K̂ + d)),    low: max(K̂ − K̂_f, 0) / (K̂ (K̂ + d)),

        both ≥ 0 and summing to 1/K̂ (where K̂ ≥ K̂_f); the high band is the shifted filter
        at the finest mode and falls off where K̂ outgrows d. The vector CG scales each
        band by the cells' own diagonal at its stiffness
        (:func:`contactpipe.solver.disk_cg.direction`), so that a stick cell keeps the
        plain filter at every frequency while a turning cell is shifted by its own
        curvature where the curvature counts.
        """
        sigma = self._root_laplacian()
        lam, plane = self.corner("11"), self._plane()
        scale = 1.0 / (self.conv.n1 * self.conv.n2)
        finest = lam / float(sigma.max())

        def apply(v, d=0.0, out=None, band=None, axis=None):
            d = np.asarray(d, dtype=float)
            if d.ndim:                      # one shift per stacked field
                d = d.reshape(d.shape + (1, 1))
            L = lam if axis is None else plane.lam * plane.along(axis)
            if band is None:                # σ / (L + d σ)
                symbol = sigma * (scale / (L + d * sigma))
            elif band == "high":            # (K̂_f + d) σ² / (L (L + d σ))
                symbol = (finest + d) * sigma * sigma * (scale / (L * (L + d * sigma)))
            elif band == "low":             # σ (L − K̂_f σ)⁺ / (L (L + d σ))
                symbol = (sigma * np.maximum(L - finest * sigma, 0.0)
                          * (scale / (L * (L + d * sigma))))
            else:
                raise ValueError(f"band must be None, 'high' or 'low', not {band!r}")
            return self.conv.periodic_filter(symbol, v, out=out)
        apply.finest = finest  # type: ignore[attr-defined]  # a function attribute
        return apply

    def coarse_normal(self):
        """The normal operator on the grid coarsened by two in each direction (cached), or
        None where a side is odd.

        Galerkin coarsening: a coarse cell carries a uniform pressure over its 2 x 2 fine
        cells and its displacement is their mean, so the coarse kernel is
        K_c(D) = Σ_e w_e K(2D + e), e in {-1, 0, 1}², w_e = (2 - |e1|)(2 - |e2|)/4, read
        from the fine kernel (one inverse real FFT of its spectrum, once per operator: set-up
        work, like the kernel spectra, not counted in FFT pairs). Only ``normal`` (K33) is
        available on the result; its FFT pairs are counted by the coarse grid's own
        :func:`convolver`.
        """
        if "coarse" not in self._derived:
            self._derived["coarse"] = self._coarsened()
        return self._derived["coarse"]

    def _coarsened(self):
        conv = self.conv
        if conv.n1 % 2 or conv.n2 % 2:
            return None
        c1, c2 = conv.n1 // 2, conv.n2 // 2
        fine = self._in_space("33")
        if conv.periodic:           # every offset of the coarse period, taken mod the fine
            d1, d2 = np.arange(c1), np.arange(c2)
        else:
            d1, d2 = np.arange(-(c1 - 1), c1), np.arange(-(c2 - 1), c2)
        acc = np.zeros((d1.size, d2.size))
        for e1 in (-1, 0, 1):
            for e2 in (-1, 0, 1):
                w = (2 - abs(e1)) * (2 - abs(e2)) / 4.0
                acc += w * fine[np.ix_((2 * d1 + e1) % conv.m1, (2 * d2 + e2) % conv.m2)]
        pad = 1 if conv.periodic else 2
        kernel = np.zeros((pad * c1, pad * c2))
        kernel[np.ix_(d1 % (pad * c1), d2 % (pad * c2))] = acc
        # FFTW_ESTIMATE: a coarse grid serves a few dozen transforms of a cold start;
        # measured plans cost more to make than they saved (docs/design-choices.md, D5)
        coarse = self._derived_on(convolver(c1, c2, conv.backend, conv.threads,
                                            "FFTW_ESTIMATE", conv.periodic),
                                  None if self.cell is None else
                                  (2.0 * self.cell[0], 2.0 * self.cell[1]))
        coarse.k = {"33": coarse.conv.kernel_spectrum(kernel)}
        return coarse

    def _derived_on(self, conv, cell):
        """An operator of another grid (``conv``, cells ``cell``) with this one's creep
        weights; its kernels ``k`` are the caller's to set."""
        sub = object.__new__(ContactOperator)
        sub.conv, sub.cell, sub.w1, sub.w2, sub.rigid = conv, cell, self.w1, self.w2, self.rigid
        sub._derived, sub.k = {}, None
        return sub

    def _in_space(self, key):
        """Kernel ``key`` on the padded grid in real space (one inverse real FFT of its
        spectrum, set-up work not counted in FFT pairs; kept until :meth:`drop_windows`)."""
        kept = self._derived.setdefault(("kernels",), {})
        if key not in kept:
            conv = self.conv
            kept[key] = scipy.fft.irfft2(self._kernels()[key] * (conv.m1 * conv.m2),
                                         s=(conv.m1, conv.m2))
        return kept[key]

    def window(self, c1, c2):
        """The operator of a c1 x c2 block of this grid's cells: the same influence
        coefficients (offsets up to c − 1 cells, read from this operator's kernels),
        applied by DC-FFT on the block padded to 2 c1 x 2 c2, with its own
        :class:`Convolver` (which counts its FFT pairs). Tractions confined to the block
        give there the displacements this operator gives, to rounding.

        The last window made is kept (a new size replaces it), and so are this grid's
        kernels in real space (nine inverse transforms, set-up work not counted in FFT
        pairs), until :meth:`drop_windows`."""
        key = ("window", int(c1), int(c2))
        if key not in self._derived:
            self.drop_windows(kernels=False)
            self._derived[key] = self._windowed(int(c1), int(c2))
        return self._derived[key]

    def drop_windows(self, kernels=True) -> None:
        """Free the window :meth:`window` made and (``kernels``) the real-space kernels
        it came from."""
        names = ("window", "kernels") if kernels else ("window",)
        for key in [k for k in self._derived if isinstance(k, tuple) and k[0] in names]:
            del self._derived[key]

    def _windowed(self, c1, c2):
        conv = self.conv
        if not (0 < c1 <= conv.n1 and 0 < c2 <= conv.n2):
            raise ValueError(f"a window of {c1} x {c2} cells on a {conv.n1} x {conv.n2} grid")
        # FFTW_ESTIMATE: a run meets many window sizes; measured plans made paper fig. 3
        # slower without wisdom, and no faster with it (docs/design-choices.md, D8)
        sub = self._derived_on(Convolver(c1, c2, backend=conv.backend, threads=conv.threads,
                                         planner="FFTW_ESTIMATE"), self.cell)
        if self.rigid:
            return sub
        d1, d2 = np.arange(-(c1 - 1), c1), np.arange(-(c2 - 1), c2)
        take = np.ix_(d1 % conv.m1, d2 % conv.m2)
        put = np.ix_(d1 % (2 * c1), d2 % (2 * c2))
        sub.k = {}
        for key in self._kernels():
            kernel = np.zeros((2 * c1, 2 * c2))
            kernel[put] = self._in_space(key)[take]
            sub.k[key] = sub.conv.kernel_spectrum(kernel)
        return sub

    def full(self, p, q1=None, q2=None):
        """(u1, u2, u3) [m] from all tractions (3 forward, 3 inverse transforms at most)."""
        k = self._kernels()
        rows = [[k[f"{i}1"], k[f"{i}2"], k[f"{i}3"]] for i in (1, 2, 3)]
        return self.conv.convolve_matrix(rows, [q1, q2, p])


def history_kernels(spectra1, spectra2):
    """Each body's kernel spectra with the signs of eq. (8) (body 1: coupling negative), for
    :func:`history_displacement`; built once per run. None for a body without spectra; a
    list (one per part) for a body given by its kernel parts (:func:`body_spectra_parts`)
    with more than one."""
    out: list = []
    for first, spectra in ((True, spectra1), (False, spectra2)):
        if spectra is None:
            out.append(None)
            continue
        parts = (spectra,) if isinstance(spectra, BodySpectra) else tuple(spectra)
        signed = [pair_kernels(p, None) if first else pair_kernels(None, p) for p in parts]
        out.append(signed[0] if len(signed) == 1 else signed)
    return tuple(out)


def history_displacement(kernels, h1, h2, conv: Convolver, outputs=(1, 2, 3)):
    """Known displacement from the bodies' Boltzmann history tractions (weights already in).

    Parameters
    ----------
    kernels : tuple
        (body 1, body 2) signed kernel spectra from :func:`history_kernels`; an entry may be
        None (rigid, or no history), or a list of parts.
    h1, h2 : sequence of 3 arrays, a list of them (one per kernel part), or None
        History tractions [Pa] for (q1, q2, p) of each body (of each part); an entry may be
        None (zero).
    outputs : tuple of int
        Which displacement components to return (1, 2, 3).

    Returns
    -------
    ndarray (len(outputs), n1, n2)
        Relative displacement [m] with the signs of eq. (8). One forward transform per
        non-zero history component and one inverse per output and body, whatever the
        number of parts.
    """
    out = np.zeros((len(outputs), conv.n1, conv.n2))
    for k, h in zip(kernels, (h1, h2), strict=True):
        if k is None or h is None:
            continue
        parts = k if isinstance(k, list) else [k]
        hs = h if isinstance(k, list) else [h]
        rows = [[p[f"{i}{j}"] for p in parts for j in (1, 2, 3)] for i in outputs]
        xs = [None if (hj is None or not np.any(hj)) else hj for hp in hs for hj in hp]
        out += conv.convolve_matrix(rows, xs)
    return out
