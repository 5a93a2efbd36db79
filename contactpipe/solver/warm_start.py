"""Warm starts: the shear continued along a straight load path, and a self-similar start
for the sub-steps of a growing load (the frictional preload).

Along a straight stretch of the load path (the increment into instant k is c times the one
into k − 1, :meth:`contactpipe.loading.Programs.continuation`) the tractions move nearly
as they did: q(k−1) + c (q(k−1) − q(k−2)) starts the instant closer than q(k−1) does, and
so does the pressure continued alike for the joint solve (:func:`continued_start`; the
block Gauss-Seidel passes' first normal solve starts from p(k−1), cheaper from it).
On the bench's fretting loop it saves FFT pairs in both forms, the most where the
passes are many (steel on aluminium; docs/design-choices.md, D19). At a knot's turn or a
reversal it is not used: the last increments say nothing of the next ones there.

Under a growing normal load on a gap homogeneous of degree d in the distance from its apex
(a sphere or an ellipsoid: d = 2), the contact grows self-similarly: its size goes as
W^(1/(d+1)) and the tractions, pressure and Spence's shear alike, keep their shape,
stretched in x by λ and scaled by W/(λ² W_from) (Spence 1975; for a sphere λ = (W/W_from)^(1/3)
and both fields scale by λ). The sub-steps of a frictional preload (graded fractions
(k/n)²) grow the contact by tens of per cent each, so the previous sub-step's fields,
stretched so, start the next one much closer than as they are, and the preload's
sub-steps cost fewer FFT pairs (docs/design-choices.md, D20).

It is only a start: the solves still run to the tolerance from it, and the path memory of
friction (the previous relative displacement) is not touched.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .options import TUNING

__all__ = ["continued_start", "self_similar_start"]


def _stretch(f, lam, centre):
    """f (N1, N2) stretched by ``lam`` about ``centre`` (in cell indices), bilinear, zero
    outside the grid."""
    from scipy import ndimage  # here: only a self-similar preload needs it (0.03 s)

    i, j = np.meshgrid(np.arange(f.shape[0], dtype=float), np.arange(f.shape[1], dtype=float),
                       indexing="ij")
    return ndimage.map_coordinates(f, [centre[0] + (i - centre[0]) / lam,
                                       centre[1] + (j - centre[1]) / lam],
                                   order=1, mode="constant", cval=0.0)


def continued_start(previous, dq, c, dp=None, tuning=TUNING):
    """The warm start of an instant that goes on along a straight load path.

    Parameters
    ----------
    previous : contactpipe.solver.coupling.Previous
        What the last instant left.
    dq : ndarray (2, N1, N2)
        The last instant's shear increment q(k−1) − q(k−2) [Pa].
    c : float
        The ratio of the load's increments (:meth:`Programs.continuation`), 0 where the
        path turns [1].
    dp : ndarray (N1, N2), optional
        The last instant's pressure increment p(k−1) − p(k−2) [Pa].
    tuning : Tuning
        ``continued_starts`` False: ``previous`` unchanged.

    Returns
    -------
    Previous
        ``previous`` with its shear moved on by c dq, and its joint solve's pressure start
        ``p_start`` by c dp (clipped at 0), the starts and nothing else (the slip is
        measured from ``u``, the normal solves start from ``p_guess``); unchanged for
        c = 0 or zero increments. The solves project a start that leaves a friction disk
        back onto it, and rescale the pressure to its force.
    """
    moves = {}
    if not tuning.continued_starts:
        return previous
    if c > 0.0 and np.any(dq):
        moves["q"] = previous.q + c * dq
    if c > 0.0 and dp is not None and np.any(dp):
        moves["p_start"] = np.maximum(previous.p_guess + c * dp, 0.0)
    return replace(previous, **moves) if moves else previous


def self_similar_start(previous, ratio, exponent, tuning=TUNING):
    """The warm start of a sub-step whose load is ``ratio`` times the last one's.

    Parameters
    ----------
    previous : contactpipe.solver.coupling.Previous
        What the last sub-step left (its pressure ``p_guess`` and shear ``q`` are used).
    ratio : float
        W / W_from > 0 [1].
    exponent : float
        1/(d + 1) for a gap homogeneous of degree d about its apex (1/3 for a sphere).
    tuning : Tuning
        ``self_similar_starts`` False: ``previous`` unchanged.

    Returns
    -------
    Previous
        ``previous`` with p_guess and q stretched by λ = ratio^exponent about the pressure's
        centroid and scaled by ratio/λ²; unchanged where nothing is in contact yet.
    """
    p = previous.p_guess
    total = float(p.sum())
    if total <= 0.0 or ratio <= 0.0 or ratio == 1.0 or not tuning.self_similar_starts:
        return previous
    i = np.arange(p.shape[0], dtype=float)
    j = np.arange(p.shape[1], dtype=float)
    centre = (float(p.sum(axis=1) @ i) / total, float(p.sum(axis=0) @ j) / total)
    lam = ratio ** exponent
    scale = ratio / lam ** 2
    p_new = np.maximum(_stretch(p, lam, centre), 0.0) * scale
    q_new = np.stack([_stretch(c, lam, centre) * scale if np.any(c) else np.zeros_like(c)
                      for c in previous.q])
    return replace(previous, p_guess=p_new, q=q_new)
