"""Sweep scaling on dask: the same 8-member sweep on a LocalCluster of 1, then 2 workers.

    python benchmarks/bench_sweep.py [--steps 200] [--members 8] [--workers 1 2]

Each member is the 24 x 24 tiny-fretting scene (rigid sphere on a Maxwell half-space,
one fretting loop) with ``time.steps`` = 200 (about 1-2 s each), swept over
``friction.mu``. For every worker count the script prints

- ``sweep``: the wall time of :func:`contactpipe.pipeline.sweep.sweep` on an already running
  cluster whose workers have imported contactpipe (the time the members take, the
  scheduling overhead included, the cluster start-up left out), and
- ``end to end``: the same sweep letting :func:`sweep` start and close its own
  LocalCluster (what a user sees),

then the speed-ups against the first worker count. Target: >= 1.6x from 1 to 2 workers
(each worker is one process with one thread; the solver's FFTs run on one thread).
Every run writes into a fresh temporary folder, so nothing is skipped.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import distributed

from contactpipe.pipeline.sweep import sweep
from contactpipe.scene import Scene
from contactpipe.testing import TINY_SCENES

FRETTING = TINY_SCENES["fretting"]


def _warm():
    # the import is the point: run on each worker, it loads numpy, pyfftw, netCDF4 there
    import contactpipe.simulation  # noqa: F401
    return os.getpid()


def run(steps: int, members: int, workers: list[int]) -> int:
    base = Scene.from_toml_text(FRETTING).replace({"time.steps": steps})
    axes = {"friction.mu": [round(0.10 + 0.01 * i, 4) for i in range(members)]}
    print(f"sweep of {members} members: tiny-fretting 24x24, {steps} steps, "
          f"friction.mu = {axes['friction.mu']}")
    print(f"machine: {os.cpu_count()} CPUs, python {sys.version.split()[0]}, "
          f"dask.distributed {distributed.__version__}, load average "
          f"{os.getloadavg()[0]:.2f} (other processes share the CPUs: compare with care)")
    rows = []
    for n in workers:
        t0 = time.perf_counter()
        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           dashboard_address=None)
        client = distributed.Client(cluster)
        client.run(_warm)
        start = time.perf_counter() - t0
        try:
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                res = sweep(base, axes, tmp, client=client, progress=False)
                wall = time.perf_counter() - t0
                if not res.ok or len(res.computed) != members:
                    print(f"error: {res.summary()}", file=sys.stderr)
                    return 1
                per = sorted(m.wall_time_s for m in res.computed)
                cpu = sorted(m.cpu_time_s for m in res.computed)
        finally:
            client.close()
            cluster.close()
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            res = sweep(base, axes, tmp, n_workers=n, progress=False)
            e2e = time.perf_counter() - t0
            if not res.ok:
                print(f"error: {res.summary()}", file=sys.stderr)
                return 1
        rows.append((n, start, wall, e2e, per[len(per) // 2]))
        print(f"{n} worker(s): cluster start {start:5.2f} s | sweep {wall:6.2f} s "
              f"(median member {per[len(per) // 2]:.2f} s wall, "
              f"{cpu[len(cpu) // 2]:.2f} s CPU; members busy "
              f"{sum(per) / wall:.2f} workers on average) | end to end {e2e:6.2f} s | "
              f"load average {os.getloadavg()[0]:.2f}")
    n0, _, w0, e0, _ = rows[0]
    for n, _, wall, e2e, _ in rows[1:]:
        print(f"speed-up {n0} -> {n} workers: sweep {w0 / wall:.2f}x, "
              f"end to end {e0 / e2e:.2f}x (ideal {n / n0:.0f}x)")
    if len(rows) > 1 and rows[0][0] == 1 and rows[1][0] == 2:
        s = rows[0][2] / rows[1][2]
        print(f"target >= 1.6x from 1 to 2 workers: {'met' if s >= 1.6 else 'NOT met'} "
              f"({s:.2f}x)")
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=int, default=200, help="time steps per member")
    p.add_argument("--members", type=int, default=8, help="members of the sweep")
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2],
                   help="worker counts to compare (first is the reference)")
    args = p.parse_args(argv)
    return run(args.steps, args.members, args.workers)


if __name__ == "__main__":          # required: dask's worker processes re-import __main__
    sys.exit(main())
