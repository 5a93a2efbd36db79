"""Tests of contactpipe.solver.influence: rectangle-cell influence coefficients of a half-space.

References checked: the Boussinesq and Cerruti point-load solutions (Johnson, Contact
Mechanics, 1985, §3.2-3.5) far from the cell and, near it, direct numerical quadrature of
those Green's functions over the cell; Love's (1929) closed form at the cell centre; the
reciprocal theorem; the symmetries of the kernels; paper eq. (8) for the pair.
"""
import warnings

import numpy as np
import pytest
from scipy.integrate import IntegrationWarning, dblquad

from contactpipe.exceptions import SceneError
from contactpipe.solver.influence import (
    COUPLING_KEYS,
    KEYS,
    body_kernels,
    cell_influence,
    offset_grid,
    pair_kernels,
)

E = 70e9     # [Pa]
NU = 0.3     # [1]
CELLS = [(1.0e-6, 1.0e-6), (1.0e-6, 2.0e-6), (3.0e-6, 1.0e-6)]   # (d1, d2) [m]


def point_load(key, x1, x2, force, young=E, nu=NU):
    """Surface displacement [m] along i from a point force [N] along j (docs/conventions.md)."""
    x1 = np.asarray(x1, dtype=float)
    x2 = np.asarray(x2, dtype=float)
    r = np.hypot(x1, x2)
    c = (1 + nu) * force / (2 * np.pi * young * r)
    cc = (1 - 2 * nu) * (1 + nu) * force / (2 * np.pi * young * r**2)
    if key == "33":
        return (1 - nu**2) * force / (np.pi * young * r)
    if key == "13":
        return -cc * x1
    if key == "23":
        return -cc * x2
    if key == "31":
        return cc * x1
    if key == "32":
        return cc * x2
    if key == "11":
        return c * (2 * (1 - nu) + 2 * nu * x1**2 / r**2)
    if key == "22":
        return c * (2 * (1 - nu) + 2 * nu * x2**2 / r**2)
    if key in ("12", "21"):
        return c * 2 * nu * x1 * x2 / r**2
    raise KeyError(key)


def scale(d1, d2, young=E, nu=NU):
    """Magnitude of the own-cell kernels [m/Pa], for absolute tolerances."""
    return (1 + nu) * max(d1, d2) / (np.pi * young)


# --------------------------------------------------------------------------- far field
@pytest.mark.parametrize("d1, d2", CELLS)
@pytest.mark.parametrize("key", KEYS)
def test_point_load_limit(key, d1, d2):
    """Boussinesq/Cerruti point load F = d1 d2 [N] at R = 20, 50, 200, 1000 cells
    (R in units of the longer cell side), 8 directions off the axes: relative error
    <= 1e-3 (the finite-cell error is O((d/R)^2): 3e-3 for K12 at 10 cells)."""
    h = max(d1, d2)
    theta = np.deg2rad([10, 30, 60, 80, 120, 200, 250, 315])
    for cells in (20, 50, 200, 1000):
        x1 = cells * h * np.cos(theta)
        x2 = cells * h * np.sin(theta)
        k = cell_influence(x1, x2, d1, d2, E, NU)[key]
        p = point_load(key, x1, x2, d1 * d2)
        err = np.max(np.abs(k / p - 1))
        assert err <= 1e-3, (f"K{key} vs Boussinesq/Cerruti point load at {cells} cells: "
                             f"relative error {err:.2e}")


@pytest.mark.parametrize("d1, d2", CELLS)
@pytest.mark.parametrize("key", KEYS)
def test_point_load_with_cell_size_correction(key, d1, d2):
    """At R = 10 cells the point load plus its O(d^2) cell-averaging term
    (d1^2/24 d^2/dx1^2 + d2^2/24 d^2/dx2^2, by finite differences) matches to 3e-5:
    the far-field error is exactly the expected finite-cell term."""
    h = max(d1, d2)
    theta = np.deg2rad([10, 30, 60, 80, 120, 200, 250, 315])
    x1 = 10 * h * np.cos(theta)
    x2 = 10 * h * np.sin(theta)
    f = d1 * d2
    g = point_load(key, x1, x2, f)
    s1, s2 = d1 / 4, d2 / 4
    g11 = (point_load(key, x1 + s1, x2, f) - 2 * g + point_load(key, x1 - s1, x2, f)) / s1**2
    g22 = (point_load(key, x1, x2 + s2, f) - 2 * g + point_load(key, x1, x2 - s2, f)) / s2**2
    expected = g + d1**2 / 24 * g11 + d2**2 / 24 * g22
    k = cell_influence(x1, x2, d1, d2, E, NU)[key]
    err = np.max(np.abs(k / expected - 1))
    assert err <= 3e-5, f"K{key} vs corrected point load at 10 cells: {err:.2e}"


# --------------------------------------------------------------------------- near field
def _green(key, nu=NU, young=E):
    """Point-load Green's function per unit force [m/N] as f(X, Y)."""
    return lambda x, y: float(point_load(key, x, y, 1.0, young, nu))


def _quadrature(key, x1, x2, d1, d2):
    """Integral of the Green's function over the cell, split at the field point so that
    the 1/r singularity sits on a corner of each sub-rectangle."""
    a, b = d1 / 2, d2 / 2
    xs = [-a] + ([x1] if -a < x1 < a else []) + [a]
    ys = [-b] + ([x2] if -b < x2 < b else []) + [b]
    g = _green(key)
    total = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("error", IntegrationWarning)
        for i in range(len(xs) - 1):
            for j in range(len(ys) - 1):
                value, _ = dblquad(lambda eta, xi: g(x1 - xi, x2 - eta),
                                   xs[i], xs[i + 1], ys[j], ys[j + 1],
                                   epsabs=0.0, epsrel=1e-10)
                total += value
    return total


# (x1/d1, x2/d2): own centre, inside the own cell, on an edge, on a corner, the adjacent
# cells (edge and diagonal neighbours), and two nearby cells off the lattice.
NEAR_POINTS = [(0.0, 0.0), (0.2, -0.3), (0.5, 0.1), (-0.5, 0.5), (1.0, 0.0), (1.0, 1.0),
               (0.0, -1.0), (1.7, 0.4), (-2.3, 1.1)]


@pytest.mark.parametrize("key", KEYS)
def test_near_field_vs_quadrature(key):
    """Closed form vs scipy dblquad of the point-load solution over a 1 x 2 um cell:
    relative 1e-6 (measured: <= 3e-14)."""
    d1, d2 = 1.0e-6, 2.0e-6
    for u1, u2 in NEAR_POINTS:
        x1, x2 = u1 * d1, u2 * d2
        k = float(cell_influence(x1, x2, d1, d2, E, NU)[key])
        q = _quadrature(key, x1, x2, d1, d2)
        tol = 1e-6 * abs(q) + 1e-12 * scale(d1, d2)
        assert abs(k - q) <= tol, (f"K{key} at ({u1}, {u2}) cells: closed form {k:.12e} vs "
                                   f"quadrature {q:.12e}")


@pytest.mark.parametrize("d1, d2", CELLS)
def test_own_cell_centre_love(d1, d2):
    """Love (1929): uniform pressure on [-a, a] x [-b, b] gives at the centre
    u3 = (1 - nu^2)/(pi E) * 2 [d1 ln((d2 + D)/d1) + d2 ln((d1 + D)/d2)], D = sqrt(d1^2 + d2^2);
    a square cell of side d: (1 - nu^2)/(pi E) * 4 d ln(1 + sqrt 2)."""
    diag = np.hypot(d1, d2)
    love = (1 - NU**2) / (np.pi * E) * 2 * (d1 * np.log((d2 + diag) / d1)
                                           + d2 * np.log((d1 + diag) / d2))
    k = cell_influence(0.0, 0.0, d1, d2, E, NU)
    assert float(k["33"]) == pytest.approx(love, rel=1e-14)
    if d1 == d2:
        square = (1 - NU**2) / (np.pi * E) * 4 * d1 * np.log(1 + np.sqrt(2))
        assert float(k["33"]) == pytest.approx(square, rel=1e-14)
    # Cerruti term at the centre: int X^2/r^3 = 2 d2 asinh(d1/d2)
    c = (1 + NU) / (np.pi * E)
    i_r = 2 * (d1 * np.arcsinh(d2 / d1) + d2 * np.arcsinh(d1 / d2))
    k11 = c * ((1 - NU) * i_r + NU * 2 * d2 * np.arcsinh(d1 / d2))
    assert float(k["11"]) == pytest.approx(k11, rel=1e-14)
    for key in ("12", "21", "13", "31", "23", "32"):
        assert float(k[key]) == 0.0


# --------------------------------------------------------------------------- symmetries
def _random_points(seed=0, n=400, d1=1e-6, d2=2e-6):
    rng = np.random.default_rng(seed)
    x1 = rng.uniform(-8, 8, n) * d1
    x2 = rng.uniform(-8, 8, n) * d2
    # add lattice points, edges and corners
    u = np.arange(-6, 7) * 0.5
    g1, g2 = np.meshgrid(u * d1, u * d2, indexing="ij")
    return np.concatenate([x1, g1.ravel()]), np.concatenate([x2, g2.ravel()])


@pytest.mark.parametrize("nu", [0.0, 0.25, NU, 0.45, 0.5])
def test_reciprocity(nu):
    """Reciprocal theorem: K_ij(x) = K_ji(-x); in particular K13 = -K31 pointwise."""
    d1, d2 = 1e-6, 2e-6
    x1, x2 = _random_points(1)
    k = cell_influence(x1, x2, d1, d2, E, nu)
    km = cell_influence(-x1, -x2, d1, d2, E, nu)
    atol = 1e-13 * scale(d1, d2, E, nu)
    for i in "123":
        for j in "123":
            np.testing.assert_allclose(k[i + j], km[j + i], rtol=1e-12, atol=atol,
                                       err_msg=f"reciprocity K{i}{j}(x) = K{j}{i}(-x)")
    np.testing.assert_array_equal(k["13"], -k["31"])
    np.testing.assert_array_equal(k["23"], -k["32"])
    np.testing.assert_array_equal(k["12"], k["21"])


PARITY = {"11": (1, 1), "22": (1, 1), "33": (1, 1), "12": (-1, -1), "21": (-1, -1),
          "13": (-1, 1), "31": (-1, 1), "23": (1, -1), "32": (1, -1)}


def test_parities():
    """K11, K22, K33 even in x1 and x2; K12 odd in both; K13, K31 odd in x1 and even in
    x2; K23, K32 even in x1 and odd in x2."""
    d1, d2 = 1e-6, 2e-6
    x1, x2 = _random_points(2)
    k = cell_influence(x1, x2, d1, d2, E, NU)
    k_m1 = cell_influence(-x1, x2, d1, d2, E, NU)
    k_m2 = cell_influence(x1, -x2, d1, d2, E, NU)
    atol = 1e-13 * scale(d1, d2)
    for key, (p1, p2) in PARITY.items():
        np.testing.assert_allclose(k_m1[key], p1 * k[key], rtol=1e-12, atol=atol,
                                   err_msg=f"K{key} parity in x1")
        np.testing.assert_allclose(k_m2[key], p2 * k[key], rtol=1e-12, atol=atol,
                                   err_msg=f"K{key} parity in x2")


def test_axis_swap():
    """Exchanging the in-plane axes: K11(x1, x2; d1, d2) = K22(x2, x1; d2, d1), and likewise
    12 <-> 21, 13 <-> 23, 31 <-> 32, 33 <-> 33."""
    d1, d2 = 1e-6, 2e-6
    x1, x2 = _random_points(3)
    k = cell_influence(x1, x2, d1, d2, E, NU)
    ks = cell_influence(x2, x1, d2, d1, E, NU)
    swap = {"11": "22", "22": "11", "12": "21", "21": "12", "13": "23", "23": "13",
            "31": "32", "32": "31", "33": "33"}
    for key, other in swap.items():
        np.testing.assert_allclose(k[key], ks[other], rtol=1e-12, atol=1e-13 * scale(d1, d2),
                                   err_msg=f"K{key} vs swapped K{other}")


def test_signs():
    """Pressure pulls the surface radially inwards (K13 < 0 ahead, x1 > 0); a shear along +1
    lifts the surface ahead of it (K31 > 0, x3 into the body); K33 and K11 positive."""
    x1 = np.array([0.6, 1.0, 3.0, 20.0]) * 1e-6
    k = cell_influence(x1, 0.2e-6, 1e-6, 1e-6, E, NU)
    assert np.all(k["13"] < 0) and np.all(k["31"] > 0)
    assert np.all(k["33"] > 0) and np.all(k["11"] > 0) and np.all(k["22"] > 0)


def test_incompressible_no_coupling():
    """nu = 0.5: the coupling kernels K13, K23, K31, K32 vanish exactly."""
    x1, x2 = _random_points(4)
    k = cell_influence(x1, x2, 1e-6, 2e-6, E, 0.5)
    for key in COUPLING_KEYS:
        assert np.all(k[key] == 0.0), key


def test_finite_on_edges_and_corners():
    """No NaN/inf at the own centre, on the cell edges and corners, right next to them,
    or far away; and continuity across the edge lines x1 = +-d1/2, x2 = +-d2/2."""
    d1, d2 = 1e-6, 2e-6
    u = np.arange(-8, 9) * 0.5
    eps = np.array([-1e-12, 0.0, 1e-12])
    g1 = (u[:, None] + eps[None, :]).ravel() * d1
    g2 = (u[:, None] + eps[None, :]).ravel() * d2
    x1, x2 = np.meshgrid(g1, g2, indexing="ij")
    for nu in (0.0, NU, 0.5):
        k = cell_influence(x1, x2, d1, d2, E, nu)
        for key, v in k.items():
            assert np.all(np.isfinite(v)), f"K{key} not finite (nu={nu})"
            # continuity: the three points around each lattice value agree
            v3 = v.reshape(len(u), 3, len(u), 3)
            spread = np.max(np.abs(v3 - v3[:, 1:2, :, 1:2]))
            assert spread <= 1e-9 * scale(d1, d2, E, max(nu, 0.1)), f"K{key} jumps at an edge"
    # extreme inputs
    k = cell_influence([0.0, 5e-324, 1e-310, 0.5e-6, 1e3], [0.0, 0.0, 1.0e-6, 1.0e-6, 1e3],
                       d1, d2, E, NU)
    assert all(np.all(np.isfinite(v)) for v in k.values())


def test_broadcasting_and_dtype():
    k = cell_influence(np.arange(3.0)[:, None] * 1e-6, np.arange(4.0)[None, :] * 1e-6,
                       1e-6, 1e-6, E, NU)
    assert set(k) == set(KEYS)
    for v in k.values():
        assert v.shape == (3, 4) and v.dtype == np.float64
    k0 = cell_influence(0.0, 0.0, 1e-6, 1e-6, E, NU)
    assert k0["33"].shape == ()


# --------------------------------------------------------------------------- grids
def test_offset_grid():
    n1, n2, d1, d2 = 4, 3, 1e-6, 2e-6
    x1, x2 = offset_grid(n1, n2, d1, d2)
    assert x1.shape == x2.shape == (2 * n1, 2 * n2)
    np.testing.assert_allclose(x1[:, 0], np.array([0, 1, 2, 3, -4, -3, -2, -1]) * d1)
    np.testing.assert_allclose(x2[0, :], np.array([0, 1, 2, -3, -2, -1]) * d2)
    assert np.all(np.isfinite(x1)) and np.all(np.isfinite(x2))
    assert np.all(x1 == x1[:, :1]) and np.all(x2 == x2[:1, :])


@pytest.mark.parametrize("n1, n2", [(5, 7), (1, 3), (8, 8)])
def test_body_kernels_layout(n1, n2):
    """Shape (2 n1, 2 n2), float64, row n1 and column n2 exactly 0, index (i, j) holds
    cell_influence at (i d1, j d2) and index (2 n1 - i, ...) the negative offset."""
    d1, d2 = 1e-6, 2e-6
    k = body_kernels(n1, n2, d1, d2, E, NU)
    assert set(k) == set(KEYS)
    for v in k.values():
        assert v.shape == (2 * n1, 2 * n2) and v.dtype == np.float64
        assert np.all(v[n1, :] == 0.0) and np.all(v[:, n2] == 0.0)
        assert np.all(np.isfinite(v))
    i = np.arange(n1)
    j = np.arange(n2)
    atol = 1e-14 * scale(d1, d2)
    for key, v in k.items():
        ref = cell_influence(i[:, None] * d1, j[None, :] * d2, d1, d2, E, NU)[key]
        np.testing.assert_allclose(v[:n1, :n2], ref, rtol=1e-12, atol=atol)
        if n1 > 1:
            ref = cell_influence(-i[1:, None] * d1, j[None, :] * d2, d1, d2, E, NU)[key]
            np.testing.assert_allclose(v[2 * n1 - i[1:], :n2], ref, rtol=1e-12, atol=atol)
        if n2 > 1:
            ref = cell_influence(i[:, None] * d1, -j[None, 1:] * d2, d1, d2, E, NU)[key]
            np.testing.assert_allclose(v[:n1, 2 * n2 - j[1:]], ref, rtol=1e-12, atol=atol)
        if n1 > 1 and n2 > 1:
            ref = cell_influence(-i[1:, None] * d1, -j[None, 1:] * d2, d1, d2, E, NU)[key]
            np.testing.assert_allclose(v[2 * n1 - i[1:]][:, 2 * n2 - j[1:]], ref,
                                       rtol=1e-12, atol=atol)
    # the same as cell_influence on offset_grid, zeroed row/column
    x1, x2 = offset_grid(n1, n2, d1, d2)
    full = cell_influence(x1, x2, d1, d2, E, NU)
    for key, v in k.items():
        f = full[key].copy()
        f[n1, :] = 0.0
        f[:, n2] = 0.0
        np.testing.assert_allclose(v, f, rtol=1e-12, atol=atol)


def test_body_kernels_dc_fft_convolution():
    """The wrap-around kernel gives, by FFT, the direct (non-periodic) superposition."""
    n1, n2, d1, d2 = 6, 5, 1e-6, 1.5e-6
    rng = np.random.default_rng(7)
    p = rng.uniform(0, 1, (n1, n2))
    k = body_kernels(n1, n2, d1, d2, E, NU)["31"]
    pad = np.zeros((2 * n1, 2 * n2))
    pad[:n1, :n2] = p
    u = np.fft.irfft2(np.fft.rfft2(pad) * np.fft.rfft2(k), s=pad.shape)[:n1, :n2]
    direct = np.zeros((n1, n2))
    for a in range(n1):
        for b in range(n2):
            direct += p[a, b] * cell_influence((np.arange(n1)[:, None] - a) * d1,
                                               (np.arange(n2)[None, :] - b) * d2,
                                               d1, d2, E, NU)["31"]
    np.testing.assert_allclose(u, direct, rtol=1e-10, atol=1e-12 * np.abs(direct).max())


# --------------------------------------------------------------------------- pair (eq. 8)
def test_pair_identical_materials_no_coupling():
    k = body_kernels(4, 4, 1e-6, 1e-6, E, NU)
    pair = pair_kernels(k, body_kernels(4, 4, 1e-6, 1e-6, E, NU))
    for key in KEYS:
        if key in COUPLING_KEYS:
            assert np.all(pair[key] == 0.0), f"identical materials: K{key} must vanish"
        else:
            np.testing.assert_array_equal(pair[key], 2 * k[key])


def test_pair_rigid_bodies():
    """A rigid body contributes nothing: rigid indenter -> + w2 K2 for every term; rigid
    half-space -> w1 K1 for in-plane/normal terms and -w1 K1 for the coupling terms."""
    k = body_kernels(3, 4, 1e-6, 2e-6, E, 0.25)
    on_rigid = pair_kernels(k, None, w1=0.7)
    by_rigid = pair_kernels(None, k, w2=0.4)
    for key in KEYS:
        np.testing.assert_array_equal(by_rigid[key], 0.4 * k[key])
        sign = -1.0 if key in COUPLING_KEYS else 1.0
        np.testing.assert_array_equal(on_rigid[key], sign * 0.7 * k[key])
        assert by_rigid[key] is not k[key] and on_rigid[key] is not k[key]
    with pytest.raises(SceneError, match="both bodies are rigid"):
        pair_kernels(None, None)


def test_pair_dissimilar_weights():
    k1 = body_kernels(3, 3, 1e-6, 1e-6, 200e9, 0.3)
    k2 = body_kernels(3, 3, 1e-6, 1e-6, 3e9, 0.4)
    pair = pair_kernels(k1, k2, w1=1.0, w2=2.5)
    for key in KEYS:
        if key in COUPLING_KEYS:
            expected = 2.5 * k2[key] - 1.0 * k1[key]
        else:
            expected = 1.0 * k1[key] + 2.5 * k2[key]
        np.testing.assert_array_equal(pair[key], expected)
    # the compliant body dominates: coupling has body 2's sign
    assert pair["31"][1, 0] > 0 and pair["13"][1, 0] < 0


def test_body_kernels_large_grid_finite():
    """n = 512 (a 1024 x 1024 offset grid): every entry finite, layout shape right.
    (Speed is reported by `contactpipe bench`, never asserted in tests.)"""
    k = body_kernels(512, 512, 1e-6, 1e-6, E, NU)
    assert all(v.shape == (1024, 1024) for v in k.values())
    assert all(np.all(np.isfinite(v)) for v in k.values())
