"""Speed against accuracy: error against the closed forms versus wall time.

Cases (each measured against its closed form):

``hertz``
    Steel ball on steel, W = 1 kN, one instant, grid over 3 a_H. Errors: the peak
    pressure against p0 (``hertz_p0``), the radius from the contact area against a
    (``hertz_a``), the approach against a^2/R (``hertz_approach``).
``md``
    The paper's elastic fretting loop (figure 2) over 3 a_H. Errors against
    Mindlin-Deresiewicz: the stick radius sqrt(stick area / pi), worst over the instants,
    relative to a (``md_stick``; in cells in the column ``md_stick_cells``), the shear
    traction along x1 through the centre over mu p0 leaving out the cells within 1.5 cells
    of a stick/slip circle (``md_traction``), the energy dissipated in the full cycle
    (``md_energy``) and the T-omega1 loop (``md_loop``); ``md_traction_mean`` is the mean
    of the traction error over the cells of the line inside the contact, worst instant.
    The kink-excluded maximum does not converge below about 0.3-0.5 % of mu p0: its worst
    cell is the first one kept next to a stick/slip circle, and the error there is fixed
    in cell units; the mean converges. No memory: the time rule plays no part.
``lr_step``, ``lr_ramp``, ``lr_zener``
    Rigid ball on a viscoelastic half-space (E = 105 GPa, nu = 0.3), auto-sized grid,
    frictionless, window 2 s: Maxwell (t' = 1 s) under a step load; Maxwell under a load
    ramped 0 -> W over t' and held (the time rule matters: the step-start rule is first
    order); Zener (E_inf = E0/3, retardation time 0.5 s) under the same ramp (phi is not
    linear in t, so even the linear rule has a time error). Error: a(t)^3 against
    Lee-Radok's hereditary integral, a = sqrt(R omega3), worst over t >= 0.25 s (all t for
    the step load) (``lr_a3``). The time rules ``solver.time_rule`` = "auto" (the rule
    the presets are measured with: "linear" where it is monotone, else "bdf2"; its rows
    repeat the resolved rule's run), "bdf2" (second order, L-stable), "linear" (second
    order, A-stable) and "step_start" (the paper's rectangle rule).

``lr_kv``, ``lr_zener100``
    Creep laws with little instantaneous elasticity, under the ramp of ``lr_ramp``:
    Kelvin-Voigt (tau = 1 s, E the long-term modulus) and Zener E0/Einf = 100 (tau = 1 s).
    "auto" takes "bdf2" for them; they give the presets' "bdf2" column of steps per
    retardation time (``lr_kv_a3``, ``lr_zener100_a3``).

``vf``
    Viscoelastic fretting, the paper's figure-3 case (rigid ball on Maxwell, tau = t'),
    on one grid (48^2 auto; 24^2 with --quick): there is no closed form, so the error is
    against the same grid run with 4 times the largest step count (640 steps by default)
    and the linear rule: the T-omega1 loop (``vf_loop``), the shear and the pressure along
    x1 through the centre (RMS over the line, worst instant, over mu p_H and p_H:
    ``vf_traction``, ``vf_pressure``). Every time rule. This is where the steps per cycle
    matter: the elastic loop is rate independent (its errors do not change with the
    steps once the mesh hits the turning points).

Grids 16^2 to 256^2 in steps of sqrt(2) in N (16, 24, 32, 48, 64, 96, 128, 192, 256; 384^2
and 512^2 with --full), steps 5, 10, 20, 40, 160 (and 640 with --full; multiples of 5 so that
the mesh hits the turning points of the fretting program); by default 192^2 and 256^2 run
only up to 40 steps (md) and 10 steps (Lee-Radok) to keep the run to a few minutes.
``--grids``, ``--steps`` and ``--cases`` choose other sets.

"Cells across the contact diameter" is 2 a / d with a the largest contact radius of the
window (a_H for the elastic cases, a(2 s) for Lee-Radok); "steps per cycle" counts the
steps of one full tangential cycle (the fretting window holds 1.25 cycles); "steps per
relaxation time" counts them per t' (Maxwell) or per retardation time (Zener).

    python studies/speed_accuracy.py [--out DIR] [--quick] [--full]

Writes ``speed_accuracy.csv`` and ``speed_accuracy.nc`` (the table: one row per run and
error measure), ``speed_accuracy.png`` (error against wall time, log-log, one panel per
measure, the Pareto front highlighted), ``accuracy_presets.json`` (cells across the
contact and steps per cycle / per relaxation time that reach the targets of the presets
fast, balanced and accurate), and prints the recommendation.

Wall times are measured around ``cp.simulate`` (time spent collecting results in the
``on_step`` callback subtracted); on a shared machine they vary by a factor of 2 or more
from run to run, so the FFT pairs (deterministic) are recorded too.
"""
from __future__ import annotations

import csv
import json
import math
import sys
import time

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.ticker import NullFormatter

import contactpipe as cp
from contactpipe.materials import kelvin_voigt as kelvin_voigt_creep
from contactpipe.materials import maxwell as maxwell_creep
from contactpipe.materials import zener as zener_creep
from contactpipe.solver.memory import resolve_rule

GRIDS = (16, 24, 32, 48, 64, 96, 128, 192, 256)
GRIDS_FULL = GRIDS + (384, 512)
STEPS, STEPS_FULL = (5, 10, 20, 40, 160), (5, 10, 20, 40, 160, 640)
#: "auto" first: its runs repeat those of the rule it resolves to (not run twice)
RULES = ("auto", "bdf2", "linear", "step_start")
#: the time rule the presets are measured with (the package's recommended rule)
PRESET_RULE = "auto"
CASES = ("hertz", "md", "lr_step", "lr_ramp", "lr_zener", "lr_kv", "lr_zener100", "vf")
VF_GRID, VF_GRID_QUICK = 48, 24
VF_REF_FACTOR = 4
#: default: the largest grid only with few steps (the run stays within minutes)
DEFAULT_LIMIT = {"md": {192: 40, 256: 40}, "lr_step": {192: 10, 256: 10},
                 "lr_ramp": {192: 10, 256: 10}, "lr_zener": {192: 10, 256: 10},
                 "lr_kv": {192: 40, 256: 10}, "lr_zener100": {192: 40, 256: 10}}
PRESETS = {"fast": 0.05, "balanced": 0.01, "accurate": 0.002}
#: the measures each preset's target applies to
PRESET_MEASURES = {"md": ("md_stick", "md_traction_mean", "md_energy"),
                   "vf": ("vf_loop", "vf_traction", "vf_pressure")}
LR_WINDOW = 2.0
ZENER = {"relaxed_young": c.E_GLASSY / 3, "retardation_time": 0.5}
#: creep laws with little instantaneous elasticity (their own preset column), ramped
STIFF_TAU = 1.0
STIFF = {"lr_kv": {"creep": "kelvin_voigt", "retardation_time": STIFF_TAU},
         "lr_zener100": {"creep": "zener", "relaxed_young": c.E_GLASSY / 100,
                         "retardation_time": STIFF_TAU}}
MEASURE_LABEL = {
    "hertz_p0": "Hertz: peak pressure p0",
    "hertz_a": "Hertz: contact radius (area)",
    "hertz_approach": "Hertz: approach",
    "md_stick": "M-D: stick radius / a",
    "md_traction": "M-D: shear traction / μp0 (max, kinks out)",
    "md_traction_mean": "M-D: shear traction / μp0 (mean)",
    "md_energy": "M-D: energy per cycle",
    "md_loop": "M-D: T–ω1 loop",
    "lr_step_a3": "Lee–Radok, Maxwell step: a³",
    "lr_ramp_a3": "Lee–Radok, Maxwell ramp: a³",
    "lr_zener_a3": "Lee–Radok, Zener ramp: a³",
    "lr_kv_a3": "Lee–Radok, Kelvin–Voigt ramp: a³",
    "lr_zener100_a3": "Lee–Radok, Zener E0/E∞ = 100 ramp: a³",
    "vf_loop": "Maxwell fretting τ=t′: T–ω1 loop (vs ref.)",
    "vf_traction": "Maxwell fretting τ=t′: q RMS / μp_H (vs ref.)",
    "vf_pressure": "Maxwell fretting τ=t′: p RMS / p_H (vs ref.)",
}


# --------------------------------------------------------------------------- scenes
def hertz_scene(n):
    return cp.Scene(name="sa-hertz", geometry={"shape": "sphere", "radius": c.R},
                    indenter=dict(c.STEEL), halfspace=dict(c.STEEL),
                    load={"time": [0.0], "normal_force": c.W},
                    grid={"points": [n, n], "size": [3 * c.A_H, 3 * c.A_H]})


def lr_scene(case, n, steps, rule):
    if case == "lr_step":
        load = {"time": [0.0, LR_WINDOW], "normal_force": c.W}
    else:
        load = {"time": [0.0, 1.0, LR_WINDOW], "normal_force": [0.0, c.W, c.W]}
    if case in STIFF:
        half = {"material": "viscoelastic", "young": c.E_GLASSY, "poisson": c.NU_STEEL,
                **STIFF[case]}
    elif case == "lr_zener":
        half = {"material": "viscoelastic", "young": c.E_GLASSY, "poisson": c.NU_STEEL,
                "creep": "zener", **ZENER}
    else:
        half = c.maxwell()
    return cp.Scene(name=f"sa-{case}", geometry={"shape": "sphere", "radius": c.R},
                    indenter=dict(c.RIGID), halfspace=half, load=load,
                    grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                    solver={"time_rule": rule, "tolerance": 1e-10},
                    output={"stride": steps})


def lr_creep(case):
    if case == "lr_kv":
        return kelvin_voigt_creep(STIFF_TAU)
    if case == "lr_zener100":
        return zener_creep(c.E_GLASSY, STIFF[case]["relaxed_young"], STIFF_TAU)
    if case == "lr_zener":
        return zener_creep(c.E_GLASSY, ZENER["relaxed_young"], ZENER["retardation_time"])
    return maxwell_creep(c.RELAXATION_TIME)


def characteristic_time(case):
    if case in STIFF:
        return STIFF_TAU
    return ZENER["retardation_time"] if case == "lr_zener" else c.RELAXATION_TIME


# --------------------------------------------------------------------------- runs
class SeriesCollector:
    """Keeps the scalar series of each instant (on_step), nothing of the fields."""

    def __init__(self):
        self.s = {}
        self.seconds = 0.0

    def __call__(self, k, t, rec):
        t0 = time.perf_counter()
        self.s.setdefault("time", []).append(t)
        for key in ("omega3", "fft_pairs", "iterations", "W"):
            self.s.setdefault(key, []).append(float(rec[key]))
        self.seconds += time.perf_counter() - t0


def run_hertz(n):
    scene = hertz_scene(n)
    ds, wall = c.run(scene)
    p = np.asarray(ds.p.values[-1])
    a_num = math.sqrt(float(ds.contact_area[-1]) / math.pi)
    d = float(ds.x1[1] - ds.x1[0])
    row = dict(case="hertz", grid=n, cells_across=2 * c.A_H / d, steps=0,
               steps_per_unit=math.nan, unit="", time_rule="n/a", wall_s=wall,
               fft_pairs=int(np.sum(ds.fft_pairs.values)),
               iterations=int(np.sum(ds.iterations.values)))
    errs = {"hertz_p0": abs(p.max() / c.P_H - 1), "hertz_a": abs(a_num / c.A_H - 1),
            "hertz_approach": abs(float(ds.omega3[-1]) / c.HERTZ.approach - 1)}
    return row, errs


def run_md(n, steps):
    scene = c.fretting_scene(n=n, steps=steps, name="sa-md", output={"stride": steps})
    col = c.MDCollector(scene)
    ds, wall = c.run(scene, on_step=col)
    wall -= col.seconds
    d = float(ds.x1[1] - ds.x1[0])
    e = c.md_errors(col, scene, mu=c.MU, W=c.W, a=c.A_H, p0=c.P_H,
                    compliance=c.COMPLIANCE_STEEL, every=max(1, steps // 40))
    # the window holds 5 time units: a quarter cycle up to +T*, then one cycle of 4
    row = dict(case="md", grid=n, cells_across=2 * c.A_H / d, steps=steps,
               steps_per_unit=steps * 4 / 5, unit="cycle", time_rule="n/a",
               wall_s=wall, fft_pairs=int(np.sum(col.series["fft_pairs"])),
               iterations=int(np.sum(col.series["iterations"])),
               md_stick_cells=e["stick_cells"])
    errs = {"md_stick": e["stick_rel"], "md_traction": e["traction"],
            "md_traction_mean": e["traction_mean"], "md_energy": e["energy"],
            "md_loop": e["loop"]}
    return row, errs


def run_lr(case, n, steps, rule):
    scene = lr_scene(case, n, steps, rule)
    col = SeriesCollector()
    ds, wall = c.run(scene, on_step=col)
    wall -= col.seconds
    L = scene.resolved_grid_size()[0]
    d = L / n
    creep = lr_creep(case)
    tk, Wk = (scene.load.knots()[0], scene.load.knots()[1])
    if case == "lr_step":
        lt, lw, t_min = [0.0], [c.W], 0.0
    else:
        lt, lw, t_min = list(tk), list(Wk), 0.25
    young = c.E_GLASSY
    t = np.array(col.s["time"])
    err = c.lee_radok_a3_error(t, col.s["omega3"], lt, lw, c.R, young, c.NU_STEEL, creep,
                               t_min=t_min)
    a_max = float(c.an.lee_radok_radius(LR_WINDOW, lt, lw, c.R, young, c.NU_STEEL, creep))
    row = dict(case=case, grid=n, cells_across=2 * a_max / d, steps=steps,
               steps_per_unit=steps * characteristic_time(case) / LR_WINDOW,
               unit=("retardation time" if case == "lr_zener" or case in STIFF
                     else "relaxation time"),
               time_rule=rule, wall_s=wall, fft_pairs=int(np.sum(col.s["fft_pairs"])),
               iterations=int(np.sum(col.s["iterations"])))
    return row, {f"{case}_a3": err}


_VF_REF = {}


def _vf_collect(n, steps, rule):
    scene = c.maxwell_fretting_scene(n=n, steps=steps, window=c.RELAXATION_TIME,
                                     solver={"time_rule": rule}, output={"stride": steps},
                                     name="sa-vf")
    col = c.MDCollector(scene)
    ds, wall = c.run(scene, on_step=col)
    return scene, col, wall - col.seconds


def run_vf(n, steps, rule, ref_steps):
    if (n, ref_steps) not in _VF_REF:
        t0 = time.perf_counter()
        _VF_REF[(n, ref_steps)] = _vf_collect(n, ref_steps, "linear")[1]
        print(f"       (vf reference: {n}^2, {ref_steps} steps, linear rule, "
              f"{time.perf_counter() - t0:.1f} s)", flush=True)
    ref = _VF_REF[(n, ref_steps)]
    scene, col, wall = _vf_collect(n, steps, rule)
    f = ref_steps // steps
    om, om_r = np.array(col.series["omega1"]), np.array(ref.series["omega1"])[::f]
    q, q_r = np.array(col.q).mean(axis=2), np.array(ref.q)[::f].mean(axis=2)
    p, p_r = np.array(col.p).mean(axis=2), np.array(ref.p)[::f].mean(axis=2)
    rms = lambda a: float(np.sqrt(np.mean(a ** 2, axis=1)).max())          # noqa: E731
    L = scene.resolved_grid_size()[0]
    a_max = float(c.an.lee_radok_radius(c.RELAXATION_TIME, [0.0], [c.W], c.R, c.E_GLASSY,
                                        c.NU_STEEL, maxwell_creep(c.RELAXATION_TIME)))
    row = dict(case="vf", grid=n, cells_across=2 * a_max / (L / n), steps=steps,
               steps_per_unit=steps / 1.25, unit="cycle (= 0.8 relaxation time)",
               time_rule=rule, wall_s=wall, fft_pairs=int(np.sum(col.series["fft_pairs"])),
               iterations=int(np.sum(col.series["iterations"])))
    errs = {"vf_loop": float(np.abs(om - om_r).max() / np.abs(om_r).max()),
            "vf_traction": rms(q - q_r) / (c.MU * c.P_H),
            "vf_pressure": rms(p - p_r) / c.P_H}
    return row, errs


def plan_runs(args):
    grids = tuple(args.grids) if args.grids else (GRIDS_FULL if args.full else GRIDS)
    steps = tuple(args.steps) if args.steps else (STEPS_FULL if args.full else STEPS)
    cases = tuple(args.cases) if args.cases else CASES
    limited = not (args.full or args.grids or args.steps)
    if args.quick:
        grids = tuple(args.grids) if args.grids else (16, 32)
        steps = tuple(args.steps) if args.steps else (10, 40)
    todo = []
    for case in cases:
        if case == "hertz":
            todo += [("hertz", n, 0, "n/a") for n in grids]
            continue
        if case == "vf":
            n = VF_GRID_QUICK if args.quick else VF_GRID
            todo += [("vf", n, s, r) for s in steps for r in RULES]
            continue
        for n in grids:
            for s in steps:
                cap = DEFAULT_LIMIT.get(case, {}).get(n)
                if limited and cap is not None and s > cap:
                    continue
                if args.quick and case != "md" and n > 24:
                    continue
                if case == "md":
                    todo.append((case, n, s, "n/a"))
                else:   # the step-start rule: refused for Kelvin-Voigt, unstable for Zener 100
                    todo += [(case, n, s, r) for r in RULES
                             if not (case in STIFF and r == "step_start")]
    return todo


def resolved_rule(case, steps, rule):
    """The rule "auto" applies to the case's creep function at its step (the others as
    given): an "auto" run equal to a measured one is not run twice."""
    if rule != "auto" or case in ("hertz", "md"):
        return rule
    window = c.RELAXATION_TIME if case == "vf" else LR_WINDOW
    creep = maxwell_creep(c.RELAXATION_TIME) if case == "vf" else lr_creep(case)
    return resolve_rule(creep, window / steps, "auto")


def execute(todo):
    rows = []
    vf_ref = VF_REF_FACTOR * max([s for case, _, s, _ in todo if case == "vf"] or [0])
    done = {}
    for i, (case, n, s, rule) in enumerate(todo):
        concrete = resolved_rule(case, s, rule)
        if (case, n, s, concrete) in done:
            row, errs = done[(case, n, s, concrete)]
            row = {**row, "time_rule": rule}
        elif case == "hertz":
            row, errs = run_hertz(n)
        elif case == "vf":
            row, errs = run_vf(n, s, rule, vf_ref)
        elif case == "md":
            row, errs = run_md(n, s)
        else:
            row, errs = run_lr(case, n, s, rule)
        done[(case, n, s, concrete)] = (row, errs)
        for measure, e in errs.items():
            rows.append({**row, "measure": measure, "error": float(e)})
        shown = ", ".join(f"{k} {v:.2e}" for k, v in errs.items())
        print(f"[{i + 1}/{len(todo)}] {case:8s} {n:4d}^2 {s:4d} steps {rule:10s} "
              f"{row['wall_s']:7.2f} s  {row['fft_pairs']:7d} pairs  {shown}", flush=True)
    return rows


# --------------------------------------------------------------------------- analysis
def pareto(points):
    """Indices of the non-dominated (wall, error) points, by increasing wall time."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def cheapest(rows, measures, target, rule=None, case=None):
    """The cheapest (wall time) run whose errors in ``measures`` are all <= target."""
    runs = {}
    for r in rows:
        if r["measure"] not in measures or (rule and r["time_rule"] not in (rule, "n/a")):
            continue
        if case and r["case"] != case:
            continue
        key = (r["case"], r["grid"], r["steps"], r["time_rule"])
        runs.setdefault(key, {"row": r, "errors": {}})["errors"][r["measure"]] = r["error"]
    def within(v):
        return (len(v["errors"]) == len(measures)
                and all(np.isfinite(e) and e <= target for e in v["errors"].values()))

    def robust(key, v):
        # no lucky cancellation: every finer grid and longer mesh measured reaches it too
        case, n, s, rule = key
        return all(within(w) for (c2, n2, s2, r2), w in runs.items()
                   if c2 == case and r2 == rule and n2 >= n and s2 >= s)

    ok = [v for key, v in runs.items() if within(v) and robust(key, v)]
    if not ok:
        return None
    return min(ok, key=lambda v: (v["row"]["wall_s"]))


def best_for(rows, measure, rule=None):
    sel = [r for r in rows if r["measure"] == measure
           and (rule is None or r["time_rule"] in (rule, "n/a")) and np.isfinite(r["error"])]
    return min(sel, key=lambda r: r["error"]) if sel else None


def _run_info(best, measures):
    r = best["row"]
    return {"grid": r["grid"], "steps": r["steps"], "cells_across": round(r["cells_across"], 1),
            "steps_per_unit": r["steps_per_unit"], "wall_s": round(r["wall_s"], 3),
            "errors": {m: best["errors"][m] for m in measures}}


def presets(rows):
    """Cells across the contact and steps per cycle / relaxation time of each preset.

    For each target: the cheapest measured run (robust: every finer grid and longer mesh
    measured reaches it too) of each group of measures, with the time rule PRESET_RULE:

    - cells across the contact diameter: the largest of the elastic loop's (stick radius,
      traction mean, energy) and the Lee-Radok cases' (a^3);
    - steps per cycle: the viscoelastic fretting case's (loop, traction, pressure against
      its reference), at least the elastic loop's;
    - steps per relaxation time: the largest of the Lee-Radok cases' and the viscoelastic
      fretting case's (its window is one relaxation time);
    - the "bdf2" columns (a body whose memory takes "bdf2": little instantaneous
      elasticity under "auto"): steps per retardation time from the Kelvin-Voigt and
      Zener E0/Einf = 100 ramps (``lr_kv``, ``lr_zener100``; at least the plain column),
      steps per cycle from the viscoelastic fretting case with the "bdf2" rule.
    """
    out = {}
    lr_cases = sorted({r["case"] for r in rows if r["case"].startswith("lr_")})
    for name, target in PRESETS.items():
        entry = {"target": target, "time_rule": PRESET_RULE}
        notes, cells, per_cycle, per_relax, per_relax_bdf2 = [], [], [], [], []
        md = cheapest(rows, PRESET_MEASURES["md"], target)
        if md:
            cells.append(md["row"]["cells_across"])
            per_cycle.append(md["row"]["steps_per_unit"])
            entry["elastic_loop"] = _run_info(md, PRESET_MEASURES["md"])
        elif any(r["case"] == "md" for r in rows):
            notes.append(f"elastic loop: {', '.join(PRESET_MEASURES['md'])} not all within "
                         f"{target:g} on any grid/steps measured")
        vf = cheapest(rows, PRESET_MEASURES["vf"], target, rule=PRESET_RULE, case="vf")
        if vf:
            per_cycle.append(vf["row"]["steps_per_unit"])
            per_relax.append(vf["row"]["steps"])      # window = one relaxation time
            entry["viscoelastic_fretting"] = _run_info(vf, PRESET_MEASURES["vf"])
        elif any(r["case"] == "vf" for r in rows):
            notes.append(f"viscoelastic fretting: not within {target:g} with the steps "
                         f"measured")
        lr_runs = {}
        for case in lr_cases:
            m = f"{case}_a3"
            lr = cheapest(rows, (m,), target, rule=PRESET_RULE, case=case)
            if lr:
                lr_runs[case] = _run_info(lr, (m,))
                cells.append(lr["row"]["cells_across"])
                (per_relax_bdf2 if case in STIFF else per_relax).append(
                    lr["row"]["steps_per_unit"])
            else:
                notes.append(f"{case}: a^3 not within {target:g} on any grid/steps measured")
        entry["lee_radok"] = lr_runs
        for other in RULES:                              # the other rules, for information
            if other == PRESET_RULE:
                continue
            ss = {}
            for case in lr_cases + (["vf"] if any(r["case"] == "vf" for r in rows) else []):
                ms = PRESET_MEASURES["vf"] if case == "vf" else (f"{case}_a3",)
                r = cheapest(rows, ms, target, rule=other, case=case)
                ss[case] = None if r is None else _run_info(r, ms)
            entry[f"{other}_rule"] = ss
        entry["cells_across_contact"] = int(math.ceil(round(max(cells), 6))) if cells else None
        entry["steps_per_cycle"] = int(math.ceil(round(max(per_cycle), 6))) if per_cycle else None
        entry["steps_per_relaxation"] = (int(math.ceil(round(max(per_relax), 6))) if per_relax
                                         else None)
        if per_relax_bdf2:
            entry["steps_per_relaxation_bdf2"] = int(math.ceil(round(max(
                per_relax_bdf2 + per_relax), 6)))
        vf2 = cheapest(rows, PRESET_MEASURES["vf"], target, rule="bdf2", case="vf")
        if vf2:
            entry["steps_per_cycle_bdf2"] = int(math.ceil(round(max(
                [vf2["row"]["steps_per_unit"]] + per_cycle), 6)))
        entry["reached"] = not notes
        if notes:
            entry["notes"] = notes
        out[name] = entry
    return out


def recommendation(rows):
    lines = []
    for target in (0.05, 0.01, 0.002):
        lines.append(f"target {target:.1%}:")
        for measure in ("md_stick", "md_traction", "md_traction_mean", "md_energy", "hertz_p0",
                        "hertz_a", "lr_step_a3", "lr_ramp_a3", "lr_zener_a3", "lr_kv_a3",
                        "lr_zener100_a3", "vf_loop",
                        "vf_traction", "vf_pressure"):
            if not any(r["measure"] == measure for r in rows):
                continue
            for rule in (RULES if measure[:3] in ("lr_", "vf_")
                         else (None,)):
                best = cheapest(rows, (measure,), target, rule=rule)
                what = MEASURE_LABEL[measure] + (f" ({rule} rule)" if rule else "")
                if best is None:
                    b = best_for(rows, measure, rule)
                    if b is None:                 # the rule did not run for this case
                        continue
                    lines.append(f"  {what}: not reached (best {b['error']:.2%} at "
                                 f"{b['cells_across']:.0f} cells across, {b['steps']} steps)")
                    continue
                r = best["row"]
                step_txt = ("" if r["case"] == "hertz" else
                            f" and {r['steps_per_unit']:.0f} steps per {r['unit']}")
                lines.append(f"  {what}: at least {r['cells_across']:.0f} cells across the "
                             f"contact diameter ({r['grid']}^2){step_txt} -> "
                             f"{best['errors'][measure]:.2%} in {r['wall_s']:.2f} s")
    return "\n".join(lines)


# --------------------------------------------------------------------------- output
def write_table(rows, out):
    keys = ["case", "measure", "grid", "cells_across", "steps", "steps_per_unit", "unit",
            "time_rule", "wall_s", "fft_pairs", "iterations", "error", "md_stick_cells"]
    path = out / "speed_accuracy.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in keys})
    print(f"wrote {path}")
    cols = {}
    for k in keys:
        vals = [r.get(k, math.nan if k == "md_stick_cells" else "") for r in rows]
        cols[k] = ("run", np.array(vals))
    ds = xr.Dataset(cols)
    units = {"cells_across": "1", "wall_s": "s", "error": "1", "grid": "1", "steps": "1",
             "steps_per_unit": "1", "fft_pairs": "1", "iterations": "1",
             "md_stick_cells": "1"}
    for k, u in units.items():
        ds[k].attrs["units"] = u
    ds["error"].attrs["long_name"] = "relative error against the closed form"
    ds.attrs["title"] = "contactpipe study: speed against accuracy"
    ds.attrs["contactpipe_version"] = cp.__version__
    nc = out / "speed_accuracy.nc"
    ds.to_netcdf(nc)
    print(f"wrote {nc}")
    return path, nc


def plot(rows, out):
    measures = [m for m in MEASURE_LABEL if any(r["measure"] == m for r in rows)]
    ncol = 5 if len(measures) > 9 else 3
    nrow = int(math.ceil(len(measures) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.5 * nrow), squeeze=False)
    grids = sorted({r["grid"] for r in rows})
    cmap = plt.cm.viridis(np.linspace(0, 0.9, len(grids)))
    color = dict(zip(grids, cmap, strict=True))
    marker = {"auto": "*", "bdf2": "D", "linear": "o", "step_start": "s", "n/a": "o"}
    for ax, m in zip(axes.flat, measures, strict=False):
        sel = [r for r in rows if r["measure"] == m and np.isfinite(r["error"])]
        floor = 1e-16
        pts = [(r["wall_s"], max(r["error"], floor)) for r in sel]
        for r, (w, e) in zip(sel, pts, strict=True):
            ax.scatter(w, e, color=color[r["grid"]], marker=marker[r["time_rule"]],
                       s=14 + 6 * math.log2(max(r["steps"], 1) + 1),
                       facecolors="none" if r["time_rule"] == "step_start" else None,
                       zorder=2)
        front = pareto(pts)
        if front:
            fx = [pts[i][0] for i in front]
            fy = [pts[i][1] for i in front]
            ax.step(fx, fy, where="post", color="crimson", lw=1.4, zorder=3)
            ax.scatter(fx, fy, s=70, facecolors="none", edgecolors="crimson", lw=1.3,
                       zorder=4)
            for i in front:
                r = sel[i]
                lab = f"{r['grid']}²" + (f"/{r['steps']}" if r["steps"] else "")
                ax.annotate(lab, pts[i], textcoords="offset points", xytext=(4, 3),
                            fontsize=6.5, color="crimson")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.tick_params(labelsize=7)
        ax.set_title(MEASURE_LABEL[m], fontsize=9)
        ax.set_xlabel("wall time [s]", fontsize=8)
        ax.set_ylabel("relative error", fontsize=8)
        ax.grid(True, which="major", color="0.9")
        for t in PRESETS.values():
            ax.axhline(t, color="0.7", lw=0.7, ls=":")
    for ax in axes.flat[len(measures):]:
        ax.axis("off")
    handles = [plt.Line2D([], [], ls="", marker="o", color=color[g], label=f"{g}²")
               for g in grids]
    handles += [plt.Line2D([], [], ls="", marker="*", color="k", label="auto rule"),
                plt.Line2D([], [], ls="", marker="D", color="k", label="bdf2 rule"),
                plt.Line2D([], [], ls="", marker="o", color="k", label="linear rule / elastic"),
                plt.Line2D([], [], ls="", marker="s", mfc="none", color="k",
                           label="step-start rule"),
                plt.Line2D([], [], color="crimson", label="Pareto front (grid²/steps)"),
                plt.Line2D([], [], color="0.7", ls=":", label="preset targets 5 %, 1 %, 0.2 %")]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 5), fontsize=8,
               bbox_to_anchor=(0.5, -0.04))
    fig.suptitle("Error against the closed form versus wall time (marker size: steps)",
                 fontsize=11)
    fig.tight_layout(rect=(0, 0.03, 1, 0.97))
    return c.save_figure(fig, out / "speed_accuracy.png")


def main(argv=None):
    p = c.parser(__doc__.splitlines()[0], __doc__)
    p.add_argument("--full", action="store_true",
                   help="add 512^2 and 640 steps and every combination (long)")
    p.add_argument("--grids", type=int, nargs="+", help="grid sizes N (N x N)")
    p.add_argument("--steps", type=int, nargs="+", help="step counts (multiples of 5)")
    p.add_argument("--cases", nargs="+", choices=CASES, help="cases to run")
    args = p.parse_args(argv)
    out = c.out_dir(args)
    todo = plan_runs(args)
    print(f"{len(todo)} runs (OPENBLAS_NUM_THREADS = {c.blas_threads()})")
    t0 = time.perf_counter()
    rows = execute(todo)
    print(f"total {time.perf_counter() - t0:.1f} s")
    csv_path, nc = write_table(rows, out)
    png = plot(rows, out)
    pre = presets(rows)
    pre_path = out / "accuracy_presets.json"
    with open(pre_path, "w") as f:
        json.dump({"description": (
            f"Accuracy presets measured by studies/speed_accuracy.py ({PRESET_RULE} time rule). "
            "For each target, the cheapest measured run whose errors are all within it "
            "(and stay within it on every finer grid and longer mesh measured). "
            "cells_across_contact: the largest contact diameter over the cell size, the "
            "largest needed by the elastic fretting loop against Mindlin-Deresiewicz (stick "
            "radius / a, traction mean / mu p0, energy per cycle) and by Lee-Radok a^3 "
            "(Maxwell step and ramp, Zener ramp). steps_per_cycle: per full tangential "
            "cycle, from the viscoelastic fretting loop (rigid ball on Maxwell, tau = t') "
            "against a 4x finer time mesh (loop, traction and pressure RMS), at least the "
            "elastic loop's. steps_per_relaxation: per relaxation (retardation) time, the "
            "largest needed by the Lee-Radok cases and the viscoelastic fretting loop. "
            "steps_per_relaxation_bdf2, steps_per_cycle_bdf2: the same where a body's "
            "memory takes the rule bdf2 (Kelvin-Voigt and Zener E0/Einf = 100 ramps; the "
            "fretting loop with bdf2)."),
            "presets": pre}, f, indent=2, default=float)
    print(f"wrote {pre_path}")
    print("\nRecommendation (cheapest measured run reaching each target):")
    print(recommendation(rows))
    print("\nPresets:")
    for name, e in pre.items():
        print(f"  {name:9s} target {e['target']:.1%}: {e['cells_across_contact']} cells across "
              f"the contact, {e['steps_per_cycle']} steps per cycle, "
              f"{e['steps_per_relaxation']} steps per relaxation time; with bdf2 "
              f"{e.get('steps_per_cycle_bdf2')} per cycle, "
              f"{e.get('steps_per_relaxation_bdf2')} per relaxation time"
              + ("" if e["reached"] else "  (NOT all reached: " + "; ".join(e["notes"]) + ")"))
    return {"csv": csv_path, "nc": nc, "png": png, "presets": pre_path, "rows": rows}


if __name__ == "__main__":
    main(sys.argv[1:])
