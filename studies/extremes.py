"""The extremes (issue 4): does every corner of the parameter space either converge to its
expected limit or stop with a clear diagnostic?

The matrix, on small grids (32 x 32 unless stated, 20 steps per fretting window):

- window tau/t' from 1e-4 to 1e3 on the paper's rigid ball / Maxwell half-space
  (nu = 0.3, coupled): short windows must reproduce the elastic loop with the glassy
  modulus (compared cell by cell with the elastic run on the same grid), long ones the
  flowing response (Lee-Radok's a(t)^3 from the approach), the automatic grid keeping the
  contact inside; an identical pair of Maxwell bodies (beta = 0) at tau/t' = 1e-3 against
  Mindlin-Deresiewicz with the glassy modulus (64 x 64);
- mu = 1e-6 and 10 (steel pair: the Mindlin-Deresiewicz tractions scale with mu; rigid
  ball on an elastic half-space, coupled: mu -> 0 gives the frictionless pressure);
- T* = 0 (no tangential load), 1e-6, 0.5, 0.999 mu W; T* = mu W (refused: gross sliding);
- nu = 0 and 0.5 (steel-like pairs against Mindlin-Deresiewicz; a rigid ball on nu = 0,
  the strongest coupling, beta = 0.5);
- stiffness ratio 1e6: an elastic indenter 1e6 times stiffer than the half-space (must
  equal the rigid indenter) and 1e6 times softer (must equal a rigid half-space);
- Kelvin-Voigt (no instantaneous elasticity) under the fretting loop;
- a single time step (Cattaneo under 0 -> T*) and 10 000 steps (16 x 16);
- a fixed grid too small for a long Maxwell window: refused when the scene is read (the
  Hertz estimate of the largest contact does not fit), and with ``grid.size_check =
  false`` stopped by the run (GridError).

Every converged archive must pass contactpipe.testing.assert_contact_laws, hold no
NaN/inf, and carry the applied load (W and T reached against the program: the
contact-law checker compares the tractions with their own sums, so this is checked here);
a run that stops must raise a ContactpipeError whose message names the step, and leave
no archive behind.

    python studies/extremes.py [--out DIR] [--quick] [--only NAME ...]

Writes an archive per converged case under ``extremes/`` and ``extremes.csv``, and prints
the table: case, outcome, check, measured, time. Exit status 1 when a case misses its
expectation.
"""
from __future__ import annotations

import csv
import math
import sys
import time
import traceback
from dataclasses import dataclass, field

import _common as c  # noqa: I001  (first: it pins the BLAS threads before numpy loads)
import numpy as np

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.materials import kelvin_voigt as kv_creep
from contactpipe.materials import maxwell as maxwell_creep
from contactpipe.testing import contact_law_violations

FORCE_TOL = 1e-8          # |reached - applied| / W


@dataclass
class Result:
    case: str
    expect: str
    outcome: str = ""
    passed: bool = False
    check: str = ""
    measured: str = ""
    seconds: float = 0.0
    message: str = ""
    data: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- helpers
def elastic(young=c.E_STEEL, poisson=c.NU_STEEL):
    return {"material": "elastic", "young": young, "poisson": poisson}


def kelvin_voigt(young=c.E_GLASSY, poisson=c.NU_STEEL, retardation_time=1.0):
    return {"material": "viscoelastic", "young": young, "poisson": poisson,
            "creep": "kelvin_voigt", "retardation_time": retardation_time}


def verify(ds, scene):
    """Problems of a converged archive: contact laws, NaN/inf, load carried."""
    problems = list(contact_law_violations(ds))
    bad = c.all_finite(ds)
    if bad:
        problems.append(f"NaN/inf in {bad}")
    eW, eT = c.force_errors(ds, scene)
    if max(eW, eT) > FORCE_TOL:
        t, Wa, Ta, _ = scene.instants()
        k = int(np.argmax(np.abs(ds.T1.values - Ta))) if "T1" in ds else 0
        problems.append(f"load not carried: |W - W_applied| = {eW:.2e} W, |T - T_applied| = "
                        f"{eT:.2e} W (worst at step {k}: T reached "
                        f"{float(ds.T1[k]) if 'T1' in ds else 0:.6g} N, applied {Ta[k]:.6g} N)")
    return problems


def profile_diff(ds, ref, scale_p, scale_q):
    """max |p - p_ref| / scale_p and max |q1 - q1_ref| / scale_q over all instants."""
    dp = float(np.abs(ds.p.values - ref.p.values).max()) / scale_p
    dq = 0.0
    if "q1" in ds and "q1" in ref:
        dq = float(np.abs(ds.q1.values - ref.q1.values).max()) / scale_q
    return dp, dq


def md_check(ds, scene, mu, W, young1, nu1, young2, nu2, tol_traction=0.02,
             tol_cells=2.0, tol_loop=0.02, tol_energy=0.02, every=1):
    """Mindlin-Deresiewicz with the given (glassy) constants; inf marks a rigid body."""
    e_star = an.composite_modulus(young1, nu1, young2, nu2)
    h = an.hertz_sphere(W, c.R, e_star)
    comp = an.tangential_compliance_sum(young1, nu1, young2, nu2)
    e = c.md_errors(ds, scene, mu=mu, W=W, a=h.contact_radius, p0=h.max_pressure,
                    compliance=comp, every=every)
    ok = (e["traction"] <= tol_traction and e["stick_cells"] <= tol_cells
          and e["loop"] <= tol_loop and (math.isnan(e["energy"]) or e["energy"] <= tol_energy))
    text = (f"traction {e['traction']:.2%} of μp0, stick radius {e['stick_cells']:.2f} cells, "
            f"loop {e['loop']:.1e}, energy {e['energy']:.1e}")
    return ok, text, e


def lee_radok_check(ds, young, nu, creep, tol, t_min=0.0):
    t = ds.time.values
    err = c.lee_radok_a3_error(t, ds.omega3.values, [t[0]], [c.W], c.R, young, nu, creep,
                               t_min=t_min)
    return err <= tol, f"a(t)^3 vs Lee-Radok {err:.2%}", err


def edge_margin(ds):
    """Fewest cells between the contact and the grid edge over the run."""
    p = np.asarray(ds.p.values) > 0
    rows = p.any(axis=2)
    cols = p.any(axis=1)
    n1, n2 = rows.shape[1], cols.shape[1]
    m = []
    for occ, n in ((rows, n1), (cols, n2)):
        idx = np.flatnonzero(occ.any(axis=0))
        m.append(min(idx[0], n - 1 - idx[-1]))
    return int(min(m))


# --------------------------------------------------------------------------- the cases
def maxwell_window(ratio, n=32, steps=20):
    return c.maxwell_fretting_scene(n=n, steps=steps, window=ratio * c.RELAXATION_TIME,
                                    name=f"ext-maxwell-window-{ratio:g}")


def glassy_twin(scene):
    """The same scene with the Maxwell half-space replaced by its glassy elastic self, on
    the same grid."""
    size = list(scene.resolved_grid_size())
    return scene.replace({"halfspace": elastic(c.E_GLASSY, c.NU_STEEL),
                          "grid.size": size, "name": scene.name + "-glassy"})


def case_window(ratio, n=32, steps=20):
    def build():
        return maxwell_window(ratio, n, steps)

    def check(ds, scene):
        if ratio <= 1e-2:
            ref = cp.simulate(glassy_twin(scene))
            dp, dq = profile_diff(ds, ref, c.P_H, c.MU * c.P_H)
            # creep over the window: phi(tau) - 1 = tau/t'; the tractions move by less
            tol = 3 * ratio
            return (dp <= tol and dq <= tol,
                    f"= glassy elastic run within 3 τ/t' = {tol:.0e}",
                    f"p {dp:.1e} p_H, q {dq:.1e} μp_H", {"dp": dp, "dq": dq})
        if ratio >= 10:
            # for t >= 0.2 tau: the grid is sized for a(tau), so the glassy contact of the
            # first instants spans only a few cells (a^3 off by 10 % at t = 0, 5 % at
            # t = 0.05 tau on 32^2, frictionless alike)
            ok, txt, err = lee_radok_check(ds, c.E_GLASSY, c.NU_STEEL,
                                           maxwell_creep(c.RELAXATION_TIME), 0.02,
                                           t_min=0.2 * scene.load.window)
            margin = edge_margin(ds)
            return (ok and margin >= 1,
                    "Lee-Radok a^3 within 2 % for t ≥ 0.2τ, contact inside the auto grid",
                    f"{txt}, {margin} cells to the edge", {"a3": err, "margin": margin})
        return True, "converges (laws, load)", "", {}
    return build, check


def case_identical_maxwell(ratio=1e-3, n=64, steps=20):
    """beta = 0: two identical Maxwell bodies with steel's glassy constants."""
    def build():
        mx = c.maxwell(young=c.E_STEEL)
        return c.fretting_scene(n=n, steps=steps, indenter=mx, halfspace=mx,
                                window=ratio * c.RELAXATION_TIME, size=3.0,
                                name=f"ext-identical-maxwell-{ratio:g}")

    def check(ds, scene):
        ok, txt, e = md_check(ds, scene, c.MU, c.W, c.E_STEEL, c.NU_STEEL, c.E_STEEL,
                              c.NU_STEEL)
        return ok, "Mindlin-Deresiewicz (glassy): 2 % μp0, 2 cells, 2 %", txt, e
    return build, check


def case_mu_steel(mu, n=32, steps=20):
    def build():
        return c.fretting_scene(n=n, steps=steps, mu=mu, name=f"ext-steel-mu-{mu:g}")

    def check(ds, scene):
        ok, txt, e = md_check(ds, scene, mu, c.W, c.E_STEEL, c.NU_STEEL, c.E_STEEL,
                              c.NU_STEEL)
        return ok, "Mindlin-Deresiewicz (scales with μ): 2 % μp0, 2 cells", txt, e
    return build, check


def case_mu_coupled(mu, n=32, steps=20):
    def build():
        return c.fretting_scene(n=n, steps=steps, mu=mu, indenter=c.RIGID,
                                halfspace=elastic(c.E_GLASSY), name=f"ext-coupled-mu-{mu:g}")

    def check(ds, scene):
        if mu >= 1:
            return True, "converges (laws, load)", "", {}
        fl = scene.replace({"friction.mu": 0.0, "load.fretting": None,
                            "load.time": [0.0, 1.0], "name": "frictionless",
                            "load.normal_force": c.W, "time.steps": 1})
        ref = cp.simulate(fl)
        p_ref = ref.p.values[-1]
        dp = float(np.abs(ds.p.values - p_ref[None]).max() / p_ref.max())
        return dp <= 1e-5, "pressure = frictionless within 1e-5 p0", f"{dp:.1e} p0", {"dp": dp}
    return build, check


def case_amplitude(amp, n=32, steps=20):
    def build():
        if amp == 0:
            return cp.Scene(name="ext-no-tangential", geometry={"shape": "sphere", "radius": c.R},
                            indenter=dict(c.STEEL), halfspace=dict(c.STEEL),
                            friction={"mu": c.MU},
                            load={"time": [0.0, 1.0], "normal_force": c.W},
                            grid={"points": [n, n], "size": [3 * c.A_H] * 2},
                            time={"steps": steps})
        return c.fretting_scene(n=n, steps=steps, amplitude=amp, name=f"ext-amplitude-{amp:g}")

    def check(ds, scene):
        if amp == 0:
            d = float(ds.x1[1] - ds.x1[0])
            x = ds.x1.values
            ref = an.cell_average(lambda u, v: c.HERTZ.pressure(np.hypot(u, v)),
                                  x[:, None], x[None, :], d, d)
            r = np.hypot(x[:, None], x[None, :])
            far = np.abs(r - c.A_H) > 1.5 * d          # leave out the square-root edge
            dp = float(np.abs(ds.p.values - ref[None])[:, far].max() / c.P_H)
            shear = "q1" in ds
            return (dp <= 0.02 and not shear, "Hertz (cell-averaged, edge cells out) within "
                    "2 % p_H, no shear solve",
                    f"{dp:.2%} p_H, tangential model: {ds.attrs['model_tangential']}",
                    {"dp": dp})
        if amp < 1e-3:
            # the slip annulus a (1 - (1 - T*/mu W)^(1/3)) = 3e-7 a is far below a cell: no
            # cell slips and nothing is dissipated (exact: 4e-20 J); the traction is
            # Mindlin's full-stick one
            ok, txt, e = md_check(ds, scene, c.MU, c.W, c.E_STEEL, c.NU_STEEL, c.E_STEEL,
                                  c.NU_STEEL, tol_energy=math.inf)
            stick = bool(np.all(ds.stick_area.values[1:] == ds.contact_area.values[1:]))
            diss = float(ds.dissipation.values[-1])
            return (ok and stick and diss == 0.0,
                    "full stick, no dissipation, Mindlin traction 2 % μp0, loop 2 %",
                    f"{txt}; all stick: {stick}, dissipation {diss:.1e} J", e)
        ok, txt, e = md_check(ds, scene, c.MU, c.W, c.E_STEEL, c.NU_STEEL, c.E_STEEL,
                              c.NU_STEEL)
        return ok, "Mindlin-Deresiewicz: 2 % μp0, 2 cells, 2 %", txt, e
    return build, check


def case_frictionless_preload(amp=1e-6, n=32, steps=20):
    """A coupled pair (rigid ball on nu = 0.3) loaded frictionless first (the paper's
    initial normal solve), then a vanishing tangential load: nothing may slip."""
    def build():
        return c.fretting_scene(n=n, steps=steps, amplitude=amp, indenter=c.RIGID,
                                halfspace=elastic(c.E_GLASSY), preload="frictionless",
                                name="ext-frictionless-preload-tiny-T")

    def check(ds, scene):
        q = float(np.abs(ds.q1.values).max()) / (c.MU * c.P_H)
        slip = int((ds.status.values == 2).sum())
        diss = float(ds.dissipation.values[-1])
        ok = q <= 1e-3 and slip == 0 and diss <= 1e-12
        return (ok, "no slip, |q| ≤ 1e-3 μp0, no dissipation (T* = 1e-6 μW)",
                f"max|q| {q:.2e} μp0, {slip} slipping cell-steps, dissipation {diss:.2e} J",
                {"q": q, "slip": slip, "dissipation": diss})
    return build, check


def case_poisson(nu, rigid, n=32, steps=20):
    def build():
        body = elastic(c.E_STEEL, nu)
        ind = c.RIGID if rigid else body
        return c.fretting_scene(n=n, steps=steps, indenter=ind, halfspace=body, size="auto",
                                name=f"ext-nu-{nu:g}-{'rigid' if rigid else 'pair'}")

    def check(ds, scene):
        if rigid and nu < 0.5:
            beta = float(ds.attrs.get("dundurs_beta", math.nan))
            return True, "converges (laws, load)", f"β = {beta:.2f}", {}
        e1 = math.inf if rigid else c.E_STEEL
        ok, txt, e = md_check(ds, scene, c.MU, c.W, e1, nu, c.E_STEEL, nu)
        return ok, "Mindlin-Deresiewicz (β = 0): 2 % μp0, 2 cells, 2 %", txt, e
    return build, check


def case_stiffness(which, ratio=1e6, n=32, steps=20):
    """An elastic body `ratio` times stiffer than steel: indenter ("stiff-indenter") or
    half-space ("soft-indenter", the indenter then 1e6 times softer)."""
    def scenes():
        stiff = elastic(c.E_STEEL * ratio)
        if which == "stiff-indenter":
            a, b = (stiff, c.STEEL), (c.RIGID, c.STEEL)
        else:
            a, b = (c.STEEL, stiff), (c.STEEL, c.RIGID)
        mk = lambda pair, tag: c.fretting_scene(n=n, steps=steps, indenter=pair[0],  # noqa
                                                halfspace=pair[1], size=3.0,
                                                name=f"ext-ratio-{which}{tag}")
        return mk(a, ""), mk(b, "-rigid-limit")

    def build():
        return scenes()[0]

    def check(ds, scene):
        ref = cp.simulate(scenes()[1])
        dp, dq = profile_diff(ds, ref, c.P_H, c.MU * c.P_H)
        dom = float(np.abs(ds.omega1.values - ref.omega1.values).max()
                    / np.abs(ref.omega1.values).max())
        tol = 1e-4
        ok = dp <= tol and dq <= tol and dom <= tol
        return (ok, f"= the rigid limit within {tol:g}",
                f"p {dp:.1e} p_H, q {dq:.1e} μp_H, ω1 {dom:.1e}",
                {"dp": dp, "dq": dq, "domega": dom})
    return build, check


def case_kelvin_voigt(nu, window=10.0, n=32, steps=20):
    def build():
        return c.fretting_scene(n=n, steps=steps, indenter=c.RIGID,
                                halfspace=kelvin_voigt(poisson=nu), window=window,
                                size="auto", name=f"ext-kelvin-voigt-nu-{nu:g}-w{window:g}")

    def check(ds, scene):
        ok, txt, err = lee_radok_check(ds, c.E_GLASSY, nu, kv_creep(1.0), 0.05,
                                       t_min=0.2 * window)
        return ok, "Lee-Radok a^3 within 5 % for t ≥ 0.2τ", txt, {"a3": err}
    return build, check


def case_one_step(n=32):
    def build():
        return c.fretting_scene(n=n, steps=1, name="ext-one-step")

    def check(ds, scene):
        ok, txt, e = md_check(ds, scene, c.MU, c.W, c.E_STEEL, c.NU_STEEL, c.E_STEEL,
                              c.NU_STEEL)
        return ok, "Cattaneo (0 -> T* in one step): 2 % μp0, 2 cells", txt, e
    return build, check


def case_many_steps(steps=10_000, n=16):
    def build():
        return c.fretting_scene(n=n, steps=steps, name="ext-many-steps",
                                output={"stride": steps // 100})

    def check(ds, scene):
        # 16 x 16 over 3 a_H: the spatial error of the energy is 2.0 % (as with 10 steps)
        ok, txt, e = md_check(ds, scene, c.MU, c.W, c.E_STEEL, c.NU_STEEL, c.E_STEEL,
                              c.NU_STEEL, tol_traction=0.03, tol_energy=0.03)
        return ok, "Mindlin-Deresiewicz on 16^2: 3 % μp0, 2 cells, loop 2 %, energy 3 %", \
            txt, e
    return build, check


def case_grid_too_small(ratio=100.0, n=32, steps=20, size_check=False):
    """The size check (refusing the scene) left off by default: the run's own check is
    what this case exercises."""
    def build():
        return c.maxwell_fretting_scene(n=n, steps=steps, window=ratio, size=3.0,
                                        name="ext-grid-too-small", grid_check=size_check)
    return build, None


def case_gross_sliding(n=32, steps=20):
    def build():
        return c.fretting_scene(n=n, steps=steps, amplitude=1.0, name="ext-gross-sliding")
    return build, None


def cases(quick=False):
    """(name, expectation, build, check); expectation: "converge", "diagnostic" (a named
    ContactpipeError) or "either"."""
    out = []
    ratios = (1e-4, 1e-2) if quick else (1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3)
    for r in ratios:
        out.append((f"window tau/t'={r:g}", "converge", *case_window(r)))
    if not quick:
        out.append(("identical Maxwell pair tau/t'=1e-3 (64^2)", "converge",
                    *case_identical_maxwell()))
    for mu in (1e-6, 10.0):
        out.append((f"mu={mu:g} steel pair", "converge", *case_mu_steel(mu)))
    if not quick:
        out.append(("mu=1e-6 rigid/elastic (coupled)", "converge", *case_mu_coupled(1e-6)))
        out.append(("mu=1 rigid/elastic (coupled)", "converge", *case_mu_coupled(1.0)))
    out.append(("mu=10 rigid/elastic (coupled)", "either", *case_mu_coupled(10.0)))
    for amp in ((0.0, 0.999) if quick else (0.0, 1e-6, 0.5, 0.999)):
        out.append((f"T*={amp:g} muW steel pair", "converge", *case_amplitude(amp)))
    out.append(("T*=1 muW (gross sliding)", "diagnostic", *case_gross_sliding()))
    if not quick:
        out.append(("T*=1e-6 muW coupled, frictionless preload", "converge",
                    *case_frictionless_preload()))
    for nu in (0.0, 0.5):
        out.append((f"nu={nu:g} steel-like pair", "converge", *case_poisson(nu, False)))
        if not quick or nu == 0.5:
            out.append((f"nu={nu:g} rigid/elastic", "converge", *case_poisson(nu, True)))
    out.append(("indenter 1e6x stiffer", "converge", *case_stiffness("stiff-indenter")))
    out.append(("indenter 1e6x softer", "converge", *case_stiffness("soft-indenter")))
    out.append(("Kelvin-Voigt nu=0.5, tau=10 t_r", "converge", *case_kelvin_voigt(0.5)))
    if not quick:
        out.append(("Kelvin-Voigt nu=0.3, tau=10 t_r", "converge", *case_kelvin_voigt(0.3)))
        out.append(("Kelvin-Voigt nu=0.3, tau=t_r", "converge",
                    *case_kelvin_voigt(0.3, window=1.0)))
    out.append(("one time step", "converge", *case_one_step()))
    out.append(("10000 steps (16^2)" if not quick else "1000 steps (16^2)", "converge",
                *case_many_steps(1000 if quick else 10_000)))
    out.append(("fixed grid 3a_H, tau/t'=100", "diagnostic", *case_grid_too_small()))
    return out


# --------------------------------------------------------------------------- running
def run_case(name, expect, build, check, folder):
    res = Result(case=name, expect=expect)
    t0 = time.perf_counter()
    slug = "".join(ch if ch.isalnum() or ch in "-_.=" else "_" for ch in name)
    path = folder / f"{slug}.nc"
    if path.exists():
        path.unlink()
    try:
        scene = build()
    except cp.SceneError as exc:
        res.seconds = time.perf_counter() - t0
        res.outcome = "SceneError"
        res.message = str(exc)
        res.passed = expect in ("diagnostic", "either")
        res.check = "refused on validation"
        res.measured = str(exc)[:90]
        return res
    try:
        ds = cp.simulate(scene, path).load()
    except cp.ContactpipeError as exc:
        res.seconds = time.perf_counter() - t0
        res.outcome = type(exc).__name__
        res.message = str(exc)
        left = path.exists()
        res.passed = expect in ("diagnostic", "either") and not left and "step" in str(exc)
        res.check = "stops with a diagnostic naming the step, no archive left" + \
            (" (an archive was left!)" if left else "")
        res.measured = str(exc)[:90]
        return res
    except Exception as exc:   # a crash is always a failure
        res.seconds = time.perf_counter() - t0
        res.outcome = f"CRASH {type(exc).__name__}"
        res.message = traceback.format_exc()
        res.measured = str(exc)[:90]
        return res
    run_s = time.perf_counter() - t0
    res.outcome = "converged"
    problems = verify(ds, scene)
    if check is None:
        ok, what, measured, data = True, "", "", {}
    else:
        ok, what, measured, data = check(ds, scene)
    res.seconds = run_s
    res.data = {"wall_s": float(ds.attrs.get("wall_time_s", run_s)),
                "fft_pairs_per_step": float(np.mean(ds.fft_pairs.values[1:]))
                if ds.sizes["time"] > 1 else float(ds.fft_pairs.values[0]),
                "max_iterations": int(ds.iterations.values.max()), **data}
    res.check = "; ".join(x for x in ("laws, finite, load carried", what) if x)
    res.measured = "; ".join(x for x in (measured, *problems) if x)
    res.passed = expect in ("converge", "either") and ok and not problems
    return res


def print_table(results):
    w = max(len(r.case) for r in results)
    print(f"\n{'case':{w}s}  {'outcome':17s} {'pass':4s} {'time':>7s} {'pairs':>6s}  "
          f"check | measured")
    for r in results:
        pairs = r.data.get("fft_pairs_per_step")
        pairs = f"{pairs:6.0f}" if pairs is not None else "     -"
        print(f"{r.case:{w}s}  {r.outcome:17s} {'ok' if r.passed else 'FAIL':4s} "
              f"{r.seconds:6.1f}s {pairs}  {r.check} | {r.measured}")
    failed = [r for r in results if not r.passed]
    print(f"\n{len(results) - len(failed)} of {len(results)} cases as expected")
    for r in failed:
        print(f"\nFAILED: {r.case} ({r.expect} expected) -> {r.outcome}\n  {r.measured}\n"
              f"  {r.message[:600]}")


def main(argv=None):
    p = c.parser(__doc__.splitlines()[0], __doc__)
    p.add_argument("--only", nargs="+", help="run the cases whose name contains one of these")
    args = p.parse_args(argv)
    out = c.out_dir(args)
    folder = out / "extremes"
    folder.mkdir(exist_ok=True)
    todo = cases(args.quick)
    if args.only:
        todo = [t for t in todo if any(s in t[0] for s in args.only)]
    results = []
    for name, expect, build, check in todo:
        r = run_case(name, expect, build, check, folder)
        print(f"{name}: {r.outcome} ({'ok' if r.passed else 'FAIL'}) {r.seconds:.1f} s "
              f"{r.measured}", flush=True)
        results.append(r)
    print_table(results)
    path = out / "extremes.csv"
    with open(path, "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["case", "expect", "outcome", "passed", "seconds", "check", "measured",
                     "message"])
        for r in results:
            wr.writerow([r.case, r.expect, r.outcome, r.passed, f"{r.seconds:.2f}", r.check,
                         r.measured, r.message.replace("\n", " | ")])
    print(f"wrote {path}")
    return {"results": results, "csv": path}


if __name__ == "__main__":
    res = main(sys.argv[1:])
    sys.exit(0 if all(r.passed for r in res["results"]) else 1)
