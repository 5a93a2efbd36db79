"""Parameter sweeps on dask: many scenes, one archive each, one labelled Dataset back.

    >>> import contactpipe as cp
    >>> base = cp.Scene.from_toml("fretting.toml")
    >>> res = cp.sweep(base, {"tau_ratio": [0.5, 1, 2], "friction.mu": [0.05, 0.1]},
    ...                out_dir="runs/")          # a LocalCluster unless told otherwise
    >>> res.ok, len(res.computed), len(res.skipped)
    >>> sw = cp.open_sweep("runs/")              # dims (tau_ratio, mu, t_norm, x1, x2)

Axes
----
An axis name is either a dotted path into the scene (``"friction.mu"``,
``"load.normal_force"``, ``"halfspace.relaxation_time"``, ``"time.steps"``; see
:meth:`Scene.replace`) or a *derived parameter* registered by name. Built in:

``tau_ratio``
    The load window tau = ``tau_ratio`` x the relaxation time of the first viscoelastic
    body that has one (indenter first): ``relaxation_time`` of a Maxwell body (or of a
    Prony body's dashpot), ``retardation_time`` of a Zener or Kelvin-Voigt body. The load
    knots are stretched proportionally from ``time[0]`` (or ``load.fretting.window`` is
    set), so the shape of the program and the number of steps stay the same.

Users register their own with :func:`register_parameter`, or give an axis as
``(values, func)`` for an ad-hoc one; ``func(scene, value)`` returns the new
:class:`~contactpipe.Scene`. Within a member, the dotted paths are applied first (all at
once), then the derived parameters in axis order, so ``tau_ratio`` sees a swept
relaxation time.

``mode="product"`` runs every combination (one dimension per axis); ``mode="zip"`` pairs
the i-th values of every axis (equal lengths; one dimension ``member``).

Files in ``out_dir``
--------------------
``<digest>.nc``
    One archive per member, named by :meth:`Scene.digest` (members with the same scene
    share it). Written atomically by :func:`~contactpipe.simulation`.
``manifest.json``
    Axes, mode, dimension names, the base scene (TOML) and, per member, its axis values,
    digest, file, status (``done`` / ``failed`` with a one-line error / ``pending``) and
    wall time. Rewritten atomically (temporary file + ``os.replace``) as members finish.
``.sweep.lock``
    Held (``fcntl.flock``) while a sweep runs: a second sweep on the same folder stops at
    once with :class:`SweepLockedError`. The file stays; the lock dies with its process.

Resuming
--------
Re-running the same sweep is cheap and safe: a member whose archive is complete and opens
cleanly (:func:`~contactpipe.archive.is_complete` and :func:`~contactpipe.open_archive`)
is skipped; a missing one is computed; a corrupt or truncated one is deleted and
recomputed; temporary files that a killed run left behind (``.<digest>.nc.*.part``) are
removed. Failed members are tried again.

Where the work runs
-------------------
``client`` (a :class:`distributed.Client`) if given; else ``scheduler``: the address of a
running scheduler (``"tcp://host:8786"``; the workers must see ``out_dir`` at the same
path) or ``"synchronous"`` (in this process, one member after the other: debugging and
tests); else a :class:`distributed.LocalCluster` of ``n_workers`` processes (default
``min(members to compute, CPU count)``) with ``threads_per_worker`` threads, started and
closed by the sweep, and only when there is something to compute. Its worker processes
are spawned, so a script that lets the sweep start one needs the usual
``if __name__ == "__main__":`` guard.

Sweep file (CONTRACT §3b)
-------------------------
::

    base = "scene.toml"        # relative to this file; or an inline [scene] table
    mode = "product"           # product | zip
    [axes]
    "friction.mu" = [0.05, 0.1]
    tau_ratio = [0.5, 1.0, 2.0]
    [dask]                     # optional (extension)
    scheduler = "tcp://10.0.0.5:8786"   # or "synchronous"; absent or "": a LocalCluster
    n_workers = 4
    threads_per_worker = 1
    retries = 0

An unquoted dotted key (``friction.mu = [...]``) is a nested table in TOML; both spellings
are read as the axis ``"friction.mu"``.

Command line: ``contactpipe sweep SWEEP.toml -o DIR/ [--scheduler ADDRESS] [--workers N]
[--no-progress]`` prints a summary; exit status 1 when a member failed (they are listed),
2 for a bad sweep file, 0 otherwise.
"""
from __future__ import annotations

import contextlib
import dataclasses
import itertools
import json
import math
import numbers
import os
import pathlib
import sys
import time as _time
from typing import Callable

from .._version import __version__
from ..exceptions import ArchiveError, ContactpipeError, SceneError, one_line as _one_line
from ..files import (LockedError, TEMP_SUFFIX, exclusive_lock,
                     utc_now as _now, write_json as _write_json)
from .config import MODES, SweepFile, load_sweep_file, read_sweep_file


__all__ = ["sweep", "open_sweep", "SweepResult", "Member", "SweepLockedError",
           "register_parameter", "derived_parameters", "relaxation_time", "with_window",
           "load_sweep_file", "read_sweep_file", "SweepFile", "read_manifest",
           "add_arguments", "main", "MANIFEST", "LOCK", "MODES", "SYNCHRONOUS"]

MANIFEST = "manifest.json"
LOCK = ".sweep.lock"
SYNCHRONOUS = "synchronous"
MANIFEST_FORMAT = 1
_MAX_PROBLEMS = 25


class SweepLockedError(LockedError):
    """Another sweep (or pipeline) holds the lock of this output folder."""


# ------------------------------------------------------------------- derived parameters

_PARAMETERS: dict[str, Callable] = {}


def register_parameter(name: str):
    """Register a derived sweep parameter under ``name`` (a decorator).

    The function is called as ``func(scene, value)`` and returns a new validated
    :class:`~contactpipe.Scene` (typically ``scene.replace({...})``). Raise
    :class:`~contactpipe.SceneError` (or ``ValueError``) for a value it cannot take; the
    sweep reports it with the axis and value.

    >>> from contactpipe.pipeline.sweep import register_parameter
    >>> @register_parameter("load_scale")
    ... def load_scale(scene, value):
    ...     return scene.replace({"load.normal_force": value * scene.load.normal_force})
    >>> cp.sweep(base, {"load_scale": [0.5, 1, 2]}, "runs/")

    Names are global to the process that builds the sweep (the members' scenes are built
    there; workers only receive finished scenes).
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise SceneError(f"a derived parameter name must be an identifier (no dots: "
                         f"dotted names are scene paths), got {name!r}")

    def decorate(func):
        if not callable(func):
            raise TypeError(f"register_parameter({name!r}) decorates a function "
                            f"(scene, value) -> Scene, got {func!r}")
        _PARAMETERS[name] = func
        return func
    return decorate


def derived_parameters() -> dict[str, Callable]:
    """The registered derived parameters, name -> function (a copy)."""
    return dict(_PARAMETERS)


def relaxation_time(scene) -> tuple[str, float]:
    """(dotted key, value [s]) of the time ``tau_ratio`` refers to.

    The first viscoelastic body (indenter, then half-space) with one: Maxwell
    ``relaxation_time``, a Prony body's ``relaxation_time`` (its dashpot), Zener or
    Kelvin-Voigt ``retardation_time``.

    Raises
    ------
    SceneError
        No body has such a time (elastic or rigid bodies, tabulated creep, Prony without
        a dashpot).
    """
    seen = []
    for key in ("indenter", "halfspace"):
        body = getattr(scene, key)
        if body.material != "viscoelastic":
            seen.append(f"{key} is {body.material}")
            continue
        if body.creep in ("maxwell", "prony") and body.relaxation_time is not None:
            return f"{key}.relaxation_time", float(body.relaxation_time)
        if body.creep in ("zener", "kelvin_voigt") and body.retardation_time is not None:
            return f"{key}.retardation_time", float(body.retardation_time)
        seen.append(f"{key} is viscoelastic ({body.creep}) without a relaxation or "
                    f"retardation time")
    raise SceneError(f"no body has a relaxation or retardation time ({'; '.join(seen)}): "
                     f"tau_ratio needs a Maxwell, Zener or Kelvin-Voigt body or a Prony "
                     f"body with relaxation_time")


def with_window(scene, window: float):
    """The scene with its load program stretched to last ``window`` [s].

    ``load.fretting.window`` is set for a fretting preset; otherwise every knot of
    ``load.time`` moves proportionally away from ``time[0]``, which stays put.
    """
    window = float(window)
    if not math.isfinite(window) or window <= 0:
        raise SceneError(f"the load window must be a finite number > 0 [s], got {window:g}")
    load = scene.load
    if load.fretting is not None:
        return scene.replace({"load.fretting.window": window})
    t = [float(x) for x in load.time]
    old = t[-1] - t[0]
    if old <= 0:
        raise SceneError(f"load.time = {t} has a single knot: there is no window to "
                         f"stretch; give at least two knots")
    new = [t[0] + (x - t[0]) * (window / old) for x in t]
    new[-1] = t[0] + window
    return scene.replace({"load.time": new})


@register_parameter("tau_ratio")
def tau_ratio(scene, value):
    """Load window tau = ``value`` x the relaxation time (:func:`relaxation_time`)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(float(value)) or float(value) <= 0:
        raise SceneError(f"tau_ratio must be a finite number > 0, got {value!r}")
    _, t_rel = relaxation_time(scene)
    return with_window(scene, float(value) * t_rel)


# ------------------------------------------------------------------- members

@dataclasses.dataclass
class Member:
    """One member of a sweep: its axis values, scene digest, file and outcome."""

    index: int
    values: dict
    digest: str
    file: str
    status: str = "pending"            # pending | done | failed
    error: str | None = None
    wall_time_s: float | None = None
    cpu_time_s: float | None = None
    scene: object = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def label(self) -> str:
        """``tau_ratio=0.5, friction.mu=0.1``."""
        return _label(self.values)

    def to_json(self) -> dict:
        return {"index": self.index, "values": {k: _jsonable(v) for k, v in self.values.items()},
                "digest": self.digest, "file": self.file, "status": self.status,
                "error": self.error, "wall_time_s": self.wall_time_s,
                "cpu_time_s": self.cpu_time_s}

    def __str__(self) -> str:
        text = f"{self.label} ({self.file})"
        return f"{text}: {self.error}" if self.error else text


@dataclasses.dataclass
class SweepResult:
    """What :func:`sweep` did.

    Attributes
    ----------
    out_dir : pathlib.Path
    manifest : dict
        The manifest as written to ``out_dir/manifest.json``.
    members : list of Member
        Every member, in sweep order.
    computed, skipped, failed : list of Member
        Members computed by this run, skipped (a valid archive was there) and failed
        (``error`` holds the one-line reason). Members sharing a scene appear once per
        member.
    wall_time_s : float
    """

    out_dir: pathlib.Path
    manifest: dict
    members: list
    computed: list
    skipped: list
    failed: list
    wall_time_s: float = 0.0

    @property
    def ok(self) -> bool:
        """True when no member failed."""
        return not self.failed

    def summary(self) -> str:
        """One line: ``N members: C computed, S skipped, F failed (T s)``."""
        return (f"{len(self.members)} members: {len(self.computed)} computed, "
                f"{len(self.skipped)} skipped, {len(self.failed)} failed "
                f"({self.wall_time_s:.1f} s)")

    def __repr__(self) -> str:
        return f"<SweepResult {self.out_dir}: {self.summary()}>"


def _jsonable(v):
    """Axis values as plain JSON types (numpy scalars and arrays, tuples -> lists)."""
    if isinstance(v, (str, bool)) or v is None:
        return v
    if isinstance(v, numbers.Integral):
        return int(v)
    if isinstance(v, numbers.Real):
        return float(v)
    if hasattr(v, "tolist"):
        return _jsonable(v.tolist())
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    return str(v)


def _show(v) -> str:
    v = _jsonable(v)
    if isinstance(v, float):
        return f"{v:g}"
    return json.dumps(v) if not isinstance(v, str) else repr(v)


def _label(values: dict) -> str:
    return ", ".join(f"{k}={_show(v)}" for k, v in values.items())


def _coord_value(v):
    """An axis value as a coordinate label (lists become their JSON text)."""
    v = _jsonable(v)
    if isinstance(v, (list, dict)):
        return json.dumps(v)
    return v


_RESERVED = None


def _reserved() -> set:
    global _RESERVED
    if _RESERVED is None:
        from ..nomenclature import COORDINATES, VARIABLES
        _RESERVED = {"time", "t_norm", "x1", "x2", "member", "digest"} | set(VARIABLES) \
            | set(COORDINATES)
    return _RESERVED


def _dim_names(names) -> dict:
    """Axis -> dimension name: the last part of a dotted path (``friction.mu`` -> ``mu``)
    unless two axes share it or it is taken (``time``, a variable name): then the path
    with underscores (``halfspace_young``)."""
    reserved = _reserved()
    last = {n: n.rsplit(".", 1)[-1] for n in names}
    out = {}
    for n in names:
        d = last[n]
        if list(last.values()).count(d) > 1 or d in reserved:
            d = n.replace(".", "_")
        while d in reserved or d in out.values():
            d += "_axis"
        out[n] = d
    return out


def _parse_axes(axes) -> tuple[list, dict, dict]:
    """names, {name: [values]}, {name: func or None}; SceneError listing every problem."""
    if not isinstance(axes, dict) or not axes:
        raise SceneError(f"axes must be a non-empty dict {{name: [values]}}, got {axes!r}")
    problems, values, funcs = [], {}, {}
    for name, spec in axes.items():
        if not isinstance(name, str) or not name or "" in name.split("."):
            problems.append(f"axis {name!r}: an axis name is a dotted scene path such as "
                            f"'friction.mu' or a derived parameter "
                            f"({', '.join(sorted(_PARAMETERS))})")
            continue
        func = _PARAMETERS.get(name)
        if isinstance(spec, tuple) and len(spec) == 2 and callable(spec[1]):
            spec, func = spec
        if hasattr(spec, "tolist") and not isinstance(spec, (str, bytes)):
            spec = spec.tolist()
        if isinstance(spec, (str, bytes, dict)) or not hasattr(spec, "__iter__"):
            problems.append(f"axis {name}: values must be a non-empty list, got "
                            f"{_show(spec) if not callable(spec) else repr(spec)}")
            continue
        vals = list(spec)
        if not vals:
            problems.append(f"axis {name}: values must be a non-empty list, got []")
            continue
        if "." not in name and func is None:
            problems.append(f"axis {name!r} is neither a dotted scene path (such as "
                            f"'friction.mu') nor a derived parameter (registered: "
                            f"{', '.join(sorted(_PARAMETERS))}); register it with "
                            f"@register_parameter({name!r}) or give (values, func)")
            continue
        values[name], funcs[name] = vals, func
    if problems:
        raise SceneError(problems)
    return list(values), values, funcs


def _build_members(base, axes, mode):
    """Every member scene, validated; SceneError naming axis and value on any problem."""
    from ..scene import Scene
    if mode not in MODES:
        raise SceneError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    names, values, funcs = _parse_axes(axes)
    if mode == "zip":
        lengths = {n: len(values[n]) for n in names}
        if len(set(lengths.values())) > 1:
            raise SceneError("mode = 'zip' needs axes of equal lengths, got "
                             + ", ".join(f"{n}: {k}" for n, k in lengths.items()))
        combos = list(zip(*(values[n] for n in names)))
    else:
        problems = []
        for n in names:
            labels = [json.dumps(_coord_value(v)) for v in values[n]]
            dup = sorted({v for v in labels if labels.count(v) > 1})
            if dup:
                problems.append(f"axis {n}: values must be distinct in mode 'product', "
                                f"got {', '.join(dup)} more than once")
        if problems:
            raise SceneError(problems)
        combos = list(itertools.product(*(values[n] for n in names)))
    dotted = [n for n in names if funcs[n] is None]
    derived = [n for n in names if funcs[n] is not None]
    problems, members = [], []
    for i, combo in enumerate(combos):
        vals = dict(zip(names, combo))
        scene = base
        try:
            if dotted:
                scene = base.replace({n: _jsonable(vals[n]) for n in dotted})
        except SceneError as err:
            for p in err.problems:
                named = [n for n in dotted if n in p] or dotted
                problems.append(f"axis {_label({n: vals[n] for n in named})}: {p}")
            continue
        except (TypeError, ValueError) as err:
            problems.append(f"axis {_label({n: vals[n] for n in dotted})}: {err}")
            continue
        bad = False
        for n in derived:
            try:
                new = funcs[n](scene, vals[n])
            except SceneError as err:
                problems.extend(f"axis {n}={_show(vals[n])}: {p}" for p in err.problems)
                bad = True
                break
            except Exception as err:           # noqa: BLE001 - a user's function
                problems.append(f"axis {n}={_show(vals[n])}: {type(err).__name__}: {err}")
                bad = True
                break
            if not isinstance(new, Scene):
                problems.append(f"axis {n}={_show(vals[n])}: the derived parameter "
                                f"returned {type(new).__name__}, not a Scene")
                bad = True
                break
            scene = new
        if bad:
            continue
        digest = scene.digest()
        members.append(Member(index=i, values=vals, digest=digest, file=f"{digest}.nc",
                              scene=scene))
    if problems:
        seen, unique = set(), []
        for p in problems:
            if p not in seen:
                seen.add(p)
                unique.append(p)
        if len(unique) > _MAX_PROBLEMS:
            unique = unique[:_MAX_PROBLEMS] + [f"... and {len(unique) - _MAX_PROBLEMS} more"]
        raise SceneError(unique)
    return names, values, funcs, members


# ------------------------------------------------------------------- files

def _clean_temporaries(out_dir: pathlib.Path, members) -> list:
    """Remove what a killed run left: ``.<digest>.nc.*.part`` and manifest temps.

    Only called under the folder's lock, so no live writer of ours owns them.
    """
    removed = []
    patterns = {f".{m.file}.*{TEMP_SUFFIX}*" for m in members} | {f".{MANIFEST}.*{TEMP_SUFFIX}*"}
    for pattern in sorted(patterns):
        for p in out_dir.glob(pattern):
            with contextlib.suppress(OSError):
                p.unlink()
                removed.append(p.name)
    return removed


def _archive_state(path: pathlib.Path):
    """('valid', wall time) | ('missing', None) | ('corrupt', reason)."""
    from ..archive import is_complete, open_archive
    if not path.exists():
        return "missing", None
    if is_complete(path):
        try:
            ds = open_archive(path)
        except ArchiveError as err:
            return "corrupt", str(err)
        try:
            wall = ds.attrs.get("wall_time_s")
            wall = float(wall) if wall is not None else None
        except (TypeError, ValueError):
            wall = None
        finally:
            ds.close()
        return "valid", wall
    try:
        open_archive(path).close()
    except ArchiveError as err:
        return "corrupt", str(err)
    except Exception as err:                    # noqa: BLE001
        return "corrupt", f"{type(err).__name__}: {err}"
    return "corrupt", f"{path}: is_complete() is false"


def read_manifest(out_dir) -> dict:
    """The manifest of a sweep folder; ArchiveError when missing or unreadable."""
    out_dir = pathlib.Path(out_dir)
    path = out_dir / MANIFEST
    if not path.exists():
        raise ArchiveError(f"{out_dir}: not a sweep folder (no {MANIFEST}); run the sweep "
                           f"first")
    try:
        with open(path, encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError) as err:
        raise ArchiveError(f"{path}: unreadable sweep manifest ({type(err).__name__}: "
                           f"{err})") from None
    missing = [k for k in ("axes", "mode", "dims", "members") if k not in manifest]
    if missing:
        raise ArchiveError(f"{path}: not a contactpipe sweep manifest (missing "
                           f"{', '.join(missing)})")
    return manifest


# ------------------------------------------------------------------- running

def _run_member(scene, path: str, digest: str, retries: int = 0) -> dict:
    """One dask task: simulate ``scene`` into ``path``; never raises.

    Failures of the scene itself (ContactpipeError: no convergence, contact off the grid,
    ...) are final; other errors (disk, memory) are tried again ``retries`` times.
    """
    from ..simulation import simulate
    t0, c0 = _time.perf_counter(), _time.process_time()
    attempt = 0
    while True:
        attempt += 1
        try:
            ds = simulate(scene, path, progress=False)
            ds.close()
            status, error = "done", None
        except Exception as err:                # noqa: BLE001 - reported, not raised
            if not isinstance(err, ContactpipeError) and attempt <= retries:
                continue
            status, error = "failed", _one_line(err)
        return {"digest": digest, "status": status, "error": error, "attempts": attempt,
                "wall_time_s": _time.perf_counter() - t0,
                "cpu_time_s": _time.process_time() - c0}


def _cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


@contextlib.contextmanager
def _dask_client(client, scheduler, n_workers, threads_per_worker, n_jobs):
    """The client to submit to: the caller's, one on ``scheduler``, or a LocalCluster."""
    if client is not None:
        yield client
        return
    import distributed
    if scheduler:
        try:
            c = distributed.Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as err:
            raise ContactpipeError(f"cannot connect to the dask scheduler at {scheduler!r}: "
                                   f"{_one_line(err)}") from None
        try:
            yield c
        finally:
            c.close()
        return
    n = int(n_workers) if n_workers else max(1, min(n_jobs, _cpu_count()))
    cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=int(threads_per_worker),
                                       processes=True, dashboard_address=None)
    try:
        c = distributed.Client(cluster)
        try:
            yield c
        finally:
            c.close()
    finally:
        cluster.close()


def _execute(jobs, *, client, scheduler, n_workers, threads_per_worker, progress, retries,
             on_done):
    """Run ``jobs`` [(digest, scene, path)], calling ``on_done(result dict)`` as each ends."""
    if not jobs:
        return
    from tqdm.auto import tqdm
    bar = tqdm(total=len(jobs), desc="sweep", unit="member", disable=not progress)
    try:
        if client is None and scheduler == SYNCHRONOUS:
            for digest, scene, path in jobs:
                on_done(_run_member(scene, path, digest, retries))
                bar.update(1)
            return
        import distributed
        with _dask_client(client, scheduler, n_workers, threads_per_worker, len(jobs)) as c:
            futures = {}
            for digest, scene, path in jobs:
                fut = c.submit(_run_member, scene, path, digest, retries, pure=False,
                               key=f"simulate-{digest}-{os.urandom(4).hex()}")
                futures[fut] = digest
            try:
                for fut in distributed.as_completed(list(futures)):
                    try:
                        res = fut.result()
                    except Exception as err:    # noqa: BLE001 - e.g. KilledWorker
                        res = {"digest": futures[fut], "status": "failed",
                               "error": _one_line(err), "wall_time_s": None}
                    on_done(res)
                    bar.update(1)
                    fut.release()
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
    finally:
        bar.close()


def sweep(base, axes: dict, out_dir, *, mode="product", client=None, scheduler=None,
          n_workers=None, threads_per_worker=1, progress=True, retries=0) -> SweepResult:
    """Run one simulation per member of a parameter sweep, on dask, resumably.

    Parameters
    ----------
    base : Scene or path-like
        The scene every member starts from (a scene TOML file is read).
    axes : dict
        ``{name: values}``: a dotted scene path (``"friction.mu"``) or a derived
        parameter (``"tau_ratio"``, or one registered with :func:`register_parameter`);
        a value may also be ``(values, func)`` with ``func(scene, value) -> Scene``.
    out_dir : path-like
        Folder of the member archives (``<digest>.nc``) and ``manifest.json``; created.
    mode : {"product", "zip"}
        Every combination, or the i-th value of each axis together (equal lengths).
    client : distributed.Client, optional
        Submit to it (left open).
    scheduler : str, optional
        Address of a running dask scheduler, or ``"synchronous"`` to run in this
        process. Ignored when ``client`` is given.
    n_workers : int, optional
        Workers of the LocalCluster started when neither is given (default:
        ``min(members to compute, CPU count)``).
    threads_per_worker : int
        Threads per LocalCluster worker process.
    progress : bool
        Show a progress bar over the members.
    retries : int
        Extra attempts for a member that failed for a reason other than its scene
        (disk, memory); solver failures (ConvergenceError, GridError) are final.

    Returns
    -------
    SweepResult
        ``.ok``, ``.computed``, ``.skipped``, ``.failed`` (members with ``.error``),
        ``.manifest``.

    Raises
    ------
    SceneError
        A bad axis, mode or member scene: every problem, naming the axis and value,
        before any work starts.
    SweepLockedError
        Another sweep is running on ``out_dir``.
    """
    from ..scene import Scene
    t0 = _time.perf_counter()
    if not isinstance(base, Scene):
        base = Scene.from_toml(base)
    retries = int(retries or 0)
    names, values, funcs, members = _build_members(base, axes, mode)
    dims = _dim_names(names)
    out_dir = pathlib.Path(out_dir).expanduser().resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    with exclusive_lock(out_dir / LOCK, "sweep", error=SweepLockedError):
        _clean_temporaries(out_dir, members)
        by_digest: dict[str, list] = {}
        for m in members:
            by_digest.setdefault(m.digest, []).append(m)
        previous, created = _previous_records(out_dir)
        jobs, skipped = [], []
        for digest, group in by_digest.items():
            path = out_dir / group[0].file
            state, info = _archive_state(path)
            if state == "valid":
                prev = previous.get(digest, {})
                for m in group:
                    m.status = "done"
                    m.wall_time_s = prev.get("wall_time_s", info)
                    m.cpu_time_s = prev.get("cpu_time_s")
                skipped.extend(group)
                continue
            if state == "corrupt":
                path.unlink(missing_ok=True)
            jobs.append((digest, group[0].scene, str(path)))
        manifest = {
            "format": MANIFEST_FORMAT,
            "contactpipe_version": __version__,
            "created": created or _now(),
            "updated": _now(),
            "mode": mode,
            "axes": {n: [_jsonable(v) for v in values[n]] for n in names},
            "derived": {n: _func_name(funcs[n]) for n in names if funcs[n] is not None},
            "dims": dims,
            "base_scene": base.to_toml(),
            "base_name": base.name,
            "members": [m.to_json() for m in members],
        }
        _write_json(out_dir / MANIFEST, manifest)
        computed, failed = [], []

        def on_done(res):
            group = by_digest[res["digest"]]
            for m in group:
                m.status = res["status"]
                m.error = res.get("error")
                m.wall_time_s = res.get("wall_time_s")
                m.cpu_time_s = res.get("cpu_time_s")
            (computed if res["status"] == "done" else failed).extend(group)
            manifest["updated"] = _now()
            manifest["members"] = [m.to_json() for m in members]
            _write_json(out_dir / MANIFEST, manifest)

        _execute(jobs, client=client, scheduler=scheduler, n_workers=n_workers,
                 threads_per_worker=threads_per_worker, progress=progress, retries=retries,
                 on_done=on_done)
    order = {id(m): m.index for m in members}
    for lst in (computed, failed, skipped):
        lst.sort(key=lambda m: order[id(m)])
    return SweepResult(out_dir=out_dir, manifest=manifest, members=members,
                       computed=computed, skipped=skipped, failed=failed,
                       wall_time_s=_time.perf_counter() - t0)


def _previous_records(out_dir: pathlib.Path) -> tuple[dict, str | None]:
    """({digest: {wall_time_s, cpu_time_s}} of done members, creation time) of an
    earlier manifest, so that skipped members keep their timings."""
    try:
        manifest = read_manifest(out_dir)
    except ArchiveError:
        return {}, None
    out = {}
    for m in manifest.get("members", []):
        if isinstance(m, dict) and m.get("status") == "done":
            out[m.get("digest")] = {k: m[k] for k in ("wall_time_s", "cpu_time_s")
                                    if m.get(k) is not None}
    return out, manifest.get("created")


def _func_name(func) -> str:
    return f"{getattr(func, '__module__', '?')}.{getattr(func, '__qualname__', repr(func))}"


# ------------------------------------------------------------------- reading back

def open_sweep(out_dir, *, allow_missing=False, chunks=None):
    """Open a sweep folder as one lazy Dataset with one dimension per axis.

    Parameters
    ----------
    out_dir : path-like
        A folder written by :func:`sweep` (its ``manifest.json``).
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
        ``friction.mu`` -> ``mu``), coordinates = the axis values. Mode "zip": one
        dimension ``member`` with every axis as a coordinate along it. A coordinate
        ``digest`` names each member's archive. Where the members' time coordinates
        differ (a ``tau_ratio`` sweep), the time dimension is ``t_norm`` = (t - t0)/tau
        (tau the member's load window) and ``time`` is a coordinate varying along the
        axes; otherwise ``time`` stays the dimension. Likewise, where the members' grids
        differ (an automatic grid size that depends on the swept window), ``x1`` and ``x2``
        stay dimensions (cell positions) and each member's cell centres are the coordinates
        ``x1_cell``, ``x2_cell`` varying along the axes. Attributes ``sweep_axes``,
        ``sweep_dims`` (JSON), ``sweep_mode``, ``base_scene`` (TOML).

    Raises
    ------
    ArchiveError
        No manifest; a member marked done whose archive is missing or corrupt (the
        message names the member and file); members not done (unless
        ``allow_missing``).
    """
    import numpy as np
    import xarray as xr
    from ..archive import open_archive
    from ..nomenclature import cf_attrs

    out_dir = pathlib.Path(out_dir)
    manifest = read_manifest(out_dir)
    mode = manifest["mode"]
    names = list(manifest["axes"])
    dims = {n: manifest["dims"][n] for n in names}
    members = manifest["members"]
    done = [m for m in members if m.get("status") == "done"]
    not_done = [m for m in members if m.get("status") != "done"]
    if not_done and not allow_missing:
        listed = "; ".join(f"{_label(m['values'])} ({m.get('status')}"
                           + (f": {m['error']}" if m.get("error") else "") + ")"
                           for m in not_done[:10])
        more = f"; ... and {len(not_done) - 10} more" if len(not_done) > 10 else ""
        raise ArchiveError(f"{out_dir}: {len(not_done)} of {len(members)} sweep members "
                           f"are not done: {listed}{more}. Re-run the sweep, or pass "
                           f"allow_missing=True to drop them")
    if not done:
        raise ArchiveError(f"{out_dir}: no sweep member is done; run the sweep first")
    opened: dict[str, xr.Dataset] = {}
    datasets = []
    try:
        for m in done:
            if m["digest"] not in opened:
                try:
                    opened[m["digest"]] = open_archive(out_dir / m["file"], chunks=chunks)
                except ArchiveError as err:
                    raise ArchiveError(f"sweep member {_label(m['values'])} "
                                       f"({m['file']}): {err}") from None
            datasets.append(opened[m["digest"]])
        times = [ds["time"].values for ds in datasets]
        same_time = all(t.shape == times[0].shape and np.array_equal(t, times[0])
                        for t in times)
        grids = [(ds["x1"].values, ds["x2"].values) for ds in datasets]
        same_grid = all(np.array_equal(g[0], grids[0][0]) and np.array_equal(g[1], grids[0][1])
                        for g in grids)
        if not same_grid and len({(g[0].size, g[1].size) for g in grids}) > 1:
            raise ArchiveError(
                f"{out_dir}: the members have grids of different sizes "
                f"({sorted({(g[0].size, g[1].size) for g in grids})}); they cannot share "
                "the x1, x2 dimensions — open them one by one with open_archive")
        prepared = []
        for m, ds in zip(done, datasets):
            ds = ds.copy()
            ds.attrs = {}
            if not same_grid:
                # each member keeps its own cell centres (e.g. an automatic grid that grows
                # with the window): x1, x2 stay dimensions (cell positions), x1_cell, x2_cell
                # are coordinates varying along the axes
                ds = ds.rename_vars({"x1": "x1_cell", "x2": "x2_cell"})
            if not same_time:
                t = ds["time"].values
                span = t[-1] - t[0] if t.size > 1 else 1.0
                tn = np.round((t - t[0]) / (span if span > 0 else 1.0), 12)
                ds = ds.assign_coords(t_norm=("time", tn)).swap_dims(time="t_norm")
                ds["t_norm"].attrs.update(cf_attrs("t_norm"))
            prepared.append((m, ds))
        attrs = dict(datasets[0].attrs)
        if mode == "zip":
            parts = []
            for m, ds in prepared:
                ds = ds.expand_dims(member=[m["index"]])
                coords = {dims[n]: ("member", [_coord_value(m["values"][n])]) for n in names}
                coords["digest"] = ("member", [m["digest"]])
                parts.append(ds.assign_coords(coords))
            sw = xr.concat(parts, "member", data_vars="all", coords="different",
                           compat="equals", join="outer", combine_attrs="drop")
        else:
            sw = _combine_product(prepared, names, dims, manifest, xr)
        for n in names:
            sw[dims[n]].attrs.update({"long_name": f"sweep axis {n}", "sweep_axis": n})
    except BaseException:
        for ds in opened.values():
            ds.close()
        raise
    keep = {k: attrs[k] for k in ("Conventions", "contactpipe_version") if k in attrs}
    models = {d.attrs.get("models") for d in opened.values()}
    if len(models) == 1:
        keep["models"] = models.pop()
    keep.update({
        "title": f"contactpipe sweep: {manifest.get('base_name', '')}".strip(),
        "sweep_mode": mode,
        "sweep_axes": json.dumps(manifest["axes"]),
        "sweep_dims": json.dumps(dims),
        "sweep_time_dim": "time" if same_time else "t_norm",
        "sweep_grid": "shared" if same_grid else "per member (coordinates x1_cell, x2_cell)",
        "base_scene": manifest.get("base_scene", ""),
        "sweep_members": len(members),
    })
    if not_done:
        keep["missing_members"] = json.dumps(
            [{"values": m["values"], "digest": m["digest"], "status": m.get("status"),
              "error": m.get("error")} for m in not_done])
        keep["note"] = (f"{len(not_done)} of {len(members)} members not done were dropped "
                        f"(see missing_members)")
    sw.attrs = keep
    files = list(opened.values())
    sw.set_close(lambda: [ds.close() for ds in files])
    return sw


def _combine_product(prepared, names, dims, manifest, xr):
    """One dimension per axis; combine_nested when complete, unstack when holes."""
    axis_values = {n: [_coord_value(v) for v in manifest["axes"][n]] for n in names}
    shape = [len(axis_values[n]) for n in names]
    cells = {}
    for m, ds in prepared:
        key = tuple(axis_values[n].index(_coord_value(m["values"][n])) for n in names)
        ds = ds.expand_dims({dims[n]: [_coord_value(m["values"][n])] for n in names})
        cells[key] = ds.assign_coords(digest=([dims[n] for n in names],
                                              _nested([m["digest"]], len(names))))
    kw = dict(data_vars="all", coords="different", compat="equals", join="outer",
              combine_attrs="drop")
    if len(cells) == math.prod(shape):
        nested = _grid(cells, shape, ())
        return xr.combine_nested(nested, concat_dim=[dims[n] for n in names], **kw)
    # holes (allow_missing): stack along "member", then unstack (NaN where missing)
    parts = []
    for i, (key, ds) in enumerate(sorted(cells.items())):
        parts.append(ds.stack(member=[dims[n] for n in names]))
    sw = xr.concat(parts, "member", **kw)
    sw = sw.unstack("member")
    order = [dims[n] for n in names]
    sw = sw.transpose(*order, ...)
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


# ------------------------------------------------------------------- command line

def add_arguments(parser) -> None:
    parser.add_argument("sweep_file", type=pathlib.Path, metavar="SWEEP.toml",
                        help="sweep file (CONTRACT §3b)")
    parser.add_argument("-o", "--out-dir", type=pathlib.Path, required=True, metavar="DIR",
                        help="folder of the member archives and manifest.json")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="dask scheduler address (tcp://host:8786) or 'synchronous'; "
                             "default: the file's [dask] scheduler, else a LocalCluster")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="LocalCluster worker processes (default: [dask] n_workers, "
                             "else min(members, CPUs))")
    parser.add_argument("--retries", type=int, default=None, metavar="N",
                        help="extra attempts for members failing for reasons other than "
                             "their scene")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args) -> int:
    sf = read_sweep_file(args.sweep_file)
    res = sweep(sf.base, sf.axes, args.out_dir, mode=sf.mode,
                scheduler=args.scheduler or sf.scheduler,
                n_workers=args.workers or sf.n_workers,
                threads_per_worker=sf.threads_per_worker,
                retries=sf.retries if args.retries is None else args.retries,
                progress=not args.no_progress)
    print(f"sweep {res.out_dir}: {res.summary()}")
    if res.failed:
        for m in res.failed:
            print(f"  failed: {m}", file=sys.stderr)
        print(f"contactpipe: error: {len(res.failed)} of {len(res.members)} sweep members "
              f"failed", file=sys.stderr)
        return 1
    return 0
