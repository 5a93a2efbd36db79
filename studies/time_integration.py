"""Time integration of the hereditary integral: stability, oscillation, order, and the
pressure field against Lee-Radok, for every creep law (issue 9; docs/time-integration.md).

Laws (normalised creep functions; tau = 1 s): Maxwell (t' = tau), Zener E0/Einf = 2 and
100, Kelvin-Voigt (no instantaneous elasticity), a 3-term Prony series with a dashpot
(c = 0.5, 1, 2 at 0.1, 1, 5 s; t' = 10 s). Rules and candidates:

``auto``         the package's recommended rule: "linear" where its error keeps its sign
                 for the creep function and step, else "bdf2"
``bdf2``         exponentially fitted BDF2 on the internal variables, two
                 exponential-Euler start steps after a jump at t0, one trapezoid otherwise
``bdf2_plain``   plain BDF2 started by two BDF1 steps (= BDF2 convolution quadrature)
``bdf2_1start``  the fitted rule with a single exponential-Euler start step
``linear``       traction linear within a step, exponentials integrated exactly
``linear_ds``    "linear" after one exponential-Euler step (a damped start)
``step_start``   the paper's rule (each increment at its step's start)
``tr_bdf2``      TR-BDF2 (gamma = 2 - sqrt 2; two solves per step): scalar model only

Parts, each printed as a table:

1. amplification factors of the traction error under a held displacement (the homogeneous
   error recursion, :func:`contactpipe.solver.memory.error_amplification`), and the
   step-start rule's largest stable step;
2. the held-displacement model problem (no contact): the traction for a smooth prescribed
   history H(t) = 1 - cos 2t + t/2, error against a 20 480-step run of the same rule and
   observed order (40 / 80 / 160 steps; TR-BDF2 at equal solves);
3. the Lee-Radok step load on a rigid sphere (R = 18 mm, W = 1 kN, E = 105 GPa, nu = 0.3,
   frictionless), through ``cp.simulate``: radius from the contact area (cells, t >= 0.25
   tau), holes (p = 0 inside 0.8 a), zigzag of the centre pressure, field error inside
   0.8 a (t >= 0.5 tau) against Lee-Radok p(r, t), a^3 from the approach; Kelvin-Voigt on
   the issue's 96^2 over 1.6 mm with 40 steps, Zener 100 on 96^2 auto with 20 steps (0.1
   tau), the others on 48^2 auto with 20 steps;
4. the pressure FIELD in dt: on the sphere of part 3 (96^2 auto; "bdf2" for Kelvin-Voigt
   and Zener 100, "linear" for the others), the successive differences at 20 / 40 / 80 /
   160 steps over the grid and inside 0.8 a; and the order on a rigid punch with a
   spherical face held in full contact (no cell enters or leaves), 16^2, W = 1 -> 1.5 kN,
   from 20 / 40 / 80 / 160 steps;
5. a varying Poisson ratio (shear creep, elastic bulk, nu0 = 0.3; Maxwell and the Prony
   series, 48^2, 20 steps): the Lee-Radok measures of part 3 with the normal compliance
   (1 - nu(t))/G(t), and the contact radius at 2 tau against constant nu;
6. the frictional preload (rigid on Maxwell, nu = 0.3, mu = 0.1, 32^2 and 64^2): the q
   field at t0 after n sub-steps against a 256-sub-step path, uniform fractions k/n
   against the graded (k/n)^2 the package uses, and the estimate it records.

    python studies/time_integration.py [--out DIR] [--quick]

Writes ``time_integration.csv`` (every measured row), ``time_integration.png`` (the
figure of docs/figures/) and prints the tables. ``--quick``: small grids, few steps, two
laws and three rules in parts 3-4, one law in part 5, 16^2 in part 6 (a smoke run of
seconds). The candidates that are not
rules of the package are memories built here and handed to ``cp.simulate`` by replacing
``contactpipe.simulation.problem.make_memory`` for the run (:func:`use_memory`).
"""
from __future__ import annotations

import contextlib
import csv
import math
import sys
import tempfile

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import matplotlib.pyplot as plt
import numpy as np

import contactpipe as cp
import contactpipe.simulation.problem as simulation_module
from contactpipe import analytic as an
from contactpipe.materials import step_start_stable_step
from contactpipe.solver import memory as mem
from contactpipe.testing import creep_laws, lee_radok_measures

E, NU, R, W = c.E_GLASSY, c.NU_STEEL, c.R, c.W
LAWS = creep_laws(E)
RULES = ("bdf2", "linear", "step_start")
CANDIDATES = ("auto", "bdf2", "bdf2_plain", "bdf2_1start", "linear", "linear_ds", "step_start")


# --------------------------------------------------------------------------- candidates
class _OneStart(mem.RecursiveMemory):
    """The fitted "bdf2" with a single exponential-Euler start step after a jump."""

    @property
    def start_steps(self):
        return 1 if self.start in ("linear", "exponential_euler") else mem.BDF2_START


class _DampedLinear(mem.RecursiveMemory):
    """"linear" after one exponential-Euler step (a damped start)."""

    def coefficients(self, k):
        if k == 1:
            x = self.dt / self.tau
            zero = np.zeros_like(self.tau)
            return (np.exp(-x), zero, zero, -np.expm1(-x)), (1.0, 0.0, 0.0, self.dt)
        return super().coefficients(k)


def candidate_memory(name):
    """make_memory's signature, for a candidate."""
    def make(creep, dt, rule, shape):
        if name == "bdf2_plain":
            return mem.RecursiveMemory(creep, dt, "bdf2", shape, fitted=False)
        if name == "bdf2_1start":
            return _OneStart(creep, dt, "bdf2", shape)
        if name == "linear_ds":
            return _DampedLinear(creep, dt, "linear", shape)
        return mem.make_memory(creep, dt, name, shape)
    return make


@contextlib.contextmanager
def use_memory(name):
    """cp.simulate with a candidate's memory (``contactpipe.simulation.problem.make_memory``)."""
    original = simulation_module.make_memory
    simulation_module.make_memory = candidate_memory(name)
    try:
        yield
    finally:
        simulation_module.make_memory = original


# --------------------------------------------------------------------------- 1: amplification
def amplification_rows(steps=(0.01, 0.1, 1.0, 10.0)):
    rows = []
    for law, (_, creep) in LAWS.items():
        for rule in ("step_start", "linear", "bdf2"):
            for dt in steps:
                try:
                    g = mem.error_amplification(creep, dt, rule)
                except ValueError:
                    rows.append(dict(part="amplification", law=law, rule=rule, dt=dt,
                                     value=math.nan, note="no weight"))
                    continue
                big = g[np.abs(g) > 1e-6]
                lead = big[0] if big.size else 0.0
                neg = big[big.real < 0]
                rows.append(dict(part="amplification", law=law, rule=rule, dt=dt,
                                 value=float(abs(lead)), signed=float(np.real(lead)),
                                 negative=float(np.abs(neg).max()) if neg.size else 0.0))
        rows.append(dict(part="bound", law=law, rule="step_start",
                         value=step_start_stable_step(creep),
                         small_step=_small_step_bound(creep)))
    return rows


def _small_step_bound(creep):
    rate = float(creep.derivative(0.0))
    return math.inf if rate <= 0 else 2.0 * creep.phi0 / rate


# --------------------------------------------------------------------------- 2: scalar model
def _history(t):
    return 1.0 - np.cos(2.0 * t) + 0.5 * t


def held_displacement(creep, steps, rule, t_end=2.0):
    """Tractions at the instants for the prescribed history H(t) (one solve per step)."""
    m = candidate_memory(rule)(creep, t_end / steps, rule, ())
    out = []
    for tk in np.linspace(0.0, t_end, steps + 1):
        w = m.instant_weight
        s = 0.0 if w == 0 else (_history(tk) - float(m.known())) / w
        m.commit(np.array(s))
        out.append(s)
    return np.array(out)


def tr_bdf2(creep, steps, t_end=2.0):
    """TR-BDF2 on (I, zeta_i) with the constraint phi0 s + b I + c.zeta = H at each stage."""
    g = 2.0 - math.sqrt(2.0)
    h = t_end / steps
    tau = np.asarray(creep.tau, float)
    cc, b, phi0 = -np.asarray(creep.d, float), float(creep.b), float(creep.phi0)
    z, i_, s = np.zeros_like(tau), 0.0, 0.0
    out = [s]
    A, B, C = 1.0 / (g * (2.0 - g)), (1.0 - g) ** 2 / (g * (2.0 - g)), (1.0 - g) / (2.0 - g)
    for k in range(steps):
        t = k * h
        q = g * h / 2.0                         # trapezoid stage to t + g h
        zk = (z * (1 - q / tau) + q / tau * s) / (1 + q / tau)   # + (q/tau)/(1+q/tau) s_g
        wz = (q / tau) / (1 + q / tau)
        ik, wi = i_ + q * s, q
        s_g = (_history(t + g * h) - b * ik - cc @ zk) / (phi0 + b * wi + cc @ wz)
        z_g, i_g = zk + wz * s_g, ik + wi * s_g
        zk = (A * z_g - B * z) / (1 + C * h / tau)                 # BDF2 stage to t + h
        wz = (C * h / tau) / (1 + C * h / tau)
        ik, wi = A * i_g - B * i_, C * h
        s = (_history(t + h) - b * ik - cc @ zk) / (phi0 + b * wi + cc @ wz)
        z, i_ = zk + wz * s, ik + wi * s
        out.append(s)
    return np.array(out)


def scalar_rows(steps=(40, 80, 160), reference=20480):
    rows = []
    for law, (_, creep) in LAWS.items():
        for rule in ("bdf2", "bdf2_plain", "linear", "step_start", "tr_bdf2"):
            if rule == "step_start" and creep.phi0 == 0:
                continue
            run = (lambda n, c=creep: tr_bdf2(c, n)) if rule == "tr_bdf2" else \
                (lambda n, c=creep, r=rule: held_displacement(c, n, r))
            ref = run(reference)
            errs = []
            for n in steps:
                s = run(n)
                t = np.linspace(0.0, 2.0, n + 1)
                late = t >= 0.25
                errs.append(float(np.abs(s[late] - ref[::reference // n][late]).max()
                                  / np.abs(ref).max()))
            order = math.log2(errs[-2] / errs[-1]) if errs[-1] > 0 else math.inf
            solves = 2 if rule == "tr_bdf2" else 1
            rows.append(dict(part="scalar", law=law, rule=rule, steps=steps[-1],
                             solves=solves * steps[-1], value=errs[-1], order=order,
                             errors=" ".join(f"{e:.2e}" for e in errs)))
    return rows


# --------------------------------------------------------------------------- 3: Lee-Radok
def lee_radok_scene(law, n, steps, size="auto"):
    return cp.Scene(name=f"ti-{law}", geometry={"shape": "sphere", "radius": R},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                               **LAWS[law][0]},
                    load={"time": [0.0, 2.0], "normal_force": W},
                    grid={"points": [n, n], "size": size}, time={"steps": steps},
                    solver={"time_rule": "linear", "tolerance": 1e-10})


def lee_radok_p(law, r, t, creep=None):
    """Lee-Radok p(r, t) [Pa] (analytic.lee_radok_pressure; for Kelvin-Voigt its branch for
    phi(0) = 0: p = 2E/(pi R (1 - nu^2)) (h + tau dh/dt), E the long-term modulus), with
    the law's creep function or ``creep`` (the normal compliance of a varying nu)."""
    return an.lee_radok_pressure(np.asarray(r, float), t, W, R, E, NU,
                                 LAWS[law][1] if creep is None else creep, n_steps=1000)


def step_load_measures(ds, law, t_min=0.25, t_field=0.5, creep=None):
    """Radius (cells), holes, zigzag, field and a³ against Lee-Radok
    (:func:`contactpipe.testing.lee_radok_measures`), with the law's creep function or
    ``creep`` (the normal compliance of a varying nu)."""
    return lee_radok_measures(ds, LAWS[law][1] if creep is None else creep, E, NU, R, W,
                              t_min=t_min, t_field=t_field)


QUICK_CANDIDATES = ("auto", "bdf2", "linear")


def lee_radok_cases(quick):
    if quick:
        return {"kelvin_voigt": (24, 10, [1.6e-3] * 2), "maxwell": (24, 10, "auto")}
    return {"kelvin_voigt": (96, 40, [1.6e-3] * 2), "zener100": (96, 20, "auto"),
            "maxwell": (48, 20, "auto"), "zener2": (48, 20, "auto"), "prony3": (48, 20, "auto")}


def lee_radok_rows(quick, keep):
    rows = []
    for law, (n, steps, size) in lee_radok_cases(quick).items():
        for name in QUICK_CANDIDATES if quick else CANDIDATES:
            if name == "step_start" and LAWS[law][1].phi0 == 0:
                continue
            with use_memory(name):
                ds, wall = c.run(lee_radok_scene(law, n, steps, size))
            m = step_load_measures(ds, law)
            if law == "kelvin_voigt" and name in ("bdf2", "linear"):
                keep[name] = (ds, m)
            rows.append(dict(part="lee_radok", law=law, rule=name, grid=n, steps=steps,
                             value=m["field"], radius_cells=m["radius_cells"],
                             holes=m["holes"], zigzag=m["zigzag"], a3=m["a3"], wall_s=wall))
            print(f"  {law:13s} {n}^2 {steps:3d} steps {name:12s} radius "
                  f"{m['radius_cells']:.2f} cells, holes {m['holes']:4d}, zigzag "
                  f"{m['zigzag']:.1e}, field {m['field']:.2e}, a3 {m['a3']:.1e}", flush=True)
    return rows


# --------------------------------------------------------------------------- 4: punch order
def punch_scene(law, n, steps, gap_file):
    return cp.Scene(name=f"ti-punch-{law}", geometry={"shape": "surface", "file": gap_file},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                               **LAWS[law][0]},
                    load={"time": [0.0, 2.0], "normal_force": [1000.0, 1500.0]},
                    grid={"points": [n, n], "size": [0.8e-3, 0.8e-3]}, time={"steps": steps},
                    solver={"time_rule": "linear", "tolerance": 1e-10})


def punch_rows(quick, folder):
    n, steps = (16, (10, 20, 40)) if quick else (16, (20, 40, 80, 160))
    x = -0.4e-3 + (np.arange(n) + 0.5) * 0.8e-3 / n
    r = np.hypot(*np.meshgrid(x, x, indexing="ij"))
    gap_file = f"{folder}/punch_{n}.npy"
    np.save(gap_file, np.where(r <= 0.3e-3, r ** 2 / (2 * R), 0.01))
    rows = []
    for law in (("maxwell", "kelvin_voigt") if quick else LAWS):
        t_min = 0.5 if law == "kelvin_voigt" else 0.25
        for rule in RULES:
            if rule == "step_start" and LAWS[law][1].phi0 == 0:
                continue
            with use_memory(rule):
                runs = [cp.simulate(punch_scene(law, n, s, gap_file)).p.values for s in steps]
            p = [runs[i][::2 ** i] for i in range(len(runs))]
            t = np.linspace(0.0, 2.0, steps[0] + 1)
            late = t >= t_min
            diffs = [float(np.abs(p[i][late] - p[i + 1][late]).max() / p[-1].max())
                     for i in range(len(p) - 1)]
            order = (math.log2(diffs[-2] / diffs[-1]) if diffs[-1] > 1e-12 else math.nan)
            rows.append(dict(part="punch_order", law=law, rule=rule, grid=n,
                             steps=steps[-1], value=diffs[-1], order=order,
                             errors=" ".join(f"{e:.2e}" for e in diffs)))
    return rows


def sphere_front_rows(quick):
    """The sphere's field in dt: successive differences of the Lee-Radok step load's
    pressure at 20 / 40 / 80 / 160 steps (96² auto), largest over the grid and over inside
    0.8 a(t), over p_max, for t >= 0.25 tau (Kelvin-Voigt 0.5 tau), and where the largest
    sits (r/a). One rule per law at every step: "bdf2" for Kelvin-Voigt and Zener 100,
    "linear" for the others ("auto" would switch Zener 100 to "linear" at 160 steps)."""
    n, steps = (24, (10, 20, 40)) if quick else (96, (20, 40, 80, 160))
    rows = []
    for law in (("maxwell", "kelvin_voigt") if quick else LAWS):
        rule = "bdf2" if law in ("kelvin_voigt", "zener100") else "linear"
        with use_memory(rule):
            runs = [cp.simulate(lee_radok_scene(law, n, s)) for s in steps]
        x1, x2 = runs[0].x1.values, runs[0].x2.values
        r = np.hypot(*np.meshgrid(x1, x2, indexing="ij"))
        p = [ds.p.values[:: 2 ** i] for i, ds in enumerate(runs)]
        t = np.linspace(0.0, 2.0, steps[0] + 1)
        late = t >= (0.5 if law == "kelvin_voigt" else 0.25)
        a = np.sqrt((p[-1][late] > 0).sum(axis=(1, 2)) / math.pi) * (x1[1] - x1[0])
        inside = r[None] < 0.8 * a[:, None, None]
        p_max = p[-1][late].max()
        whole, inner, where = [], [], []
        for i in range(len(p) - 1):
            d = np.abs(p[i][late] - p[i + 1][late])
            k = np.unravel_index(d.argmax(), d.shape)
            whole.append(d.max() / p_max)
            inner.append((d * inside).max() / p_max)
            where.append(r[k[1], k[2]] / a[k[0]])
        rows.append(dict(part="sphere_front", law=law, rule=rule, grid=n, steps=steps[-1],
                         value=whole[-1], errors=" ".join(f"{e:.2e}" for e in whole),
                         inside=" ".join(f"{e:.2e}" for e in inner),
                         front_at=" ".join(f"{w:.2f}" for w in where)))
    return rows


# --------------------------------------------------------------------------- output
# --------------------------------------------------------------------------- 5: nu(t)
def poisson_rows(quick):
    """A shear creep function with an elastic bulk modulus (bulk = "elastic", nu0 = 0.3):
    the Lee-Radok step load with the normal compliance (1 - nu(t))/G(t)
    (``Body.normal_creep``), and the contact radius at 2 tau against constant nu."""
    cases = {"maxwell": (24, 10)} if quick else {"maxwell": (48, 20), "prony3": (48, 20)}
    rows = []
    print("\n5. Varying Poisson ratio (shear creep, elastic bulk): Lee-Radok with (1 - nu)/G")
    for law, (n, steps) in cases.items():
        sc = lee_radok_scene(law, n, steps, "auto").replace(
            {"halfspace.bulk": "elastic", "solver.time_rule": "auto"})
        body = sc.halfspace.body()
        ds, wall = c.run(sc)
        m = step_load_measures(ds, law, t_field=0.25, creep=body.normal_creep)
        ratio = (float(body.normal_creep(2.0)) / float(body.creep(2.0))) ** (1 / 3)
        rows.append(dict(part="poisson", law=law, rule=ds.attrs["time_rule_resolved"],
                         grid=n, steps=steps, value=m["field"],
                         radius_cells=m["radius_cells"], holes=m["holes"],
                         zigzag=m["zigzag"], a3=m["a3"], radius_ratio=ratio, wall_s=wall))
        print(f"  {law:13s} {n}^2 {steps:3d} steps ({rows[-1]['rule']}): radius "
              f"{m['radius_cells']:.2f} cells, holes {m['holes']}, zigzag {m['zigzag']:.1e}, "
              f"field (t >= 0.25 tau) {m['field']:.2e}, a3 {m['a3']:.1e}; a(2 tau) / a at "
              f"constant nu = {ratio:.4f}", flush=True)
    return rows


# --------------------------------------------------------------------------- 6: preload
@contextlib.contextmanager
def uniform_preload():
    """cp.simulate with the former uniform preload fractions k/n (replacing
    ``contactpipe.simulation.problem.preload_fractions`` for the run)."""
    original = simulation_module.preload_fractions
    simulation_module.preload_fractions = lambda n: np.arange(1, int(n) + 1) / float(n)
    try:
        yield
    finally:
        simulation_module.preload_fractions = original


def preload_scene(n, substeps):
    return cp.Scene(name="ti-preload", geometry={"shape": "sphere", "radius": R},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                               **LAWS["maxwell"][0]},
                    friction={"mu": c.MU}, load={"time": [0.0, 1.0], "normal_force": W},
                    grid={"points": [n, n], "size": "auto"}, time={"steps": 1},
                    solver={"preload_substeps": substeps, "tolerance": 1e-10})


def preload_rows(quick):
    """The frictional preload on a coupled pair (rigid on Maxwell, nu = 0.3, mu = 0.1): the
    q field at t0 against a fine graded path, uniform fractions k/n against graded (k/n)^2,
    and the recorded estimate; rms over the contact cells over mu p_max."""
    grids, counts, ref_n = ((16,), (4, 8), 32) if quick else ((32, 64), (4, 8, 16, 32, 64),
                                                               256)
    rows = []
    print("\n6. Frictional preload: q at t0 against a fine path (rms over the contact / "
          "mu p_max)")
    for n in grids:
        ref, _ = c.run(preload_scene(n, ref_n))
        q_ref = np.stack([ref.q1.values[0], ref.q2.values[0] if "q2" in ref
                          else 0 * ref.q1.values[0]])
        p_ref = ref.p.values[0]
        for grading in ("uniform", "graded"):
            for m in counts:
                if grading == "uniform":
                    with uniform_preload():
                        ds, wall = c.run(preload_scene(n, m))
                else:
                    ds, wall = c.run(preload_scene(n, m))
                q = np.stack([ds.q1.values[0], ds.q2.values[0] if "q2" in ds
                              else 0 * ds.q1.values[0]])
                contact = (p_ref > 0) | (ds.p.values[0] > 0)
                err = float(np.sqrt(np.sum((q - q_ref) ** 2, axis=0)[contact].mean())
                            / (c.MU * p_ref.max()))
                est = ds.attrs.get("preload_error_estimate", math.nan)
                rows.append(dict(part="preload", law="maxwell", rule=grading, grid=n,
                                 steps=m, value=err, estimate=est, reference=ref_n,
                                 fft_pairs=int(ds.fft_pairs.values[0]), wall_s=wall))
                print(f"  {n}^2 {grading:8s} {m:4d} sub-steps: error {err:.2e}, recorded "
                      f"estimate {est:.2e}", flush=True)
    return rows


def print_tables(rows):
    print("\n1. Amplification factor of the traction error (largest |g|; (-) when the "
          "largest is negative; worst negative factor in brackets)")
    for law in LAWS:
        for rule in ("step_start", "linear", "bdf2"):
            cells = []
            for r in rows:
                if r["part"] == "amplification" and r["law"] == law and r["rule"] == rule:
                    if math.isnan(r["value"]):
                        cells.append("  n/a          ")
                    else:
                        sign = "-" if r["signed"] < 0 else " "
                        cells.append(f"{sign}{r['value']:6.3f} [{r['negative']:5.3f}]")
            print(f"  {law:13s} {rule:11s} " + " | ".join(cells))
    for r in rows:
        if r["part"] == "bound":
            print(f"  step-start bound, {r['law']:13s}: {r['value']:.6g} s "
                  f"(2 phi0/phi'(0) = {r['small_step']:.6g} s)")
    print("\n2. Held displacement (scalar): error at the finest steps and observed order")
    for r in rows:
        if r["part"] == "scalar":
            print(f"  {r['law']:13s} {r['rule']:11s} {r['solves']:4d} solves: errors "
                  f"{r['errors']}, order {r['order']:.2f}")
    print("\n4. Pressure field of the sphere (Lee-Radok step load): successive "
          "differences over p_max, whole grid | inside 0.8 a | where the largest is (r/a)")
    for r in rows:
        if r["part"] == "sphere_front":
            print(f"  {r['law']:13s} {r['rule']:7s} {r['grid']}^2 {r['errors']} | "
                  f"{r['inside']} | {r['front_at']}")
    print("\n4. Pressure field of the rounded punch: successive differences and order")
    for r in rows:
        if r["part"] == "punch_order":
            print(f"  {r['law']:13s} {r['rule']:11s} {r['errors']}  order {r['order']:.2f}")


def write_csv(rows, out):
    keys = sorted({k for r in rows for k in r})
    path = out / "time_integration.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in keys})
    print(f"wrote {path}")
    return path


def plot(rows, keep, out):
    fig, axes = plt.subplots(1, 4, figsize=(19, 4.2))
    ax = axes[0]
    hs = np.logspace(-3, 2, 121)
    for law, style in (("kelvin_voigt", "-"), ("zener100", "--")):
        creep = LAWS[law][1]
        for rule, color in (("linear", "tab:red"), ("bdf2", "tab:blue"),
                            ("step_start", "tab:gray")):
            if rule == "step_start" and creep.phi0 == 0:
                continue
            g = [mem.error_amplification(creep, h, rule) for h in hs]
            worst = [float(np.real(x[0])) if np.abs(x[0]) > 1e-6 else 0.0 for x in g]
            ax.plot(hs, worst, style, color=color, label=f"{rule}, {law}")
    ax.set_xscale("log")
    ax.set_ylim(-1.5, 1.05)
    ax.axhline(-1, color="k", lw=0.6)
    ax.set_xlabel("Δt / τ")
    ax.set_ylabel("leading amplification factor (real part)")
    ax.set_title("traction error under held displacement", fontsize=9)
    ax.legend(fontsize=6.5)
    if "bdf2" in keep:
        ax = axes[1]
        t = keep["bdf2"][1]["t"]
        for name, color in (("linear", "tab:red"), ("bdf2", "tab:blue")):
            if name in keep:
                ax.plot(t[1:], keep[name][1]["pc"][1:] / 1e9, "o-", ms=3, color=color,
                        label=name)
        tt = np.linspace(t[1], t[-1], 200)
        p_lr = [float(lee_radok_p("kelvin_voigt", [0.0], x)[0]) for x in tt]
        ax.plot(tt, np.array(p_lr) / 1e9, "k--", lw=1, label="Lee–Radok")
        ax.set_ylim(0, 6)
        ax.set_xlabel("t / τ")
        ax.set_ylabel("centre pressure [GPa]")
        ax.set_title("Kelvin–Voigt, step load (issue case)", fontsize=9)
        ax.legend(fontsize=7)
        ax = axes[2]
        for name, color in (("linear", "tab:red"), ("bdf2", "tab:blue")):
            if name in keep:
                ds = keep[name][0]
                k = int(np.argmin(np.abs(ds.time.values - 0.5)))
                x = ds.x1.values
                ax.plot(x * 1e3, c.centre_profile(ds.p.values[k]) / 1e9, "o-", ms=2.5,
                        color=color, label=f"{name}, t = {ds.time.values[k]:.2f} τ")
        xs = np.linspace(-0.8e-3, 0.8e-3, 400)
        ax.plot(xs * 1e3, lee_radok_p("kelvin_voigt", np.abs(xs), 0.5) / 1e9, "k--", lw=1,
                label="Lee–Radok")
        ax.set_ylim(0, 5)
        ax.set_xlabel("x1 [mm]")
        ax.set_ylabel("p [GPa]")
        ax.set_title("Kelvin–Voigt pressure through the centre", fontsize=9)
        ax.legend(fontsize=7)
    ax = axes[3]
    colors = dict(zip(LAWS, ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"),
                      strict=True))
    for r in rows:
        if r["part"] == "punch_order" and r["law"] != "kelvin_voigt":
            e = [float(v) for v in r["errors"].split()]
            n = [r["steps"] // 2 ** i for i in range(len(e), 0, -1)]
            ax.loglog(n, e, {"bdf2": "o-", "linear": "s--", "step_start": "^:"}[r["rule"]],
                      color=colors[r["law"]], ms=4, label=f"{r['law']}, {r['rule']}")
    ax.set_xlabel("steps over 2τ (difference to twice the steps)")
    ax.set_ylabel("max |Δp| / p_max (t ≥ 0.25τ)")
    ax.set_title("rounded punch: pressure field vs Δt", fontsize=9)
    ax.legend(fontsize=5.5, ncol=2)
    fig.tight_layout()
    return c.save_figure(fig, out / "time_integration.png")


def main(argv=None):
    p = c.parser(__doc__.splitlines()[0], __doc__)
    args = p.parse_args(argv)
    out = c.out_dir(args)
    rows = amplification_rows()
    rows += scalar_rows(steps=(10, 20, 40), reference=320) if args.quick else scalar_rows()
    print("\n3. Lee-Radok step load (cp.simulate)")
    keep = {}
    with tempfile.TemporaryDirectory() as folder:
        rows += lee_radok_rows(args.quick, keep)
        rows += punch_rows(args.quick, folder)
    rows += sphere_front_rows(args.quick)
    rows += poisson_rows(args.quick)
    rows += preload_rows(args.quick)
    print_tables(rows)
    csv_path = write_csv(rows, out)
    png = plot(rows, keep, out)
    return {"csv": csv_path, "png": png, "rows": rows}


if __name__ == "__main__":
    main(sys.argv[1:])
