"""The vector CG's filter (ContactOperator.tangential_preconditioner) against its definition.

M(v, d) filters v by σ/(λ + d σ), σ the symbol of (−Δ)^½ and λ the tangential block's
finest-mode stiffness: an approximation of (K_t + d I)⁻¹. Checked here: it is symmetric
positive definite (what preconditioned CG needs), its model λ/σ matches the padded K11,
K22 spectra on the grid's own frequencies, and it tends to I/d for a large shift. That it
speeds the vector form up without changing its answer is checked on the coupled instants
(test_coupling.test_preconditioned_vector_passes_reach_the_diagonally_scaled_instants).
Steel on aluminium, 32 x 24 cells of 62.5 x 83.3 µm (rectangular).
"""
import numpy as np
import pytest

from contactpipe.materials import Body
from contactpipe.solver.disk_cg import direction, slip_axes
from contactpipe.solver.operator import ContactOperator, body_spectra, convolver
from contactpipe.solver.options import TUNING

N1, N2 = 32, 24
D1, D2 = 2e-3 / N1, 2e-3 / N2
X1, X2 = np.array([1.0, 0.0]), np.array([0.0, 1.0])


@pytest.fixture(scope="module")
def op():
    s1 = body_spectra(Body("elastic", 210e9, 0.3), N1, N2, D1, D2)
    s2 = body_spectra(Body("elastic", 70e9, 0.33), N1, N2, D1, D2)
    return ContactOperator(s1, s2, 1.0, 1.0, convolver(N1, N2))


@pytest.mark.parametrize("shift", [0.0, 1.0, 10.0])
def test_symmetric_positive_definite(op, shift):
    """⟨u, M v⟩ = ⟨M u, v⟩ to 1e-12 and ⟨v, M v⟩ > 0, for two stacked fields, with the
    shift d = 0, 1 and 10 self-influences."""
    M = op.tangential_preconditioner()
    d = shift * op.self_influence("11")
    rng = np.random.default_rng(4)
    u, v = rng.standard_normal((2, 2, N1, N2))
    uv, vu = float(np.sum(u * M(v, d))), float(np.sum(M(u, d) * v))
    assert uv == pytest.approx(vu, rel=1e-12)
    for w in (u, v, np.ones((2, N1, N2))):
        assert float(np.sum(w * M(w, d))) > 0.0


def test_model_matches_the_tangential_spectra(op):
    """λ/σ against the mean of the padded K11 and K22 spectra at the unpadded grid's
    frequencies (every other padded one): within 25 % over 80 % of them, median within
    10 % (measured on these rectangular cells 0.98-1.19 between the 10th and 90th
    percentiles; 0.93-1.12, median 1.00, on square cells; the zero mode, where σ is set to
    its smallest other value, left out)."""
    conv = op.conv
    sigma, lam = op._root_laplacian(), op.corner("11")
    k = 0.5 * (np.real(op.k["11"]) + np.real(op.k["22"]))[::2, ::2] * conv.m1 * conv.m2
    ratio = (k * sigma / lam).ravel()[1:]
    lo, mid, hi = np.percentile(ratio, [10, 50, 90])
    assert 0.75 < lo and hi < 1.25 and abs(mid - 1.0) < 0.1


def test_large_shift_tends_to_the_diagonal(op):
    """M(v, d) → v/d as d grows: within 1e-5 of v/d for d = 1e6 λ/σ_min."""
    M = op.tangential_preconditioner()
    sigma, lam = op._root_laplacian(), op.corner("11")
    d = 1e6 * lam / float(sigma.min())
    v = np.random.default_rng(5).standard_normal((2, N1, N2))
    np.testing.assert_allclose(M(v, d) * d, v, rtol=0, atol=1e-5 * np.abs(v).max())


def test_one_shift_per_field(op):
    """M(v, (d1, d2)) filters each stacked field by its own shift: equal, to 1e-14 of the
    largest value, to the fields filtered one at a time."""
    M = op.tangential_preconditioner()
    a = op.self_influence("11")
    v = np.random.default_rng(6).standard_normal((2, N1, N2))
    both = M(v, np.array([0.0, 3.0 * a]))
    one = np.stack([M(v[0], 0.0), M(v[1], 3.0 * a)])
    np.testing.assert_allclose(both, one, rtol=0, atol=1e-14 * np.abs(one).max())


def _unit(angle):
    return np.stack([np.cos(angle), np.sin(angle)])


@pytest.mark.parametrize("degrees", [0.0, 30.0, 90.0])
def test_slip_axes_of_one_slip_direction(degrees):
    """Cells slipping along ±(cos θ, sin θ) turn across it: the axis carrying the whole
    share (to 1e-12) is the tangent (−sin θ, cos θ), the other carries none."""
    rng = np.random.default_rng(7)
    sign = np.where(rng.random((N1, N2)) < 0.5, -1.0, 1.0)
    qhat = sign * _unit(np.radians(degrees) * np.ones((N1, N2)))
    turning = rng.random((N1, N2)) < 0.6
    axes, share = slip_axes(qhat, turning)
    np.testing.assert_allclose(axes @ axes.T, np.eye(2), atol=1e-12)
    big = int(np.argmax(share))
    assert share[big] == pytest.approx(1.0, abs=1e-12)
    assert share[1 - big] == pytest.approx(0.0, abs=1e-12)
    tangent = _unit(np.radians(degrees + 90.0))
    assert abs(float(axes[big] @ tangent)) == pytest.approx(1.0, abs=1e-12)


def test_slip_axes_of_spread_directions():
    """Directions spread evenly round the circle (a rotating load) share the two axes
    equally: (½, ½) to 1e-12."""
    angle = np.linspace(0.0, 2.0 * np.pi, N1 * N2, endpoint=False).reshape(N1, N2)
    _, share = slip_axes(_unit(angle), np.ones((N1, N2), dtype=bool))
    np.testing.assert_allclose(share, [0.5, 0.5], atol=1e-12)


def _cells(seed):
    """A working set like a fretting step's (stick core, slip annulus turning along ±x1
    with a small spread) and positive curvatures on the turning cells [m/Pa]."""
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(N1) - N1 / 2, np.arange(N2) - N2 / 2, indexing="ij")
    r = np.hypot(i / N1, j / N2)
    free, turning = r < 0.2, (r >= 0.2) & (r < 0.45)
    sign = np.where(j >= 0, 1.0, -1.0)
    qhat = np.where(turning, sign * _unit(0.2 * rng.standard_normal((N1, N2))), 0.0)
    curv = np.where(turning, rng.uniform(0.5, 20.0, (N1, N2)), 0.0)
    return free, turning, qhat, curv


def _along_x1(turning):
    """Slip directions ±x1 on the turning cells (a fretting load along x1)."""
    return np.where(turning, np.stack([np.where(np.arange(N2) >= N2 / 2, 1.0, -1.0)
                                       * np.ones((N1, N2)), np.zeros((N1, N2))]), 0.0)


def _x1_direction(op, curvature):
    """(M, a, z, g, curv, free, turning, d̄_2): the direction of a random residual on
    _cells(8) slipping along ±x1, the curvature ``curvature`` x its draw x a."""
    M = op.tangential_preconditioner()
    a = op.self_influence("11")
    free, turning, _, curv = _cells(8)
    qhat = _along_x1(turning)
    curv = curvature * curv * a
    g = np.random.default_rng(9).standard_normal((2, N1, N2))
    g[0] = np.where(turning, 0.0, g[0])                 # tangential on turning cells
    z = direction(M, g, curv, qhat, a, free, turning)
    d2 = TUNING.curvature_shift * float(np.median(curv[turning]))
    return M, a, z, g, curv, free, turning, d2


def test_direction_is_the_filter_shifted_along_the_tangents(op):
    """The vector CG's preconditioner below the band gate: with the turning cells' axes
    (x1, x2) and all the tangents' share on x2, z = S_c M(S_c g_c, d̄_c) per component,
    d̄_1 = 0, d̄_2 = Tuning.curvature_shift x the median curvature (here 0.3 a), cut back to the
    tangents, each component's filter modelled along its own axis: to 1e-12 of the
    largest value, against the formula written out."""
    M, a, z, g, curv, free, turning, d2 = _x1_direction(op, 0.1)
    assert 0.0 < d2 < TUNING.band_gate * a
    act = free | turning
    S1, S2 = np.sqrt(a / (a + curv)) * act, np.sqrt((a + d2) / (a + curv)) * act
    expect = np.stack([S1 * M(S1 * g[0], 0.0, axis=X1), S2 * M(S2 * g[1], d2, axis=X2)])
    expect[0] = np.where(turning, 0.0, expect[0])
    np.testing.assert_allclose(z, expect, rtol=0, atol=1e-12 * np.abs(expect).max())


def test_direction_in_two_bands_above_the_gate(op):
    """Above the gate (d̄_2 about 3 a) the tangents' component is filtered in two bands,
    each scaled by the cells' diagonal at its stiffness: z_2 = H M_high(H g_2, d̄_2) +
    L M_low(L g_2, d̄_2), H = √(K̂_f/(K̂_f + d_i)), L = √(k/(k + d_i)), k = Tuning.low_band x d̄_2,
    both 1 on free cells; x1 as below the gate: to 1e-12 of the largest value."""
    M, a, z, g, curv, free, turning, d2 = _x1_direction(op, 1.0)
    assert d2 > TUNING.band_gate * a
    act = free | turning
    S1 = np.sqrt(a / (a + curv)) * act
    H = np.sqrt(np.where(turning, M.finest / (M.finest + curv), act))
    k = TUNING.low_band * d2
    L = np.sqrt(np.where(turning, k / (k + curv), act))
    expect = np.stack([S1 * M(S1 * g[0], 0.0, axis=X1),
                       H * M(H * g[1], d2, band="high", axis=X2)
                       + L * M(L * g[1], d2, band="low", axis=X2)])
    expect[0] = np.where(turning, 0.0, expect[0])
    np.testing.assert_allclose(z, expect, rtol=0, atol=1e-12 * np.abs(expect).max())


@pytest.mark.parametrize("axis", [None, "x1", "x2"])
@pytest.mark.parametrize("shift", [0.5, 3.0, 30.0])
def test_bands_sum_to_the_unshifted_filter(op, shift, axis):
    """M_high(v, d) + M_low(v, d) = M(v, 0) to 1e-12 of its largest value, and each band
    is positive semi-definite (⟨v, M_band v⟩ ≥ 0), for d = 0.5, 3 and 30 self-influences;
    isotropic and modelled along x1 or x2 (on these cells the model along an axis is
    nowhere below its finest-mode value, so the low band is not clipped)."""
    M = op.tangential_preconditioner()
    d = shift * op.self_influence("11")
    e = {None: None, "x1": X1, "x2": X2}[axis]
    v = np.random.default_rng(12).standard_normal((N1, N2))
    high, low = M(v, d, band="high", axis=e), M(v, d, band="low", axis=e)
    plain = M(v, 0.0, axis=e)
    np.testing.assert_allclose(high + low, plain, rtol=0, atol=1e-12 * np.abs(plain).max())
    assert float(np.sum(v * high)) > 0.0 and float(np.sum(v * low)) >= 0.0
    with pytest.raises(ValueError, match="band"):
        M(v, d, band="middle")


@pytest.mark.parametrize("curvature", [0.1, 1.0])
def test_direction_is_symmetric_positive_semidefinite(op, curvature):
    """On fields tangential on the turning cells and zero off the working set, the
    direction is a symmetric positive semi-definite map (what preconditioned CG needs):
    ⟨u, P v⟩ = ⟨P u, v⟩ to 1e-12, ⟨v, P v⟩ ≥ 0; in one band and in two (curvature 0.05-2
    and 0.5-20 self-influences)."""
    M = op.tangential_preconditioner()
    a = op.self_influence("11")
    free, turning, qhat, curv = _cells(10)
    curv = curvature * curv * a
    act = free | turning
    rng = np.random.default_rng(11)

    def tangential(v):
        along = qhat[0] * v[0] + qhat[1] * v[1]
        return np.where(turning, v - along * qhat, v) * act

    u, v = (tangential(rng.standard_normal((2, N1, N2))) for _ in range(2))
    Pu, Pv = (direction(M, w, curv, qhat, a, free, turning) for w in (u, v))
    assert float(np.sum(u * Pv)) == pytest.approx(float(np.sum(Pu * v)), rel=1e-12)
    assert float(np.sum(v * Pv)) > 0.0 and float(np.sum(u * Pu)) > 0.0


def test_a_cell_turning_too_far_has_its_own_step_shortened():
    """On circles of radius 1 (4 x 4 cells, A = I, no rows): a turning cell whose tangent
    step would be 2 (four times SPIN) takes a quarter of it and ends on its circle turned
    by atan(SPIN); a turning cell stepping 0.1 and the stick cells take the whole step
    (turned by atan(0.1), moved by τ t). No cell over SPIN: no shortening (None)."""
    from contactpipe.solver import disk_cg
    from contactpipe.solver.cg import Constraints
    n = 4
    rho = np.ones((n, n))
    turning = np.zeros((n, n), dtype=bool)
    turning[0, :2] = True
    stick = ~turning
    x = np.zeros((2, n, n))
    x[0, turning] = 1.0                                  # on the circle at angle 0
    t = np.full((2, n, n), 0.01)
    t[:, turning] = 0.0
    t[1, 0, 0], t[1, 0, 1] = -2.0, -0.1                  # tangent steps −τ t along +x2
    assert disk_cg.shortened(t, 0.1, rho, turning) is None
    short = disk_cg.shortened(t, 1.0, rho, turning)
    np.testing.assert_allclose(short[0, :2], [TUNING.spin / 2.0, 1.0], rtol=1e-14)
    assert np.all(short[stick] == 1.0)
    x_new, d, err, norm = disk_cg._step(x, 1.0, t, rho, Constraints.none((2, n, n)),
                                        (rho > 0, stick, turning), None, 1.0, short)
    angle = np.arctan2(x_new[1], x_new[0])
    assert angle[0, 0] == pytest.approx(np.arctan(TUNING.spin), rel=1e-12)
    assert angle[0, 1] == pytest.approx(np.arctan(0.1), rel=1e-12)
    np.testing.assert_allclose(np.hypot(*x_new[:, turning]), 1.0, rtol=1e-12)
    np.testing.assert_allclose(x_new[:, stick], -0.01, rtol=1e-12)
    # the correction is what the projection added to the plain step x − τ t
    np.testing.assert_allclose(d, x_new - (x - t), rtol=0, atol=1e-15)
    assert norm == 1.0                                   # the sizes over the given scale
    assert err == pytest.approx(np.abs(x_new - x).sum() / norm, rel=1e-14)
