"""The compare stage on the general loading's closed forms (contactpipe.pipeline.compare.reference:
hertz_tilted, lubkin_torsion, mindlin_displacement): which scenes they recognise, and the
rows of the error table against the tests' own measured figures.

Steel on steel, R = 18 mm, W = 1 kN (Hertz a = 0.489 mm), mu = 0.1 unless said.
"""
import numpy as np
import pytest
from helpers import A_HERTZ, MU, R, W, make_scene

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.pipeline.compare import compare, write_table
from contactpipe.pipeline.compare.reference import closed_form_for, closed_form_solution, diagnose

C_SUM = an.tangential_compliance_sum(210e9, 0.3, 210e9, 0.3)
D_GS = an.gross_slip_displacement(MU, W, A_HERTZ, C_SUM)
C_T = an.torsional_compliance(210e9, 0.3, 210e9, 0.3)
BETA_REF = an.full_slip_torque(MU, W, A_HERTZ) / an.torsional_stiffness(A_HERTZ, C_T)
TWISTS = [0.0, 0.01, 0.25, 0.5, 1.0, 2.0, 4.0, 20.0, -20.0]       # x beta_ref


def tilted(key, value, n=32):
    return make_scene(load={"time": [0.0], "normal_force": W, key: value},
                      grid={"points": [n, n], "size": [4 * A_HERTZ] * 2}, time=None)


def twist(n=24):
    return make_scene(friction={"mu": MU},
                      load={"time": list(range(len(TWISTS))), "normal_force": W,
                            "rotation3": [b * BETA_REF for b in TWISTS]},
                      grid={"points": [n, n], "size": [2.5 * A_HERTZ] * 2},
                      time={"steps": len(TWISTS) - 1})


def fretting(amplitude, n=32, per_quarter=8):
    d = amplitude * D_GS
    return make_scene(friction={"mu": MU},
                      load={"time": [0.0, 1.0, 3.0, 5.0], "normal_force": W,
                            "tangential_displacement": [0.0, d, -d, d]},
                      grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
                      time={"steps": 5 * per_quarter})


# --------------------------------------------------------------------------- recognition
def test_the_loading_scenes_are_recognised():
    """A moment or a rotation about x1 / x2 is hertz_tilted (no longer plain Hertz), a
    rotation3 program with friction lubkin_torsion, a displacement program
    mindlin_displacement; plain Hertz and force-controlled fretting keep their forms."""
    e = 0.3 * A_HERTZ
    assert closed_form_for(tilted("moment2", W * e)) == "hertz_tilted"
    assert closed_form_for(tilted("rotation1", e / R)) == "hertz_tilted"
    assert closed_form_for(tilted("moment2", 0.0)) == "hertz"        # a free rotation
    assert closed_form_for(twist()) == "lubkin_torsion"
    assert closed_form_for(fretting(2.0)) == "mindlin_displacement"
    assert closed_form_for(make_scene()) == "hertz"
    assert closed_form_for(make_scene(
        friction={"mu": MU}, load={"time": [0.0, 1.0], "normal_force": W,
                                   "tangential_force": [0.0, 50.0]})) == "mindlin_deresiewicz"


def test_why_not_names_the_loading_forms():
    """A torsion under moment control has no closed form; the reasons name each loading
    candidate and what it needs. A frictionless twist is plain Hertz."""
    scene = make_scene(friction={"mu": MU},
                       load={"time": [0.0, 1.0], "normal_force": W, "moment3": [0.0, 0.01]})
    name, why = diagnose(scene)
    assert name is None
    assert "needs a twist under rotation control (load.rotation3)" in why["lubkin_torsion"]
    assert "needs load.tangential_displacement" in why["mindlin_displacement"]
    assert any("no twist" in m for m in why["hertz_tilted"])
    assert any("a twist" in m for m in why["hertz"])
    assert "needs no tilt or twist" in why["mindlin_deresiewicz"]
    # without friction a twist carries nothing: the plain Hertz contact
    assert closed_form_for(make_scene(load={"time": [0.0, 1.0], "normal_force": W,
                                            "rotation3": [0.0, 0.01]})) == "hertz"


# --------------------------------------------------------------------------- tables
def test_tilted_hertz_rows():
    """M2 = W e, e = 0.3 a, 32² over 4 a (cell a/8): measured p0 0.12 %, centroid 6e-10
    cells (M2 = W e is imposed), phi2 5e-5; imposing phi2 = e/R instead: M2 5e-5,
    centroid 4e-4 cells. Bounds: p0 1 %, centroid 0.1 cell, phi2 and M2 1 %."""
    e = 0.3 * A_HERTZ
    for key, value in (("moment2", W * e), ("rotation2", e / R)):
        tb = compare(cp.simulate(tilted(key, value)))
        assert tb.attrs["closed_form"] == "hertz_tilted"
        assert float(tb.err_p0.max()) < 0.01
        assert float(tb.err_centroid_cells.max()) < 0.1
        assert float(tb.err_phi.max()) < 0.01 and float(tb.err_moment.max()) < 0.01
        assert float(tb.err_omega3.max()) < 0.01


def test_torsion_rows(tmp_path):
    """phi3 through TWISTS x beta_ref, 24² over 2.5 a (cell a/9.6): measured stuck
    stiffness +2.5 % (bound 4 %), torque within 0.15 % of M_max of Lubkin-Masing at every
    instant (bound 1 %), final torque 0.07 % (bound 2 %); the table writes as CSV."""
    tb = compare(cp.simulate(twist()), out=tmp_path / "torsion.csv")
    assert tb.attrs["closed_form"] == "lubkin_torsion"
    assert float(tb.err_stuck_stiffness) < 0.04
    assert float(tb.err_M3.max()) < 0.01
    assert float(tb.err_full_slip_torque) < 0.02
    # the closed form at the stiffness instant is Lubkin's secant, within 0.5 % of stuck
    assert tb.attrs["stiffness_lubkin_over_stuck"] == pytest.approx(1.0, abs=0.005)
    text = (tmp_path / "torsion.csv").read_text()
    assert "err_stuck_stiffness" in text and "err_M3" in text


def test_torsion_loop_follows_masing():
    """The closed-form torque after a reversal is Masing's: back from beta* to 0,
    M = M* - 2 M_v(beta*/2) (1e-12), and to -beta* it is -M* (the loop closes)."""
    b = 2.0 * BETA_REF
    M = an.torsion_loop_moment([0.0, b, 0.0, -b, b], MU, W, A_HERTZ, C_T)
    mv = an.lubkin_moment([b, b / 2], MU, W, A_HERTZ, C_T)
    assert M[1] == pytest.approx(mv[0], rel=1e-12)
    assert M[2] == pytest.approx(mv[0] - 2 * mv[1], rel=1e-12)
    assert M[3] == pytest.approx(-mv[0], rel=1e-12)
    assert M[4] == pytest.approx(mv[0], rel=1e-12)


def test_displacement_control_rows():
    """0 -> 2 delta_gs -> -2 delta_gs -> 2 delta_gs, 32² over 3 a, 8 steps per quarter:
    measured first branch 8.5e-5 mu W (bound 2 %), plateau |T| = mu W to rounding (bound
    1 %), cycle energy from the dissipation 3.7e-5 and from the loop area (trapezoids)
    3.0e-3 of E_MD(mu W) + 4 mu W (delta* - delta_gs) (bound 3 %)."""
    tb = compare(cp.simulate(fretting(2.0)))
    assert tb.attrs["closed_form"] == "mindlin_displacement"
    assert float(tb.err_first_branch) < 0.02
    assert float(tb.err_plateau) < 0.01
    assert float(tb.err_cycle_energy) < 0.03 and float(tb.err_loop_energy) < 0.03
    assert float(tb.err_T1.max()) < 0.02
    assert tb.attrs["cycle_energy_J"] == pytest.approx(
        0.8 * MU * W * D_GS + 4 * MU * W * D_GS, rel=1e-12)
    assert list(tb.attrs["cycle_instants"]) == [8, 40]


def test_displacement_control_in_partial_slip_has_no_plateau(tmp_path):
    """At 0.5 delta_gs there is no plateau row; the cycle energy is E_MD(T(delta*))
    (measured 4.5e-3 from the dissipation, 8.5e-3 from the loop area, at 32² with 8 steps
    per quarter; bound 3 %); the table writes as netCDF."""
    tb = compare(cp.simulate(fretting(0.5)))
    assert "err_plateau" not in tb
    assert float(tb.err_cycle_energy) < 0.03
    write_table(tb, tmp_path / "t.nc")
    assert (tmp_path / "t.nc").stat().st_size > 0


def test_cycle_energy_of_an_offset_cycle():
    """A cycle that is not symmetric about 0 (after a slide to +2 delta_gs, between
    -0.5 and 0.5 delta_gs) takes the closed-form loop's own area: the Mindlin-Deresiewicz
    loop of amplitude 0.5 delta_gs (congruent after the slide wiped the memory; 1e-4)."""
    d = D_GS
    scene = make_scene(friction={"mu": MU},
                       load={"time": [0.0, 1.0, 2.0, 3.0, 4.0, 5.0],
                             "normal_force": W,
                             "tangential_displacement": [0.0, 2 * d, -0.5 * d, 0.5 * d,
                                                         -0.5 * d, 0.0]},
                       grid={"points": [16, 16], "size": [3 * A_HERTZ] * 2},
                       time={"steps": 20})
    ds = cp.simulate(scene)
    sol = closed_form_solution(ds)
    (start, stop), = sol.displacement_cycles()
    assert (start, stop) == (8, 16)
    ref = an.displacement_energy_per_cycle(0.5 * d, MU, W, A_HERTZ, C_SUM)
    assert sol.cycle_energy(start, stop) == pytest.approx(ref, rel=1e-4)
    assert np.isfinite(float(compare(ds).err_cycle_energy))
