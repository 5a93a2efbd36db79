"""Bodies and their constitutive laws: rigid, elastic, linear viscoelastic.

By default a viscoelastic body has a constant Poisson ratio, so its creep function factors
as ``Phi(t) = (1 + nu) / E * phi(t)`` (paper eq. 9), where ``E`` is the *instantaneous*
(glassy) Young modulus and ``phi`` the normalised creep function (phi(0) = 1).  The one
exception is Kelvin-Voigt, which has no instantaneous elasticity: there ``E`` is the
long-term modulus and phi(t) = 1 - exp(-t/tau) starts at zero.

With ``bulk = "elastic"`` (:class:`Body`) phi is the shear creep compliance instead,
J(t) = phi(t)/G, while the bulk modulus K = E/(3(1 - 2 nu)) keeps the value it has where
phi = 1: the Poisson ratio then varies in time (towards 1/2 as the shear modulus relaxes),
and the influence coefficients split into parts with their own creep functions
(:func:`elastic_bulk_parts`).

Every normalised creep function here has the form

    phi(t) = a + b t + sum_i d_i exp(-t / tau_i)          [1]

which is what makes the O(N)-per-step recursion of :mod:`contactpipe.solver.memory` possible.
A tabulated creep function (:class:`TabulatedCreep`) is also offered; it needs the
direct (O(k N) per step) Boltzmann sum. Measured data (a creep or relaxation table, or
storage and loss moduli over frequency) give a Prony series of that form through
:func:`fit_creep_compliance`, :func:`fit_relaxation_modulus` and :func:`fit_dynamic_moduli`.
:func:`step_start_stable_step` is the largest stable step of the paper's step-start rule.

Units: moduli [Pa], times [s]; phi is dimensionless.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

__all__ = [
    "ExponentialCreep", "TabulatedCreep", "ELASTIC", "maxwell", "kelvin_voigt", "zener",
    "prony", "Body", "dundurs_beta", "composite_modulus", "step_start_stable_step",
    "PronyFit", "fit_creep_compliance", "fit_relaxation_modulus", "fit_dynamic_moduli",
    "combine", "relaxation_from_creep", "bulk_ratio", "elastic_bulk_parts", "BULK",
    "TABLE_KINDS", "read_table_file", "fit_table_file", "table_time_span",
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
        for di, ti in zip(f.d, f.tau):
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
    from scipy.optimize import brentq           # heavy; only nu(t) bodies need it

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
    brackets = list(zip(edges[:-1], edges[1:]))
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


# --------------------------------------------------------------------------- fitting
@dataclass(frozen=True)
class PronyFit:
    """A creep function fitted to measured data (:func:`fit_creep_compliance`,
    :func:`fit_relaxation_modulus`, :func:`fit_dynamic_moduli`).

    Attributes
    ----------
    creep : ExponentialCreep
        The normalised creep function phi [1], ``name = "fit"``.
    young : float
        The Young modulus that normalises phi [Pa]: the instantaneous one, 1/D(0); the
        long-term one when the data show no instantaneous compliance (phi(0) = 0).
    rms_error, max_error : float
        Root-mean-square and largest relative misfit over the data points [1] (a zero
        compliance at t = 0 left out).
    times : tuple of float
        The fixed, log-spaced times of the fit [s] (retardation times for a creep table,
        relaxation times for a relaxation or dynamic one).
    source : str
        "creep", "relaxation" or "dynamic".
    """

    creep: ExponentialCreep
    young: float
    rms_error: float
    max_error: float
    times: tuple
    source: str


def _fit_columns(what, x, columns, *, positive_x=True, zero_at_origin=False):
    """Checked, float 1-D arrays of equal length: x strictly ascending, columns > 0 (a
    creep compliance may be 0 at t = 0: no instantaneous compliance)."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 3:
        raise ValueError(f"{what}: need at least 3 points in a 1-D table, got shape {x.shape}")
    if not np.all(np.isfinite(x)) or np.any(np.diff(x) <= 0):
        raise ValueError(f"{what}: the abscissae must be finite and strictly ascending")
    if np.any(x < 0) or (positive_x and x[0] <= 0):
        raise ValueError(f"{what}: the abscissae must be >= 0 (frequencies > 0), got "
                         f"{x[0]:g}")
    out = []
    for name, col in columns:
        col = np.asarray(col, dtype=float)
        if col.shape != x.shape:
            raise ValueError(f"{what}: {name} has {col.size} values for {x.size} abscissae")
        low = col[1:] if (zero_at_origin and x[0] == 0 and col[0] == 0) else col
        if not np.all(np.isfinite(col)) or np.any(low <= 0):
            raise ValueError(f"{what}: {name} must be finite and > 0 (a positive material "
                             f"function{', 0 allowed at t = 0' if zero_at_origin else ''}), "
                             f"got min {np.min(col):g}")
        out.append(col)
    return x, out


def _check_monotone(what, x, y, sign, noise, unit):
    """Refuse data that move the wrong way by more than ``noise`` (relative): below their
    running maximum (sign +1, must not decrease) or above their running minimum (-1)."""
    if sign > 0:
        excess = np.maximum.accumulate(y) - y
    else:
        excess = y - np.minimum.accumulate(y)
    rel = excess / y
    worst = int(np.argmax(rel))
    if rel[worst] > noise:
        way = "decrease" if sign > 0 else "increase"
        raise ValueError(f"{what} must not {way}: it does so by {rel[worst]:.1%} at "
                         f"{x[worst]:g} {unit} (more than the noise allowance {noise:.1%}); "
                         f"the Prony fit would not be monotone")


def _log_times(lo, hi, per_decade, times=None):
    """The fixed times of a fit [s]: ``times`` as given, or log-spaced over [lo, hi]."""
    if times is not None:
        times = np.sort(np.asarray(times, dtype=float).ravel())
        if times.size == 0 or not np.all(np.isfinite(times)) or np.any(times <= 0) \
                or np.any(np.diff(times) <= 0):
            raise ValueError(f"times must be distinct, finite and > 0 [s], got "
                             f"{times.tolist()}")
        return times
    if int(per_decade) != per_decade or per_decade < 1:
        raise ValueError(f"terms_per_decade must be an integer >= 1, got {per_decade}")
    n = max(int(np.ceil(per_decade * np.log10(hi / lo) - 1e-9)), 1) + 1
    return np.logspace(np.log10(lo), np.log10(hi), n)


def _nonnegative_fit(matrix, data):
    """min |(A c - y)/y| over c >= 0 (scipy.optimize.least_squares with bounds); a zero
    datum (a compliance at t = 0) weighs as the smallest positive one."""
    from scipy.optimize import least_squares   # heavy; only the fits need it

    weight = 1.0 / np.where(data > 0, data, np.min(data[data > 0]))
    a = matrix * weight[:, None]
    target = data * weight
    scale = np.maximum(np.abs(a).max(axis=0), 1e-300)
    a = a / scale                               # unit columns: coefficients of order 1
    res = least_squares(lambda c: a @ c - target, np.full(a.shape[1], 1e-3),
                        jac=lambda c: a, bounds=(0.0, np.inf), method="trf",
                        ftol=1e-15, xtol=1e-15, gtol=1e-15, max_nfev=10000)
    coef = res.x / scale
    coef[res.active_mask != 0] = 0.0           # on the bound: exactly zero
    return coef


def _fit_result(creep, young, model, data, times, source):
    pos = data > 0
    err = model[pos] / data[pos] - 1.0
    fit = PronyFit(creep=creep, young=float(young),
                   rms_error=float(np.sqrt(np.mean(err ** 2))),
                   max_error=float(np.abs(err).max()), times=tuple(float(t) for t in times),
                   source=source)
    t = np.concatenate([[0.0], np.logspace(np.log10(times[0]) - 3, np.log10(times[-1]) + 3,
                                           400)])
    phi = creep(t)
    if not (np.all(phi[1:] > 0) and np.all(np.diff(phi) >= -1e-12 * phi.max())):
        raise ValueError(f"the {source} fit is not a positive, non-decreasing creep "
                         f"function (min phi {phi[1:].min():g}); check the data")
    return fit


def _creep_from_compliance(j0, jk, lam, flow):
    """Normalised phi and its modulus from D(t) = j0 + sum jk (1 - e^{-t/lam}) + flow t."""
    total = j0 + jk.sum()
    keep = jk > 1e-9 * total                    # solver tolerance, not data (as above)
    jk, lam = jk[keep], lam[keep]
    j0 = j0 if j0 > 1e-9 * total else 0.0
    if j0 > 0:
        young = 1.0 / j0
    elif jk.sum() > 0:
        young = 1.0 / jk.sum()                  # no instantaneous compliance: long-term
    else:
        raise ValueError("the fit is not positive: every coefficient is zero")
    creep = ExponentialCreep(a=young * (j0 + jk.sum()), b=young * flow,
                             d=tuple(-young * jk), tau=tuple(lam), name="fit")
    return creep, young


def fit_creep_compliance(t, compliance, *, terms_per_decade=2, times=None, dashpot=False,
                         noise=0.01):
    """Prony series fitted to a tensile creep-compliance table.

    D(t) = D0 + sum_i D_i (1 - exp(-t/tau_i)) [+ t/eta] with fixed log-spaced tau_i
    (``terms_per_decade`` per decade over the table's positive times) and D0, D_i, 1/eta
    >= 0 by the bounds of :func:`scipy.optimize.least_squares` on the relative misfit
    (linear in the coefficients: a convex problem, unique, with no start guess; free
    tau_i would make it non-convex, with terms that merge or leave the data's window).

    Parameters
    ----------
    t : array_like
        Times [s], ascending, >= 0 (at least 3).
    compliance : array_like
        D(t) = strain / stress under a constant stress [1/Pa], > 0 (0 allowed at t = 0),
        non-decreasing.
    terms_per_decade : int
        Retardation times per decade (2: exact for a spectrum on that grid, 0.5 % rms for
        a power-law creep t^0.3 over four decades; 1 gives 0.6 %).
    times : array_like, optional
        The retardation times [s] instead of the log-spaced ones.
    dashpot : bool
        Add a flow term t/eta (a fluid).
    noise : float
        Relative decrease of the data tolerated as measurement noise [1].

    Returns
    -------
    PronyFit
        phi = E D(t) with E = 1/D0 (or 1/D(inf) when D0 = 0).

    Raises
    ------
    ValueError
        Bad data (not positive, not ascending, decreasing beyond ``noise``) or a fit
        that is not a positive, non-decreasing creep function.
    """
    what = "creep compliance"
    t, (d,) = _fit_columns(what, t, [("the compliance", compliance)], positive_x=False,
                           zero_at_origin=True)
    _check_monotone(what, t[d > 0], d[d > 0], +1, noise, "s")
    pos = t[t > 0]
    lam = _log_times(pos[0], pos[-1], terms_per_decade, times)
    cols = [np.ones_like(t)] + [-np.expm1(-t / tk) for tk in lam] + ([t] if dashpot else [])
    a = np.column_stack(cols)
    c = _nonnegative_fit(a, d)
    flow = c[-1] if dashpot else 0.0
    creep, young = _creep_from_compliance(c[0], c[1:1 + lam.size], lam, flow)
    return _fit_result(creep, young, a @ c, d, lam, "creep")


def _creep_from_relaxation(e_inf, ek, tau):
    """Interconversion: the compliance of E(t) = e_inf + sum ek exp(-t/tau), exactly.

    With M(s) = s L[E](s) = e_inf + sum ek s tau/(1 + s tau), s L[D](s) = 1/M(s), whose
    poles s_j = -1/lam_j (one between consecutive -1/tau_i, one in (-1/tau_max, 0) when
    e_inf > 0, else s = 0: a dashpot) give D = 1/E0 + sum D_j (1 - exp(-t/lam_j)) + t/eta,
    D_j = lam_j / M'(s_j) > 0, 1/eta = 1 / sum ek tau."""
    from scipy.optimize import brentq           # heavy; only the fits need it

    e0 = e_inf + ek.sum()
    if e0 <= 0:
        raise ValueError("the fit is not positive: every coefficient is zero")
    # a coefficient below 1e-9 E0 is the solver's tolerance, not the data: dropped (it has
    # no effect, its root would hug a pole, and a tiny E_inf would stand in for a dashpot)
    keep = ek > 1e-9 * e0
    ek, tau = ek[keep], tau[keep]
    e_inf = e_inf if e_inf > 1e-9 * e0 else 0.0
    if ek.size == 0:
        return ExponentialCreep(name="fit"), e0

    def m(x):                                   # M(-x), x = -s > 0
        return e_inf + np.sum(ek * (1.0 - 1.0 / (1.0 - x * tau)))

    def dm(x):                                  # M'(s) at s = -x
        return np.sum(ek * tau / (1.0 - x * tau) ** 2)

    poles = np.sort(1.0 / tau)                  # x = 1/tau_i, ascending
    edges = list(zip(poles[:-1], poles[1:]))
    if e_inf > 0:
        edges.insert(0, (0.0, poles[0]))
    lam, dj = [], []
    for lo, hi in edges:
        eps = 1e-12 * (hi - lo)
        # M(0) = e_inf > 0 is finite: the first bracket starts at 0 (its root may be tiny)
        x = brentq(m, lo + eps if lo > 0 else 0.0, hi - eps, xtol=1e-300, rtol=1e-15,
                   maxiter=500)
        lam.append(1.0 / x)
        dj.append((1.0 / x) / dm(x))
    flow = 0.0 if e_inf > 0 else 1.0 / np.sum(ek * tau)
    creep, young = _creep_from_compliance(1.0 / e0, np.array(dj), np.array(lam), flow)
    return creep, young


def fit_relaxation_modulus(t, modulus, *, terms_per_decade=2, times=None, noise=0.01):
    """Prony series fitted to a relaxation-modulus table, converted to a creep function.

    E(t) = E_inf + sum_i E_i exp(-t/tau_i) (generalised Maxwell) with fixed log-spaced
    tau_i and E_inf, E_i >= 0 (as :func:`fit_creep_compliance`), then converted exactly to
    the creep compliance (:func:`_creep_from_relaxation`: retardation times interlaced with
    the relaxation times; a dashpot when E_inf = 0).

    Parameters
    ----------
    t : array_like
        Times [s], ascending, >= 0 (at least 3).
    modulus : array_like
        E(t) = stress / strain under a constant strain [Pa], > 0, non-increasing.
    terms_per_decade : int
        Relaxation times per decade.
    times : array_like, optional
        The relaxation times [s] instead of the log-spaced ones.
    noise : float
        Relative increase of the data tolerated as measurement noise [1].

    Returns
    -------
    PronyFit
        phi normalised by E0 = E_inf + sum E_i; ``rms_error``, ``max_error`` of E(t).

    Raises
    ------
    ValueError
        As :func:`fit_creep_compliance` (here the data must not increase).
    """
    what = "relaxation modulus"
    t, (e,) = _fit_columns(what, t, [("the modulus", modulus)], positive_x=False)
    _check_monotone(what, t, e, -1, noise, "s")
    pos = t[t > 0]
    tau = _log_times(pos[0], pos[-1], terms_per_decade, times)
    a = np.column_stack([np.ones_like(t)] + [np.exp(-t / tk) for tk in tau])
    c = _nonnegative_fit(a, e)
    creep, young = _creep_from_relaxation(c[0], c[1:], tau)
    return _fit_result(creep, young, a @ c, e, tau, "relaxation")


def fit_dynamic_moduli(frequency, storage, loss, *, terms_per_decade=2, times=None,
                       noise=0.01):
    """Prony series fitted to storage and loss moduli over frequency (a DMA sweep).

    E'(w) = E_inf + sum_i E_i (w tau_i)^2 / (1 + (w tau_i)^2),
    E''(w) = sum_i E_i w tau_i / (1 + (w tau_i)^2), w = 2 pi f, with fixed log-spaced
    tau_i over 1/(2 pi f_max) .. 1/(2 pi f_min) and E_inf, E_i >= 0, both moduli fitted
    together (relative misfit), then converted to the creep function as
    :func:`fit_relaxation_modulus`.

    Parameters
    ----------
    frequency : array_like
        Frequencies f [Hz], ascending, > 0 (at least 3).
    storage, loss : array_like
        E'(f) and E''(f) [Pa], > 0; E' non-decreasing with f.
    terms_per_decade : int
        Relaxation times per decade.
    times : array_like, optional
        The relaxation times [s] instead of the log-spaced ones.
    noise : float
        Relative decrease of E' tolerated as measurement noise [1].

    Returns
    -------
    PronyFit
        ``rms_error``, ``max_error`` over E' and E'' together.

    Raises
    ------
    ValueError
        As :func:`fit_creep_compliance`.
    """
    what = "dynamic moduli"
    f, (e1, e2) = _fit_columns(what, frequency, [("the storage modulus", storage),
                                                 ("the loss modulus", loss)])
    _check_monotone("storage modulus", f, e1, +1, noise, "Hz")
    w = 2.0 * np.pi * f
    tau = _log_times(1.0 / w[-1], 1.0 / w[0], terms_per_decade, times)
    wt = w[:, None] * tau[None, :]
    a1 = np.column_stack([np.ones_like(w), wt ** 2 / (1.0 + wt ** 2)])
    a2 = np.column_stack([np.zeros_like(w), wt / (1.0 + wt ** 2)])
    a = np.vstack([a1, a2])
    data = np.concatenate([e1, e2])
    c = _nonnegative_fit(a, data)
    creep, young = _creep_from_relaxation(c[0], c[1:], tau)
    return _fit_result(creep, young, a @ c, data, tau, "dynamic")


# --------------------------------------------------------------------------- table files
#: What a material table file holds (``table_kind``): its columns and the fit it gets.
TABLE_KINDS = {
    "creep": ("time [s], creep compliance [1/Pa]", 2),
    "relaxation": ("time [s], relaxation modulus [Pa]", 2),
    "dynamic": ("frequency [Hz], storage modulus [Pa], loss modulus [Pa]", 3),
}


def read_table_file(path, kind: str) -> np.ndarray:
    """The columns of a material table file: text or CSV, one row per line, numbers
    separated by commas, semicolons, tabs or spaces; blank lines, lines starting with
    ``#`` and one header line of words at the top are skipped.

    Parameters
    ----------
    path : str
        The file.
    kind : {"creep", "relaxation", "dynamic"}
        What it holds (:data:`TABLE_KINDS`): 2, 2 and 3 columns.

    Returns
    -------
    ndarray (columns, rows)

    Raises
    ------
    ValueError
        Unreadable, or a row that is not that many numbers (naming the line).
    """
    return _parse_table(_read_text(path), path, kind)


def _read_text(path) -> str:
    try:
        with open(path, encoding="utf-8") as f:
            return f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"cannot read {path}: {getattr(e, 'strerror', None) or e}") from None


def _parse_table(text, path, kind) -> np.ndarray:
    what, ncol = TABLE_KINDS[kind]
    rows, header_ok = [], True
    for number, line in enumerate(text.splitlines(), start=1):
        row = line.strip()
        if not row or row.startswith("#"):
            continue
        items = row.replace(",", " ").replace(";", " ").split()
        try:
            values = [float(x) for x in items]
        except ValueError:
            if header_ok and not rows:
                header_ok = False                  # one header line of column names
                continue
            raise ValueError(f"{path}, line {number}: {row[:60]!r} is not {ncol} numbers "
                             f"({what})") from None
        if len(values) != ncol:
            raise ValueError(f"{path}, line {number}: {len(values)} columns, expected "
                             f"{ncol} ({what})")
        rows.append(values)
    if not rows:
        raise ValueError(f"{path}: no rows of numbers ({what})")
    return np.array(rows, dtype=float).T


@lru_cache(maxsize=32)
def _fit_text_cached(text, path, kind):
    cols = _parse_table(text, path, kind)
    if kind == "creep":
        return fit_creep_compliance(cols[0], cols[1])
    if kind == "relaxation":
        return fit_relaxation_modulus(cols[0], cols[1])
    return fit_dynamic_moduli(cols[0], cols[1], cols[2])


def fit_table_file(path, kind: str) -> PronyFit:
    """The Prony fit of a material table file (:func:`read_table_file`) by
    :func:`fit_creep_compliance`, :func:`fit_relaxation_modulus` or
    :func:`fit_dynamic_moduli`; cached by the file's content.

    Raises
    ------
    ValueError
        The file cannot be read, or its data or the fit are refused (not positive, not
        monotone).
    """
    if kind not in TABLE_KINDS:
        raise ValueError(f"table kind {kind!r}: allowed {', '.join(TABLE_KINDS)}")
    return _fit_text_cached(_read_text(path), os.fspath(path), kind)


def table_time_span(path, kind: str) -> float:
    """The time [s] up to which a table file's data reach: its last time (creep or
    relaxation), or 1/(2 pi f_min) (dynamic: the longest relaxation time it resolves)."""
    cols = read_table_file(path, kind)
    if kind == "dynamic":
        return float(1.0 / (2.0 * np.pi * cols[0].min()))
    return float(cols[0].max())


#: How a viscoelastic body's bulk modulus behaves: "creep" (it creeps with the shear
#: modulus, the same phi: a constant Poisson ratio, paper eq. 9) or "elastic".
BULK = ("creep", "elastic")


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
        Poisson ratio [1], in [0, 0.5]; with ``bulk = "elastic"`` its value where phi = 1.
    creep : ExponentialCreep or TabulatedCreep
        Normalised creep function phi(t); :data:`ELASTIC` for elastic or rigid bodies.
    bulk : {"creep", "elastic"}
        "creep" (default): every compliance creeps with phi, nu is constant (paper
        eq. 9). "elastic": phi is the shear compliance J(t)/J at phi = 1, the bulk
        modulus E/(3(1 - 2 nu)) does not creep, nu(t) varies (:func:`elastic_bulk_parts`).
    """

    kind: str = "elastic"
    young: float = np.inf
    poisson: float = 0.3
    creep: object = field(default=ELASTIC)
    bulk: str = "creep"

    @property
    def rigid(self) -> bool:
        return self.kind == "rigid"

    @property
    def has_memory(self) -> bool:
        return self.kind == "viscoelastic" and not self.creep.is_elastic

    @property
    def split(self) -> bool:
        """True when the Poisson ratio varies in time: the kernels split into a shear part
        and a Poisson part with their own creep functions (:attr:`part_creeps`)."""
        return self.has_memory and self.bulk == "elastic" and self.poisson < 0.5

    @property
    def part_creeps(self) -> tuple:
        """The normalised creep functions of the body's kernel parts [1]: (phi,) for a
        constant Poisson ratio (one kernel set, :func:`~contactpipe.solver.influence.body_kernels`),
        (phi_shear, phi_poisson) when :attr:`split`
        (:func:`~contactpipe.solver.influence.body_kernel_parts`)."""
        if self.split:
            return elastic_bulk_parts(self.creep, float(self.poisson))
        return (self.creep,)

    @property
    def normal_creep(self):
        """The normal compliance (1 - nu)/G as a creep function, normalised by its value
        where phi = 1 [1]: phi itself for a constant Poisson ratio. A rigid sphere's
        normal contact (Lee-Radok) depends on this function alone."""
        if not self.split:
            return self.creep
        shear, part = self.part_creeps
        return combine([(1.0 / (1.0 - self.poisson), shear),
                        (-1.0 / (1.0 - self.poisson), part)], "normal")

    @property
    def coupling_creep(self):
        """The coupling compliance (1 - 2 nu)/G as a creep function, normalised like
        :attr:`normal_creep` [1] (phi for a constant Poisson ratio)."""
        if not self.split:
            return self.creep
        shear, part = self.part_creeps
        w = 1.0 / (1.0 - 2.0 * self.poisson)
        return combine([(w, shear), (-2.0 * w, part)], "coupling")

    @property
    def rule_creeps(self) -> tuple:
        """The compliances a time rule must integrate well [1]: phi, and with a varying
        Poisson ratio the normal compliance too."""
        return (self.creep, self.normal_creep) if self.split else (self.creep,)

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
