"""Measured topography: a height file read into heights [m] on the file's own grid, and
those heights resampled onto the scene's grid.

Formats (by the file's extension): x3p (ISO 25178-72), sur (Digital Surf), opd (Wyko),
plu (Sensofar), sdf (ISO 25178-71) are read by the SurfaceTopography library, imported
only when such a file is read; a netCDF file with a variable ``heights`` over ``x1``,
``x2`` and a text file of x, y, z columns are read here. Heights are z of the rough
body's surface toward the other (a peak closes the gap); ``z[i, j]`` lies at the file's
i-th x and j-th y, both ascending. Missing points (masked, NaN) are NaN in
:attr:`Heights.z` until :func:`fill_missing` fills them or the caller refuses them.

The file's grid is centred on the scene's origin: its point (i, j) lies at
x1 = (i + 1/2 - n1/2) dx1, x2 = (j + 1/2 - n2/2) dx2, the same cell-centre rule as the
scene's grid, so a file of the grid's points and spacing maps point to point.
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import numpy as np

from ..exceptions import SceneError

__all__ = ["Heights", "HEIGHT_UNITS", "LIBRARY_FORMATS", "TEXT_SUFFIXES", "NETCDF_SUFFIXES",
           "height_format", "read_heights", "fill_missing", "on_grid", "grid_problems"]

#: Units a height file may give, and their size in metres.
HEIGHT_UNITS = {"m": 1.0, "metre": 1.0, "meter": 1.0, "metres": 1.0, "meters": 1.0,
                "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6, "nm": 1e-9,
                "pm": 1e-12, "\u00c5": 1e-10, "A": 1e-10}
#: Extensions read by SurfaceTopography, and its name of their format.
LIBRARY_FORMATS = {".x3p": "x3p", ".sur": "sur", ".opd": "opd", ".plu": "plu",
                   ".apx": "plu", ".sdf": "sdf"}
TEXT_SUFFIXES = (".txt", ".xyz", ".csv", ".dat", ".asc")
NETCDF_SUFFIXES = (".nc", ".nc4", ".cdf", ".netcdf")
#: Relative slack on the file's extent and spacing against the grid's.
SLACK = 1e-6


@dataclass(frozen=True)
class Heights:
    """Heights of a measured file on its own grid.

    Attributes
    ----------
    z : numpy.ndarray, shape (n1, n2)
        Heights [m], ``z[i, j]`` at the file's i-th x and j-th y (ascending); NaN where
        the file has no measured point.
    spacing : (float, float)
        The file's spacing along x1 and x2 [m].
    """

    z: np.ndarray
    spacing: tuple

    @property
    def shape(self) -> tuple:
        return tuple(self.z.shape)

    def axes(self):
        """The file's cell centres along x1 and x2 [m], centred on the origin."""
        return tuple((np.arange(n) + 0.5 - n / 2) * d
                     for n, d in zip(self.z.shape, self.spacing, strict=True))


def _where(path) -> str:
    return f"geometry.file {os.fspath(path)!r}"


def height_format(path) -> str | None:
    """The format of a height file by its extension: a SurfaceTopography format name,
    "netcdf", "text", or None (a .npy gap or an unknown extension)."""
    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext in LIBRARY_FORMATS:
        return LIBRARY_FORMATS[ext]
    if ext in NETCDF_SUFFIXES:
        return "netcdf"
    if ext in TEXT_SUFFIXES:
        return "text"
    return None


def _unit(unit, path, what="heights") -> float:
    key = str(unit).strip() if unit is not None else ""
    if key not in HEIGHT_UNITS:
        raise SceneError(f"{_where(path)}: unknown units {key[:40]!r} of its {what}; "
                         f"allowed: m, mm, um (or \u00b5m), nm, pm, \u00c5")
    return HEIGHT_UNITS[key]


def _library(path, fmt) -> Heights:
    """Heights of a file SurfaceTopography reads (imported here, on first use)."""
    try:
        from SurfaceTopography import open_topography
    except ImportError as exc:          # pragma: no cover - a runtime dependency
        raise SceneError(f"{_where(path)}: reading {fmt} files needs the SurfaceTopography "
                         f"package ({exc}); pip install SurfaceTopography") from None
    try:
        topo = open_topography(os.fspath(path), format=fmt).topography()
        unit = topo.unit
        sizes = np.asarray(topo.physical_sizes, dtype=float)
        z: np.ma.MaskedArray = np.ma.masked_invalid(np.ma.asarray(topo.heights(), dtype=float))
    except Exception as exc:  # noqa: BLE001 - any failure to read is the user's file
        text = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise SceneError(f"{_where(path)}: not a readable {fmt} file, or truncated "
                         f"({type(exc).__name__}: {text})") from None
    if z.ndim != 2:
        raise SceneError(f"{_where(path)}: holds a line scan (shape {z.shape}), not a "
                         f"surface of x and y")
    f = _unit(unit, path)
    return Heights(np.ma.filled(z * f, np.nan), tuple(float(s) * f / n for s, n in
                                                      zip(sizes, z.shape, strict=True)))


def _uniform(c, path, name) -> float:
    """The step of strictly ascending uniform coordinates ``c`` [m], or a SceneError."""
    d = np.diff(c)
    if c.size < 2 or np.any(d <= 0) or np.ptp(d) > SLACK * abs(d.mean()) + 1e-300:
        raise SceneError(f"{_where(path)}: its {name} values must form a uniform grid of "
                         f"at least 2 points")
    return float(d.mean())


def _text(path) -> Heights:
    """x, y, z columns (spaces or commas; ``#`` comments; an optional ``# units = um``
    line gives the unit of all three, metres otherwise) on a full rectangular grid."""
    unit = "m"
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                s = line.strip()
                if s.startswith("#") and "units" in s:
                    unit = s.lstrip("#").split("units", 1)[1].strip(" =:\t")
        with open(path, encoding="utf-8") as f:
            rows = [ln.replace(",", " ").split() for ln in f
                    if ln.strip() and not ln.lstrip().startswith("#")]
        data = np.array(rows, dtype=float)
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise SceneError(f"{_where(path)}: not a readable x y z text file "
                         f"({type(exc).__name__}: {str(exc)[:120]})") from None
    if data.ndim != 2 or data.shape[1] != 3:
        raise SceneError(f"{_where(path)}: must hold three columns x, y, z per line")
    data = data * _unit(unit, path, "x, y, z")
    xs, ix = np.unique(data[:, 0], return_inverse=True)
    ys, iy = np.unique(data[:, 1], return_inverse=True)
    if xs.size * ys.size != data.shape[0] or \
            np.unique(ix * ys.size + iy).size != data.shape[0]:
        raise SceneError(f"{_where(path)}: the x, y points must fill a rectangular grid "
                         f"once each ({data.shape[0]} lines for {xs.size} x and {ys.size} "
                         f"y values); a truncated file?")
    z = np.full((xs.size, ys.size), np.nan)
    z[ix, iy] = data[:, 2]
    return Heights(z, (_uniform(xs, path, "x"), _uniform(ys, path, "y")))


def _netcdf(path) -> Heights:
    """A netCDF variable ``heights`` over x1, x2 with uniform coordinates; its ``units``
    attribute and the coordinates' give the units (metres when absent)."""
    import xarray as xr

    try:
        ds = xr.open_dataset(path)
    except Exception as exc:  # noqa: BLE001
        raise SceneError(f"{_where(path)}: not a readable netCDF file "
                         f"({type(exc).__name__}: {str(exc)[:120]})") from None
    with ds:
        if "heights" not in ds.data_vars or set(ds["heights"].dims) != {"x1", "x2"}:
            raise SceneError(f"{_where(path)}: a netCDF surface needs a variable 'gap' (the "
                             f"gap) or 'heights' (the heights z) over dimensions x1, x2")
        var = ds["heights"].load().transpose("x1", "x2")
        f = _unit(var.attrs.get("units", "m"), path)
        axes = []
        for dim in ("x1", "x2"):
            if dim not in var.coords:
                raise SceneError(f"{_where(path)}: dimension {dim!r} has no coordinate [m]")
            c = np.asarray(var[dim].values, dtype=float) * \
                _unit(var[dim].attrs.get("units", "m"), path, f"coordinate {dim}")
            axes.append(c)
        order = [np.argsort(c) for c in axes]
        z = np.asarray(var.values, dtype=float)[np.ix_(*order)] * f
    steps = tuple(_uniform(c[o], path, dim) for c, o, dim in
                  zip(axes, order, ("x1", "x2"), strict=True))
    return Heights(z, steps)


@functools.lru_cache(maxsize=8)
def _read(path: str, mtime_ns: int, size: int) -> Heights:
    fmt = height_format(path)
    if fmt == "text":
        out = _text(path)
    elif fmt == "netcdf":
        out = _netcdf(path)
    elif fmt is not None:
        out = _library(path, fmt)
    else:
        raise SceneError(f"{_where(path)}: unknown extension; allowed: .x3p, .sur, .opd, "
                         f".plu, .sdf, .nc (variable 'gap' or 'heights'), .npy (the gap), "
                         f"x y z text (.txt, .xyz, .csv, .dat, .asc)")
    if not np.any(np.isfinite(out.z)):
        raise SceneError(f"{_where(path)}: no measured point (NaN or masked everywhere); "
                         f"a surface needs heights")
    if min(out.z.shape) < 2:
        raise SceneError(f"{_where(path)}: holds {out.z.shape} points; a surface needs at "
                         f"least 2 along x and y")
    if np.any(np.isinf(out.z)) or not all(0 < d < np.inf for d in out.spacing):
        raise SceneError(f"{_where(path)}: holds infinite heights or a spacing that is "
                         f"not finite and > 0")
    out.z.setflags(write=False)
    return out


def read_heights(path) -> Heights:
    """The heights of a measured file [m] on its own grid (cached by the file's
    modification time and size; the array is read-only).

    Raises
    ------
    SceneError
        One line naming ``geometry.file`` and the file: missing, unreadable or truncated,
        unknown units or extension, no measured point at all.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise SceneError(f"{_where(path)}: no such file")
    st = os.stat(path)
    return _read(path, st.st_mtime_ns, st.st_size)


def fill_missing(h: Heights, missing: str, path) -> Heights:
    """``h`` with its missing points handled: refused (``missing = "refuse"``, the
    default: a SceneError naming the count) or filled with the height of the nearest
    measured point (``"fill"``: no new peak or valley is made)."""
    bad = ~np.isfinite(h.z)
    if not bad.any():
        return h
    if missing != "fill":
        raise SceneError(f"{_where(path)}: {int(bad.sum())} of {bad.size} points are "
                         f"missing (NaN or masked); set geometry.missing = 'fill' to take "
                         f"the nearest measured height there, or give a complete file")
    from scipy.ndimage import distance_transform_edt

    idx = distance_transform_edt(bad, sampling=h.spacing, return_distances=False,
                                 return_indices=True)
    return Heights(h.z[tuple(idx)], h.spacing)


def grid_problems(h: Heights, x1, x2, resample: bool, path) -> list:
    """Problems of the scene's grid (cell centres ``x1``, ``x2`` [m]) against the file:
    with resampling, the grid's outermost cell centres must lie inside the file's area
    (its n d sides, centred); without, the points and spacing must be the file's."""
    out = []
    for ax, (x, n, d) in enumerate(zip((x1, x2), h.shape, h.spacing, strict=True)):
        x = np.asarray(x, dtype=float)
        name = ("x1", "x2")[ax]
        step = float(x[1] - x[0]) if x.size > 1 else 0.0
        if not resample:
            if x.size != n or abs(step - d) > SLACK * d:
                out.append(f"{_where(path)}: geometry.resample = false needs the file's "
                           f"grid: grid.points[{ax}] = {n} and grid.size[{ax}] = "
                           f"{n * d:.10g} m along {name}, got {x.size} points of "
                           f"{step:.6g} m")
            continue
        half = n * d / 2 * (1 + SLACK)
        if x.min() < -half or x.max() > half:
            out.append(f"{_where(path)}: does not cover the grid along {name}: the file "
                       f"spans {n * d:.6g} m ({n} points of {d:.6g} m), the grid's cell "
                       f"centres reach {max(-x.min(), x.max()):.6g} m from the centre; "
                       f"shrink grid.size to at most {n * d:.6g} m")
    return out


def on_grid(h: Heights, x1, x2, resample: bool = True):
    """The heights on the scene's cell centres [m], (N1, N2): taken as they are without
    resampling, else interpolated bilinearly between the file's points (a grid centre
    between the file's outermost point and its area's edge takes that point's height).
    ``h`` must be complete (:func:`fill_missing`) and cover the grid
    (:func:`grid_problems`)."""
    if not resample:
        return np.array(h.z, dtype=float)
    from scipy.interpolate import RegularGridInterpolator

    a1, a2 = h.axes()
    x1 = np.clip(np.asarray(x1, dtype=float), a1[0], a1[-1])
    x2 = np.clip(np.asarray(x2, dtype=float), a2[0], a2[-1])
    f = RegularGridInterpolator((a1, a2), h.z, method="linear")
    g1, g2 = np.meshgrid(x1, x2, indexing="ij")
    return f(np.stack([g1.ravel(), g2.ravel()], axis=-1)).reshape(g1.shape)
