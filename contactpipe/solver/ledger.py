"""How the CGs (:func:`contactpipe.solver.cg.box_cg`,
:func:`contactpipe.solver.disk_cg.disk_cg`) keep A x in step with their iterate.

A step x → P(x − τ t) changes A x by −τ A t + A d, d the projection's correction. With a
plain product ``apply`` that is A t (one product, which also gives the line search's
tᵀA t) and, with ``update``, a product of d. With a
:class:`~contactpipe.solver.blocks.BlockOperator` and ``update`` the operator is applied
in halves: tᵀA t from t's spectra (Parseval's theorem), A x after the step from one set of
inverse transforms of both terms, so that d costs its forward transforms only. Small
corrections wait (:class:`Deferred`); where the solve converges, the caller's next start
(``follow``) and what waited ride on the last step the same way.
"""
from __future__ import annotations

import numpy as np

__all__ = ["Deferred", "Ledger", "dot"]


def dot(a, b) -> float:
    """Inner product of two fields of one shape, without BLAS: OpenBLAS threads a long
    ddot, which on a busy machine made a fretting loop several times slower
    (docs/design-choices.md, D9)."""
    return float(np.einsum("i,i->", a.ravel(), b.ravel()))


class Deferred:
    """The products of projections that box_cg (``defer``) leaves out of A x: while their
    changes, summed relative to the iterate as the convergence measure is, stay within
    ``limit``, the differences wait in ``pending``; the next projection beyond it takes
    them into its own product."""

    def __init__(self, limit):
        self.limit, self.lag, self.pending = limit, 0.0, None

    def take(self, d, norm):
        """d kept (None returned) while the changes summed stay within the limit, else d
        with what waits (the caller adds its product); ``norm`` the convergence measure's
        normaliser (the scale, or Σ|x| of the projected iterate)."""
        if self.limit > 0.0:
            size = float(np.abs(d).sum()) / norm
            if self.lag + size <= self.limit:
                self.lag += size
                self.pending = d.copy() if self.pending is None else \
                    np.add(self.pending, d, out=self.pending)
                return None
        if self.pending is not None:
            d = d + self.pending
            self.lag, self.pending = 0.0, None
        return d.copy()

    def flush(self):
        """What waits (None: nothing), handed over and forgotten."""
        out, self.lag, self.pending = self.pending, 0.0, None
        return out


class Ledger:
    """A x's bookkeeping for one CG solve (:func:`contactpipe.solver.cg.box_cg`,
    :func:`contactpipe.solver.disk_cg.disk_cg`).

    Parameters
    ----------
    apply : callable or BlockOperator
    update : bool
        A x follows the projections (else the caller recomputes it).
    limit : float
        The deferred corrections' budget (:class:`Deferred`), relative [1].
    follow : callable, optional
        ``follow(x) -> x′`` or None, called once, on the iterate where the solve
        converges: x′ takes x's place in A x (``after``), with what waited.
    exact : bool
        Where the solve converges, what waited is taken in all the same.
    """

    def __init__(self, apply, update, limit, follow=None, exact=False):
        self.apply, self.update, self.follow, self.exact = apply, update, follow, exact
        self.halves = update and hasattr(apply, "spectra")
        self.deferred, self.after, self._rhat = Deferred(limit), None, None
        self.ended = False

    def curvature(self, t):
        """(A t, or None in halves where it stays in spectra; tᵀA t)."""
        apply = self.apply
        if self.halves:
            that = apply.spectra(t)
            self._rhat = apply.product(that, out=self._rhat)
            return None, apply.inner(that, self._rhat)
        r = apply(t)
        return r, dot(r, t)

    def advance(self, Ax, r, tau, buf, x, done, d=None, norm=None):
        """A x += A(−τ t + d) in place, for the iterate x the step reached: d the
        projection's correction (None: none), kept back while small; where the solve ends
        here (``done``), d takes in :meth:`_end`'s move."""
        if d is not None:
            d = self.deferred.take(d, norm)
        if done:
            d = self._end(x, d)
        apply = self.apply
        if self.halves:
            apply.add(Ax, self._rhat, -tau,
                      None if d is None else apply.product(apply.spectra(d)))
            return
        Ax -= np.multiply(r, tau, out=buf)
        if d is not None:
            Ax += apply(d)

    def close(self, x, Ax, converged):
        """A solve that converged without a step to fold its end into (no descent was
        left): :meth:`_end`'s move by one product. Returns A x."""
        if converged and not self.ended:
            d = self._end(x, None)
            if d is not None and d.any():
                Ax += self.apply(d)
        return Ax

    def _end(self, x, d):
        """d grown, at the converged iterate x, by ``follow``'s move and, where it moves
        or with ``exact``, by what waited."""
        self.ended = True
        if not self.update:
            return d
        nxt = self.follow(x) if self.follow is not None else None
        if nxt is None and not self.exact:
            return d
        self.after = nxt
        for extra in (self.deferred.flush(), None if nxt is None else nxt - x):
            if extra is not None:
                d = extra if d is None else d + extra
        return d
