"""Creep functions fitted to measured data: a creep or relaxation table, or storage and
loss moduli over frequency, and the material table files of ``creep = "fit"``.

Units: moduli [Pa], compliances [1/Pa], times [s], frequencies [Hz].
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .creep import ExponentialCreep

__all__ = ["PronyFit", "fit_creep_compliance", "fit_relaxation_modulus",
           "fit_dynamic_moduli", "compliance_error", "TABLE_KINDS", "read_table_file",
           "fit_table_file", "table_time_span", "FIT_TOLERANCE"]


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
        The time constants of the fit [s] (retardation times for a creep table,
        relaxation times for a relaxation or dynamic one): the log-spaced (or given)
        start, moved by the free refinement where it is on.
    source : str
        "creep", "relaxation" or "dynamic".
    compliance_error : float
        The largest relative error of the fitted creep compliance [1] over the table's
        range: against D(t) at the data's times (a creep table), against D(t)
        interconverted from the data (a relaxation table: :func:`compliance_error`), or
        of the complex compliance 1/E*(f) at the data's frequencies (a dynamic table,
        which has no D(t) of its own). NaN when not measured.
    """

    creep: ExponentialCreep
    young: float
    rms_error: float
    max_error: float
    times: tuple
    source: str
    compliance_error: float = float("nan")


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


def _time_span(t):
    """The time constants a creep or relaxation table can found [s]: its positive times'
    range, from a decade below its first positive time when it holds t = 0 (a response
    faster than the first sample, which the datum at 0 bounds)."""
    pos = t[t > 0]
    return (pos[0] / 10.0 if t[0] == 0 else pos[0]), pos[-1]


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
    from scipy.optimize import least_squares  # heavy; only the fits need it

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


def _fit_terms(basis, data, times, free, span):
    """Coefficients >= 0 of the columns ``basis(times)`` (the fixed columns first, then
    one per time constant) and the time constants: the convex fit on ``times``
    (:func:`_nonnegative_fit`), then, when ``free``, the time constants of its nonzero
    terms moved (in log time, within ``span`` [s]) with all the coefficients by bounded
    least squares from that start (:func:`scipy.optimize.least_squares`, analytic
    Jacobian): the misfit never rises above the grid's, and a spectrum with few terms
    off the grid is found exactly. ``basis(times)`` returns the columns and their
    derivatives by log time."""
    from scipy.optimize import least_squares  # heavy; only the fits need it

    a, _ = basis(times)
    c = _nonnegative_fit(a, data)
    nf = a.shape[1] - times.size
    keep = c[nf:] > 0
    if not free or not np.any(keep):
        return c, times
    c, times = np.concatenate([c[:nf], c[nf:][keep]]), times[keep]
    weight = 1.0 / np.where(data > 0, data, np.min(data[data > 0]))
    n = times.size

    def residual(x):
        return (basis(np.exp(x[-n:]))[0] @ x[:-n] - data) * weight

    def jacobian(x):
        a, da = basis(np.exp(x[-n:]))
        return np.hstack([a, da[:, nf:] * x[nf:-n]]) * weight[:, None]

    bounds = np.log(np.asarray(span, dtype=float))
    x0 = np.concatenate([c, np.clip(np.log(times), *bounds)])
    lower = np.concatenate([np.zeros(c.size), np.full(n, bounds[0])])
    upper = np.concatenate([np.full(c.size, np.inf), np.full(n, bounds[1])])
    res = least_squares(residual, x0, jac=jacobian, bounds=(lower, upper), method="trf",
                        x_scale="jac", ftol=1e-15, xtol=1e-15, gtol=1e-15, max_nfev=2000)
    coef, tk = res.x[:-n], np.exp(res.x[-n:])
    # terms below 1e-7 of the largest coefficient dropped (the solver's dust: it
    # would put a pole of the interconversion on top of a real one), terms that met
    # (within 0.1 %) made one at their mean log time
    terms = []
    for ti, ci in sorted(zip(tk, coef[nf:], strict=True)):
        if not ci > 1e-7 * coef.max():
            continue
        if terms and ti < terms[-1][0] * (1.0 + 1e-3):
            t0, c0 = terms[-1]
            terms[-1] = (np.exp((c0 * np.log(t0) + ci * np.log(ti)) / (c0 + ci)), c0 + ci)
        else:
            terms.append((ti, ci))
    fixed = np.where(coef[:nf] > 1e-7 * coef.max(), coef[:nf], 0.0)
    out = (np.concatenate([fixed, [ci for _, ci in terms]]),
           np.array([ti for ti, _ in terms]))

    def cost(coef, times):
        return np.sum(((basis(times)[0] @ coef - data) * weight) ** 2)

    if not terms or not cost(*out) < cost(c, times):
        return c, times                        # no better than the grid: the grid's
    return out


def _creep_basis(t, dashpot):
    def basis(lam):
        x = t[:, None] / lam[None, :]
        fixed = [np.ones_like(t)] + ([t] if dashpot else [])
        return (np.column_stack(fixed + [-np.expm1(-x)]),
                np.column_stack([np.zeros_like(t)] * len(fixed) + [-x * np.exp(-x)]))
    return basis


def _relaxation_basis(t):
    def basis(tau):
        x = t[:, None] / tau[None, :]
        return (np.column_stack([np.ones_like(t), np.exp(-x)]),
                np.column_stack([np.zeros_like(t), x * np.exp(-x)]))
    return basis


def _dynamic_basis(w):
    def basis(tau):
        x = w[:, None] * tau[None, :]
        q = 1.0 + x ** 2
        one, zero = np.ones_like(w), np.zeros_like(w)
        return (np.vstack([np.column_stack([one, x ** 2 / q]),
                           np.column_stack([zero, x / q])]),
                np.vstack([np.column_stack([zero, 2 * x ** 2 / q ** 2]),
                           np.column_stack([zero, x * (1 - x ** 2) / q ** 2])]))
    return basis


def compliance_error(t, modulus, fitted_modulus, creep, young, refine=8):
    """The largest relative error of a fitted creep compliance D(t) = creep(t)/young
    against the one of measured relaxation data, over the data's times [1].

    The data's relaxation function is the fitted one times the ratio data/fit,
    interpolated linearly in log t between the data's positive times (in t from a datum
    at 0 to the first, held beyond the data), and its
    compliance solves int_{0-}^t E(t - s) dD(s) = 1: by product integration on the
    data's times with ``refine`` log-spaced points within each interval (D linear
    within a step, the integral of E over a step by Simpson's rule). The same scheme
    run on the fitted E gives the fitted D up to the scheme's own error, which the
    difference of the two runs leaves out: error = max |dD / (D + dD)|, with dD that
    difference (0 for a fit that meets every datum).

    Parameters
    ----------
    t, modulus : ndarray
        The data: times [s] (ascending, >= 0) and E(t) [Pa].
    fitted_modulus : callable
        The fitted E(t) [Pa].
    creep : ExponentialCreep
        The fitted phi [1]; ``young`` [Pa] its modulus.
    """
    ratio = modulus / fitted_modulus(t)
    pos = t[t > 0]
    refine = max(1, min(int(refine), 1200 // pos.size))    # N^2 work and memory
    grid = [np.linspace(0.0, pos[0], refine + 1)]
    for lo, hi in zip(pos[:-1], pos[1:], strict=True):
        grid.append(np.geomspace(lo, hi, refine + 1)[1:])
    grid = np.concatenate(grid)
    first = ratio[1] if t[0] == 0 else ratio[0]         # the ratio at pos[0]
    start = ratio[0]                                     # ... and at t = 0 (or held)

    def data_modulus(x):
        late = np.interp(np.log(np.maximum(x, pos[0])), np.log(pos), ratio[t > 0])
        early = start + (first - start) * np.minimum(x, pos[0]) / pos[0]
        return fitted_modulus(x) * np.where(x < pos[0], early, late)

    lag = grid[:, None] - grid[None, :]                  # t_k - t_j
    mid = lag[:, 1:] + 0.5 * np.diff(grid)[None, :]      # t_k - (t_{j-1} + t_j)/2

    def compliance(e):
        h = np.diff(grid)
        ok = lag[:, 1:] >= 0
        simpson = (e(np.where(ok, lag[:, 1:], 0)) + 4 * e(np.where(ok, mid, 0))
                   + e(np.where(ok, lag[:, :-1], 0)))
        m = np.where(ok, h / 6 * simpson, 0.0)
        e0 = float(e(np.zeros(1))[0])
        g = np.zeros(h.size)
        for k in range(1, grid.size):
            rest = 1.0 - e(grid[k:k + 1])[0] / e0 - m[k, :k - 1] @ g[:k - 1]
            g[k - 1] = rest / m[k, k - 1]
        return np.concatenate([[1.0 / e0], 1.0 / e0 + np.cumsum(g * h)])

    delta = compliance(data_modulus) - compliance(fitted_modulus)
    d = creep(grid) / young + delta
    inside = (grid >= t[0]) & (grid <= t[-1]) & (d > 0)
    return float(np.max(np.abs(delta[inside] / d[inside])))


def _fit_result(creep, young, model, data, times, source, compliance):
    pos = data > 0
    err = model[pos] / data[pos] - 1.0
    fit = PronyFit(creep=creep, young=float(young),
                   rms_error=float(np.sqrt(np.mean(err ** 2))),
                   max_error=float(np.abs(err).max()), times=tuple(float(t) for t in times),
                   source=source, compliance_error=float(compliance))
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
                         noise=0.01, free=True):
    """Prony series fitted to a tensile creep-compliance table.

    D(t) = D0 + sum_i D_i (1 - exp(-t/tau_i)) [+ t/eta] with D0, D_i, 1/eta >= 0 by the
    bounds of :func:`scipy.optimize.least_squares` on the relative misfit. First with
    log-spaced tau_i held fixed (``terms_per_decade`` per decade over the table's positive
    times, from a decade below the first when the table holds t = 0): linear in the
    coefficients, a convex problem with a unique answer. Then, with ``free``, the tau_i
    of its nonzero terms move (within that range) with the coefficients from there
    (:func:`_fit_terms`): a spectrum of a few terms off the grid is found exactly (a
    Zener half-way between two grid times: 1e-15, where the fixed grid is 3 % off), and
    the misfit never rises above the fixed grid's.

    Parameters
    ----------
    t : array_like
        Times [s], ascending, >= 0 (at least 3).
    compliance : array_like
        D(t) = strain / stress under a constant stress [1/Pa], > 0 (0 allowed at t = 0),
        non-decreasing.
    terms_per_decade : int
        Retardation times per decade of the start (2: a power-law creep 1 + t^0.3 over
        four decades within 0.07 %; 1 gives 0.12 %).
    times : array_like, optional
        The retardation times [s] of the start instead of the log-spaced ones.
    dashpot : bool
        Add a flow term t/eta (a fluid).
    noise : float
        Relative decrease of the data tolerated as measurement noise [1].
    free : bool
        Let the retardation times move from the start (True) or hold them (False).

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
    span = _time_span(t)
    lam = _log_times(*span, terms_per_decade, times)
    basis = _creep_basis(t, dashpot)
    c, lam = _fit_terms(basis, d, lam, free, span)
    nf = 2 if dashpot else 1
    creep, young = _creep_from_compliance(c[0], c[nf:], lam, c[1] if dashpot else 0.0)
    model = basis(lam)[0] @ c
    miss = np.abs(model[d > 0] / d[d > 0] - 1.0).max()
    return _fit_result(creep, young, model, d, lam, "creep", miss)


def _creep_from_relaxation(e_inf, ek, tau):
    """Interconversion: the compliance of E(t) = e_inf + sum ek exp(-t/tau), exactly.

    With M(s) = s L[E](s) = e_inf + sum ek s tau/(1 + s tau), s L[D](s) = 1/M(s), whose
    poles s_j = -1/lam_j (one between consecutive -1/tau_i, one in (-1/tau_max, 0) when
    e_inf > 0, else s = 0: a dashpot) give D = 1/E0 + sum D_j (1 - exp(-t/lam_j)) + t/eta,
    D_j = lam_j / M'(s_j) > 0, 1/eta = 1 / sum ek tau."""
    from scipy.optimize import brentq  # heavy; only the fits need it

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
    edges = list(zip(poles[:-1], poles[1:], strict=True))
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


def _modulus_fit(basis, data, tau, free, span):
    """A fit of a relaxation modulus (or dynamic moduli) and its creep function: the
    fixed grid's when the freed time constants cannot be interconverted (two of them
    too close for the roots between their poles in float64)."""
    c, times = _fit_terms(basis, data, tau, free, span)
    try:
        return (c, times) + _creep_from_relaxation(c[0], c[1:], times)
    except ValueError:
        if not free:
            raise
        return _modulus_fit(basis, data, tau, False, span)


def fit_relaxation_modulus(t, modulus, *, terms_per_decade=2, times=None, noise=0.01,
                           free=True):
    """Prony series fitted to a relaxation-modulus table, converted to a creep function.

    E(t) = E_inf + sum_i E_i exp(-t/tau_i) (generalised Maxwell) with E_inf, E_i >= 0 and
    log-spaced tau_i, held or freed (as :func:`fit_creep_compliance`), then converted
    exactly to the creep compliance (:func:`_creep_from_relaxation`: retardation times
    interlaced with the relaxation times; a dashpot when E_inf = 0). The error of that
    compliance against the data's (:func:`compliance_error`) is ``compliance_error``.

    Parameters
    ----------
    t : array_like
        Times [s], ascending, >= 0 (at least 3).
    modulus : array_like
        E(t) = stress / strain under a constant strain [Pa], > 0, non-increasing.
    terms_per_decade : int
        Relaxation times per decade of the start.
    times : array_like, optional
        The relaxation times [s] of the start instead of the log-spaced ones.
    noise : float
        Relative increase of the data tolerated as measurement noise [1].
    free : bool
        Let the relaxation times move from the start (True) or hold them (False).

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
    span = _time_span(t)
    tau = _log_times(*span, terms_per_decade, times)
    basis = _relaxation_basis(t)
    c, tau, creep, young = _modulus_fit(basis, e, tau, free, span)

    def fitted(x):
        x = np.asarray(x, dtype=float)
        return c[0] + np.exp(-x[..., None] / tau) @ c[1:]

    miss = compliance_error(t, e, fitted, creep, young)
    return _fit_result(creep, young, basis(tau)[0] @ c, e, tau, "relaxation", miss)


def fit_dynamic_moduli(frequency, storage, loss, *, terms_per_decade=2, times=None,
                       noise=0.01, free=True):
    """Prony series fitted to storage and loss moduli over frequency (a DMA sweep).

    E'(w) = E_inf + sum_i E_i (w tau_i)^2 / (1 + (w tau_i)^2),
    E''(w) = sum_i E_i w tau_i / (1 + (w tau_i)^2), w = 2 pi f, with log-spaced tau_i
    over 1/(2 pi f_max) .. 1/(2 pi f_min), held or freed within that range, and E_inf,
    E_i >= 0, both moduli fitted together (relative misfit), then converted to the creep
    function as :func:`fit_relaxation_modulus`. ``compliance_error`` is the largest
    relative error of the complex compliance 1/E* at the data's frequencies.

    Parameters
    ----------
    frequency : array_like
        Frequencies f [Hz], ascending, > 0 (at least 3).
    storage, loss : array_like
        E'(f) and E''(f) [Pa], > 0; E' non-decreasing with f.
    terms_per_decade : int
        Relaxation times per decade of the start.
    times : array_like, optional
        The relaxation times [s] of the start instead of the log-spaced ones.
    noise : float
        Relative decrease of E' tolerated as measurement noise [1].
    free : bool
        Let the relaxation times move from the start (True) or hold them (False).

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
    basis = _dynamic_basis(w)
    data = np.concatenate([e1, e2])
    c, tau, creep, young = _modulus_fit(basis, data, tau, free, (1.0 / w[-1], 1.0 / w[0]))
    model = basis(tau)[0] @ c
    # the complex compliance 1/E*: its relative error is |E*_data / E*_fit - 1|
    miss = np.abs((e1 + 1j * e2) / (model[:f.size] + 1j * model[f.size:]) - 1.0).max()
    return _fit_result(creep, young, model, data, tau, "dynamic", miss)


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
        if not stat.S_ISREG(os.stat(path).st_mode):     # a FIFO would block for ever
            raise ValueError(f"cannot read {path}: not a regular file (a FIFO, a device or "
                             f"a folder); give a table file")
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


#: The largest error of a fitted creep compliance a scene accepts by default [1]
#: (``fit_tolerance``; :attr:`PronyFit.compliance_error`).
FIT_TOLERANCE = 0.01


@lru_cache(maxsize=32)
def _fit_text_cached(text, path, kind, options):
    cols = _parse_table(text, path, kind)
    if kind == "creep":
        return fit_creep_compliance(cols[0], cols[1], **dict(options))
    if kind == "relaxation":
        return fit_relaxation_modulus(cols[0], cols[1], **dict(options))
    return fit_dynamic_moduli(cols[0], cols[1], cols[2], **dict(options))


def fit_table_file(path, kind: str, *, terms_per_decade=2, times=None,
                   free=True) -> PronyFit:
    """The Prony fit of a material table file (:func:`read_table_file`) by
    :func:`fit_creep_compliance`, :func:`fit_relaxation_modulus` or
    :func:`fit_dynamic_moduli` with these options; cached by the file's content.

    Raises
    ------
    ValueError
        The file cannot be read, or its data or the fit are refused (not positive, not
        monotone).
    """
    if kind not in TABLE_KINDS:
        raise ValueError(f"table kind {kind!r}: allowed {', '.join(TABLE_KINDS)}")
    options = (("terms_per_decade", terms_per_decade), ("free", bool(free)),
               ("times", None if times is None else tuple(float(x) for x in times)))
    return _fit_text_cached(_read_text(path), os.fspath(path), kind, options)


def table_time_span(path, kind: str) -> float:
    """The time [s] up to which a table file's data reach: its last time (creep or
    relaxation), or 1/(2 pi f_min) (dynamic: the longest relaxation time it resolves)."""
    cols = read_table_file(path, kind)
    if kind == "dynamic":
        return float(1.0 / (2.0 * np.pi * cols[0].min()))
    return float(cols[0].max())
