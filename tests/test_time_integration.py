"""Time integration of the hereditary integral (issue 9): the rule "bdf2" is stable, free of
step-to-step oscillation and second order for every creep law; the step-start rule's
stability bound; the pressure FIELD and the contact AREA against Lee-Radok.

Rigid sphere R = 18 mm, W = 1 kN stepped at t0, half-space E = 105 GPa, nu = 0.3,
frictionless, window 2 s (2 tau). Measures (docs/time-integration.md):

* radius from the contact area, a = sqrt(area / pi), against Lee-Radok's a(t), in cells,
  for t >= 0.25 tau;
* holes: cells with p = 0 inside 0.8 a(t), at every instant after t0;
* zigzag of the centre pressure p_c (mean of the four centre cells) after t0: the largest
  amplitude min(|D_k|, |D_k+1|, |D_k+2|) of three consecutive increments D = diff(p_c) that
  alternate in sign (up-down-up), over the final p_c; a relaxation is monotone, and a
  single jump of the contact's discrete growth gives no such pattern;
* the pressure field inside 0.8 a(t) against Lee-Radok p(r, t) at the cell centres,
  relative to Lee-Radok's centre pressure.
"""
import numpy as np
import pytest
from scipy import integrate

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.materials import (
    ExponentialCreep,
    TabulatedCreep,
    kelvin_voigt,
    maxwell,
    prony,
    step_start_stable_step,
    zener,
)
from contactpipe.planning.accuracy import resolve_accuracy
from contactpipe.solver.memory import (
    DirectMemory,
    RecursiveMemory,
    error_amplification,
    fitted_bdf2_coefficients,
    is_monotone,
    make_memory,
    resolve_rule,
)
from contactpipe.testing import creep_laws, lee_radok_measures, zigzag

R, W, E, NU = 0.018, 1000.0, 105e9, 0.3
LAWS = creep_laws(E)
CREEPS = {name: creep for name, (_, creep) in LAWS.items()}
CREEPS["burgers"] = prony([[3.0, 1.0]], 0.5)
CREEPS["zener1e4"] = zener(1e4, 1.0, 1.0)


# --------------------------------------------------------------------------- helpers
def lee_radok_scene(law, n, steps, size="auto", rule="auto", ramp=None):
    keys = LAWS[law][0]
    if ramp is None:
        load = {"time": [0.0, 2.0], "normal_force": W}
    elif ramp == 2.0:
        load = {"time": [0.0, 2.0], "normal_force": [0.0, W]}
    else:
        load = {"time": [0.0, ramp, 2.0], "normal_force": [0.0, W, W]}
    return cp.Scene(name=f"lr-{law}", geometry={"shape": "sphere", "radius": R},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E, "poisson": NU, **keys},
                    load=load, grid={"points": [n, n], "size": size}, time={"steps": steps},
                    solver={"time_rule": rule, "tolerance": 1e-10})


def kelvin_voigt_closed_form(r, t, tau=1.0):
    """Lee-Radok pressure [Pa] under a rigid sphere on a Kelvin-Voigt half-space (E the
    long-term modulus), W stepped at 0, written out: the relaxation modulus
    E (1 + tau delta(t)) turns the hereditary integral into
    p = 2E/(pi R (1 - nu^2)) (h + tau dh/dt), h = sqrt(a^2 - r^2),
    a^3 = a_inf^3 (1 - exp(-t/tau)) (infinite at the growing edge). The check of
    analytic.lee_radok_pressure's branch for phi(0) = 0, which the tests below use."""
    a_inf3 = 3 * W * R * (1 - NU ** 2) / (4 * E)
    a = (a_inf3 * -np.expm1(-t / tau)) ** (1 / 3)
    h = np.sqrt(np.clip(a ** 2 - np.asarray(r) ** 2, 0.0, None))
    rate = np.divide(a_inf3 * np.exp(-t / tau) / (3 * tau * a), h, out=np.zeros_like(h),
                     where=h > 0)
    return 2 * E / (np.pi * R * (1 - NU ** 2)) * (h + tau * rate)


def lee_radok_p(law, r, t):
    return an.lee_radok_pressure(r, t, W, R, E, NU, CREEPS[law], n_steps=1000)


def field_measures(ds, law, t_min=0.25, t_field=None):
    """Radius (cells), holes, zigzag and the pressure-field error of a step-load run."""
    return lee_radok_measures(ds, CREEPS[law], E, NU, R, W, t_min=t_min, t_field=t_field)


# --------------------------------------------------------------------------- the scheme
@pytest.mark.parametrize("x", np.logspace(-9, 3, 25))
def test_fitted_bdf2_coefficients_are_exact_for_linear_traction(x):
    """The fitted formula is exact for 1, t - tau (sigma linear) and exp(-t/tau) (free decay)
    at every x = dt/tau; BDF2 as x -> 0, BDF1 as x -> inf."""
    a1, a2, b0 = fitted_bdf2_coefficients(x)
    assert a1 + a2 + b0 == pytest.approx(1.0, abs=1e-14)
    assert a1 * (1 + x) + a2 * (1 + 2 * x) == pytest.approx(1.0, abs=1e-13)
    assert a1 * np.exp(-x) + a2 == pytest.approx(np.exp(-2 * x), abs=1e-15)
    if x < 1e-6:
        assert (a1, a2, b0 / x) == pytest.approx((4 / 3, -1 / 3, 2 / 3), rel=1e-5)
    if x > 100:
        assert (a1, b0) == pytest.approx((1 / (1 + x), x / (1 + x)), rel=1e-9)


@pytest.mark.parametrize("name", list(CREEPS))
def test_bdf2_error_never_flips_sign(name):
    """Amplification factors of the traction error under a held displacement, dt/tau from
    1e-3 to 100 (41 values): "bdf2" keeps them in the unit disc with no negative real part
    (measured: none at all), for every law; the exponentially fitted coefficients change
    nothing there against plain BDF2's stability."""
    creep = CREEPS[name]
    for dt in np.logspace(-3, 2, 41):
        for fitted in (True, False):
            g = error_amplification(creep, dt, "bdf2", fitted=fitted)
            assert np.abs(g).max() <= 1 + 1e-12, (name, dt, g)
            assert not np.any((g.real < -1e-12) & (np.abs(g) > 1e-6)), (name, dt, fitted, g)


@pytest.mark.parametrize("name,dt,worst", [("kelvin_voigt", 0.05, -0.98),
                                           ("zener100", 0.1, -0.64)])
def test_linear_rule_flips_the_error(name, dt, worst):
    """The diagnosis of issue 9: the trapezoid-type "linear" rule has an amplification factor
    near -1 for Kelvin-Voigt (-1 + dt/(3 tau)) and -0.644 for Zener E0/Einf = 100 at
    dt = 0.1 tau: the error alternates in sign and barely decays."""
    g = error_amplification(CREEPS[name], dt, "linear")
    assert g.real.min() < worst
    assert not is_monotone(CREEPS[name], dt, "linear")
    assert is_monotone(CREEPS[name], dt, "bdf2")


@pytest.mark.parametrize("name", ["maxwell", "kelvin_voigt", "zener100", "prony3", "burgers"])
def test_bdf2_recursion_equals_convolution_quadrature(name):
    """Plain BDF2 (fitted=False) on the internal variables is Lubich's BDF2 convolution
    quadrature of the Stieltjes integral (started by two BDF1 steps), which the direct sum
    computes from the Laplace-Stieltjes transform by FFT: 300 random steps of dt = 0.1 s,
    equal to 1e-9 of the largest history (measured 6e-12 to 1e-10)."""
    creep = CREEPS[name]
    rng = np.random.default_rng(3)
    a = RecursiveMemory(creep, 0.1, "bdf2", (3, 4), fitted=False)
    b = DirectMemory(creep, 0.1, "bdf2", (3, 4))
    worst, scale = 0.0, 1.0
    for _ in range(300):
        assert b.instant_weight == pytest.approx(a.instant_weight, rel=1e-10)
        ka = a.known()
        worst = max(worst, float(np.abs(ka - b.known()).max()))
        scale = max(scale, float(np.abs(ka).max()))
        s = rng.normal(size=(3, 4))
        a.commit(s)
        b.commit(s)
    assert worst < 1e-9 * scale


def test_tabulated_creep_bdf2():
    """A table linear up to 100 s is Maxwell's phi over a 30 s run: the direct sum's BDF2
    weights (from the table's exact Laplace-Stieltjes transform) reproduce the recursion
    to 1e-9; the transform matches quadrature of dphi."""
    tab = TabulatedCreep(t=(0.0, 100.0), phi=(1.0, 1.0 + 100.0 / 1.3))
    a = RecursiveMemory(maxwell(1.3), 0.1, "bdf2", (2,), fitted=False)
    b = make_memory(tab, 0.1, "bdf2", (2,))
    assert isinstance(b, DirectMemory)
    rng = np.random.default_rng(1)
    for _ in range(300):
        assert b.instant_weight == pytest.approx(a.instant_weight, rel=1e-10)
        np.testing.assert_allclose(b.known(), a.known(), rtol=0, atol=1e-9 * 30)
        s = rng.normal(size=2)
        a.commit(s)
        b.commit(s)
    table = TabulatedCreep(t=(0.0, 0.5, 1.0, 3.0), phi=(0.0, 0.6, 0.8, 1.0))
    for s in (0.3, 2.0 + 1.0j, 10.0 - 3.0j):
        def part(t, f, s=s):
            return f(np.exp(-s * t) * table.derivative(t))
        quad = sum(integrate.quad(part, lo, hi, args=(np.real,))[0]
                   + 1j * integrate.quad(part, lo, hi, args=(np.imag,))[0]
                   for lo, hi in ((0, 0.5), (0.5, 1), (1, 3)))
        assert complex(table.stieltjes(np.array([s]))[0]) == pytest.approx(quad, rel=1e-10)


def test_bdf2_state_round_trip():
    """A checkpoint (state / load_state) taken after the start continues identically, the
    start kind included."""
    creep = CREEPS["zener100"]
    rng = np.random.default_rng(2)
    a = RecursiveMemory(creep, 0.1, "bdf2", (5,))
    for _ in range(4):
        a.commit(rng.normal(size=5) + 3)
    b = RecursiveMemory(creep, 0.1, "bdf2", (5,))
    b.load_state({k: np.array(v) for k, v in a.state().items()})
    assert b.start == a.start == "exponential_euler"
    for _ in range(5):
        assert b.instant_weight == a.instant_weight
        np.testing.assert_array_equal(b.known(), a.known())
        s = rng.normal(size=5)
        a.commit(s)
        b.commit(s)


def test_start_follows_the_jump():
    """After a jump at t0 "bdf2" starts with two exponential-Euler steps (blind to sigma_0,
    exact for a constant traction); a traction growing from zero starts with one
    trapezoid step (exact for a linear growth); plain BDF2 with two BDF1 steps."""
    for name, jump, start, steps in (("kelvin_voigt", 1.0, "exponential_euler", 2),
                                     ("zener2", 1.0, "exponential_euler", 2),
                                     ("kelvin_voigt", 0.0, "linear", 1)):
        m = RecursiveMemory(CREEPS[name], 0.1, "bdf2", (2,))
        m.commit(np.full(2, jump))
        assert (m.start, m.start_steps) == (start, steps), name
    m = RecursiveMemory(CREEPS["zener2"], 0.1, "bdf2", (2,), fitted=False)
    m.commit(np.zeros(2))
    assert (m.start, m.start_steps) == ("bdf1", 2)


@pytest.mark.parametrize("name,dt,rule", [
    ("maxwell", 0.1, "linear"), ("maxwell", 1.9, "linear"), ("maxwell", 2.1, "bdf2"),
    ("zener2", 0.1, "linear"), ("zener100", 0.1, "bdf2"), ("zener100", 0.01, "linear"),
    ("kelvin_voigt", 0.05, "bdf2"), ("prony3", 0.1, "linear"), ("prony3", 0.2, "bdf2")])
def test_auto_rule(name, dt, rule):
    """"auto" takes "linear" exactly where its error keeps its sign (Maxwell: dt < 2 t';
    Zener 100: dt below about 0.02 tau), "bdf2" elsewhere and for a table without
    instantaneous elasticity (phi(0) = 0), "linear" for a table with it."""
    assert resolve_rule(CREEPS[name], dt, "auto") == rule
    assert make_memory(CREEPS[name], dt, "auto", (2,)).rule == rule
    assert make_memory(TabulatedCreep(t=(0.0, 1.0), phi=(0.0, 2.0)), dt, "auto",
                       (2,)).rule == "bdf2"
    assert make_memory(TabulatedCreep(t=(0.0, 100.0), phi=(1.0, 2.0)), dt, "auto",
                       (2,)).rule == "linear"


@pytest.mark.parametrize("name,dt", [("maxwell", 0.1), ("maxwell", 2.5), ("zener2", 0.1),
                                     ("zener100", 0.1), ("zener100", 0.01),
                                     ("kelvin_voigt", 0.05), ("burgers", 0.1)])
def test_auto_rule_of_a_table_sampled_from_a_law(name, dt):
    """A table sampled from a law (5 knots a step over 120 steps) gets the rule "auto"
    gives the law itself: its error followed step by step (linear_error_keeps_sign)
    zigzags exactly where the law's amplification factors say it alternates."""
    tt = np.linspace(0.0, 120 * dt, 601)
    table = TabulatedCreep(t=tuple(tt), phi=tuple(CREEPS[name](tt)))
    assert resolve_rule(table, dt, "auto") == resolve_rule(CREEPS[name], dt, "auto")


@pytest.mark.parametrize("rule,ratio", [("auto", 1.5), ("linear", 1.5),
                                        ("bdf2", 1.4208)])
def test_auto_rule_of_a_table_on_a_flat_punch(rule, ratio):
    """A rigid flat punch (a = 0.5 mm) on a tabulated half-space, W stepped: the contact
    stays the punch's face, so omega3(t)/omega3(0) = phi(t) exactly (1.5 at 1 s for
    phi = 1, 1.2, 1.5 at 0, 0.5, 1 s). 32^2, 5 steps: "auto" takes "linear", exact to
    1e-9 (measured 2e-14); plain BDF2 is 5.3 % off (1.4208), as before the fix."""
    a = 0.5e-3
    sc = cp.Scene(name="punch", geometry={"shape": "flat_punch", "radius": a},
                  indenter={"material": "rigid"},
                  halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                             "creep": "tabulated", "table": [[0, 1], [0.5, 1.2], [1, 1.5]]},
                  load={"time": [0.0, 1.0], "normal_force": W},
                  grid={"points": [32, 32], "size": [2.5 * a] * 2}, time={"steps": 5},
                  solver={"time_rule": rule, "tolerance": 1e-10})
    ds = cp.simulate(sc)
    got = float(ds.omega3[-1] / ds.omega3[0])
    assert got == pytest.approx(ratio, rel=1e-9 if ratio == 1.5 else 1e-4)
    if rule == "auto":
        assert ds.attrs["time_rule_resolved"] == "halfspace: linear"


# --------------------------------------------------------------------------- order
def _smooth_history(t):
    return 1.0 - np.cos(2.0 * t) + 0.5 * t          # H(0) = 0: no jump to resolve


def _invert(creep, steps, rule, t_end=2.0):
    """sigma_k from a prescribed history H(t_k) (the held-displacement model problem)."""
    m = RecursiveMemory(creep, t_end / steps, rule, ())
    t = np.linspace(0.0, t_end, steps + 1)
    out = []
    for tk in t:
        w = m.instant_weight
        s = 0.0 if w == 0 else (_smooth_history(tk) - float(m.known())) / w
        m.commit(np.array(s))
        out.append(s)
    return t, np.array(out)


def _observed_order(series, t, t_min=0.25):
    """log2 of successive differences of runs with N, 2N, 4N steps (on the N-step instants)."""
    coarse = [s[::2 ** i] for i, s in enumerate(series)]
    m = t >= t_min
    d1 = np.abs(coarse[0][m] - coarse[1][m]).max()
    d2 = np.abs(coarse[1][m] - coarse[2][m]).max()
    return float(np.log2(d1 / d2))


@pytest.mark.parametrize("name", list(CREEPS))
def test_order_held_displacement(name):
    """The traction under a smooth prescribed history (no contact): "bdf2" converges with
    order >= 1.8 for every law, Kelvin-Voigt included (40 / 80 / 160 steps over 2 s;
    measured 1.96-2.00); the step-start rule is first order where it applies (1.02-1.05)."""
    creep = CREEPS[name]
    runs = [_invert(creep, s, "bdf2") for s in (40, 80, 160)]
    order = _observed_order([r[1] for r in runs], runs[0][0])
    assert order >= 1.8, f"{name}: observed order {order:.2f}"
    if creep.phi0 > 0 and step_start_stable_step(creep) > 0.05:
        runs = [_invert(creep, s, "step_start") for s in (40, 80, 160)]
        order = _observed_order([r[1] for r in runs], runs[0][0])
        assert 0.8 < order < 1.2, f"{name} step-start: observed order {order:.2f}"


def rounded_punch_scene(law, n, steps, gap_file, rule="bdf2"):
    """A rigid punch with a spherical face (R = 18 mm, face radius 0.3 mm, a 10 mm step
    outside), grid 0.8 mm, W = 1 kN stepped at t0 then ramped to 1.5 kN over 2 s: the whole
    face stays in contact (no cell enters or leaves: the contact's discrete growth, which
    limits the order of a sphere's pressure field on a fixed grid, is absent), while the
    pressure is not proportional to W (flat-punch and curvature parts relax apart)."""
    return cp.Scene(name=f"punch-{law}", geometry={"shape": "surface", "file": str(gap_file)},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                               **LAWS[law][0]},
                    load={"time": [0.0, 2.0], "normal_force": [1000.0, 1500.0]},
                    grid={"points": [n, n], "size": [0.8e-3, 0.8e-3]}, time={"steps": steps},
                    solver={"time_rule": rule, "tolerance": 1e-10})


@pytest.mark.parametrize("law", list(LAWS))
def test_order_pressure_field(law, tmp_path):
    """The pressure FIELD of the rounded punch, 16^2, 40 / 80 / 160 steps over 2 tau:
    "bdf2" converges with order >= 1.8 over t >= 0.25 tau (measured 2.00 Maxwell, 2.03
    Zener 2, 2.17 Prony; 5.2 Zener 100, whose fast relaxation is over within the first
    steps). Kelvin-Voigt, once the face is in full contact (t >= 0.5 tau), is integrated
    exactly for a linear load: the runs agree to 1e-9 of the peak pressure (measured 1e-11)."""
    n = 16
    x = -0.4e-3 + (np.arange(n) + 0.5) * 0.8e-3 / n
    r = np.hypot(*np.meshgrid(x, x, indexing="ij"))
    gap_file = tmp_path / "punch.npy"
    np.save(gap_file, np.where(r <= 0.3e-3, r ** 2 / (2 * R), 0.01))
    runs = [cp.simulate(rounded_punch_scene(law, n, s, gap_file)) for s in (40, 80, 160)]
    p = [ds.p.values[::2 ** i] for i, ds in enumerate(runs)]
    assert all(np.all((ds.p.values[-1] > 0) == (r <= 0.3e-3)) for ds in runs)
    t = runs[0].time.values
    if law == "kelvin_voigt":
        late = t >= 0.5
        diff = max(np.abs(p[0][late] - p[1][late]).max(), np.abs(p[1][late] - p[2][late]).max())
        assert diff < 1e-9 * p[2].max()
        return
    late = t >= 0.25
    order = np.log2(np.abs(p[0][late] - p[1][late]).max() / np.abs(p[1][late] - p[2][late]).max())
    assert order >= 1.8, f"{law}: observed order of the pressure field {order:.2f}"


# --------------------------------------------------------------------------- step-start bound
def test_step_start_bound_closed_forms():
    """Maxwell 2 t'; Zener tau ln(r / (r - 2)) (r = E0/Einf > 2; any step for r <= 2);
    Kelvin-Voigt never stable; the small-step form 2 phi0/phi'(0) is a lower bound, exact
    for Maxwell; the issue's Maxwell case dt = 3 t' exceeds it."""
    assert step_start_stable_step(maxwell(1.5)) == pytest.approx(3.0, rel=1e-14)
    assert 3.0 * 1.0 > step_start_stable_step(maxwell(1.0))
    for r in (2.5, 3.0, 10.0, 100.0):
        bound = step_start_stable_step(zener(r, 1.0, 0.7))
        assert bound == pytest.approx(0.7 * np.log(r / (r - 2)), rel=1e-12)
        assert bound >= 2 * 0.7 / (r - 1)
    assert step_start_stable_step(zener(2.0, 1.0, 0.7)) == np.inf
    assert step_start_stable_step(kelvin_voigt(1.0)) == 0.0
    tab = TabulatedCreep(t=(0.0, 1.0, 2.0), phi=(1.0, 1.5, 1.6))
    assert step_start_stable_step(tab) == pytest.approx(4.0)
    with pytest.raises(ValueError, match="decreasing"):
        step_start_stable_step(ExponentialCreep(a=1.0, d=(0.5,), tau=(1.0,)))


@pytest.mark.parametrize("seed", range(6))
def test_step_start_bound_is_sharp(seed):
    """Random Prony series with a dashpot (1-3 terms): the step-start recursion's largest
    amplification factor is below 1 at 0.999 x the bound and above 1 at 1.001 x (the
    factor leaves the unit disc through -1 there)."""
    rng = np.random.default_rng(seed)
    terms = [[rng.uniform(0.1, 20), 10 ** rng.uniform(-1, 1)] for _ in range(rng.integers(1, 4))]
    creep = prony(terms, 10 ** rng.uniform(-1, 1) if seed % 2 else None)
    bound = step_start_stable_step(creep)
    assert np.isfinite(bound)
    below = np.abs(error_amplification(creep, 0.999 * bound, "step_start")).max()
    above = error_amplification(creep, 1.001 * bound, "step_start")
    assert below < 1.0
    assert np.abs(above).max() > 1.0
    assert above[0].real < -1.0


# --------------------------------------------------------------------------- Lee-Radok fields
def test_kelvin_voigt_pressure_carries_the_load():
    """analytic.lee_radok_pressure for phi(0) = 0: Kelvin-Voigt equals the closed form
    above to round-off (r up to 1.2 a but not at the singular edge, t = 0.1, 0.5, 2 tau) and
    integrates to W (radial quadrature with the edge singularity taken by the substitution
    r = a sin(theta)); a
    two-term Kelvin chain (no closed form: its regular relaxation part integrated by the
    product-trapezoid rule, 4000 steps) carries W within 1e-6 (measured 2e-8)."""
    chain = ExponentialCreep(a=1.0, d=(-0.4, -0.6), tau=(0.3, 2.0))
    for t in (0.1, 0.5, 2.0):
        a = ((3 * W * R * (1 - NU ** 2) / (4 * E)) * -np.expm1(-t)) ** (1 / 3)
        r = np.linspace(0.0, 1.2 * a, 24)              # r = a (singular) left out
        np.testing.assert_allclose(lee_radok_p("kelvin_voigt", r, t),
                                   kelvin_voigt_closed_form(r, t), rtol=1e-12, atol=0)
        force = integrate.quad(lambda th, a=a, t=t: lee_radok_p("kelvin_voigt", a * np.sin(th), t)
                               * 2 * np.pi * a * np.sin(th) * a * np.cos(th), 0, np.pi / 2,
                               limit=200)[0]
        assert force == pytest.approx(W, rel=1e-8)
    for t in (0.2, 1.0):
        a = ((3 * W * R * (1 - NU ** 2) / (4 * E)) * float(chain(t))) ** (1 / 3)
        force = integrate.quad(lambda th, a=a, t=t: float(an.lee_radok_pressure(
            np.array([a * np.sin(th)]), t, W, R, E, NU, chain, n_steps=4000)[0])
            * 2 * np.pi * a * np.sin(th) * a * np.cos(th), 0, np.pi / 2, limit=200)[0]
        assert force == pytest.approx(W, rel=1e-6)


def test_kelvin_voigt_issue_case():
    """Issue 9, case 1: Kelvin-Voigt tau = 1 s, window 2 tau, 96^2 over 1.6 mm, 40 steps.
    "auto" (here "bdf2"): the radius from the area within 1 cell of Lee-Radok for t >= 0.25 tau
    (measured 0.24), no hole after t0 (0), no zigzag of the centre pressure (0), the field
    inside 0.8 a within 2 % of the centre pressure for t >= 0.5 tau (measured 1.5 %)."""
    m = field_measures(cp.simulate(lee_radok_scene("kelvin_voigt", 96, 40, [1.6e-3] * 2)),
                       "kelvin_voigt", t_field=0.5)
    assert m["radius_cells"] < 1.0 and m["holes"] == 0 and m["zigzag"] < 1e-3, m
    assert m["field"] < 0.02, m


@pytest.mark.slow
def test_kelvin_voigt_issue_case_linear_rule():
    """The same run with the trapezoid-type "linear" rule: the issue's finding (2.2 cells
    off, 252 holes): the measures above do see the failure."""
    m = field_measures(cp.simulate(lee_radok_scene("kelvin_voigt", 96, 40, [1.6e-3] * 2,
                                                   rule="linear")), "kelvin_voigt")
    assert m["radius_cells"] > 2.0 and m["holes"] > 100, m


def test_stiff_zener_issue_case():
    """Issue 9, case 2: Zener E0/Einf = 100, tau = 1 s, steps of 0.1 tau (20 over 2 tau),
    96^2 auto-sized, "auto" (here "bdf2"): radius within 1 cell for t >= 0.25 tau (measured
    0.19), no hole (0), no zigzag (0), field within 3 % of the centre pressure for t >= 0.7 tau
    (2.5 %; the
    error near t0 is the time step's: 27 % at 0.3 tau with 20 steps, 1.1 % with 160)."""
    m = field_measures(cp.simulate(lee_radok_scene("zener100", 96, 20)), "zener100",
                       t_field=0.7)
    assert m["radius_cells"] < 1.0 and m["holes"] == 0 and m["zigzag"] < 1e-3, m
    assert m["field"] < 0.03, m


@pytest.mark.parametrize("law,rule,bound", [
    ("maxwell", "auto", 0.006), ("zener2", "auto", 0.003), ("prony3", "auto", 0.012),
    ("maxwell", "bdf2", 0.01), ("zener2", "bdf2", 0.008), ("prony3", "bdf2", 0.025)])
def test_lee_radok_fields(law, rule, bound):
    """Maxwell, Zener E0/Einf = 2 and a 3-term Prony series with a dashpot, 48^2 auto-sized,
    20 steps over 2 s ("auto" resolves to "linear" for all three): radius within 1 cell
    (measured 0.22, 0.24, 0.23 with both rules), no hole, no zigzag, and the field inside
    0.8 a within the stated fraction of the centre pressure for t >= 0.25 tau (measured
    "auto" 0.38 %, 0.13 %, 0.75 %; "bdf2" 0.73 %, 0.50 %, 1.7 %)."""
    m = field_measures(cp.simulate(lee_radok_scene(law, 48, 20, rule=rule)), law, t_field=0.25)
    assert m["radius_cells"] < 1.0 and m["holes"] == 0 and m["zigzag"] < 1e-3, m
    assert m["field"] < bound, m


def test_tabulated_kelvin_voigt_like_creep_has_no_holes():
    """A tabulated phi starting at 0 (no instantaneous elasticity) takes the direct sum with
    BDF2 weights ("auto" resolves to "bdf2" for it): 48^2 over 1.6 mm, 20 steps: no
    hole, radius within 1 cell of the Kelvin-Voigt it samples (table every 0.05 s)."""
    ts = np.linspace(0.0, 3.0, 61)
    table = [[float(t), float(-np.expm1(-t))] for t in ts]
    sc = cp.Scene(name="tab", geometry={"shape": "sphere", "radius": R},
                  indenter={"material": "rigid"},
                  halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                             "creep": "tabulated", "table": table},
                  load={"time": [0.0, 2.0], "normal_force": W},
                  grid={"points": [48, 48], "size": [1.6e-3, 1.6e-3]}, time={"steps": 20},
                  solver={"time_rule": "auto", "tolerance": 1e-10})
    ds = cp.simulate(sc)
    assert "memory=direct" in ds.attrs["models"]
    m = field_measures(ds, "kelvin_voigt")
    assert m["radius_cells"] < 1.0 and m["holes"] == 0, m


@pytest.mark.slow
def test_kelvin_voigt_converges_with_many_steps():
    """Issue 9: "with 2000 steps it is worse, not better". Kelvin-Voigt at 48^2 over 1.6 mm
    with 2000 steps: "auto" ("bdf2") keeps the radius within 1 cell (measured 0.28; "linear"
    1.28) and no hole (linear: 64). The centre pressure then resolves each ring of cells
    entering the contact (the semi-discrete Kelvin-Voigt pressure jumps there): before
    0.01 tau, with 4 to 32 cells in contact, that reads as a zigzag of 0.85 p_c; from
    0.25 tau on, 1.1e-3 p_c at most (bound 2e-3)."""
    ds = cp.simulate(lee_radok_scene("kelvin_voigt", 48, 2000, [1.6e-3] * 2))
    m = field_measures(ds, "kelvin_voigt")
    assert m["radius_cells"] < 1.0 and m["holes"] == 0, m
    t = ds.time.values
    pc = ds.p.values[:, 23:25, 23:25].mean(axis=(1, 2))
    assert zigzag(pc[t >= 0.25]) / pc[-1] < 2e-3


@pytest.mark.slow
@pytest.mark.parametrize("law", list(LAWS))
def test_lee_radok_fields_full_size(law):
    """Every law at 128^2 (auto, 1.6 mm for Kelvin-Voigt) with 80 steps, "auto": radius within
    1 cell (measured 0.18-0.22), no hole, no zigzag (1e-4 at most), field within 2 % of the
    centre pressure for t >= 0.5 tau (measured 0.02 % Zener 2 to 0.67 % Kelvin-Voigt)."""
    size = [1.6e-3] * 2 if law == "kelvin_voigt" else "auto"
    m = field_measures(cp.simulate(lee_radok_scene(law, 128, 80, size)), law, t_field=0.5)
    assert m["radius_cells"] < 1.0 and m["holes"] == 0 and m["zigzag"] < 1e-3, m
    assert m["field"] < 0.02, m


# --------------------------------------------------------------------------- presets
@pytest.mark.parametrize("law,per_tau", [("kelvin_voigt", 10), ("zener100", 10),
                                         ("maxwell", 5), ("zener2", 5)])
def test_balanced_preset_holds_for_every_law(law, per_tau):
    """solver.accuracy = "balanced" (target 1 %) on a ramp 0 -> W over tau held to 2 tau:
    a body whose memory takes "bdf2" (Kelvin-Voigt, Zener E0/Einf = 100) gets 10 steps per
    retardation time, the others keep 5; a^3 from the approach against Lee-Radok's
    hereditary integral within the target for t >= 0.25 tau (96^2 or 98^2 auto; measured
    0.40 % and 0.39 % at 10 steps per tau, where 5 gave 1.2 %; Maxwell 0.019 %, Zener 2
    0.016 %)."""
    sc = lee_radok_scene(law, 16, 1, ramp=1.0).replace({"solver.accuracy": "balanced",
                                                         "grid.size": "auto"})
    resolved, note = resolve_accuracy(sc)
    assert resolved.time.steps == 2 * per_tau, note
    ds = cp.simulate(sc)
    t = ds.time.values
    a_ref = an.lee_radok_radius(t, [0.0, 1.0, 2.0], [0.0, W, W], R, E, NU, CREEPS[law])
    a3 = (R * ds.omega3.values) ** 1.5
    late = t >= 0.25
    assert np.abs(a3[late] / a_ref[late] ** 3 - 1).max() < 0.01
