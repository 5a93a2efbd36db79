"""Creep functions fitted to measured data (materials.fit_*): exact on data a Prony series
on the fitted grid represents, the relaxation -> creep interconversion against closed
forms (Zener, Maxwell), the fit error reported, bad data refused; and scenes with
creep = "fit" and a table file (issue 9, item 6): the simulation of the series the table
was sampled from, the file relative to the scene and counted by the digest, refusals
naming the key."""
import numpy as np
import pytest

import contactpipe as cp
from contactpipe.materials import (
    PronyFit,
    fit_creep_compliance,
    fit_dynamic_moduli,
    fit_relaxation_modulus,
    kelvin_voigt,
    prony,
    zener,
)
from contactpipe.solver.memory import error_amplification

T = np.concatenate([[0.0], np.logspace(-2, 2, 60)])         # 0 and 10 ms .. 100 s


def test_creep_table_of_a_prony_series():
    """A compliance table sampled from a 3-term Prony series whose retardation times lie on
    the fit's grid (2 per decade over 1 ms-100 s): phi and E0 back to 1e-6 (measured
    8e-15), the reported error is the misfit (6e-15 rms), the fit's phi is stable under
    "bdf2"."""
    true = prony([[0.5, 0.1], [1.0, 1.0], [2.0, 10.0]])
    fit = fit_creep_compliance(T, true(T) / 2e9)
    assert isinstance(fit, PronyFit) and fit.source == "creep"
    assert fit.young == pytest.approx(2e9, rel=1e-6)
    tt = np.linspace(0.0, 300.0, 301)
    np.testing.assert_allclose(fit.creep(tt), true(tt), rtol=1e-6)
    assert fit.rms_error < 1e-6 and fit.max_error < 1e-6
    assert np.all(np.abs(error_amplification(fit.creep, 0.05, "bdf2")) <= 1.0)


def test_creep_table_without_instantaneous_compliance():
    """Kelvin-Voigt data (D(0) = 0): phi normalised by the long-term modulus, phi(0) = 0."""
    fit = fit_creep_compliance(T, kelvin_voigt(1.0)(T) / 1e9 + 0.0)
    assert fit.creep.phi0 == pytest.approx(0.0, abs=1e-12)
    assert fit.young == pytest.approx(1e9, rel=1e-6)
    np.testing.assert_allclose(fit.creep(T[1:]), kelvin_voigt(1.0)(T[1:]), rtol=1e-6)


def test_creep_table_with_a_dashpot():
    """Burgers data (one Kelvin element and a dashpot t' = 5 s): dashpot=True recovers b."""
    true = prony([[1.0, 1.0]], 5.0)
    fit = fit_creep_compliance(T, true(T) / 1e9, dashpot=True)
    assert fit.creep.b == pytest.approx(0.2, rel=1e-6)
    np.testing.assert_allclose(fit.creep(T), true(T), rtol=1e-6)


def test_power_law_creep_fit_error():
    """A broad spectrum the series does not contain (D = D0 (1 + t^0.3), 4 decades): the fit
    error is reported: 0.015 % rms, 0.070 % at most (2 terms per decade, free), 0.067 % /
    0.12 % with 1 (2.3 % at most before the grid reached a decade below the first
    sample: the creep faster than 10 ms had no term); phi positive and non-decreasing."""
    d = 1e-9 * (1.0 + T ** 0.3)
    two = fit_creep_compliance(T, d)
    one = fit_creep_compliance(T, d, terms_per_decade=1)
    assert two.rms_error < 0.0005 and two.max_error < 0.002
    assert one.rms_error < 0.001 and one.max_error < 0.002
    assert np.all(np.diff(two.creep(np.logspace(-4, 4, 200))) >= 0)


def test_relaxation_table_converts_to_zener_creep():
    """E(t) = Einf + (E0 - Einf) exp(-t/tau_R), tau_R = 1 s on the grid: the creep function
    is Zener's with retardation time tau_R E0/Einf (closed-form interconversion), 1e-6."""
    e0, e_inf = 3e9, 1e9
    fit = fit_relaxation_modulus(T, e_inf + (e0 - e_inf) * np.exp(-T / 1.0))
    assert fit.young == pytest.approx(e0, rel=1e-6)
    tt = np.linspace(0.0, 30.0, 61)
    np.testing.assert_allclose(fit.creep(tt), zener(e0, e_inf, 3.0)(tt), rtol=1e-6)


def test_relaxation_table_of_a_maxwell_fluid():
    """E(t) = E0 exp(-t/tau): no long-term modulus, so the creep function has a dashpot,
    phi = 1 + t/tau (exactly the materials.maxwell form)."""
    fit = fit_relaxation_modulus(T, 3e9 * np.exp(-T / 1.0))
    assert fit.creep.b == pytest.approx(1.0, rel=1e-6)
    assert fit.creep.a == pytest.approx(1.0, rel=1e-6)
    np.testing.assert_allclose(fit.creep(T), 1.0 + T, rtol=1e-6)


def test_dynamic_moduli_convert_to_the_same_creep():
    """Storage and loss moduli of a two-term generalised Maxwell model (tau on the grid of
    2 per decade over 1/(2 pi f)): the creep function equals the one fitted from its
    relaxation table (both are exact interconversions), 1e-6."""
    f = np.logspace(-3, 2, 41)
    w = 2 * np.pi * f
    e_inf, terms = 1e9, [(2e9, 1 / (2 * np.pi)), (1e9, 10 / (2 * np.pi))]
    storage = e_inf + sum(e * (w * t) ** 2 / (1 + (w * t) ** 2) for e, t in terms)
    loss = sum(e * w * t / (1 + (w * t) ** 2) for e, t in terms)
    dyn = fit_dynamic_moduli(f, storage, loss)
    assert dyn.rms_error < 1e-6
    relax = fit_relaxation_modulus(T, e_inf + sum(e * np.exp(-T / t) for e, t in terms),
                                   times=[t for _, t in terms])
    assert dyn.young == pytest.approx(4e9, rel=1e-6)
    tt = np.linspace(0.0, 50.0, 51)
    np.testing.assert_allclose(dyn.creep(tt), relax.creep(tt), rtol=1e-6)


@pytest.mark.parametrize("call,match", [
    (lambda: fit_creep_compliance(T, -np.ones_like(T)), "must be finite and > 0"),
    (lambda: fit_creep_compliance(T, np.where(T > 1, 0.9, 1.0) * 1e-9), "must not decrease"),
    (lambda: fit_relaxation_modulus(T, np.where(T > 1, 1.1, 1.0) * 1e9), "must not increase"),
    (lambda: fit_creep_compliance(T[::-1], np.ones_like(T)), "strictly ascending"),
    (lambda: fit_creep_compliance([0.0, 1.0], [1e-9, 2e-9]), "at least 3 points"),
    (lambda: fit_creep_compliance(T, np.full(T.size, np.nan)), "finite"),
    (lambda: fit_dynamic_moduli(np.logspace(-1, 1, 5), [5, 4, 3, 2, 1],
                                np.ones(5)), "storage modulus must not decrease"),
    (lambda: fit_creep_compliance(T, 1e-9 + T * 0, terms_per_decade=0), "terms_per_decade"),
    (lambda: fit_creep_compliance(T, 1e-9 + T * 0, times=[1.0, -1.0]), "times must be"),
])
def test_bad_data_refused(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_noise_within_the_allowance_is_fitted():
    """0.5 % Gaussian noise (seeded) on a Zener creep table drops the data by up to 1.6 %
    below its running maximum: refused with the default allowance (1 %), fitted with
    noise = 0.03, phi non-decreasing, rms error of the noise's size (measured 0.43 %)."""
    rng = np.random.default_rng(0)
    d = zener(3e9, 1e9, 1.0)(T) / 3e9 * (1 + 0.005 * rng.standard_normal(T.size))
    with pytest.raises(ValueError, match="noise allowance"):
        fit_creep_compliance(T, d)
    fit = fit_creep_compliance(T, d, noise=0.03)
    assert fit.rms_error < 0.006
    assert np.all(np.diff(fit.creep(np.logspace(-3, 3, 100))) >= 0)


# --------------------------------------------------------------------------- creep = "fit"
R_SPHERE, W_LOAD, NU = 0.018, 1000.0, 0.3


def write_table(path, columns, header="time, value"):
    rows = "\n".join(", ".join(f"{v:.17g}" for v in row) for row in zip(*columns, strict=True))
    path.write_text(f"# synthetic material data\n{header}\n{rows}\n")
    return path


def fit_scene(halfspace, n=24, steps=10, window=2.0):
    return cp.Scene(name="fit", geometry={"shape": "sphere", "radius": R_SPHERE},
                    indenter={"material": "rigid"}, halfspace=halfspace,
                    load={"time": [0.0, window], "normal_force": W_LOAD},
                    grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                    solver={"tolerance": 1e-10})


def assert_same_run(a, b, rtol):
    for v in ("p", "u3", "omega3", "contact_area"):
        x, y = a[v].values, b[v].values
        assert np.abs(x - y).max() <= rtol * np.abs(x).max(), v


def test_fit_scene_reproduces_the_prony_series(tmp_path):
    """A creep-compliance table sampled from a known Prony series (retardation times on the
    fit's grid) gives, through creep = "fit", the simulation of that series: 24^2, 10 steps,
    p, u3, omega3 and the contact area within 1e-6 (measured 1.5e-14); the fit error is in
    the archive attributes (measured 6e-15 rms, 1.2e-14 max) and young comes from the
    table."""
    e0, terms = 2e9, [[0.5, 0.1], [1.0, 1.0], [2.0, 10.0]]
    true = prony(terms)
    file = write_table(tmp_path / "creep.csv", (T, true(T) / e0))
    fitted = fit_scene({"material": "viscoelastic", "poisson": NU, "creep": "fit",
                        "file": str(file), "table_kind": "creep"})
    assert fitted.halfspace.young == pytest.approx(e0, rel=1e-7)
    ref = fit_scene({"material": "viscoelastic", "young": e0, "poisson": NU,
                     "creep": "prony", "terms": terms})
    a, b = cp.simulate(fitted), cp.simulate(ref)
    assert_same_run(a, b, 1e-6)
    assert a.attrs["halfspace_fit_rms_error"] < 1e-6
    assert a.attrs["halfspace_fit_max_error"] < 1e-6
    assert 3 <= a.attrs["halfspace_fit_terms"] <= 9          # at most one per grid time


@pytest.mark.parametrize("kind", ["relaxation", "dynamic"])
def test_fit_scene_from_zener_relaxation_data(kind, tmp_path):
    """A Zener relaxation modulus E(t) = Einf + (E0 - Einf) exp(-t/tau_R) with tau_R on the
    fit's grid (1 s for a relaxation table over 0.01-100 s; 10/(2 pi) s for storage and loss
    moduli over 1e-3 .. 1e2 Hz): creep = "fit" runs the simulation of creep = "zener"
    (E0, Einf, retardation time tau_R E0/Einf) within 1e-6 (measured 1.3e-8 relaxation,
    3.7e-9 dynamic)."""
    e0, e_inf = 3e9, 1e9
    if kind == "relaxation":
        tau_r = 1.0
        file = write_table(tmp_path / "relax.txt", (T, e_inf + (e0 - e_inf) * np.exp(-T)))
    else:
        tau_r = 10 / (2 * np.pi)
        f = np.logspace(-3, 2, 41)
        wt = 2 * np.pi * f * tau_r
        file = write_table(tmp_path / "dma.csv",
                           (f, e_inf + (e0 - e_inf) * wt ** 2 / (1 + wt ** 2),
                            (e0 - e_inf) * wt / (1 + wt ** 2)), header="f E1 E2")
    fitted = fit_scene({"material": "viscoelastic", "poisson": NU, "creep": "fit",
                        "file": str(file), "table_kind": kind})
    ref = fit_scene({"material": "viscoelastic", "young": e0, "poisson": NU,
                     "creep": "zener", "relaxed_young": e_inf,
                     "retardation_time": tau_r * e0 / e_inf})
    assert_same_run(cp.simulate(fitted), cp.simulate(ref), 1e-6)


SCENE_TEXT = """name = "fit"
[geometry]
shape = "sphere"
radius = 0.018
[indenter]
material = "rigid"
[halfspace]
material = "viscoelastic"
poisson = 0.3
creep = "fit"
file = "creep.csv"
table_kind = "creep"
[load]
time = [0.0, 2.0]
normal_force = 1000.0
[grid]
points = [16, 16]
size = "auto"
"""


def test_fit_scene_file_relative_to_the_scene_and_digest(tmp_path):
    """A relative file is taken relative to the scene file; the digest counts the file's
    content (a copy elsewhere has the same digest, an edited file another); the stored
    scene reads back equal (young written as fitted)."""
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        write_table(tmp_path / folder / "creep.csv", (T, zener(3e9, 1e9, 1.0)(T) / 3e9))
        (tmp_path / folder / "scene.toml").write_text(SCENE_TEXT)
    a = cp.Scene.from_toml(tmp_path / "a" / "scene.toml")
    b = cp.Scene.from_toml(tmp_path / "b" / "scene.toml")
    assert a.halfspace.file == str(tmp_path / "a" / "creep.csv")
    assert a.digest() == b.digest()
    assert cp.Scene.from_toml_text(a.to_toml()) == a
    assert a.replace({"friction.mu": 0.1}).halfspace.young == a.halfspace.young
    write_table(tmp_path / "b" / "creep.csv", (T, zener(3e9, 1e9, 2.0)(T) / 3e9))
    assert cp.Scene.from_toml(tmp_path / "b" / "scene.toml").digest() != a.digest()


def test_fit_scene_shear_data_with_an_elastic_bulk(tmp_path):
    """With bulk = "elastic" the table is the shear compliance: young = 2 (1 + nu) G0."""
    file = write_table(tmp_path / "shear.csv", (T, zener(3.0, 1.0, 1.0)(T) / 1e9))
    sc = fit_scene({"material": "viscoelastic", "poisson": NU, "creep": "fit",
                    "file": str(file), "table_kind": "creep", "bulk": "elastic"})
    assert sc.halfspace.young == pytest.approx(2 * 1.3 * 1e9, rel=1e-7)
    assert sc.halfspace.body().split


@pytest.mark.parametrize("table,kind,extra,match", [
    ((T, np.where(T > 1, 0.9, 1.0) * 1e-9), "creep", {},
     r"halfspace\.file = .*creep table\): creep compliance must not decrease"),
    ((T[T <= 1.0], zener(3e9, 1e9, 1.0)(T[T <= 1.0]) / 3e9), "creep", {},
     r"halfspace\.file = .*: the creep data reach t = 0.92\d+ s \(its last time\), before the end "
     r"of the load window"),
    ((T, zener(3e9, 1e9, 1.0)(T) / 3e9), "creep", {"young": 1e9},
     r"halfspace\.young = 1e\+09 Pa contradicts the modulus of the fitted table"),
    ((T, np.exp(-T)), "dynamic", {}, r"halfspace\.file = .*line 3: 2 columns, expected 3"),
    ((T, zener(3e9, 1e9, 1.0)(T) / 3e9), None, {},
     r"halfspace\.table_kind is required for creep = 'fit'"),
])
def test_fit_scene_refusals(table, kind, extra, match, tmp_path):
    """A table that is not monotone, does not cover the load window, contradicts young or
    is malformed is refused with a SceneError naming the key."""
    file = write_table(tmp_path / "data.csv", table)
    hs = {"material": "viscoelastic", "poisson": NU, "creep": "fit", "file": str(file),
          **extra}
    if kind:
        hs["table_kind"] = kind
    with pytest.raises(cp.SceneError, match=match):
        fit_scene(hs)


def test_fit_scene_refuses_a_fifo_at_once(tmp_path):
    """creep = "fit" with ``file`` a FIFO: refused at once with a SceneError naming the key
    (opening it to read blocked for ever), as the geometry and friction files are."""
    import os
    fifo = tmp_path / "data.csv"
    os.mkfifo(fifo)
    hs = {"material": "viscoelastic", "poisson": NU, "creep": "fit", "file": str(fifo),
          "table_kind": "creep"}
    with pytest.raises(cp.SceneError, match=r"halfspace\.file = .*not a regular file \(a "
                                            r"FIFO, a device or a folder\)"):
        fit_scene(hs)


# ------------------------------------------------ time constants off the grid (issue 42)
OFF = 10 ** 0.25              # half-way (in log) between two grid times of 2 per decade
E0, EINF = 3e9, 1e9


def off_grid_table(kind):
    """A Zener material (E0 = 3 GPa, E_inf = 1 GPa) whose one time constant lies off
    the fit's grid: (abscissae, columns, the exact creep function phi)."""
    if kind == "creep":
        return T, (zener(E0, EINF, OFF)(T) / E0,), zener(E0, EINF, OFF)
    if kind == "relaxation":
        return (T, (EINF + (E0 - EINF) * np.exp(-T / OFF),),
                zener(E0, EINF, OFF * E0 / EINF))
    f = np.logspace(-3, 2, 41)
    tau = OFF / (2 * np.pi)
    wt = 2 * np.pi * f * tau
    storage = EINF + (E0 - EINF) * wt ** 2 / (1 + wt ** 2)
    return f, (storage, (E0 - EINF) * wt / (1 + wt ** 2)), zener(E0, EINF, tau * E0 / EINF)


FITS = {"creep": fit_creep_compliance, "relaxation": fit_relaxation_modulus,
        "dynamic": fit_dynamic_moduli}
TT = np.concatenate([[0.0], np.logspace(-3, 2, 300)])


@pytest.mark.parametrize("kind", list(FITS))
def test_off_grid_time_constant_is_found(kind):
    """One time constant half-way between two grid times (2 per decade): the free time
    constants (the default) find it, D(t) = phi/E0 within 1e-9 of the exact Zener over
    1 ms .. 100 s and E0 within 1e-9 (measured 1e-15 for all three kinds), and the
    recorded compliance error says so (< 1e-9). The grid alone (free=False, the fit
    before) is off by more than 1 % in D(t) (measured 3.2 %, 2.6 %, 7.3 %, with E0 off
    by 1.1 %, 1.4 %, -5.7 %); its recorded error tracks that: the creep data's misfit,
    the compliance interconverted from the relaxation data within 5 % of the true error
    (measured 2.59 % against 2.60 %), the complex compliance of the dynamic data above
    1 % (measured 12 %)."""
    x, cols, true = off_grid_table(kind)
    exact = true(TT) / E0
    fit = FITS[kind](x, *cols)
    assert np.abs(fit.creep(TT) / fit.young / exact - 1).max() < 1e-9
    assert fit.young == pytest.approx(E0, rel=1e-9)
    assert fit.compliance_error < 1e-9
    grid = FITS[kind](x, *cols, free=False)
    wrong = np.abs(grid.creep(TT) / grid.young / exact - 1)
    assert wrong.max() > 0.01
    assert grid.compliance_error > 0.01
    if kind != "dynamic":
        at = TT[(TT >= x[0]) & (TT <= x[-1])]
        truth = np.abs(grid.creep(at) / grid.young / (true(at) / E0) - 1).max()
        assert grid.compliance_error == pytest.approx(truth, rel=0.05)


def test_given_time_constants_are_used():
    """time_constants fixed (free=False) at the true one: exact; given with the grid's
    spacing, the free refinement still finds it."""
    x, (d,), true = off_grid_table("creep")
    fixed = fit_creep_compliance(x, d, times=[OFF], free=False)
    assert fixed.times == (pytest.approx(OFF),)
    np.testing.assert_allclose(fixed.creep(TT), true(TT), rtol=1e-9)
    moved = fit_creep_compliance(x, d, times=[0.1, 1.0, 10.0])
    np.testing.assert_allclose(moved.creep(TT), true(TT), rtol=1e-9)


def off_grid_scene(tmp_path, **keys):
    file = write_table(tmp_path / "creep.csv", (T, zener(E0, EINF, OFF)(T) / E0))
    return fit_scene({"material": "viscoelastic", "poisson": NU, "creep": "fit",
                      "file": str(file), "table_kind": "creep", **keys})


def test_fit_scene_off_grid_runs_the_exact_material(tmp_path):
    """creep = "fit" on the off-grid Zener creep table runs creep = "zener" (24^2, 10
    steps) within 1e-6 (measured 8e-15); the archive records the fit's compliance error
    (< 1e-9) and the bound it met (1 %)."""
    fitted = off_grid_scene(tmp_path)
    ref = fit_scene({"material": "viscoelastic", "young": E0, "poisson": NU,
                     "creep": "zener", "relaxed_young": EINF, "retardation_time": OFF})
    a = cp.simulate(fitted)
    assert_same_run(a, cp.simulate(ref), 1e-6)
    assert a.attrs["halfspace_fit_compliance_error"] < 1e-9
    assert a.attrs["halfspace_fit_tolerance"] == 0.01


def test_fit_scene_refuses_a_fit_above_the_bound(tmp_path):
    """With the time constants held on the grid (free_times = false) the fit is 3.2 % off:
    refused by the default bound (1 %) naming the key that raises it; accepted when it is
    raised, the archive recording the error (3.2 %) and the bound (5 %). Four per decade
    put a time at 10^0.25: the fixed grid is then exact (measured 7e-10)."""
    with pytest.raises(cp.SceneError, match=r"halfspace\.file = .*: the fitted creep "
                       r"compliance is 0\.032\d* off the creep data, above "
                       r"halfspace\.fit_tolerance = 0\.01; give more "
                       r"halfspace\.terms_per_decade .* or raise halfspace\.fit_tolerance"):
        off_grid_scene(tmp_path, free_times=False)
    sc = off_grid_scene(tmp_path, free_times=False, fit_tolerance=0.05)
    ds = cp.simulate(sc.replace({"time.steps": 2}))
    assert ds.attrs["halfspace_fit_compliance_error"] == pytest.approx(0.0321, abs=5e-4)
    assert ds.attrs["halfspace_fit_tolerance"] == 0.05
    four = off_grid_scene(tmp_path, free_times=False, terms_per_decade=4)
    assert four.halfspace.fit().compliance_error < 1e-8


def test_fit_scene_time_constants_and_terms_per_decade_exclusive(tmp_path):
    with pytest.raises(cp.SceneError, match=r"halfspace\.time_constants and "
                       r"halfspace\.terms_per_decade both give the fit's time constants"):
        off_grid_scene(tmp_path, time_constants=[1.0], terms_per_decade=3)
    sc = off_grid_scene(tmp_path, time_constants=[OFF], free_times=False)
    assert sc.halfspace.fit().times == (pytest.approx(OFF),)
    assert cp.Scene.from_toml_text(sc.to_toml()) == sc
