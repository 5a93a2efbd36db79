"""DC-FFT: linear (non-periodic) convolution of cell tractions with influence kernels.

Liu, Wang & Liu (2000), "A versatile method of discrete convolution and FFT (DC-FFT) for
contact analyses", Wear 243, 101-111. The N1 x N2 traction field is zero-padded to
M1 x M2 = 2N1 x 2N2; kernels are laid out in wrap-around order on that padded grid
(:func:`contactpipe.solver.influence.body_kernels`) and their real-FFT spectra are computed
once per grid and material pair and reused by every iteration and time step.

The cost unit reported everywhere in contactpipe is one *FFT pair*: one forward plus one
inverse real FFT of the padded grid. :class:`Convolver` counts them.

pyFFTW with plans made once per padded shape is the main path; ``scipy.fft`` is the
fallback and gives the same results to rounding. The 1/(M1 M2) normalisation of the
inverse transform is folded into the kernel spectra, so no extra pass is spent on it.
"""
from __future__ import annotations

import contextlib
import sys
import threading

import numpy as np
import scipy.fft


@contextlib.contextmanager
def _sparing_dask_array():
    """Inside the block, ``import dask.array.fft`` fails: around the one import of pyfftw.

    ``import pyfftw`` imports ``pyfftw.interfaces``, which offers its dask interface when
    ``from dask.array.fft import fft_wrap`` succeeds, and so imported dask and dask.array
    (0.28-0.45 s) with the solver. contactpipe calls only ``pyfftw.FFTW``,
    ``pyfftw.zeros_aligned`` and the wisdom functions. A name mapped to None in
    ``sys.modules`` makes its import raise ImportError before any parent package is
    imported; pyfftw catches it and skips that interface (pyfftw itself is not patched).
    The entry is taken out again if it is still ours, so a later ``import dask.array.fft``
    works. pyfftw's import took 0.29 s, 0.007 s so; ``import contactpipe.simulation``
    1.00 s, 0.77 s so (2 cores, median of 5 fresh processes). xarray still imports
    dask.array the first time it wraps an array, so a run that builds its results loads it
    then; a process that only solves does not.

    scipy.fftpack, which pyfftw.interfaces imports too, is left alone: the solver uses
    scipy.fft (kernel spectra, the scipy backend), after which scipy.fftpack costs about
    1 ms, and hiding it would also drop pyfftw's scipy interfaces.
    """
    name = "dask.array.fft"
    ours = name not in sys.modules      # already imported: nothing to spare
    if ours:
        sys.modules[name] = None        # type: ignore[assignment]  # the import system's "absent"
    try:
        yield
    finally:
        if ours and name in sys.modules and sys.modules[name] is None:
            del sys.modules[name]


try:  # pragma: no cover - exercised when pyfftw is installed
    with _sparing_dask_array():
        import pyfftw

    from . import wisdom
    HAVE_PYFFTW = True
except ImportError:  # pragma: no cover
    pyfftw = wisdom = None  # type: ignore[assignment]  # optional modules, absent
    HAVE_PYFFTW = False

__all__ = ["Convolver", "HAVE_PYFFTW"]

_PLAN_LOCK = threading.Lock()


class Convolver:
    """Linear convolution on an ``n1 x n2`` grid by DC-FFT on a ``2n1 x 2n2`` padded grid
    (or, ``periodic``, circular convolution on the grid itself).

    Parameters
    ----------
    n1, n2 : int
        Cells along x1 and x2.
    backend : {"auto", "pyfftw", "scipy"}
        FFT library; "auto" takes pyFFTW when installed.
    threads : int
        Threads given to the FFT library.
    periodic : bool
        The grid is one period of an infinite surface: a circular convolution on the grid
        itself, not padded (the kernel spectra then come from
        :mod:`~contactpipe.solver.periodic`; the same pruned plans serve, with nothing
        pruned).
    planner : str
        pyFFTW planner effort ("FFTW_ESTIMATE", "FFTW_MEASURE", ...). Planning happens once,
        here, and its time is recorded in :attr:`plan_time_s`. Measured plans start from,
        and add to, the wisdom that earlier processes kept (:mod:`.wisdom`).

    Attributes
    ----------
    forward_count, inverse_count : int
        Transforms executed since construction (or :meth:`reset_counts`).
    charged : float
        Work done on other (coarser) grids for this one, in this grid's FFT pairs
        (:meth:`charge`); part of :attr:`pairs`.
    filtered : int
        Fields filtered on the unpadded grid (:meth:`periodic_filter`), a quarter of an FFT
        pair each in :attr:`pairs`.
    """

    def __init__(self, n1: int, n2: int, backend: str = "auto", threads: int = 1,
                 planner: str = "FFTW_MEASURE", periodic: bool = False):
        import time
        self.n1, self.n2 = int(n1), int(n2)
        self.periodic = bool(periodic)
        pad = 1 if self.periodic else 2
        self.m1, self.m2 = pad * self.n1, pad * self.n2
        self.spec_shape = (self.m1, self.m2 // 2 + 1)
        if backend == "auto":
            backend = "pyfftw" if HAVE_PYFFTW else "scipy"
        if backend == "pyfftw" and not HAVE_PYFFTW:
            raise ImportError("backend 'pyfftw' asked for but pyfftw is not installed; "
                              "use backend='scipy'")
        if backend not in ("pyfftw", "scipy"):
            raise ValueError(f"backend {backend!r}: allowed 'auto', 'pyfftw', 'scipy'")
        self.backend = backend
        self.threads = max(1, int(threads))
        self.forward_count = 0
        self.inverse_count = 0
        self.charged = 0.0
        self.filtered = 0
        t0 = time.perf_counter()
        if backend == "pyfftw":
            self._plan_pruned(planner)
        else:
            self._rin = np.zeros((self.m1, self.m2))
        self.plan_time_s = time.perf_counter() - t0
        self._tmp = np.zeros(self.spec_shape, dtype=complex)
        self._periodic: dict[tuple, tuple] = {}

    def _plan_pruned(self, planner):
        """The padded grid's transforms, pruned of the padding's zeros.

        Only the top n1 rows of the padded field are non-zero, and only the top-left
        n1 x n2 block of a convolution is kept: the forward transform runs along x2 on the
        n1 field rows alone (the padded half of each row is zero), then along x1 over the
        whole column; the inverse runs along x1 over the whole column, then along x2 on
        the n1 rows that are kept. Each transform so skips half of one of its two passes:
        a pair costs about a fifth less than the unpruned 2D plan's, to rounding the same
        result (docs/design-choices.md, D6).
        """
        n1, m2 = self.n1, self.m2
        self._planner = planner
        self._rin = pyfftw.zeros_aligned((n1, m2), dtype="float64")
        self._cin = pyfftw.zeros_aligned(self.spec_shape, dtype="complex128")
        self._rout = pyfftw.zeros_aligned((n1, m2), dtype="float64")
        kw = dict(threads=self.threads)
        self._slots = []
        measured = planner != "FFTW_ESTIMATE"
        if measured:
            with _PLAN_LOCK:
                wisdom.load()      # the plans measured by an earlier process
        self._forward_slot(0)
        with _PLAN_LOCK:
            self._inv_cols = pyfftw.FFTW(self._cin, self._cin, axes=(0,),
                                         direction="FFTW_BACKWARD", flags=(planner,), **kw)
            self._inv_rows = pyfftw.FFTW(self._cin[:n1], self._rout, axes=(1,),
                                         direction="FFTW_BACKWARD",
                                         flags=(planner, "FFTW_DESTROY_INPUT"), **kw)
            if measured:
                wisdom.save()

    def _forward_slot(self, n):
        """The n-th forward spectrum buffer and its two plans (made when first asked
        for; the plans after the first come from FFTW's wisdom): a block product keeps
        each input's spectrum in its own buffer and copies none (the copy was a
        measurable share of a 2 x 2 product: docs/design-choices.md, D6)."""
        while len(self._slots) <= n:
            cout = pyfftw.zeros_aligned(self.spec_shape, dtype="complex128")
            kw = dict(threads=self.threads, flags=(self._planner,))
            with _PLAN_LOCK:
                rows = pyfftw.FFTW(self._rin, cout[:self.n1], axes=(1,),
                                   direction="FFTW_FORWARD", **kw)
                cols = pyfftw.FFTW(cout, cout, axes=(0,), direction="FFTW_FORWARD", **kw)
            self._slots.append((cout, rows, cols))
        return self._slots[n]

    def _execute_forward(self, x, slot=0):
        """The spectrum of the zero-padded x, left in (and returned as) the buffer of
        forward slot ``slot`` (pyFFTW)."""
        cout, rows, cols = self._forward_slot(slot)
        self._rin[:, :self.n2] = x              # the row's padded half stays zero
        rows.execute()
        cout[self.n1:] = 0.0                    # the padded rows' spectra
        cols.execute()
        return cout

    def _execute_inverse(self):
        """The inverse transform of ``self._cin``; its kept block is
        ``self._rout[:, :n2]`` (pyFFTW)."""
        self._inv_cols.execute()
        self._inv_rows.execute()

    # -- counting -------------------------------------------------------------------
    @property
    def pairs(self) -> float:
        """FFT pairs spent: (forward + inverse transforms) / 2, plus the work charged to
        this grid (:meth:`charge`) and a quarter per field filtered on the unpadded grid."""
        return (0.5 * (self.forward_count + self.inverse_count) + self.charged
                + 0.25 * self.filtered)

    def charge(self, pairs: float) -> None:
        """Count work done elsewhere for this grid (a coarse-grid start), already
        converted to this grid's FFT pairs [1]."""
        self.charged += float(pairs)

    def reset_counts(self) -> None:
        self.forward_count = 0
        self.inverse_count = 0
        self.charged = 0.0
        self.filtered = 0

    # -- transforms -----------------------------------------------------------------
    def periodic_filter(self, sigma: np.ndarray, v: np.ndarray, out=None) -> np.ndarray:
        """``v`` (n1 x n2, or a stack of such fields) filtered by the spectrum ``sigma``
        (real-FFT layout of the n1 x n2 grid, scaled by 1/(n1 n2) like the kernel spectra)
        on the grid itself, periodic, not padded.

        A preconditioner's work, not a convolution: the transforms are a quarter of the
        padded grid's size, so each field filtered counts a quarter of an FFT pair in
        :attr:`pairs` (by operation count, N log N, it is a little less).
        """
        v = np.asarray(v, dtype=float)
        self.filtered += v.size // (self.n1 * self.n2)
        if self.backend != "pyfftw":
            spec = scipy.fft.rfft2(v, workers=self.threads)
            spec *= sigma
            res = scipy.fft.irfft2(spec, s=(self.n1, self.n2), norm="forward",
                                   workers=self.threads)
            if out is None:
                return res
            out[...] = res
            return out
        fwd, inv = self._periodic_plans(v.shape)
        fwd.input_array[...] = v
        fwd.execute()
        np.multiply(fwd.output_array, sigma, out=inv.input_array)
        inv.execute()
        if out is None:
            return inv.output_array.copy()
        out[...] = inv.output_array
        return out

    def _periodic_plans(self, shape):
        """Plans of the unpadded filter, made with FFTW_ESTIMATE whatever the planner:
        measured plans ran no faster here and cost a noticeable fraction of a second
        each to make, for each grid of a multilevel solve (docs/design-choices.md, D4)."""
        if shape not in self._periodic:
            spec = shape[:-1] + (self.n2 // 2 + 1,)
            with _PLAN_LOCK:
                rin = pyfftw.zeros_aligned(shape, dtype="float64")
                cout = pyfftw.zeros_aligned(spec, dtype="complex128")
                cin = pyfftw.zeros_aligned(spec, dtype="complex128")
                rout = pyfftw.zeros_aligned(shape, dtype="float64")
                fwd = pyfftw.FFTW(rin, cout, axes=(-2, -1), direction="FFTW_FORWARD",
                                  flags=("FFTW_ESTIMATE",), threads=self.threads)
                inv = pyfftw.FFTW(cin, rout, axes=(-2, -1), direction="FFTW_BACKWARD",
                                  flags=("FFTW_ESTIMATE", "FFTW_DESTROY_INPUT"),
                                  threads=self.threads)
            self._periodic[shape] = (fwd, inv)
        return self._periodic[shape]

    def kernel_spectrum(self, kernel: np.ndarray) -> np.ndarray:
        """Spectrum of a wrap-around kernel (2n1 x 2n2), scaled by 1/(M1 M2).

        Not counted as solver work: spectra are computed once per grid and material.
        """
        kernel = np.asarray(kernel, dtype=float)
        if kernel.shape != (self.m1, self.m2):
            raise ValueError(f"kernel shape {kernel.shape}, expected {(self.m1, self.m2)}")
        return scipy.fft.rfft2(kernel, workers=self.threads) / (self.m1 * self.m2)

    def forward(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Spectrum of the zero-padded field ``x`` (n1 x n2). Returns a new array or ``out``."""
        self.forward_count += 1
        if self.backend == "pyfftw":
            spec = self._execute_forward(x)
            if out is None:
                return spec.copy()
            out[...] = spec
            return out
        self._rin[:self.n1, :self.n2] = x
        spec = scipy.fft.rfft2(self._rin, workers=self.threads)
        if out is None:
            return spec
        out[...] = spec
        return out

    def inverse(self, spec: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The n1 x n2 block of the (unnormalised) inverse transform of ``spec``.

        ``spec`` is a product with a scaled kernel spectrum, so the result is the linear
        convolution itself.
        """
        self.inverse_count += 1
        if self.backend == "pyfftw":
            self._cin[...] = spec
            self._execute_inverse()
            block = self._rout[:, :self.n2]
        else:
            block = scipy.fft.irfft2(spec, s=(self.m1, self.m2), norm="forward",
                                     workers=self.threads)[:self.n1, :self.n2]
        if out is None:
            return block.copy()
        out[...] = block
        return out

    def forward_slot(self, x: np.ndarray, slot: int = 0) -> np.ndarray:
        """Spectrum of the zero-padded field ``x``, left in the engine's forward buffer
        ``slot`` (pyFFTW; scipy: a new array): no copy, and overwritten by the next
        forward transform into that slot."""
        if self.backend == "pyfftw":
            self.forward_count += 1
            return self._execute_forward(x, slot)
        return self.forward(x)

    def inverse_add(self, spec: np.ndarray, factor: float, extra, out: np.ndarray):
        """``out`` += the n1 x n2 block of the inverse transform of factor x ``spec``
        (+ ``extra``, a spectrum, where not None): the sum is formed in the inverse
        plan's input, so nothing is copied (one inverse transform)."""
        self.inverse_count += 1
        if self.backend == "pyfftw":
            np.multiply(spec, factor, out=self._cin)
            if extra is not None:
                self._cin += extra
            self._execute_inverse()
            out += self._rout[:, :self.n2]
            return out
        full = spec * factor if extra is None else spec * factor + extra
        out += scipy.fft.irfft2(full, s=(self.m1, self.m2), norm="forward",
                                workers=self.threads)[:self.n1, :self.n2]
        return out

    def convolve(self, khat: np.ndarray, x: np.ndarray, out: np.ndarray | None = None):
        """K ⊛ x for one kernel spectrum (one FFT pair)."""
        if self.backend == "pyfftw":      # no intermediate copies on the main path
            self.forward_count += 1
            self.inverse_count += 1
            np.multiply(self._execute_forward(x), khat, out=self._cin)
            self._execute_inverse()
            block = self._rout[:, :self.n2]
            if out is None:
                return block.copy()
            out[...] = block
            return out
        spec = self.forward(x, out=self._tmp)
        np.multiply(spec, khat, out=spec)
        return self.inverse(spec, out=out)

    def convolve_matrix(self, khat, xs, out=None):
        """u_i = Σ_j K_ij ⊛ x_j for a block of kernels.

        Parameters
        ----------
        khat : sequence of sequences of spectra or None
            ``khat[i][j]`` is the spectrum of K_ij, or None where it vanishes.
        xs : sequence of arrays (n1 x n2) or None
            Input fields; None means zero (no transform spent).

        Costs one forward transform per non-zero input and one inverse per output that
        receives anything.
        """
        if self.backend == "pyfftw":
            return self._convolve_matrix_fftw(khat, xs, out)
        nin = len(xs)
        specs = [None if (x is None) else self.forward(x) for x in xs]
        nout = len(khat)
        if out is None:
            out = np.zeros((nout, self.n1, self.n2))
        acc = np.empty(self.spec_shape, dtype=complex)
        for i in range(nout):
            have = False
            for j in range(nin):
                k, spec = khat[i][j], specs[j]
                if k is None or spec is None:
                    continue
                if not have:
                    np.multiply(k, spec, out=acc)
                    have = True
                else:
                    np.multiply(k, spec, out=self._tmp)
                    acc += self._tmp
            if have:
                self.inverse(acc, out=out[i])
            else:
                out[i] = 0.0
        return out

    def _convolve_matrix_fftw(self, khat, xs, out):
        """:meth:`convolve_matrix` on pyFFTW's buffers: each input's spectrum stays in its
        own forward buffer (:meth:`_forward_slot`), and each output's sum of products is
        formed in the inverse plan's input, so no spectrum is copied."""
        specs: list[np.ndarray | None] = [None] * len(xs)
        n = 0
        for j, x in enumerate(xs):
            if x is not None:
                self.forward_count += 1
                specs[j] = self._execute_forward(x, n)
                n += 1
        if out is None:
            out = np.zeros((len(khat), self.n1, self.n2))
        for i, row in enumerate(khat):
            terms = [(k, spec) for j, k in enumerate(row)
                     if k is not None and (spec := specs[j]) is not None]
            if not terms:
                out[i] = 0.0
                continue
            np.multiply(terms[0][0], terms[0][1], out=self._cin)
            for k, spec in terms[1:]:
                np.multiply(k, spec, out=self._tmp)
                self._cin += self._tmp
            self.inverse_count += 1
            self._execute_inverse()
            out[i] = self._rout[:, :self.n2]
        return out
