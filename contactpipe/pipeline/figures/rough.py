"""The ``rough`` figure of an archive: maps and contact fractions that stay readable on
rough contacts of 512^2 cells and more.

:func:`plot_rough` draws, at one instant (default: the peak tangential load |T|, else the
last instant), the initial gap ``h0`` (when the archive holds it), the pressure and the
contact status with the contact and stick clusters outlined, their counts in the title
(edge-connected clusters, :func:`contactpipe.post.clusters.count_clusters`); beneath, the
contact-area fraction (contact_area / grid area) and the stick fraction (stick_area /
contact_area) against the normal force W when W changes monotonically over the run, else
against time, and the cluster counts against time at most :data:`CLUSTER_INSTANTS`
instants. Any archive plots (the maps mean something for a smooth one too); ``--kind
all`` adds it for an archive that holds ``h0``.

Large grids: each map is one image (no per-cell patches), downsampled by matplotlib's
antialiasing and rasterized; an archive given as a path is opened lazily (one chunk per
instant of a field) and only the instants drawn are read and checked
(:func:`contactpipe.archive.content_problems` on them), not the whole file.
"""
from __future__ import annotations

import contextlib
import os
import re

import numpy as np
import xarray as xr

from ...archive import content_problems, open_archive
from ...exceptions import ArchiveError
from ...nomenclature import STATUS_SEPARATED, STATUS_SLIP, STATUS_STICK
from ...post.clusters import count_clusters, is_periodic
from ..inputs import grid_of
from .canvas import new_figure
from .common import _index, _scene_title, _time_label, input_kind

__all__ = ["plot_rough", "rough_series", "rough_instant", "CLUSTER_INSTANTS"]

#: The most instants whose clusters are counted for the count-against-time panel.
CLUSTER_INSTANTS = 24
STATUS_COLOURS = ("#e6e6e6", "#2c7bb6", "#d7191c")     # separated, stick, slip
DEPTH_UNITS = ((1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm"))
STRESS_UNITS = ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa"), (1.0, "Pa"))
MAP_FIELDS = ("p", "q1", "q2", "status")
SERIES = ("W", "T1", "T2", "contact_area", "stick_area")


def _scaled(value, units):
    for factor, unit in units:
        if abs(value) >= factor:
            return factor, unit
    return units[-1]


def _check(ds, path, k, ks) -> None:
    """Refuse ``path`` when a value read for the figure breaks the archive's rules: the
    map fields at instant ``k``, ``status`` at the instants ``ks``, the series."""
    maps = [n for n in MAP_FIELDS if n in ds] + [n for n in ("h0", "mu") if n in ds]
    parts = [(ds[maps].isel(time=[k]), [k]),
             (ds[["status"]].isel(time=list(ks)), list(ks)),
             (ds[[n for n in SERIES if n in ds]], range(ds.sizes["time"]))]
    # a subset's steps counted from 0: named by their index in the archive
    problems = [re.sub(r"step (\d+) \(", lambda m, at=at: f"step {at[int(m[1])]} (", line)
                for part, at in parts for line in content_problems(part)]
    if problems:
        raise ArchiveError(f"{path}: damaged archive: " + "; ".join(dict.fromkeys(problems)))


@contextlib.contextmanager
def _lazy(obj):
    """(Dataset, path or None): a Dataset as it is, or an archive path opened lazily."""
    if isinstance(obj, xr.Dataset):
        yield obj, None
        return
    if not isinstance(obj, (str, os.PathLike)):
        raise ArchiveError(f"expected a path or an xarray.Dataset, got {type(obj).__name__}")
    if input_kind(obj) != "archive":
        raise ArchiveError(f"{obj} is not an archive: the rough figure draws an archive")
    ds = open_archive(obj)
    try:
        yield ds, obj
    finally:
        ds.close()


def rough_instant(ds, instant=None) -> int:
    """The instant drawn: ``instant`` (index or time [s], :func:`_index`), else the peak
    of the tangential load |T| when there is one, else the last instant."""
    if instant is not None:
        return _index(ds, instant)
    if "T1" in ds:
        t = np.hypot(np.asarray(ds["T1"].values, float),
                     np.asarray(ds["T2"].values, float) if "T2" in ds else 0.0)
        if np.any(t > 0):
            return int(np.argmax(t))
    return ds.sizes["time"] - 1


def _cluster_instants(n) -> np.ndarray:
    return np.unique(np.linspace(0, n - 1, min(n, CLUSTER_INSTANTS)).round().astype(int))


def rough_series(ds) -> dict:
    """What the lower panels draw: ``x`` (W [N] or time [s]), ``against`` ("W" or
    "time"), ``why`` (a phrase), ``contact_fraction`` = contact_area / grid area,
    ``stick_fraction`` = stick_area / contact_area (NaN without contact; None without
    stick_area)."""
    x1, x2, d1, d2 = grid_of(ds)
    area = x1.size * x2.size * d1 * d2
    ca = np.asarray(ds["contact_area"].values, float)
    out = {"contact_fraction": ca / area, "stick_fraction": None}
    if "stick_area" in ds:
        with np.errstate(invalid="ignore", divide="ignore"):
            out["stick_fraction"] = np.where(
                ca > 0, np.asarray(ds["stick_area"].values, float) / np.where(ca > 0, ca, 1),
                np.nan)
    w = np.asarray(ds["W"].values, float)
    dw = np.diff(w)
    varies = w.size > 1 and np.ptp(w) > 1e-3 * max(np.max(np.abs(w)), 1e-300)
    if varies and (np.all(dw >= 0) or np.all(dw <= 0)):
        out.update(x=w, against="W", why="W changes monotonically")
    else:
        why = "W is not monotone" if varies else f"W = {w[-1]:.4g} N held"
        out.update(x=np.asarray(ds["time"].values, float), against="time", why=why)
    return out


def _extent(ds):
    x1, x2, d1, d2 = grid_of(ds)
    return x1, x2, [(x1[0] - d1 / 2) * 1e3, (x1[-1] + d1 / 2) * 1e3,
                    (x2[0] - d2 / 2) * 1e3, (x2[-1] + d2 / 2) * 1e3]


def _image(fig, ax, field, extent, cmap, label, **kw):
    """One map as one image: antialiased when downsampled, rasterized in vector output."""
    im = ax.imshow(field.T, origin="lower", extent=extent, cmap=cmap,
                   interpolation="antialiased", rasterized=True, **kw)
    bar = fig.colorbar(im, ax=ax, fraction=0.046, pad=0.02)
    bar.ax.tick_params(labelsize=6)
    if label:
        bar.set_label(label, fontsize=7)
    return im, bar


def _status_map(fig, ax, status, extent, grid_x, frictional, periodic=False):
    """The status with contact (grey) and stick (black) clusters outlined; returns the
    counts (contact, stick, slip). Frictionless: separated or in contact only."""
    from matplotlib.colors import BoundaryNorm, ListedColormap
    if frictional:
        colours, bounds, ticks = STATUS_COLOURS, [-0.5, 0.5, 1.5, 2.5], [0, 1, 2]
        names = ["separated", "stick", "slip"]
    else:                                  # every contact cell slips
        colours, bounds, ticks = STATUS_COLOURS[::2], [-0.5, 0.5, 2.5], [0, 1.5]
        names = ["separated", "contact"]
    cmap = ListedColormap(colours)
    # colours blended after mapping (rgba stage): a downsampled pixel shows the mix of
    # its cells, not a status between two
    _, bar = _image(fig, ax, status.astype(float), extent, cmap, None,
                    norm=BoundaryNorm(bounds, cmap.N), interpolation_stage="rgba")
    bar.set_ticks(ticks)
    bar.ax.set_yticklabels(names, fontsize=6)
    contact, stick = status != STATUS_SEPARATED, status == STATUS_STICK
    lw = 0.6 if max(status.shape) <= 128 else 0.3
    for mask, colour in ((contact, "0.3"), (stick, "k")):
        if mask.any() and not mask.all():
            ax.contour(grid_x[0] * 1e3, grid_x[1] * 1e3, mask.T.astype(np.float32),
                       levels=[0.5], colors=colour, linewidths=lw).set_rasterized(True)
    counts = (count_clusters(contact, periodic), count_clusters(stick, periodic),
              count_clusters(status == STATUS_SLIP, periodic))
    ax.set_title(f"status: {counts[0]} contact, {counts[1]} stick, {counts[2]} slip "
                 "clusters" if frictional else
                 f"status: {counts[0]} contact clusters (frictionless)", fontsize=8)
    return counts


def _maps(fig, axes, ds, k, frictional):
    x1, x2, extent = _extent(ds)
    panels = list(axes)
    if "h0" in ds:
        h0 = np.asarray(ds["h0"].values, float)
        f, unit = _scaled(float(np.max(np.abs(h0))) or 1e-9, DEPTH_UNITS)
        _image(fig, panels[0], h0 / f, extent, "cividis", f"h0 [{unit}]")
        panels[0].set_title("initial gap h0", fontsize=8)
        panels = panels[1:]
    p = np.asarray(ds["p"].isel(time=k).values, float)
    f, unit = _scaled(float(p.max()) or 1.0, STRESS_UNITS)
    _image(fig, panels[0], p / f, extent, "viridis", f"p [{unit}]", vmin=0.0)
    panels[0].set_title("pressure p", fontsize=8)
    counts = _status_map(fig, panels[1], np.asarray(ds["status"].isel(time=k).values),
                         extent, (x1, x2), frictional, is_periodic(ds))
    for ax in axes:
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)
        ax.set_xlabel("x1 [mm]", fontsize=7, labelpad=1)
    axes[0].set_ylabel("x2 [mm]", fontsize=7)
    return counts


def _fraction_axis(ax, x, y, style, colour, label):
    ax.plot(x, y, style, ms=2.5, lw=1.1, color=colour, label=label)
    top = float(np.nanmax(y)) if np.any(np.isfinite(y)) else 1.0
    ax.set_ylim(0.0, min(1.0, 1.1 * top) if top > 0 else 1.0)
    ax.set_ylabel(label, fontsize=7, color=colour)
    ax.tick_params(labelsize=6)


def _fractions(ax, k, series):
    """The contact-area fraction (left axis) and the stick fraction (right axis), each
    scaled to its own values from 0."""
    x = series["x"]
    _fraction_axis(ax, x, series["contact_fraction"], "o-", "C0",
                   "contact area / grid area")
    if series["stick_fraction"] is not None:
        _fraction_axis(ax.twinx(), x, series["stick_fraction"], "s-", "C3",
                       "stick area / contact area")
    ax.axvline(x[k], color="0.5", lw=0.8, ls=":")
    ax.set_xlabel("normal force W [N]" if series["against"] == "W" else "time t [s]",
                  fontsize=7)
    ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))
    what = "W" if series["against"] == "W" else "time"
    ax.set_title(f"fractions against {what} ({series['why']})", fontsize=8)


def _counts(ax, ds, k, ks, status, frictional):
    """Cluster counts at the instants ``ks`` (``status`` their maps) against time."""
    t = np.asarray(ds["time"].values, float)
    kinds = (("contact", lambda s: s != STATUS_SEPARATED, "k"),
             ("stick", lambda s: s == STATUS_STICK, STATUS_COLOURS[1]),
             ("slip", lambda s: s == STATUS_SLIP, STATUS_COLOURS[2]))
    periodic = is_periodic(ds)
    for name, test, colour in kinds if frictional else kinds[:1]:
        ax.plot(t[ks], [count_clusters(test(s), periodic) for s in status], "o-", ms=2.5, lw=1.1,
                color=colour, label=name)
    ax.axvline(t[k], color="0.5", lw=0.8, ls=":")
    ax.tick_params(labelsize=6)
    ax.set_xlabel("time t [s]", fontsize=7)
    ax.set_ylabel("clusters", fontsize=7)
    every = "" if len(ks) == len(t) else f", {len(ks)} of {len(t)} instants"
    ax.set_title(f"edge-connected clusters{every}", fontsize=8)
    ax.legend(fontsize=6, loc="best")


def plot_rough(ds, instant=None, *, fig=None):
    """The rough-contact figure (see the module): maps at one instant, fractions and
    cluster counts over the run.

    Parameters
    ----------
    ds : xarray.Dataset or path
        An archive (any: ``h0`` is drawn when it holds one). A path is opened lazily and
        only the values drawn are read and checked.
    instant : int or float, optional
        Index (negative from the end) or time [s] of the maps; default the peak
        tangential load, else the last instant.
    fig : matplotlib.figure.Figure, optional
        Draw into it; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ArchiveError
        Not an archive, or a value drawn breaks the archive's rules.
    """
    with _lazy(ds) as (ds, path):
        k = rough_instant(ds, instant)
        ks = _cluster_instants(ds.sizes["time"])
        if path is not None:
            _check(ds, path, k, ks)
        fig = new_figure() if fig is None else fig
        nmap = 3 if "h0" in ds else 2
        grid = fig.add_gridspec(2, 6, height_ratios=(1.5, 1.0))
        maps = [fig.add_subplot(grid[0, j * (6 // nmap):(j + 1) * (6 // nmap)])
                for j in range(nmap)]
        frictional = "stick_area" in ds
        counts = _maps(fig, maps, ds, k, frictional)
        _fractions(fig.add_subplot(grid[1, :3]), k, rough_series(ds))
        _counts(fig.add_subplot(grid[1, 3:]), ds, k, ks,
                np.asarray(ds["status"].isel(time=ks).values), frictional)
        t = float(ds["time"].values[k])
        fig.suptitle(f"{_scene_title(ds)}: {ds.sizes['x1']}x{ds.sizes['x2']} cells, maps "
                     f"at t = {t:.4g} s ({_time_label(ds, k)}); {counts[0]} contact "
                     "clusters", fontsize=9)
    return fig
