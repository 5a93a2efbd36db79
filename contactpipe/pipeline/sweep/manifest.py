"""The manifest of a sweep folder (``manifest.json``): written by the sweep, validated on
every read.

Format 1::

    {"format": 1, "contactpipe_version": "...", "created": "...", "updated": "...",
     "mode": "product" | "zip",
     "axes": {"<axis>": [values, ...]},          # in sweep order
     "derived": {"<axis>": "module.function"},   # the derived parameters' functions
     "dims": {"<axis>": "<dimension name>"},
     "base_scene": "<TOML>", "base_name": "...",
     "members": [{"index": 0, "values": {"<axis>": value}, "digest": "<16 hex>",
                  "file": "<digest>.nc", "status": "pending" | "done" | "failed",
                  "error": null | "<one line>", "wall_time_s": null | s,
                  "cpu_time_s": null | s}, ...]}

A manifest edited by hand is read only if it still has this structure: otherwise one
:class:`~contactpipe.ArchiveError` line names the first key that is wrong, its value and
what it should be (never a bare KeyError).
"""
from __future__ import annotations

import json
import numbers
import pathlib
import re

from ..._util.files import utc_now, write_json
from ..._version import __version__
from ...exceptions import ArchiveError
from .members import MODES, STATUSES, coord_value, jsonable

__all__ = ["MANIFEST", "MANIFEST_FORMAT", "read_manifest", "check_manifest", "new_manifest",
           "write_manifest", "previous_records", "DIGEST"]

MANIFEST = "manifest.json"
MANIFEST_FORMAT = 1
#: A member digest (:meth:`contactpipe.Scene.digest`): 16 lowercase hex characters.
DIGEST = re.compile(r"[0-9a-f]{16}")


def _brief(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class _Checker:
    """Raise one ArchiveError naming the key of the first problem."""

    def __init__(self, where: str):
        self.where = where

    def need(self, ok: bool, key: str, what: str, value) -> None:
        if not ok:
            raise ArchiveError(f"{self.where}: {key} must be {what}, got {_brief(value)} "
                               f"(a manifest edited by hand? re-run the sweep to rewrite it)")


def _is_real(v) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _check_axes(c: _Checker, manifest: dict) -> list:
    axes, dims = manifest["axes"], manifest["dims"]
    c.need(isinstance(axes, dict) and bool(axes), "axes", "a non-empty object "
           "{axis: [values]}", axes)
    for name, values in axes.items():
        c.need(isinstance(values, list) and bool(values), f"axes.{name}",
               "a non-empty list of values", values)
    c.need(isinstance(dims, dict) and set(dims) == set(axes), "dims",
           f"an object with one dimension name per axis ({', '.join(axes)})", dims)
    for name, dim in dims.items():
        c.need(isinstance(dim, str) and bool(dim), f"dims.{name}",
               "a dimension name (a non-empty string)", dim)
    c.need(len(set(dims.values())) == len(dims), "dims", "distinct dimension names", dims)
    return list(axes)


def _check_member(c: _Checker, i: int, m, names: list, axis_values: dict) -> None:
    key = f"members[{i}]"
    c.need(isinstance(m, dict), key, "an object", m)
    for field in ("index", "values", "digest", "file", "status"):
        c.need(field in m, f"{key}.{field}", "present", "nothing")
    c.need(isinstance(m["index"], int) and not isinstance(m["index"], bool)
           and m["index"] >= 0, f"{key}.index", "an integer >= 0", m["index"])
    values = m["values"]
    c.need(isinstance(values, dict) and set(values) == set(names), f"{key}.values",
           f"an object with a value for each axis ({', '.join(names)})", values)
    for n in names:
        c.need(coord_value(values[n]) in axis_values[n], f"{key}.values.{n}",
               f"one of axes.{n}", values[n])
    digest = m["digest"]
    c.need(isinstance(digest, str) and DIGEST.fullmatch(digest) is not None,
           f"{key}.digest", "16 lowercase hex characters (a scene digest)", digest)
    c.need(m["file"] == f"{digest}.nc", f"{key}.file", f"'{digest}.nc' (the member's "
           f"digest; never a path)", m["file"])
    c.need(m["status"] in STATUSES, f"{key}.status", f"one of {', '.join(STATUSES)}",
           m["status"])
    c.need(m.get("error") is None or isinstance(m.get("error"), str), f"{key}.error",
           "null or a string", m.get("error"))
    for field in ("wall_time_s", "cpu_time_s"):
        v = m.get(field)
        c.need(v is None or _is_real(v), f"{key}.{field}", "null or a number [s]", v)


def check_manifest(manifest, where: str = MANIFEST) -> dict:
    """Check the structure and types of a manifest; returns it.

    Raises
    ------
    ArchiveError
        One line naming the first key that is missing or wrong (``where`` first).
    """
    c = _Checker(where)
    c.need(isinstance(manifest, dict), "the manifest", "a JSON object", manifest)
    missing = [k for k in ("axes", "mode", "dims", "members") if k not in manifest]
    if missing:
        raise ArchiveError(f"{where}: not a contactpipe sweep manifest (missing "
                           f"{', '.join(missing)})")
    fmt = manifest.get("format", MANIFEST_FORMAT)
    c.need(fmt == MANIFEST_FORMAT and not isinstance(fmt, bool), "format",
           f"{MANIFEST_FORMAT} (the format this contactpipe reads)", fmt)
    c.need(manifest["mode"] in MODES, "mode", f"one of {', '.join(MODES)}",
           manifest["mode"])
    for key in ("base_scene", "base_name", "created", "updated"):
        if key in manifest:
            c.need(isinstance(manifest[key], str), key, "a string", manifest[key])
    names = _check_axes(c, manifest)
    members = manifest["members"]
    c.need(isinstance(members, list), "members", "a list of member objects", members)
    axis_values = {n: [coord_value(v) for v in manifest["axes"][n]] for n in names}
    seen = set()
    for i, m in enumerate(members):
        _check_member(c, i, m, names, axis_values)
        combo = (m["index"],) if manifest["mode"] == "zip" else \
            tuple(json.dumps(coord_value(m["values"][n])) for n in names)
        c.need(combo not in seen, f"members[{i}]", "a member not listed before "
               "(the same index or axis values twice)", m["values"])
        seen.add(combo)
    return manifest


def read_manifest(out_dir) -> dict:
    """The manifest of a sweep folder, checked (:func:`check_manifest`).

    Raises
    ------
    ArchiveError
        No manifest (not a sweep folder), not JSON, or not the structure above; one line
        naming the file and the key.
    """
    out_dir = pathlib.Path(out_dir)
    path = out_dir / MANIFEST
    if not path.exists():
        raise ArchiveError(f"{out_dir}: not a sweep folder (no {MANIFEST}); run the sweep "
                           f"first")
    try:
        with open(path, encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError) as err:     # ValueError: not JSON, or not UTF-8
        raise ArchiveError(f"{path}: unreadable sweep manifest ({type(err).__name__}: "
                           f"{err})") from None
    except RecursionError:
        raise ArchiveError(f"{path}: unreadable sweep manifest (arrays or objects nested "
                           "too deep to read; a manifest nests a few levels)") from None
    try:
        return check_manifest(manifest, str(path))
    except RecursionError:                   # nested values deep enough to pass json.load
        raise ArchiveError(f"{path}: not a contactpipe sweep manifest (values nested too "
                           "deep; a manifest nests a few levels)") from None


def new_manifest(base, mode, names, values, funcs, dims, members, created=None) -> dict:
    """The manifest of a sweep about to run (every member as it stands)."""
    return {
        "format": MANIFEST_FORMAT,
        "contactpipe_version": __version__,
        "created": created or utc_now(),
        "updated": utc_now(),
        "mode": mode,
        "axes": {n: [jsonable(v) for v in values[n]] for n in names},
        "derived": {n: _func_name(funcs[n]) for n in names if funcs[n] is not None},
        "dims": dims,
        "base_scene": base.to_toml(),
        "base_name": base.name,
        "members": [m.to_json() for m in members],
    }


def write_manifest(out_dir, manifest: dict, members=None) -> None:
    """Write ``manifest`` atomically into ``out_dir`` (its members first refreshed from
    ``members`` and ``updated`` set to now)."""
    if members is not None:
        manifest["members"] = [m.to_json() for m in members]
    manifest["updated"] = utc_now()
    write_json(pathlib.Path(out_dir) / MANIFEST, manifest)


def previous_records(out_dir) -> tuple[dict, str | None]:
    """({digest: {wall_time_s, cpu_time_s}} of done members, creation time) of an
    earlier manifest, so that skipped members keep their timings; ({}, None) when there
    is none or it is not a valid manifest (the sweep rewrites it)."""
    try:
        manifest = read_manifest(out_dir)
    except ArchiveError:
        return {}, None
    out = {}
    for m in manifest["members"]:
        if m["status"] == "done":
            out[m["digest"]] = {k: m[k] for k in ("wall_time_s", "cpu_time_s")
                                if m.get(k) is not None}
    return out, manifest.get("created")


def _func_name(func) -> str:
    return f"{getattr(func, '__module__', '?')}.{getattr(func, '__qualname__', repr(func))}"
