"""The ``wear`` case of ``contactpipe bench``: a fretting life of 10⁵ cycles end to end,
and what the cycle jumps cost in accuracy.

Force-controlled partial-slip fretting of a steel sphere on a steel half-space (R = 18 mm,
W = 1 kN, μ = 0.3, T = 0 → T* → 0 → −T* → 0 with T* = 0.5 μW, one cycle in ``steps``
steps), Archard wear of the half-space (k = 1e-14 1/Pa), ``jump = "auto"``:

``life``       the whole life (``cycles``, default 10⁵) end to end: cycles simulated and wall
               time (the archive written to a temporary folder, as a user's run writes it).
``check``      the accuracy of the jumps, over a shorter life (``check_cycles``, default 300)
               worn as much as the whole one (k × cycles / check_cycles: the same scar in
               fewer cycles, so that the jumps have as much wear to get wrong): ``jump =
               "auto"`` against every cycle simulated (``jump = 1``), the largest wear-depth
               difference over the largest depth and the worn volume's relative difference
               at the end.

The figures are printed and returned as records (:func:`bench_wear`); ``contactpipe bench
wear`` writes them to ``benchmarks/results/bench-wear.csv`` with the columns of
:data:`WEAR_COLUMNS`.
"""
from __future__ import annotations

import math
import pathlib
import tempfile
import time

import numpy as np

from ...scene import Scene
from .bench_scenes import A_HERTZ, W, load_average, make_scene

__all__ = ["bench_wear", "wear_scene", "WEAR_COLUMNS", "QUICK_WEAR"]

MU = 0.3            # the bodies, R and W are those of the other cases (bench_scenes)
T_STAR = 0.5 * MU * W
K_ARCHARD = 1e-14
#: The columns of bench-wear.csv: what was run, the figures, where and when.
WEAR_COLUMNS = ("case", "run", "grid", "steps", "cycles", "jump", "coefficient",
                "cycles_simulated", "run_s", "ms_per_simulated_cycle", "max_wear_depth",
                "worn_volume", "depth_error", "volume_error", "date", "commit", "cpus",
                "load_average")
#: ``--quick``: seconds.
QUICK_WEAR = dict(n=16, steps=8, cycles=1000, check_cycles=30)


def wear_scene(n, steps, cycles, jump, coefficient, backend="auto", threads=1) -> Scene:
    """The bench's scene: steel on steel, Archard wear, force-controlled partial slip."""
    return make_scene(name="bench-wear", friction={"mu": MU},
                      load={"time": [0.0, 0.25, 0.5, 0.75, 1.0], "normal_force": W,
                            "tangential_force": [0.0, T_STAR, 0.0, -T_STAR, 0.0]},
                      grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
                      time={"steps": steps},
                      wear={"law": "archard", "coefficient": coefficient, "cycles": cycles,
                            "jump": jump},
                      solver={"fft": backend, "threads": threads})


def _run(scene, folder: pathlib.Path, name: str):
    """(final wear depth, worn volume, cycles simulated, wall [s], load) of a run written
    to ``folder``."""
    from ...simulation import simulate  # the solver and the FFTs: only when a case runs
    load = load_average()
    t0 = time.perf_counter()
    ds = simulate(scene, folder / f"{name}.nc")
    wall = time.perf_counter() - t0
    with ds:
        depth = np.asarray(ds["wear_depth"].isel(cycle=-1).values, float)
        volume = float(ds["worn_volume"].values[-1])
        simulated = int(ds.attrs["cycles_simulated"])
    return depth, volume, simulated, wall, max(load, load_average())


def _record(run, n, steps, cycles, jump, k, result, **extra) -> dict:
    depth, volume, simulated, wall, load = result
    return dict(case="wear", run=run, grid=n, steps=steps, cycles=cycles, jump=str(jump),
                coefficient=k, cycles_simulated=simulated, run_s=wall,
                ms_per_simulated_cycle=wall / simulated * 1e3,
                max_wear_depth=float(depth.max()), worn_volume=volume,
                load_average=load, **extra)


def bench_wear(backend="auto", threads=1, n=48, steps=20, cycles=100_000,
               check_cycles=300) -> list[dict]:
    """The life and the check (see the module); returns their records."""
    print(f"wear: steel sphere on steel, W = 1 kN, μ = {MU}, T* = {T_STAR / (MU * W):.2g} μW, "
          f"Archard k = {K_ARCHARD:g} 1/Pa, {n}², {steps} steps per cycle, jump auto")
    print(f"{'run':>6} {'cycles':>8} {'jump':>5} {'simulated':>9} {'wall s':>8} "
          f"{'ms/cycle':>8} {'depth µm':>9} {'volume mm³':>11} {'depth err':>9} {'vol err':>8}")
    rows = []
    k_check = K_ARCHARD * cycles / check_cycles
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(tmp)
        life = _run(wear_scene(n, steps, cycles, "auto", K_ARCHARD, backend, threads),
                    folder, "life")
        rows.append(_record("life", n, steps, cycles, "auto", K_ARCHARD, life))
        every = _run(wear_scene(n, steps, check_cycles, 1, k_check, backend, threads),
                     folder, "every")
        auto = _run(wear_scene(n, steps, check_cycles, "auto", k_check, backend, threads),
                    folder, "auto")
    top = float(every[0].max())
    errors = dict(depth_error=float(np.abs(auto[0] - every[0]).max()) / top if top > 0
                  else math.nan,
                  volume_error=abs(auto[1] - every[1]) / every[1] if every[1] > 0
                  else math.nan)
    rows.append(_record("check", n, steps, check_cycles, 1, k_check, every))
    rows.append(_record("check", n, steps, check_cycles, "auto", k_check, auto, **errors))
    for r in rows:
        err = (f"{r['depth_error']:>9.2%} {r['volume_error']:>8.2%}"
               if "depth_error" in r else f"{'':>9} {'':>8}")
        print(f"{r['run']:>6} {r['cycles']:>8} {r['jump']:>5} {r['cycles_simulated']:>9} "
              f"{r['run_s']:>8.1f} {r['ms_per_simulated_cycle']:>8.1f} "
              f"{r['max_wear_depth'] * 1e6:>9.4g} {r['worn_volume'] * 1e9:>11.4g} {err}")
    return rows
