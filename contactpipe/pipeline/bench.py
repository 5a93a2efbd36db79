"""Speed figures: ``contactpipe bench [CASE ...]`` prints them (never asserted in tests).

The cost unit is one *FFT pair*: one forward plus one inverse real FFT of the padded
(2N1 x 2N2) grid. Each case prints the pairs spent, the iterations, the wall time, and the
time of one FFT pair on that grid (the floor: pairs x floor is the least the FFTs cost).
Planning (pyFFTW plans, kernel spectra) happens once per grid and is reported apart
("setup s": the first run's extra time); wall times exclude it.

Cases
-----
normal      Hertz (steel on steel, W = 1 kN, R = 18 mm) over 4a, tolerance 1e-10, grids 64² to 512²
fretting    the paper's elastic fretting loop (β = 0) and steel on aluminium (β ≠ 0), 40 steps,
            grids 64² to 256²: pairs and iterations per warm-started step, the first
            instant's pairs and those of the frictional preload's error estimate
memory      per-step time at steps 10 and 1000 of a 64² creep run (Maxwell, Prony)
paper-fig3  rigid sphere on a Maxwell half-space (ν = 0.3, coupling on), 128², 200 steps, end to end
            (``--vector`` adds the vector tangential form)
long-run    256², 2000 steps streamed to disk: peak resident memory

Each case also returns its figures as records (one dict per row: the case, the grid, the
form and the measured quantities), which ``benchmarks/readme_figures.py`` writes to the
file the README's speed figures are quoted from.
"""
from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time

import numpy as np

from ..exceptions import SceneError
from ..scene import Scene
from ..simulation import simulate
from ..solver.convolution import Convolver

__all__ = ["add_arguments", "main", "CASES"]

E_STEEL, NU, R, W, MU = 210e9, 0.3, 0.018, 1000.0, 0.1
A_HERTZ = (3 * W * R / (4 / (2 * (1 - NU ** 2) / E_STEEL))) ** (1 / 3)
STEEL = {"material": "elastic", "young": E_STEEL, "poisson": NU}
ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}


def _scene(**kw):
    d = {"name": "bench", "geometry": {"shape": "sphere", "radius": R},
         "indenter": dict(STEEL), "halfspace": dict(STEEL)}
    d.update(kw)
    return Scene(**d)


def _floor_ms(n, backend, threads):
    """Milliseconds of one forward + inverse real FFT of the padded n x n grid."""
    conv = Convolver(n, n, backend=backend, threads=threads)
    k = conv.kernel_spectrum(np.ones((2 * n, 2 * n)))
    x = np.random.default_rng(0).normal(size=(n, n))
    reps = max(5, int(2e6 / (n * n)))
    conv.convolve(k, x)
    t0 = time.perf_counter()
    for _ in range(reps):
        conv.convolve(k, x)
    return (time.perf_counter() - t0) / reps * 1e3, conv.plan_time_s


def bench_normal(grids, backend, threads):
    rows = []
    print("normal contact: Hertz, steel on steel, W = 1 kN, R = 18 mm, grid over 4a, tol 1e-10")
    print(f"{'grid':>9} {'iter':>5} {'pairs':>6} {'pairs/it':>8} {'wall ms':>8} "
          f"{'floor ms':>9} {'pairs*floor':>11} {'plan s':>7}")
    for n in grids:
        sc = _scene(load={"time": [0.0], "normal_force": W},
                    grid={"points": [n, n], "size": [4 * A_HERTZ] * 2},
                    solver={"tolerance": 1e-10, "fft": backend, "threads": threads})
        t0 = time.perf_counter()
        simulate(sc)                                  # plans and kernel spectra (cached)
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        ds = simulate(sc)
        wall = (time.perf_counter() - t0) * 1e3
        plan = first - wall / 1e3                     # planning + kernel spectra, once per grid
        floor, _ = _floor_ms(n, backend, threads)
        it, pairs = int(ds.iterations[0]), int(ds.fft_pairs[0])
        print(f"{n:>4}x{n:<4} {it:>5} {pairs:>6} {pairs / it:>8.2f} {wall:>8.1f} {floor:>9.3f} "
              f"{pairs * floor:>11.1f} {plan:>7.2f}")
        rows.append(dict(case="normal", pair="steel/steel", form="normal", grid=n,
                         iterations=it, fft_pairs=pairs, wall_ms=wall, floor_ms=floor))
    return rows


def bench_fretting(grids, backend, threads, steps=40):
    rows = []
    print(f"fretting loop T: 0 -> .9μW -> -.9μW -> .9μW, μ = 0.1, {steps} steps, grid over 3a, "
          "tol 1e-9; per step after the first (warm-started)")
    print(f"{'pair':>16} {'form':>7} {'grid':>9} {'iter/step':>9} {'pairs/step':>10} "
          f"{'passes':>6} {'first':>6} {'preload':>7} {'ms/step':>8} {'floor ms':>9}")
    Ts = 0.9 * MU * W
    for label, half in (("steel/steel β=0", STEEL), ("steel/Al β≠0", ALUMINIUM)):
        for form in ("scalar", "vector"):
            for n in grids:
                if form == "vector" and n > 128:
                    continue
                sc = _scene(halfspace=dict(half), friction={"mu": MU},
                            load={"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W,
                                  "tangential_force": [0.0, Ts, -Ts, Ts]},
                            grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
                            time={"steps": steps},
                            solver={"fft": backend, "threads": threads})
                t0 = time.perf_counter()
                ds = simulate(sc, tangential=form)
                wall = time.perf_counter() - t0
                floor, _ = _floor_ms(n, backend, threads)
                it = ds.iterations.values[1:].mean()
                pairs = ds.fft_pairs.values[1:].mean()
                passes = ds.coupling_passes.values[1:].mean()
                first = int(ds.fft_pairs.values[0])
                pre = int(ds.attrs.get("preload_estimate_fft_pairs", 0))
                print(f"{label:>16} {form:>7} {n:>4}x{n:<4} {it:>9.1f} {pairs:>10.1f} "
                      f"{passes:>6.1f} {first:>6} {pre:>7} {wall / (steps + 1) * 1e3:>8.1f} "
                      f"{floor:>9.3f}")
                rows.append(dict(case="fretting", pair=label, form=form, grid=n, steps=steps,
                                 iterations_per_step=it, fft_pairs_per_step=pairs,
                                 passes_per_step=passes, first_instant_fft_pairs=first,
                                 preload_estimate_fft_pairs=pre,
                                 ms_per_step=wall / (steps + 1) * 1e3, floor_ms=floor))
    return rows


def bench_memory(backend, threads, n=64, steps=1000):
    rows = []
    print(f"memory: per-step cost of the viscoelastic history ({n}², rigid sphere, W stepped, "
          "window 2 s); the recursion keeps it flat")
    print(f"{'creep':>8} {'ms/step (steps 0-10)':>21} "
          f"{f'ms/step (steps {steps - 10}-{steps})':>25}")
    for creep in ({"creep": "maxwell", "relaxation_time": 1.0},
                  {"creep": "prony", "terms": [[0.5, 0.1], [1.0, 1.0]], "relaxation_time": 2.0}):
        sc = _scene(indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": 105e9, "poisson": 0.5,
                               **creep},
                    load={"time": [0.0, 2.0], "normal_force": W},
                    grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                    solver={"fft": backend, "threads": threads})
        stamps = []
        simulate(sc, on_step=lambda k, t, rec: stamps.append(time.perf_counter()))
        d = np.diff(stamps) * 1e3
        times = (d[1:11].mean(), d[-10:].mean())
        print(f"{creep['creep']:>8} {times[0]:>21.2f} {times[1]:>25.2f}")
        rows.append(dict(case="memory", pair=creep["creep"], form="normal", grid=n,
                         steps=steps, ms_per_step_first=times[0], ms_per_step_last=times[1]))
    return rows


def bench_paper_fig3(backend, threads, steps=200, n=128, forms=("scalar",)):
    rows = []
    Ts = 0.9 * MU * W
    print(f"paper figure 3: rigid sphere on Maxwell (glassy E = 105 GPa, ν = 0.3: the steel "
          f"pair's composite modulus; coupling on), τ = t', {n}², {steps} steps, end to end, "
          f"{threads} FFT thread{'s' if threads > 1 else ''}")
    for form in forms:
        sc = _scene(indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": 105e9, "poisson": NU,
                               "creep": "maxwell", "relaxation_time": 1.0},
                    friction={"mu": MU},
                    load={"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W,
                          "tangential_force": [0.0, Ts, -Ts, Ts]},
                    grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                    solver={"fft": backend, "threads": threads})
        # the floor pair just before and after the run: this shared machine's speed
        # varies, and wall / floor is the run's time in floor pairs, comparable across runs
        floor = _floor_ms(n, backend, threads)[0]
        t0 = time.perf_counter()
        ds = simulate(sc, tangential=form)
        wall = time.perf_counter() - t0
        floor = min(floor, _floor_ms(n, backend, threads)[0])
        print(f"  {form:>6}: {wall:.1f} s = {wall / floor * 1e3:,.0f} floor pairs of "
              f"{floor:.3f} ms (the run spent {ds.fft_pairs.values.sum():,.0f}), "
              f"{ds.fft_pairs.values.sum() / (steps + 1):.0f} FFT pairs "
              f"per step ({ds.fft_pairs.values[1:].mean():.0f} after the first instant's "
              f"{int(ds.fft_pairs.values[0])}, preload estimate "
              f"{int(ds.attrs.get('preload_estimate_fft_pairs', 0))}), "
              f"{ds.iterations.values.mean():.0f} iterations per step, "
              f"{ds.coupling_passes.values[1:].mean():.1f} coupling passes; {ds.attrs['models']}")
        rows.append(dict(case="paper-fig3", pair="rigid/Maxwell", form=form, grid=n,
                         steps=steps, wall_s=wall, floor_ms=floor,
                         fft_pairs=int(ds.fft_pairs.values.sum()),
                         fft_pairs_per_step=ds.fft_pairs.values.sum() / (steps + 1),
                         fft_pairs_per_step_after_first=ds.fft_pairs.values[1:].mean(),
                         first_instant_fft_pairs=int(ds.fft_pairs.values[0]),
                         preload_estimate_fft_pairs=int(
                             ds.attrs.get("preload_estimate_fft_pairs", 0)),
                         iterations_per_step=ds.iterations.values.mean(),
                         passes_per_step=ds.coupling_passes.values[1:].mean()))
    return rows


def bench_long_run(backend, threads, n=256, steps=2000):
    sc = _scene(indenter={"material": "rigid"},
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
         "paper-fig3": bench_paper_fig3, "long-run": bench_long_run}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("cases", nargs="*", default=["normal"],
                        help=f"which figures to print: {', '.join(CASES)} (default: normal)")
    parser.add_argument("--grids", type=int, nargs="+", default=None,
                        help="grid sizes (cells per side)")
    parser.add_argument("--fft", choices=("auto", "pyfftw", "scipy"), default="auto")
    parser.add_argument("--threads", type=int, default=1,
                        help="FFT threads of each run (default 1, as solver.threads; 2 puts "
                             "a single run on both cores of a 2-core machine)")
    parser.add_argument("--vector", action="store_true",
                        help="paper-fig3: also time the vector tangential form (slow)")


def main(args) -> int:
    for case in args.cases:
        if case not in CASES:
            raise SceneError(f"bench case {case!r}: allowed {', '.join(CASES)}")
    for case in args.cases:
        if case == "normal":
            bench_normal(args.grids or [64, 128, 256, 512], args.fft, args.threads)
        elif case == "fretting":
            bench_fretting(args.grids or [64, 128, 256], args.fft, args.threads)
        elif case == "paper-fig3":
            bench_paper_fig3(args.fft, args.threads,
                             forms=("scalar", "vector") if args.vector else ("scalar",))
        else:
            CASES[case](args.fft, args.threads)
        print()
    return 0
