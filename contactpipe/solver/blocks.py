"""A block of influence kernels applied whole, or in its two halves: the inputs' spectra
(forward transforms), then the outputs (inverse transforms) of any sum of spectra.

A projected CG step x → P(x − τ t) changes A x by A(P(x − τ t) − x) = −τ A t + A d, d
the projection's correction. Applied whole, that costs one product for t (its curvature
tᵀA t sets τ) and a second for d. In halves, tᵀA t comes from t's spectra by Parseval's
theorem (:meth:`BlockOperator.inner`) and A x takes the step's and the correction's
spectra summed through one set of inverse transforms: the correction costs one forward
transform per moved field and no inverse.
The CG's next start (the next coupling pass's, or the instant's final state) is folded
into the last step the same way (:func:`contactpipe.solver.disk_cg.disk_cg`,
``follow``).

The DC-FFT layout (:mod:`.convolution`): a field is zero-padded to the 2N1 x 2N2 grid and
its convolution is the N1 x N2 block of the padded circular one. A zero-padded x has
xᵀ(K ⊛ y) over the block = the sum over the padded grid = Σ_k conj(x̂_k) K̂_k ŷ_k, the
kernel spectra carrying the inverse transform's 1/(M1 M2); over the real FFT's half
spectrum the columns 1 … M2/2 − 1 count twice.
"""
from __future__ import annotations

import numpy as np

from .convolution import Convolver

__all__ = ["BlockOperator", "DirectOperator"]


class BlockOperator:
    """u_i = Σ_j K_ij ⊛ x_j for a fixed block of kernel spectra on one grid.

    Parameters
    ----------
    conv : Convolver
        The grid's DC-FFT engine (it counts the transforms).
    khat : sequence of sequences of spectra or None
        ``khat[i][j]`` the scaled spectrum of K_ij (:meth:`Convolver.kernel_spectrum`),
        None where the block vanishes. Square: the CGs' operators map x's shape to itself.
    """

    def __init__(self, conv: Convolver, khat):
        self.conv = conv
        self.khat = [list(row) for row in khat]
        self.n = len(self.khat)
        self._tmp: np.ndarray | None = None

    def __call__(self, x, out=None):
        """A x [m] (x stacked (n, N1, N2)); a zero block costs no forward transform."""
        return self.conv.convolve_matrix(self.khat, [f if f.any() else None for f in x],
                                         out=out)

    def spectra(self, x):
        """The zero-padded fields' spectra, None for a zero field (no transform spent).
        They lie in the engine's forward buffers: valid until the next call."""
        out: list[np.ndarray | None] = []
        n = 0
        for f in x:
            if f.any():
                out.append(self.conv.forward_slot(f, n))
                n += 1
            else:
                out.append(None)
        return out

    def product(self, xhat, out=None):
        """Σ_j K̂_ij x̂_j per output i (n, M1, M2/2 + 1), complex; zero rows where no
        input reaches them. ``out`` (of that shape) is overwritten and returned."""
        if out is None:
            out = np.empty((self.n,) + self.conv.spec_shape, dtype=complex)
        if self._tmp is None:
            self._tmp = np.empty(self.conv.spec_shape, dtype=complex)
        tmp = self._tmp
        for i, row in enumerate(self.khat):
            have = False
            for k, s in zip(row, xhat, strict=True):
                if k is None or s is None:
                    continue
                if not have:
                    np.multiply(k, s, out=out[i])
                    have = True
                else:
                    out[i] += np.multiply(k, s, out=tmp)
            if not have:
                out[i] = 0.0
        return out

    def inner(self, xhat, rhat) -> float:
        """Σ_i x_iᵀ r_i over the N1 x N2 block [m·unit of x], x_i the zero-padded field
        of the spectrum ``xhat[i]`` and r_i the convolution of spectrum ``rhat[i]``
        (Parseval's theorem on the padded grid; no transform): with rhat =
        :meth:`product` (xhat), xᵀ A x."""
        total = 0.0
        last = self.conv.m2 // 2
        for s, r in zip(xhat, rhat, strict=True):
            if s is None:
                continue
            total += 2.0 * _real_dot(s, r) - _real_dot(s[:, 0], r[:, 0]) \
                - _real_dot(s[:, last], r[:, last])
        return float(total)

    def add(self, Ax, rhat, factor=1.0, extra=None):
        """Ax += the convolutions of factor x ``rhat`` (+ ``extra``, spectra of the same
        shape, where not None), in place [m]: one inverse transform per output."""
        for i in range(self.n):
            self.conv.inverse_add(rhat[i], factor, None if extra is None else extra[i],
                                  Ax[i])
        return Ax


def _real_dot(a, b) -> float:
    """Re Σ conj(a) b of two complex arrays, as Σ (a_re b_re + a_im b_im) over their
    float views, without BLAS (OpenBLAS threads long dot products:
    :func:`contactpipe.solver.ledger.dot`)."""
    a = np.ascontiguousarray(a).view(np.float64)
    b = np.ascontiguousarray(b).view(np.float64)
    return float(np.einsum("i,i->", a.ravel(), b.ravel()))


class DirectOperator:
    """:class:`BlockOperator`'s interface for an operator given only as its product
    x ↦ A x (a dense matrix, an operator without kernel spectra): its "spectra" are the
    fields themselves and its product the whole application, so a correction folded into
    a step costs a whole product, as it would applied alone."""

    def __init__(self, apply):
        self.apply = apply

    def __call__(self, x, out=None):
        return self.apply(x)

    def spectra(self, x):
        return x

    def product(self, xhat, out=None):
        return self.apply(xhat)

    def inner(self, xhat, rhat) -> float:
        return float(np.sum(xhat * rhat))

    def add(self, Ax, rhat, factor=1.0, extra=None):
        Ax += factor * rhat if extra is None else factor * rhat + extra
        return Ax
