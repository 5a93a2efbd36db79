"""Figure 3 of the paper: contact tractions of a rigid ball on a Maxwell half-space.

The loads of figure 1 (W = 1 kN stepped at t = 0, T: 0 -> +T* -> -T* -> +T*,
T* = 0.9 mu W, mu = 0.1) act on a rigid sphere (R = 18 mm) pressed into a Maxwell
half-space, phi(t) = 1 + t/t' (t' = 1 s), whose glassy modulus (E = 105 GPa, nu = 0.3)
gives the instantaneous composite modulus of the steel pair: at t = 0 the contact is the
elastic one of figure 2 (p_H = 1.996 GPa, a_H = 0.489 mm). Two windows: (a) tau = t',
(b) tau = 2 t'. The half-space is compressible (nu = 0.3) and the indenter rigid, so
the normal and tangential problems couple (Dundurs beta = 0.29) and the middle loop runs.
As in the paper, the normal load is applied first by a frictionless normal solve (its
outer loop, step 1: ``load.preload = "frictionless"``), so the contact holds no shear at
t = 0. (With the package's default, ``"frictional"``, friction acts during the
indentation and this coupled pair is left with Spence's antisymmetric shear at t = 0;
``--frictional-preload`` draws that variant.)

While the material creeps the contact grows (Lee-Radok: a^3 grows as phi(t)) and the
pressure flattens; the shear follows the fretting program on the growing contact. The
longer window creeps further, so at the same t/tau its pressure is lower and wider and
its shear spreads further out. The grey dashed line is Lee-Radok's frictionless
pressure at t = tau (the coupling with the shear is not in it).

    python studies/fig3_maxwell.py [--out DIR] [--quick]

Default: 128 x 128 cells on the automatic grid (grid.size = "auto": 3 a_max from a Hertz
estimate with the most compliant phi over the window), 200 steps per window (quick:
24 x 24, 10 steps). Writes ``fig3_maxwell_tau1.nc``, ``fig3_maxwell_tau2.nc`` and
``fig3_maxwell.png``, and prints what each run measured.
"""
from __future__ import annotations

import sys

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import matplotlib.pyplot as plt
import numpy as np

from contactpipe import analytic as an
from contactpipe.materials import maxwell as maxwell_creep
from contactpipe.testing import contact_law_violations

INSTANTS = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)
WINDOWS = (1.0, 2.0)           # tau / t'
PRELOAD = ["frictionless"]     # the paper's initial normal solve (--frictional-preload: not)


def run_window(out, ratio, n, steps):
    tau = ratio * c.RELAXATION_TIME
    scene = c.maxwell_fretting_scene(n=n, steps=steps, window=tau,
                                     name=f"fig3-maxwell-tau{ratio:g}",
                                     preload=PRELOAD[0])
    path = c.fresh(out / f"fig3_maxwell_tau{ratio:g}.nc")
    ds, wall = c.run(scene, path)
    ds = ds.load()
    bad = contact_law_violations(ds)
    if bad:
        raise AssertionError(f"tau = {ratio:g} t': contact laws violated: " + "; ".join(bad))
    nonfinite = c.all_finite(ds)
    if nonfinite:
        raise AssertionError(f"tau = {ratio:g} t': NaN/inf in {nonfinite}")
    return scene, path, ds, wall


def describe(scene, ds, wall, ratio):
    x1, x2, d1, d2 = c.grid_of(ds)
    n1 = len(x1)
    p = np.asarray(ds.p.values)
    inside = p.any(axis=2)                                    # (time, N1)
    first = np.argmax(inside, axis=1)
    last = n1 - 1 - np.argmax(inside[:, ::-1], axis=1)
    margin = int(min(first.min(), (n1 - 1 - last).min()))     # cells to the grid edge
    a_end = np.sqrt(float(ds.contact_area[-1]) / np.pi)
    tau = scene.load.window
    a_lr = float(an.lee_radok_sphere(tau, c.W, c.R, c.E_GLASSY, c.NU_STEEL,
                                     maxwell_creep(c.RELAXATION_TIME)).contact_radius)
    a_om = np.sqrt(c.R * float(ds.omega3[-1]))
    eW, eT = c.force_errors(ds, scene)
    pairs = np.asarray(ds.fft_pairs.values)
    stick = np.asarray(ds.stick_area.values) / np.asarray(ds.contact_area.values)
    info = {"tau_ratio": ratio, "grid": n1, "steps": ds.sizes["time"] - 1,
            "side_mm": (x1[-1] - x1[0] + d1) * 1e3, "margin_cells": margin,
            "a_end_over_aH": a_end / c.A_H, "a_end_lee_radok_over_aH": a_lr / c.A_H,
            "a_omega3_err": abs(a_om ** 3 / a_lr ** 3 - 1),
            "p_max_end_over_pH": float(p[-1].max() / c.P_H), "wall_s": wall,
            "fft_pairs_per_step": float(pairs[1:].mean()),
            "coupling_passes": float(np.mean(ds.coupling_passes.values[1:])),
            "force_W": eW, "force_T": eT, "stick_fraction_end": float(stick[-1])}
    print(f"\ntau = {ratio:g} t': {n1}x{n1} cells over {info['side_mm']:.3f} mm (auto), "
          f"{info['steps']} steps, wall {wall:.1f} s, "
          f"{info['fft_pairs_per_step']:.0f} FFT pairs and "
          f"{info['coupling_passes']:.1f} coupling passes per step")
    print(f"  contact stays {margin} cells inside the grid edge; radius at t = tau "
          f"{info['a_end_over_aH']:.3f} a_H from the area, {a_om / c.A_H:.3f} a_H from the "
          f"approach (Lee-Radok {info['a_end_lee_radok_over_aH']:.3f} a_H, a^3 off by "
          f"{info['a_omega3_err']:.2%})")
    print(f"  peak pressure at t = tau {info['p_max_end_over_pH']:.3f} p_H; stick fraction "
          f"at +T* (t = tau) {info['stick_fraction_end']:.2f}; load carried: W {eW:.1e}, "
          f"T {eT:.1e} (of W)")
    if max(eW, eT) > 1e-6:
        print(f"  WARNING: the reached force differs from the applied one by "
              f"{max(eW, eT):.2e} of W (a package defect; see studies/README.md)")
    return info


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--frictional-preload" in argv:
        argv.remove("--frictional-preload")
        PRELOAD[0] = "frictional"
    args = c.parser(__doc__.splitlines()[0], __doc__).parse_args(argv)
    out = c.out_dir(args)
    n, steps = (24, 10) if args.quick else (128, 200)
    runs = [run_window(out, r, n, steps) for r in WINDOWS]
    infos = [describe(sc, ds, wall, r) for r, (sc, _, ds, wall) in zip(WINDOWS, runs, strict=True)]

    fig, axes = plt.subplots(2, 2, figsize=(11.5, 7.6), sharex=True, sharey="row")
    colors = plt.cm.plasma(np.linspace(0, 0.85, len(INSTANTS)))
    xs = np.linspace(-2.0, 2.0, 801)
    creep = maxwell_creep(c.RELAXATION_TIME)
    for j, (ratio, (scene, _, ds, _)) in enumerate(zip(WINDOWS, runs, strict=True)):
        x1 = ds.x1.values
        t = ds.time.values
        tau = scene.load.window
        axp, axq = axes[0, j], axes[1, j]
        axp.plot(xs, c.HERTZ.pressure(np.abs(xs) * c.A_H) / c.P_H, color="0.7", lw=3,
                 label="Hertz (glassy, t = 0)")
        p_lr = an.lee_radok_pressure(np.abs(xs) * c.A_H, tau, c.W, c.R, c.E_GLASSY,
                                     c.NU_STEEL, creep, n_steps=400)
        axp.plot(xs, p_lr / c.P_H, "--", color="0.45", lw=1.5,
                 label=r"Lee-Radok, $t=\tau$ (frictionless)")
        for s, col in zip(INSTANTS, colors, strict=True):
            k = int(np.argmin(np.abs(t / tau - s)))
            p = c.centre_profile(ds.p.isel(time=k).values)
            q = c.centre_profile(ds.q1.isel(time=k).values)
            lab = rf"$t/\tau = {s:g}$"
            axp.plot(x1 / c.A_H, p / c.P_H, "-", lw=1.3, color=col, label=lab)
            axq.plot(x1 / c.A_H, q / c.P_H, "-", lw=1.3, color=col, label=lab)
        letter = "ab"[j]
        axp.set_title(f"({letter}) " + (r"$\tau = t'$" if ratio == 1 else
                                        rf"$\tau = {ratio:g}t'$")
                      + f"   ({len(x1)}$^2$ cells, {len(t) - 1} steps)")
        axq.set_xlabel(r"$x_1/a_H$ (through the centre; $|x_1|/a_H = r/a_H$)")
        for ax in (axp, axq):
            ax.axhline(0, color="0.85", lw=0.6)
            ax.set_xlim(-1.9, 1.9)
    axes[0, 0].set_ylabel(r"$p/p_H$")
    axes[1, 0].set_ylabel(r"$q_1/p_H$")
    axes[0, 1].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[1, 1].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle("Rigid ball on a Maxwell half-space (E = 105 GPa, ν = 0.3, t' = 1 s): "
                 "W = 1 kN step, T = ±0.9μW", fontsize=11)
    png = c.save_figure(fig, out / "fig3_maxwell.png")
    return {"png": png, "nc": [r[1] for r in runs], "summary": infos}


if __name__ == "__main__":
    main(sys.argv[1:])
