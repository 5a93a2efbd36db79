"""Tangential contact of elastic spheres: Cattaneo-Mindlin and Mindlin-Deresiewicz.

Hertzian normal pressure, no normal-tangential coupling (Dundurs beta = 0), load along x1.
References: Johnson (1985) §7.2-7.3; Mindlin & Deresiewicz (1953); Jaeger (1998) for
histories by superposition (Masing). Force control, and displacement control (a fretting
rig's), where the contact may slide as a whole (gross slip). SI units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

from ..exceptions import GrossSlidingError
from ._common import masing_loop, sqrt_plus

#: Fouvry's energy ratio A = E / (4 T* delta*) at the partial / gross slip transition of a
#: sphere on a plane; :func:`energy_ratio` gives exactly this value at delta* = delta_gs.
ENERGY_RATIO_TRANSITION = 0.2

__all__ = ["CattaneoMindlin", "cattaneo_mindlin", "masing_memory",
           "mindlin_deresiewicz_traction", "stick_radius", "tangential_displacement",
           "energy_per_cycle", "gross_slip_displacement", "mindlin_force",
           "displacement_loop_force", "displacement_energy_per_cycle", "gross_slip_boundary",
           "energy_ratio", "ENERGY_RATIO_TRANSITION"]


# --------------------------------------------------------------------------- Cattaneo
def _check_partial_slip(t, mu_w):
    if not mu_w > 0:
        raise ValueError(f"mu W must be > 0 [N], got {mu_w!r}")
    t = np.asarray(t, float)
    if np.any(np.abs(t) > mu_w * (1.0 + 1e-12)):
        raise GrossSlidingError(
            f"|T| = {np.max(np.abs(t)):.6g} N exceeds mu W = {mu_w:.6g} N: gross sliding, "
            "no partial-slip solution")


def _circle(force, mu_w, a):
    """Stick radius of a Cattaneo distribution carrying |force| [m]."""
    return a * np.clip(1.0 - np.abs(force) / mu_w, 0.0, 1.0) ** (1.0 / 3.0)


def _cattaneo_q(r, force, mu, mu_w, a, p0):
    """Signed Cattaneo traction carrying ``force`` [N]: sign * mu p0/a [sqrt(a^2-r^2)
    - sqrt(c^2-r^2)], c = a (1 - |force|/mu W)^(1/3)."""
    c = _circle(force, mu_w, a)
    return np.sign(force) * mu * p0 / a * (sqrt_plus(a, r) - sqrt_plus(c, r))


@dataclass(frozen=True)
class CattaneoMindlin:
    """Cattaneo-Mindlin partial slip under a monotonically applied force T, [J85]_ §7.2.

    Attributes
    ----------
    tangential_force : float
        T [N] along x1, |T| <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        a [m].
    max_pressure : float
        p0 [Pa].
    stick_radius : float
        c = a (1 - |T| / (mu W))^(1/3) [m].
    """

    tangential_force: float
    friction_coefficient: float
    normal_force: float
    contact_radius: float
    max_pressure: float
    stick_radius: float

    def traction(self, r):
        """q1(r) [Pa] = sign(T) mu p0/a [sqrt(a^2 - r^2) - sqrt(c^2 - r^2) (r < c)]."""
        return _cattaneo_q(np.asarray(r, float), self.tangential_force,
                           self.friction_coefficient,
                           self.friction_coefficient * self.normal_force,
                           self.contact_radius, self.max_pressure)


def cattaneo_mindlin(tangential_force, friction_coefficient, normal_force,
                     contact_radius, max_pressure) -> CattaneoMindlin:
    """Cattaneo (1938) - Mindlin (1949) solution, monotonic loading 0 -> T.

    ``c = a (1 - |T|/(mu W))^(1/3)`` and ``q(r) = mu p0/a [sqrt(a^2 - r^2) -
    sqrt(c^2 - r^2)]`` ([J85]_ §7.2); q carries T because
    ``int mu p0/a sqrt(c^2 - r^2) dA = mu W (c/a)^3``, which requires the Hertz
    relation p0 = 3W / (2 pi a^2) between the inputs.

    Parameters
    ----------
    tangential_force : float
        T [N] along x1, |T| <= mu W (:class:`GrossSlidingError` otherwise).
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    max_pressure : float
        Hertz maximum pressure p0 [Pa].

    Returns
    -------
    CattaneoMindlin
    """
    mu_w = friction_coefficient * normal_force
    _check_partial_slip(tangential_force, mu_w)
    return CattaneoMindlin(float(tangential_force), float(friction_coefficient),
                           float(normal_force), float(contact_radius), float(max_pressure),
                           float(_circle(tangential_force, mu_w, contact_radius)))


# --------------------------------------------------------------------------- Mindlin-Deresiewicz
def masing_memory(history):
    """Reversal points still remembered after a tangential force history [N].

    The body starts virgin at T = 0 and follows ``0 -> history[0] -> history[1] ...``,
    linearly (hence monotonically) between samples. A reversal point is pushed when
    the direction changes. Memory is wiped (Masing's rules, [MD53]_, [Ja98]_) when the
    current branch, started at the last reversal T_n, passes the previous one
    T_(n-1): the pair (T_(n-1), T_n) is erased and the branch continues the older
    one. The first reversal T_1 (reached on the virgin curve) is erased when the
    force reaches -T_1, after which the virgin curve is followed again.

    Parameters
    ----------
    history : array_like
        1-D tangential force samples [N], up to and including the current instant.

    Returns
    -------
    reversals : tuple of float
        Remembered reversal points (T_1, ..., T_n) [N] (empty on the virgin curve).
    current : float
        The current force T [N] (``history[-1]``, 0 for an empty history).
    """
    rev, t = (), 0.0
    for state in _memory_states(history):
        rev, t = state                    # keep the last state
    return rev, t


def _memory_states(history):
    """Yield (reversals, current force) after each sample of ``history``."""
    stack: list = []
    prev, direction = 0.0, 0
    for t in np.atleast_1d(np.asarray(history, float)).ravel():
        t = float(t)
        if t != prev:
            d = 1 if t > prev else -1
            if direction != 0 and d != direction:
                stack.append(prev)
            direction = d
            while True:
                if len(stack) >= 2 and d * (t - stack[-2]) >= 0.0:
                    del stack[-2:]
                elif len(stack) == 1 and d * (t + stack[0]) >= 0.0:
                    stack.pop()
                else:
                    break
            prev = t
        yield tuple(stack), prev


def _masing_terms(history):
    """(weight, force) of the superposed Cattaneo terms of the current state.

    Virgin: [(1, T)]. Otherwise [(1, T_1), (2, (T_2 - T_1)/2), ...,
    (2, (T - T_n)/2)]: each reversal adds twice the monotonic solution for half the
    force change since that reversal.
    """
    return _terms_of_state(*masing_memory(history))


def _terms_of_state(rev, t):
    if not rev:
        return [(1.0, t)]
    points = list(rev) + [t]
    terms = [(1.0, rev[0])]
    for k in range(len(points) - 1):
        terms.append((2.0, 0.5 * (points[k + 1] - points[k])))
    return terms


def mindlin_deresiewicz_traction(r, history, friction_coefficient, normal_force,
                                 contact_radius, max_pressure):
    """Tangential traction q1(r) [Pa] at the last instant of a force history.

    Superposition of Cattaneo distributions ([MD53]_, [J85]_ §7.3, [Ja98]_): with
    ``C(r; F) = sign(F) mu p0/a [sqrt(a^2 - r^2) - sqrt(c(F)^2 - r^2)]``,
    ``c(F) = a (1 - |F|/mu W)^(1/3)`` (the monotonic solution carrying F),

    * virgin loading 0 -> T: ``q = C(r; T)``;
    * after reversals T_1 .. T_n (see :func:`masing_memory`):
      ``q = C(r; T_1) + sum_k 2 C(r; (T_(k+1) - T_k)/2)`` with T_(n+1) = T.

    E.g. unloading from T* > 0 to T: with c* = c(T*), c' = a(1 - (T* - T)/(2 mu W))^(1/3),
    ``q = -mu p0/a [sqrt(a^2 - r^2) - 2 sqrt(c'^2 - r^2) + sqrt(c*^2 - r^2)]``, which
    carries T ([J85]_ §7.3; the minus sign is that of an unloading increment:
    q = -mu p in the new slip annulus c' < r < a).

    Parameters
    ----------
    r : array_like
        Radii [m].
    history : array_like
        Tangential force samples T [N] (along x1), up to the current instant; the
        body starts virgin at T = 0. All |T| <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    max_pressure : float
        Hertz maximum pressure p0 = 3W/(2 pi a^2) [Pa].

    Returns
    -------
    ndarray
        q1(r) [Pa], with the sign convention of ``docs/conventions.md``.
    """
    mu_w = friction_coefficient * normal_force
    _check_partial_slip(history, mu_w)
    r = np.asarray(r, float)
    q = np.zeros(r.shape)
    for w, f in _masing_terms(history):
        q = q + w * _cattaneo_q(r, f, friction_coefficient, mu_w, contact_radius,
                                max_pressure)
    return q


def stick_radius(history, friction_coefficient, normal_force, contact_radius) -> float:
    """Radius of the current stick zone [m] after a tangential force history.

    The slip annulus of the current branch is ``c_cur < r < a`` with
    ``c_cur = a (1 - |T|/mu W)^(1/3)`` on the virgin curve and
    ``c_cur = a (1 - |T - T_n|/(2 mu W))^(1/3)`` after the last remembered reversal T_n.
    Inside c_cur nothing slips in the current increment (stick, Delta s = 0).
    ``c_cur`` is the largest of the circles of the remembered branches; the smallest
    (that of the first term) bounds the zone that has never slipped. Equals ``a``
    exactly at a reversal.

    Parameters
    ----------
    history : array_like
        Tangential force samples [N] (see :func:`mindlin_deresiewicz_traction`).
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        a [m].

    Returns
    -------
    float
        c_cur [m].
    """
    mu_w = friction_coefficient * normal_force
    _check_partial_slip(history, mu_w)
    _, f = _masing_terms(history)[-1]
    return float(_circle(f, mu_w, contact_radius))


def _mindlin_delta(force, mu_w, a, compliance_sum):
    """Signed monotonic (virgin) displacement: 3 mu W C/(16 a) [1 - (1 - |F|/mu W)^(2/3)]."""
    x = np.clip(1.0 - np.abs(force) / mu_w, 0.0, 1.0)
    return np.sign(force) * 3.0 * mu_w * compliance_sum / (16.0 * a) * (1.0 - x ** (2.0 / 3.0))


def tangential_displacement(history, friction_coefficient, normal_force, contact_radius,
                            compliance_sum, all_instants: bool = False):
    """Tangential rigid displacement omega1 [m] of body 1 relative to body 2.

    Mindlin's virgin curve ([J85]_ §7.2)
    ``delta(T) = 3 mu W/(16 a) * compliance_sum * [1 - (1 - T/mu W)^(2/3)]``
    and its Masing branches ([MD53]_, [J85]_ §7.3): with the remembered
    reversals T_1 .. T_n, ``delta = delta(T_1) + sum_k 2 delta((T_(k+1) - T_k)/2)``,
    e.g. ``delta = delta* - 2 delta((T* - T)/2)`` on unloading from T*.

    Parameters
    ----------
    history : array_like
        Tangential force samples T [N], body virgin at T = 0, |T| <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    compliance_sum : float
        ``(2 - nu1)/G1 + (2 - nu2)/G2`` [1/Pa] (0 for two rigid bodies), see
        :func:`tangential_compliance_sum`.
    all_instants : bool, optional
        Return the displacement at every sample of ``history`` (one pass) instead of
        at the last one only.

    Returns
    -------
    float or ndarray
        omega1 [m], same sign as T on the virgin curve.
    """
    mu_w = friction_coefficient * normal_force
    hist = np.atleast_1d(np.asarray(history, float)).ravel()
    _check_partial_slip(hist, mu_w)

    def value(state):
        return float(sum(w * _mindlin_delta(f, mu_w, contact_radius, compliance_sum)
                         for w, f in _terms_of_state(*state)))

    if not all_instants:
        return value(masing_memory(hist))
    return np.array([value(state) for state in _memory_states(hist)])


def energy_per_cycle(amplitude, friction_coefficient, normal_force, contact_radius,
                     compliance_sum) -> float:
    """Energy dissipated per full cycle T = +-T* [J] (area of the delta-T loop).

    Integrating the Masing branches, ``E = 4 T* delta(T*) - 8 int_0^T* delta(x) dx``,
    which gives (cf. [J85]_ eq. 7.64, [MD53]_), with tau = T*/(mu W),

    ``E = 9 mu^2 W^2 C / (10 a) * [1 - (1 - tau)^(5/3) - (5 tau / 6)(1 + (1 - tau)^(2/3))]``

    where C is ``compliance_sum``. For small amplitude ``E ~ C T*^3 / (36 a mu W)``.

    Parameters
    ----------
    amplitude : float
        T* [N], 0 <= T* <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    compliance_sum : float
        ``(2 - nu1)/G1 + (2 - nu2)/G2`` [1/Pa].

    Returns
    -------
    float
        Dissipated energy per cycle [J].
    """
    mu_w = friction_coefficient * normal_force
    amplitude = abs(float(amplitude))
    _check_partial_slip(amplitude, mu_w)
    tau = amplitude / mu_w
    s = max(1.0 - tau, 0.0)
    bracket = 1.0 - s ** (5.0 / 3.0) - 5.0 * tau / 6.0 * (1.0 + s ** (2.0 / 3.0))
    return float(9.0 * mu_w ** 2 * compliance_sum / (10.0 * contact_radius) * bracket)




# --------------------------------------------------------------------------- displacement control
def gross_slip_displacement(friction_coefficient, normal_force, contact_radius,
                            compliance_sum) -> float:
    """Displacement at which the contact starts to slide as a whole [m].

    Mindlin's virgin curve reaches T = mu W at ``delta_gs = 3 mu W C / (16 a)``, C the
    compliance sum ``(2 - nu1)/G1 + (2 - nu2)/G2`` ([J85]_ §7.2); for identical bodies
    ``delta_gs = 3 mu W (2 - nu) / (8 G a)``.

    Parameters
    ----------
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    compliance_sum : float
        C [1/Pa] (:func:`tangential_compliance_sum`).
    """
    return 3.0 * friction_coefficient * normal_force * compliance_sum / (16.0 * contact_radius)


def _virgin_force(delta, mu_w, d_gs):
    """Signed T(delta) on the virgin curve: mu W [1 - (1 - |delta|/delta_gs)^(3/2)],
    mu W beyond delta_gs (gross slip)."""
    x = np.clip(1.0 - np.abs(delta) / d_gs, 0.0, 1.0)
    return np.sign(delta) * mu_w * (1.0 - x ** 1.5)


def mindlin_force(displacement, friction_coefficient, normal_force, contact_radius,
                  compliance_sum):
    """Tangential force on the first branch under displacement control [N].

    Inverting Mindlin's virgin curve ([J85]_ §7.2, :func:`tangential_displacement`):
    ``T = mu W [1 - (1 - delta/delta_gs)^(3/2)]`` for ``|delta| <= delta_gs``
    (:func:`gross_slip_displacement`), and ``T = mu W`` (gross slip) beyond; odd in delta.

    Parameters
    ----------
    displacement : float or array_like
        delta = omega1 [m], from rest.
    friction_coefficient, normal_force, contact_radius, compliance_sum
        mu [1], W [N], a [m], C [1/Pa].

    Returns
    -------
    float or ndarray
        T [N], with the sign of delta.
    """
    mu_w = friction_coefficient * normal_force
    d_gs = gross_slip_displacement(friction_coefficient, normal_force, contact_radius,
                                   compliance_sum)
    out = _virgin_force(np.asarray(displacement, float), mu_w, d_gs)
    return float(out) if np.ndim(out) == 0 else out


def displacement_loop_force(history, friction_coefficient, normal_force, contact_radius,
                            compliance_sum):
    """Tangential force [N] at every sample of a displacement history (Mindlin-Deresiewicz
    under displacement control, with gross slip).

    Masing's rules in displacement: from the last remembered reversal (delta_r, T_r) the
    branch is ``T = T_r + s 2 T_v(|delta - delta_r| / 2)`` (s the direction, T_v the
    virgin curve :func:`mindlin_force`), memory is wiped as in :func:`masing_memory`, and
    once |T| reaches mu W the contact slides as a whole: T stays at s mu W, every memory
    is erased and the state is that of the virgin curve at delta_gs (q = mu p everywhere)
    about the centre ``delta - s delta_gs``. A cycle between +-delta* > delta_gs thus has
    Mindlin-Deresiewicz branches of width 2 delta_gs and plateaus |T| = mu W.

    Parameters
    ----------
    history : array_like
        delta [m] samples, from rest at 0, linear between samples.
    friction_coefficient, normal_force, contact_radius, compliance_sum
        mu [1], W [N], a [m], C [1/Pa].

    Returns
    -------
    ndarray
        T [N] at each sample.
    """
    mu_w = friction_coefficient * normal_force
    d_gs = gross_slip_displacement(friction_coefficient, normal_force, contact_radius,
                                   compliance_sum)
    return masing_loop(history, lambda d: _virgin_force(d, mu_w, d_gs), slide=(mu_w, d_gs))


def displacement_energy_per_cycle(amplitude, friction_coefficient, normal_force,
                                  contact_radius, compliance_sum) -> float:
    """Energy dissipated per full cycle delta = +-delta* under displacement control [J].

    Partial slip (delta* <= delta_gs): the Mindlin-Deresiewicz energy
    :func:`energy_per_cycle` of the force amplitude T* = T(delta*) on the virgin curve.
    Gross slip (delta* > delta_gs): ``E = E_MD(mu W) + 4 mu W (delta* - delta_gs)``, the
    loop of two Mindlin-Deresiewicz branches of width 2 delta_gs closed by the sliding
    plateaus |T| = mu W (``E_MD(mu W) = 3 mu^2 W^2 C / (20 a) = (4/5) mu W delta_gs``).

    Parameters
    ----------
    amplitude : float
        delta* [m], >= 0.
    friction_coefficient, normal_force, contact_radius, compliance_sum
        mu [1], W [N], a [m], C [1/Pa].
    """
    amplitude = abs(float(amplitude))
    mu_w = friction_coefficient * normal_force
    d_gs = gross_slip_displacement(friction_coefficient, normal_force, contact_radius,
                                   compliance_sum)
    if amplitude <= d_gs:
        t_star = min(float(_virgin_force(amplitude, mu_w, d_gs)), mu_w)
        return energy_per_cycle(t_star, friction_coefficient, normal_force, contact_radius,
                                compliance_sum)
    return energy_per_cycle(mu_w, friction_coefficient, normal_force, contact_radius,
                            compliance_sum) + 4.0 * mu_w * (amplitude - d_gs)


def gross_slip_boundary(friction_coefficient, normal_force, radius, composite_modulus,
                        compliance_sum):
    """The partial / gross slip boundary of a sphere on a plane: delta_gs(mu, W) [m].

    :func:`gross_slip_displacement` with the Hertz contact radius of W,
    ``a = (3 W R / (4 E*))^(1/3)`` ([J85]_ §4.2): ``delta_gs = 3 mu W C / (16 a)``, which for
    identical bodies (C = 2 (2 - nu) / G) is ``3 mu W (2 - nu) / (8 G a)``. A fretting
    loop of displacement amplitude delta* < delta_gs stays in partial slip, one beyond slides
    as a whole on every stroke.

    Parameters
    ----------
    friction_coefficient : float or array_like
        mu [1], >= 0.
    normal_force : float or array_like
        W [N], > 0 (broadcast with ``friction_coefficient``).
    radius : float
        Relative radius of curvature R [m].
    composite_modulus : float
        E* [Pa] (:func:`composite_modulus`).
    compliance_sum : float
        C = (2 - nu1)/G1 + (2 - nu2)/G2 [1/Pa] (:func:`tangential_compliance_sum`).

    Returns
    -------
    float or ndarray
        delta_gs [m], the shape of mu and W broadcast.
    """
    mu, w = np.broadcast_arrays(np.asarray(friction_coefficient, float),
                                np.asarray(normal_force, float))
    if np.any(w <= 0) or np.any(mu < 0):
        raise ValueError(f"gross_slip_boundary needs W > 0 [N] and mu >= 0, got W = "
                         f"{normal_force!r}, mu = {friction_coefficient!r}")
    a = (3.0 * w * float(radius) / (4.0 * float(composite_modulus))) ** (1.0 / 3.0)
    out = 3.0 * mu * w * float(compliance_sum) / (16.0 * a)
    return float(out) if out.ndim == 0 else out


#: Below this force ratio tau = T*/(mu W) the bracket of E_MD is summed as a series.
_SERIES_BELOW = 0.05
_SERIES_TERMS = 40


def _md_bracket(tau):
    """1 - (1 - tau)^(5/3) - (5 tau/6)(1 + (1 - tau)^(2/3)) (:func:`energy_per_cycle`),
    summed as its power series below tau = 0.05 (the closed form cancels to O(tau^3))."""
    tau = np.asarray(tau, float)
    s = np.clip(1.0 - tau, 0.0, 1.0)
    out = 1.0 - s ** (5.0 / 3.0) - 5.0 * tau / 6.0 * (1.0 + s ** (2.0 / 3.0))
    small = tau < _SERIES_BELOW
    if np.any(small):
        k = np.arange(3, _SERIES_TERMS + 3)
        # coefficient of tau^k: -(-1)^k C(5/3, k) - (5/6)(-1)^(k-1) C(2/3, k-1); those of
        # tau and tau^2 vanish exactly
        coef = -(-1.0) ** k * special.binom(5.0 / 3.0, k) \
            - 5.0 / 6.0 * (-1.0) ** (k - 1) * special.binom(2.0 / 3.0, k - 1)
        t = tau[small][:, None]
        out = np.where(small, 0.0, out)
        out[small] = (coef[None, :] * t ** k[None, :]).sum(axis=1)
    return out


def energy_ratio(delta_ratio):
    """Fouvry's energy ratio A = E / (4 T* delta*) of the Mindlin-Deresiewicz fretting loop.

    Under displacement control at amplitude delta* = x delta_gs
    (:func:`gross_slip_displacement`), with E the energy per cycle
    (:func:`displacement_energy_per_cycle`) and T* the force amplitude:

    * partial slip (x <= 1): T* = mu W tau, tau = 1 - (1 - x)^(3/2), and
      ``A = (6/5) [1 - (1 - tau)^(5/3) - (5 tau/6)(1 + (1 - tau)^(2/3))] / (tau x)``
      (A ~ x/12 for small x);
    * gross slip (x > 1): T* = mu W and ``A = 1 - 0.8 / x``.

    A grows from 0 to 1 and passes :data:`ENERGY_RATIO_TRANSITION` = 0.2 exactly at x = 1:
    the transition value Fouvry et al. found for a sphere on a plane ([F95]_; E_MD(mu W) =
    (4/5) mu W delta_gs). It depends on x alone: not on mu, W, the radius or the moduli.

    Parameters
    ----------
    delta_ratio : float or array_like
        x = delta*/delta_gs [1], >= 0.

    Returns
    -------
    float or ndarray
        A [1] (0 at x = 0).

    References
    ----------
    .. [F95] S. Fouvry, Ph. Kapsa, L. Vincent, "Analysis of sliding behaviour for fretting
       loadings: determination of transition criteria", Wear 185 (1995) 35-46.
    """
    x = np.asarray(delta_ratio, float)
    if np.any(~np.isfinite(x)) or np.any(x < 0):
        raise ValueError(f"delta_ratio must be finite and >= 0, got {delta_ratio!r}")
    xp = np.clip(x, 0.0, 1.0)
    tau = -np.expm1(1.5 * np.log1p(-np.minimum(xp, np.nextafter(1.0, 0.0))))    # 1 - (1 - x)^(3/2)
    tau = np.where(xp >= 1.0, 1.0, tau)
    partial = np.zeros(x.shape)
    pos = x > 0
    partial[pos] = 1.2 * _md_bracket(tau[pos]) / (tau[pos] * xp[pos])
    out = np.where(x > 1.0, 1.0 - 0.8 / np.maximum(x, 1.0), partial)
    return float(out) if out.ndim == 0 else out
