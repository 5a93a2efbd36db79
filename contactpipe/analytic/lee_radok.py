"""Viscoelastic normal contact of a rigid sphere (Lee & Radok 1960; Ting 1966).

SI units; the creep function is a :mod:`contactpipe.materials` creep object.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..materials import ExponentialCreep, relaxation_from_creep
from ._common import sqrt_plus

__all__ = ["LeeRadokContact", "lee_radok_sphere", "lee_radok_radius",
           "relaxation_function", "lee_radok_pressure"]


# --------------------------------------------------------------------------- Lee-Radok
@dataclass(frozen=True)
class LeeRadokContact:
    """Rigid sphere on a viscoelastic half-space under a step load ([LR60]_).

    Attributes
    ----------
    t : ndarray
        Times [s] after the load step.
    contact_radius : ndarray
        a(t) [m].
    approach : ndarray
        a(t)^2 / R [m].
    """

    t: np.ndarray
    contact_radius: np.ndarray
    approach: np.ndarray


def lee_radok_sphere(t, normal_force, radius, young, poisson, creep) -> LeeRadokContact:
    """Lee-Radok solution for a step load W applied at t = 0 on a rigid sphere.

    With a constant Poisson ratio the elastic compliance ``(1 - nu^2)/E`` becomes the
    creep function ``(1 - nu^2)/E * phi(t)``; while the contact grows the Hertz
    relations hold with it ([LR60]_):
    ``a(t)^3 = 3 W R (1 - nu^2) phi(t) / (4 E)`` and ``delta(t) = a(t)^2 / R``.

    Parameters
    ----------
    t : array_like
        Times [s]; a = 0 for t < 0.
    normal_force : float
        W [N], applied as a step at t = 0.
    radius : float
        Sphere radius R [m].
    young : float
        Modulus E [Pa] of the normalisation of ``creep`` (instantaneous for most
        models, long-term for Kelvin-Voigt; see :mod:`contactpipe.materials`).
    poisson : float
        Constant Poisson ratio nu [1].
    creep : callable
        Normalised creep function phi(t) [1], non-decreasing (a
        :mod:`contactpipe.materials` creep object).

    Returns
    -------
    LeeRadokContact
    """
    t = np.asarray(t, float)
    phi = np.where(t >= 0.0, creep(np.maximum(t, 0.0)), 0.0)
    a = (3.0 * normal_force * radius * (1.0 - poisson ** 2) * phi / (4.0 * young)) ** (1 / 3)
    return LeeRadokContact(t, a, a ** 2 / radius)


def _creep_integral(creep, u0, u1):
    """int_{u0}^{u1} phi(u) du [s] (exact with the creep object's ``mean`` if any)."""
    from scipy.integrate import quad  # scipy.integrate loads scipy.optimize: ~0.3 s
    if u1 <= u0:
        return 0.0
    if hasattr(creep, "mean"):
        return float(np.squeeze(creep.mean(u0, u1))) * (u1 - u0)
    return quad(lambda u: float(creep(u)), u0, u1, limit=200)[0]


def lee_radok_radius(t, load_times, load_values, radius, young, poisson, creep):
    """Contact radius a(t) [m] of a rigid sphere under a growing load W(t).

    Hereditary integral of [LR60]_, valid while the contact area does not shrink
    (otherwise see [T66]_; a non-decreasing load and creep function guarantee it):

    ``a(t)^3 = 3 R (1 - nu^2) / (4 E) * int_{0-}^{t} phi(t - s) dW(s)``

    W(t) is 0 before the first knot, jumps to ``load_values[0]`` there (the step is
    included), is linear between knots and constant after the last one; two knots at
    the same time make a further step. The linear pieces are integrated exactly with
    the creep object's ``mean`` (or by :func:`scipy.integrate.quad` for a plain
    callable).

    Parameters
    ----------
    t : array_like
        Times [s].
    load_times : array_like
        Knot times [s], non-decreasing.
    load_values : array_like
        Loads W at the knots [N], >= 0 and non-decreasing.
    radius : float
        Sphere radius R [m].
    young : float
        Modulus E [Pa] normalising ``creep``.
    poisson : float
        Constant Poisson ratio [1].
    creep : callable
        Normalised creep function phi(t) [1].

    Returns
    -------
    ndarray
        a(t) [m], shape of ``t``.
    """
    tk = np.asarray(load_times, float).ravel()
    wk = np.asarray(load_values, float).ravel()
    if tk.size != wk.size or tk.size == 0:
        raise ValueError("load_times and load_values must be non-empty and of equal length")
    if np.any(np.diff(tk) < 0):
        raise ValueError("load_times [s] must be non-decreasing")
    if wk[0] < 0 or np.any(np.diff(wk) < 0):
        raise ValueError("load_values [N] must be >= 0 and non-decreasing "
                         "(Lee-Radok needs a growing contact; see Ting 1966)")
    t = np.asarray(t, float)
    out = np.zeros(t.shape)
    pref = 3.0 * radius * (1.0 - poisson ** 2) / (4.0 * young)
    for idx in np.ndindex(t.shape):
        ti = float(t[idx])
        if ti < tk[0]:
            continue
        acc = wk[0] * float(creep(ti - tk[0]))
        for k in range(tk.size - 1):
            s0, s1 = tk[k], tk[k + 1]
            if s0 > ti:
                break
            dw = wk[k + 1] - wk[k]
            if dw == 0.0:
                continue
            if s1 == s0:                       # a step
                acc += dw * float(creep(ti - s0))
                continue
            se = min(s1, ti)
            acc += dw / (s1 - s0) * _creep_integral(creep, ti - se, ti - s0)
        out[idx] = (pref * acc) ** (1.0 / 3.0)
    return out


def _relaxation_grid(creep, t_end, n_steps):
    """psi on the uniform grid t_j = j t_end / n (j = 0..n), see relaxation_function."""
    s = np.linspace(0.0, t_end, n_steps + 1)
    phi = np.asarray(creep(s), float)
    if phi[0] <= 0.0:
        raise ValueError("phi(0) = 0 (no instantaneous elasticity, e.g. Kelvin-Voigt): "
                         "the relaxation function has a Dirac part; not supported")
    dphi = np.diff(phi)                                  # dphi[k] = phi_{k+1} - phi_k
    psi = np.empty(n_steps + 1)
    psi[0] = 1.0 / phi[0]
    diag = phi[0] + 0.5 * dphi[0] if n_steps else phi[0]
    for n in range(1, n_steps + 1):
        # sum_{k=0}^{n-1} (psi_{n-k} + psi_{n-k-1})/2 dphi_k + psi_n phi_0 = 1
        k = np.arange(n)
        rest = 0.5 * (psi[n - 1 - k] @ dphi[:n])
        if n >= 2:
            rest += 0.5 * (psi[n - k[1:]] @ dphi[1:n])
        psi[n] = (1.0 - rest) / diag
    return s, psi


def relaxation_function(t, creep, n_steps: int = 2000):
    """Normalised relaxation function psi(t) [1] from the creep function phi.

    psi solves the Volterra identity ``int_{0-}^{t} psi(t - s) dphi(s) = 1``, i.e.
    ``psi(t) phi(0) + int_0^t psi(t - s) phi'(s) ds = 1`` (phi * dpsi = H), so that
    the relaxation modulus is ``E/(1 - nu^2) * psi(t)`` when the compliance is
    ``(1 - nu^2)/E * phi(t)``. It is solved by product-trapezoid quadrature of the
    Stieltjes integral on a uniform grid of ``n_steps`` steps over [0, max(t)]
    (second order in the step; the implicit coefficient phi(0) + [phi(h) - phi(0)]/2
    is > 0 for a non-decreasing phi with phi(0) > 0), then interpolated linearly.
    Maxwell (phi = 1 + t/t') gives psi = exp(-t/t').

    Parameters
    ----------
    t : array_like
        Times [s], >= 0.
    creep : callable
        Normalised creep function phi [1] with phi(0) > 0.
    n_steps : int, optional
        Number of time steps of the quadrature (default 2000; cost O(n^2)).

    Returns
    -------
    ndarray
        psi(t) [1].
    """
    t = np.asarray(t, float)
    t_end = float(np.max(t)) if t.size else 0.0
    if t_end <= 0.0:
        return np.full(t.shape, 1.0 / float(creep(0.0)))
    s, psi = _relaxation_grid(creep, t_end, n_steps)
    return np.interp(t, s, psi)


def lee_radok_pressure(r, t, normal_force, radius, young, poisson, creep,
                       n_steps: int = 2000):
    """Contact pressure [Pa] under a rigid sphere, step load W at t = 0 ([LR60]_).

    ``p(r, t) = 2 E / (pi R (1 - nu^2)) int_{0-}^{t} psi(t - s) d h(r, s)``,
    ``h(r, s) = sqrt(a(s)^2 - r^2)`` (0 for r > a(s)), the hereditary form of the Hertz
    pressure ``p = 2 E*/(pi R) sqrt(a^2 - r^2)`` with a(s) from
    :func:`lee_radok_sphere` and psi from :func:`relaxation_function` on the same
    grid. The Stieltjes integral uses the same product-trapezoid rule, so the total
    force equals W to round-off (up to the radial quadrature of the user).

    A creep function without instantaneous compliance (phi(0) = 0: Kelvin-Voigt, a
    Kelvin chain) has a relaxation function with a Dirac part, psi = delta(t)/phi'(0) +
    psi_r(t) (:func:`contactpipe.materials.relaxation_from_creep`, exact for a sum of
    exponentials), so ``p = 2 E/(pi R (1 - nu^2)) (dh/dt / phi'(0) + int psi_r dh)`` with
    dh/dt = a a'/h and a^3 = a_inf^3 phi(t): infinite at the growing edge, and for
    Kelvin-Voigt ``p = 2 E/(pi R (1 - nu^2)) (h + tau dh/dt)`` (E the long-term modulus).
    There the integral of psi_r is taken in closed form for Kelvin-Voigt and by the
    product-trapezoid rule otherwise.

    Parameters
    ----------
    r : array_like
        Radii [m].
    t : float
        Time since the load step [s], >= 0 (> 0 when phi(0) = 0).
    normal_force : float
        W [N].
    radius : float
        Sphere radius R [m].
    young : float
        Modulus E [Pa] normalising ``creep``.
    poisson : float
        Constant Poisson ratio [1].
    creep : callable
        Normalised creep function phi [1]; phi(0) > 0, or an
        :class:`~contactpipe.materials.ExponentialCreep` with phi(0) = 0.
    n_steps : int, optional
        Number of time steps over [0, t] (default 2000).

    Returns
    -------
    ndarray
        p(r, t) [Pa], shape of ``r``.
    """
    r = np.asarray(r, float)
    t = float(t)
    pref = 2.0 * young / (np.pi * radius * (1.0 - poisson ** 2))
    if float(creep(0.0)) == 0.0:
        return pref * _zero_origin_pressure(r, t, normal_force, radius, young, poisson,
                                            creep, n_steps)
    if t <= 0.0:
        a0 = lee_radok_sphere(0.0, normal_force, radius, young, poisson, creep).contact_radius
        return pref / float(creep(0.0)) * sqrt_plus(float(a0), r)
    s, psi = _relaxation_grid(creep, t, n_steps)
    a = lee_radok_sphere(s, normal_force, radius, young, poisson, creep).contact_radius
    h = sqrt_plus(a[:, None], r.ravel()[None, :])      # (n+1, m)
    w = 0.5 * (psi[::-1][:-1] + psi[::-1][1:])          # (psi_{n-k} + psi_{n-k-1})/2
    val = psi[-1] * h[0] + w @ np.diff(h, axis=0)
    return (pref * val).reshape(r.shape)


def _zero_origin_pressure(r, t, normal_force, radius, young, poisson, creep, n_steps):
    """dh/dt / phi'(0) + int psi_r dh [m] (see :func:`lee_radok_pressure`)."""
    if not isinstance(creep, ExponentialCreep):
        raise ValueError("phi(0) = 0 (no instantaneous elasticity): the relaxation "
                         "function has a Dirac part; lee_radok_pressure needs an "
                         "ExponentialCreep for it")
    if t <= 0.0:
        raise ValueError(f"phi(0) = 0: the pressure is singular at the load step, t must "
                         f"be > 0, got {t:g} s")
    a_inf3 = 3.0 * normal_force * radius * (1.0 - poisson ** 2) / (4.0 * young)
    a = (a_inf3 * float(creep(t))) ** (1.0 / 3.0)
    h = sqrt_plus(a, r)
    a_rate = a_inf3 * float(creep.derivative(t)) / (3.0 * a ** 2)
    dh = np.divide(a * a_rate, h, out=np.zeros_like(h), where=h > 0)
    regular = relaxation_from_creep(creep)
    if not regular.d:                              # psi_r constant: int psi_r dh = psi_r h
        val = regular.a * h
    else:
        s = np.linspace(0.0, t, n_steps + 1)
        psi = np.asarray(regular(t - s), float)
        hs = sqrt_plus(((a_inf3 * creep(s)) ** (1.0 / 3.0))[:, None], r.ravel()[None, :])
        w = 0.5 * (psi[:-1] + psi[1:])
        val = (w @ np.diff(hs, axis=0)).reshape(r.shape)
    return dh / float(creep.derivative(0.0)) + val
