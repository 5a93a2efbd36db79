"""Creep functions: the exponential form, tables, the models, the step-start rule's
stability bound, and the interconversions of a varying Poisson ratio.

Units: times [s]; phi is dimensionless.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

__all__ = ["ExponentialCreep", "TabulatedCreep", "ELASTIC", "maxwell", "kelvin_voigt",
           "zener", "prony", "step_start_stable_step", "combine", "relaxation_from_creep",
           "bulk_ratio", "elastic_bulk_parts"]


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
        for di, ti in zip(self.d, self.tau, strict=True):
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
        for di, ti in zip(self.d, self.tau, strict=True):
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
        for di, ti in zip(self.d, self.tau, strict=True):
            out = out - di / ti * np.exp(-t / ti)
        return out

    def stieltjes(self, s):
        """K(s) = int_{0-}^inf exp(-s t) dphi(t) = s * Laplace[phi](s) [1], Re s > 0:
        phi0 + b/s + sum_i c_i / (1 + s tau_i) with c_i = -d_i."""
        s = np.asarray(s, dtype=complex)
        out = self.phi0 + self.b / s
        for di, ti in zip(self.d, self.tau, strict=True):
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
        phi at those times [1]; held constant past the last time. A table is only
        known up to its last time (:attr:`last_time`): a scene refuses a load window
        longer than it.
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
    def last_time(self) -> float:
        """The table's last time [s]: phi is known on [0, last_time]."""
        return float(self.t[-1])

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
        for t0, t1, slope in zip(tk[:-1], tk[1:], np.diff(pk) / np.diff(tk), strict=True):
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
    from scipy.optimize import brentq  # scipy.optimize is heavy; only needed here

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


# --------------------------------------------------------------------------- nu(t)
def combine(terms, name="combined") -> ExponentialCreep:
    """The linear combination sum_k w_k f_k of exponential creep functions, terms of equal
    time constant merged and exactly cancelling ones dropped.

    Parameters
    ----------
    terms : sequence of (float, ExponentialCreep)
        Weights [1] and functions.
    name : str
        The result's name.
    """
    a = b = 0.0
    merged = {}
    for w, f in terms:
        a += w * f.a
        b += w * f.b
        for di, ti in zip(f.d, f.tau, strict=True):
            merged[ti] = merged.get(ti, 0.0) + w * di
    keep = [(ti, di) for ti, di in merged.items() if di != 0.0]
    out = ExponentialCreep(a=a, b=b, d=tuple(di for _, di in keep),
                           tau=tuple(ti for ti, _ in keep), name=name)
    if all(f.phi0 == 0.0 for w, f in terms if w != 0.0):
        out = _zero_at_origin(out)
    return out


def _zero_at_origin(creep: ExponentialCreep) -> ExponentialCreep:
    """``creep`` with its last amplitude corrected for the rounding of phi(0), which is 0
    in exact arithmetic (a combination of functions without instantaneous compliance): a weight of
    1e-17 would otherwise stand for a rigid instant."""
    if not creep.d:
        return replace(creep, a=0.0)
    partial = creep.a                        # phi(0) summed as __call__ sums it
    for di in creep.d[:-1]:
        partial = partial + di
    return replace(creep, d=creep.d[:-1] + (-partial,))


def relaxation_from_creep(creep: ExponentialCreep, extra: float = 0.0) -> ExponentialCreep:
    """The relaxation function of the creep function phi + ``extra``, exactly.

    r(t) solves int_{0-}^t r(t - s) d(phi + extra)(s) = 1 (in Carson transforms
    s L[r](s) = 1/psi(s), psi(s) = phi0 + extra + b/s + sum_i c_i/(1 + s tau_i) with
    c_i = -d_i >= 0). The zeros of psi on the negative real axis, s_j = -1/lambda_j, lie
    one between consecutive poles -1/tau_i, one beyond the last and one in
    (-1/tau_max, 0) with a dashpot (b > 0), so

        r(t) = r_inf + sum_j r_j exp(-t/lambda_j),   r_j = 1/(s_j psi'(s_j)) > 0,

    r_inf = 1/(phi(inf) + extra) (0 with a dashpot) and r(0) = 1/(phi0 + extra). Without
    instantaneous compliance (phi0 + extra = 0: Kelvin-Voigt) 1/psi grows like
    s/phi'(0): the relaxation function is then delta(t)/phi'(0) plus the regular part
    returned (no zero beyond the last pole; r_inf and r_j as above).

    Parameters
    ----------
    creep : ExponentialCreep
        phi [1] with b >= 0 and c_i >= 0.
    extra : float
        A constant compliance added to phi [1], >= 0.

    Returns
    -------
    ExponentialCreep
        r [1] (a decreasing function: a = r_inf, d = (r_j), tau = (lambda_j)).

    Raises
    ------
    ValueError
        A decreasing term, or phi0 + extra < 0, or phi = 0.
    """
    from scipy.optimize import brentq  # heavy; only nu(t) bodies need it

    c = -np.asarray(creep.d, dtype=float)
    tau = np.asarray(creep.tau, dtype=float)
    b = float(creep.b)
    a0 = float(creep.phi0) + float(extra)
    if b < 0 or np.any(c < 0) or not a0 >= 0 or (a0 == 0 and b == 0 and not np.any(c > 0)):
        raise ValueError(f"relaxation function: need b >= 0, c_i >= 0, phi(0) + extra "
                         f">= 0 and phi not 0, got b = {b:g}, c = {c.tolist()}, {a0:g}")
    keep = c > 0
    c, tau = c[keep], tau[keep]
    order = np.argsort(1.0 / tau)
    c, tau = c[order], tau[order]
    poles = 1.0 / tau                            # x = -s = 1/tau_i, ascending

    def psi(x):                                  # psi(-x)
        return a0 - (b / x if b else 0.0) + float(np.sum(c / (1.0 - x * tau)))

    def slope(x):                                # -psi'(s) at s = -x, > 0
        return (b / x ** 2 if b else 0.0) + float(np.sum(c * tau / (1.0 - x * tau) ** 2))

    edges = list(poles)
    brackets = list(zip(edges[:-1], edges[1:], strict=True))
    if edges and a0 > 0:                         # psi -> a0 beyond the last pole
        brackets.append((edges[-1], np.inf))
    if b > 0 and (edges or a0 > 0):
        brackets.insert(0, (0.0, edges[0] if edges else np.inf))
    lam, rj = [], []
    for lo, hi in brackets:
        if np.isinf(hi):
            hi = 2.0 * max(lo, b / a0)
            while psi(hi) <= 0:
                hi *= 2.0
        else:
            hi = hi - 1e-12 * (hi - lo)
        if lo == 0.0:
            lo = 1e-9 * b / (a0 + c.sum())       # psi < 0 there (the dashpot dominates)
        else:
            lo = lo + 1e-12 * (hi - lo)
        x = brentq(psi, lo, hi, xtol=1e-300, rtol=1e-15, maxiter=500)
        lam.append(1.0 / x)
        rj.append(1.0 / (x * slope(x)))
    r_inf = 0.0 if b > 0 else 1.0 / (a0 + c.sum())
    return ExponentialCreep(a=float(r_inf), d=tuple(float(x) for x in rj),
                            tau=tuple(float(x) for x in lam), name="relaxation")


def bulk_ratio(poisson: float) -> float:
    """kappa = G/K = 3 (1 - 2 nu) / (2 (1 + nu)) [1]: 0 for an incompressible body."""
    return 3.0 * (1.0 - 2.0 * poisson) / (2.0 * (1.0 + poisson))


@lru_cache(maxsize=64)
def elastic_bulk_parts(creep: ExponentialCreep, poisson: float):
    """The creep functions of a body whose shear compliance creeps and bulk does not.

    The shear compliance is J(t) = phi(t)/G and the bulk modulus K is constant, with G,
    K the moduli where phi = 1 (Young modulus E, Poisson ratio nu: G = E/(2(1 + nu)),
    K = E/(3(1 - 2 nu)), kappa = G/K). Every influence coefficient is a combination of two
    compliances (:func:`contactpipe.solver.influence.body_kernel_parts`): 1/G and nu/G.
    By the correspondence principle, with Carson transforms (^) and
    nu^ = (3K - 2G^)/(2(3K + G^)),

        (nu/G)^ = J^/2 - 1/(2K) + (1/(2K)) / (1 + 3K J^),

    whose last term is the relaxation function of the compliance J + 1/(3K)
    (:func:`relaxation_from_creep`). Normalised by 1/G:

        phi_shear = phi,    phi_poisson = phi/2 - kappa/2 + kappa^2 r(t)/6,

    r the relaxation function of phi + kappa/3; phi_poisson = nu where phi = 1. The
    normal compliance (1 - nu)/G is phi_shear - phi_poisson and the coupling compliance
    (1 - 2 nu)/G is phi_shear - 2 phi_poisson = kappa - kappa^2 r/3: both creep functions
    with non-negative terms; the coupling one is bounded by kappa (1/K).

    Parameters
    ----------
    creep : ExponentialCreep
        phi [1], the normalised shear creep function.
    poisson : float
        nu [1] where phi = 1 (t = 0, or t = inf for phi(0) = 0), in [0, 0.5].

    Returns
    -------
    (ExponentialCreep, ExponentialCreep)
        phi_shear, phi_poisson [1].
    """
    if not isinstance(creep, ExponentialCreep):
        raise ValueError("bulk = 'elastic' needs a creep function of exponentials "
                         "(maxwell, kelvin_voigt, zener, prony, fit), not a table")
    kappa = bulk_ratio(poisson)
    if kappa == 0.0:
        return creep, combine([(0.5, creep)], "poisson_part")
    r = relaxation_from_creep(creep, kappa / 3.0)
    part = combine([(0.5, creep), (kappa ** 2 / 6.0, r),
                    (-kappa / 2.0, ExponentialCreep())], "poisson_part")
    if creep.phi0 == 0.0:       # phi_poisson(0) = 0 exactly: kappa^2 r(0)/6 = kappa/2
        part = _zero_at_origin(part)
    return creep, part
