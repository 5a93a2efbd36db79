"""Displacement control: Mindlin's closed forms under an imposed displacement
(contactpipe.analytic.mindlin) and a simulated fretting loop driven into gross slip.

The simulated contact is the paper's elastic one: steel on steel, R = 18 mm, W = 1 kN
(Hertz a = 0.489 mm), mu = 0.1; the displacement omega1 goes 0 -> 2 delta_gs -> -2 delta_gs
-> 2 delta_gs (load.tangential_displacement), delta_gs = 3 mu W (2 - nu) / (8 G a).
"""
import numpy as np
import pytest
from helpers import A_HERTZ, MU, W, make_scene

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.testing import contact_law_violations

C_SUM = an.tangential_compliance_sum(210e9, 0.3, 210e9, 0.3)
D_GS = an.gross_slip_displacement(MU, W, A_HERTZ, C_SUM)
MUW = MU * W


# --------------------------------------------------------------------------- closed forms
def test_gross_slip_displacement_of_identical_bodies():
    """delta_gs = 3 mu W C / (16 a) is 3 mu W (2 - nu) / (8 G a) for identical bodies, and
    Mindlin's virgin displacement at T = mu W (1e-14)."""
    G = 210e9 / 2.6
    assert D_GS == pytest.approx(3 * MUW * (2 - 0.3) / (8 * G * A_HERTZ), rel=1e-14)
    assert an.tangential_displacement([MUW], MU, W, A_HERTZ, C_SUM) == \
        pytest.approx(D_GS, rel=1e-14)


def test_mindlin_force_inverts_the_virgin_curve():
    """T(delta(T)) = T on the first branch (1e-12 mu W), odd, mu W at and beyond
    delta_gs (gross slip)."""
    T = np.linspace(-0.999, 0.999, 41) * MUW
    delta = np.array([an.tangential_displacement([t], MU, W, A_HERTZ, C_SUM) for t in T])
    np.testing.assert_allclose(an.mindlin_force(delta, MU, W, A_HERTZ, C_SUM), T, rtol=0,
                               atol=1e-12 * MUW)
    assert an.mindlin_force(D_GS, MU, W, A_HERTZ, C_SUM) == MUW
    assert an.mindlin_force(-3 * D_GS, MU, W, A_HERTZ, C_SUM) == -MUW


def test_loop_force_follows_masing_below_gross_slip():
    """A partial-slip displacement history (|delta| < delta_gs, reversals nested and
    wiped) gives the force whose Masing displacement it is: tangential_displacement of
    the forces returns the displacements (1e-12 delta_gs)."""
    history = np.array([0.0, 0.6, -0.3, 0.2, -0.1, 0.4, -0.7, 0.5, 0.9]) * D_GS
    path = np.concatenate([np.linspace(a, b, 30, endpoint=False)
                           for a, b in zip(history[:-1], history[1:], strict=True)]
                          + [history[-1:]])
    T = an.displacement_loop_force(path, MU, W, A_HERTZ, C_SUM)
    back = an.tangential_displacement(T, MU, W, A_HERTZ, C_SUM, all_instants=True)
    np.testing.assert_allclose(back, path, rtol=0, atol=1e-12 * D_GS)


@pytest.mark.parametrize("amplitude", [0.3, 1.0, 2.0, 5.0])
def test_cycle_energy_is_the_loop_area(amplitude):
    """E(delta*) equals the area of the loop of displacement_loop_force over one cycle
    (trapezoid on 4 x 20001 samples: within 1e-6): E_MD(T(delta*)) in partial slip,
    E_MD(mu W) + 4 mu W (delta* - delta_gs) in gross slip; E_MD(mu W) = (4/5) mu W
    delta_gs."""
    d = amplitude * D_GS
    path = np.concatenate([np.linspace(0, d, 10001), np.linspace(d, -d, 20001)[1:],
                           np.linspace(-d, d, 20001)[1:]])
    T = an.displacement_loop_force(path, MU, W, A_HERTZ, C_SUM)
    cycle = slice(10000, None)
    area = abs(np.sum(0.5 * (T[cycle][1:] + T[cycle][:-1]) * np.diff(path[cycle])))
    E = an.displacement_energy_per_cycle(d, MU, W, A_HERTZ, C_SUM)
    assert area == pytest.approx(E, rel=1e-6)
    if amplitude > 1:
        assert E == pytest.approx(0.8 * MUW * D_GS + 4 * MUW * (d - D_GS), rel=1e-12)


# --------------------------------------------------------------------------- simulation
def fretting(n, steps_per_quarter):
    """omega1: 0 -> 2 delta_gs -> -2 delta_gs -> 2 delta_gs, n² cells over 3 a."""
    d = 2 * D_GS
    return cp.simulate(make_scene(
        friction={"mu": MU},
        load={"time": [0.0, 1.0, 3.0, 5.0], "normal_force": W,
              "tangential_displacement": [0.0, d, -d, d]},
        grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
        time={"steps": 5 * steps_per_quarter}))


def check_fretting(ds, quarter):
    """The first branch within 2 % of mu W of Mindlin's T(delta); the plateaus |T| = mu W
    within 1 %; every instant within 2 % of mu W of the Masing loop with gross slip; the
    energy of the cycle from 2 delta_gs back to it (the friction work, the archive's
    dissipation) within 3 % of E_MD(mu W) + 4 mu W (delta* - delta_gs); the contact laws,
    the stick area 0 on the plateaus and the imposed displacement reached."""
    om, T = ds.omega1.values, ds.T1.values
    t = ds.time.values
    np.testing.assert_allclose(om, np.interp(t, [0, 1, 3, 5], [0, 2, -2, 2]) * D_GS,
                               rtol=0, atol=1e-15 * D_GS)
    ref = an.displacement_loop_force(om, MU, W, A_HERTZ, C_SUM)
    first = om <= D_GS
    first[quarter + 1:] = False
    branch = np.abs(T[first] - ref[first]).max() / MUW
    plateau_ = np.isclose(np.abs(ref), MUW) & (np.arange(om.size) > 0)
    plateau = np.abs(np.abs(T[plateau_]) / MUW - 1).max()
    assert branch < 0.02 and plateau < 0.01
    assert np.abs(T - ref).max() < 0.02 * MUW
    assert np.all(ds.stick_area.values[plateau_ & (np.abs(om) > D_GS)] == 0)
    d = ds.dissipation.values
    E = d[-1] - d[quarter]
    energy = E / an.displacement_energy_per_cycle(2 * D_GS, MU, W, A_HERTZ, C_SUM) - 1
    assert abs(energy) < 0.03
    assert contact_law_violations(ds) == []
    return branch, plateau, energy


def test_fretting_into_gross_slip():
    """32² over 3 a, 8 steps per quarter cycle: measured first branch 9e-5 mu W, plateau
    exact to rounding, cycle energy -4e-5."""
    check_fretting(fretting(32, 8), 8)


@pytest.mark.slow
def test_fretting_into_gross_slip_fine():
    """64² over 3 a, 16 steps per quarter: measured first branch 8e-5 mu W, plateau
    rounding, cycle energy -4e-5."""
    check_fretting(fretting(64, 16), 16)
