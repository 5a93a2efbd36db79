"""Gap builders: the composite initial gap hi(x1, x2) of the two bodies.

Pure functions of the 1-D cell-centre coordinates ``x1`` (N1,) and ``x2`` (N2,) [m],
returning the gap on the grid as an array of shape (N1, N2) [m], ``gap[i, j]`` at
``(x1[i], x2[j])``. The analytical shapes have their first contact point at the origin,
where the gap is zero (docs/scene-file.md, [geometry]); the gap is >= 0 everywhere.

- :func:`sphere_gap`: the Hertz paraboloid r^2 / (2 R).
- :func:`ellipsoid_gap`: x1^2 / (2 R1) + x2^2 / (2 R2).
- :func:`flat_punch_gap`: 0 on the flat circular end, a finite step outside.
- :func:`surface_gap`: read from a netCDF file (variable ``gap`` over ``x1``, ``x2``,
  interpolated linearly onto the grid) or a ``.npy`` array on the grid itself.
- :func:`topography_gap`: ``shape = "surface"`` whatever its file: a gap file as above,
  or measured heights z (:mod:`contactpipe.scene.topography`), whose gap is
  max(z) - z on the grid (a peak closes the gap; first contact at the highest point).
- :func:`rough_gap`: a generated self-affine surface (:mod:`contactpipe.scene.rough`).

Both may ride on a sphere (``form = "sphere"``): the heights minus r^2 / (2 R).

Units: metres throughout.
"""
from __future__ import annotations

import functools
import os

import numpy as np

from ..exceptions import SceneError
from . import rough, topography
from .gridded import coordinate_problems, coverage_problems, in_metres, variable_problems

__all__ = ["sphere_gap", "ellipsoid_gap", "flat_punch_gap", "surface_gap", "check_surface",
           "surface_edge", "is_gap_file", "topography_gap", "rough_gap", "heights_gap"]

#: Units a netCDF ``gap`` variable may declare (absent is read as metres).
_METRE = ("m", "meter", "metre", "meters", "metres")


def _axes(x1, x2):
    """Broadcastable column / row views of the 1-D coordinates."""
    x1 = np.asarray(x1, dtype=float).reshape(-1, 1)
    x2 = np.asarray(x2, dtype=float).reshape(1, -1)
    return x1, x2


def sphere_gap(x1, x2, radius):
    """Gap of a sphere on a flat, ``r^2 / (2 R)`` [m].

    This is the paraboloid of Hertz theory rather than the exact cap
    ``R - sqrt(R^2 - r^2)``: the two agree to O(r^4 / R^3), which is far below the
    accuracy of the half-space approximation the method rests on (a << R), it keeps the
    comparison with the Hertz closed forms exact, and it stays defined where r > R.

    Parameters
    ----------
    x1, x2 : array_like, shape (N1,) and (N2,)
        Cell-centre coordinates [m].
    radius : float
        Composite radius of curvature R [m] (1/R = 1/R_indenter + 1/R_halfspace).

    Returns
    -------
    numpy.ndarray, shape (N1, N2)
        Initial gap [m].
    """
    x1, x2 = _axes(x1, x2)
    return (x1 ** 2 + x2 ** 2) / (2.0 * radius)


def ellipsoid_gap(x1, x2, radii):
    """Gap of an ellipsoid on a flat, ``x1^2 / (2 R1) + x2^2 / (2 R2)`` [m].

    The same paraboloid approximation as :func:`sphere_gap`, with principal radii of
    curvature along the grid axes.

    Parameters
    ----------
    x1, x2 : array_like, shape (N1,) and (N2,)
        Cell-centre coordinates [m].
    radii : (float, float)
        Principal radii of curvature (R1 along x1, R2 along x2) [m].

    Returns
    -------
    numpy.ndarray, shape (N1, N2)
        Initial gap [m].
    """
    r1, r2 = radii
    x1, x2 = _axes(x1, x2)
    return x1 ** 2 / (2.0 * r1) + x2 ** 2 / (2.0 * r2)


def flat_punch_gap(x1, x2, radius, height=None):
    """Gap of a flat-ended cylindrical punch: 0 where r <= radius, ``height`` outside [m].

    The punch is a cylinder of finite height rather than an infinitely tall one: the
    gap outside the flat end is ``height`` (default: the radius), so no cell outside the
    end can touch under any realistic load, while every value stays finite and an
    archive never holds inf.

    Parameters
    ----------
    x1, x2 : array_like, shape (N1,) and (N2,)
        Cell-centre coordinates [m].
    radius : float
        Radius of the flat circular end [m].
    height : float, optional
        Gap outside the flat end [m]; default ``radius``.

    Returns
    -------
    numpy.ndarray, shape (N1, N2)
        Initial gap [m].
    """
    h = float(radius if height is None else height)
    x1, x2 = _axes(x1, x2)
    return np.where(x1 ** 2 + x2 ** 2 <= radius ** 2, 0.0, h)


def _is_npy(path: str) -> bool:
    return path.lower().endswith(".npy")


def _is_real(dtype) -> bool:
    """Integers or floats: not complex, boolean, object, text or structured."""
    return np.dtype(dtype).kind in "iuf"


@functools.lru_cache(maxsize=16)
def _nonfinite(path: str, mtime_ns: int, size: int) -> int:
    """How many values of a real .npy array are NaN or inf, read in blocks of rows
    (memory-mapped); cached by the file's modification time and size."""
    arr = np.load(path, mmap_mode="r", allow_pickle=False)
    if arr.dtype.kind != "f":
        return 0
    rows = max(1, (1 << 22) // max(1, arr.shape[1]))
    return sum(int(np.count_nonzero(~np.isfinite(arr[i:i + rows])))
               for i in range(0, arr.shape[0], rows))


def check_surface(file, x1=None, x2=None) -> list:
    """Problems with a surface file, and with the grid when ``x1``, ``x2`` are given.

    Reads headers and coordinates, and scans a .npy array for NaN and inf once per
    version of the file (memory-mapped, in blocks; the count is cached by modification
    time and size), so it is cheap enough to run on every scene validation.

    Parameters
    ----------
    file : str or path-like
        A netCDF file with a variable ``gap`` over dimensions ``x1``, ``x2`` [m], or a
        ``.npy`` array of shape (N1, N2).
    x1, x2 : array_like, optional
        Cell-centre coordinates of the grid [m].

    Returns
    -------
    list of str
        One message per problem, each naming ``geometry.file`` and the file; empty
        when the file can serve the grid. Refused: a missing or unreadable file, a gap
        that is not real numbers (complex, boolean, object, text), a .npy array that is
        not 2-D or holds NaN or inf, a netCDF gap without coordinates or not over
        x1, x2.
    """
    path = os.fspath(file)
    where = f"geometry.file {path!r}"
    if not os.path.isfile(path):
        return [f"{where}: no such file"]
    grid = x1 is not None and x2 is not None
    if _is_npy(path):
        try:
            arr = np.load(path, mmap_mode="r", allow_pickle=False)
        except Exception as exc:  # noqa: BLE001 - any failure to read is the user's file
            return [f"{where}: not a readable .npy array ({exc})"]
        if arr.ndim != 2 or not _is_real(arr.dtype):
            return [f"{where}: must hold a 2-D array of real numbers [m] of shape (N1, N2), "
                    f"got shape {arr.shape} of {arr.dtype}"
                    + (" (a complex gap has no meaning)"
                       if np.issubdtype(arr.dtype, np.complexfloating) else "")]
        bad = _nonfinite(path, os.stat(path).st_mtime_ns, os.stat(path).st_size)
        if bad:
            return [f"{where}: the gap holds NaN or inf at {bad} of {arr.size} points; "
                    f"every value must be finite [m]"]
        if grid and arr.shape != (len(x1), len(x2)):
            return [f"{where}: array of shape {arr.shape}, but grid.points is "
                    f"[{len(x1)}, {len(x2)}]; a .npy gap must be given on the scene's grid "
                    f"(or use a netCDF file with coordinates x1, x2)"]
        return []
    import xarray as xr  # lazily: the numerical core does not need xarray

    try:
        ds = xr.open_dataset(path)
    except Exception as exc:  # noqa: BLE001
        return [f"{where}: not a readable netCDF file ({type(exc).__name__}: {exc}); "
                f"give a netCDF file with a variable 'gap' over x1, x2, or a .npy array"]
    with ds:
        problems = variable_problems(ds, "gap", where, "the gap", "m")
        if problems:
            return problems
        units = str(ds["gap"].attrs.get("units", "m")).strip()
        if units not in _METRE:
            return [f"{where}: variable 'gap' has units {units!r}, expected 'm'"]
        problems, ranges = coordinate_problems(ds, where)
        if problems or not grid:
            return problems
        return coverage_problems(ranges, x1, x2, where)


def surface_gap(x1, x2, file):
    """Gap read from a file [m].

    Parameters
    ----------
    x1, x2 : array_like, shape (N1,) and (N2,)
        Cell-centre coordinates [m].
    file : str or path-like
        Either a netCDF file with a variable ``gap`` [m] over dimensions ``x1``, ``x2``
        (with coordinates in m, any order, covering the grid), interpolated linearly
        onto the grid with xarray; or a ``.npy`` array of exactly shape (N1, N2), taken
        as the gap at the cell centres.

    Returns
    -------
    numpy.ndarray, shape (N1, N2)
        Initial gap [m], as the file gives it (not shifted: under force control a
        constant offset only changes the rigid approach omega3).

    Raises
    ------
    SceneError
        The file is missing, unreadable, has no ``gap`` over ``x1``, ``x2``, has the
        wrong shape, does not cover the grid, or holds NaN or inf.
    """
    problems = check_surface(file, x1, x2)
    if problems:
        raise SceneError(problems)
    path = os.fspath(file)
    if _is_npy(path):
        out = np.array(np.load(path, allow_pickle=False), dtype=float)
    else:
        import xarray as xr

        x1 = np.asarray(x1, dtype=float)
        x2 = np.asarray(x2, dtype=float)
        with xr.open_dataset(path) as ds:
            gap = in_metres(ds["gap"].load()).transpose("x1", "x2").sortby(["x1", "x2"])
        gap = gap.astype(float)
        # Clip into the file's range: check_surface allowed a rounding-size overshoot.
        x1c = np.clip(x1, float(gap.x1[0]), float(gap.x1[-1]))
        x2c = np.clip(x2, float(gap.x2[0]), float(gap.x2[-1]))
        out = np.asarray(gap.interp(x1=x1c, x2=x2c, method="linear").values, dtype=float)
    if not np.all(np.isfinite(out)):
        bad = int(np.count_nonzero(~np.isfinite(out)))
        raise SceneError(f"geometry.file {path!r}: the gap holds NaN or inf at {bad} of "
                         f"{out.size} grid points; every value must be finite [m]")
    return out



def surface_edge(file, x1, x2):
    """The gap of a surface file on the grid's outermost cells, and its least value [m].

    Cheap enough for a scene's validation: a ``.npy`` array is memory-mapped and only its
    border read (its least value scans it once), a netCDF gap is interpolated on the four
    edges alone. The file must be valid for the grid (:func:`check_surface`).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, numpy.ndarray, float)
        The border cells' x1, x2 [m] and gap [m], and the least gap of the file [m].
    """
    x1, x2 = np.asarray(x1, dtype=float), np.asarray(x2, dtype=float)
    path = os.fspath(file)
    if _is_npy(path):
        a = np.load(path, mmap_mode="r", allow_pickle=False)
        low = float(np.min(a))
        edges = [(x1[[0, -1]], x2, np.asarray(a[[0, -1], :], dtype=float)),
                 (x1, x2[[0, -1]], np.asarray(a[:, [0, -1]], dtype=float))]
    else:
        import xarray as xr

        with xr.open_dataset(path) as ds:
            gap = ds["gap"].load().transpose("x1", "x2").sortby(["x1", "x2"]).astype(float)
        low = float(gap.min())
        lo1, hi1 = float(gap.x1[0]), float(gap.x1[-1])
        lo2, hi2 = float(gap.x2[0]), float(gap.x2[-1])
        edges = []
        for e1, e2 in ((x1[[0, -1]], x2), (x1, x2[[0, -1]])):
            e1c, e2c = np.clip(e1, lo1, hi1), np.clip(e2, lo2, hi2)
            edges.append((e1, e2, np.asarray(gap.interp(x1=e1c, x2=e2c).values, dtype=float)))
    xs1, xs2, hs = [], [], []
    for e1, e2, h in edges:
        g1, g2 = np.meshgrid(e1, e2, indexing="ij")
        xs1.append(g1.ravel())
        xs2.append(g2.ravel())
        hs.append(h.ravel())
    return np.concatenate(xs1), np.concatenate(xs2), np.concatenate(hs), low


# ------------------------------------------------------------ measured and generated surfaces

def is_gap_file(file) -> bool:
    """A surface file that holds the gap itself: a ``.npy`` array, or a netCDF file
    with a variable ``gap`` (or any file not of a height format, read as such a netCDF
    file); a height file (x3p, sur, opd, plu, sdf, x y z text, netCDF ``heights``)
    holds heights z."""
    path = os.fspath(file)
    fmt = topography.height_format(path)
    if _is_npy(path) or fmt is None:
        return True
    if fmt != "netcdf":
        return False
    import xarray as xr

    try:
        with xr.open_dataset(path) as ds:
            return "gap" in ds.data_vars or "heights" not in ds.data_vars
    except Exception:  # noqa: BLE001 - unreadable: the gap reader says why
        return True


def _height_problems(path, x1, x2, missing, resample) -> list:
    try:
        h = topography.fill_missing(topography.read_heights(path), missing or "refuse",
                                    path)
    except SceneError as exc:
        return [str(exc)]
    if x1 is None or x2 is None:
        return []
    return topography.grid_problems(h, x1, x2, resample is not False, path)


def surface_problems(file, x1=None, x2=None, missing=None, resample=None) -> list:
    """Problems of ``shape = "surface"``'s file, and of the grid when ``x1``, ``x2`` [m]
    are given: :func:`check_surface` for a gap file (``missing`` and ``resample`` are
    for height files), else the height file read, its missing points and its cover of
    the grid (:mod:`contactpipe.scene.topography`)."""
    path = os.fspath(file)
    if not os.path.isfile(path):
        return [f"geometry.file {path!r}: no such file"]
    if not is_gap_file(path):
        return _height_problems(path, x1, x2, missing, resample)
    given = [k for k, v in (("missing", missing), ("resample", resample)) if v is not None]
    if given:
        return [f"geometry.{given[0]} is for height files (x3p, sur, opd, plu, sdf, x y z "
                f"text, netCDF 'heights'); geometry.file {path!r} holds the gap itself: "
                f"remove geometry.{given[0]}"]
    return check_surface(path, x1, x2)


def heights_gap(z, x1, x2, radius=None):
    """The gap of heights ``z`` (N1, N2) [m] on the grid, riding on a sphere of
    ``radius`` [m] when given: with z' = z - r^2 / (2 R), the gap max(z') - z' (zero at
    the highest point, where contact starts)."""
    z = np.asarray(z, dtype=float)
    if radius is not None:
        z = z - sphere_gap(x1, x2, radius)
    return float(np.max(z)) - z


def topography_gap(x1, x2, file, radius=None, missing=None, resample=None):
    """Gap [m] (N1, N2) of ``shape = "surface"``: a gap file's gap (:func:`surface_gap`,
    plus the sphere's r^2 / (2 R) when ``radius`` is given), or a height file's heights
    on the grid (bilinear resampling unless ``resample`` is false; missing points
    refused or filled by ``missing``) turned into a gap by :func:`heights_gap`."""
    path = os.fspath(file)
    problems = surface_problems(path, x1, x2, missing, resample)
    if problems:
        raise SceneError(problems)
    if is_gap_file(path):
        gap = surface_gap(x1, x2, path)
        return gap if radius is None else gap + sphere_gap(x1, x2, radius)
    h = topography.fill_missing(topography.read_heights(path), missing or "refuse", path)
    return heights_gap(topography.on_grid(h, x1, x2, resample is not False), x1, x2, radius)


def rough_gap(x1, x2, hurst, wavelengths, seed, rms_slope=None, rms_height=None,
              radius=None):
    """Gap [m] (N1, N2) of a generated self-affine surface (``shape = "rough"``) on the
    grid of cell centres ``x1``, ``x2`` [m] (:func:`contactpipe.scene.rough.self_affine`),
    riding on a sphere of ``radius`` when given (:func:`heights_gap`)."""
    x1, x2 = np.asarray(x1, dtype=float), np.asarray(x2, dtype=float)
    problems = rough.rough_problems(wavelengths, x1, x2)
    if problems:
        raise SceneError(problems)
    l1, l2 = (float(x[1] - x[0]) * x.size for x in (x1, x2))
    z = rough.self_affine(x1.size, x2.size, l1, l2, hurst, wavelengths, seed,
                          rms_slope_=rms_slope, rms_height=rms_height)
    return heights_gap(z, x1, x2, radius)
