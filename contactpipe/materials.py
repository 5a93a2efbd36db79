"""Bodies and their constitutive laws: rigid, elastic, linear viscoelastic.

A viscoelastic body has a constant Poisson ratio, so its creep function factors as
``Phi(t) = (1 + nu) / E * phi(t)`` (paper eq. 9), where ``E`` is the *instantaneous*
(glassy) Young modulus and ``phi`` the normalised creep function (phi(0) = 1).  The one
exception is Kelvin-Voigt, which has no instantaneous elasticity: there ``E`` is the
long-term modulus and phi(t) = 1 - exp(-t/tau) starts at zero.

Every normalised creep function here has the form

    phi(t) = a + b t + sum_i d_i exp(-t / tau_i)          [1]

which is what makes the O(N)-per-step recursion of :mod:`contactpipe.solver.memory` possible.
A tabulated creep function (:class:`TabulatedCreep`) is also offered; it needs the
direct (O(k N) per step) Boltzmann sum.

Units: moduli [Pa], times [s]; phi is dimensionless.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "ExponentialCreep", "TabulatedCreep", "ELASTIC", "maxwell", "kelvin_voigt", "zener",
    "prony", "Body", "dundurs_beta", "composite_modulus", "step_start_stable_step",
]


@dataclass(frozen=True)
class ExponentialCreep:
    """Normalised creep function ``phi(t) = a + b t + sum_i d_i exp(-t/tau_i)``.

    Parameters
    ----------
    a : float
        Constant term [1].
    b : float
        Linear (flow) term [1/s]; 1/t' for a Maxwell dashpot.
    d, tau : tuple of float
        Amplitudes [1] and time constants [s] of the exponential terms.
    name : str
        The creep model's name, for the archive.
    """

    a: float = 1.0
    b: float = 0.0
    d: tuple = ()
    tau: tuple = ()
    name: str = "elastic"

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        out = self.a + self.b * t
        for di, ti in zip(self.d, self.tau):
            out = out + di * np.exp(-t / ti)
        return out

    @property
    def phi0(self) -> float:
        """phi(0): 1 with instantaneous elasticity, 0 for Kelvin-Voigt."""
        return float(self(0.0))

    @property
    def is_elastic(self) -> bool:
        return self.b == 0.0 and not self.d and self.a == 1.0

    def mean(self, t0, t1):
        """Mean of phi over [t0, t1] [1] (exact)."""
        t0 = np.asarray(t0, dtype=float)
        t1 = np.asarray(t1, dtype=float)
        h = t1 - t0
        out = self.a + self.b * 0.5 * (t0 + t1)
        for di, ti in zip(self.d, self.tau):
            out = out + di * ti * (np.exp(-t0 / ti) - np.exp(-t1 / ti)) / h
        return out

    def max_over(self, t_end: float) -> float:
        """The largest phi on [0, t_end] (phi is non-decreasing for the models here)."""
        ts = np.linspace(0.0, t_end, 257)
        return float(np.max(self(ts)))

    def derivative(self, t):
        """phi'(t) [1/s] (the creep rate; phi'(0) at t = 0)."""
        t = np.asarray(t, dtype=float)
        out = np.full(t.shape, self.b)
        for di, ti in zip(self.d, self.tau):
            out = out - di / ti * np.exp(-t / ti)
        return out

    def stieltjes(self, s):
        """K(s) = int_{0-}^inf exp(-s t) dphi(t) = s * Laplace[phi](s) [1], Re s > 0:
        phi0 + b/s + sum_i c_i / (1 + s tau_i) with c_i = -d_i."""
        s = np.asarray(s, dtype=complex)
        out = self.phi0 + self.b / s
        for di, ti in zip(self.d, self.tau):
            out = out - di / (1.0 + s * ti)
        return out


@dataclass(frozen=True)
class TabulatedCreep:
    """Normalised creep function given as a table, linearly interpolated.

    Parameters
    ----------
    t : tuple of float
        Ascending times [s], starting at 0.
    phi : tuple of float
        phi at those times [1]; held constant past the last time.
    """

    t: tuple
    phi: tuple
    name: str = "tabulated"

    def __call__(self, t):
        return np.interp(np.asarray(t, dtype=float), self.t, self.phi)

    @property
    def phi0(self) -> float:
        return float(self.phi[0])

    @property
    def is_elastic(self) -> bool:
        return False

    def mean(self, t0, t1):
        """Mean of phi over [t0, t1] by the trapezoid rule on the table's knots [1]."""
        t0 = np.atleast_1d(np.asarray(t0, dtype=float))
        t1 = np.atleast_1d(np.asarray(t1, dtype=float))
        out = np.empty(np.broadcast(t0, t1).shape)
        tk = np.asarray(self.t)
        for i, (a, b) in enumerate(np.broadcast(t0, t1)):
            inner = tk[(tk > a) & (tk < b)]
            x = np.concatenate([[a], inner, [b]])
            y = self(x)
            out[i] = np.trapezoid(y, x) / (b - a)
        return out if out.size > 1 else float(out[0])

    def max_over(self, t_end: float) -> float:
        ts = np.concatenate([np.linspace(0.0, t_end, 257), [t for t in self.t if t <= t_end]])
        return float(np.max(self(ts)))

    def derivative(self, t):
        """phi'(t) [1/s]: the slope of the table's segment right of t (0 past the end)."""
        t = np.asarray(t, dtype=float)
        tk, pk = np.asarray(self.t, dtype=float), np.asarray(self.phi, dtype=float)
        slope = np.append(np.diff(pk) / np.diff(tk), 0.0)
        i = np.clip(np.searchsorted(tk, t, side="right") - 1, 0, tk.size - 1)
        return slope[i]

    def stieltjes(self, s):
        """K(s) = int_{0-}^inf exp(-s t) dphi(t) [1], Re s > 0 (exact for the linear
        interpolation, phi constant past the last time)."""
        s = np.asarray(s, dtype=complex)
        tk, pk = np.asarray(self.t, dtype=float), np.asarray(self.phi, dtype=float)
        out = np.full(s.shape, pk[0], dtype=complex)
        for t0, t1, slope in zip(tk[:-1], tk[1:], np.diff(pk) / np.diff(tk)):
            out = out + slope * (np.expm1(-s * t0) - np.expm1(-s * t1)) / s
        return out


ELASTIC = ExponentialCreep()


def maxwell(relaxation_time: float) -> ExponentialCreep:
    """Maxwell fluid: phi(t) = 1 + t/t' with t' = eta/G the relaxation time [s]."""
    return ExponentialCreep(a=1.0, b=1.0 / relaxation_time, name="maxwell")


def kelvin_voigt(retardation_time: float) -> ExponentialCreep:
    """Kelvin-Voigt solid: phi(t) = 1 - exp(-t/tau), normalised by the long-term modulus."""
    return ExponentialCreep(a=1.0, d=(-1.0,), tau=(retardation_time,), name="kelvin_voigt")


def zener(young: float, relaxed_young: float, retardation_time: float) -> ExponentialCreep:
    """Standard linear solid: phi(t) = E0/Einf - (E0/Einf - 1) exp(-t/tau)."""
    r = young / relaxed_young
    return ExponentialCreep(a=r, d=(-(r - 1.0),), tau=(retardation_time,), name="zener")


def prony(terms, relaxation_time: float | None = None) -> ExponentialCreep:
    """Generalised Kelvin chain (Prony series) with an optional dashpot:
    phi(t) = 1 + sum_i c_i (1 - exp(-t/tau_i)) + t/t'."""
    c = tuple(float(ci) for ci, _ in terms)
    tau = tuple(float(ti) for _, ti in terms)
    b = 0.0 if relaxation_time is None else 1.0 / relaxation_time
    return ExponentialCreep(a=1.0 + sum(c), b=b, d=tuple(-ci for ci in c), tau=tau,
                            name="prony")


def step_start_stable_step(creep) -> float:
    """The largest time step [s] for which the step-start rule is stable.

    The step-start rule (paper eq. 7 with each increment at the start of its step) is an
    explicit scheme. For phi = phi0 + b t + sum_i c_i (1 - exp(-t/tau_i)) with b, c_i >= 0
    (a non-decreasing phi with a completely monotone rate: every model here) its traction
    error under a fixed displacement obeys a linear recursion whose amplification factors
    g are the roots of ``phi0 + b dt/(g - 1) + sum_i c_i (1 - l_i)/(g - l_i) = 0``,
    l_i = exp(-dt/tau_i): all real, all in (-1, 1) except one that leaves through -1 when

        phi0 = b dt / 2 + sum_i c_i tanh(dt / (2 tau_i)).

    That root of dt is returned: inf when there is no memory or the right-hand side never
    reaches phi0 (b = 0 and sum c_i < phi0, e.g. Zener with E0/Einf <= 2), 0 for phi0 = 0
    (Kelvin-Voigt: never stable). At the bound the error alternates without decay, so a
    stable step is strictly below it. Maxwell: 2 t'; Zener: tau ln(r / (r - 2)),
    r = E0/Einf > 2. The small-step form 2 phi0 / phi'(0) (tanh x <= x) is a lower bound,
    exact for Maxwell and within 1/r of the exact one for Zener (2 tau / (r - 1)). A
    tabulated phi gets that estimate, from the slope of its first segment.

    Parameters
    ----------
    creep : ExponentialCreep or TabulatedCreep
        Normalised creep function phi [1].

    Returns
    -------
    float
        The largest stable step [s] (inf: any step).

    Raises
    ------
    ValueError
        A creep function with a decreasing term (b < 0 or some c_i < 0): the bound
        above does not hold for it.
    """
    from scipy.optimize import brentq      # scipy.optimize is heavy; only needed here

    phi0 = float(creep.phi0)
    if isinstance(creep, TabulatedCreep):
        rate = float(creep.derivative(0.0))
        if phi0 <= 0.0:
            return 0.0
        return np.inf if rate <= 0.0 else 2.0 * phi0 / rate
    c = -np.asarray(creep.d, dtype=float)
    tau = np.asarray(creep.tau, dtype=float)
    b = float(creep.b)
    if b < 0 or np.any(c < 0):
        raise ValueError(f"step-start stability bound: the creep function has a decreasing "
                         f"term (b = {b:g} 1/s, c = {c.tolist()}); it needs b >= 0 and "
                         f"c_i >= 0")
    if phi0 <= 0.0:
        return 0.0
    if b == 0.0 and c.sum() <= phi0:
        return np.inf

    def excess(dt):
        return 0.5 * b * dt + float(np.sum(c * np.tanh(dt / (2.0 * tau)))) - phi0

    rate = b + float(np.sum(c / tau))
    lo, hi = 2.0 * phi0 / rate, 2.0 * phi0 / rate
    while excess(hi) < 0.0:
        hi *= 2.0
    return float(brentq(excess, lo, hi, xtol=1e-15 * hi, rtol=1e-15))


@dataclass(frozen=True)
class Body:
    """One contacting body.

    Parameters
    ----------
    kind : {"rigid", "elastic", "viscoelastic"}
    young : float
        Young modulus [Pa]; the instantaneous (glassy) one for a viscoelastic body,
        except Kelvin-Voigt where it is the long-term modulus. Unused when rigid.
    poisson : float
        Poisson ratio [1], in [0, 0.5].
    creep : ExponentialCreep or TabulatedCreep
        Normalised creep function phi(t); :data:`ELASTIC` for elastic or rigid bodies.
    """

    kind: str = "elastic"
    young: float = np.inf
    poisson: float = 0.3
    creep: object = field(default=ELASTIC)

    @property
    def rigid(self) -> bool:
        return self.kind == "rigid"

    @property
    def has_memory(self) -> bool:
        return self.kind == "viscoelastic" and not self.creep.is_elastic

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)) [Pa]; inf for a rigid body."""
        return np.inf if self.rigid else self.young / (2.0 * (1.0 + self.poisson))

    @property
    def normal_compliance(self) -> float:
        """(1 - nu^2)/E [1/Pa]; 0 for a rigid body."""
        return 0.0 if self.rigid else (1.0 - self.poisson ** 2) / self.young

    @property
    def coupling_compliance(self) -> float:
        """(1 - 2 nu)/G [1/Pa], the factor of the normal-tangential coupling terms."""
        return 0.0 if self.rigid else (1.0 - 2.0 * self.poisson) / self.shear_modulus


def composite_modulus(b1: Body, b2: Body, phi1: float = 1.0, phi2: float = 1.0) -> float:
    """Composite modulus E* [Pa]: 1/E* = phi1 (1-nu1^2)/E1 + phi2 (1-nu2^2)/E2."""
    c = phi1 * b1.normal_compliance + phi2 * b2.normal_compliance
    return np.inf if c == 0 else 1.0 / c


def dundurs_beta(b1: Body, b2: Body) -> float:
    """Dundurs' second parameter (instantaneous moduli), with body 1 the indenter.

    beta = [(1-2nu1)/G1 - (1-2nu2)/G2] / (2 [(1-nu1)/G1 + (1-nu2)/G2]).
    Zero for identical materials, for two incompressible bodies, and for a rigid body on
    an incompressible one: then normal and tangential problems do not couple.
    """
    num = b1.coupling_compliance - b2.coupling_compliance
    den1 = 0.0 if b1.rigid else 2.0 * (1.0 - b1.poisson) / b1.shear_modulus
    den2 = 0.0 if b2.rigid else 2.0 * (1.0 - b2.poisson) / b2.shear_modulus
    den = den1 + den2
    return 0.0 if den == 0 else 0.5 * num / (0.5 * den)
