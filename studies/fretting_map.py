"""Fretting map: the partial / gross slip regime over displacement amplitude and mu (or W).

Steel ball (R = 18 mm) on a steel half-space under a constant W (1 kN unless swept), a
displacement-controlled fretting cycle 0 -> +delta* -> -delta* -> +delta*
(``load.tangential_displacement`` over knots t = 0, 1, 3, 5 s). ``cp.sweep`` (dask) varies
delta* (the derived parameter ``delta_amplitude``) against ``friction.mu`` (default) or
``load.normal_force`` (``--against W``); each member's loop is classified by Fouvry's
energy ratio A = E/(4 T* delta*) (partial slip A < 0.2, gross slip A >= 0.2, mixed when
its cycles differ: contactpipe.post.fretting) and set against the closed form: the boundary
delta_gs = 3 mu W C/(16 a) of Mindlin's sphere and the Mindlin-Deresiewicz A(delta*/delta_gs).

    python studies/fretting_map.py [--out DIR] [--quick] [--against mu|W] [--points N]
                                   [--scheduler synchronous|ADDRESS]

Default: 32 x 32 cells over 3 a_H (of the largest W), 8 steps per quarter cycle (40 steps),
7 amplitudes x 5 friction coefficients (or 4 normal forces); quick: 16 x 16, 4 steps per
quarter, 3 x 2 members. Writes the sweep folder ``fretting_map/`` (one archive per
member), ``fretting_map.csv`` (the regime table), ``fretting_map.png`` (the map with the
closed-form boundary, and A against delta*/delta_gs) and prints the summary.
"""
from __future__ import annotations

import sys
import time

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import matplotlib.pyplot as plt
import numpy as np

import contactpipe as cp
from contactpipe.pipeline.figures.fretting import plot_energy_ratio, plot_fretting_map
from contactpipe.pipeline.figures.regimes import fretting_map, write_regime_table

#: Displacement amplitudes [m] of the default map, and of the quick one.
AMPLITUDES = [0.5e-6, 1e-6, 1.5e-6, 2e-6, 3e-6, 4e-6, 6e-6]
AMPLITUDES_QUICK = [0.5e-6, 1.5e-6, 4e-6]
MUS = [0.05, 0.1, 0.15, 0.2, 0.3]
MUS_QUICK = [0.1, 0.2]
FORCES = [250.0, 500.0, 1000.0, 2000.0]
FORCES_QUICK = [500.0, 2000.0]


def base_scene(n, per_quarter, w_max):
    """The fretting cycle's scene, its grid 3 a_H of the largest W."""
    a = cp.analytic.hertz_sphere(w_max, c.R, c.E_STAR).contact_radius
    return cp.Scene(name="fretting-map", geometry={"shape": "sphere", "radius": c.R},
                    indenter=dict(c.STEEL), halfspace=dict(c.STEEL),
                    friction={"mu": c.MU},
                    load={"time": [0.0, 1.0, 3.0, 5.0], "normal_force": c.W,
                          "tangential_displacement": [0.0, 1e-6, -1e-6, 1e-6]},
                    grid={"points": [n, n], "size": [3 * a, 3 * a]},
                    time={"steps": 5 * per_quarter})


def summary(table):
    """Members, regimes, agreement with the closed form, largest |A - A_cf|."""
    regimes = np.asarray(table.regime.values).astype(str)
    closed = np.asarray(table.regime_closed_form.values).astype(str)
    x = np.asarray(table.delta_ratio.values, float)
    gap = np.abs(np.asarray(table.energy_ratio.values, float)
                 - np.asarray(table.energy_ratio_closed_form.values, float))
    away = np.abs(x - 1.0) > 0.1
    return {"members": int(regimes.size),
            "regimes": {str(r): int(np.sum(regimes == r)) for r in np.unique(regimes)},
            "disagree": int(np.sum(regimes != closed)),
            "disagree_away_from_boundary": int(np.sum((regimes != closed) & away)),
            "max_A_error": float(np.max(gap)),
            "max_A_error_at": float(x[int(np.argmax(gap))])}


def main(argv=None):
    p = c.parser(__doc__.splitlines()[0], __doc__)
    p.add_argument("--against", choices=("mu", "W"), default="mu")
    p.add_argument("--points", type=int, default=None, help="cells per side")
    p.add_argument("--scheduler", default=None,
                   help="dask scheduler address, or 'synchronous' (default: a LocalCluster)")
    args = p.parse_args(argv)
    out = c.out_dir(args)
    n = args.points or (16 if args.quick else 32)
    per_quarter = 4 if args.quick else 8
    amplitudes = AMPLITUDES_QUICK if args.quick else AMPLITUDES
    if args.against == "mu":
        other = ("friction.mu", MUS_QUICK if args.quick else MUS)
        w_max = c.W
    else:
        other = ("load.normal_force", FORCES_QUICK if args.quick else FORCES)
        w_max = max(other[1])
    base = base_scene(n, per_quarter, w_max)
    folder = out / "fretting_map"
    t0 = time.perf_counter()
    res = cp.sweep(base, {"delta_amplitude": amplitudes, other[0]: other[1]}, folder,
                   scheduler=args.scheduler, progress=False)
    wall_sweep = time.perf_counter() - t0
    if not res.ok:
        raise RuntimeError(f"{len(res.failed)} members failed: {res.failed[0]}")
    t0 = time.perf_counter()
    table = fretting_map(folder)
    csv = write_regime_table(table, out / "fretting_map.csv")
    wall_classify = time.perf_counter() - t0
    fig, (ax_map, ax_a) = plt.subplots(1, 2, figsize=(13, 5))
    plot_fretting_map(table, args.against, ax=ax_map)
    plot_energy_ratio(table, ax=ax_a)
    png = out / "fretting_map.png"
    c.save_figure(fig, png)
    info = summary(table)
    info.update({"grid": n, "steps": 5 * per_quarter, "wall_sweep_s": wall_sweep,
                 "wall_classify_s": wall_classify, "computed": len(res.computed),
                 "skipped": len(res.skipped)})
    print(f"fretting map over delta* x {other[0]}: {info['members']} members on {n}^2, "
          f"{5 * per_quarter} steps; regimes {info['regimes']}; {info['disagree']} differ "
          f"from the closed form ({info['disagree_away_from_boundary']} more than 10 % "
          f"from delta_gs); max |A - A_cf| = {info['max_A_error']:.4f} (at delta*/delta_gs "
          f"= {info['max_A_error_at']:.3g}); sweep {wall_sweep:.1f} s "
          f"({len(res.computed)} computed, {len(res.skipped)} skipped), classification "
          f"{wall_classify:.1f} s (busy machine)")
    return {"png": png, "csv": csv, "folder": folder, "summary": info}


if __name__ == "__main__":
    main(sys.argv[1:])
