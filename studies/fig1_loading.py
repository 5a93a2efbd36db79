"""Figure 1 of the paper: the loading history.

The normal force W is stepped to 1 kN at t = 0 and held; the tangential force T then goes
0 -> +T* -> -T* -> +T* (T* = 0.9 mu W = 90 N) linearly, with knots at t/tau = 0, 0.2, 0.6
and 1, tau the length of the simulation window. The program is read from the scene's
fretting preset (``load.fretting``), the one every other study runs, and sampled on the
40-step mesh of figure 2 (marked). The instants shown in figures 2 and 3 (the turning
points and the zero crossings of T) are marked too.

    python studies/fig1_loading.py [--out DIR] [--quick]

Writes ``fig1_loading.png`` and ``fig1_loading.nc`` (the program on the mesh: time, W, T1).
"""
from __future__ import annotations

import sys

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

INSTANTS = (0.2, 0.4, 0.6, 0.8, 1.0)   # t/tau of the profiles in figures 2 and 3


def main(argv=None):
    args = c.parser(__doc__.splitlines()[0], __doc__).parse_args(argv)
    out = c.out_dir(args)
    steps = 10 if args.quick else 40
    scene = c.fretting_scene(n=16, steps=steps)
    tk, Wk, Tk, _ = scene.load.knots()
    t, Wm, Tm, _ = scene.instants()
    tau = scene.load.window

    fig, ax = plt.subplots(figsize=(6.2, 3.8))
    # W: zero before t = 0, stepped at t = 0
    ax.plot(np.r_[-0.05, 0.0, tk / tau], np.r_[0.0, 0.0, Wk / float(np.max(Wk))], color="k",
            lw=2, label=r"$W/W_0$")
    ax.plot(tk / tau, Tk / c.T_STAR, color="C0", lw=2, label=r"$T/T^*$")
    ax.plot(t / tau, Tm / c.T_STAR, "o", ms=3, color="C0", alpha=0.6,
            label=f"time mesh ({steps} steps)")
    for s in INSTANTS:
        ax.axvline(s, color="0.8", lw=0.8, zorder=0)
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(r"$t/\tau$")
    ax.set_ylabel("load / amplitude")
    ax.set_xlim(-0.05, 1.02)
    ax.set_ylim(-1.15, 1.25)
    ax.set_title(f"Loading history: W = {c.W / 1e3:g} kN step, "
                 f"T* = {c.AMPLITUDE:g} μW = {c.T_STAR:g} N")
    ax.legend(loc="lower left", fontsize=8)
    png = c.save_figure(fig, out / "fig1_loading.png")

    ds = xr.Dataset(
        {"W": ("time", Wm, {"units": "N", "long_name": "normal force"}),
         "T1": ("time", Tm, {"units": "N", "long_name": "tangential force along x1"})},
        coords={"time": ("time", t, {"units": "s"}),
                "t_norm": ("time", t / tau, {"units": "1", "long_name": "t / tau"})},
        attrs={"title": "contactpipe study: the paper's loading history (figure 1)",
               "scene": scene.to_toml()})
    nc = out / "fig1_loading.nc"
    ds.to_netcdf(nc)
    print(f"wrote {nc}")
    print("knots t/tau:", ", ".join(f"{v:g}" for v in tk / tau),
          "| T [N]:", ", ".join(f"{v:g}" for v in Tk), "| W [N]:", f"{Wk[0]:g} (step at t = 0)")
    return {"png": png, "nc": nc}


if __name__ == "__main__":
    main(sys.argv[1:])
