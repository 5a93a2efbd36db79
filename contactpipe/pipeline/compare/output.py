"""A comparison table written and shown: netCDF or CSV by the suffix, atomically, never
over an input (:func:`write_table`, :func:`check_table_path`), and as text
(:func:`format_table`)."""
from __future__ import annotations

import pathlib

import numpy as np
import xarray as xr

from ..._util.files import atomic_path, check_output_dir, check_output_path, make_folder
from ...exceptions import ArchiveError

__all__ = ["check_table_path", "write_table", "format_table", "TABLE_SUFFIXES"]

#: The formats of an error table, by suffix.
TABLE_SUFFIXES = (".nc", ".csv")

# --------------------------------------------------------------------------- output

def check_table_path(out, inputs=()) -> pathlib.Path:
    """Refuse, before any work, a path an error table cannot be written to.

    Raises
    ------
    ArchiveError
        The suffix is neither ``.nc`` nor ``.csv``.
    OutputPathError
        Empty, a directory, a device or other special file, one of ``inputs``, or a
        folder that is a file (:func:`contactpipe._util.files.check_output_path`).
    """
    out = check_output_path(out, "error table", inputs=inputs)
    if out.suffix.lower() not in TABLE_SUFFIXES:
        raise ArchiveError(f"{out}: the error table is written as netCDF (.nc) or CSV "
                           f"(.csv), got suffix {out.suffix!r}")
    check_output_dir(out.parent, "folder of the error table")
    return out


def write_table(table: xr.Dataset, out) -> pathlib.Path:
    """Write an error table atomically: netCDF for ``.nc``, CSV for ``.csv``.

    The CSV has ``#`` comment lines first (attributes and scalar errors), then one row
    per instant (read it with ``pandas.read_csv(path, comment="#")``). The path is
    checked first (:func:`check_table_path`); its folder is created.
    """
    out = check_table_path(out)
    make_folder(out.parent)
    with atomic_path(out) as tmp:
        if out.suffix.lower() == ".nc":
            table.to_netcdf(tmp, engine="netcdf4")
        else:
            _write_csv(table, tmp)
    return out


def _write_csv(table: xr.Dataset, path) -> None:
    lines = [f"# {k}: {_attr_text(v)}" for k, v in table.attrs.items()]
    lines += [f"# {k} = {float(table[k]):.17g}" for k in table.data_vars
              if table[k].ndim == 0]
    series = [k for k in table.data_vars if table[k].dims == ("time",)]
    frame = table[series].to_dataframe()
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write("\n".join(lines) + "\n")
        frame.to_csv(f, float_format="%.10g")


def _attr_text(v):
    if isinstance(v, np.ndarray):
        return " ".join(str(x) for x in v.tolist())
    return " ".join(str(v).split())


def format_table(table: xr.Dataset) -> str:
    """A short text table: the largest value of each error and when it occurs."""
    rows = []
    width = max(len(k) for k in table.data_vars)
    for k, v in table.data_vars.items():
        vals = np.asarray(v.values, float)
        if v.ndim == 0:
            rows.append(f"  {k:<{width}}  {float(vals):10.3g}  (final)")
            continue
        if not np.any(np.isfinite(vals)):
            rows.append(f"  {k:<{width}}  {'n/a':>10}")
            continue
        i = int(np.nanargmax(vals))
        rows.append(f"  {k:<{width}}  {vals[i]:10.3g}  (max, at t = "
                    f"{float(table['time'][i]):.4g} s)")
    return "\n".join([table.attrs.get("summary", "")] + rows)
