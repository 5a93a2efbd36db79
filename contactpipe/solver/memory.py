"""Viscoelastic memory: the Boltzmann sum of paper eq. (7) without O(Nt²) work.

With a constant Poisson ratio the viscoelastic influence coefficients factor as
KV(t) = φ(t)·K (paper eq. 9, φ the normalised creep function), so the displacement is one
spatial convolution of a *history traction*

    H(t_k) = Σ_n  W(k, n) · Δσ_n          (pointwise in space, per traction component)

with the elastic kernel of the instantaneous modulus. The weights W depend on how the
traction is assumed to vary between instants (the *time rule*):

``"step_start"`` (the paper's rule, first order in Δt)
    each increment acts from the start of its step: W(k, n) = φ((k − n)Δt).
``"linear"`` (second order)
    the traction is linear between instants (the initial jump at t0 stays a jump):
    W(k, n) = (1/Δt)∫ φ over [(k−n)Δt, (k−n+1)Δt] for n ≥ 1, W(k, 0) = φ(kΔt).
    The weight of the current increment is the mean of φ over the first step, which is
    positive even for Kelvin-Voigt (φ(0) = 0), so bodies without instantaneous elasticity
    are handled.

At step k the current traction σ_k is unknown: H(t_k) = c0·σ_k + H_known, where c0 is the
*instantaneous weight* (it scales the kernels of the inner problems) and ``H_known``
depends on the past only. For φ = a + b t + Σ d_i exp(−t/τ_i) (Maxwell, Kelvin-Voigt,
Zener, Prony, Burgers), H obeys a recursion on a few fields per component — the running
integral of σ and one exponential average per τ_i — so work and memory per step do not
grow with k (:class:`RecursiveMemory`). A tabulated φ needs the direct sum
(:class:`DirectMemory`, O(k·N) work and memory per step: offered, and said so).
"""
from __future__ import annotations

import numpy as np

from ..materials import ExponentialCreep

__all__ = ["RecursiveMemory", "DirectMemory", "make_memory", "TIME_RULES"]

TIME_RULES = ("linear", "step_start")


class RecursiveMemory:
    """Exact O(N)-per-step history for φ(t) = a + b t + Σ d_i exp(−t/τ_i).

    Parameters
    ----------
    creep : ExponentialCreep
        Normalised creep function.
    dt : float
        Time step [s] (uniform mesh).
    rule : {"linear", "step_start"}
        Time rule (module doc).
    shape : tuple
        Shape of the traction array held (e.g. (3, N1, N2) for q1, q2, p).
    """

    def __init__(self, creep: ExponentialCreep, dt: float, rule: str, shape):
        if rule not in TIME_RULES:
            raise ValueError(f"time rule {rule!r}: allowed {TIME_RULES}")
        self.creep, self.dt, self.rule, self.shape = creep, float(dt), rule, tuple(shape)
        self.lam = np.array([np.exp(-dt / t) for t in creep.tau])
        if rule == "linear":
            self.gamma = np.array([t / dt * (1.0 - np.exp(-dt / t)) for t in creep.tau])
            self.weight = creep.a + 0.5 * creep.b * dt + float(np.dot(creep.d, self.gamma))
        else:
            self.gamma = np.ones(len(creep.tau))
            self.weight = creep.phi0
        self.weight0 = creep.phi0          # weight of the jump at the first instant
        self.k = 0                         # instants committed
        self._integral = np.zeros(self.shape)
        self._exp = np.zeros((len(creep.tau),) + self.shape)
        self._prev = np.zeros(self.shape)

    @property
    def instant_weight(self) -> float:
        """c0 of the next instant to solve."""
        return self.weight0 if self.k == 0 else self.weight

    def known(self) -> np.ndarray:
        """H_known for the next instant [Pa] (the part of H not multiplied by σ_k)."""
        c = self.creep
        if self.k == 0:
            return np.zeros(self.shape)
        if self.rule == "linear":
            out = c.b * (self._integral + 0.5 * self.dt * self._prev)
        else:
            out = c.b * (self._integral + self.dt * self._prev)
        for i, di in enumerate(c.d):
            out = out + di * (self.lam[i] * self._exp[i] - self.gamma[i] * self._prev)
        return out

    def commit(self, sigma: np.ndarray) -> None:
        """Record the solved traction of the current instant [Pa]."""
        sigma = np.asarray(sigma, dtype=float).reshape(self.shape)
        if self.k == 0:
            self._exp[...] = sigma
        else:
            if self.rule == "linear":
                self._integral += 0.5 * self.dt * (self._prev + sigma)
            else:
                self._integral += self.dt * self._prev
            for i in range(len(self.lam)):
                self._exp[i] = self.lam[i] * self._exp[i] + self.gamma[i] * (sigma - self._prev)
        self._prev = sigma.copy()
        self.k += 1

    def state(self) -> dict:
        """Arrays that fully describe the memory (for checkpoints)."""
        return {"k": self.k, "integral": self._integral, "exp": self._exp, "prev": self._prev}

    def load_state(self, state) -> None:
        """Restore what :meth:`state` gave."""
        self.k = int(state["k"])
        self._integral = np.array(state["integral"], dtype=float)
        self._exp = np.array(state["exp"], dtype=float)
        self._prev = np.array(state["prev"], dtype=float)


class DirectMemory:
    """Direct Boltzmann sum for any creep function (e.g. tabulated): O(k·N) per step.

    Keeps every past increment; use :class:`RecursiveMemory` whenever φ is a sum of
    exponentials and a linear term.
    """

    def __init__(self, creep, dt: float, rule: str, shape):
        if rule not in TIME_RULES:
            raise ValueError(f"time rule {rule!r}: allowed {TIME_RULES}")
        self.creep, self.dt, self.rule, self.shape = creep, float(dt), rule, tuple(shape)
        self.weight0 = float(creep.phi0)
        self.weight = float(np.asarray(self._w(0))) if rule == "linear" else self.weight0
        self.k = 0
        self._increments = []
        self._prev = np.zeros(self.shape)

    def _w(self, m):
        """Weight of a ramp increment m steps back (linear rule)."""
        return self.creep.mean(m * self.dt, (m + 1) * self.dt)

    @property
    def instant_weight(self) -> float:
        return self.weight0 if self.k == 0 else self.weight

    def known(self) -> np.ndarray:
        k = self.k
        if k == 0:
            return np.zeros(self.shape)
        out = -self.weight * self._prev
        for n, inc in enumerate(self._increments):
            if n == 0 or self.rule == "step_start":
                w = float(self.creep((k - n) * self.dt))
            else:
                w = float(np.asarray(self._w(k - n)))
            out = out + w * inc
        return out

    def state(self) -> dict:
        inc = np.stack(self._increments) if self._increments else np.zeros((0,) + self.shape)
        return {"k": self.k, "increments": inc, "prev": self._prev}

    def load_state(self, state) -> None:
        self.k = int(state["k"])
        self._increments = list(np.array(state["increments"], dtype=float))
        self._prev = np.array(state["prev"], dtype=float)

    def commit(self, sigma: np.ndarray) -> None:
        sigma = np.asarray(sigma, dtype=float).reshape(self.shape)
        self._increments.append(sigma - self._prev)
        self._prev = sigma.copy()
        self.k += 1


def make_memory(creep, dt, rule, shape):
    """The cheapest exact memory for a creep function."""
    if isinstance(creep, ExponentialCreep):
        return RecursiveMemory(creep, dt, rule, shape)
    return DirectMemory(creep, dt, rule, shape)
