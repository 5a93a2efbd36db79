"""Speed figures: ``contactpipe bench [CASE ...]`` prints them and writes them to a CSV file
(never asserted in tests: a smoke test checks only the table's structure).

The cost unit is one *FFT pair*: one forward plus one inverse real FFT of the padded
(2N1 x 2N2) grid, as the solver's convolution engine does it (pyFFTW plans pruned of the
padding's zero rows, the same threads). Each case prints, per row:

``pairs/step``  FFT pairs a step, as the engine counts them (coarse-grid and window work
                charged in this grid's pairs);
``ms/step``     the wall time of a step;
``pair ms``     the measured time of one FFT pair on that grid (the least of three timed
                blocks, measured just before and just after the run, the least kept);
``floor``       pairs/step x pair ms: the least the step's transforms can cost;
``wall/floor``  ms/step / floor: the step's time in floor pairs, which stays comparable
                across machines and days when the wall time alone does not.

Both per-step figures leave out the first instant and the setup (FFT plans, kernel
spectra): they are of the steps after the first, timed from the end of the first instant
to the end of the last step (:func:`timed_run`); the first instant's pairs and the whole
run's time are columns of their own. The ``normal`` case is one instant: its figures are
of that solve, run a second time in the process so that the setup is left out.

Cases
-----
normal      Hertz (steel on steel, W = 1 kN, R = 18 mm) over 4a, tolerance 1e-10, grids 64² to 512²
fretting    the paper's elastic fretting loop (β = 0) and steel on aluminium (β ≠ 0), 40 steps,
            grids 64² to 256² (the vector form to 128²), tolerance 1e-9: per step after the
            first, the first instant's pairs and those of the frictional preload's error
            estimate
memory      per-step time at steps 10 and 1000 of a 64² creep run (Maxwell, Prony)
paper-fig3  rigid sphere on a Maxwell half-space (ν = 0.3, coupling on), 128², 200 steps, end to end
            in memory, then again into an archive (``file_run_s``: written, read back and
            checked); ``--vector`` adds the vector tangential form
long-run    256², 2000 steps streamed to disk: peak resident memory
wear        10⁵ cycles of partial-slip fretting with Archard wear, 48², 20 steps a cycle,
            jump auto, end to end; and jump auto against every cycle simulated over a
            shorter life (:mod:`contactpipe.pipeline.cli.bench_wear`)
phases      where a step's time goes: the spectral work (transforms, filters, kernel
            products, Parseval inners) timed in situ against the floor, and the rest, for
            fretting steel/Al scalar 128² and 256², vector 128², steel/steel vector 128² and
            paper-fig3 (:mod:`contactpipe.pipeline.cli.bench_phases`)

``--tuning NAME=VALUE ...`` runs ``fretting``, ``paper-fig3`` and ``phases`` with solver
switches or constants changed from their defaults
(:class:`contactpipe.solver.options.Tuning`, e.g. ``joint=false`` or ``defer=0``): the FFT
pairs are deterministic, so the pair columns of two runs show what a feature saves.

The table
---------
``normal``, ``fretting``, ``paper-fig3``, ``wear`` and ``phases`` write their rows to
``benchmarks/results/bench-<case>.csv`` (beside the package in a source checkout, else
under the current folder), or all to ``--csv PATH``, atomically (a reader never sees half a
file), with the columns of :data:`COLUMNS` (``wear`` and ``phases``: their own,
:data:`~contactpipe.pipeline.cli.bench_wear.WEAR_COLUMNS` and
:data:`~contactpipe.pipeline.cli.bench_phases.PHASE_COLUMNS`): the date (UTC), the commit, the
CPUs and the one-minute load average during the row's run say on what it was measured. ``--quick``
(16², 5 steps: seconds) writes no file unless ``--csv`` is given, so the checked-in tables
keep full figures. ``memory`` and ``long-run`` only print.

Each case also returns its figures as records (one dict per row: the case, the grid, the
form and the measured quantities, all numbers), which ``benchmarks/readme_figures.py``
writes to the file the README's speed figures are quoted from.
"""
from __future__ import annotations

import argparse
import csv
import datetime
import io
import math
import os
import pathlib
import resource
import subprocess
import tempfile
import time

import numpy as np

from ..._util.files import check_output_path, write_text
from ...exceptions import SceneError
from .bench_phases import PHASE_COLUMNS, QUICK_PHASES, bench_phases
from .bench_scenes import (
    A_HERTZ,
    ALUMINIUM,
    E_STEEL,
    STEEL,
    W,
    floor_ms,
    fretting_scene,
    load_average,
    make_scene,
    pair_ms_around,
    paper_fig3_scene,
    timed_run,
)
from .bench_wear import QUICK_WEAR, WEAR_COLUMNS, bench_wear

__all__ = ["add_arguments", "main", "CASES", "COLUMNS", "TABLE_CASES", "timed_run",
           "table_rows", "write_table", "default_table_path", "fretting_scene",
           "paper_fig3_scene", "floor_ms", "pair_ms_around"]

#: The columns of the CSV table, in order: what was run (case, the bodies, grid N for
#: N x N cells, steps after the first instant, solver tolerance, tangential form), the
#: figures (see the module's docstring; ``run_pairs`` and ``run_s`` are of the whole run:
#: every instant's pairs and the preload estimate's, the setup's time; ``file_run_s``,
#: paper-fig3 only, the same run written to an archive: written, read back and checked)
#: and where and when it was measured.
COLUMNS = ("case", "pair", "grid", "steps", "tolerance", "form", "pairs_per_step",
           "ms_per_step", "pair_ms", "floor_ms_per_step", "wall_over_floor",
           "first_instant_pairs", "preload_estimate_pairs", "run_pairs", "run_s",
           "file_run_s", "date", "commit", "cpus", "load_average")
#: The cases that write the table (the others only print).
TABLE_CASES = ("normal", "fretting", "paper-fig3", "wear", "phases")
#: The table cases with columns of their own (a table holds one kind of row).
OWN_COLUMNS = {"wear": WEAR_COLUMNS, "phases": PHASE_COLUMNS}
#: ``--quick``: a smoke run of seconds.
QUICK = dict(grids=[16], steps=5, memory=(16, 25), long_run=(16, 20))
_ROOT = pathlib.Path(__file__).resolve().parents[2]


def _timed(run, *args):
    """(``run(*args)``, its wall time [ms])."""
    t0 = time.perf_counter()
    out = run(*args)
    return out, (time.perf_counter() - t0) * 1e3


def _figures(pairs_per_step, ms_per_step, pair_ms):
    """The floor of a step and the step's time in floor pairs."""
    floor = pairs_per_step * pair_ms
    return dict(pairs_per_step=pairs_per_step, ms_per_step=ms_per_step, pair_ms=pair_ms,
                floor_ms_per_step=floor,
                wall_over_floor=ms_per_step / floor if floor > 0 else math.nan)


def _step_figures(ds, ms_per_step, pair_ms):
    """A run's figures per step after the first instant, and its first instant's."""
    pairs = ds.fft_pairs.values
    estimate = int(ds.attrs.get("preload_estimate_fft_pairs", 0))
    return dict(_figures(float(pairs[1:].mean()), ms_per_step, pair_ms),
                first_instant_pairs=int(pairs[0]), preload_estimate_pairs=estimate,
                run_pairs=float(pairs.sum()) + estimate,
                iterations_per_step=float(ds.iterations.values[1:].mean()),
                passes_per_step=float(ds.coupling_passes.values[1:].mean()))


_HEAD = (f"{'pairs/step':>10} {'ms/step':>8} {'pair ms':>8} {'floor ms':>9} {'wall/floor':>10}")


def _cells(r):
    return (f"{r['pairs_per_step']:>10.1f} {r['ms_per_step']:>8.2f} {r['pair_ms']:>8.4f} "
            f"{r['floor_ms_per_step']:>9.2f} {r['wall_over_floor']:>9.1f}x")


def bench_normal(grids, backend, threads):
    from ...simulation import simulate  # the solver and the FFTs: only when a case runs
    rows = []
    print("normal contact: Hertz, steel on steel, W = 1 kN, R = 18 mm, grid over 4a, tol "
          "1e-10; one instant, solved a second time (setup left out)")
    print(f"{'grid':>9} {'iter':>5} {_HEAD} {'setup s':>7}")
    for n in grids:
        sc = make_scene(load={"time": [0.0], "normal_force": W},
                        grid={"points": [n, n], "size": [4 * A_HERTZ] * 2},
                        solver={"tolerance": 1e-10, "fft": backend, "threads": threads})
        load = load_average()
        t0 = time.perf_counter()
        simulate(sc)                                  # plans and kernel spectra (cached)
        first = time.perf_counter() - t0
        (ds, wall), pair = pair_ms_around(n, backend, threads, _timed, simulate, sc)
        pairs = float(ds.fft_pairs.values[0])
        r = dict(case="normal", pair="steel/steel", form="normal", grid=n, steps=0,
                 tolerance=1e-10, iterations_per_step=int(ds.iterations[0]),
                 **_figures(pairs, wall, pair), first_instant_pairs=int(pairs),
                 preload_estimate_pairs=0, run_pairs=pairs, run_s=first,
                 load_average=max(load, load_average()))
        print(f"{n:>4}x{n:<4} {r['iterations_per_step']:>5} {_cells(r)} "
              f"{first - wall / 1e3:>7.2f}")
        rows.append(r)
    return rows


def bench_fretting(grids, backend, threads, steps=40, tuning=None):
    rows = []
    print(f"fretting loop T: 0 -> .9μW -> -.9μW -> .9μW, μ = 0.1, {steps} steps, grid over 3a, "
          "tol 1e-9; per step after the first instant (warm-started; setup left out)")
    print(f"{'pair':>16} {'form':>7} {'grid':>9} {'iter/step':>9} {'passes':>6} {_HEAD} "
          f"{'first':>6} {'preload':>7}")
    for label, half in (("steel/steel β=0", STEEL), ("steel/Al β≠0", ALUMINIUM)):
        for form in ("scalar", "vector"):
            for n in grids:
                if form == "vector" and n > 128:
                    continue
                sc = fretting_scene(half, n, steps, backend, threads)
                (ds, run_s, ms, load), pair = pair_ms_around(
                    n, backend, threads, timed_run, sc, form, tuning)
                r = dict(case="fretting", pair=label, form=form, grid=n,
                         steps=ds.sizes["time"] - 1,
                         tolerance=float(sc.solver.tolerance),
                         **_step_figures(ds, ms, pair), run_s=run_s, load_average=load)
                print(f"{label:>16} {form:>7} {n:>4}x{n:<4} {r['iterations_per_step']:>9.1f} "
                      f"{r['passes_per_step']:>6.1f} {_cells(r)} "
                      f"{r['first_instant_pairs']:>6} {r['preload_estimate_pairs']:>7}")
                rows.append(r)
    return rows


def bench_memory(backend, threads, n=64, steps=1000):
    from ...simulation import simulate  # the solver and the FFTs: only when a case runs
    rows = []
    print(f"memory: per-step cost of the viscoelastic history ({n}², rigid sphere, W stepped, "
          "window 2 s); the recursion keeps it flat")
    print(f"{'creep':>8} {'ms/step (steps 0-10)':>21} "
          f"{f'ms/step (steps {steps - 10}-{steps})':>25}")
    for creep in ({"creep": "maxwell", "relaxation_time": 1.0},
                  {"creep": "prony", "terms": [[0.5, 0.1], [1.0, 1.0]], "relaxation_time": 2.0}):
        sc = make_scene(indenter={"material": "rigid"},
                        halfspace={"material": "viscoelastic", "young": 105e9, "poisson": 0.5,
                                   **creep},
                        load={"time": [0.0, 2.0], "normal_force": W},
                        grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                        solver={"fft": backend, "threads": threads})
        stamps = []
        simulate(sc, on_step=lambda k, t, rec, out=stamps: out.append(time.perf_counter()))
        d = np.diff(stamps) * 1e3
        times = (d[1:11].mean(), d[-10:].mean())
        print(f"{creep['creep']:>8} {times[0]:>21.2f} {times[1]:>25.2f}")
        rows.append(dict(case="memory", pair=creep["creep"], form="normal", grid=n,
                         steps=steps, ms_per_step_first=times[0], ms_per_step_last=times[1]))
    return rows


def bench_paper_fig3(backend, threads, steps=200, n=128, forms=("scalar",), tuning=None):
    rows = []
    print(f"paper figure 3: rigid sphere on Maxwell (glassy E = 105 GPa, ν = 0.3: the steel "
          f"pair's composite modulus; coupling on), τ = t', {n}², {steps} steps, "
          f"{threads} FFT thread{'s' if threads > 1 else ''}; per step after the first "
          "instant, and the whole run (setup included)")
    print(f"{'form':>7} {'iter/step':>9} {'passes':>6} {_HEAD} {'first':>6} {'preload':>7} "
          f"{'run s':>7} {'run pairs':>9}")
    for form in forms:
        sc = paper_fig3_scene(n, steps, backend, threads)
        (ds, run_s, ms, load), pair = pair_ms_around(
            n, backend, threads, timed_run, sc, form, tuning)
        r = dict(case="paper-fig3", pair="rigid/Maxwell", form=form, grid=n,
                 steps=ds.sizes["time"] - 1,
                 tolerance=float(sc.solver.tolerance), **_step_figures(ds, ms, pair),
                 run_s=run_s, load_average=load)
        print(f"{form:>7} {r['iterations_per_step']:>9.1f} {r['passes_per_step']:>6.1f} "
              f"{_cells(r)} {r['first_instant_pairs']:>6} {r['preload_estimate_pairs']:>7} "
              f"{run_s:>7.2f} {r['run_pairs']:>9.0f}")
        print(f"{'':>7} the whole run: {run_s:.2f} s = {run_s / (r['run_pairs'] * pair) * 1e3:.1f}"
              f" x its {r['run_pairs']:,.0f} pairs' floor ({ds.attrs['models']})")
        r["file_run_s"] = _file_run(sc, form, tuning)
        print(f"{'':>7} the same run to an archive (written, read back, checked): "
              f"{r['file_run_s']:.2f} s")
        rows.append(r)
    return rows


def _file_run(scene, form, tuning) -> float:
    """Seconds of ``scene`` run into an archive in a temporary folder: the instants written
    on the writer's thread, the file read back and checked at close (setup included)."""
    from ...simulation import run_scene
    kw = {"tangential": form} if tuning is None else {"tangential": form, "tuning": tuning}
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        run_scene(scene, os.path.join(tmp, "run.nc"), **kw)
        return time.perf_counter() - t0


def bench_long_run(backend, threads, n=256, steps=2000):
    from ...simulation import simulate  # the solver and the FFTs: only when a case runs
    sc = make_scene(indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E_STEEL, "poisson": 0.5,
                               "creep": "maxwell", "relaxation_time": 1.0},
                    load={"time": [0.0, 1.0], "normal_force": W},
                    grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                    solver={"fft": backend, "threads": threads})
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        simulate(sc, os.path.join(tmp, "long.nc"))
        wall = time.perf_counter() - t0
        size = os.path.getsize(os.path.join(tmp, "long.nc"))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"long run: {n}², {steps} steps streamed to disk in {wall:.0f} s, archive "
          f"{size / 2**20:.0f} MiB, peak resident memory {peak:.0f} MiB")
    return [dict(case="long-run", pair="rigid/Maxwell", form="normal", grid=n, steps=steps,
                 wall_s=wall, archive_mib=size / 2 ** 20, peak_rss_mib=peak)]


CASES = {"normal": bench_normal, "fretting": bench_fretting, "memory": bench_memory,
         "paper-fig3": bench_paper_fig3, "long-run": bench_long_run, "wear": bench_wear,
         "phases": bench_phases}


# ----------------------------------------------------------------------------- the table
def _commit() -> str:
    """The checkout's commit (``+`` when its tracked files differ from it), or ``unknown``
    outside a git checkout."""
    def git(*a):
        return subprocess.run(["git", "-C", str(_ROOT), *a], capture_output=True, text=True,
                              timeout=10)
    try:
        head = git("rev-parse", "--short=7", "HEAD")
        if head.returncode != 0:
            return "unknown"
        dirty = git("diff", "--quiet", "HEAD", "--", ".").returncode != 0
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head.stdout.strip() + ("+" if dirty else "")


def default_table_path(case: str) -> pathlib.Path:
    """``benchmarks/results/bench-<case>.csv`` of the source checkout the package runs
    from, or under the current folder when it is installed elsewhere."""
    results = _ROOT / "benchmarks" / "results"
    base = results if results.is_dir() else pathlib.Path("benchmarks") / "results"
    return base / f"bench-{case}.csv"


def _cell(v) -> str:
    if isinstance(v, (float, np.floating)):
        return f"{float(v):.6g}" if math.isfinite(v) else ""   # never NaN in the file
    return str(v)


def table_rows(records, date=None, commit=None) -> list:
    """The CSV rows (dicts of :data:`COLUMNS`, as text) of the records of the table cases."""
    date = date or f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%dT%H:%MZ}"
    commit = commit or _commit()
    meta = dict(date=date, commit=commit, cpus=os.cpu_count() or "")
    return [{c: _cell({**r, **meta}.get(c, ""))
             for c in OWN_COLUMNS.get(r.get("table", r["case"]), COLUMNS)}
            for r in records if r.get("table", r["case"]) in TABLE_CASES]


def write_table(rows, path) -> pathlib.Path:
    """Write the rows of :func:`table_rows` to ``path`` as CSV, atomically."""
    text = io.StringIO()
    w = csv.DictWriter(text, fieldnames=list(rows[0]) if rows else COLUMNS,
                       lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_text(path, text.getvalue())


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("cases", nargs="*", default=["normal"],
                        help=f"which figures to print: {', '.join(CASES)} (default: normal)")
    parser.add_argument("--grids", type=int, nargs="+", default=None,
                        help="grid sizes (cells per side; paper-fig3 takes the first, "
                             "phases the first and the last)")
    parser.add_argument("--steps", type=int, default=None,
                        help="steps of the fretting loop and of paper-fig3 (default 40, 200)")
    parser.add_argument("--quick", action="store_true",
                        help=f"a smoke run of seconds: {QUICK['grids'][0]}² grids, "
                             f"{QUICK['steps']} steps; writes no table unless --csv is given")
    parser.add_argument("--csv", default=None, metavar="PATH",
                        help="write the table of every case run here to PATH (default: each "
                             "of normal, fretting, paper-fig3 to "
                             "benchmarks/results/bench-<case>.csv)")
    parser.add_argument("--fft", choices=("auto", "pyfftw", "scipy"), default="auto")
    parser.add_argument("--threads", type=int, default=1,
                        help="FFT threads of each run (default 1, as solver.threads; 2 puts "
                             "a single run on both cores of a 2-core machine)")
    parser.add_argument("--vector", action="store_true",
                        help="paper-fig3: also time the vector tangential form (slow)")
    parser.add_argument("--tuning", nargs="+", default=[], metavar="NAME=VALUE",
                        help="fretting, paper-fig3, phases: solver switches and constants changed "
                             "from their defaults, e.g. joint=false defer=0 (the names: "
                             "contactpipe.solver.options.Tuning)")


def _run_case(case, args, tuning=None):
    grids, steps = args.grids, args.steps
    if case == "wear":
        kw = dict(QUICK_WEAR) if args.quick else {}
        if grids:
            kw["n"] = grids[0]
        if steps:
            kw["steps"] = steps
        return bench_wear(args.fft, args.threads, **kw)
    if case == "phases":
        kw = dict(QUICK_PHASES) if args.quick else {}
        if grids:
            kw["grids"] = (grids[0], grids[-1])
        if steps:
            kw["steps"] = steps
        return bench_phases(args.fft, args.threads, tuning=tuning, **kw)
    if args.quick:
        grids, steps = grids or QUICK["grids"], steps or QUICK["steps"]
    if case == "normal":
        return bench_normal(grids or [64, 128, 256, 512], args.fft, args.threads)
    if case == "fretting":
        return bench_fretting(grids or [64, 128, 256], args.fft, args.threads,
                              steps=steps or 40, tuning=tuning)
    if case == "paper-fig3":
        return bench_paper_fig3(args.fft, args.threads, steps=steps or 200,
                                n=grids[0] if grids else 128,
                                forms=("scalar", "vector") if args.vector else ("scalar",),
                                tuning=tuning)
    if args.quick:
        return CASES[case](args.fft, args.threads,
                           *QUICK["memory" if case == "memory" else "long_run"])
    return CASES[case](args.fft, args.threads)


def main(args) -> int:
    from ...solver.options import tuning_from
    for case in args.cases:
        if case not in CASES:
            raise SceneError(f"bench case {case!r}: allowed {', '.join(CASES)}")
    if args.grids and min(args.grids) < 2:
        raise SceneError(f"bench --grids {min(args.grids)}: allowed whole numbers ≥ 2")
    if args.steps is not None and args.steps < 1:
        raise SceneError(f"bench --steps {args.steps}: allowed whole numbers ≥ 1")
    try:
        tuning = tuning_from(args.tuning) if args.tuning else None
    except ValueError as e:
        raise SceneError(f"bench --{e}") from None
    for own in OWN_COLUMNS:
        if args.csv is not None and own in args.cases and len(set(args.cases)) > 1:
            raise SceneError(f"bench --csv with {own} and other cases: the {own} table has "
                             f"its own columns; run {own} alone")
    csv_path = None if args.csv is None else check_output_path(args.csv, "table (--csv)")
    date = f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%dT%H:%MZ}"
    tables = []
    for case in args.cases:
        rows = table_rows(_run_case(case, args, tuning), date=date)
        if rows:
            tables.append((case, rows))
        print()
    if csv_path is not None and tables:
        print(f"wrote {write_table([r for _, rows in tables for r in rows], csv_path)}")
    elif csv_path is None and args.quick and tables:
        print("--quick: no table written (give --csv PATH to write one)")
    elif csv_path is None:
        for case, rows in tables:
            print(f"wrote {write_table(rows, default_table_path(case))}")
    return 0
