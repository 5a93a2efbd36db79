"""Torsion: Lubkin's closed form (contactpipe.analytic.torsion) and the simulated twist of
two steel spheres under rotation control, into full slip and back.

The simulated contact: steel on steel, R = 18 mm, W = 1 kN (Hertz a = 0.489 mm), mu = 0.1,
the rotation phi3 imposed (load.rotation3) with T = 0 force-controlled; beta_ref = the
full-slip torque over the stuck stiffness.
"""
import numpy as np
import pytest
from helpers import A_HERTZ, MU, P0_HERTZ, W, make_scene
from scipy import integrate

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.testing import contact_law_violations

C_T = an.torsional_compliance(210e9, 0.3, 210e9, 0.3)
K_STUCK = an.torsional_stiffness(A_HERTZ, C_T)
M_MAX = an.full_slip_torque(MU, W, A_HERTZ)
BETA_REF = M_MAX / K_STUCK


# --------------------------------------------------------------------------- closed form
def test_stiffness_and_full_slip_torque():
    """16 a³/(3 C) with C = 1/G1 + 1/G2 (a rigid body adds nothing); 3 pi mu W a / 16 is
    the integral of mu p r over the Hertz contact (quadrature, 1e-10)."""
    G = 210e9 / 2.6
    assert C_T == pytest.approx(2 / G, rel=1e-15)
    assert an.torsional_compliance(np.inf, 0.0, 210e9, 0.3) == pytest.approx(1 / G, rel=1e-15)
    assert K_STUCK == pytest.approx(16 * A_HERTZ ** 3 * G / 6, rel=1e-15)
    quad = integrate.quad(lambda r: MU * P0_HERTZ * np.sqrt(1 - (r / A_HERTZ) ** 2)
                          * r * 2 * np.pi * r, 0, A_HERTZ)[0]
    assert M_MAX == pytest.approx(quad, rel=1e-10)


def test_lubkin_limits():
    """c = a: no twist, no torque; c -> a: M/beta -> the stuck stiffness (c/a = 0.99999:
    within 2e-5); c = 0: full slip, M = 3 pi mu W a / 16 (1e-12) and beta = inf; beta and
    M both fall as the stick zone grows."""
    beta, M = an.lubkin_torsion([1.0, 0.99999, 0.0], MU, W, A_HERTZ, C_T)
    assert beta[0] == 0.0 and M[0] == 0.0
    assert M[1] / beta[1] == pytest.approx(K_STUCK, rel=2e-5)
    assert np.isinf(beta[2]) and M[2] == pytest.approx(M_MAX, rel=1e-12)
    ratio = np.linspace(0.01, 0.99, 50)
    beta, M = an.lubkin_torsion(ratio, MU, W, A_HERTZ, C_T)
    assert np.all(np.diff(beta) < 0) and np.all(np.diff(M) < 0)


@pytest.mark.parametrize("ratio", [0.2, 0.5, 0.8, 0.95])
def test_lubkin_tangent_stiffness_is_the_stick_discs(ratio):
    """A twist increment is carried by the stick zone turning as a rigid disc: the tangent
    stiffness dM/dbeta of Lubkin's curve equals the stuck stiffness of a disc of the stick
    radius, 16 c³/(3 C) (central differences in c/a, step 1e-5: within 1e-6)."""
    h = 1e-5
    beta, M = an.lubkin_torsion([ratio - h, ratio + h], MU, W, A_HERTZ, C_T)
    slope = (M[1] - M[0]) / (beta[1] - beta[0])
    assert slope == pytest.approx(an.torsional_stiffness(ratio * A_HERTZ, C_T), rel=1e-6)


def test_lubkin_moment_inverts_the_curve():
    """lubkin_moment(beta(c)) = M(c) (1e-10); odd in beta; beyond any resolvable stick
    zone it returns the full-slip torque."""
    beta, M = an.lubkin_torsion(0.6, MU, W, A_HERTZ, C_T)
    assert an.lubkin_moment(beta, MU, W, A_HERTZ, C_T) == pytest.approx(M, rel=1e-10)
    assert an.lubkin_moment(-beta, MU, W, A_HERTZ, C_T) == pytest.approx(-M, rel=1e-10)
    assert an.lubkin_moment(1e6, MU, W, A_HERTZ, C_T) == pytest.approx(M_MAX, rel=1e-12)
    np.testing.assert_allclose(an.lubkin_moment([0.0, beta], MU, W, A_HERTZ, C_T), [0.0, M],
                               rtol=1e-10)


# --------------------------------------------------------------------------- simulation
TWISTS = [0.0, 0.01, 0.25, 0.5, 1.0, 2.0, 4.0, 20.0, -20.0]     # x beta_ref


def twist(n):
    """phi3 through TWISTS (one step per knot), n² cells over 2.5 a."""
    return cp.simulate(make_scene(
        friction={"mu": MU},
        load={"time": list(range(len(TWISTS))), "normal_force": W,
              "rotation3": [b * BETA_REF for b in TWISTS]},
        grid={"points": [n, n], "size": [2.5 * A_HERTZ] * 2}, time={"steps": len(TWISTS) - 1}))


def check_twist(ds, tol_stiffness, tol_curve):
    """Small twist (0.01 beta_ref, c/a = 0.998): M/phi3 within ``tol_stiffness`` of the
    stuck stiffness; the partial-slip curve within ``tol_curve`` M_max of Lubkin at every
    twist; at 20 beta_ref (stick radius 4e-9 a) within 2 % of the full-slip torque; back at
    -20 beta_ref, through the reversal, -M_max within 2 %; the contact laws hold (gross
    slip is a valid state under rotation control)."""
    M, phi = ds.M3.values, ds.phi3.values
    np.testing.assert_allclose(phi, np.array(TWISTS) * BETA_REF, rtol=1e-12, atol=0)
    stiffness = M[1] / phi[1] / K_STUCK - 1
    assert abs(stiffness) < tol_stiffness
    curve = np.abs(M - an.lubkin_moment(phi, MU, W, A_HERTZ, C_T)) / M_MAX
    assert curve.max() < tol_curve
    assert M[-2] == pytest.approx(M_MAX, rel=0.02)
    assert M[-1] == pytest.approx(-M_MAX, rel=0.02)
    assert float(ds.stick_area[-2]) == 0.0 and float(ds.stick_area[-1]) == 0.0
    assert np.abs(ds.T1.values).max() < 1e-9 * MU * W
    assert contact_law_violations(ds) == []
    return stiffness, curve.max(), M[-2] / M_MAX - 1


def test_torsion_to_full_slip():
    """24² over 2.5 a (cell a/9.6): measured stiffness +2.5 %, curve within 0.15 % of
    M_max (bound 1 %), final torque -0.07 %."""
    check_twist(twist(24), 0.04, 0.01)


@pytest.mark.slow
def test_torsion_to_full_slip_fine():
    """64² over 2.5 a (cell a/25.6): measured stiffness -0.06 %, curve within 0.02 % of
    M_max (bound 0.2 %), final torque -0.015 %."""
    check_twist(twist(64), 0.04, 0.002)
