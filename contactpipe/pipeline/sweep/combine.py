"""A sweep folder read back as one labelled Dataset (:func:`open_sweep`).

Every member archive is checked against the manifest before it is combined: it opens as
a complete contactpipe archive, and the scene it holds has the member's digest (the name
of its file), so archives swapped or copied by hand are refused instead of being shown
under another member's axis values.
"""
from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import xarray as xr

from ...archive import open_archive
from ...exceptions import ArchiveError
from ...nomenclature import cf_attrs
from ..inputs import scene_digest
from .manifest import MANIFEST, read_manifest
from .members import coord_value, label_of

__all__ = ["open_sweep", "open_member", "MANIFEST"]

#: Members listed at most in the message about members not done.
_LISTED = 10
_COMBINE = dict(data_vars="all", coords="different", compat="equals", join="outer",
                combine_attrs="drop")


def open_member(out_dir, member: dict, chunks=None) -> xr.Dataset:
    """Open one member's archive, checked: a complete archive whose scene has the
    member's digest.

    Raises
    ------
    ArchiveError
        Naming the member and its file: missing, unreadable, incomplete, or holding the
        scene of another digest (swapped or copied by hand).
    """
    where = f"sweep member {label_of(member['values'])} ({member['file']})"
    try:
        ds = open_archive(pathlib.Path(out_dir) / member["file"], chunks=chunks)
    except ArchiveError as err:
        raise ArchiveError(f"{where}: {err}") from None
    try:
        found = scene_digest(ds)
    except ArchiveError as err:
        ds.close()
        raise ArchiveError(f"{where}: {err}") from None
    if found != member["digest"]:
        ds.close()
        raise ArchiveError(f"{where}: the archive holds the scene of digest {found}, not "
                           f"{member['digest']} (swapped or copied by hand?); re-run the "
                           f"sweep to set it aside and recompute the member")
    return ds


def _split_done(out_dir, manifest, allow_missing):
    members = manifest["members"]
    done = [m for m in members if m["status"] == "done"]
    not_done = [m for m in members if m["status"] != "done"]
    if not_done and not allow_missing:
        listed = "; ".join(f"{label_of(m['values'])} ({m['status']}"
                           + (f": {m['error']}" if m.get("error") else "") + ")"
                           for m in not_done[:_LISTED])
        more = f"; ... and {len(not_done) - _LISTED} more" if len(not_done) > _LISTED else ""
        raise ArchiveError(f"{out_dir}: {len(not_done)} of {len(members)} sweep members "
                           f"are not done: {listed}{more}. Re-run the sweep, or pass "
                           f"allow_missing=True to drop them")
    if not done:
        raise ArchiveError(f"{out_dir}: no sweep member is done; run the sweep first")
    return done, not_done


def _alignment(out_dir, datasets) -> tuple[bool, bool]:
    """(same time, same grid) of the members; ArchiveError for grids of other sizes."""
    times = [ds["time"].values for ds in datasets]
    same_time = all(t.shape == times[0].shape and np.array_equal(t, times[0]) for t in times)
    grids = [(ds["x1"].values, ds["x2"].values) for ds in datasets]
    same_grid = all(np.array_equal(g[0], grids[0][0]) and np.array_equal(g[1], grids[0][1])
                    for g in grids)
    sizes = sorted({(g[0].size, g[1].size) for g in grids})
    if not same_grid and len(sizes) > 1:
        raise ArchiveError(
            f"{out_dir}: the members have grids of different sizes ({sizes}); they cannot "
            "share the x1, x2 dimensions — open them one by one with open_archive")
    return same_time, same_grid


def _prepared(ds, same_time, same_grid, taken=()) -> xr.Dataset:
    """A member ready to combine: no attributes; its own cell centres (x1_cell, x2_cell)
    when the grids differ; on t_norm when the times differ; a variable named as a sweep
    dimension (``taken``: a friction map ``mu`` in a ``friction.mu`` sweep) renamed
    ``<name>_map``."""
    ds = ds.copy()
    ds.attrs = {}
    clash = {v: f"{v}_map" for v in ds.data_vars if v in taken}
    if clash:
        ds = ds.rename_vars(clash)
    if not same_grid:
        # each member keeps its own cell centres (e.g. an automatic grid that grows with
        # the window): x1, x2 stay dimensions (cell positions), x1_cell, x2_cell are
        # coordinates varying along the axes
        ds = ds.rename_vars({"x1": "x1_cell", "x2": "x2_cell"})
    if not same_time:
        t = ds["time"].values
        span = t[-1] - t[0] if t.size > 1 else 1.0
        tn = np.round((t - t[0]) / (span if span > 0 else 1.0), 12)
        ds = ds.assign_coords(t_norm=("time", tn)).swap_dims(time="t_norm")
        ds["t_norm"].attrs.update(cf_attrs("t_norm"))
    return ds


def _labeller(manifest, names):
    """``label(axis, value)``: a member's coordinate label on an axis, its value
    (:func:`coord_value`), or its text on an axis that mixes numbers and text
    (``friction.mu = [0.1, "map.nc"]``: the labels "0.1" and the file's path), so that
    the coordinate has one type."""
    mixed = {n: len({isinstance(coord_value(v), str) for v in manifest["axes"][n]}) > 1
             for n in names}

    def label(n, v):
        v = coord_value(v)
        return str(v) if mixed[n] else v
    return label


def _combine_zip(prepared, names, dims, label) -> xr.Dataset:
    parts = []
    for m, ds in prepared:
        ds = ds.expand_dims(member=[m["index"]])
        coords = {dims[n]: ("member", [label(n, m["values"][n])]) for n in names}
        coords["digest"] = ("member", [m["digest"]])
        parts.append(ds.assign_coords(coords))
    return xr.concat(parts, "member", **_COMBINE)


def _combine_product(prepared, names, dims, manifest, label) -> xr.Dataset:
    """One dimension per axis; combine_nested when complete, unstack when holes."""
    axis_values = {n: [label(n, v) for v in manifest["axes"][n]] for n in names}
    shape = [len(axis_values[n]) for n in names]
    cells = {}
    for m, ds in prepared:
        key = tuple(axis_values[n].index(label(n, m["values"][n])) for n in names)
        ds = ds.expand_dims({dims[n]: [label(n, m["values"][n])] for n in names})
        cells[key] = ds.assign_coords(digest=([dims[n] for n in names],
                                              _nested([m["digest"]], len(names))))
    if len(cells) == math.prod(shape):
        nested = _grid(cells, shape, ())
        return xr.combine_nested(nested, concat_dim=[dims[n] for n in names], **_COMBINE)
    # holes (allow_missing): stack along "member", then unstack (NaN where missing)
    parts = [ds.stack(member=[dims[n] for n in names]) for _, ds in sorted(cells.items())]
    sw = xr.concat(parts, "member", **_COMBINE).unstack("member")
    sw = sw.transpose(*[dims[n] for n in names], ...)
    present = {dims[n]: [v for v in axis_values[n] if v in set(sw[dims[n]].values.tolist())]
               for n in names}
    return sw.reindex(present)


def _nested(value, depth):
    for _ in range(depth - 1):
        value = [value]
    return value


def _grid(cells, shape, prefix):
    if len(prefix) == len(shape):
        return cells[prefix]
    return [_grid(cells, shape, prefix + (i,)) for i in range(shape[len(prefix)])]


def _attributes(manifest, dims, opened, same_time, same_grid, not_done) -> dict:
    first = next(iter(opened.values()))
    keep = {k: first.attrs[k] for k in ("Conventions", "contactpipe_version")
            if k in first.attrs}
    models = {d.attrs.get("models") for d in opened.values()}
    if len(models) == 1:
        keep["models"] = models.pop()
    members = manifest["members"]
    keep.update({
        "title": f"contactpipe sweep: {manifest.get('base_name', '')}".strip(),
        "sweep_mode": manifest["mode"],
        "sweep_axes": json.dumps(manifest["axes"]),
        "sweep_dims": json.dumps(dims),
        "sweep_time_dim": "time" if same_time else "t_norm",
        "sweep_grid": "shared" if same_grid else "per member (coordinates x1_cell, x2_cell)",
        "base_scene": manifest.get("base_scene", ""),
        "sweep_members": len(members),
    })
    if not_done:
        keep["missing_members"] = json.dumps(
            [{"values": m["values"], "digest": m["digest"], "status": m["status"],
              "error": m.get("error")} for m in not_done])
        keep["note"] = (f"{len(not_done)} of {len(members)} members not done were dropped "
                        f"(see missing_members)")
    return keep


def open_sweep(out_dir, *, allow_missing=False, chunks=None) -> xr.Dataset:
    """Open a sweep folder as one lazy Dataset with one dimension per axis.

    Parameters
    ----------
    out_dir : path-like
        A folder written by :func:`~contactpipe.pipeline.sweep.sweep` (its
        ``manifest.json``, checked: :func:`~contactpipe.pipeline.sweep.manifest.read_manifest`).
    allow_missing : bool
        Drop members that failed or were never run (listed in the attribute
        ``missing_members``) instead of raising. In mode "product" a dropped member
        leaves a hole, filled with NaN (integer variables then become floats); an axis
        value with no member left disappears.
    chunks : optional
        Passed to :func:`~contactpipe.open_archive`.

    Returns
    -------
    xarray.Dataset
        Mode "product": dimensions = the axes (named as in the manifest's ``dims``:
        ``friction.mu`` -> ``mu``), coordinates = the axis values (as text on an axis
        that mixes numbers and files: ``friction.mu = [0.1, "map.nc"]``; a member's
        friction map is then the variable ``mu_map``). Mode "zip": one
        dimension ``member`` with every axis as a coordinate along it. A coordinate
        ``digest`` names each member's archive. Where the members' time coordinates
        differ (a ``tau_ratio`` sweep), the time dimension is ``t_norm`` = (t - t0)/tau
        (tau the member's load window) and ``time`` is a coordinate varying along the
        axes; otherwise ``time`` stays the dimension. Likewise, where the members' grids
        differ (an automatic grid size that depends on the swept window), ``x1`` and
        ``x2`` stay dimensions (cell positions) and each member's cell centres are the
        coordinates ``x1_cell``, ``x2_cell`` varying along the axes. Attributes
        ``sweep_axes``, ``sweep_dims`` (JSON), ``sweep_mode``, ``base_scene`` (TOML).
        Closing it closes the member archives.

    Raises
    ------
    ArchiveError
        No manifest, or one that is not valid (the message names the key); a member
        marked done whose archive is missing, corrupt or holds another member's scene
        (the message names the member and file); members not done (unless
        ``allow_missing``).
    """
    out_dir = pathlib.Path(out_dir)
    manifest = read_manifest(out_dir)
    names = list(manifest["axes"])
    dims = {n: manifest["dims"][n] for n in names}
    done, not_done = _split_done(out_dir, manifest, allow_missing)
    opened: dict[str, xr.Dataset] = {}
    try:
        for m in done:
            if m["digest"] not in opened:
                opened[m["digest"]] = open_member(out_dir, m, chunks=chunks)
        datasets = [opened[m["digest"]] for m in done]
        same_time, same_grid = _alignment(out_dir, datasets)
        taken = set(dims.values())
        prepared = [(m, _prepared(ds, same_time, same_grid, taken))
                    for m, ds in zip(done, datasets, strict=True)]
        label = _labeller(manifest, names)
        if manifest["mode"] == "zip":
            sw = _combine_zip(prepared, names, dims, label)
        else:
            sw = _combine_product(prepared, names, dims, manifest, label)
        for n in names:
            sw[dims[n]].attrs.update({"long_name": f"sweep axis {n}", "sweep_axis": n})
    except BaseException:
        for ds in opened.values():
            ds.close()
        raise
    sw.attrs = _attributes(manifest, dims, opened, same_time, same_grid, not_done)
    files = list(opened.values())
    sw.set_close(lambda: [ds.close() for ds in files])
    return sw
