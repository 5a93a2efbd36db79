"""The frictional preload's estimate: how many proportional sub-steps the load at t0 is
applied in, and the error that leaves (:func:`contactpipe.planning.accuracy.choose_preload`).

The preload path at t0 starts from the unloaded state without history, so it is known
before the march: the coarser paths the estimate compares run on a scratch state, each a
:class:`Path` handed to the instant's solve (:func:`contactpipe.simulation.march._step`),
which the run's own first instant is too.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from ..exceptions import ConvergenceError
from ..planning.accuracy import PRELOAD_TARGET, PRESETS, choose_preload
from ..solver.coupling import Tolerances
from ..solver.state import State

__all__ = ["Path", "estimate", "PATH_TOLERANCE"]

#: Tolerance of the coarser paths of a frictional preload's error estimate, as a fraction
#: of the path's error target (:func:`coarse_limits`) [1].
PATH_TOLERANCE = 1e-5


@dataclass(frozen=True)
class Path:
    """How the first instant is solved: the preload's sub-step count, the solver limits,
    and whether it is a scratch path of the estimate (its windows of the contact are then
    kept for the next path; the run drops the preload's windows and makes its own)."""

    substeps: int
    limits: Tolerances
    scratch: bool = False


def _target(scene) -> float:
    acc = scene.solver.accuracy
    return PRESETS[acc].target if acc in PRESETS else PRELOAD_TARGET


def coarse_limits(pb) -> Tolerances:
    """The solver limits of the estimate's coarser paths: solved to
    :data:`PATH_TOLERANCE` of the path's error target (never tighter than the scene's
    tolerance): they only measure a difference of 0.3-4 % of mu p_max. The path of the
    run itself keeps the full tolerance at every station, so that a run is determined
    to its tolerance whatever the process (FFTW plans) and a resumed run matches an
    uninterrupted one (docs/time-integration.md)."""
    return replace(pb.limits, tol=max(pb.limits.tol, PATH_TOLERANCE * _target(pb.scene)))


def estimate(pb, step) -> dict:
    """The frictional preload's sub-step count and its estimated error for problem
    ``pb``; ``step(pb, state, k, path)`` solves an instant.

    Returns
    -------
    dict
        ``substeps`` (0 without a frictional preload), ``error`` (estimated rms error
        of the q field over the contact, over mu p_max [1], or None), ``pairs`` (the
        FFT pairs the coarser paths cost).
    """
    pairs0 = pb.ops.conv.pairs
    n, est = 0, None
    if pb.preload_active():
        limits = coarse_limits(pb)

        def path(substeps):
            """(q, p) after a frictional preload in ``substeps`` sub-steps on a scratch
            state, or None when it does not converge."""
            try:
                st = State.initial(pb.grid.shape, pb.ops.new_memories())
                step(pb, st, 0, Path(int(substeps), limits, scratch=True))
                return st.q.copy(), st.p.copy()
            except ConvergenceError:
                return None

        n, est = choose_preload(pb.scene.solver.preload_substeps, path, pb.grid.mu,
                                _target(pb.scene))
    return {"substeps": n, "error": est, "pairs": int(pb.ops.conv.pairs - pairs0)}
