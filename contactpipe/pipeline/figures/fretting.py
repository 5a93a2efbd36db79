"""The fretting map of a sweep (the ``fretting-map`` kind of ``contactpipe plot``).

:func:`plot_fretting_map` draws each member's regime (:mod:`contactpipe.pipeline.figures.regimes`:
partial slip, mixed, gross slip by Fouvry's energy ratio; one marker per regime) over the
displacement amplitude delta* [um] and the friction coefficient mu or the normal force W,
with the closed-form boundary delta_gs(mu, W) = 3 mu W C / (16 a) of Mindlin's sphere
(:func:`contactpipe.analytic.gross_slip_boundary`) drawn over it.
:func:`plot_energy_ratio` draws the members' energy ratios against delta*/delta_gs with the
Mindlin-Deresiewicz curve A(delta*/delta_gs) and the transition 0.2.

Both take ``ax=None`` (a new 8 x 5 in figure, :func:`contactpipe.pipeline.figures.new_figure`)
and return the Figure (never pyplot).
"""
from __future__ import annotations

import os

import numpy as np
import xarray as xr

from ... import analytic
from ...exceptions import ArchiveError
from .canvas import axes_of
from .regimes import fretting_map

__all__ = ["plot_fretting_map", "plot_energy_ratio", "MARKERS", "map_axis"]

#: Marker, colour of each regime.
MARKERS = {"partial slip": ("o", "#2c7bb6"), "mixed": ("s", "#fdae61"),
           "gross slip": ("^", "#d7191c")}
AXES = {"mu": ("mu", "friction coefficient μ"), "W": ("W", "normal force W [N]")}
#: The sweep axis that makes each ordinate vary.
SWEPT = {"mu": "friction.mu", "W": "load.normal_force"}


def _table(obj):
    """A regime table: the Dataset given, or the one of a sweep folder."""
    if isinstance(obj, xr.Dataset):
        if "regime" not in obj:
            raise ArchiveError("the dataset is not a regime table (no 'regime'); give a "
                               "sweep folder or "
                               "contactpipe.pipeline.figures.regimes.fretting_map()")
        return obj
    if isinstance(obj, (str, os.PathLike)):
        return fretting_map(obj)
    raise ArchiveError(f"expected a sweep folder or a regime table, got "
                       f"{type(obj).__name__}")


def map_axis(table, against=None) -> str:
    """The map's ordinate: ``against`` ("mu" or "W"), else the one that varies over the
    members (mu when both do, or neither)."""
    if against is not None:
        if against not in AXES:
            raise ValueError(f"against must be 'mu' or 'W', got {against!r}")
        values = np.unique(np.asarray(table[against].values, float))
        if values.size < 2:
            other = "W" if against == "mu" else "mu"
            raise ArchiveError(
                f"against = {against!r}: every member has {against} = "
                f"{', '.join(f'{v:g}' for v in values) or 'nothing'}, one value: a map "
                f"against {against} needs members that differ in it (sweep "
                f"{SWEPT[against]}), or against = {other!r}")
        return against
    varies = {k: np.unique(np.asarray(table[k].values, float)).size > 1 for k in AXES}
    return "W" if varies["W"] and not varies["mu"] else "mu"


def _boundary(ax, table, y_name):
    """The closed-form boundary: a curve over the ordinate's range where the other load
    and the constants are common to the members, else a tick at each member's delta_gs."""
    other = "W" if y_name == "mu" else "mu"
    ys = np.asarray(table[y_name].values, float)
    fixed = np.unique(np.asarray(table[other].values, float))
    have = all(k in table.attrs for k in ("radius_m", "composite_modulus_Pa",
                                          "compliance_sum_per_Pa"))
    if have and fixed.size == 1 and np.all(np.isfinite(ys)) and np.isfinite(fixed[0]):
        lo, hi = float(ys.min()), float(ys.max())
        pad = 0.08 * (hi - lo) if hi > lo else 0.1 * abs(hi)
        y = np.linspace(max(lo - pad, 1e-12), hi + pad, 200)
        kw = {y_name: y, other: fixed[0]}
        d = analytic.gross_slip_boundary(kw["mu"], kw["W"], table.attrs["radius_m"],
                                         table.attrs["composite_modulus_Pa"],
                                         table.attrs["compliance_sum_per_Pa"])
        ax.plot(d * 1e6, y, "-", color="0.25", lw=1.3,
                label=r"closed form $\delta_{gs}$ = 3μWC/(16a)")
        return
    d = np.asarray(table["delta_gs"].values, float)
    ok = np.isfinite(d)
    if np.any(ok):
        ax.plot(d[ok] * 1e6, ys[ok], "|", color="0.25", ms=14, mew=1.5,
                label=r"closed form $\delta_{gs}$ of each member")


def plot_fretting_map(sweep, against=None, *, ax=None):
    """The fretting map of a sweep: the regime of each member over (delta*, mu or W).

    Parameters
    ----------
    sweep : path or xarray.Dataset
        A sweep folder (classified by :func:`contactpipe.pipeline.figures.regimes.fretting_map`)
        or its regime table.
    against : {"mu", "W"}, optional
        The ordinate; default the load that varies over the members (:func:`map_axis`).
    ax : matplotlib.axes.Axes, optional
        Draw into it; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ArchiveError
        Not a sweep folder or a regime table; a member that is not a fretting loop;
        ``against`` names a load that has one value over the members.
    """
    table = _table(sweep)
    y_name = map_axis(table, against)
    fig, ax = axes_of(ax)
    x = np.asarray(table["delta_star"].values, float) * 1e6
    y = np.asarray(table[y_name].values, float)
    regimes = np.asarray(table["regime"].values).astype(str)
    for regime, (marker, colour) in MARKERS.items():
        sel = regimes == regime
        if np.any(sel):
            ax.plot(x[sel], y[sel], marker, color=colour, ms=8, ls="none",
                    label=f"{regime} ({int(sel.sum())})")
    _boundary(ax, table, y_name)
    ax.set_xlabel("displacement amplitude δ* [µm]")
    ax.set_ylabel(AXES[y_name][1])
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=8, loc="best", framealpha=0.9)
    disagree = int(np.sum((np.asarray(table["regime_closed_form"].values).astype(str) != "")
                          & (np.asarray(table["regime_closed_form"].values).astype(str)
                             != regimes)))
    ax.set_title(f"fretting map: {table.sizes['member']} members, Fouvry's A = E/(4T*δ*) "
                 f"vs 0.2; {disagree} differ from the closed form", fontsize=9)
    return fig


def plot_energy_ratio(sweep, *, ax=None):
    """The members' energy ratio A against delta*/delta_gs, over the Mindlin-Deresiewicz
    curve :func:`contactpipe.analytic.energy_ratio` and the transition A = 0.2.

    Parameters
    ----------
    sweep : path or xarray.Dataset
        A sweep folder or its regime table (members without a closed form are left out).
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    table = _table(sweep)
    fig, ax = axes_of(ax)
    xr_ = np.asarray(table["delta_ratio"].values, float)
    a = np.asarray(table["energy_ratio"].values, float)
    regimes = np.asarray(table["regime"].values).astype(str)
    ok = np.isfinite(xr_)
    top = max(float(np.max(xr_[ok])) if np.any(ok) else 2.0, 1.5) * 1.05
    grid = np.linspace(0.0, top, 400)
    ax.plot(grid, analytic.energy_ratio(grid), "-", color="0.25", lw=1.3,
            label="Mindlin–Deresiewicz A(δ*/δ_gs)")
    ax.axhline(analytic.ENERGY_RATIO_TRANSITION, color="0.5", ls="--", lw=1.0,
               label="transition A = 0.2")
    ax.axvline(1.0, color="0.5", ls=":", lw=1.0)
    for regime, (marker, colour) in MARKERS.items():
        sel = ok & (regimes == regime)
        if np.any(sel):
            ax.plot(xr_[sel], a[sel], marker, color=colour, ms=7, ls="none", label=regime)
    ax.set_xlabel("δ* / δ_gs")
    ax.set_ylabel("energy ratio A = E / (4 T* δ*)")
    ax.set_xlim(0.0, top)
    ax.set_ylim(0.0, 1.0)
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=8, loc="lower right")
    return fig
