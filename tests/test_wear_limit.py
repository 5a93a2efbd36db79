"""The limiting worn state of a fretted sphere (contactpipe.analytic.wear_limit), checked
against independent quadratures: the force it carries, and the Boussinesq displacement of
its pressure, which must be rigid over the stick zone and close the worn gap outside."""
import numpy as np
import pytest
from scipy import integrate, special

from contactpipe import analytic as an

E_STAR = 210e9 / (2 * (1 - 0.3 ** 2))
R, W, MU = 0.018, 1000.0, 0.3
T_STAR = 0.875 * MU * W                      # c = a / 2


def _limit(t=T_STAR):
    return an.fretting_wear_limit(W, t, MU, R, E_STAR)


def _force(lim):
    """int_0^c 2 pi r p(r) dr with r = c sin(theta): the edge singularity drops out."""
    c = lim.stick_radius

    def f(th):
        r = c * np.sin(th)
        return 2 * np.pi * r * float(lim.pressure(r)) * c * np.cos(th)
    return integrate.quad(f, 0.0, np.pi / 2, epsabs=0.0, epsrel=1e-12)[0]


def _boussinesq(lim, r):
    """Normal displacement at radius r of the axisymmetric pressure (Johnson 1985, ch. 3:
    u = 4/(pi E*) int_0^c p(s) s/(r+s) K(2 sqrt(rs)/(r+s)) ds), by quadrature in
    s = c sin(theta), split at the log singularity s = r."""
    c = lim.stick_radius

    def f(th):
        s = c * np.sin(th)
        k2 = 4 * r * s / (r + s) ** 2
        return float(lim.pressure(s)) * c * np.cos(th) * s / (r + s) * special.ellipk(k2)
    pts = [0.0, np.pi / 2] + ([np.arcsin(r / c)] if 0 < r < c else [])
    pts = sorted(pts)
    total = sum(integrate.quad(f, lo, hi, epsabs=0.0, epsrel=1e-10, limit=200)[0]
                for lo, hi in zip(pts[:-1], pts[1:], strict=True))
    return 4.0 / (np.pi * E_STAR) * total


def test_stick_radius_and_approach_match_the_closed_form():
    lim = _limit()
    a = (3 * W * R / (4 * E_STAR)) ** (1 / 3)
    assert lim.contact_radius == pytest.approx(a, rel=1e-14)
    assert lim.stick_radius == pytest.approx(a / 2, rel=1e-14)       # (1 - 0.875)^(1/3)
    c = a / 2
    assert lim.approach == pytest.approx(W / (2 * E_STAR * c) + c ** 2 / (3 * R), rel=1e-14)
    # the edge term's strength, written through a: 2 E* (a^3 - c^3) / (3 pi R c)
    assert lim.edge_factor == pytest.approx(2 * E_STAR * (a ** 3 - c ** 3) / (3 * np.pi * R * c),
                                            rel=1e-12)
    assert lim.pressure(1.0001 * c) == 0.0 and lim.pressure(2 * c) == 0.0


@pytest.mark.parametrize("ratio", [0.0, 0.3, 0.875, 0.99])
def test_limiting_pressure_carries_the_normal_force(ratio):
    """int p dA = W: 2 pi [2E* c^3/(3 pi R) ... ] reduces to 2E*(d c - c^3/(3R)) = W; here
    by quadrature, to 1e-10."""
    assert _force(_limit(ratio * MU * W)) == pytest.approx(W, rel=1e-10)


def test_no_fretting_leaves_hertz():
    """T* = 0: c = a, d = a^2/R, no edge term, and the pressure is Hertz's."""
    lim, hz = _limit(0.0), an.hertz_sphere(W, R, E_STAR)
    assert lim.stick_radius == pytest.approx(hz.contact_radius, rel=1e-14)
    assert lim.approach == pytest.approx(hz.approach, rel=1e-13)
    assert abs(lim.edge_factor) < 1e-12 * hz.max_pressure * hz.contact_radius
    r = np.linspace(0, 0.99, 12) * hz.contact_radius
    np.testing.assert_allclose(lim.pressure(r), hz.pressure(r), rtol=1e-10)
    np.testing.assert_array_equal(lim.wear_depth(np.linspace(0, 3, 7) * hz.contact_radius), 0.0)


@pytest.mark.parametrize("frac", [0.0, 0.35, 0.8])
def test_pressure_moves_the_stick_zone_rigidly(frac):
    """The Boussinesq displacement of the limiting pressure is d - r^2/(2R) inside r < c:
    the unworn sphere at approach d, i.e. the pressure solves the contact problem (1e-8)."""
    lim = _limit()
    r = frac * lim.stick_radius
    assert _boussinesq(lim, r) == pytest.approx(lim.approach - r ** 2 / (2 * R), rel=1e-8)


@pytest.mark.parametrize("frac", [1.2, 1.6, 3.0])
def test_displacement_outside_the_stick_zone(frac):
    lim = _limit()
    r = frac * lim.stick_radius
    assert _boussinesq(lim, r) == pytest.approx(float(lim.displacement(r)), rel=1e-8)


def test_wear_depth_closes_the_gap_on_the_scar_only():
    lim = _limit()
    c, rs = lim.stick_radius, lim.scar_radius
    assert rs > lim.contact_radius                      # the indenter sinks: the scar spreads
    r = np.linspace(1.001 * c, 0.999 * rs, 50)
    h = lim.wear_depth(r)
    assert np.all(h > 0)
    gap = r ** 2 / (2 * R) + h + lim.displacement(r) - lim.approach
    np.testing.assert_allclose(gap, 0.0, atol=1e-12 * lim.approach)
    np.testing.assert_array_equal(lim.wear_depth(np.array([0.0, 0.5 * c, 0.99 * c])), 0.0)
    np.testing.assert_array_equal(lim.wear_depth(np.array([1.01 * rs, 2 * rs])), 0.0)


@pytest.mark.parametrize("bad", [-1.0, MU * W, 2 * MU * W, np.nan])
def test_refuses_gross_slip_and_bad_amplitude(bad):
    with pytest.raises(ValueError, match="tangential_amplitude"):
        _limit(bad)
