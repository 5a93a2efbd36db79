"""Subsurface stress: cost per depth, wall time for 40 depths x 40 instants, and Tamaas.

    python benchmarks/bench_stress.py [--n 128] [--depths 40] [--instants 40] [--no-tamaas]

Tractions: the solver's Hertz pressure (steel sphere R = 18 mm on steel, W = 1 kN,
128^2 cells over 4a), with a shear q1 = 0.09 p sin(2 pi k / K) over K instants (a
fretting-like history; the cost does not depend on the values). Depths 0 to 2a.

Printed (figures, not assertions; the machine is shared with other work, so wall times
are indicative only, FFT counts are exact):

1. transforms per instant and depth: forward transforms (one per non-zero traction
   component, shared by every depth of an instant) and inverse transforms (one per stress
   component and depth), as FFT pairs (forward + inverse = 1 pair) per depth;
2. the one-off cost of the depth spectra (closed-form kernels + 15 real FFTs per depth,
   cached per grid, nu and depth) and the wall time of 40 depths x 40 instants at 128^2,
   computed in memory, and streamed to a netCDF file through dask (lazy, block by block);
3. Tamaas (optional extra ``bench``: ``pip install tamaas``), if importable: its volume
   operators (``boussinesq_gradient`` then ``hooke``; periodic, so the tractions are laid
   on a zero-padded 2n x 2n grid, the padding DC-FFT uses) on the same tractions and
   depths, one instant: the largest difference per component over the n x n grid,
   relative to p0, and the time ratio. Tamaas works on point values of a periodic field
   (spectral), contactpipe on cell-wise constant tractions (DC-FFT, non-periodic), so
   the fields differ near the surface (cell-scale detail) and by the periodic images.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings

import numpy as np


def hertz_tractions(n, instants):
    import contactpipe as cp
    nu, R, W = 0.3, 0.018, 1000.0
    e_star = 1.0 / (2 * (1 - nu ** 2) / 210e9)
    a = (3 * W * R / (4 * e_star)) ** (1 / 3)
    p0 = 3 * W / (2 * np.pi * a ** 2)
    steel = {"material": "elastic", "young": 210e9, "poisson": nu}
    scene = cp.Scene(name="bench-stress", geometry={"shape": "sphere", "radius": R},
                     indenter=steel, halfspace=steel,
                     load={"time": [0.0, 1.0], "normal_force": W},
                     grid={"points": [n, n], "size": [4 * a, 4 * a]}, time={"steps": 1})
    base = cp.simulate(scene, progress=False)
    p = base["p"].values[-1]
    k = np.arange(instants)
    amp = 0.09 * np.sin(2 * np.pi * k / instants)
    import xarray as xr
    ds = xr.Dataset({"p": (("time", "x1", "x2"), np.broadcast_to(p, (instants,) + p.shape)),
                     "q1": (("time", "x1", "x2"), amp[:, None, None] * p[None]),
                     "q2": (("time", "x1", "x2"), np.zeros((instants,) + p.shape))},
                    coords={"time": k * 1.0, "x1": base["x1"].values,
                            "x2": base["x2"].values}, attrs=base.attrs)
    return ds, a, p0


def transforms(ds, depths):
    from contactpipe.solver.subsurface import SubsurfaceOperator
    n1, n2 = ds.sizes["x1"], ds.sizes["x2"]
    d = float(ds["x1"][1] - ds["x1"][0])
    op = SubsurfaceOperator(n1, n2, d, d, 0.3)
    for z in depths:                          # spectra first: not counted as solver work
        op.spectra(z)
    conv = op.conv
    conv.reset_counts()
    k = ds.sizes["time"] // 4                 # an instant with shear
    specs = op.traction_spectra({t: ds[t].values[k] for t in ("p", "q1", "q2")})
    for z in depths:
        op.stress(specs, z)
    f, i = conv.forward_count, conv.inverse_count
    nz = len(depths)
    print(f"1. transforms for one instant at {nz} depths ({n1}x{n2}, padded "
          f"{2 * n1}x{2 * n2}): {f} forward (p and q1; q2 = 0 costs none), {i} inverse "
          f"({i // nz} per depth): {(f + i) / 2 / nz:.3f} FFT pairs per depth and instant "
          f"(-> {i / 2 / nz:.1f} with many depths)")


def wall_times(ds, depths):
    from contactpipe.post.stress import save_stress, subsurface_stress
    from contactpipe.solver.subsurface import SubsurfaceOperator, clear_cache
    n1, n2 = ds.sizes["x1"], ds.sizes["x2"]
    d = float(ds["x1"][1] - ds["x1"][0])
    clear_cache()
    op = SubsurfaceOperator(n1, n2, d, d, 0.3)
    _ = op.conv                               # FFTW plans made here, outside the timings
    t0 = time.perf_counter()
    for z in depths:
        op.spectra(z)
    t_spec = time.perf_counter() - t0
    t0 = time.perf_counter()
    st = subsurface_stress(ds, depths, time="all", chunks=False)
    t_eager = time.perf_counter() - t0
    nt, nz = ds.sizes["time"], len(depths)
    print(f"2. {nz} depths x {nt} instants at {n1}x{n2}: depth spectra {t_spec:.2f} s once "
          f"({t_spec / nz * 1e3:.0f} ms per depth, cached); stresses in memory {t_eager:.2f} s "
          f"({t_eager / (nz * nt) * 1e3:.2f} ms per depth and instant, spectra cached), "
          f"{st.nbytes / 2 ** 20:.0f} MiB of results")
    clear_cache()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        lazy = subsurface_stress(ds, depths, time="all", chunks={"time": 4})
        save_stress(lazy, os.path.join(tmp, "st.nc"), precision="float32")
        t_lazy = time.perf_counter() - t0
    print(f"   streamed to netCDF through dask (blocks of 4 instants x {nz} depths, float32, "
          f"spectra recomputed from an empty cache): {t_lazy:.2f} s")
    return st, t_eager / nt


def tamaas_side_by_side(ds, depths, a, p0, ours_per_instant):
    try:
        import tamaas as tm
    except ImportError as err:
        print(f"3. Tamaas not importable ({err}); pip install tamaas (optional extra 'bench')")
        return
    from contactpipe.post.stress import subsurface_stress
    from contactpipe.solver.subsurface import COMPONENTS
    n = ds.sizes["x1"]
    d = float(ds["x1"][1] - ds["x1"][0])
    k = ds.sizes["time"] // 4                     # an instant with shear
    ours = subsurface_stress(ds, depths, time=float(ds["time"][k]))
    for pad in (2, 4):
        m = pad * n
        nz = len(depths)
        step = depths[1] - depths[0]
        model = tm.ModelFactory.createModel(tm.model_type.volume_2d,
                                            [step * (nz - 1), m * d, m * d], [nz, m, m])
        model.E, model.nu = 210e9, 0.3
        tm.ModelFactory.registerVolumeOperators(model)
        tr = np.zeros((m, m, 3))
        o = (m - n) // 2
        for c, name in enumerate(("q1", "q2", "p")):
            tr[o:o + n, o:o + n, c] = ds[name].values[k]
        grad = np.zeros((nz, m, m, 6))
        sig = np.zeros((nz, m, m, 6))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            model.operators["boussinesq_gradient"](tr, grad)     # warm-up (plans)
            t0 = time.perf_counter()
            model.operators["boussinesq_gradient"](tr, grad)
            model.operators["hooke"](grad, sig)
            t_tm = time.perf_counter() - t0
        # Tamaas stores [11, 22, 33, 12, 13, 23] with sqrt(2) on the shear (Mandel)
        scale = np.array([1, 1, 1, 2 ** -0.5, 2 ** -0.5, 2 ** -0.5])
        mine = np.stack([ours[c].values[0] for c in COMPONENTS], -1)      # (nz, n, n, 6)
        theirs = sig[:, o:o + n, o:o + n, :] * scale
        err = np.abs(theirs - mine).max(axis=(1, 2)) / p0                  # (nz, 6)
        deep = depths >= 0.25 * a
        print(f"3. Tamaas {tm.__version__}, periodic {m}x{m} (tractions on the central "
              f"{n}x{n}), {nz} depths, one instant: {t_tm:.2f} s, contactpipe "
              f"{ours_per_instant:.2f} s: time ratio Tamaas/contactpipe "
              f"{t_tm / ours_per_instant:.2f}")
        print("   largest |difference| / p0 over the grid, per component, x3 >= 0.25a "
              "(and at x3 = 0):")
        for j, c in enumerate(COMPONENTS):
            print(f"     {c}: {err[deep, j].max():.2e}   (surface {err[0, j]:.2e})")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=128)
    parser.add_argument("--depths", type=int, default=40)
    parser.add_argument("--instants", type=int, default=40)
    parser.add_argument("--no-tamaas", action="store_true")
    args = parser.parse_args(argv)
    ds, a, p0 = hertz_tractions(args.n, args.instants)
    depths = np.linspace(0.0, 2.0, args.depths) * a
    print(f"machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} (shared: "
          "wall times indicative)")
    transforms(ds, depths)
    _, per_instant = wall_times(ds, depths)
    if not args.no_tamaas:
        tamaas_side_by_side(ds, depths, a, p0, per_instant)
    return 0


if __name__ == "__main__":
    sys.exit(main())
