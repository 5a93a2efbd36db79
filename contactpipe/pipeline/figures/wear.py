"""The ``wear`` figure of a fretting-wear archive: how the scar grows over the cycles.

Six panels (:func:`plot_wear`): the worn surface through the centre at a few recorded
cycles, the wear-depth map at the last one, the pressure through the centre (each kept
loop's peak over its cycle when the archive keeps loops of tractions, else the last
simulated cycle's), the worn volume and the dissipated energy against cycles, the largest
pressure of each cycle, and the smallest stick area of each cycle. An archive without the
``cycle`` dimension is refused with a one-line reason.
"""
from __future__ import annotations

import numpy as np

from ...exceptions import ArchiveError
from ..inputs import centre_rows, grid_of
from .canvas import new_figure
from .common import _dataset, _scene_title

__all__ = ["plot_wear", "is_wear_archive", "kept_loop_cycles", "WEAR_SERIES"]

#: The wear history an archive of a wear run holds over ``cycle``.
WEAR_SERIES = ("wear_depth", "worn_volume", "cumulative_dissipation", "cycle_p_max",
               "cycle_stick_area")
#: How the kept loops of tractions are named: the pressure over (loop_cycle, loop_time,
#: x1, x2), its cycle coordinate.
KEPT_PRESSURE, KEPT_CYCLE = "loop_p", "loop_cycle"


def is_wear_archive(ds) -> bool:
    """True for an archive of a wear run: a ``cycle`` dimension and the wear history."""
    return "cycle" in ds.dims and all(v in ds for v in WEAR_SERIES)


def _require_wear(ds) -> None:
    if "cycle" not in ds.dims:
        raise ArchiveError(
            f"the wear figure needs an archive of a wear run (a scene with [wear]); "
            f"{_scene_title(ds)!r} has no 'cycle' dimension (dims: "
            f"{', '.join(map(str, ds.dims))})")
    missing = [v for v in WEAR_SERIES if v not in ds]
    if missing:
        raise ArchiveError(f"the wear figure needs the wear history over 'cycle'; "
                           f"{_scene_title(ds)!r} lacks {', '.join(missing)}")


def kept_loop_cycles(ds) -> list[int]:
    """The cycles whose loop of tractions the archive keeps (none: [])."""
    if KEPT_PRESSURE not in ds or KEPT_CYCLE not in ds.coords:
        return []
    return [int(c) for c in np.asarray(ds[KEPT_CYCLE].values)]


def _shown_cycles(cycles, count=5) -> list[int]:
    """Indices of about ``count`` recorded cycles, log-spaced from the first to the last."""
    n = len(cycles)
    if n <= count:
        return list(range(n))
    c = np.asarray(cycles, float)
    want = np.geomspace(max(c[0], 1.0), c[-1], count)
    return sorted({int(np.argmin(np.abs(np.log(c.clip(1.0)) - np.log(w)))) for w in want})


def _rows(ds):
    x1, x2, d1, d2 = grid_of(ds)
    return x1, x2, d1, d2, centre_rows(x2)


def _centre_profile(da, rows) -> np.ndarray:
    """A field over (x1, x2) through the centre (the two middle rows of an even grid
    averaged)."""
    return np.asarray(da.isel(x2=rows).values, float).reshape(da.sizes["x1"], -1).mean(axis=1)


def _scaled(value, units):
    """(factor, unit) showing ``value`` in one of (factor, unit) ``units``, largest first."""
    for factor, unit in units:
        if abs(value) >= factor:
            return factor, unit
    return units[-1]


DEPTH_UNITS = ((1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm"))
STRESS_UNITS = ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa"), (1.0, "Pa"))


def _worn_profiles(ax, ds, geo):
    x1, rows = geo[0], geo[4]
    cycles = np.asarray(ds["cycle"].values)
    depth = ds["wear_depth"]
    f, unit = _scaled(float(np.max(np.abs(depth.isel(cycle=-1).values))) or 1e-9,
                      DEPTH_UNITS)
    for n, j in enumerate(_shown_cycles(cycles)):
        ax.plot(x1 * 1e3, -_centre_profile(depth.isel(cycle=j), rows) / f, "-", lw=1.2,
                color=f"C{n % 10}", label=f"N = {int(cycles[j]):,}")
    ax.axhline(0.0, color="0.7", lw=0.6, zorder=-1)
    ax.set_xlabel("x1 [mm]", fontsize=8)
    ax.set_ylabel(f"worn surface [{unit}]", fontsize=8)
    ax.set_title("worn profile through the centre", fontsize=9)
    ax.legend(fontsize=6)


def _depth_map(fig, ax, ds, geo):
    x1, x2, d1, d2, _ = geo
    h = np.asarray(ds["wear_depth"].isel(cycle=-1).values, float)
    f, unit = _scaled(float(h.max()) or 1e-9, DEPTH_UNITS)
    extent = [(x1[0] - d1 / 2) * 1e3, (x1[-1] + d1 / 2) * 1e3,
              (x2[0] - d2 / 2) * 1e3, (x2[-1] + d2 / 2) * 1e3]
    im = ax.imshow(h.T / f, origin="lower", extent=extent, cmap="inferno_r",
                   interpolation="nearest")
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.03, label=f"wear depth [{unit}]")
    im.colorbar.ax.tick_params(labelsize=7)
    ax.set_aspect("equal")
    ax.set_xlabel("x1 [mm]", fontsize=8)
    ax.set_ylabel("x2 [mm]", fontsize=8)
    ax.set_title(f"wear depth at N = {int(ds['cycle'].values[-1]):,}", fontsize=9)


def _pressure_profiles(ax, ds, geo):
    """Each kept loop's peak pressure over its cycle, else the last simulated cycle's."""
    x1, rows = geo[0], geo[4]
    kept = kept_loop_cycles(ds)
    if kept:
        peak = ds[KEPT_PRESSURE].max(dim=[d for d in ds[KEPT_PRESSURE].dims
                                          if d not in (KEPT_CYCLE, "x1", "x2")])
        shown = [(f"N = {kept[j]:,}", peak.isel({KEPT_CYCLE: j}))
                 for j in _shown_cycles(kept)]
        title = "peak p over each kept cycle"
    else:
        last = int(ds.attrs.get("cycles_simulated", 0)) or None
        shown = [(f"last simulated cycle{f' (of {last:,} solved)' if last else ''}",
                  ds["p"].max(dim="time"))]
        title = "peak p over the last cycle"
    top = max(float(np.max(np.asarray(da.values))) for _, da in shown) or 1.0
    f, unit = _scaled(top, STRESS_UNITS)
    for n, (label, da) in enumerate(shown):
        ax.plot(x1 * 1e3, _centre_profile(da, rows) / f, lw=1.2, color=f"C{n % 10}",
                label=label)
    ax.set_xlabel("x1 [mm]", fontsize=8)
    ax.set_ylabel(f"p [{unit}]", fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6)


def _history(axes, ds):
    n = np.asarray(ds["cycle"].values, float)
    vol, ax_v = np.asarray(ds["worn_volume"].values, float), axes[0]
    ax_v.plot(n, vol * 1e9, "o-", ms=2.5, lw=1.2, color="C0", label="worn volume")
    ax_v.set_ylabel("worn volume [mm³]", fontsize=8, color="C0")
    ax_e = ax_v.twinx()
    # hollow markers: under Archard with a uniform mu or the energy law the two curves
    # coincide (the volume is proportional to the energy), and the volume shows through
    ax_e.plot(n, np.asarray(ds["cumulative_dissipation"].values, float), "s--", ms=3.5,
              mfc="none", lw=1.0, color="C3", label="dissipated energy")
    ax_e.set_ylabel("dissipated energy [J]", fontsize=8, color="C3")
    ax_v.set_title("worn volume and dissipated energy", fontsize=9)
    pm = np.asarray(ds["cycle_p_max"].values, float)
    f, unit = _scaled(float(pm.max()) or 1.0, STRESS_UNITS)
    axes[1].plot(n, pm / f, "o-", ms=2.5, lw=1.2, color="C2")
    axes[1].set_ylabel(f"largest p in the cycle [{unit}]", fontsize=8)
    axes[1].set_title("peak pressure per cycle", fontsize=9)
    axes[2].plot(n, np.asarray(ds["cycle_stick_area"].values, float) * 1e6, "o-", ms=2.5,
                 lw=1.2, color="C4")
    axes[2].set_ylabel("smallest stick area [mm²]", fontsize=8)
    axes[2].set_title("stick area per cycle", fontsize=9)
    for ax in (ax_v, ax_e, *axes[1:]):
        if n[0] > 0 and n[-1] > 10 * n[0]:
            ax.set_xscale("log")
        ax.tick_params(labelsize=7)
    for ax in axes:
        ax.set_xlabel("cycles N", fontsize=8)
        ax.grid(True, lw=0.3, alpha=0.5)


def plot_wear(ds, *, fig=None):
    """The wear figure of a wear archive (six panels, see the module).

    Parameters
    ----------
    ds : xarray.Dataset or path
        An archive of a wear run: the wear history over ``cycle`` (wear_depth,
        worn_volume, cumulative_dissipation, cycle_p_max, cycle_stick_area) and the last
        simulated cycle's fields over (time, x1, x2).
    fig : matplotlib.figure.Figure, optional
        Draw into it (2 x 3 axes); default a new figure.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ArchiveError
        The archive is not one of a wear run (no ``cycle`` dimension or no wear history).
    """
    with _dataset(ds) as ds:
        _require_wear(ds)
        fig = new_figure() if fig is None else fig
        axes = fig.subplots(2, 3)
        geo = _rows(ds)
        _worn_profiles(axes[0, 0], ds, geo)
        _depth_map(fig, axes[0, 1], ds, geo)
        _pressure_profiles(axes[0, 2], ds, geo)
        _history(axes[1], ds)
        for ax in axes[0]:
            ax.tick_params(labelsize=7)
        solved = ds.attrs.get("cycles_simulated", "?")
        fig.suptitle(f"{_scene_title(ds)}: {ds.attrs.get('wear_law', '?')} wear over "
                     f"{int(ds['cycle'].values[-1]):,} cycles ({solved} simulated)",
                     fontsize=10)
    return fig
