"""Parameter sweeps on dask: many scenes, one archive each, one labelled Dataset back.

    >>> import contactpipe as cp
    >>> base = cp.Scene.from_toml("fretting.toml")
    >>> res = cp.sweep(base, {"tau_ratio": [0.5, 1, 2], "friction.mu": [0.05, 0.1]},
    ...                out_dir="runs/")          # a LocalCluster unless told otherwise
    >>> res.ok, len(res.computed), len(res.skipped)
    >>> sw = cp.open_sweep("runs/")              # dims (tau_ratio, mu, t_norm, x1, x2)

The stage is in several modules, this one the entry point (every public name of the
stage can be imported from here):

- :mod:`~contactpipe.pipeline.sweep.parameters`: derived parameters (``tau_ratio``,
  :func:`register_parameter`);
- :mod:`~contactpipe.pipeline.sweep.members`: axes parsed into members, each a validated scene;
- :mod:`~contactpipe.pipeline.sweep.manifest`: ``manifest.json``, written and validated;
- :mod:`~contactpipe.pipeline.sweep.execute`: where the members run and where their archives
  are written;
- :mod:`~contactpipe.pipeline.sweep.combine`: :func:`open_sweep`;
- this module: :func:`sweep` (resuming included) and the command line.

Axes
----
An axis name is either a dotted path into the scene (``"friction.mu"``,
``"load.normal_force"``, ``"halfspace.relaxation_time"``, ``"time.steps"``; see
:meth:`Scene.replace`) or a *derived parameter* registered by name: ``tau_ratio`` (the
load window as a multiple of the relaxation time), ``delta_amplitude`` and ``delta_ratio``
(the amplitude of a displacement-controlled tangential program, in metres or over the
gross-slip displacement); each is documented in :mod:`contactpipe.pipeline.sweep.parameters`.

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
    share it), written atomically.
``manifest.json``
    Axes, mode, dimension names, the base scene (TOML) and, per member, its axis values,
    digest, file, status (``done`` / ``failed`` with a one-line error / ``pending``) and
    wall time (:mod:`~contactpipe.pipeline.sweep.manifest`). Rewritten atomically as members
    finish; checked on every read, so a manifest edited by hand is refused with one line
    naming the key instead of a bare KeyError.
``.sweep.lock``
    Held (:func:`contactpipe._util.files.exclusive_lock`) while a sweep runs: a second sweep on
    the same folder stops at once with :class:`SweepLockedError`. The file stays; the
    lock dies with its process.

Resuming
--------
Re-running the same sweep is cheap and safe. For each member's file:

- a complete archive that opens and holds the member's own scene (its ``scene``
  attribute has the member's digest) is kept and the member skipped;
- a missing one is computed;
- a broken one (it fails to open as a contactpipe archive: truncated, corrupt,
  incomplete, not netCDF) is recomputed, and the new archive replaces it atomically when
  it is done (nothing is deleted before: if the recomputation fails, the broken file
  stays and the member is reported failed);
- a valid archive of *another* scene (files swapped or copied by hand) is set aside,
  renamed ``<digest>.nc.foreign-<its digest>``, never deleted, and the member recomputed;
  :attr:`SweepResult.set_aside` lists them.

Anything else stops the sweep with its own one-line error and touches nothing: a file
that cannot be read (permissions, I/O errors), or a member path that is not a regular
file. Temporary files that a killed run left behind (``.<digest>.nc.*.part``) are
removed. Failed members are tried again.

Where the work runs
-------------------
``client`` (a :class:`distributed.Client`) if given; else ``scheduler``: the address of a
running scheduler (``"tcp://host:8786"``) or ``"synchronous"`` (in this process, one
member after the other: debugging and tests); else a :class:`distributed.LocalCluster` of
``n_workers`` processes (default ``min(members to compute, CPU count)``) with
``threads_per_worker`` threads, started and closed by the sweep, and only when there is
something to compute. Its worker processes are spawned: each imports the calling script
again, so a script that lets the sweep start one needs the usual
``if __name__ == "__main__":`` guard. Without it, the sweep called again by a worker's
import ends that worker with one line saying so (:class:`ScriptReimportError`) and the
sweep fails to start its cluster with one line naming the guard.

The workers need not share the client's disk: with ``shared_disk=None`` (the default)
the workers of a LocalCluster (or of ``"synchronous"``) write the archives into
``out_dir`` themselves, and those of any other cluster simulate into a temporary folder
of their own and send the archive back, which the client checks and writes
(:mod:`~contactpipe.pipeline.sweep.execute`; ``shared_disk=True`` lets the workers of a shared
filesystem write in place and spares the transfer).

**A scheduler address is trusted code.** dask's protocol unpickles what the scheduler
sends, so connecting to a scheduler runs whatever code it hands back, in this process:
never point a sweep (argument, ``--scheduler`` or a sweep file's ``[dask] scheduler``)
at a scheduler you do not control.

Sweep file (docs/scene-file.md)
-------------------------------
::

    base = "scene.toml"        # relative to this file; or an inline [scene] table
    mode = "product"           # product | zip
    [axes]
    "friction.mu" = [0.05, 0.1]
    tau_ratio = [0.5, 1.0, 2.0]
    [dask]                     # optional (extension)
    scheduler = "tcp://10.0.0.5:8786"   # or "synchronous"; absent or "": a LocalCluster
    n_workers = 4                       # TRUSTED: see "A scheduler address is trusted
    threads_per_worker = 1              # code" above
    retries = 0

An unquoted dotted key (``friction.mu = [...]``) is a nested table in TOML; both spellings
are read as the axis ``"friction.mu"``.

Command line: ``contactpipe sweep SWEEP.toml -o DIR/ [--scheduler ADDRESS] [--workers N]
[--shared-disk | --no-shared-disk] [--no-progress]`` prints a summary; exit status 1 when
a member failed (they are listed), 2 for a bad sweep file or output folder, 0 otherwise.
"""
from __future__ import annotations

import argparse
import dataclasses
import multiprocessing
import os
import pathlib
import stat
import sys
import time

from ..._util.files import TEMP_SUFFIX, LockedError, check_output_dir, exclusive_lock, make_folder
from ...archive import open_archive
from ...exceptions import ArchiveError, SceneError, one_line
from ...scene import Scene
from ..inputs import scene_digest
from .combine import open_member, open_sweep
from .config import SweepFile, load_sweep_file, read_sweep_file
from .execute import SYNCHRONOUS, execute
from .manifest import MANIFEST, new_manifest, previous_records, read_manifest, write_manifest
from .members import MODES, Member, build_members, dim_names, label_of
from .parameters import (
    derived_parameters,
    register_parameter,
    relaxation_time,
    tau_ratio,
    with_window,
)

__all__ = ["sweep", "open_sweep", "open_member", "SweepResult", "Member",
           "SweepLockedError", "ScriptReimportError", "register_parameter", "derived_parameters",
           "relaxation_time", "with_window", "tau_ratio", "load_sweep_file",
           "read_sweep_file", "SweepFile", "read_manifest", "archive_state",
           "add_arguments", "main", "MANIFEST", "LOCK", "MODES", "SYNCHRONOUS"]

LOCK = ".sweep.lock"
#: What a member's file is found to be when a sweep resumes (:func:`archive_state`).
STATES = ("valid", "missing", "broken", "foreign")


class SweepLockedError(LockedError):
    """Another sweep (or pipeline) holds the lock of this output folder."""


class ScriptReimportError(SystemExit):
    """:func:`sweep` was called by a worker process while it imported the user's script
    again (a script without the ``if __name__ == "__main__":`` guard). It ends that
    process with one line (a :class:`SystemExit`, so no traceback): it must not sweep."""


#: The one line of :class:`ScriptReimportError`.
REIMPORT_MESSAGE = ("contactpipe: error: cp.sweep was called while a worker process "
                    "re-imported your script; put the call under "
                    "if __name__ == \"__main__\":")


def _refuse_in_reimport() -> None:
    """Raise :class:`ScriptReimportError` when called from the top level of a script that
    a spawned worker process is importing again (``multiprocessing`` runs it as
    ``__mp_main__``)."""
    if multiprocessing.current_process().name == "MainProcess":   # named before the import
        return
    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_code.co_name == "<module>" and \
                frame.f_globals.get("__name__") == "__mp_main__":
            raise ScriptReimportError(REIMPORT_MESSAGE)
        frame = frame.f_back


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
    set_aside : list of pathlib.Path
        Archives of another scene found under a member's name, renamed (module
        docstring, "Resuming").
    """

    out_dir: pathlib.Path
    manifest: dict
    members: list
    computed: list
    skipped: list
    failed: list
    wall_time_s: float = 0.0
    set_aside: list = dataclasses.field(default_factory=list)

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


# ------------------------------------------------------------------- resuming

def _clean_temporaries(out_dir: pathlib.Path, members) -> list:
    """Remove what a killed run left: ``.<digest>.nc.*.part`` and manifest temps.

    Only called under the folder's lock, so no live writer of ours owns them.
    """
    removed = []
    patterns = {f".{m.file}.*{TEMP_SUFFIX}*" for m in members} | {f".{MANIFEST}.*{TEMP_SUFFIX}*"}
    for pattern in sorted(patterns):
        for p in out_dir.glob(pattern):
            p.unlink(missing_ok=True)
            removed.append(p.name)
    return removed


def archive_state(path, digest: str) -> tuple[str, object]:
    """What a member's file is, to decide whether a resumed sweep recomputes it.

    Returns
    -------
    ("valid", wall time [s] or None)
        A complete archive of the member's own scene.
    ("missing", None)
    ("broken", reason)
        Not a readable contactpipe archive (:func:`~contactpipe.open_archive` refuses
        it: truncated, corrupt, incomplete, not netCDF, no valid scene): recompute it.
    ("foreign", its digest)
        A valid archive of another scene: set it aside and recompute.

    Raises
    ------
    ArchiveError
        The path is not a regular file (a folder, a device): not ours to replace.
    OSError
        The file cannot be read (permissions, I/O): nothing is decided about it.
    """
    path = pathlib.Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return "missing", None
    if not stat.S_ISREG(st.st_mode):
        raise ArchiveError(f"{path}: the archive of a sweep member is not a regular file "
                           f"(a folder, a device?); move it away and re-run the sweep")
    with open(path, "rb") as f:        # unreadable (permissions, I/O): raise, decide nothing
        f.read(8)
    try:
        ds = open_archive(path)
    except ArchiveError as err:
        return "broken", one_line(err, with_type=False)
    with ds:
        try:
            found = scene_digest(ds)
        except ArchiveError as err:
            return "broken", one_line(err, with_type=False)
        if found != digest:
            return "foreign", found
        wall = ds.attrs.get("wall_time_s")
    try:
        return "valid", float(wall) if wall is not None else None
    except (TypeError, ValueError):
        return "valid", None


def _set_aside(path: pathlib.Path, found: str) -> pathlib.Path:
    """Rename a foreign archive out of the member's way (never over another file)."""
    target = path.with_name(f"{path.name}.foreign-{found}")
    n = 1
    while target.exists():
        n += 1
        target = path.with_name(f"{path.name}.foreign-{found}-{n}")
    os.rename(path, target)
    return target


def _resume(out_dir, by_digest: dict, previous: dict) -> tuple[list, list, list]:
    """(jobs [(digest, scene, path)], skipped members, files set aside)."""
    jobs, skipped, set_aside = [], [], []
    for digest, group in by_digest.items():
        path = out_dir / group[0].file
        state, info = archive_state(path, digest)
        if state == "valid":
            prev = previous.get(digest, {})
            for m in group:
                m.status = "done"
                m.wall_time_s = prev.get("wall_time_s", info)
                m.cpu_time_s = prev.get("cpu_time_s")
            skipped.extend(group)
            continue
        if state == "foreign":
            set_aside.append(_set_aside(path, info))
        jobs.append((digest, group[0].scene, str(path)))
    return jobs, skipped, set_aside


# ------------------------------------------------------------------- the sweep

def _check_run_times(members):
    """Every member estimated to take longer than its ``solver.max_hours`` is refused
    before any work (:func:`contactpipe.planning.check_time`; the memory is the worker's,
    checked where it runs)."""
    # planning pulls the solver (and pyfftw) in: imported by the sweep that runs, not by
    # every reader of the sweep package (open_sweep, the figures)
    from ...planning import check_time, estimate_resources
    from ...planning.accuracy import resolve_accuracy
    problems = []
    for m in members:
        try:
            check_time(estimate_resources(resolve_accuracy(m.scene)[0]),
                       m.scene.solver.max_hours)
        except SceneError as err:
            problems.append(f"member {label_of(m.values)}: {err}")
    if problems:
        raise SceneError(problems)


def sweep(base, axes: dict, out_dir, *, mode="product", client=None, scheduler=None,
          n_workers=None, threads_per_worker=1, progress=True, retries=0,
          shared_disk=None) -> SweepResult:
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
        Refused before any work when it exists as something else than a folder.
    mode : {"product", "zip"}
        Every combination, or the i-th value of each axis together (equal lengths).
    client : distributed.Client, optional
        Submit to it (left open).
    scheduler : str, optional
        Address of a running dask scheduler, or ``"synchronous"`` to run in this
        process. Ignored when ``client`` is given. **Trusted code**: dask unpickles what
        the scheduler sends; never give the address of a scheduler you do not control.
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
    shared_disk : bool, optional
        Whether the workers write the archives into ``out_dir`` themselves (they see it
        at the same path) or send them back to this process, which writes them. Default:
        they write in place on this machine (``"synchronous"``, a LocalCluster), and
        send them back from any other cluster (module docstring).

    Returns
    -------
    SweepResult
        ``.ok``, ``.computed``, ``.skipped``, ``.failed`` (members with ``.error``),
        ``.set_aside``, ``.manifest``.

    Raises
    ------
    SceneError
        A bad axis, mode or member scene: every problem, naming the axis and value,
        before any work starts.
    OutputPathError
        ``out_dir`` exists and is not a folder (a file, a device), before any work.
    SweepLockedError
        Another sweep is running on ``out_dir``.
    ScriptReimportError
        Called while a worker process imports the calling script again (a script that
        starts a LocalCluster needs the ``if __name__ == "__main__":`` guard): that
        process ends with one line saying so.
    ContactpipeError
        The LocalCluster's workers failed to start (the message names the guard when
        the sweep was called from the top level of a script).
    """
    _refuse_in_reimport()
    t0 = time.perf_counter()
    out_dir = check_output_dir(out_dir, "sweep output folder", inputs=_paths(base))
    base = base if isinstance(base, Scene) else Scene.from_toml(base)
    names, values, funcs, members = build_members(base, axes, mode)
    _check_run_times(members)
    out_dir = out_dir.resolve()
    make_folder(out_dir)
    with exclusive_lock(out_dir / LOCK, "sweep", error=SweepLockedError):
        manifest, computed, failed, skipped, set_aside = _run_members(
            out_dir, members, (base, mode, names, values, funcs), client=client,
            scheduler=scheduler, n_workers=n_workers, threads_per_worker=threads_per_worker,
            progress=progress, retries=int(retries or 0), shared_disk=shared_disk)
    return SweepResult(out_dir=out_dir, manifest=manifest, members=members,
                       computed=computed, skipped=skipped, failed=failed,
                       wall_time_s=time.perf_counter() - t0, set_aside=set_aside)


def _run_members(out_dir, members, new_manifest_args, **execute_kw):
    """Under the folder's lock: clear what a killed sweep left, resume from the previous
    manifest, write the new one, and run the members still to do, recording each in the
    manifest as it ends. Returns (manifest, computed, failed, skipped, set_aside), each
    list in sweep order."""
    _clean_temporaries(out_dir, members)
    by_digest: dict[str, list] = {}
    for m in members:
        by_digest.setdefault(m.digest, []).append(m)
    previous, created = previous_records(out_dir)
    jobs, skipped, set_aside = _resume(out_dir, by_digest, previous)
    base, mode, names, values, funcs = new_manifest_args
    manifest = new_manifest(base, mode, names, values, funcs, dim_names(names),
                            members, created)
    write_manifest(out_dir, manifest)
    computed, failed = [], []

    def on_done(res):
        group = by_digest[res["digest"]]
        for m in group:
            m.status = res["status"]
            m.error = res.get("error")
            m.wall_time_s = res.get("wall_time_s")
            m.cpu_time_s = res.get("cpu_time_s")
        (computed if res["status"] == "done" else failed).extend(group)
        write_manifest(out_dir, manifest, members)

    execute(jobs, on_done=on_done, **execute_kw)
    order = {id(m): m.index for m in members}
    for lst in (computed, failed, skipped):
        lst.sort(key=lambda m: order[id(m)])
    return manifest, computed, failed, skipped, set_aside


def _paths(*objs) -> list:
    return [o for o in objs if isinstance(o, (str, os.PathLike))]


# ------------------------------------------------------------------- command line

DESCRIPTION = """\
Run every member of a sweep file (a base scene and the axes it varies) as a dask task and
write one archive per member, with manifest.json, into DIR. Resumable: run it again and
the members already done are kept. Exit status 0 when every member is done, 1 when one
failed (they are listed), 2 for a bad sweep file or output folder. The sweep file's keys
are in docs/scene-file.md; cp.open_sweep(DIR) reads the folder as one Dataset."""

EPILOG = """\
Examples:
  contactpipe sweep examples/sweep.toml -o runs/sweep
  contactpipe sweep examples/sweep.toml -o runs/sweep --workers 2 --no-progress
  contactpipe sweep sweep.toml -o runs/sweep --scheduler tcp://10.0.0.5:8786"""


def add_arguments(parser) -> None:
    parser.description = DESCRIPTION      # short help; the module docstring is for developers
    parser.epilog = EPILOG
    parser.add_argument("sweep_file", type=pathlib.Path, metavar="SWEEP.toml",
                        help="sweep file (keys: docs/scene-file.md)")
    # str, not pathlib.Path: Path("") is "." and an empty -o must be refused, not the cwd
    parser.add_argument("-o", "--out-dir", required=True, metavar="DIR",
                        help="folder of the member archives and manifest.json")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="dask scheduler address (tcp://host:8786) or 'synchronous'; "
                             "default: the file's [dask] scheduler, else a LocalCluster. "
                             "Trusted: dask unpickles what the scheduler sends")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="LocalCluster worker processes (default: [dask] n_workers, "
                             "else min(members, CPUs))")
    parser.add_argument("--retries", type=int, default=None, metavar="N",
                        help="extra attempts for members failing for reasons other than "
                             "their scene")
    parser.add_argument("--shared-disk", action=argparse.BooleanOptionalAction,
                        default=None,
                        help="the workers write the archives into DIR themselves (they "
                             "see it at the same path) or send them back; default: in "
                             "place on this machine, sent back from another cluster")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args) -> int:
    check_output_dir(args.out_dir, "sweep output folder", inputs=[args.sweep_file])
    sf = read_sweep_file(args.sweep_file)
    res = sweep(sf.base, sf.axes, args.out_dir, mode=sf.mode,
                scheduler=args.scheduler or sf.scheduler,
                n_workers=args.workers or sf.n_workers,
                threads_per_worker=sf.threads_per_worker,
                retries=sf.retries if args.retries is None else args.retries,
                progress=not args.no_progress, shared_disk=args.shared_disk)
    print(f"sweep {res.out_dir}: {res.summary()}")
    for p in res.set_aside:
        print(f"  note: {p.name} held another scene than its name says: set aside, "
              f"member recomputed", file=sys.stderr)
    if res.failed:
        for m in res.failed:
            print(f"  failed: {m}", file=sys.stderr)
        print(f"contactpipe: error: {len(res.failed)} of {len(res.members)} sweep members "
              f"failed", file=sys.stderr)
        return 1
    return 0
