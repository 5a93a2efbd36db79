"""The paper's figure-3 case through the stress and fatigue stages.

A rigid ball (R = 18 mm) on a Maxwell half-space (glassy E = 105 GPa, nu = 0.3, t' = 1 s)
under W = 1 kN and the fretting program T: 0 -> +T* -> -T* -> +T* (T* = 0.9 mu W,
mu = 0.1) over the window tau = t', with the paper's frictionless initial normal solve
(as studies/fig3_maxwell.py). The archive's tractions go through
``cp.subsurface_stress`` (every instant, depths 0 to 1.2 a_H) and the stress history over
the fretting cycle (t/tau from 0.2, the first +T*, to 1, back at +T*) through
``cp.fatigue``: Crossland and Dang Van, with illustrative fatigue limits of a hardened
steel (fully reversed bending f_-1 = 600 MPa, torsion t_-1 = 400 MPa; the indices are
relative, the stresses of a 2 GPa Hertz contact are far above any such limit near the
surface). Smith-Watson-Topper is left out: it needs the elastic strain, and the Maxwell
body's strain is not sigma/E.

With a constant Poisson ratio the stresses due to given tractions are the elastic ones,
so the viscoelasticity enters only through the tractions the solver found.

    python studies/stress_fig3.py [--out DIR] [--quick]

Default: 128 x 128 cells on the automatic grid, 100 steps, 16 depths; writes
``stress_fig3.nc`` (the archive) and ``stress_fig3.png`` in --out and copies the figure
to docs/figures/stress_fig3.png (the stress field itself, 101 instants x 16 depths x 128^2
x 7 variables, is 0.5 GB even in float32: ``contactpipe stress`` writes it when wanted).
--quick: 24 x 24 cells, 10 steps, 5 depths, nothing written outside --out.
"""
from __future__ import annotations

import shutil
import sys
import time

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import numpy as np

import contactpipe as cp
from contactpipe.pipeline.figures.stress import plot_stress_section, plot_stress_surface

BENDING_LIMIT = 600e6      # f_-1 [Pa], illustrative
TORSION_LIMIT = 400e6      # t_-1 [Pa], illustrative
CYCLE_START = 0.2          # t/tau of the first +T*


def run(out, n, steps, depths_over_a):
    scene = c.maxwell_fretting_scene(n=n, steps=steps, window=c.RELAXATION_TIME,
                                     name="stress-fig3", preload="frictionless")
    ds, wall = c.run(scene, c.fresh(out / "stress_fig3.nc"))
    ds = ds.load()
    tau = scene.load.window
    t = ds["time"].values
    depths = depths_over_a * c.A_H
    t0 = time.perf_counter()
    st = cp.subsurface_stress(ds, depths, time=float(t[-1]))         # at +T*, t = tau
    t_stress = time.perf_counter() - t0
    # the cycle, lazily: one depth at a time goes through the criteria (bounded memory)
    cycle_times = [float(v) for v in t if v >= CYCLE_START * tau - 1e-9]
    cycle = cp.subsurface_stress(ds, depths, time=cycle_times, chunks={"x3": 1})
    t0 = time.perf_counter()
    cross = cp.fatigue(cycle, "crossland", torsion_limit=TORSION_LIMIT,
                       bending_limit=BENDING_LIMIT)
    dv = cp.fatigue(cycle, "dang_van", torsion_limit=TORSION_LIMIT,
                    bending_limit=BENDING_LIMIT)
    t_fatigue = time.perf_counter() - t0
    return scene, ds, st, cross, dv, {"simulate_s": wall, "stress_s": t_stress,
                                      "stress_and_fatigue_s": t_fatigue,
                                      "cycle_instants": len(cycle_times)}


def describe(ds, st, cross, dv, times):
    n = ds.sizes["x1"]
    vm = st["von_mises"]
    k = np.unravel_index(int(np.argmax(vm.values)), vm.shape)
    at = {d: float(vm[d].values[i]) for d, i in zip(vm.dims, k, strict=True)}
    info = {
        "grid": n, "instants": ds.sizes["time"], "depths": st.sizes["x3"],
        "von_mises_max_over_pH": float(vm.values[k]) / c.P_H,
        "von_mises_max_x1_over_aH": at["x1"] / c.A_H,
        "von_mises_max_x3_over_aH": at["x3"] / c.A_H,
        "von_mises_max_t": at["time"],
        "crossland_max": float(cross["maximum"]),
        "crossland_x1_over_aH": float(cross["maximum_x1"]) / c.A_H,
        "crossland_x3_over_aH": float(cross["maximum_x3"]) / c.A_H,
        "dang_van_max": float(dv["maximum"]),
        "dang_van_x1_over_aH": float(dv["maximum_x1"]) / c.A_H,
        "dang_van_x3_over_aH": float(dv["maximum_x3"]) / c.A_H,
        **times,
    }
    print(f"{n}x{n} cells, {info['instants']} instants, {info['depths']} depths "
          f"(0 to {float(st['x3'].max()) / c.A_H:.2f} a_H); simulate {times['simulate_s']:.1f} s, "
          f"stress at t = tau {times['stress_s']:.1f} s, stress and two criteria over the "
          f"{times['cycle_instants']} instants of the cycle {times['stress_and_fatigue_s']:.1f} "
          "s (busy machine: indicative)")
    print(f"  largest von Mises at t = tau {info['von_mises_max_over_pH']:.3f} p_H at x1 = "
          f"{info['von_mises_max_x1_over_aH']:+.2f} a_H, x3 = "
          f"{info['von_mises_max_x3_over_aH']:.2f} a_H, t = {at['time']:.3g} s")
    print(f"  Crossland index max {info['crossland_max']:.3f} at x1 = "
          f"{info['crossland_x1_over_aH']:+.2f} a_H, x3 = {info['crossland_x3_over_aH']:.2f} a_H;"
          f" Dang Van index max {info['dang_van_max']:.3f} at x1 = "
          f"{info['dang_van_x1_over_aH']:+.2f} a_H, x3 = {info['dang_van_x3_over_aH']:.2f} a_H")
    return info


def figure(st, cross, dv, tau):
    from matplotlib.figure import Figure
    fig = Figure(figsize=(12.5, 8.2), dpi=110)
    axes = fig.subplots(2, 2)
    plot_stress_section(st, "von_mises", time=tau, ax=axes[0, 0])
    plot_stress_surface(st, "s11", time=tau, ax=axes[0, 1])
    plot_stress_section(cross, ax=axes[1, 0])
    plot_stress_section(dv, ax=axes[1, 1])
    titles = ["(a) von Mises, x1-x3 plane through the centre, t = tau (+T*)",
              "(b) surface s11, t = tau (+T*)",
              "(c) Crossland index over the cycle (f_-1 = 600, t_-1 = 400 MPa)",
              "(d) Dang Van index over the cycle (same limits)"]
    for ax, title in zip(axes.ravel(), titles, strict=True):
        ax.set_title(title, fontsize=9)
    fig.suptitle("Rigid ball on a Maxwell half-space (paper fig. 3, tau = t'): stresses and "
                  "fatigue indices", fontsize=11)
    fig.tight_layout()
    return fig


def main(argv=None):
    args = c.parser(__doc__.splitlines()[0], __doc__).parse_args(argv)
    out = c.out_dir(args)
    if args.quick:
        n, steps, depths = 24, 10, np.array([0.0, 0.1, 0.3, 0.6, 1.0])
    else:
        n, steps, depths = 128, 100, np.concatenate([[0.0], np.linspace(0.05, 1.2, 15)])
    scene, ds, st, cross, dv, times = run(out, n, steps, depths)
    info = describe(ds, st, cross, dv, times)
    png = c.save_figure(figure(st, cross, dv, scene.load.window), out / "stress_fig3.png")
    if not args.quick:
        docs = c.HERE.parent / "docs" / "figures" / "stress_fig3.png"
        shutil.copyfile(png, docs)
        print(f"wrote {docs}")
    return {"png": png, "summary": info}


if __name__ == "__main__":
    main(sys.argv[1:])
