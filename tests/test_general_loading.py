"""General loading (paper eqs. 1-4): moments and rotations, approach
control down to separation, combined loading through the contact-law checker, and the
one-line errors of bad input.

Steel on steel (R = 18 mm, W = 1 kN: Hertz a = 0.489 mm, p0 = 1.996 GPa) unless said.
"""
import re

import numpy as np
import pytest
from helpers import A_HERTZ, E_STAR_STEEL, MU, STEEL, R, W, make_scene

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.testing import assert_contact_laws, contact_law_violations

ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}
SERIES = ("M1", "M2", "M3", "phi1", "phi2", "phi3")


def tilted(n, e, key="moment2"):
    """W = 1 kN with M2 = W e (or phi2 = e/R), one instant, n² cells over 4 a."""
    value = W * e if key == "moment2" else e / R
    return make_scene(load={"time": [0.0], "normal_force": W, key: value},
                      grid={"points": [n, n], "size": [4 * A_HERTZ, 4 * A_HERTZ]},
                      time=None)


def check_tilted(n, tol_p0):
    """M2 = W e with e = 0.3 a (not a whole number of cells): p0 within ``tol_p0`` of
    Hertz, the pressure centroid within 0.1 cell of e, phi2 = e/R within 1 %, the contact
    area's own centroid within half a cell of e (the rotation moved the contact, not only
    its load); and phi2 = e/R imposed gives back M2 = W e within 1 %."""
    e = 0.3 * A_HERTZ
    ds = cp.simulate(tilted(n, e))
    cell = 4 * A_HERTZ / n
    p = ds.p.values[0]
    x1 = ds.x1.values[:, None] + 0 * ds.x2.values[None, :]
    ref = an.hertz_tilted(W, 0.0, W * e, R, E_STAR_STEEL)
    assert p.max() == pytest.approx(ref.max_pressure, rel=tol_p0)
    assert abs((p * x1).sum() / p.sum() - e) < 0.1 * cell
    assert float(ds.phi2[0]) == pytest.approx(ref.rotation[1], rel=0.01)
    assert abs(x1[p > 0].mean() - e) < 0.5 * cell
    assert float(ds.M1[0]) == pytest.approx(0.0, abs=1e-9 * W * cell)
    back = cp.simulate(tilted(n, e, key="rotation2"))
    assert float(back.M2[0]) == pytest.approx(W * e, rel=0.01)
    return p.max() / ref.max_pressure - 1, float(ds.phi2[0]) / ref.rotation[1] - 1, \
        float(back.M2[0]) / (W * e) - 1


def test_tilted_hertz():
    """48² over 4 a (cell a/12): measured p0 -0.06 %, phi2 -0.02 %, M2 from phi2 +0.02 %."""
    check_tilted(48, 0.01)


@pytest.mark.slow
def test_tilted_hertz_fine():
    """128² over 4 a (cell a/32), the same bounds: measured p0 -0.008 %, phi2 and M2 from
    phi2 2e-4 %."""
    check_tilted(128, 0.01)


def test_every_archive_reports_the_six_freedoms():
    """A frictionless Hertz contact: M1 = M2 = 0 by symmetry (1e-9 W a), M3 = 0, the
    rotations held at 0; the series exist, with their units."""
    ds = cp.simulate(make_scene(grid={"points": [24, 24]}))
    units = {"M1": "N m", "M2": "N m", "M3": "N m", "phi1": "rad", "phi2": "rad",
             "phi3": "rad"}
    for name in SERIES:
        assert ds[name].attrs["units"] == units[name]
    for name in ("M1", "M2"):
        assert np.abs(ds[name].values).max() < 1e-9 * W * A_HERTZ
    assert np.all(ds.M3.values == 0) and np.all(ds[["phi1", "phi2", "phi3"]].to_array() == 0)


def test_reaction_moment_and_a_free_rotation():
    """Steel on aluminium at T1 = 0.9 mu W (coupled, 32² over 4 a): with rotation2 held
    at 0 (absent) the pressure carries a reaction moment M2 != 0 (measured -6.2e-3 W a);
    with moment2 = 0 the rotation is free: M2 = 0 (1e-9 W a; measured 8e-15) and
    phi2 != 0 (measured 1.7e-4 rad)."""
    base = dict(halfspace=ALUMINIUM, friction={"mu": MU},
                grid={"points": [32, 32], "size": [4 * A_HERTZ, 4 * A_HERTZ]},
                time={"steps": 2})
    load = {"time": [0.0, 1.0], "normal_force": W, "tangential_force": [0.0, 0.9 * MU * W]}
    held = cp.simulate(make_scene(load=load, **base))
    assert abs(float(held.M2[-1])) > 1e-4 * W * A_HERTZ
    assert np.all(held.phi2.values == 0)
    free = cp.simulate(make_scene(load={**load, "moment2": 0.0}, **base))
    assert abs(float(free.M2[-1])) < 1e-9 * W * A_HERTZ
    assert abs(float(free.phi2[-1])) > 0
    assert_contact_laws(held)
    assert_contact_laws(free)


def test_approach_control_unloads_to_separation():
    """omega3: 0 -> delta_Hertz -> -0.2 delta_Hertz (8 steps, 48² over 4 a): W at the peak
    within 1 % of Hertz's 1 kN (measured +0.05 %); the contact opens entirely (W = 0,
    p = 0 everywhere, h > 0 everywhere); the contact laws hold at every step."""
    delta = A_HERTZ ** 2 / R
    ds = cp.simulate(make_scene(load={"time": [0.0, 1.0, 2.0],
                                      "normal_approach": [0.0, delta, -0.2 * delta]},
                                grid={"points": [48, 48], "size": [4 * A_HERTZ] * 2},
                                time={"steps": 8}))
    assert float(ds.W[4]) == pytest.approx(W, rel=0.01)
    np.testing.assert_allclose(ds.omega3.values, np.interp(ds.time.values, [0, 1, 2],
                                                          [0, delta, -0.2 * delta]),
                               rtol=0, atol=1e-15 * delta)
    assert float(ds.W[-1]) == 0.0 and np.all(ds.p.values[-1] == 0)
    assert ds.h.values[-1].min() > 0 and float(ds.contact_area[-1]) == 0.0
    assert_contact_laws(ds)


def test_torque_with_a_tangential_force_passes_the_checker():
    """T1 ramped to 0.5 mu W with M3 ramped to 0.3 of the full-slip torque (force
    control of both; steel/aluminium, coupled, vector form; 24² over 3 a, 3 steps):
    equilibrium of all six freedoms, complementarity, Coulomb, dissipation >= 0."""
    m_max = an.full_slip_torque(MU, W, A_HERTZ)
    ds = cp.simulate(make_scene(
        halfspace=ALUMINIUM, friction={"mu": MU},
        load={"time": [0.0, 1.0], "normal_force": W, "tangential_force": [0.0, 0.5 * MU * W],
              "moment3": [0.0, 0.3 * m_max]},
        grid={"points": [24, 24], "size": [3 * A_HERTZ] * 2}, time={"steps": 3}))
    assert "tangential=vector" in ds.attrs["models"]
    assert float(ds.M3[-1]) == pytest.approx(0.3 * m_max, rel=1e-6)
    assert contact_law_violations(ds) == []


def test_tilted_fretting_loop_passes_the_checker():
    """A fretting loop T1 = 0, +-0.8 mu W under W with M2 = 0.2 W a and phi1 = 2e-3
    imposed (steel on steel, 24² over 4 a, 10 steps): the checker passes, the moment is
    carried and the imposed rotation reached."""
    ds = cp.simulate(make_scene(
        friction={"mu": MU},
        load={"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W, "moment2": 0.2 * W * A_HERTZ,
              "rotation1": 2e-3,
              "tangential_force": [0.0, 0.8 * MU * W, -0.8 * MU * W, 0.8 * MU * W]},
        grid={"points": [24, 24], "size": [4 * A_HERTZ] * 2}, time={"steps": 10}))
    assert contact_law_violations(ds) == []
    np.testing.assert_allclose(ds.M2.values, 0.2 * W * A_HERTZ, rtol=1e-6)
    np.testing.assert_array_equal(ds.phi1.values, 2e-3)


# --------------------------------------------------------------------------- bad input
BASE = {"geometry": {"shape": "sphere", "radius": R}, "indenter": dict(STEEL),
        "halfspace": dict(STEEL), "friction": {"mu": MU},
        "grid": {"points": [32, 32], "size": [4 * A_HERTZ, 4 * A_HERTZ]}}


def scene_error(load, **tables):
    with pytest.raises(cp.SceneError) as err:
        cp.Scene(**{**BASE, **tables, "load": load})
    message = str(err.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize("force, motion, what", [
    ("normal_force", "normal_approach", r"normal freedom \(W \| omega3\)"),
    ("tangential_force", "tangential_displacement",
     r"tangential freedom \(T1, T2 \| omega1, omega2\)"),
    ("moment1", "rotation1", r"tilt 1 freedom \(M1 \| phi1\)"),
    ("moment2", "rotation2", r"tilt 2 freedom \(M2 \| phi2\)"),
    ("moment3", "rotation3", r"twist freedom \(M3 \| phi3\)"),
])
def test_both_keys_of_one_row(force, motion, what):
    values = {"normal_force": W, "normal_approach": 1e-6, "tangential_force": [0.0, 1.0],
              "tangential_displacement": [0.0, 1e-7], "moment1": 0.0, "rotation1": 0.0,
              "moment2": 0.0, "rotation2": 0.0, "moment3": 0.0, "rotation3": 0.0}
    load = {"time": [0.0, 1.0], "normal_force": W, force: values[force],
            motion: values[motion]}
    assert re.search(rf"load\.{force} and load\.{motion} both control the {what}: give "
                     rf"one of them", scene_error(load))


@pytest.mark.parametrize("load, message", [
    ({"rotation2": 0.1},
     r"load\.rotation2 = 0\.1 at t = 0 s moves the contact, by R phi, 0\.0018 m along x1: "
     r"with its Hertz semi-axis .* the contact would reach .* m from the centre, past the "
     r".* m the grid allows \(its half-side less one cell: the contact must stay a cell "
     r"inside the edge, or it opens there\); keep the shift below .* m, or give grid\.size"),
    # 32 cells over 4 a: the grid allows 2 a - 4 a / 32 = 0.9171 mm, the shift 0.428 mm;
    # the least size 2 (a + e) / (1/2 - 1/32) = 2.750 mm along x2
    ({"moment1": [0.0, 0.8]},
     r"^load\.moment1 = 0\.8 at t = 1 s moves its pressure centre M/W 0\.0008 m along x2: "
     r"with its Hertz semi-axis 0\.0004891 m the contact would reach 0\.001289 m from the "
     r"centre, past the 0\.0009171 m the grid allows \(its half-side less one cell: the "
     r"contact must stay a cell inside the edge, or it opens there\); keep the shift below "
     r"0\.000428 m, or give grid\.size = \[0\.001956, 0\.00275\] m or more, or \"auto\" "
     r"\(grid\.size_check = false leaves it to the run\)$"),
])
def test_a_tilt_that_would_open_the_contact(load, message):
    """Decided at validation from the Hertz estimate: the contact, moved by R phi (or by
    e = M/W), would come within a cell of the grid's edge and open there."""
    text = scene_error({"time": [0.0, 1.0], "normal_force": W, **load})
    assert re.search(message, text), text


def test_a_moment_that_would_tip_a_flat_punch():
    text = scene_error({"time": [0.0], "normal_force": W, "moment2": 0.6e-3 * W},
                       geometry={"shape": "flat_punch", "radius": 0.5e-3},
                       grid={"points": [32, 32], "size": [1.5e-3, 1.5e-3]})
    assert text.startswith("load.moment2 = 0.6 at t = 0 s puts its pressure centre M/W at "
                           "0.0006 m along x1, beyond the flat punch's radius 0.0005 m: the "
                           "punch would tip and the contact open")


def test_gross_slip_under_force_control():
    """A tangential force above mu W, or a torque at or above 3 pi mu W a / 16, under
    force control: one line naming the key; imposing the motion instead is valid."""
    text = scene_error({"time": [0.0, 1.0], "normal_force": W,
                        "tangential_force": [0.0, 1.2 * MU * W]})
    assert text.startswith("load.tangential_force reaches 120 N at t = 1 s, above "
                           "friction.mu * W = 100 N")
    m_max = an.full_slip_torque(MU, W, A_HERTZ)
    text = scene_error({"time": [0.0, 1.0], "normal_force": W, "moment3": [0.0, m_max]})
    assert text.startswith("load.moment3 reaches ") and "at or above the torque of full " \
        "sliding 3 pi mu W a / 16 (Lubkin, Hertz a)" in text and "load.rotation3" in text
    cp.Scene(**{**BASE, "load": {"time": [0.0, 1.0], "normal_force": W,
                                 "tangential_displacement": [0.0, 1e-5]}})


def test_torsional_gross_slip_at_run_time():
    """Where validation cannot tell (an ellipsoid: no closed-form full-slip torque is
    checked for it, nor for a surface), the run refuses a torque it cannot carry with one
    GrossSlidingError naming load.moment3 and the step (16², 1 step)."""
    sc = cp.Scene(**{**BASE, "geometry": {"shape": "ellipsoid", "radii": [R, R]},
                     "grid": {"points": [16, 16], "size": [3 * A_HERTZ] * 2},
                     "load": {"time": [0.0, 1.0], "normal_force": W,
                              "moment3": [0.0, 1.05 * an.full_slip_torque(MU, W, A_HERTZ)]},
                     "time": {"steps": 1}})
    with pytest.raises(cp.ConvergenceError, match=r"^step 1 \(t = 1 s\): the stick zone "
                                                  r"was lost under load\.moment3 = ") as err:
        cp.simulate(sc)
    assert "\n" not in str(err.value) and "load.rotation3" in str(err.value)


# --------------------------------------------------------------------------- API, closed form
def test_hertz_tilted_closed_form():
    """The moved Hertz contact carries W, M1, M2 exactly (quadrature on its disc, 1e-9);
    phi = (M1, M2)/(W R); omega3 = a²/R − R |phi|²/2; no moment: Hertz itself."""
    from scipy import integrate
    M1, M2 = -0.1 * W * A_HERTZ, 0.25 * W * A_HERTZ
    tz = an.hertz_tilted(W, M1, M2, R, E_STAR_STEEL)
    a, (e1, e2) = tz.contact_radius, tz.centre

    def moment(f):
        return integrate.dblquad(lambda y, x: tz.pressure(x, y) * f(x, y), e1 - a, e1 + a,
                                 lambda x: e2 - np.sqrt(max(a * a - (x - e1) ** 2, 0.0)),
                                 lambda x: e2 + np.sqrt(max(a * a - (x - e1) ** 2, 0.0)),
                                 epsrel=1e-11)[0]

    assert moment(lambda x, y: 1.0) == pytest.approx(W, rel=1e-9)
    assert moment(lambda x, y: y) == pytest.approx(M1, rel=1e-9)
    assert moment(lambda x, y: x) == pytest.approx(M2, rel=1e-9)
    assert tz.rotation == pytest.approx((M1 / (W * R), M2 / (W * R)), rel=1e-15)
    assert tz.approach == pytest.approx(a * a / R - R * (tz.rotation[0] ** 2
                                                         + tz.rotation[1] ** 2) / 2, rel=1e-15)
    assert tz.moments == pytest.approx((M1, M2), rel=1e-15)
    plain = an.hertz_tilted(W, 0.0, 0.0, R, E_STAR_STEEL)
    hz = an.hertz_sphere(W, R, E_STAR_STEEL)
    assert plain.max_pressure == hz.max_pressure and plain.approach == hz.approach


def test_load_programs_and_round_trip():
    """Load.programs gives the six freedoms at the knots and on the mesh (NaN where not
    controlled that way, rotations held at 0 where absent); knots() keeps (t, W, T1, T2)
    with NaN for a displacement-controlled row; the scene reads back equal from its TOML."""
    sc = make_scene(friction={"mu": MU},
                    load={"time": [0.0, 1.0, 2.0], "normal_approach": [1e-6, 2e-6, 1e-6],
                          "tangential_displacement": [[0, 0], [1e-7, 2e-7], [0, 0]],
                          "moment2": 0.01, "rotation3": [0.0, 1e-3, 0.0]},
                    time={"steps": 4})
    prog = sc.load.programs()
    assert [prog.is_force(i) for i in range(6)] == [False, False, False, False, True, False]
    np.testing.assert_array_equal(prog.motion[0], [1e-6, 2e-6, 1e-6])
    np.testing.assert_array_equal(prog.motion[2], [0, 2e-7, 0])
    np.testing.assert_array_equal(prog.motion[3], 0.0)            # phi1 held at 0
    np.testing.assert_array_equal(prog.force[4], 0.01)
    assert np.isnan(prog.force[[0, 1, 2, 3, 5]]).all() and np.isnan(prog.motion[4]).all()
    assert prog.keys == ("normal_approach", "tangential_displacement",
                         "tangential_displacement", "", "moment2", "rotation3")
    mesh = sc.load.programs(4)
    np.testing.assert_allclose(mesh.motion[5], [0, 5e-4, 1e-3, 5e-4, 0], rtol=1e-15)
    t, Wk, T1, T2 = sc.load.knots()
    assert np.isnan(Wk).all() and np.isnan(T1).all() and np.isnan(T2).all()
    assert cp.Scene.from_toml_text(sc.to_toml()) == sc
    assert "tangential=vector" in cp.plan(sc).describe()
    with pytest.raises(cp.SceneError, match=r"^tangential='scalar': load\.rotation3 twists "
                                            r"the contact; the one-component form cannot "
                                            r"carry a torque"):
        cp.plan(sc, tangential="scalar")


def test_old_scenes_keep_their_digest():
    """A scene without the new keys writes none of them: its dict, TOML and digest are
    those of before (the new keys are absent, not None)."""
    sc = make_scene(friction={"mu": MU}, load={"time": [0.0, 1.0], "normal_force": W,
                                                "tangential_force": [0.0, 50.0]})
    assert set(sc.to_dict()["load"]) == {"time", "normal_force", "tangential_force",
                                         "preload"}
    assert sc.digest() == cp.Scene.from_toml_text(sc.to_toml()).digest()


def _programs(tangential, normal=None):
    from contactpipe.scene.loading import Programs
    n = len(tangential)
    force = np.full((6, n), np.nan)
    motion = np.full((6, n), np.nan)
    force[0] = 1000.0 if normal is None else normal
    force[1] = tangential
    force[2] = 0.0
    motion[3:] = 0.0
    return Programs(np.arange(n, dtype=float), force, motion, ("",) * 6)


def test_continuation_of_a_straight_load_path():
    """Programs.continuation(k): the ratio of the increments into k and k − 1 along a
    straight path (1 for even steps, 2 where the steps double), 0 at a reversal, where
    the load is held, where another freedom turns, and before the second increment."""
    even = _programs([0.0, 1.0, 2.0, 3.0, 2.0, 2.0, 2.0])
    assert [even.continuation(k) for k in range(7)] == pytest.approx(
        [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0], abs=1e-12)
    doubled = _programs([0.0, 1.0, 3.0])
    assert doubled.continuation(2) == pytest.approx(2.0, rel=1e-12)
    turned = _programs([0.0, 1.0, 2.0], normal=[1000.0, 1000.0, 1100.0])
    assert turned.continuation(2) == 0.0
    together = _programs([0.0, 1.0, 2.0], normal=[1000.0, 1100.0, 1200.0])
    assert together.continuation(2) == pytest.approx(1.0, rel=1e-12)
