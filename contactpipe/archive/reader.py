"""Reading archives: open lazily, refuse what is not a finished archive, verify on demand.

:func:`open_archive` opens lazily (dask, one time step per chunk of a field) and refuses,
with :class:`~contactpipe.exceptions.ArchiveError`, a file that is missing, unreadable,
interrupted (no ``complete = "true"``) or off the schema (from the metadata alone). With
``verify=True`` it also reads every value once, block by block
(:func:`~contactpipe.archive.content_problems`: NaN/inf, p < 0, h < 0, status flags,
Coulomb, checksums and corrupt chunks), as the pipeline stages do on their inputs.
:func:`is_complete` is the cheap yes/no form that sweeps use to decide what to recompute.
"""
from __future__ import annotations

import glob
import pathlib

import netCDF4
import xarray as xr

from ..exceptions import ArchiveError, one_line
from ..nomenclature import FIELD
from .content import BLOCK_BYTES, content_problems
from .schema import DIMS, join_problems, schema_problems

__all__ = ["open_archive", "is_complete"]


def _unreadable_coordinate(path) -> str:
    """Which coordinate of a file that xarray cannot open fails to read ("" if none)."""
    try:
        nc = netCDF4.Dataset(path, mode="r")
    except Exception:                      # noqa: BLE001 - not even netCDF: nothing to add
        return ""
    try:
        for name in DIMS:
            if name in nc.variables:
                try:
                    nc.variables[name][:]
                except Exception as e:     # noqa: BLE001 - checksum or decompression
                    return f"coordinate {name!r} cannot be read ({one_line(e)}); "
        return ""
    finally:
        nc.close()


def _open(path, chunks, dask: bool) -> xr.Dataset:
    """Open and check the metadata; every failure is one ArchiveError naming the path."""
    path = pathlib.Path(path)
    if not path.exists():
        parts = sorted(path.parent.glob(f".{glob.escape(path.name)}.*.part")) \
            if path.parent.is_dir() else []
        hint = f" (an interrupted write left {parts[0].name})" if parts else ""
        raise ArchiveError(f"{path}: no such archive{hint}")
    if not path.is_file():
        raise ArchiveError(f"{path}: not a regular file (a directory or a device), not an "
                           "archive")
    kwargs = {"chunks": {} if chunks is None else chunks} if dask else {}
    try:
        ds = xr.open_dataset(path, engine="netcdf4", decode_timedelta=False, **kwargs)
    except Exception as e:                 # noqa: BLE001 - HDF/netCDF errors of every kind
        raise ArchiveError(f"{path}: not a readable netCDF archive (truncated or corrupt?): "
                           f"{_unreadable_coordinate(path)}{one_line(e)}") from None
    try:
        if ds.attrs.get("complete") != "true":
            raise ArchiveError(f"{path}: incomplete archive (attribute complete = "
                               f"{ds.attrs.get('complete')!r}, expected 'true'): an "
                               "interrupted write; recompute it")
        problems = schema_problems(ds)
        if problems:
            raise ArchiveError(f"{path}: not a contactpipe archive: "
                               + join_problems(problems))
    except BaseException:
        ds.close()
        raise
    return ds


def _verify(path, budget_bytes: int) -> None:
    """Read every value of the archive at ``path`` once; ArchiveError naming each problem."""
    ds = _open(path, None, dask=False)
    try:
        problems = content_problems(ds, budget_bytes)
    finally:
        ds.close()
    if problems:
        raise ArchiveError(f"{path}: damaged archive: " + join_problems(problems))


def open_archive(path, chunks=None, *, verify: bool = False,
                 budget_bytes: int = BLOCK_BYTES) -> xr.Dataset:
    """Open an archive lazily (dask-backed).

    Parameters
    ----------
    path : str or path-like
        A file written by :func:`save` or :class:`ArchiveWriter`.
    chunks : None or anything :func:`xarray.open_dataset` takes
        None: one time step per chunk of a field, the on-disk chunks for series.
    verify : bool
        Read every value once before returning, streaming over time (at most
        ``budget_bytes`` of fields at a time), and refuse the archive when a value breaks
        its rules or cannot be read back (:func:`content_problems`). Costs one read of the
        file; the pipeline stages (compare, plot) verify their inputs.
    budget_bytes : int
        Memory bound of the verification [bytes].

    Raises
    ------
    ArchiveError
        One line naming the path: missing, unreadable (truncated, corrupt, not netCDF),
        incomplete (no ``complete = "true"``: an interrupted write), not following the
        schema (dims, variables, units, required attributes, the instants the ``scene``
        attribute implies); with ``verify``, each damaged variable with its first bad time
        step and what is wrong there.
    """
    if verify:
        _verify(path, budget_bytes)
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
