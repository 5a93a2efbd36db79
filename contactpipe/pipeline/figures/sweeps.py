"""The figure of a sweep: one variable of every member over time (or a reduced value
over a swept parameter)."""
from __future__ import annotations

import itertools

import numpy as np

from ...exceptions import ArchiveError
from ...nomenclature import HISTORY, VARIABLES
from .canvas import axes_of
from .common import _opened

__all__ = ["plot_sweep"]

# --------------------------------------------------------------------------- sweeps

BASE_DIMS = ("time", "t_norm", "cycle", "x1", "x2")
MAX_LEGEND = 20             # more members than this: no legend


def _member_label(sw, sel) -> str:
    """'mu = 0.1, tau_ratio = 2' for one member: the coordinates along each looped
    dimension (the dimension's own, or those along it in a zip sweep; not the digest)."""
    parts = []
    for d, i in sel.items():
        names = [c for c, v in sw.coords.items()
                 if v.dims == (d,) and c != "digest" and (c == d or c not in sw.dims)]
        names.sort(key=lambda c: c != d)
        if not names:
            parts.append(f"{d} = {i}")
        parts += [f"{c} = {_value_text(sw[c].values[i])}" for c in names]
    return ", ".join(parts) or "sweep"


def _value_text(v):
    v = v.item() if hasattr(v, "item") else v
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


#: SI units shown in a unit of the contact's size: (factor to multiply by, label).
DISPLAY_UNITS = {"m2": (1e6, "mm²"), "m3": (1e9, "mm³"), "m": (1e6, "µm"), "J": (1e6, "µJ"),
                 "Pa": (1e-6, "MPa"), "N m": (1e3, "N mm")}


def _display_unit(units):
    """(factor, label) to show values in ``units`` (SI) at the contact's scale."""
    return DISPLAY_UNITS.get(units, (1.0, "" if units in ("", "1") else units))


def _axis_labels(ax, sw, variable, xname, reduced):
    known = VARIABLES.get(variable) or HISTORY.get(variable, {})
    units = sw[variable].attrs.get("units", known.get("units", ""))
    long = sw[variable].attrs.get("long_name", known.get("long_name", variable))
    unit = _display_unit(units)[1]
    ylab = f"{'max over x1, x2 of ' if reduced else ''}{long}" \
        + (f" [{unit}]" if unit else "")
    ax.set_ylabel(ylab, fontsize=9)
    xunits = sw[xname].attrs.get("units", "") if xname in sw.variables else ""
    if xname == "t_norm":
        ax.set_xlabel("t / τ (dimensionless time)")
    else:
        ax.set_xlabel(f"{xname}" + (f" [{xunits}]" if xunits else ""))


def plot_sweep(sw, variable="contact_area", x="time", *, ax=None):
    """One curve of ``variable`` per member of a combined sweep Dataset.

    Parameters
    ----------
    sw : xarray.Dataset or path
        A sweep (:func:`contactpipe.open_sweep`, or its folder): archives combined along
        one dimension per swept parameter; the dimensions beyond time/t_norm/x1/x2 are
        looped over (all their combinations).
    variable : str
        A series (over time, or over cycle for a wear run: then drawn against cycle, each
        member at the cycles it recorded). A field is reduced to its largest value over
        x1, x2.
        Shown at the contact's scale (:data:`DISPLAY_UNITS`: an area in mm², a length in
        µm, an energy in µJ, a stress in MPa), labelled by its long name and unit.
    x : str
        The abscissa; ``"time"`` uses ``t_norm`` when the sweep has it (members with
        different windows are aligned on it).
    ax : matplotlib.axes.Axes, optional
        Draw into it; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ArchiveError
        ``variable`` or ``x`` is not in the sweep.
    """
    with _opened(sw, "sweep") as sw:
        if variable not in sw:
            raise ArchiveError(f"variable {variable!r} is not in the sweep; it has: "
                               f"{', '.join(sorted(map(str, sw.data_vars)))}")
        da = sw[variable]
        reduced = [d for d in ("x1", "x2") if d in da.dims]
        if reduced:
            da = da.max(reduced)
        has_t_norm = "t_norm" in sw.coords or "t_norm" in sw.dims
        xname = "t_norm" if (x == "time" and has_t_norm) else x
        if x == "time" and "cycle" in da.dims:
            xname = "cycle"
        if xname not in sw.coords and xname not in sw.dims and xname not in sw:
            raise ArchiveError(f"x = {x!r} is not a coordinate of the sweep")
        extra = [d for d in da.dims if d not in BASE_DIMS]
        factor = _display_unit(sw[variable].attrs.get(
            "units", (VARIABLES.get(variable) or HISTORY.get(variable, {})).get("units", "")))[0]
        fig, ax = axes_of(ax)
        combos = list(itertools.product(*[range(da.sizes[d]) for d in extra])) \
            if extra else [()]
        xs_all = sw[xname] if xname in sw.variables else None
        for n, combo in enumerate(combos):
            sel = dict(zip(extra, combo, strict=True))
            y = da.isel(sel) if sel else da
            xv = y[xname] if xs_all is None else \
                xs_all.isel({d: i for d, i in sel.items() if d in xs_all.dims})
            xv = np.asarray(xv.values, float).ravel()
            yv = np.asarray(y.values, float).ravel() * factor
            if xv.size != yv.size:
                raise ArchiveError(f"x = {xname!r} does not run along {variable!r} "
                                   f"({xv.size} values against {yv.size})")
            kept = np.isfinite(yv)      # a wear sweep: each member at its own records
            xv, yv = xv[kept], yv[kept]
            ax.plot(xv, yv, "-", marker="o" if yv.size <= 30 else None, ms=3, lw=1.2,
                    color=f"C{n % 10}", label=_member_label(sw, sel))
        _axis_labels(ax, sw, variable, xname, reduced)
        if xname == "cycle" and float(sw["cycle"].max()) > 10 * max(float(sw["cycle"].min()), 1):
            ax.set_xscale("log")
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, lw=0.3, alpha=0.5)
        if len(combos) <= MAX_LEGEND:
            ax.legend(fontsize=7, ncol=1 if len(combos) <= 8 else 2)
        ax.set_title(f"sweep over {', '.join(extra) if extra else '(no axis)'}: {variable} "
                     f"({len(combos)} members)", fontsize=9)
    return fig
