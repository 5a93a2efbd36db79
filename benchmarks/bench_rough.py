"""Partial slip with memory on a rough sphere: wall time and peak memory of a free-boundary
run, against the estimate that refuses a run before it starts.

    python benchmarks/bench_rough.py [--n 512] [--steps 20] [--precision float64]

The scene: a rigid rough sphere (a generated self-affine surface, H = 0.8, rms slope
0.02, roll-off half the side, cut-off 6 cells, riding on R = 18 mm) on a Maxwell
half-space (E = 210 GPa, nu = 0.3, t' = 1 s), mu = 0.1, W = 1 kN, a fretting loop
T: 0 -> +T* -> -T* -> +T* with T* = 0.5 mu W over 1 s, on n^2 cells of 3 Hertz radii,
``steps`` steps, streamed to a netCDF archive. Each run is a fresh process (the peak
resident memory ``ru_maxrss`` is the process's); the memory the run adds is that peak
minus the resident memory just before it.

Written: one row per run to benchmarks/results/bench_rough.csv (appended): grid, steps,
output precision, wall time [s], peak added memory [MiB], the estimate [MiB] and its
figure per cell [bytes], the date and commit. Figures, not assertions: the machine is
shared, so wall times are indicative only.
"""
from __future__ import annotations

import argparse
import csv
import datetime
import os
import resource
import subprocess
import sys
import tempfile
import time

RESULTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results",
                       "bench_rough.csv")
COLUMNS = ["case", "grid", "steps", "precision", "wall_s", "peak_mib", "estimate_mib",
           "estimate_bytes_per_cell", "measured_bytes_per_cell", "contact_clusters",
           "stick_clusters", "slip_clusters", "date", "commit"]


def scene(n, steps, precision):
    import contactpipe as cp

    R, W, mu, nu = 0.018, 1000.0, 0.1, 0.3
    e_star = 1.0 / (2 * (1 - nu ** 2) / 210e9)
    side = 3 * (3 * W * R / (4 * e_star)) ** (1 / 3)
    ts = 0.5 * mu * W
    return cp.Scene(
        name=f"bench-rough-{n}",
        geometry={"shape": "rough", "hurst": 0.8, "rms_slope": 0.02,
                  "wavelengths": [side / 2, 6 * side / n], "seed": 1, "form": "sphere",
                  "radius": R},
        indenter={"material": "rigid"},
        halfspace={"material": "viscoelastic", "young": 210e9, "poisson": nu,
                   "creep": "maxwell", "relaxation_time": 1.0},
        friction={"mu": mu},
        load={"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W,
              "tangential_force": [0.0, ts, -ts, ts]},
        grid={"points": [n, n], "size": [side, side]}, time={"steps": steps},
        output={"precision": precision})


def _rss_kib() -> int:
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def child(n, steps, precision):
    """One run in this process; prints one CSV row."""
    import xarray as xr

    import contactpipe as cp
    from contactpipe.planning import estimate_resources
    from contactpipe.post.clusters import contact_clusters

    sc = scene(n, steps, precision)
    est = estimate_resources(sc)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "rough.nc")
        before = _rss_kib()
        t0 = time.perf_counter()
        cp.simulate(sc, path)
        wall = time.perf_counter() - t0
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before   # KiB
        with xr.open_dataset(path) as ds:
            counts = contact_clusters(ds.load())
    commit = subprocess.run(["git", "rev-parse", "--short=7", "HEAD"], capture_output=True,
                            text=True, cwd=os.path.dirname(RESULTS)).stdout.strip()
    row = ["rough sphere on Maxwell fretting", f"{n}", f"{steps}", precision,
           f"{wall:.3f}", f"{peak / 1024:.1f}", f"{est.memory_bytes / 2**20:.1f}",
           f"{est.memory_bytes / n ** 2:.0f}", f"{peak * 1024 / n ** 2:.0f}",
           f"{int(counts.contact_clusters[-1])}", f"{int(counts.stick_clusters[-1])}",
           f"{int(counts.slip_clusters[-1])}",
           datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d"), commit]
    print(",".join(row))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=512)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--precision", default="float64", choices=("float64", "float32"))
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        child(args.n, args.steps, args.precision)
        return 0
    out = subprocess.run([sys.executable, __file__, "--child", "--n", str(args.n),
                          "--steps", str(args.steps), "--precision", args.precision],
                         capture_output=True, text=True, check=True).stdout.strip()
    row = out.splitlines()[-1]
    new = not os.path.exists(RESULTS)
    with open(RESULTS, "a", newline="", encoding="utf-8") as f:
        if new:
            csv.writer(f).writerow(COLUMNS)
        f.write(row + "\n")
    for k, v in zip(COLUMNS, row.split(","), strict=True):
        sys.stdout.write(f"{k:>24}: {v}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
