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


#: Cycles of relaxation the Kelvin strains get per jump beyond the simulated cycle's.
KELVIN_CYCLES = 1


def _advance_part(m, start: dict, more: int, period=None) -> None:
    """Advance one recursive memory ``m`` by ``more`` cycles as the cycle from ``start``
    to its present state would repeat.

    The dashpot's integral (I' = σ: the steady creep under the cycle's mean traction) grows
    by the cycle's increment every cycle. The Kelvin strains ζ_i (τ_i ζ' + ζ = σ) are
    left as they are: under a periodic traction they repeat from cycle to cycle, and
    while they still settle (a transient of a few τ_i) the traction they leave feeds back
    on them, so that a jump extrapolating them as though the traction were frozen
    overshoots and oscillates from jump to jump (measured: a Zener polymer whose loops
    then differed by 60 %); their transient runs its course over the simulated cycles
    instead (docs/wear.md)."""
    now = m.state()
    if "zeta" not in now:
        raise ValueError("a cycle jump needs a creep function that is a sum of exponentials")
    integral = np.asarray(now["integral"]) + more * (np.asarray(now["integral"])
                                                     - np.asarray(start["integral"]))
    steps = int(now["k"]) - int(start["k"])
    out = {**now, "integral": integral, "k": int(now["k"]) + more * steps}
    if KELVIN_CYCLES and period is not None:
        lam = np.exp(-period / np.asarray(m.tau, dtype=float))
        lam = lam[(None, slice(None)) + (None,) * (np.ndim(now["zeta"]) - 2)]
        z1, z0 = np.asarray(now["zeta"]), np.asarray(start["zeta"])
        out["zeta"] = lam * z1 + (z1 - lam * z0)          # one more cycle of the same σ
    m.load_state(out)


def _parts(m) -> list:
    return list(getattr(m, "parts", [m]))


def memory_snapshot(memories) -> list:
    """The state of every recursive memory (per body, per kernel part), to advance from."""
    return [None if m is None else
            [{key: np.array(v, copy=True) for key, v in part.state().items()}
             for part in _parts(m)] for m in memories]


def advance_memories(memories, start, more: int, period=None) -> None:
    """Advance each body's memory by ``more`` cycles as the cycle since ``start``
    (:func:`memory_snapshot`) would leave it, repeated (:func:`_advance_part`)."""
    if more <= 0:
        return
    for m, snap in zip(memories, start, strict=True):
        if m is None:
            continue
        for part, s in zip(_parts(m), snap, strict=True):
            _advance_part(part, s, more, period)
