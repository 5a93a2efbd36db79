"""Writing archives: streamed step by step (:class:`ArchiveWriter`, :class:`MemoryWriter`)
or whole (:func:`save`), always atomic, checksummed and checked before they are published.

:class:`ArchiveWriter` streams time steps into a hidden temporary file next to the target
(``.NAME.<pid>-<token>.part``, or ``.NAME.resumable.part`` for a resumable run) and
renames it onto the target only in :meth:`~ArchiveWriter.close`, after reading the whole
file back (schema, coordinates, every value: :func:`contactpipe.archive.content_problems`,
which also verifies the checksums), setting ``complete = "true"`` and an fsync. On
:meth:`~ArchiveWriter.abort`, on an exception inside its ``with`` block, or when it is
garbage-collected unclosed, the temporary file is removed; a resumable writer may instead
:meth:`~ArchiveWriter.suspend` (keep its part file for a later resume).

Layout on disk: ``time`` unlimited; fields chunked (1, N1, N2), zlib level 1 with shuffle
when compressed; series in uncompressed chunks of ``SERIES_CHUNK`` steps (a few bytes per
instant: a series chunk is rewritten at every flush, and uncompressed it keeps its size
and place, so a part file killed between two flushes still matches its checkpoint); every
variable, coordinates included, with a fletcher32 checksum per chunk; no fill values;
floats in float64 or float32 (the precision), ``status`` int8, counts int32, coordinates
always float64.
"""
from __future__ import annotations

import math
import mmap
import pathlib
import time as _time
import weakref

import netCDF4
import numpy as np
import xarray as xr

from .._util.files import publish, temp_name
from .._util.interrupts import raise_if_signalled
from ..exceptions import ArchiveError, one_line
from ..nomenclature import FIELD, HISTORY, MAP, MAPS, VARIABLES, cf_attrs
from .background import NETCDF_LOCK, Background
from .content import content_problems
from .schema import (
    COMPLEVEL,
    SERIES_CHUNK,
    attr_problems,
    axis,
    global_attrs,
    join_problems,
    precision_dtype,
    resumable_part,
    schema_problems,
    storable,
    storage_dtype,
    variable_problems,
)

__all__ = ["ArchiveWriter", "MemoryWriter", "to_dataset", "save", "validate"]


def validate(ds: xr.Dataset) -> list[str]:
    """Every way ``ds`` departs from the archive schema and rules; empty when none.

    Checks dimensions and coordinates (present, units, finite, strictly ascending, at
    least one instant), the variables (known names, required ones present, the tangential
    outputs when a tangential model ran, dims, units, type, status flags), the global
    attributes (present, netCDF-storable, ``scene`` readable as TOML, its step count
    matching the instants), and every value (:func:`content_problems`: NaN or inf, p < 0,
    h < 0, flags, Coulomb). Lazy data is read block by block.
    """
    if not isinstance(ds, xr.Dataset):
        return [f"expected an xarray.Dataset, got {type(ds).__name__}"]
    return schema_problems(ds) + content_problems(ds)


class _StepWriter:
    """What both writers share: argument checks, per-step checks, context management."""

    def __init__(self, x1, x2, variables, attrs, precision, maps=None):
        self.x1 = axis("x1", x1)
        self.x2 = axis("x2", x2)
        self.variables = tuple(variables)
        self.precision = precision_dtype(precision)
        self.attrs = global_attrs(attrs)
        problems = variable_problems(self.variables)
        problems += attr_problems(self.attrs, required=("scene", "models"))
        self.maps = {}
        for name, value in (maps or {}).items():
            if name not in MAPS:
                problems.append(f"{name}: not a map of contactpipe.nomenclature.MAPS")
                continue
            arr = self._check_value(name, self.precision, value)
            if isinstance(arr, str):
                problems.append(arr)
            else:
                self.maps[name] = np.array(arr)
        if problems:
            raise ArchiveError(f"{self._label()}: " + join_problems(problems))
        self._dtypes = {n: storage_dtype(n, self.precision) for n in self.variables}
        self.steps = 0
        self._last_t = None
        self._done = False
        self._started = _time.perf_counter()

    def _label(self) -> str:
        return type(self).__name__

    def _check_value(self, name, dtype, value):
        """One variable of one instant, cast to its storage type (``value`` itself where it
        has that type already: not to be kept without a copy); or a problem (str)."""
        arr = np.asarray(value)
        entry = VARIABLES.get(name) or MAPS[name]
        want = (self.x1.size, self.x2.size) if entry["dims"] in (FIELD, MAP) else ()
        if want == () and arr.size == 1:
            arr = arr.reshape(())
        if arr.shape != want:
            return f"{name}: shape {arr.shape}, expected {want}"
        if arr.dtype.kind not in "biuf":
            return f"{name}: dtype {arr.dtype} is not numeric"
        finite = np.isfinite(arr)
        if not finite.all():
            return f"{name} holds {arr.size - int(finite.sum())} NaN or inf value(s)"
        if dtype.kind == "i":
            info = np.iinfo(dtype)
            if arr.dtype.kind == "f" and np.any(arr != np.round(arr)) \
                    or arr.min() < info.min or arr.max() > info.max:
                return f"{name}: values must be integers within {dtype}"
            arr = arr.astype(dtype)
            flags = entry.get("flag_values")
            if flags is not None and not np.isin(arr, flags).all():
                return (f"{name}: values {np.setdiff1d(arr, flags)} outside flag_values "
                        f"{list(flags)}")
            return arr
        if arr.dtype == dtype:             # the writers copy it where they keep it
            return arr
        with np.errstate(over="ignore"):   # a float32 overflow is reported just below
            arr = arr.astype(dtype)
        if not np.all(np.isfinite(arr)):
            return f"{name}: exceeds the range of {dtype}"
        return arr

    def _check_step(self, t, values) -> tuple[float, dict]:
        """Every value of one instant, checked and cast; raises before anything is kept."""
        if self._done:
            raise ArchiveError(f"{self._label()}: already closed or aborted; cannot append")
        k = self.steps
        try:
            t = float(t)
        except (TypeError, ValueError):
            raise ArchiveError(f"{self._label()}: step {k}: time {t!r} is not a number") from None
        problems = []
        if not math.isfinite(t):
            problems.append(f"time is {t}")
        elif self._last_t is not None and not t > self._last_t:
            problems.append(f"time {t:g} s is not after the previous instant {self._last_t:g} s")
        problems += [f"{n} missing" for n in self.variables if n not in values]
        problems += [f"{n} not declared when the writer was created"
                     for n in values if n not in self._dtypes]
        out = {}
        for name, dtype in self._dtypes.items():
            if name in values:
                arr = self._check_value(name, dtype, values[name])
                if isinstance(arr, str):
                    problems.append(arr)
                else:
                    out[name] = arr
        if problems:
            raise ArchiveError(f"{self._label()}: step {k} (t = {t:g} s) refused, nothing of "
                               "it written: " + "; ".join(problems))
        return t, out

    def _commit(self, t: float) -> None:
        self._last_t = t
        self.steps += 1

    def _final_attrs(self, attrs) -> dict:
        """The attributes at close: wall_time_s defaults to the time since creation."""
        merged = {**self.attrs, **storable(attrs)}
        merged.pop("complete", None)
        merged.setdefault("wall_time_s", _time.perf_counter() - self._started)
        problems = attr_problems(merged)
        if self.steps == 0:
            problems.insert(0, "no time step appended")
        if problems:
            raise ArchiveError(f"{self._label()}: cannot close, nothing written: "
                               + join_problems(problems))
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


def _discard(nc, tmp: pathlib.Path, background: Background | None = None) -> None:
    """Close the netCDF handle and remove the temporary file (abort and garbage
    collection), once the writer thread has finished the write it was doing."""
    if background is not None:
        background.stop()
    try:
        if nc.isopen():
            nc.close()
    except Exception:                      # noqa: BLE001 - cleanup must not mask the cause
        pass
    try:
        tmp.unlink(missing_ok=True)
    except OSError:
        pass


#: HDF5 chunk cache of each variable while a written file is read back [bytes]. The
#: library's default (64 MiB a variable) kept every chunk read, so the check held up to
#: 64 MiB per field (+325 MiB at 512^2, 21 instants); the check reads each chunk once.
READBACK_CACHE = 2**20


def _open_for_check(file):
    """The file opened by xarray with a small chunk cache (:data:`READBACK_CACHE`); the
    library's default is restored for later opens."""
    import netCDF4

    old = netCDF4.get_chunk_cache()
    netCDF4.set_chunk_cache(READBACK_CACHE, old[1], old[2])
    try:
        return xr.open_dataset(file, engine="netcdf4", decode_timedelta=False)
    finally:
        netCDF4.set_chunk_cache(*old)


def _written_problems(file, x1, x2, names, steps: int, whole: bool) -> list[str]:
    """What is wrong with a written file, read back: its grid, its variables, its instants
    (exactly ``steps`` when ``whole``, at least ``steps`` for a part file to continue) and
    every value of the first ``steps`` instants (reading verifies the checksums)."""
    try:
        ds = _open_for_check(file)
    except Exception as e:                 # noqa: BLE001 - HDF/netCDF errors of every kind
        return [f"unreadable ({one_line(e)})"]
    with ds:
        problems = []
        for name, want in (("x1", x1), ("x2", x2)):
            if name not in ds.coords or not np.array_equal(ds[name].values, want):
                problems.append(f"coordinate {name!r} differs from the grid written")
        if sorted(ds.data_vars) != sorted(names):
            problems.append(f"variables {sorted(ds.data_vars)}, expected {sorted(names)}")
        have = ds.sizes.get("time", 0)
        if whole and have != steps:
            problems.append(f"{have} instants, expected {steps}")
        elif have < steps:
            problems.append(f"the part file holds {have} instants, the checkpoint {steps}")
        if problems:
            return problems
        head = ds.isel(time=slice(0, steps))
        if whole:
            return schema_problems(ds) + content_problems(head)
        t = np.asarray(head["time"].values, dtype=float)
        if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
            return ["its time coordinate is not finite and ascending"]
        return content_problems(head)


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
        zlib (level 1) with shuffle on every field (series stay uncompressed).
    resumable : bool
        Write to the fixed part file ``.NAME.resumable.part`` (:func:`resumable_part`),
        which :meth:`suspend` keeps for a later run.
    resume_steps : int, optional
        Continue the existing part file after this many instants (checked first: its grid,
        variables and those instants; :class:`ArchiveError` when it is damaged).
    maps : dict, optional
        Variables over (x1, x2) written once (:data:`contactpipe.nomenclature.MAPS`, e.g. a
        mapped friction coefficient ``mu``), checked like a field.

    Notes
    -----
    The writer keeps at most three instants in memory (two queued and the one being
    handed over: :data:`.background.DEPTH`): each ``append`` is handed to the
    writer's thread, which compresses and writes it while the caller computes the next
    (:mod:`.background`); ``flush`` and ``close`` wait for it. A step
    holding NaN or inf is refused whole (``ArchiveError`` naming variable and step) and the
    writer stays usable. ``close`` adds the final attributes (``wall_time_s`` defaults to
    the seconds since the writer was created), reads the file back and refuses to publish
    it when anything breaks the archive's rules, then sets ``complete = "true"``, fsyncs
    and renames atomically.
    """

    def __init__(self, path, x1, x2, variables: list[str], attrs: dict,
                 precision="float64", compress=True, resumable=False, resume_steps=None,
                 maps=None):
        self.path = pathlib.Path(path)
        super().__init__(x1, x2, variables, attrs, precision, maps)
        self.compress = bool(compress)
        self.resumable = bool(resumable)
        self._tmp = resumable_part(self.path) if resumable else temp_name(self.path)
        if resume_steps is not None:
            self._reopen(int(resume_steps))
            return
        try:
            nc = netCDF4.Dataset(self._tmp, mode="w", format="NETCDF4",
                                 clobber=self.resumable)
        except Exception as e:             # noqa: BLE001 - reported with the path
            self._done = True
            raise ArchiveError(f"{self.path}: cannot create the temporary file "
                               f"{self._tmp.name} ({one_line(e)})") from e
        self._nc = nc
        self._background = Background(str(self.path))
        self._finalizer = weakref.finalize(self, _discard, nc, self._tmp, self._background)
        try:
            self._define()
        except BaseException as e:
            self.abort()
            if isinstance(e, Exception):
                raise ArchiveError(f"{self.path}: cannot lay out the archive "
                                   f"({one_line(e)})") from e
            raise

    def _label(self) -> str:
        return str(self.path)

    def _reopen(self, steps: int) -> None:
        """Continue a resumable write: check its part file, then reopen it after ``steps``
        instants."""
        self._done = True                  # until the part file proved usable
        if not self._tmp.exists():
            problems = ["the part file is missing"]
        elif steps < 1:
            problems = [f"the checkpoint records {steps} instants written"]
        else:
            problems = _written_problems(self._tmp, self.x1, self.x2,
                                         self.variables + tuple(self.maps), steps, whole=False)
        if problems:
            raise ArchiveError(f"{self.path}: cannot resume from {self._tmp.name}: "
                               + join_problems(problems))
        try:
            nc = netCDF4.Dataset(self._tmp, mode="a")
            self._last_t = float(nc["time"][steps - 1])
        except Exception as e:             # noqa: BLE001 - reported with the path
            raise ArchiveError(f"{self.path}: cannot resume from {self._tmp.name} "
                               f"({one_line(e)})") from e
        self._nc = nc
        self.steps = steps
        self._done = False
        self._background = Background(str(self.path))
        self._finalizer = weakref.finalize(self, _discard, nc, self._tmp, self._background)

    def flush(self) -> None:
        """Push what was appended to disk (before a checkpoint): wait for the writer
        thread, then sync; nothing once closed. Raises a failed write."""
        if self._nc.isopen():
            self._background.drain()
            with NETCDF_LOCK:
                self._nc.sync()

    def suspend(self) -> None:
        """Close the part file and keep it for a later resume (resumable writers only)."""
        if not self.resumable:
            return self.abort()
        self._finalizer.detach()
        self._background.stop()        # the part file keeps what was written (checkpointed)
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
            v = nc.createVariable(name, "f8", (name,), fletcher32=True)
            v.setncatts(cf_attrs(name))
            v[:] = getattr(self, name)
        v = nc.createVariable("time", "f8", ("time",), chunksizes=(SERIES_CHUNK,),
                              fletcher32=True)
        v.setncatts(cf_attrs("time"))
        zip_ = {"compression": "zlib", "complevel": COMPLEVEL, "shuffle": True} \
            if self.compress else {"compression": None}
        field_chunks = (1, self.x1.size, self.x2.size)
        for name, dtype in self._dtypes.items():
            dims = VARIABLES[name]["dims"]
            field = dims == FIELD
            v = nc.createVariable(name, dtype, dims, fill_value=False,
                                  chunksizes=field_chunks if field else (SERIES_CHUNK,),
                                  fletcher32=True, **(zip_ if field else {"compression": None}))
            # each chunk is written once: cache one (not the library's 64 MiB per variable),
            # so memory stays flat however many steps are written
            v.set_var_chunk_cache(size=int(np.prod(v.chunking())) * dtype.itemsize, nelems=7,
                                  preemption=1.0)
            v.setncatts(cf_attrs(name))
        for name, arr in self.maps.items():
            v = nc.createVariable(name, arr.dtype, MAP, fill_value=False, fletcher32=True,
                                  **zip_)
            v.setncatts(cf_attrs(name))
            v[:] = arr
        nc.setncatts(self.attrs)

    def append(self, t: float, values: dict) -> None:
        """Write one instant: time ``t`` [s] and a value for every declared variable.

        The values are checked here (a refused instant raises, nothing of it kept) and
        written by the writer's thread (:mod:`.background`) while the caller goes on;
        the arrays are copied where they are the caller's own. A failed write is raised
        by a later ``append``, ``flush`` or ``close``."""
        t, arrays = self._check_step(t, values)
        owned = {name: (arr.copy() if isinstance(values[name], np.ndarray)
                        and np.may_share_memory(arr, values[name]) else arr)
                 for name, arr in arrays.items()}
        self._background.submit(self.steps, _write_instant, self._nc, self.steps, t, owned)
        self._commit(t)

    def close(self, attrs: dict | None = None) -> pathlib.Path:
        """Finish: final attributes, read back and check, ``complete = "true"``, fsync,
        rename onto the target. Nothing is published when the check finds a problem, nor
        when a signal came (:func:`~contactpipe._util.interrupts.raise_if_signalled`, checked
        first and again just before the rename): a resumable writer then keeps its
        part file, whole, for a resume to publish."""
        if self._done:
            raise ArchiveError(f"{self.path}: writer already closed or aborted")
        raise_if_signalled()
        try:
            self._background.drain()
            self._background.stop()
            final = self._final_attrs(attrs)
            final["complete"] = "true"
            self._nc.setncatts(final)
            self._nc.close()
            problems = _written_problems(self._tmp, self.x1, self.x2,
                                         self.variables + tuple(self.maps), self.steps,
                                         whole=True)
            if problems:
                raise ArchiveError(f"{self.path}: not published, the archive written breaks "
                                   "the archive's rules: " + join_problems(problems))
            # a signal received so far stops the publication (checked last thing before
            # the rename, with the signals held back until it is done)
            publish(self._tmp, self.path, check=raise_if_signalled)
        except BaseException as e:
            if self.resumable and isinstance(e, KeyboardInterrupt):
                self.suspend()
                raise
            self.abort()
            if isinstance(e, Exception) and not isinstance(e, ArchiveError):
                raise ArchiveError(f"{self.path}: closing failed, nothing written "
                                   f"({one_line(e)})") from e
            raise
        self._finalizer.detach()
        self._done = True
        return self.path

    def abort(self) -> None:
        """Drop everything written so far; the target path is left as it was."""
        finalizer = getattr(self, "_finalizer", None)
        if finalizer is not None:
            finalizer()
        self._done = True


def _write_instant(nc, k: int, t: float, arrays: dict) -> None:
    """Instant ``k`` into the open file ``nc`` (on the writer's thread)."""
    nc["time"][k] = t
    for name, arr in arrays.items():
        nc[name][k] = arr


#: Arrays of a MemoryWriter at least this large [bytes] are kept on their own anonymous
#: private memory map rather than numpy's heap (:func:`_fresh`).
MAPPED_BYTES = 1 << 22


def _fresh(shape, dtype) -> np.ndarray:
    """An uninitialised array for the steps of a :class:`MemoryWriter`.

    A large one lies on an anonymous private memory map: numpy asks the kernel for huge
    pages on its large allocations (madvise), and where the kernel compacts memory to
    find them on first touch (``defrag = madvise``, the kernel's default) filling a paper
    fig. 3 run's steps cost several times as long as on plain pages
    (docs/design-choices.md, D23). Its pages are made when it is mapped
    (``MAP_POPULATE``, where the system has it), in one call, rather than one fault per
    page as the steps fill it. The map is private, so a forked process never shares it,
    and it is unmapped with the last array that uses it.
    """
    dtype = np.dtype(dtype)
    nbytes = int(np.prod(shape)) * dtype.itemsize
    flags = getattr(mmap, "MAP_PRIVATE", 0) | getattr(mmap, "MAP_ANONYMOUS", 0)
    if nbytes < MAPPED_BYTES or not flags:
        return np.empty(shape, dtype)
    flags |= getattr(mmap, "MAP_POPULATE", 0)
    return np.frombuffer(mmap.mmap(-1, nbytes, flags=flags), dtype=dtype).reshape(shape)


class MemoryWriter(_StepWriter):
    """The :class:`ArchiveWriter` interface, kept in memory; ``close`` returns the Dataset.

    The constructor takes the same arguments, so either class can be chosen by whether a
    path is given: ``path`` must be None and ``compress`` has no effect in memory. Same
    checks per step (NaN/inf refused, integer and flag types), same precision and
    attributes, the same check at close, so ``MemoryWriter(None, ...).close()`` equals
    ``open_archive`` of what ``ArchiveWriter`` wrote from the same steps (less the
    ``complete`` attribute). ``capacity``, the number of instants expected, sizes the
    arrays that keep them at once (more are taken, the arrays doubled when full; the
    Dataset is the arrays themselves when full, so that close copies nothing).
    """

    def __init__(self, path, x1, x2, variables: list[str], attrs: dict, precision="float64",
                 compress=True, maps=None, capacity=None):
        if path is not None:
            raise ArchiveError(f"MemoryWriter: path={str(path)!r}, expected None (it keeps "
                               "the steps in memory; ArchiveWriter writes a file)")
        super().__init__(x1, x2, variables, attrs, precision, maps)
        self._times: list[float] = []
        # one (capacity, ...) array per variable, filled in place and doubled when full:
        # the Dataset is then views of them, with no copy of every step at close
        self._capacity = max(1, int(capacity)) if capacity is not None else 16
        self._data: dict[str, np.ndarray] = {}

    def append(self, t: float, values: dict) -> None:
        """Keep one instant: time ``t`` [s] and a value for every declared variable."""
        t, arrays = self._check_step(t, values)
        k = len(self._times)
        if k == self._capacity and self._data:
            self._capacity *= 2
            for name, old in self._data.items():
                self._data[name] = _fresh((self._capacity,) + old.shape[1:], old.dtype)
                self._data[name][:k] = old
        for name, arr in arrays.items():
            if name not in self._data:
                self._data[name] = _fresh((self._capacity,) + arr.shape, arr.dtype)
            self._data[name][k] = arr
        self._times.append(t)
        self._commit(t)

    def close(self, attrs: dict | None = None) -> xr.Dataset:
        """The labelled Dataset of every appended step (checked as :func:`validate` does)."""
        if self._done:
            raise ArchiveError(f"{self._label()}: writer already closed or aborted")
        final = self._final_attrs(attrs)
        data, self._data, n = self._data, {}, len(self._times)
        fields = {name: arr if n == len(arr) else arr[:n].copy() for name, arr in data.items()}
        ds = to_dataset(self.x1, self.x2, self._times, {**fields, **self.maps}, final)
        self.abort()
        problems = schema_problems(ds) + content_problems(ds)
        if problems:
            raise ArchiveError(f"{self._label()}: the steps appended break the archive's "
                               "rules: " + join_problems(problems))
        return ds

    def abort(self) -> None:
        """Drop every step kept."""
        self._times, self._data = [], {}
        self._done = True


def to_dataset(x1, x2, times, fields: dict, attrs: dict) -> xr.Dataset:
    """Label arrays as an archive Dataset.

    Parameters
    ----------
    x1, x2 : array_like
        Cell centres [m], strictly ascending.
    times : array_like
        The instants [s], strictly ascending.
    fields : dict of str -> array_like
        Variable name -> values, shaped (time, x1, x2), (time,) or (x1, x2) as the
        nomenclature says. Floats stay float32 when given as float32, else become float64;
        ``status`` becomes int8 and counts int32.
    attrs : dict
        Global attributes (``Conventions`` and ``contactpipe_version`` are filled in).

    Returns
    -------
    xarray.Dataset
        With ``units``, ``long_name`` (and flags) on every variable and coordinate.
    """
    coords = {"time": axis("time", times), "x1": axis("x1", x1), "x2": axis("x2", x2)}
    sizes = {d: v.size for d, v in coords.items()}
    problems = variable_problems([n for n in fields if n not in MAPS])
    data_vars = {}
    for name, values in fields.items():
        if name not in VARIABLES and name not in MAPS:
            continue
        entry = VARIABLES.get(name) or MAPS[name]
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
        raise ArchiveError("to_dataset: " + join_problems(problems))
    coord_vars = {d: xr.Variable((d,), v, attrs=cf_attrs(d)) for d, v in coords.items()}
    return xr.Dataset(data_vars, coords=coord_vars, attrs=global_attrs(attrs))


def _encoding(ds: xr.Dataset, prec, compress: bool) -> dict:
    zip_ = {"zlib": True, "complevel": COMPLEVEL, "shuffle": True} if compress \
        else {"zlib": False}
    encoding = {}
    for name, v in ds.variables.items():
        enc = {"_FillValue": None, "fletcher32": True}
        if name in VARIABLES or name in MAPS or name in HISTORY:
            entry = VARIABLES.get(name) or MAPS.get(name) or HISTORY[name]
            enc["dtype"] = (prec or v.dtype) if entry["dtype"] == "float" \
                else np.dtype(entry["dtype"])
            dims = entry["dims"]
            if dims == MAP:
                enc.update(zip_)
            elif dims[-2:] == MAP:           # a field over time, or over a wear run's cycles
                enc["chunksizes"] = (1,) * (len(dims) - 2) + (ds.sizes["x1"], ds.sizes["x2"])
                enc.update(zip_)
            elif dims == ("time",):
                enc.update(chunksizes=(SERIES_CHUNK,), zlib=False)
            else:
                enc.update(zlib=False)
        elif name == "time":
            enc["chunksizes"] = (SERIES_CHUNK,)
        encoding[name] = enc
    return encoding


def save(ds: xr.Dataset, path, precision=None, compress=True) -> pathlib.Path:
    """Write ``ds`` to a netCDF4 archive atomically, after validating it.

    Parameters
    ----------
    ds : xarray.Dataset
        An archive Dataset (:func:`to_dataset`, :func:`contactpipe.simulate`,
        :func:`open_archive`). Boolean and None attributes are converted.
    path : str or path-like
        Target file; replaced only once the new archive is complete.
    precision : {None, "float64", "float32"}
        Storage type of floating-point variables; None keeps each variable's own.
    compress : bool
        zlib level 1 with shuffle on the fields (series stay uncompressed).

    Returns
    -------
    pathlib.Path
        The archive written, with global attribute ``complete = "true"``.

    Raises
    ------
    ArchiveError
        Listing every problem :func:`validate` finds, before a byte is written; or when
        writing fails (then nothing is left at ``path`` but what was there before).
    """
    path = pathlib.Path(path)
    if not isinstance(ds, xr.Dataset):
        raise ArchiveError(f"{path}: not saved: expected an xarray.Dataset, got "
                           f"{type(ds).__name__}")
    prec = None if precision is None else precision_dtype(precision)
    ds = ds.drop_encoding()
    ds.attrs = storable(ds.attrs)
    ds.attrs.pop("complete", None)
    for v in ds.variables.values():
        v.attrs = storable(v.attrs)
    problems = validate(ds)
    if problems:
        raise ArchiveError(f"{path}: not saved, the dataset does not follow the archive "
                           "schema: " + join_problems(problems))
    ds.attrs["complete"] = "true"
    tmp = temp_name(path)
    try:
        ds.to_netcdf(tmp, mode="w", format="NETCDF4", engine="netcdf4",
                     encoding=_encoding(ds, prec, compress), unlimited_dims=["time"])
        publish(tmp, path)
    except BaseException as e:
        tmp.unlink(missing_ok=True)
        if isinstance(e, Exception) and not isinstance(e, ArchiveError):
            raise ArchiveError(f"{path}: writing failed, nothing written "
                               f"({one_line(e)})") from e
        raise
    return path
