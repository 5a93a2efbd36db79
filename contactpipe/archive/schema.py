"""What an archive must look like, checked from its metadata (no data read but coordinates).

The pieces every other module of :mod:`contactpipe.archive` shares: attribute conversion,
coordinate and variable checks, the storage types, and :func:`schema_problems`, the check
of a Dataset's dimensions, coordinates, variables and global attributes against
:mod:`contactpipe.nomenclature`.
"""
from __future__ import annotations

import json
import math
import numbers
import pathlib

import numpy as np
import xarray as xr

from .._util.files import TOMLDecodeError, loads_toml
from .._version import __version__
from ..exceptions import ArchiveError, one_line
from ..nomenclature import (
    CONVENTIONS,
    COORDINATES,
    FIELD,
    HISTORY,
    MAPS,
    REQUIRED_ATTRS,
    TANGENTIAL,
    VARIABLES,
)

__all__ = ["PRECISIONS", "SERIES_CHUNK", "COMPLEVEL", "DIMS", "join_problems", "storable",
           "global_attrs", "attr_problems", "axis", "variable_problems", "precision_dtype",
           "storage_dtype", "resumable_part", "schema_problems", "scene_table",
           "tangential_model", "expected_instants"]

PRECISIONS = ("float64", "float32")
SERIES_CHUNK = 1024        # time steps per on-disk chunk of a series (and of `time`)
COMPLEVEL = 1
DIMS = FIELD               # ("time", "x1", "x2")


def join_problems(problems: list[str]) -> str:
    """Several problems as one line."""
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


def storable(attrs: dict | None) -> dict:
    """Attributes converted to what netCDF stores (booleans to "true"/"false", None to "")."""
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


def global_attrs(attrs: dict | None) -> dict:
    """Defaults (Conventions, contactpipe_version) under the caller's attributes."""
    out = {"Conventions": CONVENTIONS, "contactpipe_version": __version__}
    out.update(storable(attrs))
    out.pop("complete", None)          # only a finished write sets it
    return out


def scene_table(attrs: dict) -> dict | None:
    """The ``scene`` attribute as a TOML table, or None when absent or not TOML."""
    scene = attrs.get("scene")
    if not isinstance(scene, str):
        return None
    try:
        return loads_toml(scene)
    except (ValueError, TOMLDecodeError):
        return None


def attr_problems(attrs: dict, required=REQUIRED_ATTRS) -> list[str]:
    """Missing, unreadable or unstorable global attributes."""
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
                problems.append(f"global attribute 'scene' is not TOML text "
                                f"({one_line(e)})")
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


def axis(name: str, values) -> np.ndarray:
    """A coordinate as float64: 1-D, non-empty, finite, strictly ascending."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ArchiveError(f"coordinate {name!r}: not numeric ({one_line(e)})") from None
    unit = COORDINATES[name]["units"]
    if arr.ndim != 1 or arr.size == 0:
        raise ArchiveError(f"coordinate {name!r}: shape {arr.shape}, expected a non-empty "
                           f"1-D array [{unit}]")
    if not np.all(np.isfinite(arr)):
        raise ArchiveError(f"coordinate {name!r} holds NaN or inf")
    if arr.size > 1 and not np.all(np.diff(arr) > 0):
        raise ArchiveError(f"coordinate {name!r} is not strictly ascending")
    return arr


def variable_problems(names) -> list[str]:
    """Unknown, repeated or missing required variable names."""
    names = list(names)
    problems = [f"unknown variable {n!r} (not in contactpipe.nomenclature.VARIABLES)"
                for n in names if n not in VARIABLES]
    problems += [f"variable {n!r} given twice" for n in sorted(set(names))
                 if names.count(n) > 1]
    problems += [f"variable {n!r} missing (every archive has it)"
                 for n, e in VARIABLES.items() if e["required"] and n not in names]
    return problems


def precision_dtype(precision) -> np.dtype:
    """The storage type of floats, refusing anything but float64 and float32."""
    try:
        dt = np.dtype(precision)
    except TypeError:
        dt = None
    if dt is None or dt.name not in PRECISIONS:
        raise ArchiveError(f"precision={precision!r}: expected one of {PRECISIONS}")
    return dt


def storage_dtype(name: str, precision: np.dtype) -> np.dtype:
    kind = VARIABLES[name]["dtype"]
    return precision if kind == "float" else np.dtype(kind)


def resumable_part(path) -> pathlib.Path:
    """The fixed part-file name of a resumable write of ``path``."""
    path = pathlib.Path(path)
    return path.with_name(f".{path.name}.resumable.part")


def tangential_model(attrs: dict) -> str | None:
    """The tangential model the archive says ran ("none", "scalar", ...), None if unsaid."""
    name = attrs.get("model_tangential")
    if isinstance(name, str) and name:
        return name
    models = attrs.get("models")
    if isinstance(models, str):
        for item in models.split(","):
            key, sep, value = item.strip().partition("=")
            if sep and key.strip() == "tangential":
                return value.strip()
    return None


def expected_instants(table: dict | None) -> int | None:
    """Instants a simulation of the scene table writes (every ``output.stride``-th of
    ``time.steps + 1``, and the last), or None when the table does not say."""
    if not isinstance(table, dict):
        return None
    steps = (table.get("time") or {}).get("steps") if isinstance(table.get("time"), dict) \
        else None
    out = table.get("output") if isinstance(table.get("output"), dict) else {}
    stride = out.get("stride", 1)
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in (steps, stride)) \
            or steps < 0 or stride < 1:
        return None
    return steps // stride + 1 + (1 if steps % stride else 0)


def _coordinate_problems(ds: xr.Dataset) -> list[str]:
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
    if "time" in ds.dims and ds.sizes["time"] == 0:
        problems.append("dimension 'time' has size 0: the archive holds no instant")
    for name, c in ds.coords.items():
        if name in COORDINATES and name not in DIMS \
                and c.attrs.get("units") != COORDINATES[name]["units"]:
            problems.append(f"coordinate {name!r}: units {c.attrs.get('units')!r}, expected "
                            f"{COORDINATES[name]['units']!r}")
    return problems


def _variable_schema_problems(ds: xr.Dataset) -> list[str]:
    problems = [f"unknown variable {name!r} (not in contactpipe.nomenclature.VARIABLES)"
                for name in ds.data_vars
                if name not in VARIABLES and name not in MAPS and name not in HISTORY]
    for name in sorted(str(n) for n in ds.data_vars if n in MAPS or n in HISTORY):
        v, entry = ds[name], MAPS.get(name) or HISTORY[name]
        if tuple(v.dims) != entry["dims"]:
            problems.append(f"{name}: dims {tuple(v.dims)}, expected {entry['dims']}")
        if v.attrs.get("units") != entry["units"]:
            problems.append(f"{name}: units {v.attrs.get('units')!r}, expected "
                            f"{entry['units']!r}")
    tangential = tangential_model(ds.attrs)
    for name, entry in VARIABLES.items():
        if name not in ds.data_vars:
            if entry["required"]:
                problems.append(f"variable {name!r} missing")
            elif (entry.get("model") == TANGENTIAL and not entry.get("diagnostic")
                  and tangential not in (None, "none")):
                problems.append(f"variable {name!r} missing: the archive says a tangential "
                                f"model ran (tangential={tangential})")
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
    return problems


def _instants_problems(ds: xr.Dataset) -> list[str]:
    """The time size against what the scene attribute says a run writes."""
    if "time" not in ds.dims:
        return []
    table = scene_table(ds.attrs)
    want = expected_instants(table)
    have = ds.sizes["time"]
    if want is None or want == have:
        return []
    stride = (table.get("output") or {}).get("stride", 1)
    return [f"the scene attribute has time.steps = {table['time']['steps']} and "
            f"output.stride = {stride}, which write {want} instants, but the archive holds "
            f"{have}"]


def schema_problems(ds: xr.Dataset) -> list[str]:
    """Problems visible from the metadata alone (reads no data but the dimension coords).

    Dimensions and coordinates (present, units, finite, ascending, at least one instant),
    variables (known, required ones present, the tangential model's outputs present when
    the archive says one ran, dims, units, type, flags), global attributes, and the number
    of instants against the ``scene`` attribute (``time.steps``, ``output.stride``).
    """
    return (_coordinate_problems(ds) + _variable_schema_problems(ds)
            + attr_problems(ds.attrs) + _instants_problems(ds))
