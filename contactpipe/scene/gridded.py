"""Fields over the contact grid read from netCDF files: their coordinates and coverage.

A surface gap (``geometry.file``) and a friction map (``friction.mu``) are both a variable
over dimensions ``x1``, ``x2`` with coordinates in metres, any order, that must cover the
scene's grid. :func:`variable_problems` checks the variable, :func:`coordinate_problems`
the coordinates and :func:`coverage_problems` the grid, with one wording for both callers.
"""
from __future__ import annotations

import numpy as np

__all__ = ["coordinate_problems", "coverage_problems", "variable_problems",
           "in_metres", "LENGTH_UNITS"]

#: Units a coordinate may carry, and their size in metres; none given means metres.
LENGTH_UNITS = {"m": 1.0, "metre": 1.0, "metres": 1.0, "meter": 1.0, "meters": 1.0,
                "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6}


def _unit_factor(ds, dim: str):
    """(metres per unit of coordinate ``dim``, problem or None)."""
    units = ds[dim].attrs.get("units")
    if units is None:
        return 1.0, None
    key = str(units).strip()
    if key == "":
        return 1.0, None
    factor = LENGTH_UNITS.get(key)
    if factor is None:
        return 1.0, (f"coordinate {dim!r} has units {str(units)[:40]!r}: allowed m, mm, "
                     f"um (or \u00b5m), or none (metres)")
    return factor, None


def in_metres(ds):
    """``ds`` with its ``x1``, ``x2`` coordinates converted to metres (from the units
    of :data:`LENGTH_UNITS`); checked by :func:`coordinate_problems` first."""
    for dim in ("x1", "x2"):
        factor, _ = _unit_factor(ds, dim)
        if factor != 1.0:
            ds = ds.assign_coords({dim: (dim, np.asarray(ds[dim].values, float) * factor,
                                         dict(ds[dim].attrs, units="m"))})
    return ds


def variable_problems(ds, name: str, where: str, meaning: str, unit: str) -> list:
    """Problems of a dataset's variable ``name``: it must exist, hold real numbers and lie
    over dimensions ``x1``, ``x2``. ``meaning`` says what it is in the messages ("the
    gap"), ``unit`` its unit ("m"); ``where`` starts every message."""
    if name not in ds.data_vars:
        found = ", ".join(map(str, ds.data_vars)) or "none"
        return [f"{where}: no variable {name!r} (found: {found}); {meaning} [{unit}] must be "
                f"a variable {name!r} over dimensions x1, x2"]
    var = ds[name]
    if var.dtype.kind not in "iuf":
        return [f"{where}: variable {name!r} holds {var.dtype} values; {meaning} must be "
                f"real numbers [{unit}]"]
    if set(var.dims) != {"x1", "x2"}:
        return [f"{where}: variable {name!r} has dimensions {tuple(var.dims)}, expected "
                f"('x1', 'x2')"]
    return []


def coordinate_problems(ds, where: str):
    """(problems, {dim: (min, max)}) of a dataset's ``x1``, ``x2`` coordinates [m].

    Each coordinate must exist, hold at least two distinct finite real numbers (not
    dates nor durations) and carry units of length that :data:`LENGTH_UNITS` converts
    (m, mm, um; none: metres); ``where`` starts every message (the key and the file).
    The ranges are in metres.
    """
    problems, ranges = [], {}
    for dim in ("x1", "x2"):
        if dim not in ds.coords:
            problems.append(f"{where}: dimension {dim!r} has no coordinate [m]")
            continue
        if ds[dim].dtype.kind not in "iuf":
            problems.append(f"{where}: coordinate {dim!r} holds {ds[dim].dtype} values; "
                            f"coordinates must be real numbers [m]")
            continue
        factor, problem = _unit_factor(ds, dim)
        if problem is not None:
            problems.append(f"{where}: {problem}")
            continue
        c = np.asarray(ds[dim].values, dtype=float) * factor
        if c.size < 2 or not np.all(np.isfinite(c)) or np.unique(c).size != c.size:
            problems.append(f"{where}: coordinate {dim!r} must hold at least 2 distinct "
                            f"finite values [m], got {c.size} value(s)")
            continue
        ranges[dim] = (float(c.min()), float(c.max()))
    return problems, ranges


def coverage_problems(ranges: dict, x1, x2, where: str) -> list:
    """Problems where the cell centres ``x1``, ``x2`` [m] leave the file's coordinate
    ``ranges`` (from :func:`coordinate_problems`), beyond a rounding slack of 1e-9 of the
    range."""
    problems = []
    for dim, x in (("x1", x1), ("x2", x2)):
        lo, hi = ranges[dim]
        x = np.asarray(x, dtype=float)
        slack = 1e-9 * (hi - lo)
        if x.min() < lo - slack or x.max() > hi + slack:
            problems.append(f"{where}: does not cover the grid: the grid's {dim} runs from "
                            f"{x.min():.6g} to {x.max():.6g} m, outside the file's {dim} "
                            f"from {lo:.6g} to {hi:.6g} m; shrink grid.size or extend the "
                            f"file")
    return problems
