"""Shared pieces of the studies: the paper's constants and scenes, closed-form error
measures, and the command line. Only the public API of contactpipe is used
(``cp.Scene``, ``cp.simulate`` and :mod:`contactpipe.analytic`).

The paper's case (Spinu et al., section 5): a steel ball, R = 18 mm, pressed with a step
W = 1 kN on a steel half-space, mu = 0.1, then T: 0 -> +T* -> -T* -> +T* with
T* = 0.9 mu W, knots at t = 0, 0.2 tau, 0.6 tau, tau (the fretting preset, one cycle).
Hertz: p_H = 1.996 GPa, a_H = 0.489 mm. Viscoelastic case: a rigid sphere on a Maxwell
half-space, phi(t) = 1 + t/t', whose glassy modulus (E = 105 GPa, nu = 0.3) gives the
instantaneous composite modulus of the steel pair.

Units: SI (m, s, N, Pa, J).
"""
from __future__ import annotations

import argparse
import math
import os
import pathlib
import time

# One BLAS thread (unless the caller says otherwise), set before numpy loads: the solver's
# inner products (np.dot over the working set) go multithreaded in OpenBLAS above ~30 000
# cells, and on a small loaded machine the thread hand-off costs more than the FFTs: a
# 256^2 fretting run took 15.7 s with the default threads and 4.0 s with one (see
# studies/README.md, 'Findings'). Has no effect when numpy is already imported.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import matplotlib
import numpy as np  # noqa: E402

matplotlib.use("Agg")

import contactpipe as cp  # noqa: E402
from contactpipe import analytic as an  # noqa: E402

# --------------------------------------------------------------------------- constants
R = 0.018                    # sphere radius [m]
W = 1000.0                   # normal force [N]
MU = 0.1                     # friction coefficient [1]
AMPLITUDE = 0.9              # T* / (mu W)
T_STAR = AMPLITUDE * MU * W  # [N]
E_STEEL, NU_STEEL = 210e9, 0.3
STEEL = {"material": "elastic", "young": E_STEEL, "poisson": NU_STEEL}
RIGID = {"material": "rigid"}
E_GLASSY = 105e9             # Maxwell half-space under a rigid ball: same E* as steel/steel
RELAXATION_TIME = 1.0        # t' [s]
E_STAR = an.composite_modulus(E_STEEL, NU_STEEL, E_STEEL, NU_STEEL)
HERTZ = an.hertz_sphere(W, R, E_STAR)
A_H = HERTZ.contact_radius   # 0.489 mm
P_H = HERTZ.max_pressure     # 1.996 GPa
COMPLIANCE_STEEL = an.tangential_compliance_sum(E_STEEL, NU_STEEL, E_STEEL, NU_STEEL)

HERE = pathlib.Path(__file__).resolve().parent
DEFAULT_OUT = HERE / "output"


def maxwell(young=E_GLASSY, poisson=NU_STEEL, relaxation_time=RELAXATION_TIME):
    return {"material": "viscoelastic", "young": young, "poisson": poisson,
            "creep": "maxwell", "relaxation_time": relaxation_time}


# --------------------------------------------------------------------------- scenes
def fretting_scene(n=128, steps=40, *, indenter=STEEL, halfspace=STEEL, mu=MU,
                   amplitude=AMPLITUDE, window=1.0, cycles=1, size=3.0, W=W, name="fretting",
                   solver=None, output=None, preload=None, grid_check=True):
    """The paper's fretting program on an n x n grid.

    ``size`` is the grid side in units of the steel Hertz radius a_H, a pair of side
    lengths [m], or "auto". ``preload``: "frictional" (the package default: friction acts
    while W is applied) or "frictionless" (the paper's initial normal solve).
    ``grid_check=False``: a grid the estimated contact does not fit is left to the run
    (``grid.size_check = false``)."""
    if isinstance(size, (int, float)):
        size = [size * A_H, size * A_H]
    d = dict(name=name, geometry={"shape": "sphere", "radius": R},
             indenter=dict(indenter), halfspace=dict(halfspace), friction={"mu": mu},
             load={"normal_force": W,
                   "fretting": {"amplitude": amplitude * mu * W, "window": window,
                                "cycles": cycles}},
             grid={"points": [n, n], "size": size}, time={"steps": steps})
    if not grid_check:
        d["grid"]["size_check"] = False
    if preload:
        d["load"]["preload"] = preload
    if solver:
        d["solver"] = dict(solver)
    if output:
        d["output"] = dict(output)
    return cp.Scene(**d)


def maxwell_fretting_scene(n=128, steps=200, window=1.0, *, size="auto", mu=MU,
                           name="maxwell-fretting", **kw):
    """Rigid ball on the Maxwell half-space, the paper's loads over a window tau [s]."""
    return fretting_scene(n, steps, indenter=RIGID, halfspace=maxwell(), mu=mu,
                          window=window, size=size, name=name, **kw)


# --------------------------------------------------------------------------- measures
def grid_of(ds):
    x1, x2 = np.asarray(ds.x1.values), np.asarray(ds.x2.values)
    return x1, x2, float(x1[1] - x1[0]), float(x2[1] - x2[0])


def centre_rows(n2):
    """The two rows at x2 = -d/2 and +d/2 of an even grid (one row for an odd one)."""
    return [n2 // 2 - 1, n2 // 2] if n2 % 2 == 0 else [n2 // 2]


def centre_profile(field2d):
    """A (N1, N2) field along x1 through the centre: the mean of the middle rows."""
    return np.asarray(field2d)[:, centre_rows(np.shape(field2d)[1])].mean(axis=1)


def applied_program(scene, times=None):
    """(t, W, T1, T2) the scene asks for at its instants, or at ``times`` [s] (the
    instants an archive kept, with ``output.stride``)."""
    t, Wa, T1, T2 = scene.instants()
    if times is None:
        return t, Wa, T1, T2
    times = np.asarray(times, float)
    return (times,) + tuple(np.interp(times, t, v) for v in (Wa, T1, T2))


def force_errors(ds, scene):
    """Largest |reached - applied| of W and of T [N], relative to the applied W.

    The archive's W and T1 are sums of the tractions; the contact-law checker compares the
    tractions with those sums, so this is the check that the solve carried the load."""
    _, Wa, T1a, T2a = applied_program(scene, ds.time.values)
    Wr = np.asarray(ds.W.values, float)
    eW = float(np.max(np.abs(Wr - Wa)) / np.max(Wa))
    eT = 0.0
    if "T1" in ds:
        eT = float(max(np.max(np.abs(ds.T1.values - T1a)), np.max(np.abs(ds.T2.values - T2a)))
                   / np.max(Wa))
    return eW, eT


def all_finite(ds):
    """Names of the archive variables holding NaN or inf (empty when all finite)."""
    bad = []
    for name, v in ds.data_vars.items():
        a = np.asarray(v.values)
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            bad.append(name)
    return bad


def boundary_radii(history, mu, W, a):
    """Current and remembered stick/slip circles of the Mindlin-Deresiewicz solution [m]."""
    mem, cur = an.masing_memory(history)
    Ts = [0.0] + list(mem) + [cur]
    radii = [a]
    for i in range(1, len(Ts)):
        dT = abs(Ts[i] - Ts[i - 1]) / (1 if i == 1 else 2)
        radii.append(a * max(1 - dT / (mu * W), 0.0) ** (1 / 3))
    return radii


class MDCollector:
    """Collects, step by step (``simulate(on_step=...)``), what the Mindlin-Deresiewicz
    comparison needs: the centre rows of q1, T, stick area, omega1, dissipation.

    Keeps memory flat whatever the grid and the number of steps."""

    def __init__(self, scene):
        self.scene = scene
        self.rows = None
        self.q = []
        self.p = []
        self.series = {k: [] for k in ("T1", "stick_area", "contact_area", "omega1",
                                       "omega3", "dissipation", "fft_pairs", "iterations",
                                       "W")}
        self.seconds = 0.0

    def __call__(self, k, t, rec):
        t0 = time.perf_counter()
        p = rec["p"]
        if self.rows is None:
            self.rows = centre_rows(p.shape[1])
        self.p.append(np.array(p[:, self.rows]))
        self.q.append(np.array(rec["q1"][:, self.rows]) if "q1" in rec
                      else np.zeros((p.shape[0], len(self.rows))))
        for key, lst in self.series.items():
            lst.append(float(rec.get(key, 0.0)))
        self.seconds += time.perf_counter() - t0


def md_errors(collector_or_ds, scene, *, mu, W, a, p0, compliance, every=1):
    """Errors of a fretting run against Mindlin-Deresiewicz (beta = 0 pairs).

    Returns a dict:

    - ``traction``: max over the instants of |q1 - q1_MD| / (mu p0) along x1 through the
      centre (mean of the two middle rows against the cell-averaged closed form),
      leaving out cells within 1.5 cells of a current or remembered stick/slip circle
      (the square-root kink): the studies' centre-line measure (``contactpipe
      compare`` takes every cell: its ``err_q1_max``, ``err_q1_max_interior``);
    - ``traction_plain``, ``traction_rms``: the same over every cell, max and RMS;
    - ``traction_mean``: the mean of |q1 - q1_MD| / (mu p0) over the cells of the line
      inside the contact (|x1| < a), worst instant: converges with the grid, where the
      kink-excluded maximum stalls at a few tenths of a percent (its worst cell is the
      first one kept beside a stick/slip circle, a fixed number of cells away);
    - ``stick_cells``: max |c - c_MD| in cells, c = sqrt(stick area / pi), over t > 0;
    - ``stick_rel``: the same relative to a;
    - ``loop``: max |omega1 - omega1_MD| / max |omega1_MD|;
    - ``energy``: relative error of the energy dissipated from +T* round to +T* (the
      last full cycle), or NaN when the program has no full cycle.
    The applied program (not the reached force) is the closed form's history.
    """
    if isinstance(collector_or_ds, MDCollector):
        t, _, T1, _ = applied_program(scene)
        c = collector_or_ds
        q_rows = np.array(c.q)
        ser = {k: np.array(v) for k, v in c.series.items()}
        x1, x2 = (np.asarray(v) for v in scene.resolved_grid().coordinates())
    else:
        ds = collector_or_ds
        t, _, T1, _ = applied_program(scene, ds.time.values)
        x1, x2, _, _ = grid_of(ds)
        rows = centre_rows(len(x2))
        q_rows = np.asarray(ds.q1.values)[:, :, rows]
        ser = {k: np.asarray(ds[k].values, float) for k in
               ("stick_area", "omega1", "dissipation")}
    d1 = float(x1[1] - x1[0])
    d2 = float(x2[1] - x2[0])
    rows = centre_rows(len(x2))
    worst = plain = rms = mean = 0.0
    ks = list(range(0, len(t), every))
    if ks[-1] != len(t) - 1:
        ks.append(len(t) - 1)
    for k in ks:
        hist = T1[:k + 1]
        q = q_rows[k].mean(axis=1)
        ref = an.cell_average(
            lambda u, v, hist=hist: an.mindlin_deresiewicz_traction(np.hypot(u, v), hist, mu,
                                                                    W, a, p0),
            x1[:, None], x2[None, rows], d1, d2).mean(axis=1)
        r = np.hypot(x1, x2[rows[-1]])
        near = np.zeros(r.shape, bool)
        for circ in boundary_radii(hist, mu, W, a):
            near |= np.abs(r - circ) < 1.5 * d1
        e = np.abs(q - ref) / (mu * p0)
        if (~near).any():
            worst = max(worst, float(e[~near].max()))
        plain = max(plain, float(e.max()))
        rms = max(rms, float(np.sqrt(np.mean(e ** 2))))
        inside = np.abs(x1) < a
        if inside.any():
            mean = max(mean, float(e[inside].mean()))
    c_ex = np.array([an.stick_radius(T1[:k + 1], mu, W, a) for k in range(len(t))])
    c_num = np.sqrt(ser["stick_area"] / np.pi)
    dc = np.abs(c_num - c_ex)[1:]
    om_ex = an.tangential_displacement(T1, mu, W, a, compliance, all_instants=True)
    loop = float(np.abs(ser["omega1"] - om_ex).max() / max(np.abs(om_ex).max(), 1e-300))
    energy = math.nan
    Tmax = np.max(np.abs(T1))
    peaks = np.flatnonzero(np.isclose(T1, Tmax, rtol=1e-12, atol=0))
    if peaks.size >= 2:
        e_num = float(ser["dissipation"][peaks[-1]] - ser["dissipation"][peaks[-2]])
        e_ex = an.energy_per_cycle(Tmax, mu, W, a, compliance)
        energy = abs(e_num / e_ex - 1.0)
    return {"traction": worst, "traction_plain": plain, "traction_rms": rms,
            "traction_mean": mean,
            "stick_cells": float(dc.max() / d1), "stick_rel": float(dc.max() / a),
            "loop": loop, "energy": energy}


def lee_radok_a3_error(t, omega3, load_times, load_values, radius, young, poisson, creep,
                       t_min=0.0):
    """max |a^3 / a_LR^3 - 1| over t >= t_min, a = sqrt(R omega3) (Lee-Radok's geometric
    relation of the approach and the radius)."""
    t = np.asarray(t, float)
    a_num = np.sqrt(radius * np.clip(np.asarray(omega3, float), 0.0, None))
    a_ex = an.lee_radok_radius(t, load_times, load_values, radius, young, poisson, creep)
    m = (t >= t_min) & (a_ex > 0)
    return float(np.max(np.abs(a_num[m] ** 3 / a_ex[m] ** 3 - 1.0)))


# --------------------------------------------------------------------------- running
def blas_threads():
    """The OPENBLAS_NUM_THREADS in effect when the studies loaded (for the printout)."""
    return os.environ.get("OPENBLAS_NUM_THREADS", "default")


def run(scene, path=None, **kw):
    """simulate() with its wall time [s] measured around it: (ds, seconds)."""
    t0 = time.perf_counter()
    ds = cp.simulate(scene, path, **kw)
    return ds, time.perf_counter() - t0


def parser(description, doc=None):
    p = argparse.ArgumentParser(description=description, epilog=doc,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default=str(DEFAULT_OUT),
                   help="output folder (default: studies/output/)")
    p.add_argument("--quick", action="store_true",
                   help="small grids and few steps: a smoke test that runs in seconds")
    return p


def out_dir(args) -> pathlib.Path:
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return out


def save_figure(fig, path):
    path = pathlib.Path(path)
    fig.savefig(path, dpi=130, bbox_inches="tight")
    import matplotlib.pyplot as plt
    plt.close(fig)
    print(f"wrote {path}")
    return path


def fresh(path):
    """Remove an archive of a previous run so simulate() writes it anew."""
    path = pathlib.Path(path)
    if path.exists():
        os.remove(path)
    return path
