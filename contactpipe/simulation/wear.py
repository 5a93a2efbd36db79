"""The worn surface of a wear run: the wear laws per cell and step, the depth each body
lost, the gap it opens, and the extrapolation of a simulated cycle over a cycle jump
(:class:`WearTracker`; the cycles themselves: :mod:`.cycles`; docs/wear.md).

Per cell and step, with the step's slip increment Δs and its end-of-step tractions p, q
(those the frictional dissipation Σ q·Δs ΔA of the step is counted with):

* Archard: Δh = k p |Δs|;
* energy (Fouvry): Δh = k |q·Δs|.

With a uniform μ a slipping cell carries |q| = μp along Δs, so the worn volume is
(k/μ) times the dissipation (Archard) or k times it (energy law), step by step.
"""
from __future__ import annotations

import numpy as np

__all__ = ["WearTracker", "advance_memories"]


class WearTracker:
    """The depth each body lost [m], and the gap it opens.

    Parameters
    ----------
    wear : contactpipe.scene.Wear
        The scene's ``[wear]`` table.
    gap : ndarray (N1, N2)
        The unworn gap hi [m].
    """

    def __init__(self, wear, gap):
        self.law = wear.law
        self.k = np.array(wear.coefficients, dtype=float)       # (k_indenter, k_halfspace)
        self.hi = np.array(gap, dtype=float)
        #: depth lost by the indenter and by the half-space [m], (2, N1, N2)
        self.depth = np.zeros((2,) + self.hi.shape)

    @property
    def total(self) -> np.ndarray:
        """The depth removed from both bodies together [m] (N1, N2)."""
        return self.depth[0] + self.depth[1]

    def gap(self) -> np.ndarray:
        """The worn gap hi + wear_depth [m]."""
        return self.hi + self.total

    def take(self, p, q, ds) -> np.ndarray:
        """Wear one (sub-)step with end-of-step pressure ``p`` [Pa], shear ``q`` (2, N1, N2)
        [Pa] and slip increment ``ds`` (2, N1, N2) [m]; return the worn gap."""
        if self.law == "archard":
            per_k = p * np.hypot(ds[0], ds[1])
        else:
            per_k = np.abs(q[0] * ds[0] + q[1] * ds[1])
        self.depth += self.k[:, None, None] * per_k[None]
        return self.gap()

    def state(self) -> dict:
        return {"depth": self.depth.copy()}

    def load_state(self, state) -> None:
        self.depth = np.array(state["depth"], dtype=float).reshape(self.depth.shape)


def _rate_factor(decay, more: int):
    """Σ_{j<more} λ^j for λ = ``decay`` (array), exact as λ → 1 (then ``more``)."""
    decay = np.asarray(decay, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        ln = np.log(np.maximum(decay, 1e-300))
        out = np.where(np.abs(ln) < 1e-12, float(more), np.expm1(more * ln) / np.expm1(ln))
    return out


def _advance_part(m, start: dict, more: int, period: float) -> None:
    """Advance one recursive memory ``m`` by ``more`` cycles of period ``period`` [s], as
    the cycle from ``start`` to its present state would repeat: each Kelvin strain
    ζ_i obeys τ_i ζ' + ζ = σ, so a periodic σ maps it over a cycle as ζ → λ ζ + f with
    λ = exp(−P/τ_i); the dashpot's integral I' = σ grows by the same amount every cycle."""
    now = m.state()
    if "zeta" not in now:
        raise ValueError("a cycle jump needs a creep function that is a sum of exponentials")
    lam = np.exp(-period / np.asarray(m.tau, dtype=float))
    ex = (None, slice(None)) + (None,) * (now["zeta"].ndim - 2)
    z1, z0 = np.asarray(now["zeta"]), np.asarray(start["zeta"])
    lam_e, rate = lam[ex], _rate_factor(lam, more)[ex]
    f = z1 - lam_e * z0
    zeta = lam_e ** more * z1 + rate * f
    integral = np.asarray(now["integral"]) + more * (np.asarray(now["integral"])
                                                     - np.asarray(start["integral"]))
    steps = int(now["k"]) - int(start["k"])
    m.load_state({**now, "zeta": zeta, "integral": integral,
                  "k": int(now["k"]) + more * steps})


def _parts(m) -> list:
    return list(getattr(m, "parts", [m]))


def memory_snapshot(memories) -> list:
    """The state of every recursive memory (per body, per kernel part), to advance from."""
    return [None if m is None else
            [{key: np.array(v, copy=True) for key, v in part.state().items()}
             for part in _parts(m)] for m in memories]


def advance_memories(memories, start, more: int, period: float) -> None:
    """Advance each body's memory by ``more`` cycles as the cycle since ``start``
    (:func:`memory_snapshot`) would leave it, repeated (:func:`_advance_part`)."""
    if more <= 0:
        return
    for m, snap in zip(memories, start, strict=True):
        if m is None:
            continue
        for part, s in zip(_parts(m), snap, strict=True):
            _advance_part(part, s, more, period)
