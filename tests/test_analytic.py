"""Tests of the closed-form solutions in contactpipe.analytic."""
import numpy as np
import pytest
from helpers import md_circles, radial_force
from scipy import integrate

from contactpipe import analytic as an
from contactpipe import materials as mat
from contactpipe.exceptions import GrossSlidingError

# the paper's steel-on-steel case
E_STEEL, NU_STEEL = 210e9, 0.3
R_BALL, W = 0.018, 1000.0
MU = 0.3
E_STAR = an.composite_modulus(E_STEEL, NU_STEEL, E_STEEL, NU_STEEL)
HZ = an.hertz_sphere(W, R_BALL, E_STAR)
A, P0 = HZ.contact_radius, HZ.max_pressure
C_SUM = an.tangential_compliance_sum(E_STEEL, NU_STEEL, E_STEEL, NU_STEEL)
MUW = MU * W


# --------------------------------------------------------------------------- Hertz
def test_paper_numbers():
    assert HZ.max_pressure == pytest.approx(1.996e9, rel=5e-4)
    assert HZ.contact_radius == pytest.approx(0.489e-3, rel=1e-3)
    assert HZ.approach == pytest.approx(A ** 2 / R_BALL, rel=1e-14)
    assert HZ.mean_pressure == pytest.approx(2 * P0 / 3, rel=1e-14)


def test_composite_modulus_and_compliance():
    assert E_STAR == pytest.approx(E_STEEL / (2 * (1 - NU_STEEL ** 2)), rel=1e-14)
    assert an.composite_modulus(np.inf, 0.3, 3e9, 0.4) == pytest.approx(3e9 / 0.84)
    assert an.composite_modulus(np.inf, 0.3, np.inf, 0.3) == np.inf
    g = E_STEEL / (2 * 1.3)
    assert C_SUM == pytest.approx(2 * 1.7 / g, rel=1e-14)
    assert an.tangential_compliance_sum(np.inf, 0.3, E_STEEL, NU_STEEL) == pytest.approx(1.7 / g)
    assert an.tangential_compliance_sum(np.inf, 0.3, np.inf, 0.3) == 0.0


def test_hertz_equilibrium_and_cell_average():
    assert radial_force(HZ.pressure, A) == pytest.approx(W, rel=1e-10)
    assert HZ.pressure(0.0) == P0 and HZ.pressure(1.01 * A) == 0.0
    n, L = 64, 3 * A
    d = L / n
    x = -L / 2 + (np.arange(n) + 0.5) * d
    pbar = an.cell_average(HZ.pressure, x[:, None], x[None, :], d, d, order=16, radial=True)
    assert pbar.sum() * d * d == pytest.approx(W, rel=2e-4)
    # interior cells: the cell average of a smooth field is close to the centre value
    r = np.hypot(x[:, None], x[None, :])
    inner = r < 0.5 * A
    np.testing.assert_allclose(pbar[inner], HZ.pressure(r[inner]), rtol=2e-3)


def test_cell_average_is_exact_for_polynomials():
    def f(x1, x2):
        return x1 ** 4 * x2 ** 2 + 3 * x1 * x2
    x1c, x2c, d1, d2 = 0.3, -0.7, 0.2, 0.5
    exact = ((((x1c + d1 / 2) ** 5 - (x1c - d1 / 2) ** 5) / 5)
             * (((x2c + d2 / 2) ** 3 - (x2c - d2 / 2) ** 3) / 3)) / (d1 * d2) + 3 * x1c * x2c
    assert an.cell_average(f, x1c, x2c, d1, d2) == pytest.approx(exact, rel=1e-13)


# --------------------------------------------------------------------------- ellipsoid
def test_ellipsoid_reduces_to_sphere():
    el = an.hertz_ellipsoid(W, (R_BALL, R_BALL), E_STAR)
    assert el.semi_axes[0] == pytest.approx(A, rel=1e-13)
    assert el.semi_axes[1] == pytest.approx(A, rel=1e-13)
    assert el.max_pressure == pytest.approx(P0, rel=1e-13)
    assert el.approach == pytest.approx(HZ.approach, rel=1e-13)
    assert el.eccentricity == 0.0
    # and continuously so
    near = an.hertz_ellipsoid(W, (R_BALL, R_BALL * (1 + 1e-8)), E_STAR)
    assert near.max_pressure == pytest.approx(P0, rel=1e-8)
    assert near.approach == pytest.approx(HZ.approach, rel=1e-8)
    assert near.semi_axes[1] > near.semi_axes[0]


def _boussinesq_u3(el, x0, y0):
    """u3 at (x0, y0) under the ellipsoidal pressure, by polar integration about it.

    The radial integral of p0 sqrt(Q(rho)) with Q quadratic is done in closed form,
    the angular one by quadrature: u = 1/(pi E*) int dtheta int p drho.
    """
    a1, a2 = el.semi_axes

    def inner(th):
        c, s = np.cos(th), np.sin(th)
        q2 = c * c / a1 ** 2 + s * s / a2 ** 2
        q1 = -2 * (x0 * c / a1 ** 2 + y0 * s / a2 ** 2)
        q0 = 1 - x0 ** 2 / a1 ** 2 - y0 ** 2 / a2 ** 2
        rc = q1 / (2 * q2)
        dd = q0 / q2 + rc ** 2
        # int_{-rc}^{sqrt(dd)} sqrt(dd - u^2) du = dd pi/4 - F(-rc),
        # F(u) = (u sqrt(dd - u^2) + dd arcsin(u / sqrt(dd))) / 2
        f_lo = 0.5 * (-rc * np.sqrt(dd - rc * rc) + dd * np.arcsin(-rc / np.sqrt(dd)))
        return np.sqrt(q2) * (0.25 * np.pi * dd - f_lo)

    val = integrate.quad(inner, 0, 2 * np.pi, epsabs=0, epsrel=1e-12, limit=200)[0]
    return el.max_pressure * val / (np.pi * el.composite_modulus)


@pytest.mark.parametrize("radii", [(0.018, 0.05), (0.2, 0.01), (0.001, 1.0)])
def test_ellipsoid_satisfies_contact_conditions(radii):
    el = an.hertz_ellipsoid(W, radii, E_STAR)
    a1, a2 = el.semi_axes
    assert (a1 < a2) == (radii[0] < radii[1])
    assert el.max_pressure == pytest.approx(3 * W / (2 * np.pi * a1 * a2), rel=1e-14)
    # the displacement fills the gap inside the ellipse: u3 = delta - x1^2/2R1 - x2^2/2R2
    for x0, y0 in [(0.0, 0.0), (0.6 * a1, 0.0), (0.0, 0.7 * a2), (0.3 * a1, -0.5 * a2)]:
        target = el.approach - x0 ** 2 / (2 * radii[0]) - y0 ** 2 / (2 * radii[1])
        assert _boussinesq_u3(el, x0, y0) == pytest.approx(target, abs=1e-11 * el.approach)


def test_ellipsoid_equilibrium():
    el = an.hertz_ellipsoid(W, (0.018, 0.05), E_STAR)
    a1, a2 = el.semi_axes
    force = integrate.dblquad(lambda x2, x1: float(el.pressure(x1, x2)), -a1, a1,
                              lambda x1: -a2 * np.sqrt(max(1 - (x1 / a1) ** 2, 0.0)),
                              lambda x1: a2 * np.sqrt(max(1 - (x1 / a1) ** 2, 0.0)),
                              epsabs=0, epsrel=1e-9)[0]
    assert force == pytest.approx(W, rel=1e-6)


def test_ellipsoid_rejects_line_contact():
    with pytest.raises(ValueError):
        an.hertz_ellipsoid(W, (0.01, np.inf), E_STAR)


# --------------------------------------------------------------------------- flat punch
FP = an.flat_punch(W, 1e-3, E_STAR)


def test_flat_punch_pressure_and_approach():
    a = FP.contact_radius
    assert FP.approach == pytest.approx(W / (2 * a * E_STAR), rel=1e-14)
    # int 2 pi r p dr with the (a - r)^(-1/2) weight handled by QAWS
    def g(r):
        return 2 * np.pi * r * W / (2 * np.pi * a * np.sqrt(a + r))
    force = integrate.quad(g, 0, a, weight="alg", wvar=(0.0, -0.5), epsrel=1e-12)[0]
    assert force == pytest.approx(W, rel=1e-10)
    assert radial_force(FP.pressure, 0.5 * a) == pytest.approx(
        W * (1 - np.sqrt(1 - 0.25)), rel=1e-10)
    assert FP.pressure(2 * a) == 0.0 and FP.pressure(a) == np.inf


def test_flat_punch_cell_averages():
    a = FP.contact_radius
    n, L = 24, 2.6 * a
    d = L / n
    x = -L / 2 + (np.arange(n) + 0.5) * d
    pbar = FP.cell_average_pressure(x[:, None], x[None, :], d, d)
    assert pbar.sum() * d * d == pytest.approx(W, rel=1e-10)
    np.testing.assert_allclose(pbar, pbar[::-1, :], rtol=1e-9)
    np.testing.assert_allclose(pbar, pbar.T, rtol=1e-9)
    # one column |x1| < b over all x2 carries W b/a exactly (int dx2/sqrt = pi)
    j = n // 2
    b_lo, b_hi = x[j] - d / 2, x[j] + d / 2
    col = pbar[j, :].sum() * d * d
    exact = W / (2 * np.pi * a) * np.pi * (b_hi - b_lo)
    assert col == pytest.approx(exact, rel=1e-10)
    # cells well inside the punch: agree with Gauss-Legendre averages of the point values
    r = np.hypot(x[:, None], x[None, :]) + np.sqrt(2) * d / 2
    inner = r < 0.8 * a
    gl = an.cell_average(FP.pressure, x[:, None], x[None, :], d, d, order=12, radial=True)
    np.testing.assert_allclose(pbar[inner], gl[inner], rtol=1e-9)
    # cells beyond the punch are exactly zero
    outside = np.hypot(np.abs(x[:, None]) - d / 2, np.abs(x[None, :]) - d / 2) >= a
    assert np.all(pbar[outside] == 0.0)


def _punch_cell_force_polar(a, x0, x1, y0, y1):
    """Force on [x0, x1] x [y0, y1] (not containing the origin) by polar integration.

    Along a ray, p r dr = W/(2 pi a) d(-sqrt(a^2 - r^2)), so the radial integral between
    the ray's entry and exit radii is analytic and bounded; the angular one is done by
    quadrature split at the corner angles. Independent of the x-then-y method used by
    FlatPunch.cell_average_pressure.
    """
    corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
    angles = np.unwrap(sorted(np.arctan2(y, x) for x, y in corners))
    lo, hi = angles.min(), angles.max()
    if hi - lo > np.pi:                 # cell straddles the negative x1 axis
        angles = np.sort(np.mod(angles, 2 * np.pi))
        lo, hi = angles.min(), angles.max()

    def ray(th):
        c, s = np.cos(th), np.sin(th)
        tx = sorted(((x0 / c), (x1 / c))) if abs(c) > 1e-300 else [-np.inf, np.inf]
        ty = sorted(((y0 / s), (y1 / s))) if abs(s) > 1e-300 else [-np.inf, np.inf]
        r_in, r_out = max(tx[0], ty[0], 0.0), min(tx[1], ty[1])
        r_in, r_out = min(r_in, a), min(max(r_out, r_in), a)
        return W / (2 * np.pi * a) * (np.sqrt(a * a - r_in ** 2) - np.sqrt(a * a - r_out ** 2))

    # the ray integrand has square-root cusps where the ring crosses the cell's edges
    brk = list(angles)
    for xe in (x0, x1):
        if abs(xe) < a:
            for ye in (np.sqrt(a * a - xe * xe), -np.sqrt(a * a - xe * xe)):
                if y0 <= ye <= y1:
                    brk.append(np.arctan2(ye, xe))
    for ye in (y0, y1):
        if abs(ye) < a:
            for xe in (np.sqrt(a * a - ye * ye), -np.sqrt(a * a - ye * ye)):
                if x0 <= xe <= x1:
                    brk.append(np.arctan2(ye, xe))
    brk = np.array(brk)
    if angles.max() > np.pi:
        brk = np.mod(brk, 2 * np.pi)
    brk = np.unique(np.clip(brk, lo, hi))
    return sum(integrate.quad(ray, u, v, epsabs=0, epsrel=1e-13, limit=200)[0]
               for u, v in zip(brk[:-1], brk[1:], strict=True))


def test_flat_punch_cut_cells_against_polar_integration():
    a = FP.contact_radius
    d = 0.13 * a
    for xc, yc in [(0.95 * a, 0.02 * a), (0.7 * a, 0.66 * a), (-0.3 * a, -0.97 * a),
                   (0.99 * a, 0.1 * a), (-0.2 * a, 0.5 * a), (-0.95 * a, 0.03 * a)]:
        got = float(FP.cell_average_pressure(xc, yc, d, d)) * d * d
        ref = _punch_cell_force_polar(a, xc - d / 2, xc + d / 2, yc - d / 2, yc + d / 2)
        assert got == pytest.approx(ref, rel=1e-12)


# --------------------------------------------------------------------------- Cattaneo
@pytest.mark.parametrize("t", [0.0, 0.3 * MUW, -0.8 * MUW, MUW])
def test_cattaneo_equilibrium_and_slip_zone(t):
    cm = an.cattaneo_mindlin(t, MU, W, A, P0)
    c = cm.stick_radius
    assert c == pytest.approx(A * (1 - abs(t) / MUW) ** (1 / 3), abs=1e-18)
    assert radial_force(cm.traction, A, [c]) == pytest.approx(t, rel=1e-9, abs=1e-9 * MUW)
    r = np.linspace(0, A, 2001)
    q, p = cm.traction(r), HZ.pressure(r)
    slip = r > c
    np.testing.assert_allclose(q[slip], np.sign(t) * MU * p[slip], rtol=1e-12, atol=1e-9 * P0)
    assert np.all(np.abs(q) <= MU * p * (1 + 1e-12) + 1e-9 * P0)
    assert np.all(q * t >= 0)


def test_gross_sliding_raises():
    with pytest.raises(GrossSlidingError):
        an.cattaneo_mindlin(1.01 * MUW, MU, W, A, P0)
    with pytest.raises(GrossSlidingError):
        an.mindlin_deresiewicz_traction(0.0, [0.5 * MUW, 1.2 * MUW], MU, W, A, P0)


# --------------------------------------------------------------------------- Mindlin-Deresiewicz
TS = 0.7 * MUW          # amplitude T*
HISTORIES = {
    "virgin": [0.2 * TS, 0.6 * TS, TS],
    "unloading": [TS, 0.4 * TS],
    "reversed": [TS, -0.5 * TS],
    "reloading": [TS, -0.8 * TS, 0.1 * TS],
    "nested": [TS, -0.8 * TS, 0.5 * TS, -0.2 * TS, 0.3 * TS],
    "closed_then_virgin": [0.5 * TS, -0.2 * TS, TS],
}


def _circles(hist):
    return md_circles(hist, A, MUW)


@pytest.mark.parametrize("name", sorted(HISTORIES))
def test_md_equilibrium_and_friction_bound(name):
    hist = HISTORIES[name]
    def q(r):
        return an.mindlin_deresiewicz_traction(r, hist, MU, W, A, P0)
    assert radial_force(q, A, _circles(hist)) == pytest.approx(hist[-1], rel=1e-10)
    r = np.linspace(0, A, 4001)
    assert np.all(np.abs(q(r)) <= MU * HZ.pressure(r) * (1 + 1e-10) + 1e-9 * P0)
    # slip annulus of the current branch: |q| = mu p with the sign of the increment
    c = an.stick_radius(hist, MU, W, A)
    direction = np.sign(hist[-1] - (hist[-2] if len(hist) > 1 else 0.0))
    out = r > c
    np.testing.assert_allclose(q(r[out]), direction * MU * HZ.pressure(r[out]),
                               rtol=1e-10, atol=1e-9 * P0)


def test_md_unloading_closed_form():
    t = -0.3 * TS
    c_star = A * (1 - TS / MUW) ** (1 / 3)
    c_prime = A * (1 - (TS - t) / (2 * MUW)) ** (1 / 3)
    r = np.linspace(0, 1.1 * A, 501)
    def sq(c):
        return np.sqrt(np.clip(c * c - r * r, 0, None))
    ref = -MU * P0 / A * (sq(A) - 2 * sq(c_prime) + sq(c_star))
    np.testing.assert_allclose(an.mindlin_deresiewicz_traction(r, [TS, t], MU, W, A, P0),
                               ref, rtol=1e-13, atol=1e-12 * P0)
    assert an.stick_radius([TS, t], MU, W, A) == pytest.approx(c_prime, rel=1e-14)
    assert an.stick_radius([TS], MU, W, A) == pytest.approx(c_star, rel=1e-14)
    assert an.stick_radius([TS, TS - 1e-9], MU, W, A) == pytest.approx(A, rel=1e-9)


def test_md_continuity_at_reversals():
    r = np.linspace(0, A, 801)
    eps = 1e-9 * MUW
    for base in ([TS], [TS, -0.8 * TS], [TS, -0.8 * TS, 0.5 * TS]):
        back = base[-1] - np.sign(base[-1] - (base[-2] if len(base) > 1 else 0.0)) * eps
        q0 = an.mindlin_deresiewicz_traction(r, base, MU, W, A, P0)
        q1 = an.mindlin_deresiewicz_traction(r, base + [back], MU, W, A, P0)
        assert np.max(np.abs(q1 - q0)) < 1e-3 * MU * P0
        d0 = an.tangential_displacement(base, MU, W, A, C_SUM)
        d1 = an.tangential_displacement(base + [back], MU, W, A, C_SUM)
        assert abs(d1 - d0) < 1e-6 * abs(d0)


def test_md_virgin_displacement_and_stiffness():
    d = an.tangential_displacement([TS], MU, W, A, C_SUM)
    assert d == pytest.approx(3 * MUW / (16 * A) * C_SUM * (1 - (1 - TS / MUW) ** (2 / 3)),
                              rel=1e-14)
    assert an.tangential_displacement([-TS], MU, W, A, C_SUM) == pytest.approx(-d, rel=1e-14)
    # initial tangential stiffness 8 a / C  (Mindlin)
    dt = 1e-6 * MUW
    assert an.tangential_displacement([dt], MU, W, A, C_SUM) / dt == pytest.approx(
        C_SUM / (8 * A), rel=1e-5)
    assert an.tangential_displacement([TS], MU, W, A, 0.0) == 0.0


def test_md_loop_closes():
    cycle = [TS, -TS, TS]
    assert an.masing_memory(cycle) == ((), TS)
    d_top = an.tangential_displacement([TS], MU, W, A, C_SUM)
    assert an.tangential_displacement(cycle, MU, W, A, C_SUM) == pytest.approx(d_top, rel=1e-14)
    d_bottom = an.tangential_displacement([TS, -TS], MU, W, A, C_SUM)
    assert d_bottom == pytest.approx(-d_top, rel=1e-14)
    # several cycles, sampled: periodic
    t = TS * np.cos(np.linspace(0, 6 * np.pi, 601))
    hist = np.concatenate([np.linspace(0, TS, 51)[1:], t])
    d = an.tangential_displacement(hist, MU, W, A, C_SUM, all_instants=True)
    assert d.shape == hist.shape
    assert d[-1] == pytest.approx(d_top, rel=1e-12)
    np.testing.assert_allclose(d[50:250], d[250:450], rtol=1e-12, atol=1e-15)
    assert d[123] == pytest.approx(an.tangential_displacement(hist[:124], MU, W, A, C_SUM))
    q_end = an.mindlin_deresiewicz_traction(np.linspace(0, A, 50), hist, MU, W, A, P0)
    np.testing.assert_allclose(q_end, an.cattaneo_mindlin(TS, MU, W, A, P0).traction(
        np.linspace(0, A, 50)), rtol=1e-12, atol=1e-9 * P0)


def test_md_masing_nested_subcycles():
    t1, t2, t3, t4 = TS, -0.8 * TS, 0.5 * TS, -0.2 * TS
    # two nested sub-cycles: t3 -> t4 -> t3 inside t2 -> t1 -> t2 inside the main branch
    hist = [t1, t2, t3, t4, 0.1 * TS, t4 + 0.05 * TS]
    assert an.masing_memory(hist)[0] == (t1, t2, t3, t4, 0.1 * TS)
    # closing the inner sub-cycle (back through t3) wipes (t3, t4)
    hist_in = [t1, t2, t3, t4, 0.7 * TS]
    assert an.masing_memory(hist_in) == ((t1, t2), 0.7 * TS)
    def d(h):
        return an.tangential_displacement(h, MU, W, A, C_SUM)
    def q(h):
        return an.mindlin_deresiewicz_traction(np.linspace(0, A, 101), h, MU, W, A, P0)
    assert d(hist_in) == pytest.approx(d([t1, t2, 0.7 * TS]), rel=1e-13)
    np.testing.assert_allclose(q(hist_in), q([t1, t2, 0.7 * TS]), rtol=1e-12, atol=1e-9 * P0)
    # return-point memory: back at t3 the state is the one left at t3
    assert d([t1, t2, t3, t4, t3]) == pytest.approx(d([t1, t2, t3]), rel=1e-13)
    # going on past t1 wipes the outer sub-cycle too: virgin curve again
    hist_out = [t1, t2, t3, t4, 0.9 * MUW]
    assert an.masing_memory(hist_out) == ((), 0.9 * MUW)
    assert d(hist_out) == pytest.approx(d([0.9 * MUW]), rel=1e-13)
    # explicit Masing branch inside the inner sub-cycle
    def dv(f):
        return np.sign(f) * 3 * MUW * C_SUM / (16 * A) * (1 - (1 - abs(f) / MUW) ** (2 / 3))
    t = 0.1 * TS
    ref = dv(t1) + 2 * dv((t2 - t1) / 2) + 2 * dv((t3 - t2) / 2) + 2 * dv((t4 - t3) / 2) \
        + 2 * dv((t - t4) / 2)
    assert d([t1, t2, t3, t4, t]) == pytest.approx(ref, rel=1e-13)
    # the virgin-curve memory closes at -T1
    assert an.masing_memory([t1, -t1 * 1.1]) == ((), -t1 * 1.1)
    assert an.masing_memory([t1, -t1 * 0.9]) == ((t1,), -t1 * 0.9)


@pytest.mark.parametrize("frac", [0.05, 0.5, 0.95])
def test_energy_per_cycle_equals_loop_area(frac):
    ts = frac * MUW
    def down(t):
        return an.tangential_displacement([ts, t], MU, W, A, C_SUM)
    def up(t):
        return an.tangential_displacement([ts, -ts, t], MU, W, A, C_SUM)
    area = integrate.quad(lambda t: down(t) - up(t), -ts, ts, epsabs=0, epsrel=1e-12)[0]
    e = an.energy_per_cycle(ts, MU, W, A, C_SUM)
    assert e > 0
    assert e == pytest.approx(area, rel=1e-6)
    # the same from the dissipation sum of an integration of T d(delta) round the loop
    t = ts * np.cos(np.linspace(0, 2 * np.pi, 20001))
    dd = an.tangential_displacement(np.concatenate([[ts], t]), MU, W, A, C_SUM,
                                    all_instants=True)[1:]
    loop = np.sum(0.5 * (t[1:] + t[:-1]) * np.diff(dd))
    assert loop == pytest.approx(e, rel=1e-3)


def test_energy_small_amplitude_limit():
    ts = 1e-3 * MUW
    e = an.energy_per_cycle(ts, MU, W, A, C_SUM)
    assert e == pytest.approx(C_SUM * ts ** 3 / (36 * A * MUW), rel=2e-3)


# --------------------------------------------------------------------------- Lee-Radok
E_V, NU_V, R_V, W_V = 3e9, 0.4, 0.01, 10.0


def test_lee_radok_maxwell():
    tp = 2.0
    t = np.linspace(0, 10, 11)
    a = an.lee_radok_sphere(t, W_V, R_V, E_V, NU_V, mat.maxwell(tp))
    a0 = an.hertz_sphere(W_V, R_V, E_V / (1 - NU_V ** 2)).contact_radius
    np.testing.assert_allclose(a.contact_radius ** 3, a0 ** 3 * (1 + t / tp), rtol=1e-13)
    np.testing.assert_allclose(a.approach, a.contact_radius ** 2 / R_V, rtol=1e-14)
    assert an.lee_radok_sphere(-1.0, W_V, R_V, E_V, NU_V, mat.maxwell(tp)).contact_radius == 0


def test_lee_radok_kelvin_voigt():
    kv = mat.kelvin_voigt(1.5)
    res = an.lee_radok_sphere(np.array([0.0, 60.0]), W_V, R_V, E_V, NU_V, kv)
    assert res.contact_radius[0] == 0.0
    a_inf = an.hertz_sphere(W_V, R_V, E_V / (1 - NU_V ** 2)).contact_radius
    assert res.contact_radius[1] == pytest.approx(a_inf, rel=1e-12)
    with pytest.raises(ValueError):
        an.relaxation_function([1.0], kv)


@pytest.mark.parametrize("creep", [mat.maxwell(2.0), mat.zener(3e9, 1e9, 1.5),
                                   mat.TabulatedCreep((0.0, 1.0, 3.0), (1.0, 1.4, 2.0)),
                                   lambda u: 1.2 - 0.2 * np.exp(-np.asarray(u) / 0.7)])
def test_lee_radok_ramp_hereditary_integral(creep):
    knots_t, knots_w = [0.5, 2.0, 2.0, 4.0], [2.0, 8.0, 9.0, 10.0]
    pref = 3 * R_V * (1 - NU_V ** 2) / (4 * E_V)
    def phi(u):
        return float(creep(u))
    for t in [0.2, 0.5, 1.3, 2.0, 3.1, 7.0]:
        got = float(an.lee_radok_radius(t, knots_t, knots_w, R_V, E_V, NU_V, creep))
        if t < 0.5:
            assert got == 0.0
            continue
        acc = 2.0 * phi(t - 0.5)
        acc += integrate.quad(lambda s, t=t: phi(t - s) * 4.0, 0.5, min(t, 2.0), epsrel=1e-12)[0]
        if t >= 2.0:
            acc += 1.0 * phi(t - 2.0)
            acc += integrate.quad(lambda s, t=t: phi(t - s) * 0.5, 2.0, min(t, 4.0),
                                  epsrel=1e-12)[0]
        assert got == pytest.approx((pref * acc) ** (1 / 3), rel=1e-9)
    # a single step is lee_radok_sphere
    t = np.array([0.0, 1.0, 5.0])
    np.testing.assert_allclose(
        an.lee_radok_radius(t, [0.0], [W_V], R_V, E_V, NU_V, creep),
        an.lee_radok_sphere(t, W_V, R_V, E_V, NU_V, creep).contact_radius, rtol=1e-13)


def test_lee_radok_rejects_unloading():
    with pytest.raises(ValueError):
        an.lee_radok_radius(1.0, [0.0, 1.0], [5.0, 2.0], R_V, E_V, NU_V, mat.maxwell(1.0))


def test_relaxation_function_closed_forms():
    t = np.linspace(0, 6, 25)
    np.testing.assert_allclose(an.relaxation_function(t, mat.maxwell(2.0)),
                               np.exp(-t / 2.0), rtol=0, atol=2e-7)
    r, tau = 3.0, 1.5
    np.testing.assert_allclose(an.relaxation_function(t, mat.zener(3e9, 1e9, tau)),
                               1 / r + (1 - 1 / r) * np.exp(-r * t / tau), rtol=0, atol=3e-6)
    np.testing.assert_allclose(an.relaxation_function(t, mat.ELASTIC), 1.0, rtol=1e-14)


def _force_axisym(p, a, a0):
    """int_0^a 2 pi r p dr, Gauss-Legendre in r = a sin(theta), split at a0."""
    x, w = np.polynomial.legendre.leggauss(200)
    total = 0.0
    for lo, hi in ((0.0, a0), (a0, a)):
        if hi <= lo:
            continue
        t0, t1 = np.arcsin(lo / a), np.pi / 2 if hi == a else np.arcsin(hi / a)
        th = 0.5 * (t1 - t0) * x + 0.5 * (t1 + t0)
        r = a * np.sin(th)
        total += 0.5 * (t1 - t0) * np.sum(w * 2 * np.pi * r * p(r) * a * np.cos(th))
    return total


def test_lee_radok_pressure():
    # elastic: Hertz
    hz = an.hertz_sphere(W_V, R_V, E_V / (1 - NU_V ** 2))
    r = np.linspace(0, 1.2 * hz.contact_radius, 50)
    np.testing.assert_allclose(an.lee_radok_pressure(r, 3.0, W_V, R_V, E_V, NU_V, mat.ELASTIC),
                               hz.pressure(r), rtol=1e-12, atol=1e-9 * hz.max_pressure)
    np.testing.assert_allclose(an.lee_radok_pressure(r, 0.0, W_V, R_V, E_V, NU_V,
                                                     mat.maxwell(2.0)),
                               hz.pressure(r), rtol=1e-12, atol=1e-9 * hz.max_pressure)
    # Maxwell, psi = exp(-t/t'): p = C [h(r, t) - int_0^t psi(t-s)/t' h(r, s) ds]
    tp, t = 2.0, 3.0
    mx = mat.maxwell(tp)
    a0 = hz.contact_radius
    a_t = float(an.lee_radok_sphere(t, W_V, R_V, E_V, NU_V, mx).contact_radius)
    pref = 2 * E_V / (np.pi * R_V * (1 - NU_V ** 2))

    def p_ref(rr):
        def h(s):
            return np.sqrt(max(a0 ** 2 * (1 + s / tp) ** (2 / 3) - rr ** 2, 0.0))
        s_on = max(((rr / a0) ** 3 - 1) * tp, 0.0)
        integral = integrate.quad(lambda s: np.exp(-(t - s) / tp) / tp * h(s), s_on, t,
                                  epsabs=0, epsrel=1e-11)[0]
        return pref * (h(t) - integral)

    rr = np.array([0.0, 0.5 * a0, 0.99 * a0, 1.05 * a0, 0.5 * (a0 + a_t), 0.98 * a_t])
    got = an.lee_radok_pressure(rr, t, W_V, R_V, E_V, NU_V, mx)
    ref = np.array([p_ref(x) for x in rr])
    np.testing.assert_allclose(got, ref, rtol=1e-4, atol=1e-6 * hz.max_pressure)
    assert np.all(an.lee_radok_pressure([1.01 * a_t], t, W_V, R_V, E_V, NU_V, mx) == 0.0)
    # equilibrium at every instant (the load is constant)
    for creep in (mx, mat.zener(3e9, 1e9, 1.5)):
        for tt in (0.5, 4.0):
            at = float(an.lee_radok_sphere(tt, W_V, R_V, E_V, NU_V, creep).contact_radius)
            def p(x, tt=tt, creep=creep):
                return an.lee_radok_pressure(x, tt, W_V, R_V, E_V, NU_V, creep)
            assert _force_axisym(p, at, a0) == pytest.approx(W_V, rel=1e-6)


# --------------------------------------------------------------------------- Spence
def test_spence_reference_is_the_flat_punch_without_coupling():
    """β = 0, every ring stuck: no shear, and the load increment is the frictionless flat
    punch's, P = 2/(π √(1 − r²)) per unit approach (units of 1/A), to 0.12 % over r < a/2
    and 0.44 % over r < 0.9 a at 200 rings (measured)."""
    from contactpipe.analytic.spence import spence_increments
    r, P, Q, U = spence_increments(0.3, 0.0, 200, 200)
    exact = 2.0 / (np.pi * np.sqrt(1.0 - r ** 2))
    assert np.all(Q == 0) and np.all(U == 0)
    assert np.abs(P / exact - 1)[r < 0.5].max() < 1.5e-3
    assert np.abs(P / exact - 1)[r < 0.9].max() < 5e-3


def test_spence_stick_ratio_limits_and_trend():
    """λ = c/a: 0 without friction, 1 without coupling; grows with μ from near 0
    (μ/|β| = 0.2: 0.015) to near 1 (μ/|β| = 8: 1.0); the sign of β does not matter."""
    from contactpipe.analytic import spence_stick_ratio as lam
    assert lam(0.0, 0.5) == 0.0 and lam(0.3, 0.0) == 1.0 and lam(np.inf, 0.3) == 1.0
    values = [lam(m, -0.5) for m in (0.1, 0.15, 0.2, 0.2986, 0.4, 0.5, 1.0, 2.0, 4.0)]
    assert values == [0.015, 0.09, 0.22, 0.5, 0.7, 0.815, 0.97, 0.995, 1.0]
    assert lam(0.2986, 0.5) == lam(0.2986, -0.5)
    with pytest.raises(ValueError, match="mu = -0.1"):
        lam(-0.1, 0.5)
    with pytest.raises(ValueError, match="beta = 0.6"):
        lam(0.1, 0.6)


def test_spence_stick_ratio_converges():
    """The reference's λ at 50 and at 200 rings agree to 1/50 (one ring of the coarse
    one; measured at most 0.005 apart), 400 rings were measured the same to 1/200."""
    from contactpipe.analytic import spence_stick_ratio as lam
    for mu in (0.1, 0.2, 0.2986, 0.4, 0.5, 1.0):
        assert abs(lam(mu, 0.5, 50) - lam(mu, 0.5, 200)) <= 1 / 50 + 1e-12
