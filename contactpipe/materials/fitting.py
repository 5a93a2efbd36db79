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
           "fit_dynamic_moduli", "TABLE_KINDS", "read_table_file", "fit_table_file",
           "table_time_span"]


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
