"""The instants of a streamed archive written on a thread of their own.

Compressing and writing an instant's fields (zlib with shuffle, a fletcher32 checksum
per chunk) is most of what a file run spends outside the solver: about 3.5 of 8.0 s for
the paper's figure-3 run at 128², 200 steps, on one thread. netCDF4 releases the GIL
while the HDF5 library compresses and writes, so a second core can do it while the
solver computes the next instant (docs/design-choices.md, D36).

:class:`Background` keeps one worker thread and at most ``depth`` instants waiting
for it, so memory stays flat (an ``append`` waits while ``depth`` are queued: with the
instant being handed over, ``depth`` + 1 are held at most). The thread's writes run
under one process-wide lock, xarray's HDF5 lock where xarray has one: the HDF5 library
is not safe for concurrent calls, and a process may read or write other files on other
threads (a dask worker with several threads); the writer's own calls on its caller's
thread come only once the queue is drained. A write
that fails is raised by the next call that waits on the queue, naming the instant.
"""
from __future__ import annotations

import collections
import threading
from concurrent.futures import Future, ThreadPoolExecutor

from ..exceptions import ArchiveError, one_line

try:  # the lock xarray takes around its own netCDF4 reads and writes
    from xarray.backends.locks import HDF5_LOCK as NETCDF_LOCK
except ImportError:  # pragma: no cover - an xarray without it: ours alone
    NETCDF_LOCK = threading.Lock()

__all__ = ["Background", "NETCDF_LOCK"]

#: Instants a writer may hold in memory while its thread writes the ones before.
DEPTH = 2


class Background:
    """One writer thread for one archive; ``label`` names the archive in errors."""

    def __init__(self, label: str, depth: int = DEPTH):
        self.label, self.depth = label, int(depth)
        self._pool: ThreadPoolExecutor | None = None
        self._pending: collections.deque[tuple[int, Future]] = collections.deque()
        self.failed: ArchiveError | None = None

    def submit(self, step: int, write, *args) -> None:
        """Write instant ``step`` by ``write(*args)`` on the thread, once fewer than
        ``depth`` instants wait. Raises a failure of an earlier instant first."""
        self.check()
        while len(self._pending) >= self.depth:
            self._wait_one()
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1,
                                            thread_name_prefix="contactpipe-archive")
        self._pending.append((step, self._pool.submit(_locked, write, *args)))

    def drain(self) -> None:
        """Wait until every instant handed over is written; raise the first failure."""
        while self._pending:
            self._wait_one()
        self.check()

    def check(self) -> None:
        if self.failed is not None:
            raise self.failed

    def stop(self) -> None:
        """Wait for the write in progress, drop those not started, end the thread
        (abort, suspend, garbage collection): the file may then be closed."""
        for _, future in self._pending:
            future.cancel()
        self._pending.clear()
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def _wait_one(self) -> None:
        step, future = self._pending.popleft()
        try:
            future.result()
        except Exception as e:             # noqa: BLE001 - reported with the path and step
            if self.failed is None:
                self.failed = ArchiveError(f"{self.label}: writing step {step} failed "
                                           f"({one_line(e)})")
                self.failed.__cause__ = e


def _locked(write, *args):
    with NETCDF_LOCK:
        return write(*args)
