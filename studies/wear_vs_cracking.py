"""Wear against cracking: the fatigue indicator's peak at the end of a fretting life
against the slip amplitude.

Steel ball (R = 18 mm) on a steel half-space, W = 1 kN, mu = 0.1, a displacement-controlled
fretting cycle 0 -> +delta* -> 0 -> -delta* -> 0 (knots t = 0, 1/4, 1/2, 3/4, 1 s) repeated
over the life with Archard wear of the half-space (k = 2e-15 1/Pa) and cycle jumps
(``jump = "auto"``). ``cp.sweep`` (dask) varies delta* as delta*/delta_gs (the derived
parameter ``delta_ratio``; delta_gs = 3 mu W C/(16 a), 1.61 um, the closed-form partial /
gross slip boundary). Each member keeps the loop of tractions of its first and last
cycle (``wear.keep_tractions = 2``), on which ``cp.fatigue_over_cycles`` evaluates
Crossland's index (t_-1 = 400 MPa, f_-1 = 600 MPa, illustrative) at the surface and a
few depths: its peak in the unworn first cycle and at the end of life.

    python studies/wear_vs_cracking.py [--out DIR] [--quick] [--cycles N]
                                       [--scheduler synchronous|ADDRESS]

Default: 32 x 32 cells over 3.5 a_H, 16 steps a cycle, 10^5 cycles, delta*/delta_gs =
0.3, 0.5, 0.7, 0.9, 1.2, 1.6, 2.5; quick: 16 x 16, 8 steps, 1000 cycles, 0.4, 1.0, 2.5.
Writes the sweep folder ``wear_vs_cracking/``, ``wear_vs_cracking.csv`` (per member: the
ratio, cycles simulated, worn volume, deepest wear, Crossland's peak in the first and the
last cycle and its depth) and ``wear_vs_cracking.png``, and prints the table.
"""
from __future__ import annotations

import csv
import sys
import time

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import matplotlib.pyplot as plt
import numpy as np

import contactpipe as cp

RATIOS = [0.3, 0.5, 0.7, 0.9, 1.2, 1.6, 2.5]
RATIOS_QUICK = [0.4, 1.0, 2.5]
K_ARCHARD = 2e-15            # [1/Pa]
#: The jump's error budget (``wear.tolerance``): the end-of-life peak is a sharper
#: functional of the worn surface than its depth; at 2.5 delta_gs it is 0.2769 at the
#: default 0.003 and 0.2665 at 0.001 and at 0.0003 (studies/README.md).
JUMP_TOLERANCE = 0.001
TORSION_LIMIT, BENDING_LIMIT = 400e6, 600e6      # t_-1, f_-1 [Pa], illustrative
#: Depths of the fatigue evaluation, as fractions of a_H (the surface first).
DEPTHS = (0.0, 0.05, 0.15, 0.3, 0.5)
COLUMNS = ("delta_ratio", "delta_amplitude_m", "cycles", "cycles_simulated",
           "worn_volume_m3", "max_wear_depth_m", "crossland_first", "crossland_last",
           "crossland_last_x3_m", "crossland_last_x1_m")


def base_scene(n, steps, cycles):
    """The fretting life's scene (delta* set by the sweep), its grid 3.5 a_H."""
    side = 3.5 * c.A_H
    return cp.Scene(name="wear-vs-cracking", geometry={"shape": "sphere", "radius": c.R},
                    indenter=dict(c.STEEL), halfspace=dict(c.STEEL),
                    friction={"mu": c.MU},
                    load={"time": [0.0, 0.25, 0.5, 0.75, 1.0], "normal_force": c.W,
                          "tangential_displacement": [0.0, 1e-6, 0.0, -1e-6, 0.0]},
                    grid={"points": [n, n], "size": [side, side]}, time={"steps": steps},
                    wear={"law": "archard", "coefficient": K_ARCHARD, "cycles": cycles,
                          "jump": "auto", "keep_tractions": 2,
                          "tolerance": JUMP_TOLERANCE})


def member_row(ratio, archive) -> dict:
    """One member's row: its wear and Crossland's peak in the first and last cycle."""
    with cp.open_archive(archive) as ds:
        ds = ds.load()
    fc = cp.fatigue_over_cycles(ds, [f * c.A_H for f in DEPTHS], "crossland",
                                torsion_limit=TORSION_LIMIT, bending_limit=BENDING_LIMIT)
    om = np.asarray(ds["omega1"].values, float)
    return {"delta_ratio": ratio, "delta_amplitude_m": float(np.max(np.abs(om))),
            "cycles": int(ds["cycle"].values[-1]),
            "cycles_simulated": int(ds.attrs["cycles_simulated"]),
            "worn_volume_m3": float(ds["worn_volume"].values[-1]),
            "max_wear_depth_m": float(ds["wear_depth"].isel(cycle=-1).max()),
            "crossland_first": float(fc["maximum"].values[0]),
            "crossland_last": float(fc["maximum"].values[-1]),
            "crossland_last_x3_m": float(fc["maximum_x3"].values[-1]),
            "crossland_last_x1_m": float(fc["maximum_x1"].values[-1])}


def write_table(rows, path):
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()}
                    for r in rows)
    return path


def figure(rows, cycles):
    x = [r["delta_ratio"] for r in rows]
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    ax.plot(x, [r["crossland_first"] for r in rows], "o--", color="0.5",
            label="first cycle (unworn)")
    ax.plot(x, [r["crossland_last"] for r in rows], "o-", color="C3",
            label=f"end of life ({cycles:,} cycles)")
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    ax.axvline(1.0, color="0.7", lw=0.8)
    ax.set_xlabel("δ*/δ_gs (partial slip < 1 < gross slip)")
    ax.set_ylabel("peak Crossland index")
    ax.set_xscale("log")
    ax2 = ax.twinx()
    ax2.plot(x, [r["worn_volume_m3"] * 1e9 for r in rows], "s:", color="C0", ms=4,
             label="worn volume")
    ax2.set_ylabel("worn volume at end of life [mm³]", color="C0")
    lines = ax.get_legend_handles_labels()
    more = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="upper left")
    ax.set_title(f"wear against cracking: steel on steel, μ = {c.MU}, W = {c.W:g} N, "
                 f"Archard k = {K_ARCHARD:g} 1/Pa", fontsize=9)
    return fig


def main(argv=None):
    p = c.parser(__doc__.splitlines()[0], __doc__)
    p.add_argument("--cycles", type=int, default=None, help="cycles of the life")
    p.add_argument("--scheduler", default=None,
                   help="dask scheduler address, or 'synchronous' (default: a LocalCluster)")
    args = p.parse_args(argv)
    out = c.out_dir(args)
    n, steps = (16, 8) if args.quick else (32, 16)
    cycles = args.cycles or (1000 if args.quick else 100_000)
    ratios = RATIOS_QUICK if args.quick else RATIOS
    folder = out / "wear_vs_cracking"
    t0 = time.perf_counter()
    res = cp.sweep(base_scene(n, steps, cycles), {"delta_ratio": ratios}, folder,
                   scheduler=args.scheduler, progress=False)
    wall = time.perf_counter() - t0
    if not res.ok:
        raise RuntimeError(f"{len(res.failed)} members failed: {res.failed[0]}")
    with cp.open_sweep(folder) as sw:
        digest = {round(float(v), 12): str(d) for v, d in
                  zip(sw["delta_ratio"].values, sw["digest"].values, strict=True)}
    rows = [member_row(r, folder / f"{digest[round(r, 12)]}.nc") for r in ratios]
    table = write_table(rows, out / "wear_vs_cracking.csv")
    png = out / "wear_vs_cracking.png"
    c.save_figure(figure(rows, cycles), png)
    print(f"wear against cracking: {len(rows)} amplitudes on {n}^2, {steps} steps a cycle, "
          f"{cycles:,} cycles, sweep {wall:.1f} s")
    print(f"{'δ*/δ_gs':>8} {'simulated':>9} {'volume mm³':>11} {'depth µm':>9} "
          f"{'Crossland first':>15} {'end of life':>11} {'at x3 µm':>8}")
    for r in rows:
        print(f"{r['delta_ratio']:>8.2f} {r['cycles_simulated']:>9} "
              f"{r['worn_volume_m3'] * 1e9:>11.4g} {r['max_wear_depth_m'] * 1e6:>9.3g} "
              f"{r['crossland_first']:>15.4f} {r['crossland_last']:>11.4f} "
              f"{r['crossland_last_x3_m'] * 1e6:>8.1f}")
    return {"png": png, "csv": table, "folder": folder, "rows": rows}


if __name__ == "__main__":
    main(sys.argv[1:])
