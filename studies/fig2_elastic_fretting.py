"""Figure 2 of the paper: the elastic fretting loop against the closed form.

Steel ball (R = 18 mm) on a steel half-space, W = 1 kN stepped at t = 0, mu = 0.1, then
T: 0 -> +T* -> -T* -> +T* with T* = 0.9 mu W (figure 1). Identical bodies: Dundurs
beta = 0, no normal-tangential coupling, so the pressure is Hertz's at every instant and
the shear follows Mindlin-Deresiewicz (Masing superposition of Cattaneo distributions).

The profiles are taken along x1 through the centre (the mean of the two middle rows,
x2 = +-d/2) and plotted as p/p_H and q1/p_H against x1/a_H at the paper's instants: the
turning points (t/tau = 0.2, 0.6, 1: T = +T*, -T*, +T*) and the zero crossings of T
(t/tau = 0.4, 0.8). The closed forms (Hertz, Mindlin-Deresiewicz) are the grey lines.

    python studies/fig2_elastic_fretting.py [--out DIR] [--quick]

Default: 128 x 128 cells over 3 a_H, 40 steps (quick: 32 x 32, 10 steps). Writes
``fig2_elastic_fretting.nc`` (the archive), ``fig2_elastic_fretting.png`` and prints the
error summary against the closed forms (measured as in tests/test_tangential.py).
"""
from __future__ import annotations

import sys

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import matplotlib.pyplot as plt
import numpy as np

from contactpipe import analytic as an
from contactpipe.pipeline.compare import compare
from contactpipe.testing import contact_law_violations

INSTANTS = (0.2, 0.4, 0.6, 0.8, 1.0)
LABELS = {0.2: r"$t/\tau=0.2$, $T=+T^*$", 0.4: r"$t/\tau=0.4$, $T=0$",
          0.6: r"$t/\tau=0.6$, $T=-T^*$", 0.8: r"$t/\tau=0.8$, $T=0$",
          1.0: r"$t/\tau=1$, $T=+T^*$"}


def hertz_errors(ds):
    """p0 and a of the archive's last instant against Hertz (relative)."""
    p = np.asarray(ds.p.isel(time=-1).values)
    a_num = np.sqrt(float(ds.contact_area[-1]) / np.pi)
    return {"p0": abs(p.max() / c.P_H - 1.0), "a": abs(a_num / c.A_H - 1.0),
            "approach": abs(float(ds.omega3[-1]) / c.HERTZ.approach - 1.0)}


def main(argv=None):
    args = c.parser(__doc__.splitlines()[0], __doc__).parse_args(argv)
    out = c.out_dir(args)
    n, steps = (32, 10) if args.quick else (128, 40)
    scene = c.fretting_scene(n=n, steps=steps, name="fig2-elastic-fretting")
    path = c.fresh(out / "fig2_elastic_fretting.nc")
    ds, wall = c.run(scene, path)
    ds = ds.load()
    bad = contact_law_violations(ds)
    if bad:
        raise AssertionError("contact laws violated: " + "; ".join(bad))
    nonfinite = c.all_finite(ds)
    if nonfinite:
        raise AssertionError(f"NaN/inf in {nonfinite}")
    eW, eT = c.force_errors(ds, scene)

    x1, x2, d1, d2 = c.grid_of(ds)
    t = ds.time.values
    tau = scene.load.window
    T_hist = scene.instants()[2]
    xs = np.linspace(-1.5, 1.5, 601)   # x1/a_H, fine, for the closed forms (x2 = 0)

    fig, (axp, axq) = plt.subplots(2, 1, figsize=(9.0, 7.6), sharex=True)
    axp.plot(xs, c.HERTZ.pressure(np.abs(xs) * c.A_H) / c.P_H, color="0.6", lw=3,
             label="Hertz")
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(INSTANTS)))
    for s, col in zip(INSTANTS, colors, strict=True):
        k = int(np.argmin(np.abs(t / tau - s)))
        hist = T_hist[:k + 1]
        q_md = an.mindlin_deresiewicz_traction(np.abs(xs) * c.A_H, hist, c.MU, c.W, c.A_H,
                                               c.P_H)
        axq.plot(xs, q_md / c.P_H, color="0.6", lw=3, zorder=1)
        p = c.centre_profile(ds.p.isel(time=k).values)
        q = c.centre_profile(ds.q1.isel(time=k).values)
        big = s == INSTANTS[0]          # +T* again at t/tau = 1: the same distribution
        axq.plot(x1 / c.A_H, q / c.P_H, "o-", ms=6 if big else 2.5, lw=0.8, color=col,
                 mfc="none" if big else col, label=LABELS[s], zorder=2)
        if s == INSTANTS[0]:
            axp.plot(x1 / c.A_H, p / c.P_H, "o", ms=2.5, color="k",
                     label="contactpipe (every instant: identical)")
    axq.plot([], [], color="0.6", lw=3, label="Mindlin-Deresiewicz")
    axp.set_ylabel(r"$p/p_H$")
    axq.set_ylabel(r"$q_1/p_H$")
    axq.set_xlabel(r"$x_1/a_H$ (along $x_1$ through the centre; $|x_1|/a_H = r/a_H$)")
    axp.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axq.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0),
               title="contactpipe (dots)", title_fontsize=8)
    for ax in (axp, axq):
        ax.axhline(0, color="0.8", lw=0.6)
        ax.set_xlim(-1.5, 1.5)
    axp.set_title(f"Elastic fretting loop, steel on steel: {n}x{n} cells over 3$a_H$, "
                  f"{steps} steps")
    png = c.save_figure(fig, out / "fig2_elastic_fretting.png")

    h = hertz_errors(ds)
    md = c.md_errors(ds, scene, mu=c.MU, W=c.W, a=c.A_H, p0=c.P_H,
                     compliance=c.COMPLIANCE_STEEL)
    pairs = np.asarray(ds.fft_pairs.values)
    summary = {"grid": n, "steps": steps, "wall_s": wall,
               "fft_pairs_per_step": float(pairs[1:].mean()),
               "fft_pairs_first": int(pairs[0]),
               "force_W": eW, "force_T": eT, **{f"hertz_{k}": v for k, v in h.items()},
               **{f"md_{k}": v for k, v in md.items()}}
    print(f"\nfigure 2, {n}x{n} over 3 a_H (d = {d1 * 1e6:.2f} um, "
          f"{2 * c.A_H / d1:.0f} cells across the contact diameter), {steps} steps:")
    print(f"  wall time {wall:.2f} s, FFT pairs per step {summary['fft_pairs_per_step']:.1f} "
          f"(first instant {pairs[0]})")
    print(f"  Hertz: p0 {h['p0']:.2%}, a (from the contact area) {h['a']:.2%}, "
          f"approach {h['approach']:.2%}")
    tb = compare(ds)
    q = {k: float(tb[k].max()) for k in ("err_q1_max", "err_q1_max_interior", "err_q1_rms")}
    summary.update({f"compare_{k}": v for k, v in q.items()})
    print(f"  Mindlin-Deresiewicz traction as `contactpipe compare` measures it: max "
          f"{q['err_q1_max']:.2%} of mu p0 over every cell and instant, "
          f"{q['err_q1_max_interior']:.2%} away from the stick/slip circles and the "
          f"contact edge, RMS {q['err_q1_rms']:.2%}")
    print(f"  (along x1 through the centre, kink cells excluded: {md['traction']:.2%}; "
          f"plain max {md['traction_plain']:.2%}, RMS {md['traction_rms']:.2%})")
    print(f"  stick radius within {md['stick_cells']:.2f} cells ({md['stick_rel']:.2%} of a), "
          f"loop {md['loop']:.2e}, energy per cycle {md['energy']:.2e}")
    print(f"  load carried: W {eW:.1e}, T {eT:.1e} (of W); contact laws hold at every step")
    return {"png": png, "nc": path, "summary": summary}


if __name__ == "__main__":
    main(sys.argv[1:])
