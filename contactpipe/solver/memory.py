"""Viscoelastic memory: the Boltzmann sum of paper eq. (7) without O(Nt²) work.

With a constant Poisson ratio the viscoelastic influence coefficients factor as
KV(t) = φ(t)·K (paper eq. 9, φ the normalised creep function), so the displacement is one
spatial convolution of a *history traction* (pointwise in space, per traction component)

    H(t) = ∫_{0−}^{t} φ(t − s) dσ(s)

with the elastic kernel of the modulus that normalises φ. For
φ(t) = a + b t + Σ d_i exp(−t/τ_i) (Maxwell, Kelvin–Voigt, Zener, Prony, Burgers) write
c_i = −d_i and φ0 = φ(0) = a + Σ d_i; then

    H = φ0 σ + b I + Σ c_i ζ_i,    I′ = σ,    τ_i ζ_i′ + ζ_i = σ,    I(0) = ζ_i(0) = 0,

the strains of the dashpot and of the Kelvin elements (ζ_i is continuous where σ jumps).
A *time rule* integrates these ODEs on the uniform mesh t_k = kΔt; each of I, ζ_i then
obeys a recursion, so work and memory per step do not grow with k
(:class:`RecursiveMemory`). At step k the traction σ_k is unknown:
H(t_k) = c0·σ_k + H_known, where c0 is the *instantaneous weight* (it scales the kernels of
the inner problems) and ``H_known`` depends on the past only. The first instant t0 holds
the jump of the load: H(t0) = φ0 σ_0.

``"auto"`` (recommended)
    per body, "linear" where its traction error keeps its sign from step to step for this
    φ and Δt (:func:`is_monotone`, for a table :func:`linear_error_keeps_sign`; there it
    is the more accurate of the two), "bdf2" elsewhere: Kelvin–Voigt, stiff Zener/Prony
    terms, a dashpot with Δt ≳ 2t′, a table starting at 0 (:func:`resolve_rule`).
``"bdf2"`` (second order, L-stable, no negative amplification factor for any φ and Δt)
    exponentially fitted BDF2 on each ζ_i (exact when σ is linear over the last two
    steps, and BDF2 itself as Δt/τ_i → 0) and BDF2 on I. It uses the past of I and ζ_i
    only, never past tractions, so an error in σ — the concentrated load of a body without
    instantaneous elasticity at t0, a cell the contact front just crossed — is not carried
    to the next step: the traction error's amplification factor is 0 for Kelvin–Voigt
    (φ0 = 0) and small for stiff terms (E0/E∞ ≫ 1 with Δt ≳ τ/(E0/E∞)), where "linear"
    gives −1 (:func:`error_amplification`). A two-step formula needs a start, chosen
    when the state at t0 is known: after a jump (σ_0 ≠ 0), two exponential-Euler steps
    (σ held constant over the step: exact after a step load, L-stable, and blind to σ_0);
    without one (σ_0 = 0), one "linear" step (exact for a traction growing linearly from
    zero). Instantaneous weights: φ0 at t0, then that of the start,
    then φ0 + 2bΔt/3 + Σ c_i B0(Δt/τ_i) (:func:`fitted_bdf2_coefficients`).
    With ``fitted=False``: plain BDF2 started by two BDF1 steps, identical to Lubich's
    BDF2 convolution quadrature, which :class:`DirectMemory` applies to a tabulated φ.
``"linear"`` (second order, A- but not L-stable)
    the traction is linear between instants, the ODEs integrated exactly. For Kelvin–Voigt
    (φ0 = 0) and stiff terms its traction error changes sign every step and does not
    decay (amplification → −1): pressure holes and oscillation, docs/time-integration.md.
    Where it is monotone it is the most accurate rule here (the trapezoid's error
    constant 1/12 against BDF2's 2/9, and exact for a traction linear in time).
``"step_start"`` (the paper's rule, first order)
    each increment acts from the start of its step: W(k, n) = φ((k − n)Δt), explicit Euler
    in disguise: stable only for Δt < :func:`contactpipe.materials.step_start_stable_step`.

A tabulated φ needs the direct sum (:class:`DirectMemory`, O(k·N) work and memory per
step: offered, and said so).

A body whose Poisson ratio varies in time (a shear creep function with an elastic bulk
modulus, :func:`contactpipe.materials.elastic_bulk_parts`) has two kernel parts with their
own creep functions: :class:`BodyMemory` holds one recursion per part, all with the rule
:func:`resolve_body_rule` picks for the body. The rules are linear in φ and share their
coefficients per time constant, so the history of any combination of the parts (the
normal compliance (1 − ν)/G, the coupling one (1 − 2ν)/G) is the same combination of the
parts' histories, and the analysis above applies to those physical compliances.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..materials import ExponentialCreep

__all__ = ["RecursiveMemory", "DirectMemory", "BodyMemory", "make_memory", "TIME_RULES",
           "BDF2_START", "bdf2_weights", "fitted_bdf2_coefficients", "error_amplification",
           "is_monotone", "linear_error_keeps_sign", "resolve_rule",
           "resolve_body_rule"]

TIME_RULES = ("auto", "bdf2", "linear", "step_start")

#: Steps from t0 taken by the one-step start of rule "bdf2" before its two-step formula:
#: two, so that the BDF2 weights (3, −4, 1) meet a history that grows like a power of
#: (t − t0) only after two steps (3·3^α − 4·2^α + 1 ≥ 0 for 0 ≤ α ≤ 1). With one, the
#: Kelvin–Voigt centre (ζ ∝ t^{1/3} under a step load) gets a negative traction at t2.
BDF2_START = 2

#: The one-step starts of rule "bdf2" (:meth:`RecursiveMemory._choose_start`).
START_KINDS = ("exponential_euler", "linear", "bdf1")


def is_monotone(creep: ExponentialCreep, dt: float, rule: str) -> bool:
    """True when no amplification factor of the rule's traction error is negative (or
    complex with a negative real part): the error then never changes sign from one step
    to the next (:func:`error_amplification`). False when the rule cannot solve for the
    current traction, or the constants are beyond float64."""
    try:
        g = error_amplification(creep, dt, rule)
    except (ValueError, np.linalg.LinAlgError):
        return False      # no weight for the current traction, or constants beyond float64
    # |g| < 1e-6: a zero factor of a Jordan block, split by round-off into ±1e-8
    return bool(np.all((g.real >= -1e-12) | (np.abs(g) < 1e-6)))


def resolve_rule(creep, dt: float, rule: str) -> str:
    """The rule a memory applies: ``rule`` itself, or for "auto" "linear" where it is
    monotone for this creep function and step (:func:`is_monotone`; there the more accurate
    rule: Lee-Radok fields 1.3-3 times and the Maxwell fretting loop about 20 times closer,
    docs/time-integration.md) and "bdf2" elsewhere (Kelvin-Voigt, stiff terms, a dashpot
    with Δt > 2 t'). A tabulated φ is judged by :func:`linear_error_keeps_sign` (the
    error followed step by step): a table with instantaneous elasticity takes "linear",
    exact where φ is linear between the instants (a flat punch under a stepped W:
    ω3(t)/ω3(0) = φ(t), where plain BDF2 was 5 % off at five steps).

    Parameters
    ----------
    creep : ExponentialCreep or TabulatedCreep
        Normalised creep function.
    dt : float
        Time step [s].
    rule : {"auto", "bdf2", "linear", "step_start"}

    Returns
    -------
    str
        "bdf2", "linear" or "step_start".
    """
    if rule not in TIME_RULES:
        raise ValueError(f"time rule {rule!r}: allowed {', '.join(TIME_RULES)}")
    if rule != "auto":
        return rule
    if isinstance(creep, ExponentialCreep):
        monotone = is_monotone(creep, dt, "linear")
    else:
        monotone = linear_error_keeps_sign(creep, dt)
    return "linear" if monotone else "bdf2"


#: The most steps over which :func:`linear_error_keeps_sign` follows a table's error.
TABLE_HORIZON = 2048


@lru_cache(maxsize=64)
def linear_error_keeps_sign(creep, dt: float) -> bool:
    """True when rule "linear" keeps the sign of a traction error from step to step for
    the creep function ``creep`` (a table: no eigenvalues to take) and step ``dt``.

    The error's response is followed step by step: a traction error e_0 = 1 at some
    instant, the displacement held from then on, so that
    sum_{n <= k} w_{k-n} (e_n - e_{n-1}) = 0 for k >= 1 with w_m the mean of phi over
    [m dt, (m + 1) dt] (the rule's weights). After the first step (where the held
    displacement takes most of the error back) the error must not zigzag (change sign
    at two steps in a row): with little instantaneous elasticity (phi(0) small against
    phi's growth over a step: Kelvin-Voigt, a table starting at 0, stiff terms) it does,
    at every step. A lone change of sign, from a kink of the table (its end, where phi
    stops growing), is no alternation. Followed over the table's span (every step a run
    on it can take; at least 16 steps, at most :data:`TABLE_HORIZON`); errors below
    1e-9 of the first are not counted. On the exponential laws it agrees with
    :func:`is_monotone` except where a fast term's negative eigenvalue is too weak to
    turn the error's sign (there it says True).
    """
    last = float(getattr(creep, "last_time", 0.0))
    n = int(min(max(np.ceil(last / dt) + 2, 16), TABLE_HORIZON))
    edges = np.arange(n + 1) * dt
    w = np.atleast_1d(np.asarray(creep.mean(edges[:-1], edges[1:]), dtype=float))
    if not w[0] > 0.0:
        return False
    inc = np.zeros(n)
    inc[0] = 1.0
    for k in range(1, n):
        inc[k] = -np.dot(w[k:0:-1], inc[:k]) / w[0]
    err = np.cumsum(inc)[1:]
    signs = np.where(np.abs(err) > 1e-9, np.sign(err), 0.0)
    flips = signs[:-1] * signs[1:] < 0.0
    return not bool(np.any(flips[:-1] & flips[1:]))


def resolve_body_rule(creeps, dt: float, rule: str) -> str:
    """The rule of a body whose compliances are ``creeps`` (one rule for all its kernel
    parts): ``rule`` itself, or for "auto" "linear" when :func:`resolve_rule` gives it
    for every one of them, else "bdf2".

    Parameters
    ----------
    creeps : sequence of ExponentialCreep or TabulatedCreep
        The body's physical compliances (``Body.rule_creeps``: φ, and with a varying
        Poisson ratio the normal compliance too).
    dt : float
        Time step [s].
    rule : {"auto", "bdf2", "linear", "step_start"}
    """
    rules = {resolve_rule(c, dt, rule) for c in creeps}
    return rules.pop() if len(rules) == 1 else "bdf2"


def _phi1(x):
    """(1 − e^{−x})/x, stable for small x ≥ 0."""
    x = np.asarray(x, dtype=float)
    small = x < 1e-8
    safe = np.where(small, 1.0, x)
    return np.where(small, 1.0 - 0.5 * x, -np.expm1(-safe) / safe)


def _phi2(x):
    """(1 − (1 + x) e^{−x})/x², stable for small x ≥ 0 (series below 0.5)."""
    x = np.asarray(x, dtype=float)
    series = np.zeros_like(x)
    term = np.full_like(x, 0.5)                  # (−1)^n (n − 1) x^{n−2} / n!, n = 2
    for n in range(2, 24):
        series = series + term
        term = -term * x * n / ((n + 1) * (n - 1))
    safe = np.where(x < 0.5, 1.0, x)
    direct = (-np.expm1(-safe) - safe * np.exp(-safe)) / safe ** 2
    return np.where(x < 0.5, series, direct)


def fitted_bdf2_coefficients(x):
    """Exponentially fitted BDF2 for τ ζ′ + ζ = σ with x = Δt/τ: (A1, A2, B0) of
    ζ_k = A1 ζ_{k−1} + A2 ζ_{k−2} + B0 σ_k, exact when σ is linear over [t_{k−2}, t_k]
    (ζ = σ − τσ′ + C e^{−t/τ}). Tends to BDF2 (4/3, −1/3, 2x/3) as x → 0 and to BDF1
    as x → ∞ (stiff terms)."""
    x = np.asarray(x, dtype=float)
    lam = np.exp(-x)
    a1 = 4.0 * _phi2(2.0 * x) / (_phi2(x) + _phi1(x))
    a2 = lam * (lam - a1)
    return a1, a2, x * (a1 + 2.0 * a2)


class RecursiveMemory:
    """O(N)-per-step history for φ(t) = a + b t + Σ d_i exp(−t/τ_i).

    Parameters
    ----------
    creep : ExponentialCreep
        Normalised creep function.
    dt : float
        Time step [s] (uniform mesh).
    rule : {"auto", "bdf2", "linear", "step_start"}
        Time rule (module doc); "auto" is resolved here (:attr:`rule` holds the result).
    shape : tuple
        Shape of the traction array held (e.g. (3, N1, N2) for q1, q2, p).
    fitted : bool
        Rule "bdf2" only: exponentially fitted coefficients for the Kelvin terms and the
        adaptive start (default; module doc). False gives plain BDF2 started by two BDF1
        steps, the scheme :class:`DirectMemory` applies to any φ.

    Notes
    -----
    Every rule is a two-step recursion per internal variable y (I, or ζ_i with time
    constant τ_i), for k ≥ 1::

        y_k = A1 y_{k−1} + A2 y_{k−2} + B1 σ_{k−1} + B0 σ_k

    with coefficients that depend on the rule and, for "bdf2", on whether k is one of the
    first steps (:meth:`coefficients`, :attr:`start`).
    """

    def __init__(self, creep: ExponentialCreep, dt: float, rule: str, shape, *,
                 fitted: bool = True):
        rule = resolve_rule(creep, dt, rule)
        self.creep, self.dt, self.rule, self.shape = creep, float(dt), rule, tuple(shape)
        self.fitted = bool(fitted)
        self.tau = np.asarray(creep.tau, dtype=float)
        self.c = -np.asarray(creep.d, dtype=float)
        self.b = float(creep.b)
        self.phi0 = float(creep.phi0)
        self.start = "exponential_euler" if self.fitted else "bdf1"
        self.weight0 = self.phi0                 # weight of the jump at the first instant
        self.weight = self._weight(self.coefficients(BDF2_START + 1))   # from then on
        self.k = 0                               # instants committed
        n = len(self.tau)
        self._zeta = np.zeros((2, n) + self.shape)       # ζ_i at k−1, k−2
        self._integral = np.zeros((2,) + self.shape)     # I at k−1, k−2
        self._prev = np.zeros(self.shape)                # σ_{k−1}
        self._parts: tuple | None = None                 # (k, ζ_k, I_k) less σ_k's terms

    # -- the scheme ---------------------------------------------------------------------
    def _choose_start(self, sigma0):
        """Rule "bdf2", fitted: the one-step start, chosen when the state at t0 is known.

        After a jump (σ_0 ≠ 0: a step load) two exponential-Euler steps: σ held constant
        over the step, exact for a constant traction, L-stable, and blind to σ_0 — the
        concentrated load of a body without instantaneous elasticity, or a glassy response
        that relaxes within the step. Without a jump (the traction grows from zero) one
        exponential-trapezoid ("linear") step, exact for a linear growth (measured in
        docs/time-integration.md: a ramp's a³ error drops from 45 % to 1.2 % at 10 steps)."""
        if self.rule != "bdf2" or not self.fitted:
            return
        self.start = "exponential_euler" if np.any(sigma0) else "linear"

    @property
    def start_steps(self) -> int:
        """Steps taken by the one-step start of rule "bdf2" (1 or :data:`BDF2_START`)."""
        return 1 if self.start == "linear" else BDF2_START

    def coefficients(self, k: int):
        """(A1, A2, B1, B0) of the step to instant k ≥ 1: arrays over the exponential
        terms for ζ_i, then a tuple of four floats for the integral I (b term)."""
        h, tau = self.dt, self.tau
        x = h / tau
        lam = np.exp(-x)
        zero = np.zeros_like(tau)
        if self.rule == "step_start":
            return (lam, zero, 1.0 - lam, zero), (1.0, 0.0, h, 0.0)
        if self.rule == "linear" or (k <= self.start_steps and self.start == "linear"):
            gam = _phi1(x)                                # (1 − λ) τ/Δt
            return (lam, zero, gam - lam, 1.0 - gam), (1.0, 0.0, 0.5 * h, 0.5 * h)
        if k <= self.start_steps:                         # from the jump at t0
            if self.start == "exponential_euler":
                return (lam, zero, zero, x * _phi1(x)), (1.0, 0.0, 0.0, h)
            return (1.0 / (1.0 + x), zero, zero, x / (1.0 + x)), (1.0, 0.0, 0.0, h)
        integral = (4.0 / 3.0, -1.0 / 3.0, 0.0, 2.0 * h / 3.0)
        if self.fitted:
            a1, a2, b0 = fitted_bdf2_coefficients(x)
            return (a1, a2, zero, b0), integral
        den = 3.0 + 2.0 * x
        return (4.0 / den, -1.0 / den, zero, 2.0 * x / den), integral

    def _weight(self, coef) -> float:
        (_, _, _, b0), (_, _, _, f0) = coef
        return self.phi0 + self.b * f0 + float(np.dot(self.c, b0))

    @property
    def instant_weight(self) -> float:
        """c0 of the next instant to solve (it can differ at t0, t1 and later)."""
        if self.k == 0:
            return self.weight0
        return self._weight(self.coefficients(self.k))

    def _known_parts(self):
        """(ζ_k, I_k) less their σ_k terms: the past's share, kept for the instant k it was
        formed for, so that :meth:`known` and :meth:`commit` of one instant form it once."""
        if self._parts is not None and self._parts[0] == self.k:
            return self._parts[1], self._parts[2]
        (a1, a2, b1, _), (e1, e2, f1, _) = self.coefficients(self.k)
        ex = (slice(None),) + (None,) * len(self.shape)
        zeta = a1[ex] * self._zeta[0] + a2[ex] * self._zeta[1] + b1[ex] * self._prev
        integral = e1 * self._integral[0] + e2 * self._integral[1] + f1 * self._prev
        self._parts = (self.k, zeta, integral)
        return zeta, integral

    def _advance(self, sigma):
        """(ζ_k, I_k) from the state and σ_k: the past's share plus σ_k's terms, summed in
        the order A1 y_{k−1} + A2 y_{k−2} + B1 σ_{k−1} + B0 σ_k."""
        (_, _, _, b0), (_, _, _, f0) = self.coefficients(self.k)
        ex = (slice(None),) + (None,) * len(self.shape)
        zeta, integral = self._known_parts()
        return zeta + b0[ex] * sigma, integral + f0 * sigma

    def known(self) -> np.ndarray:
        """H_known for the next instant [Pa] (the part of H not multiplied by σ_k)."""
        if self.k == 0:
            return np.zeros(self.shape)
        zeta, integral = self._known_parts()
        return self.b * integral + np.tensordot(self.c, zeta, axes=(0, 0))

    def commit(self, sigma: np.ndarray) -> None:
        """Record the solved traction of the current instant [Pa]."""
        sigma = np.asarray(sigma, dtype=float).reshape(self.shape)
        if self.k == 0:
            self._choose_start(sigma)
        else:
            zeta, integral = self._advance(sigma)
            self._zeta = np.stack([zeta, self._zeta[0]])
            self._integral = np.stack([integral, self._integral[0]])
        self._prev = sigma.copy()
        self.k += 1

    def history(self) -> np.ndarray:
        """H at the last committed instant [Pa] (for checks)."""
        return (self.phi0 * self._prev + self.b * self._integral[0]
                + np.tensordot(self.c, self._zeta[0], axes=(0, 0)))

    def state(self) -> dict:
        """Arrays that fully describe the memory (for checkpoints)."""
        return {"k": self.k, "zeta": self._zeta, "integral": self._integral,
                "prev": self._prev, "start": START_KINDS.index(self.start)}

    def load_state(self, state) -> None:
        """Restore what :meth:`state` gave."""
        self.k = int(state["k"])
        self.start = START_KINDS[int(state["start"])]
        self._zeta = np.array(state["zeta"], dtype=float)
        self._integral = np.array(state["integral"], dtype=float)
        self._prev = np.array(state["prev"], dtype=float)
        self._parts = None


def error_amplification(creep: ExponentialCreep, dt: float, rule: str, *,
                        fitted: bool = True) -> np.ndarray:
    """Amplification factors of a traction error under a fixed history H (the contact
    region's displacement held), for the steady recursion of a rule (after its start).

    The error obeys the recursion of :class:`RecursiveMemory` with H = 0: with the state
    (ζ_{k−1}, ζ_{k−2}, I_{k−1}, I_{k−2}, σ_{k−1}) (I only with a dashpot), σ_k solves
    φ0 σ_k + b I_k + Σ c_i ζ_{i,k} = 0. Returns the eigenvalues of that linear map
    (complex, sorted by decreasing modulus); the error is stable when they lie in the
    closed unit disc (a root 1 is the neutral mode of the dashpot), and alternates from
    step to step when the largest is negative. Test model for docs/time-integration.md.

    Parameters
    ----------
    creep : ExponentialCreep
        Normalised creep function.
    dt : float
        Time step [s].
    rule : {"bdf2", "linear", "step_start"}
    fitted : bool
        Rule "bdf2": exponentially fitted (default) or plain.

    Returns
    -------
    ndarray
        The eigenvalues [1].
    """
    m = RecursiveMemory(creep, dt, rule, (), fitted=fitted)
    (a1, a2, b1, b0), (e1, e2, f1, f0) = m.coefficients(BDF2_START + 1)
    weight = m._weight(m.coefficients(BDF2_START + 1))
    if weight <= 0.0:
        raise ValueError(f"time rule {rule!r} with phi(0) = {m.phi0:g}: the current "
                         f"traction has no weight, the rule cannot solve for it")
    n = len(m.tau)
    dashpot = 2 if m.b != 0.0 else 0           # I only matters with a dashpot
    size = 2 * n + dashpot + 1
    z1, z2, s1 = slice(0, n), slice(n, 2 * n), size - 1
    # the parts of ζ_k and I_k that do not depend on σ_k, as rows over the state
    zk = np.zeros((n, size))
    zk[:, z1] = np.diag(a1)
    zk[:, z2] = np.diag(a2)
    zk[:, s1] = b1
    ik = np.zeros(size)
    if dashpot:
        ik[[2 * n, 2 * n + 1, s1]] = (e1, e2, f1)
    sigma = -(m.b * ik + m.c @ zk) / weight
    step = np.zeros((size, size))
    step[z1] = zk + np.outer(b0, sigma)
    step[z2, z1] = np.eye(n)
    if dashpot:
        step[2 * n] = ik + f0 * sigma
        step[2 * n + 1, 2 * n] = 1.0
    step[s1] = sigma
    g = np.linalg.eigvals(step)
    return g[np.argsort(-np.abs(g), kind="stable")]


# --------------------------------------------------------------------------- direct sum
def bdf2_weights(transform, dt: float, count: int):
    """Convolution-quadrature weights of plain BDF2 started by two BDF1 steps (Lubich).

    For K(s) = ∫_{0−}^∞ e^{−st} dφ(t) (the creep object's ``stieltjes``) this scheme
    gives, for k ≥ 1 (σ_0 at t0 enters only through H_0 = φ0 σ_0)::

        H_k = Σ_{n=3}^{k} ω_{k−n} σ_n + ω²_{k−2} σ_2 + ω¹_{k−1} σ_1

    with Σ ω_j z^j = K(δ/Δt), δ(z) = (1 − z)(3 − z)/2 (BDF2); the impulses at the two
    BDF1 steps continue under BDF2, which gives, with K1 = K(1/Δt), K1′ = K′(1/Δt),
    D1 = (K(δ/Δt) − K1)/(1 − δ) and D2 = (D1 + K1′/Δt)/(1 − δ)::

        Σ ω²_j z^j = F = K(δ/Δt) + D1/2,      Σ ω¹_j z^j = F + z (D2/2 − D1).

    (Per Kelvin term, K = μ/(s + μ), these are the responses of the recursion; |1 − δ| ≥ 1
    on the unit circle, and the singularities at δ = 1 are removable.) The coefficients
    are taken by the FFT on a circle of radius ρ with ρ^count = 1e-5 (round-off about
    1e-11 of max|K|, aliasing 1e-10); K1′ by a complex step.

    Parameters
    ----------
    transform : callable
        K(s) for complex s with Re s > 0 [1], real on the real axis.
    dt : float
        Time step [s].
    count : int
        Number of weights wanted (lags 0 .. count − 1).

    Returns
    -------
    (ndarray, ndarray, ndarray)
        ω, ω¹, ω², each of length ``count`` [1].
    """
    count = max(int(count), 4)
    L = 2 * count
    rho = 1e-5 ** (1.0 / count)
    z = rho * np.exp(2j * np.pi * np.arange(L) / L)
    delta = 0.5 * (1.0 - z) * (3.0 - z)
    k_delta = np.asarray(transform(delta / dt), dtype=complex)
    s1, eps = 1.0 / dt, 1e-20 / dt
    k1 = complex(np.asarray(transform(np.array([s1 + 0j])))[0]).real
    k1_prime = complex(np.asarray(transform(np.array([s1 + 1j * eps])))[0]).imag / eps
    d1 = (k_delta - k1) / (1.0 - delta)
    d2 = (d1 + k1_prime / dt) / (1.0 - delta)
    second = k_delta + 0.5 * d1
    first = second + z * (0.5 * d2 - d1)
    scale = rho ** -np.arange(count)
    return tuple((np.fft.fft(g) / L).real[:count] * scale for g in (k_delta, first, second))


class DirectMemory:
    """Direct Boltzmann sum for any creep function (e.g. tabulated): O(k·N) per step.

    Keeps every past traction (or increment); use :class:`RecursiveMemory` whenever φ is
    a sum of exponentials and a linear term. The rule "bdf2" is plain BDF2 started by
    two BDF1 steps (exponential fitting needs exponential terms), as a convolution
    quadrature of the creep object's Laplace–Stieltjes transform ``stieltjes(s)``
    (:func:`bdf2_weights`): it equals ``RecursiveMemory(..., fitted=False)``.
    """

    def __init__(self, creep, dt: float, rule: str, shape):
        rule = resolve_rule(creep, dt, rule)
        self.creep, self.dt, self.rule, self.shape = creep, float(dt), rule, tuple(shape)
        self.weight0 = float(creep.phi0)
        self._w = self._w1 = self._w2 = np.zeros(0)
        if rule == "bdf2":
            self._grow(64)
            self.weight = float(self._w[0])
        elif rule == "linear":
            self.weight = float(np.asarray(self._mean(0)))
        else:
            self.weight = self.weight0
        self.k = 0
        self._past: list = []    # increments (linear, step_start) or tractions (bdf2)
        self._prev = np.zeros(self.shape)

    def _grow(self, count):
        if count > len(self._w):
            self._w, self._w1, self._w2 = bdf2_weights(self.creep.stieltjes, self.dt,
                                                       max(count, 2 * len(self._w)))

    def _mean(self, m):
        """Weight of a ramp increment m steps back (linear rule)."""
        return self.creep.mean(m * self.dt, (m + 1) * self.dt)

    @property
    def instant_weight(self) -> float:
        if self.k == 0:
            return self.weight0
        if self.rule == "bdf2" and self.k <= BDF2_START:
            return float(self._w1[0])
        return self.weight

    def known(self) -> np.ndarray:
        k = self.k
        if k == 0:
            return np.zeros(self.shape)
        if self.rule == "bdf2":
            self._grow(k + 1)
            out = np.zeros(self.shape)
            start = {1: self._w1, 2: self._w2}
            for n, s in enumerate(self._past[1:], start=1):
                out = out + start.get(n, self._w)[k - n] * s
            return out
        out = -self.weight * self._prev
        for n, inc in enumerate(self._past):
            if n == 0 or self.rule == "step_start":
                w = float(self.creep((k - n) * self.dt))
            else:
                w = float(np.asarray(self._mean(k - n)))
            out = out + w * inc
        return out

    def state(self) -> dict:
        past = np.stack(self._past) if self._past else np.zeros((0,) + self.shape)
        return {"k": self.k, "past": past, "prev": self._prev}

    def load_state(self, state) -> None:
        self.k = int(state["k"])
        self._past = list(np.array(state["past"], dtype=float))
        self._prev = np.array(state["prev"], dtype=float)

    def commit(self, sigma: np.ndarray) -> None:
        sigma = np.asarray(sigma, dtype=float).reshape(self.shape)
        self._past.append(sigma.copy() if self.rule == "bdf2" else sigma - self._prev)
        self._prev = sigma.copy()
        self.k += 1


class BodyMemory:
    """The memories of one body's kernel parts (one recursion per distinct creep function),
    seen as one memory: the weights are tuples and :meth:`known` a list, one per part.

    Parameters
    ----------
    parts : sequence
        :class:`RecursiveMemory` (or :class:`DirectMemory`) objects, all with one rule.
    """

    def __init__(self, parts):
        self.parts = list(parts)
        self.rule = self.parts[0].rule

    @property
    def k(self) -> int:
        return self.parts[0].k

    @property
    def weight0(self) -> tuple:
        return tuple(float(m.weight0) for m in self.parts)

    @property
    def weight(self) -> tuple:
        return tuple(float(m.weight) for m in self.parts)

    @property
    def instant_weight(self) -> tuple:
        return tuple(float(m.instant_weight) for m in self.parts)

    def known(self) -> list:
        """H_known of each part for the next instant [Pa]."""
        return [m.known() for m in self.parts]

    def commit(self, sigma) -> None:
        for m in self.parts:
            m.commit(sigma)

    def state(self) -> dict:
        return {f"part{j}_{key}": v for j, m in enumerate(self.parts)
                for key, v in m.state().items()}

    def load_state(self, state) -> None:
        for j, m in enumerate(self.parts):
            prefix = f"part{j}_"
            m.load_state({key[len(prefix):]: v for key, v in state.items()
                          if key.startswith(prefix)})


def make_memory(creep, dt, rule, shape):
    """The cheapest exact memory for a creep function."""
    if isinstance(creep, ExponentialCreep):
        return RecursiveMemory(creep, dt, rule, shape)
    return DirectMemory(creep, dt, rule, shape)
