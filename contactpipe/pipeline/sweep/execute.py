"""Running the members of a sweep: in this process, on a LocalCluster, or on any dask
cluster, with or without a disk the workers share with the client.

Where the work runs
-------------------
``client`` (a :class:`distributed.Client`) if given; else ``scheduler``: the address of a
running scheduler (``"tcp://host:8786"``) or ``"synchronous"`` (in this process, one
member after the other); else a :class:`distributed.LocalCluster` of ``n_workers``
processes, started and closed here.

Where the archives are written (``shared_disk``)
------------------------------------------------
``True``
    Each worker simulates straight into ``out_dir``: it must see that folder at the same
    path (the same machine, or a shared filesystem). Nothing travels but the outcome.
``False``
    Each worker simulates into a scratch folder of its own,
    ``contactpipe-member-<pid>-<host>-<token>`` in its dask local directory (``dask worker
    --local-directory``; outside a worker, dask's ``temporary-directory`` or the system's
    temporary folder), and sends the archive's bytes back; the scratch folders that
    killed workers left there are removed by the next member simulated there (and dask
    removes a dead worker's local directory when a new worker starts); the client checks them
    (a complete archive of the member's own scene: :func:`land_member`) and writes them atomically
    into ``out_dir``.
    Workers are never told ``out_dir``. Each archive then travels through the scheduler's
    network and is held in memory once on the worker and once on the client: for archives
    of several GB, prefer a shared disk.
``None`` (default)
    ``True`` when the workers run on this machine: ``"synchronous"``, the LocalCluster
    the sweep starts, or a ``client`` of a LocalCluster of this process; ``False`` for a
    scheduler address or any other client (its workers may be anywhere).

Security
--------
dask's protocol unpickles what the scheduler sends: connecting to a scheduler runs
whatever code it hands back, in this process. A scheduler address (argument, command line
option or sweep file ``[dask] scheduler``) is therefore trusted code; never point a sweep
at a scheduler you do not control.
"""
from __future__ import annotations

import concurrent.futures
import contextlib
import os
import pathlib
import shutil
import socket
import sys
import tempfile
import time

from ..._util.files import atomic_path
from ...archive import open_archive
from ...exceptions import ArchiveError, ContactpipeError, one_line
from ..inputs import scene_digest

__all__ = ["execute", "run_member", "land_member", "dask_client", "workers_share_disk",
           "scratch_root", "clean_scratch", "SYNCHRONOUS", "SCRATCH_PREFIX"]

SYNCHRONOUS = "synchronous"


def workers_share_disk(shared_disk, client, scheduler) -> bool:
    """Whether the workers write the archives into ``out_dir`` themselves (module
    docstring: ``shared_disk``)."""
    if shared_disk is not None:
        return bool(shared_disk)
    if client is None:
        return not scheduler or scheduler == SYNCHRONOUS
    # distributed is imported here, not at the top: a heavy import that only a cluster
    # run needs (a LocalCluster started in this process is on this machine)
    from distributed import LocalCluster
    return isinstance(getattr(client, "cluster", None), LocalCluster)


#: Prefix of the scratch folder of a member simulated away from ``out_dir``
#: (``contactpipe-member-<pid>-<host>-<token>``).
SCRATCH_PREFIX = "contactpipe-member-"


def _host() -> str:
    """This machine's name, as a file name can hold it."""
    return "".join(c if c.isalnum() else "_" for c in socket.gethostname()) or "host"


def scratch_root() -> pathlib.Path:
    """Where a worker simulates a member it sends back: its dask local directory (the
    ``--local-directory`` of ``dask worker``), else dask's ``temporary-directory``
    setting, else the system's temporary folder."""
    try:
        from distributed import get_worker
        return pathlib.Path(get_worker().local_directory)
    except (ImportError, ValueError):        # not in a dask worker
        pass
    import dask
    return pathlib.Path(dask.config.get("temporary-directory", None) or tempfile.gettempdir())


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:                          # another user's: alive
        return True
    return True


def clean_scratch(root) -> list:
    """Remove the scratch folders of this machine in ``root`` whose process is gone (a
    killed worker's partial archives); returns their names."""
    removed = []
    for d in pathlib.Path(root).glob(f"{SCRATCH_PREFIX}*"):
        pid, _, rest = d.name[len(SCRATCH_PREFIX):].partition("-")
        if d.is_dir() and pid.isdigit() and rest.startswith(f"{_host()}-") \
                and not _alive(int(pid)):
            shutil.rmtree(d, ignore_errors=True)
            removed.append(d.name)
    return removed


def simulate(scene, path, **options):
    """:func:`contactpipe.simulate` without opening the archive it writes (the member
    needs the file: opened lazily, it imported dask.array, 0.23 s, into each worker),
    imported at the first member: planning, resuming or reading a sweep (and
    ``contactpipe sweep --help``) need neither the simulation nor the FFTs."""
    from ...simulation import run_scene
    return run_scene(scene, path, **options)


def _simulate(scene, path) -> bytes | None:
    """Simulate ``scene`` into ``path``; with no path, into a scratch folder of this
    process under :func:`scratch_root` (those of killed processes removed first),
    returning the archive's bytes."""
    if path is not None:
        simulate(scene, path, progress=False)
        return None
    root = scratch_root()
    root.mkdir(parents=True, exist_ok=True)
    clean_scratch(root)
    with tempfile.TemporaryDirectory(prefix=f"{SCRATCH_PREFIX}{os.getpid()}-{_host()}-",
                                     dir=root) as tmp:
        target = pathlib.Path(tmp) / "member.nc"
        simulate(scene, target, progress=False)
        return target.read_bytes()


def run_member(scene, digest: str, path=None, retries: int = 0) -> dict:
    """One task: simulate a member's scene; returns its outcome, never raises.

    Parameters
    ----------
    scene : Scene
    digest : str
        The member's digest (echoed in the outcome).
    path : str, optional
        Write the archive there (the worker sees ``out_dir``); None: return its bytes
        under ``"archive"`` (:func:`land_member` writes them).
    retries : int
        Failures of the scene itself (:class:`~contactpipe.ContactpipeError`: no
        convergence, contact off the grid, ...) are final; any other failure (disk full,
        memory) is tried again this many times.

    Returns
    -------
    dict
        ``digest``, ``status`` ("done" or "failed"), ``error`` (one line: the exception's
        type and message), ``attempts``, ``wall_time_s``, ``cpu_time_s`` and, without a
        path, ``archive`` (bytes).
    """
    t0, c0 = time.perf_counter(), time.process_time()
    attempt, data = 0, None
    while True:
        attempt += 1
        try:
            data = _simulate(scene, path)
            status, error = "done", None
        except ContactpipeError as err:
            status, error = "failed", one_line(err)
        # a task reports its member's failure instead of raising, whatever it is, so the
        # other members go on; the failure is recorded with its own type and message
        except Exception as err:                # noqa: BLE001
            if attempt <= retries:
                continue
            status, error = "failed", one_line(err)
        out = {"digest": digest, "status": status, "error": error, "attempts": attempt,
               "wall_time_s": time.perf_counter() - t0,
               "cpu_time_s": time.process_time() - c0}
        if data is not None:
            out["archive"] = data
        return out


def land_member(result: dict, path) -> dict:
    """Write the archive bytes a worker sent back (``result["archive"]``) atomically to
    ``path``, after checking them: a complete contactpipe archive whose scene has the
    member's digest. Returns ``result`` without the bytes; a check that fails makes it a
    failed member (nothing is written)."""
    data = result.pop("archive", None)
    if result["status"] != "done" or data is None:
        return result
    path = pathlib.Path(path)
    try:
        with atomic_path(path) as tmp:
            tmp.write_bytes(data)
            with open_archive(tmp) as ds:
                found = scene_digest(ds)
            if found != result["digest"]:
                raise ArchiveError(f"the archive sent back holds the scene of digest "
                                   f"{found}, not {result['digest']}")
    except ArchiveError as err:
        result.update(status="failed", error=f"{path.name}: {one_line(err)}")
    return result


def _from_a_script() -> bool:
    """Whether the top level of a script (``python script.py``) is on the call stack:
    the spawned workers of a LocalCluster import that script again."""
    main = sys.modules.get("__main__")
    if not getattr(main, "__file__", None):
        return False                  # an interactive session, a notebook, python -c
    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_code.co_name == "<module>" and frame.f_globals is vars(main):
            return True
        frame = frame.f_back
    return False


def _cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


@contextlib.contextmanager
def dask_client(client, scheduler, n_workers, threads_per_worker, n_jobs):
    """The client to submit to: the caller's (left open), one on ``scheduler``, or one of
    a LocalCluster of ``n_workers`` processes (default ``min(n_jobs, CPU count)``)."""
    if client is not None:
        yield client
        return
    # distributed is imported here, not at the top: a heavy import that only a cluster
    # run needs
    import distributed
    if scheduler:
        try:
            c = distributed.Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as err:
            raise ContactpipeError(f"cannot connect to the dask scheduler at {scheduler!r}: "
                                   f"{one_line(err)}") from None
        try:
            yield c
        finally:
            c.close()
        return
    n = int(n_workers) if n_workers else max(1, min(n_jobs, _cpu_count()))
    try:
        cluster = distributed.LocalCluster(n_workers=n,
                                           threads_per_worker=int(threads_per_worker),
                                           processes=True, dashboard_address=None)
    except (RuntimeError, OSError, TimeoutError) as err:
        hint = (" (the workers import this script again: the sweep must be called under "
                "if __name__ == \"__main__\":)" if _from_a_script() else "")
        raise ContactpipeError(f"the LocalCluster's {n} worker process(es) failed to "
                               f"start: {one_line(err)}{hint}") from None
    try:
        c = distributed.Client(cluster)
        try:
            yield c
        finally:
            c.close()
    finally:
        cluster.close()


def _submit_all(c, jobs, retries, in_place) -> dict:
    futures = {}
    for digest, scene, path in jobs:
        fut = c.submit(run_member, scene, digest, path if in_place else None, retries,
                       pure=False, key=f"simulate-{digest}-{os.urandom(4).hex()}")
        futures[fut] = (digest, path)
    return futures


def _gather(futures, in_place, on_done, bar) -> None:
    """Hand each outcome to ``on_done`` as it comes, landing returned archives first."""
    # distributed is imported here, not at the top: a heavy import that only a cluster
    # run needs (loaded already when futures exist)
    import distributed
    try:
        for fut in distributed.as_completed(list(futures)):
            digest, path = futures[fut]
            try:
                res = fut.result()
            # the infrastructure failed for this member (a worker died running it, the
            # task was cancelled, the connection dropped): the member failed, say why
            except (distributed.KilledWorker, concurrent.futures.CancelledError, OSError,
                    TimeoutError) as err:
                res = {"digest": digest, "status": "failed", "error": one_line(err),
                       "wall_time_s": None}
            on_done(res if in_place else land_member(res, path))
            bar.update(1)
            fut.release()
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise


def execute(jobs, *, client=None, scheduler=None, n_workers=None, threads_per_worker=1,
            progress=False, retries=0, shared_disk=None, on_done) -> None:
    """Run ``jobs`` [(digest, scene, path)], calling ``on_done(outcome)`` as each ends.

    ``outcome`` is :func:`run_member`'s dict (the archive bytes already written to
    ``path`` when the workers do not share the disk). See the module docstring for where
    the work runs and where the archives are written.
    """
    if not jobs:
        return
    from tqdm.auto import tqdm
    in_place = workers_share_disk(shared_disk, client, scheduler)
    bar = tqdm(total=len(jobs), desc="sweep", unit="member", disable=not progress)
    try:
        if client is None and scheduler == SYNCHRONOUS:
            for digest, scene, path in jobs:
                res = run_member(scene, digest, path if in_place else None, retries)
                on_done(res if in_place else land_member(res, path))
                bar.update(1)
            return
        with dask_client(client, scheduler, n_workers, threads_per_worker, len(jobs)) as c:
            _gather(_submit_all(c, jobs, retries, in_place), in_place, on_done, bar)
    finally:
        bar.close()
