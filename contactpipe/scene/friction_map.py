"""A mapped friction coefficient mu(x1, x2) read from a netCDF file (docs/scene-file.md).

``[friction] mu`` is a number or the name of a netCDF file holding a variable ``mu`` over
the dimensions ``x1``, ``x2`` (coordinates in m, any order), on the scene's grid or
covering it. It is interpolated linearly onto the cell centres (xarray's ``interp``),
clipped to the range of the file's values, so a uniform map gives exactly its value.
Refused, with one message naming ``friction.mu`` and the file: a missing or unreadable
file, no variable ``mu`` over x1, x2, coordinates that are not distinct finite numbers,
values that are not finite or are negative, and a grid that the file does not cover.

Units: mu [1], coordinates [m], or in mm or um when their ``units`` attribute says so
(converted to metres); other units, and coordinates that are dates, are refused.
"""
from __future__ import annotations

import os

import numpy as np

from ..exceptions import SceneError
from .gridded import coordinate_problems, coverage_problems, in_metres, variable_problems

__all__ = ["check_mu_file", "mu_on_grid", "largest", "WHERE"]

#: The scene key every message names.
WHERE = "friction.mu"


def _open(path):
    import xarray as xr  # lazily: the numerical core does not need xarray

    return xr.open_dataset(path)


def check_mu_file(file, x1=None, x2=None) -> list:
    """Problems with a friction-map file, and with the grid when ``x1``, ``x2`` are given.

    Parameters
    ----------
    file : str or path-like
        A netCDF file with a variable ``mu`` [1] over dimensions ``x1``, ``x2`` [m].
    x1, x2 : array_like, optional
        Cell-centre coordinates of the grid [m].

    Returns
    -------
    list of str
        One message per problem, each naming ``friction.mu`` and the file; empty when the
        file can serve the grid.
    """
    path = os.fspath(file)
    where = f"{WHERE} = {path!r}"
    if not os.path.isfile(path):
        return [f"{where}: no such file (give a number >= 0, or a netCDF file with a "
                f"variable 'mu' over x1, x2)"]
    try:
        ds = _open(path)
    except Exception as exc:  # noqa: BLE001 - any failure to read is the user's file
        return [f"{where}: not a readable netCDF file ({type(exc).__name__}: {exc})"]
    with ds:
        problems = variable_problems(ds, "mu", where, "the friction coefficient", "1")
        if problems:
            return problems
        values = np.asarray(ds["mu"].values, dtype=float)
        bad = int(np.count_nonzero(~np.isfinite(values)))
        if bad:
            return [f"{where}: 'mu' holds NaN or inf at {bad} of {values.size} points; "
                    f"every value must be finite"]
        if values.min() < 0:
            return [f"{where}: 'mu' is negative at {int(np.count_nonzero(values < 0))} of "
                    f"{values.size} points (min {values.min():g}); mu must be >= 0"]
        problems, ranges = coordinate_problems(ds, where)
    if problems or x1 is None or x2 is None:
        return problems
    return coverage_problems(ranges, x1, x2, where)


def mu_on_grid(file, x1, x2) -> np.ndarray:
    """The friction coefficient at the cell centres (N1, N2) [1].

    Taken as it is where the file's coordinates are the grid's, else interpolated
    linearly and clipped to the range of the file's values (a uniform map stays exact).

    Raises
    ------
    SceneError
        The file cannot serve the grid (:func:`check_mu_file`).
    """
    problems = check_mu_file(file, x1, x2)
    if problems:
        raise SceneError(problems)
    x1 = np.asarray(x1, dtype=float)
    x2 = np.asarray(x2, dtype=float)
    with _open(os.fspath(file)) as ds:
        mu = in_metres(ds["mu"].load()).transpose("x1", "x2").sortby(["x1", "x2"])
        mu = mu.astype(float)
    lo, hi = float(mu.min()), float(mu.max())
    c1, c2 = np.asarray(mu.x1.values, float), np.asarray(mu.x2.values, float)
    if c1.shape == x1.shape and c2.shape == x2.shape and np.array_equal(c1, x1) \
            and np.array_equal(c2, x2):
        return np.array(mu.values, dtype=float)
    # clip into the file's range: check_mu_file allowed a rounding-size overshoot
    x1c = np.clip(x1, c1[0], c1[-1])
    x2c = np.clip(x2, c2[0], c2[-1])
    out = np.asarray(mu.interp(x1=x1c, x2=x2c, method="linear").values, dtype=float)
    return np.clip(out, lo, hi)


def largest(file) -> float:
    """The largest value of a (checked) friction-map file [1]."""
    with _open(os.fspath(file)) as ds:
        return float(ds["mu"].max())
