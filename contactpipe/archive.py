"""Archives: one simulation per netCDF4 file, written atomically and validated (CONTRACT §3).

Writing
-------
:class:`ArchiveWriter` streams time steps into a hidden temporary file next to the target
(``.NAME.<pid>-<token>.part``) and renames it onto the target only in :meth:`close`, after
setting the global attribute ``complete = "true"`` and an fsync. On :meth:`abort`, on an
exception inside its ``with`` block, or when it is garbage-collected unclosed, the temporary
file is removed. Only a killed process leaves a ``.part`` behind; the target path then holds
nothing, or the previous archive. :class:`MemoryWriter` has the same interface and returns a
Dataset. :func:`save` writes a whole Dataset the same way, after :func:`validate` found no
problem.

Reading
-------
:func:`open_archive` opens lazily (dask, one time step per chunk of a field) and refuses,
with :class:`~contactpipe.exceptions.ArchiveError`, a file that is missing, unreadable,
interrupted (no ``complete = "true"``) or off the schema. :func:`is_complete` is the cheap
yes/no form that sweeps use to decide what to recompute.

Layout on disk: ``time`` unlimited; fields chunked (1, N1, N2), series in chunks of
``SERIES_CHUNK`` steps; zlib level 1 when compressed; no fill values; floats in float64
or float32 (the precision), ``status`` int8, counts int32, coordinates always float64.
"""
from __future__ import annotations

import glob
import json
import math
import numbers
import pathlib
import time as _time
import weakref

import netCDF4
import numpy as np
import xarray as xr

from ._version import __version__
from .exceptions import ArchiveError, one_line as _one_line
from .files import loads_toml, publish as _publish, temp_name as _temp_path
from .nomenclature import (
    CONVENTIONS, COORDINATES, FIELD, REQUIRED_ATTRS, VARIABLES, cf_attrs,
)

__all__ = ["ArchiveWriter", "MemoryWriter", "to_dataset", "save", "open_archive",
           "is_complete", "validate", "resumable_part", "PRECISIONS", "SERIES_CHUNK"]

PRECISIONS = ("float64", "float32")
SERIES_CHUNK = 1024        # time steps per on-disk chunk of a series (and of `time`)
COMPLEVEL = 1
DIMS = FIELD               # ("time", "x1", "x2")


# --------------------------------------------------------------------------- helpers

def _join(problems: list[str]) -> str:
    if len(problems) == 1:
        return problems[0]
    return f"{len(problems)} problems: " + "; ".join(problems)


def _storable_value(value):
    """An attribute value netCDF can hold: str, a number or a 1-D numeric array."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (str, numbers.Real)):
        return value
    if isinstance(value, pathlib.PurePath):
        return str(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.asarray(value)
        if arr.ndim == 1 and arr.size and arr.dtype.kind in "iuf":
            return arr
        return json.dumps(np.asarray(value, dtype=object).tolist(), default=str)
    if isinstance(value, dict):
        return json.dumps(value, default=str)
    return str(value)


def _storable(attrs: dict | None) -> dict:
    out = {}
    for key, value in (attrs or {}).items():
        if not isinstance(key, str) or not key:
            raise ArchiveError(f"attribute name {key!r} is not a non-empty string")
        out[key] = _storable_value(value)
    return out


def _is_storable(value) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, (str, numbers.Real)):
        return True
    return isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "iuf"


def _global_attrs(attrs: dict | None) -> dict:
    """Defaults (Conventions, contactpipe_version) under the caller's attributes."""
    out = {"Conventions": CONVENTIONS, "contactpipe_version": __version__}
    out.update(_storable(attrs))
    out.pop("complete", None)          # only a finished write sets it
    return out


def _attr_problems(attrs: dict, required=REQUIRED_ATTRS) -> list[str]:
    problems = [f"global attribute {k!r} missing" for k in required if k not in attrs]
    conv = attrs.get("Conventions", CONVENTIONS)
    if conv != CONVENTIONS:
        problems.append(f"global attribute 'Conventions' = {conv!r}, expected {CONVENTIONS!r}")
    if "scene" in attrs:
        scene = attrs["scene"]
        if not isinstance(scene, str):
            problems.append(f"global attribute 'scene' is a {type(scene).__name__}, "
                            "expected the scene as TOML text")
        else:
            try:
                loads_toml(scene)
            except ValueError as e:
                problems.append(f"global attribute 'scene' is not TOML text ({_one_line(e)})")
    if "models" in attrs and not isinstance(attrs["models"], str):
        problems.append(f"global attribute 'models' = {attrs['models']!r}, expected text "
                        "such as 'normal, tangential'")
    if "wall_time_s" in attrs:
        wt = attrs["wall_time_s"]
        if isinstance(wt, (bool, np.bool_)) or not isinstance(wt, numbers.Real) \
                or not (math.isfinite(wt) and wt >= 0):
            problems.append(f"global attribute 'wall_time_s' = {wt!r}, expected a number of "
                            "seconds >= 0")
    for key, value in attrs.items():
        if not _is_storable(value):
            problems.append(f"global attribute {key!r} = {value!r} cannot be stored in netCDF "
                            "(allowed: str, number, 1-D numeric array)")
    return problems


def _axis(name: str, values) -> np.ndarray:
    """A coordinate as float64: 1-D, non-empty, finite, strictly ascending."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ArchiveError(f"coordinate {name!r}: not numeric ({_one_line(e)})") from None
    unit = COORDINATES[name]["units"]
    if arr.ndim != 1 or arr.size == 0:
        raise ArchiveError(f"coordinate {name!r}: shape {arr.shape}, expected a non-empty "
                           f"1-D array [{unit}]")
    if not np.all(np.isfinite(arr)):
        raise ArchiveError(f"coordinate {name!r} holds NaN or inf")
    if arr.size > 1 and not np.all(np.diff(arr) > 0):
        raise ArchiveError(f"coordinate {name!r} is not strictly ascending")
    return arr


def _variable_problems(names) -> list[str]:
    names = list(names)
    problems = [f"unknown variable {n!r} (not in contactpipe.nomenclature.VARIABLES)"
                for n in names if n not in VARIABLES]
    problems += [f"variable {n!r} given twice" for n in sorted(set(names))
                 if names.count(n) > 1]
    problems += [f"variable {n!r} missing (every archive has it)"
                 for n, e in VARIABLES.items() if e["required"] and n not in names]
    return problems


def _precision(precision) -> np.dtype:
    try:
        dt = np.dtype(precision)
    except TypeError:
        dt = None
    if dt is None or dt.name not in PRECISIONS:
        raise ArchiveError(f"precision={precision!r}: expected one of {PRECISIONS}")
    return dt


def _storage_dtype(name: str, precision: np.dtype) -> np.dtype:
    kind = VARIABLES[name]["dtype"]
    return precision if kind == "float" else np.dtype(kind)


def resumable_part(path) -> pathlib.Path:
    """The fixed part-file name of a resumable write of ``path``."""
    path = pathlib.Path(path)
    return path.with_name(f".{path.name}.resumable.part")


# --------------------------------------------------------------------------- writers

class _StepWriter:
    """What both writers share: argument checks, per-step checks, context management."""

    def __init__(self, x1, x2, variables, attrs, precision):
        self.x1 = _axis("x1", x1)
        self.x2 = _axis("x2", x2)
        self.variables = tuple(variables)
        self.precision = _precision(precision)
        self.attrs = _global_attrs(attrs)
        problems = _variable_problems(self.variables)
        problems += _attr_problems(self.attrs, required=("scene", "models"))
        if problems:
            raise ArchiveError(f"{self._label()}: " + _join(problems))
        self._dtypes = {n: _storage_dtype(n, self.precision) for n in self.variables}
        self.steps = 0
        self._last_t = None
        self._done = False
        self._started = _time.perf_counter()

    def _label(self) -> str:
        return type(self).__name__

    def _check_step(self, t, values) -> tuple[float, dict]:
        """Every value of one instant, checked and cast; raises before anything is kept."""
        if self._done:
            raise ArchiveError(f"{self._label()}: already closed or aborted; cannot append")
        k = self.steps
        try:
            t = float(t)
        except (TypeError, ValueError):
            raise ArchiveError(f"{self._label()}: step {k}: time {t!r} is not a number") from None
        where = f"step {k} (t = {t:g} s)"
        problems = []
        if not math.isfinite(t):
            problems.append(f"time is {t}")
        elif self._last_t is not None and not t > self._last_t:
            problems.append(f"time {t:g} s is not after the previous instant {self._last_t:g} s")
        problems += [f"{n} missing" for n in self.variables if n not in values]
        problems += [f"{n} not declared when the writer was created"
                     for n in values if n not in self._dtypes]
        shape_field = (self.x1.size, self.x2.size)
        out = {}
        for name, dtype in self._dtypes.items():
            if name not in values:
                continue
            arr = np.asarray(values[name])
            want = shape_field if VARIABLES[name]["dims"] == FIELD else ()
            if want == () and arr.size == 1:
                arr = arr.reshape(())
            if arr.shape != want:
                problems.append(f"{name}: shape {arr.shape}, expected {want}")
                continue
            if arr.dtype.kind not in "biuf":
                problems.append(f"{name}: dtype {arr.dtype} is not numeric")
                continue
            finite = np.isfinite(arr)
            if not finite.all():
                problems.append(f"{name} holds {arr.size - int(finite.sum())} NaN or inf "
                                "value(s)")
                continue
            if dtype.kind == "i":
                info = np.iinfo(dtype)
                if arr.dtype.kind == "f" and np.any(arr != np.round(arr)) \
                        or arr.min() < info.min or arr.max() > info.max:
                    problems.append(f"{name}: values must be integers within {dtype}")
                    continue
                arr = arr.astype(dtype)
                flags = VARIABLES[name].get("flag_values")
                if flags is not None and not np.isin(arr, flags).all():
                    problems.append(f"{name}: values {np.setdiff1d(arr, flags)} outside "
                                    f"flag_values {list(flags)}")
                    continue
            else:
                arr = arr.astype(dtype)
                if not np.all(np.isfinite(arr)):
                    problems.append(f"{name}: exceeds the range of {dtype}")
                    continue
            out[name] = arr
        if problems:
            raise ArchiveError(f"{self._label()}: {where} refused, nothing of it written: "
                               + "; ".join(problems))
        return t, out

    def _commit(self, t: float) -> None:
        self._last_t = t
        self.steps += 1

    def _final_attrs(self, attrs) -> dict:
        """The attributes at close: wall_time_s defaults to the time since creation."""
        merged = {**self.attrs, **_storable(attrs)}
        merged.pop("complete", None)
        merged.setdefault("wall_time_s", _time.perf_counter() - self._started)
        problems = _attr_problems(merged)
        if self.steps == 0:
            problems.insert(0, "no time step appended")
        if problems:
            raise ArchiveError(f"{self._label()}: cannot close, nothing written: "
                               + _join(problems))
        return merged

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            if not self._done:
                self.close()
        else:
            self.abort()
        return False


def _discard(nc, tmp: pathlib.Path) -> None:
    """Close the netCDF handle and remove the temporary file (abort and garbage collection)."""
    try:
        if nc.isopen():
            nc.close()
    except Exception:                      # noqa: BLE001 - cleanup must not mask the cause
        pass
    try:
        tmp.unlink(missing_ok=True)
    except OSError:
        pass


class ArchiveWriter(_StepWriter):
    """Streams time steps into a netCDF4 archive; the target appears only on :meth:`close`.

    Parameters
    ----------
    path : str or path-like
        The archive to write. An existing file there is replaced only by a finished write.
    x1, x2 : array_like
        Cell centres [m], strictly ascending.
    variables : list of str
        Names from :data:`contactpipe.nomenclature.VARIABLES`; every ``append`` gives
        exactly these. The required ones (``p``, ``u3``, ``h``, ``status``, ``W``,
        ``omega3``, ``contact_area``, ``iterations``) must be among them.
    attrs : dict
        Global attributes; ``scene`` (TOML text) and ``models`` are required,
        ``Conventions`` and ``contactpipe_version`` are filled in. Booleans become
        "true"/"false", None an empty string.
    precision : {"float64", "float32"}
        Storage type of the floating-point variables (coordinates stay float64).
    compress : bool
        zlib (level 1) with shuffle on every variable.

    Notes
    -----
    The writer keeps nothing per step in memory: each ``append`` goes to disk. A step
    holding NaN or inf is refused whole (``ArchiveError`` naming variable and step) and the
    writer stays usable. ``close`` adds the final attributes (``wall_time_s`` defaults to
    the seconds since the writer was created), sets ``complete = "true"``, fsyncs and
    renames atomically.
    """

    def __init__(self, path, x1, x2, variables: list[str], attrs: dict,
                 precision="float64", compress=True, resumable=False, resume_steps=None):
        self.path = pathlib.Path(path)
        super().__init__(x1, x2, variables, attrs, precision)
        self.compress = bool(compress)
        self.resumable = bool(resumable)
        self._tmp = resumable_part(self.path) if resumable else _temp_path(self.path)
        if resume_steps is not None:
            self._reopen(int(resume_steps))
            return
        try:
            nc = netCDF4.Dataset(self._tmp, mode="w", format="NETCDF4",
                                 clobber=self.resumable)
        except Exception as e:             # noqa: BLE001 - reported with the path
            self._done = True
            raise ArchiveError(f"{self.path}: cannot create the temporary file "
                               f"{self._tmp.name} ({_one_line(e)})") from e
        self._nc = nc
        self._finalizer = weakref.finalize(self, _discard, nc, self._tmp)
        try:
            self._define()
        except BaseException as e:
            self.abort()
            if isinstance(e, Exception):
                raise ArchiveError(f"{self.path}: cannot lay out the archive "
                                   f"({_one_line(e)})") from e
            raise

    def _label(self) -> str:
        return str(self.path)

    def _reopen(self, steps: int) -> None:
        """Continue a resumable write: reopen its part file after ``steps`` instants."""
        try:
            nc = netCDF4.Dataset(self._tmp, mode="a")
            have = len(nc.dimensions["time"])
            if have < steps:
                raise ArchiveError(f"the part file holds {have} instants, the checkpoint "
                                   f"{steps}")
            self._last_t = float(nc["time"][steps - 1]) if steps else None
        except Exception as e:             # noqa: BLE001 - reported with the path
            self._done = True
            raise ArchiveError(f"{self.path}: cannot resume from {self._tmp.name} "
                               f"({_one_line(e)})") from e
        self._nc = nc
        self.steps = steps
        self._finalizer = weakref.finalize(self, _discard, nc, self._tmp)

    def flush(self) -> None:
        """Push what was appended to disk (before a checkpoint)."""
        self._nc.sync()

    def suspend(self) -> None:
        """Close the part file and keep it for a later resume (resumable writers only)."""
        if not self.resumable:
            return self.abort()
        self._finalizer.detach()
        try:
            self._nc.close()
        except Exception:                  # noqa: BLE001 - already broken: nothing to keep
            pass
        self._done = True

    def _define(self) -> None:
        nc = self._nc
        nc.set_fill_off()
        nc.createDimension("time", None)
        nc.createDimension("x1", self.x1.size)
        nc.createDimension("x2", self.x2.size)
        for name in ("x1", "x2"):
            v = nc.createVariable(name, "f8", (name,))
            v.setncatts(cf_attrs(name))
            v[:] = getattr(self, name)
        v = nc.createVariable("time", "f8", ("time",), chunksizes=(SERIES_CHUNK,))
        v.setncatts(cf_attrs("time"))
        zip_ = {"compression": "zlib", "complevel": COMPLEVEL, "shuffle": True} \
            if self.compress else {"compression": None}
        field_chunks = (1, self.x1.size, self.x2.size)
        for name, dtype in self._dtypes.items():
            dims = VARIABLES[name]["dims"]
            chunks = field_chunks if dims == FIELD else (SERIES_CHUNK,)
            v = nc.createVariable(name, dtype, dims, fill_value=False, chunksizes=chunks,
                                  **zip_)
            # each chunk is written once: cache one (not the library's 64 MiB per variable),
            # so memory stays flat however many steps are written
            v.set_var_chunk_cache(size=int(np.prod(chunks)) * dtype.itemsize, nelems=7,
                                  preemption=1.0)
            v.setncatts(cf_attrs(name))
        nc.setncatts(self.attrs)

    def append(self, t: float, values: dict) -> None:
        """Write one instant: time ``t`` [s] and a value for every declared variable."""
        t, arrays = self._check_step(t, values)
        k = self.steps
        try:
            self._nc["time"][k] = t
            for name, arr in arrays.items():
                self._nc[name][k] = arr
        except Exception as e:             # noqa: BLE001 - reported with the path
            raise ArchiveError(f"{self.path}: writing step {k} failed ({_one_line(e)})") from e
        self._commit(t)

    def close(self, attrs: dict | None = None) -> pathlib.Path:
        """Finish: final attributes, ``complete = "true"``, fsync, rename onto the target."""
        if self._done:
            raise ArchiveError(f"{self.path}: writer already closed or aborted")
        try:
            final = self._final_attrs(attrs)
            final["complete"] = "true"
            self._nc.setncatts(final)
            self._nc.close()
            _publish(self._tmp, self.path)
        except BaseException as e:
            self.abort()
            if isinstance(e, Exception) and not isinstance(e, ArchiveError):
                raise ArchiveError(f"{self.path}: closing failed, nothing written "
                                   f"({_one_line(e)})") from e
            raise
        self._finalizer.detach()
        self._done = True
        return self.path

    def abort(self) -> None:
        """Drop everything written so far; the target path is left as it was."""
        self._finalizer()
        self._done = True


class MemoryWriter(_StepWriter):
    """The :class:`ArchiveWriter` interface, kept in memory; ``close`` returns the Dataset.

    The constructor takes the same arguments, so either class can be chosen by whether a
    path is given: ``path`` must be None and ``compress`` has no effect in memory. Same
    checks per step (NaN/inf refused, integer and flag types), same precision and
    attributes, so ``MemoryWriter(None, ...).close()`` equals ``open_archive`` of what
    ``ArchiveWriter`` wrote from the same steps (less the ``complete`` attribute).
    """

    def __init__(self, path, x1, x2, variables: list[str], attrs: dict, precision="float64",
                 compress=True):
        if path is not None:
            raise ArchiveError(f"MemoryWriter: path={str(path)!r}, expected None (it keeps "
                               "the steps in memory; ArchiveWriter writes a file)")
        super().__init__(x1, x2, variables, attrs, precision)
        self._times: list[float] = []
        self._data: dict[str, list] = {n: [] for n in self.variables}

    def append(self, t: float, values: dict) -> None:
        """Keep one instant: time ``t`` [s] and a value for every declared variable."""
        t, arrays = self._check_step(t, values)
        self._times.append(t)
        for name, arr in arrays.items():
            self._data[name].append(arr)
        self._commit(t)

    def close(self, attrs: dict | None = None) -> xr.Dataset:
        """The labelled Dataset of every appended step."""
        if self._done:
            raise ArchiveError(f"{self._label()}: writer already closed or aborted")
        final = self._final_attrs(attrs)
        ds = to_dataset(self.x1, self.x2, self._times,
                        {n: np.stack(v) for n, v in self._data.items()}, final)
        self.abort()
        return ds

    def abort(self) -> None:
        """Drop every step kept."""
        self._times, self._data = [], {}
        self._done = True


# --------------------------------------------------------------------------- datasets

def to_dataset(x1, x2, times, fields: dict, attrs: dict) -> xr.Dataset:
    """Label arrays as an archive Dataset (CONTRACT §3).

    Parameters
    ----------
    x1, x2 : array_like
        Cell centres [m], strictly ascending.
    times : array_like
        The instants [s], strictly ascending.
    fields : dict of str -> array_like
        Variable name -> values, shaped (time, x1, x2) or (time,) as the nomenclature
        says. Floats stay float32 when given as float32, else become float64; ``status``
        becomes int8 and counts int32.
    attrs : dict
        Global attributes (``Conventions`` and ``contactpipe_version`` are filled in).

    Returns
    -------
    xarray.Dataset
        With ``units``, ``long_name`` (and flags) on every variable and coordinate.
    """
    coords = {"time": _axis("time", times), "x1": _axis("x1", x1), "x2": _axis("x2", x2)}
    sizes = {d: v.size for d, v in coords.items()}
    problems = _variable_problems(fields)
    data_vars = {}
    for name, values in fields.items():
        if name not in VARIABLES:
            continue
        entry = VARIABLES[name]
        arr = np.asarray(values)
        want = tuple(sizes[d] for d in entry["dims"])
        if arr.shape != want:
            problems.append(f"{name}: shape {arr.shape}, expected {want} {entry['dims']}")
            continue
        if entry["dtype"] != "float":
            dtype = np.dtype(entry["dtype"])
        else:
            dtype = np.float32 if arr.dtype == np.float32 else np.float64
        data_vars[name] = xr.Variable(entry["dims"], arr.astype(dtype, copy=False),
                                      attrs=cf_attrs(name))
    if problems:
        raise ArchiveError("to_dataset: " + _join(problems))
    coord_vars = {d: xr.Variable((d,), v, attrs=cf_attrs(d)) for d, v in coords.items()}
    return xr.Dataset(data_vars, coords=coord_vars, attrs=_global_attrs(attrs))


def _schema_problems(ds: xr.Dataset) -> list[str]:
    """Problems visible from the metadata alone (reads no data but the dimension coords)."""
    problems = []
    for d in DIMS:
        if d not in ds.dims:
            problems.append(f"dimension {d!r} missing (dims: {dict(ds.sizes)})")
            continue
        if d not in ds.coords:
            problems.append(f"coordinate {d!r} missing")
            continue
        c = ds[d]
        unit = COORDINATES[d]["units"]
        if c.attrs.get("units") != unit:
            problems.append(f"coordinate {d!r}: units {c.attrs.get('units')!r}, expected {unit!r}")
        if c.dtype.kind not in "iuf":
            problems.append(f"coordinate {d!r}: dtype {c.dtype}, expected float")
            continue
        vals = np.asarray(c.values, dtype=float)
        if not np.all(np.isfinite(vals)):
            problems.append(f"coordinate {d!r} holds NaN or inf")
        elif vals.size > 1 and not np.all(np.diff(vals) > 0):
            problems.append(f"coordinate {d!r} is not strictly ascending")
    for name, c in ds.coords.items():
        if name in COORDINATES and name not in DIMS \
                and c.attrs.get("units") != COORDINATES[name]["units"]:
            problems.append(f"coordinate {name!r}: units {c.attrs.get('units')!r}, expected "
                            f"{COORDINATES[name]['units']!r}")
    for name in ds.data_vars:
        if name not in VARIABLES:
            problems.append(f"unknown variable {name!r} (not in "
                            "contactpipe.nomenclature.VARIABLES)")
    for name, entry in VARIABLES.items():
        if name not in ds.data_vars:
            if entry["required"]:
                problems.append(f"variable {name!r} missing")
            continue
        v = ds[name]
        if tuple(v.dims) != entry["dims"]:
            problems.append(f"{name}: dims {tuple(v.dims)}, expected {entry['dims']}")
        if v.attrs.get("units") != entry["units"]:
            problems.append(f"{name}: units {v.attrs.get('units')!r}, expected {entry['units']!r}")
        kinds = "f" if entry["dtype"] == "float" else "iu"
        if v.dtype.kind not in kinds:
            problems.append(f"{name}: dtype {v.dtype}, expected "
                            + ("float" if kinds == "f" else entry["dtype"]))
        if "flag_values" in entry:
            for key in ("flag_values", "flag_meanings"):
                if key not in v.attrs:
                    problems.append(f"{name}: attribute {key!r} missing")
    problems += _attr_problems(ds.attrs)
    return problems


def _data_problems(ds: xr.Dataset) -> list[str]:
    """NaN/inf in any variable, flags out of range (computes lazy data, one pass each)."""
    problems = []
    for name, v in ds.data_vars.items():
        if v.dtype.kind not in "biuf":
            continue
        if v.dtype.kind == "f":
            other = [d for d in v.dims if d != "time"]
            bad = ~np.isfinite(v)
            if "time" in v.dims:
                per_step = np.asarray(bad.any(dim=other).values if other else bad.values)
                if per_step.any():
                    k = int(np.argmax(per_step))
                    t = float(ds["time"].values[k]) if "time" in ds.coords else float("nan")
                    problems.append(f"{name} holds NaN or inf at {int(per_step.sum())} time "
                                    f"step(s), first at step {k} (t = {t:g} s)")
            elif bool(bad.any()):
                problems.append(f"{name} holds NaN or inf")
        flags = VARIABLES.get(name, {}).get("flag_values")
        if flags is not None and v.dtype.kind in "iu":
            outside = np.setdiff1d(np.unique(np.asarray(v.values)), flags)
            if outside.size:
                problems.append(f"{name}: values {outside.tolist()} outside flag_values "
                                f"{list(flags)}")
    return problems


def validate(ds: xr.Dataset) -> list[str]:
    """Every way ``ds`` departs from the archive schema (CONTRACT §3); empty when none.

    Checks dimensions and coordinates (present, units, finite, strictly ascending), the
    variables (known names, required ones present, dims, units, type, status flags), the
    global attributes (present, netCDF-storable, ``scene`` readable as TOML) and that no
    variable holds NaN or inf. Lazy data is computed.
    """
    if not isinstance(ds, xr.Dataset):
        return [f"expected an xarray.Dataset, got {type(ds).__name__}"]
    return _schema_problems(ds) + _data_problems(ds)


# --------------------------------------------------------------------------- files

def save(ds: xr.Dataset, path, precision=None, compress=True) -> pathlib.Path:
    """Write ``ds`` to a netCDF4 archive atomically, after validating it.

    Parameters
    ----------
    ds : xarray.Dataset
        An archive Dataset (:func:`to_dataset`, :func:`contactpipe.simulation`,
        :func:`open_archive`). Boolean and None attributes are converted.
    path : str or path-like
        Target file; replaced only once the new archive is complete.
    precision : {None, "float64", "float32"}
        Storage type of floating-point variables; None keeps each variable's own.
    compress : bool
        zlib level 1 with shuffle.

    Returns
    -------
    pathlib.Path
        The archive written, with global attribute ``complete = "true"``.

    Raises
    ------
    ArchiveError
        Listing every schema problem, before a byte is written; or when writing fails
        (then nothing is left at ``path`` but what was there before).
    """
    path = pathlib.Path(path)
    if not isinstance(ds, xr.Dataset):
        raise ArchiveError(f"{path}: not saved: expected an xarray.Dataset, got "
                           f"{type(ds).__name__}")
    prec = None if precision is None else _precision(precision)
    ds = ds.drop_encoding()
    ds.attrs = _storable(ds.attrs)
    ds.attrs.pop("complete", None)
    for v in ds.variables.values():
        v.attrs = _storable(v.attrs)
    problems = validate(ds)
    if problems:
        raise ArchiveError(f"{path}: not saved, the dataset does not follow the archive "
                           "schema: " + _join(problems))
    ds.attrs["complete"] = "true"
    zip_ = {"zlib": True, "complevel": COMPLEVEL, "shuffle": True} if compress \
        else {"zlib": False}
    encoding = {}
    for name, v in ds.variables.items():
        enc = {"_FillValue": None}
        if name in VARIABLES:
            entry = VARIABLES[name]
            enc["dtype"] = (prec or v.dtype) if entry["dtype"] == "float" \
                else np.dtype(entry["dtype"])
            enc["chunksizes"] = (1, ds.sizes["x1"], ds.sizes["x2"]) \
                if entry["dims"] == FIELD else (SERIES_CHUNK,)
            enc.update(zip_)
        elif name == "time":
            enc["chunksizes"] = (SERIES_CHUNK,)
        encoding[name] = enc
    tmp = _temp_path(path)
    try:
        ds.to_netcdf(tmp, mode="w", format="NETCDF4", engine="netcdf4", encoding=encoding,
                     unlimited_dims=["time"])
        _publish(tmp, path)
    except BaseException as e:
        tmp.unlink(missing_ok=True)
        if isinstance(e, Exception) and not isinstance(e, ArchiveError):
            raise ArchiveError(f"{path}: writing failed, nothing written "
                               f"({_one_line(e)})") from e
        raise
    return path


def _open(path, chunks, dask: bool) -> xr.Dataset:
    """Open and check the metadata; every failure is one ArchiveError naming the path."""
    path = pathlib.Path(path)
    if not path.exists():
        parts = sorted(path.parent.glob(f".{glob.escape(path.name)}.*.part")) \
            if path.parent.is_dir() else []
        hint = f" (an interrupted write left {parts[0].name})" if parts else ""
        raise ArchiveError(f"{path}: no such archive{hint}")
    kwargs = {"chunks": {} if chunks is None else chunks} if dask else {}
    try:
        ds = xr.open_dataset(path, engine="netcdf4", decode_timedelta=False, **kwargs)
    except Exception as e:                 # noqa: BLE001 - HDF/netCDF errors of every kind
        raise ArchiveError(f"{path}: not a readable netCDF archive (truncated or corrupt?): "
                           f"{_one_line(e)}") from None
    try:
        if ds.attrs.get("complete") != "true":
            raise ArchiveError(f"{path}: incomplete archive (attribute complete = "
                               f"{ds.attrs.get('complete')!r}, expected 'true'): an "
                               "interrupted write; recompute it")
        problems = _schema_problems(ds)
        if problems:
            raise ArchiveError(f"{path}: not a contactpipe archive: " + _join(problems))
    except BaseException:
        ds.close()
        raise
    return ds


def open_archive(path, chunks=None) -> xr.Dataset:
    """Open an archive lazily (dask-backed).

    Parameters
    ----------
    path : str or path-like
        A file written by :func:`save` or :class:`ArchiveWriter`.
    chunks : None or anything :func:`xarray.open_dataset` takes
        None: one time step per chunk of a field, the on-disk chunks for series.

    Raises
    ------
    ArchiveError
        One line naming the path: missing, unreadable (truncated, corrupt, not netCDF),
        incomplete (no ``complete = "true"``: an interrupted write) or not following the
        schema (dims, variables, units, required attributes).
    """
    ds = _open(path, chunks, dask=True)
    if chunks is None:                     # files of other origin: one step per field chunk
        for name, v in ds.data_vars.items():
            if v.dims == FIELD and v.chunks is not None and max(v.chunks[0]) > 1:
                ds[name] = v.chunk({"time": 1})
    return ds


def is_complete(path) -> bool:
    """True when ``path`` is a finished, readable archive with the schema's metadata.

    Cheap (reads metadata only) and never raises: sweeps use it to decide what to
    recompute.
    """
    try:
        _open(path, None, dask=False).close()
        return True
    except Exception:                      # noqa: BLE001 - any failure means "recompute"
        return False
