"""How the CGs (:func:`contactpipe.solver.cg.box_cg`,
:func:`contactpipe.solver.disk_cg.disk_cg`) keep A x in step with their iterate.

A step x → P(x − τ t) changes A x by −τ A t + A d, d the projection's correction. With a
plain product ``apply`` that is A t (one product, which also gives the line search's
tᵀA t) and, with ``update``, a product of d. With a
:class:`~contactpipe.solver.blocks.BlockOperator` and ``update`` the operator is applied
in halves: tᵀA t from t's spectra (Parseval's theorem), A x after the step from one set of
inverse transforms of both terms, so that d costs its forward transforms only. Small
corrections wait (:class:`Deferred`); where the solve converges, the caller's next start
(``follow``, which returns a :class:`Move`) and what waited ride on the last step the same
way.

The contract the CGs keep with it (:meth:`Ledger.outcome`): a result's ``Ax`` is A times
that result's own ``x`` — ``follow``'s point where it moved the solve on, what still
waited taken in — or None where the caller let the last corrections wait (``exact``
False) and so will not use it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Deferred", "Ledger", "Move", "dot"]


@dataclass(frozen=True)
class Move:
    """What a ``follow`` decided at the converged iterate: ``to`` the point the caller
    moves to next (None: it stays), ``verdict`` the caller's own reading of the solve
    (e.g. "next", "settled", "sliding"), handed back in the result."""

    to: np.ndarray | None = None
    verdict: str = ""


def dot(a, b) -> float:
    """Inner product of two fields of one shape, without BLAS: OpenBLAS threads a long
    ddot, which on a busy machine made a fretting loop several times slower
    (docs/design-choices.md, D9)."""
    return float(np.einsum("i,i->", a.ravel(), b.ravel()))


class Deferred:
    """The products of projections that a CG defers (leaves out of A x): while their
    changes, summed relative to the iterate as the convergence measure is, stay within
    the ``budget``, the corrections are ``deferred`` (summed here); the next projection
    beyond it takes them into its own product."""

    def __init__(self, budget):
        self.budget, self.spent, self.deferred = budget, 0.0, None

    def take(self, d, norm):
        """d deferred (None returned) while the changes summed stay within the budget,
        else d with what was deferred (the caller adds its product); ``norm`` the
        convergence measure's normaliser (the scale, or Σ|x| of the projected iterate)."""
        if self.budget > 0.0:
            size = float(np.abs(d).sum()) / norm
            if self.spent + size <= self.budget:
                self.spent += size
                self.deferred = d.copy() if self.deferred is None else \
                    np.add(self.deferred, d, out=self.deferred)
                return None
        if self.deferred is not None:
            d = d + self.deferred
            self.spent, self.deferred = 0.0, None
        return d.copy()

    def flush(self):
        """What was deferred (None: nothing), handed over and forgotten."""
        out, self.spent, self.deferred = self.deferred, 0.0, None
        return out


class Ledger:
    """A x's bookkeeping for one CG solve (:func:`contactpipe.solver.cg.box_cg`,
    :func:`contactpipe.solver.disk_cg.disk_cg`): built by the caller, bound by the CG to
    its operator and tolerance (:meth:`bind`).

    Parameters
    ----------
    update : bool
        A x follows the projections (else the CG recomputes it).
    defer : float
        The deferred corrections' budget (:class:`Deferred`), a fraction of the CG's
        tolerance [1]; 0: every product exact.
    follow : callable, optional
        ``follow(x) -> Move``, called once, on the iterate where the solve converges:
        the move's point takes x's place in A x (``after``), with what waited.
    exact : bool
        Where the solve converges, what waited is taken in all the same; False: A x is
        dropped (None) where something still waits.
    """

    def __init__(self, update=False, defer=0.0, follow=None, exact=True):
        self.update, self.defer, self.follow, self.exact = update, defer, follow, exact
        self.apply = None

    def bind(self, apply, tol) -> Ledger:
        """Ready for one solve of ``apply`` at tolerance ``tol``."""
        self.apply = apply
        self.halves = self.update and hasattr(apply, "spectra")
        self.deferred, self.after, self._rhat = Deferred(self.defer * tol), None, None
        self.ended, self.move = False, None
        return self

    def curvature(self, t):
        """(A t, or None in halves where it stays in spectra; tᵀA t)."""
        apply = self.apply
        assert apply is not None, "bind() first"
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
        assert apply is not None, "bind() first"
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
                assert self.apply is not None, "bind() first"
                Ax += self.apply(d)
        return Ax

    def _end(self, x, d):
        """d grown, at the converged iterate x, by ``follow``'s move and, where it moves
        or with ``exact``, by what waited."""
        self.ended = True
        if not self.update:
            return d
        self.move = self.follow(x) if self.follow is not None else None
        nxt = None if self.move is None else self.move.to
        if nxt is None and not self.exact:
            return d
        self.after = nxt
        for extra in (self.deferred.flush(), None if nxt is None else nxt - x):
            if extra is not None:
                d = extra if d is None else d + extra
        return d

    def outcome(self, x, Ax):
        """(x, A x) of the result (the module's contract): ``follow``'s point where it
        moved, else the iterate x; what still waits taken in by one product (``exact``:
        only a solve that did not converge has any), or A x None (not ``exact``)."""
        deferred = self.deferred.deferred
        if deferred is not None:
            assert self.apply is not None, "bind() first"
            Ax = Ax + self.apply(deferred) if self.exact else None
        return (x if self.after is None else self.after), Ax
