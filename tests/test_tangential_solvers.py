"""Unit tests of the uncoupled tangential solvers (contactpipe.solver.tangential).

The solvers only call four methods of their operator; here they get a dense matrix behind
those methods (:class:`DenseOperator`): either a random SPD matrix, or the elastic
influence matrix of two steel bodies on a 6 x 6 grid of 0.1 mm cells assembled directly
from :func:`contactpipe.solver.influence.cell_influence` (no FFT), with a Hertz-like
bound μp = 0.1 · 2 GPa · sqrt(1 − r²/a²), a = 0.27 mm (24 cells in contact).

Checks, each against something the solvers do not compute themselves:

* the optimality conditions, which are the contact laws (module doc of the solvers):
  Coulomb |q| ≤ μp; force balance Σq Δ = T; stick (|q| < μp): the slip increment
  Δs = Δω − (Aq + b) vanishes; slip (|q| = μp): Δs is parallel to q and q·Δs ≥ 0;
* the exact active-set solution (scalar form, 8 cells) and scipy's SLSQP (both forms);
* the disk projections as Euclidean projections (hypothesis).
"""
import numpy as np
import pytest
from helpers import box_qp_exact, spd_matrix
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize

from contactpipe.solver.cg import Constraints
from contactpipe.solver.influence import cell_influence
from contactpipe.solver.tangential import (
    disk_project,
    force_rows,
    project_disks_sum,
    solve_scalar,
    solve_vector,
)


class DenseOperator:
    """The operator interface of the tangential solvers on a dense (2N x 2N) SPD matrix
    ``K = [[K11, K12], [K21, K22]]`` for an n1 x n2 grid (N = n1 n2 cells), counting the
    applications."""

    def __init__(self, K, shape):
        self.K, self.shape = np.asarray(K, float), tuple(shape)
        self.n = int(np.prod(shape))
        self.K11 = self.K[:self.n, :self.n]
        self.calls = 0

    def tangential_scalar(self, q1):
        self.calls += 1
        return (self.K11 @ q1.ravel()).reshape(self.shape)

    def tangential_vector(self, q):
        self.calls += 1
        return (self.K @ q.reshape(-1)).reshape((2,) + self.shape)

    def self_influence(self, component="11"):
        return float(np.mean(np.diag(self.K11)))

    def tangential_norm(self, components=2):
        return float(np.linalg.eigvalsh(self.K11 if components == 1 else self.K).max())


N, D = 6, 1e-4                       # 6 x 6 cells of 0.1 mm
RADIUS = 0.45 * N * D                # contact radius [m]
AREA = D * D


def elastic_matrix(n=N, d=D, young=210e9, poisson=0.3):
    """Tangential block of two identical elastic half-spaces (relative displacement = twice
    one body's), assembled cell by cell from the closed-form cell influence [m/Pa]."""
    i1, i2 = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x1, x2 = i1.ravel() * d, i2.ravel() * d
    k = cell_influence(x1[:, None] - x1[None, :], x2[:, None] - x2[None, :], d, d, young,
                       poisson)
    return 2.0 * np.block([[k["11"], k["12"]], [k["21"], k["22"]]])


def grid_coordinates(n=N, d=D):
    x = (np.arange(n) - (n - 1) / 2) * d
    return np.meshgrid(x, x, indexing="ij")


def hertz_bound(n=N, d=D, mu_p0=0.1 * 2e9, a=RADIUS):
    X1, X2 = grid_coordinates(n, d)
    return mu_p0 * np.sqrt(np.clip(1.0 - (X1 ** 2 + X2 ** 2) / a ** 2, 0.0, None))


@pytest.fixture(scope="module")
def elastic():
    K = elastic_matrix()
    assert np.allclose(K, K.T, rtol=0, atol=1e-12 * np.abs(K).max())
    assert np.linalg.eigvalsh(K).min() > 0
    return K


def kkt_vector(K, b, rho, T, area, q, domega):
    """Violations of the vector problem's optimality conditions, each relative: Coulomb
    (|q| − ρ)/max ρ; force |Σq Δ − T| / (Σρ Δ); stick |Δs|/max|Aq + b|; slip: the
    component of Δs normal to q and −q̂·Δs (dissipation), / max|Aq + b|."""
    g = (K @ q.reshape(-1)).reshape(q.shape) + b
    s = np.asarray(domega)[:, None, None] - g                  # slip increment Δs
    mag = np.hypot(q[0], q[1])
    stick = (rho > 0) & (mag < rho * (1 - 1e-9))
    slip = (rho > 0) & ~stick
    gs = float(np.abs(g).max())
    qh = q[:, slip] / np.where(mag[slip] > 0, mag[slip], 1.0)
    return {
        "coulomb": max(0.0, float(np.max(mag - rho)) / float(rho.max())),
        "outside": float(np.abs(q[:, rho == 0]).max(initial=0.0)),
        "force": float(np.abs(q.sum(axis=(1, 2)) * area - T).max() / (rho.sum() * area)),
        "stick": float(np.abs(s[:, stick]).max(initial=0.0)) / gs,
        "parallel": float(np.abs(qh[0] * s[1, slip] - qh[1] * s[0, slip]).max(initial=0.0)) / gs,
        "dissipation": max(0.0, -float((qh * s[:, slip]).sum(axis=0).min(initial=0.0))) / gs,
    }


def slsqp_tangential(K, b, rho, target, vector):
    """Independent solution of min ½qᵀKq + bᵀq, |q| ≤ ρ (disks, or −ρ ≤ q1 ≤ ρ with
    q2 = 0), Σq = target, by scipy's SLSQP on the cells with ρ > 0, in units of max ρ."""
    n = rho.size
    cells = np.flatnonzero(rho.ravel() > 0)
    m = len(cells)
    idx = np.concatenate([cells, n + cells]) if vector else cells
    A = K[np.ix_(idx, idx)]
    unit_q, unit_a = float(rho.max()), float(np.abs(A).max())
    An = A / unit_a
    bn = np.asarray(b).reshape(-1)[idx] / (unit_q * unit_a)
    r = rho.ravel()[cells] / unit_q
    tgt = np.atleast_1d(np.asarray(target, float)) / unit_q
    if vector:
        ones = np.vstack([np.r_[np.ones(m), np.zeros(m)], np.r_[np.zeros(m), np.ones(m)]])
        cons = [{"type": "ineq", "fun": lambda x: r ** 2 - x[:m] ** 2 - x[m:] ** 2,
                 "jac": lambda x: np.hstack([np.diag(-2 * x[:m]), np.diag(-2 * x[m:])])},
                {"type": "eq", "fun": lambda x: ones @ x - tgt, "jac": lambda x: ones}]
        bounds, x0 = None, np.repeat(tgt / m, m)
    else:
        cons = [{"type": "eq", "fun": lambda x: np.array([x.sum() - tgt[0]]),
                 "jac": lambda x: np.ones((1, m))}]
        bounds, x0 = list(zip(-r, r, strict=True)), np.full(m, tgt[0] / m)
    res = minimize(lambda x: 0.5 * x @ An @ x + bn @ x, x0, jac=lambda x: An @ x + bn,
                   method="SLSQP", bounds=bounds, constraints=cons,
                   options={"ftol": 1e-14, "maxiter": 500})
    q = np.zeros(2 * n)
    q[idx] = res.x * unit_q
    return q.reshape((2,) + rho.shape)


# --------------------------------------------------------------------------- scalar form
@pytest.mark.parametrize("seed", range(6))
def test_solve_scalar_equals_the_exact_active_set_solution(seed):
    """Random SPD K11 on a 2 x 4 grid (8 cells, eigenvalues in [1, 50]), random b, bounds
    ρ in [0.2, 1] with one cell out of contact (ρ = 0), T within 80 % of ±Σρ Δ, Δ = 0.5:
    q1 within 1e-12 and Δω1 within 1e-12 of the enumerated solution (measured: rounding);
    q2 = 0, Δω2 = 0; Aq = K11 q1."""
    rng = np.random.default_rng(seed)
    K11 = spd_matrix(rng, 8)
    op = DenseOperator(np.block([[K11, np.zeros((8, 8))], [np.zeros((8, 8)), np.eye(8)]]),
                       (2, 4))
    rho = rng.uniform(0.2, 1.0, (2, 4))
    rho[1, 3] = 0.0
    b1 = rng.standard_normal((2, 4))
    area = 0.5
    T1 = float(rng.uniform(-0.8, 0.8) * rho.sum() * area)
    res = solve_scalar(op, b1, rho, T1, area, np.zeros((2, 4)), 1e-12, 200)
    x_ex, lam_ex = box_qp_exact(K11, b1.ravel(), -rho.ravel(), rho.ravel(), T1 / area)
    assert res.converged
    np.testing.assert_allclose(res.q[0].ravel(), x_ex, rtol=0, atol=1e-12)
    assert np.all(res.q[1] == 0) and res.domega[1] == 0 and np.all(res.Aq[1] == 0)
    np.testing.assert_allclose(res.Aq[0].ravel(), K11 @ x_ex, rtol=0,
                               atol=1e-12 * np.abs(K11).max())
    if lam_ex is not None:
        assert res.domega[0] == pytest.approx(lam_ex, rel=0, abs=1e-12 * (1 + abs(lam_ex)))


@pytest.mark.parametrize("frac", [0.3, 0.9, 0.999])
def test_solve_scalar_elastic_contact_laws_and_slsqp(elastic, frac):
    """Elastic 6 x 6 operator, b a random known displacement (0.1 µm), T1 = frac Σμp Δ
    (near gross sliding included): the contact laws hold (Coulomb exactly, force to 1e-12,
    stick and slip conditions to 1e-9 of max|Aq + b|; measured 1e-14 at most) and SLSQP
    finds the same q within 1e-6 μp0 (measured 4e-8 at most)."""
    rho = hertz_bound()
    b = np.random.default_rng(1).standard_normal((2, N, N)) * 1e-7 * (rho > 0)
    b[1] = 0.0
    T = np.array([frac * rho.sum() * AREA, 0.0])
    op = DenseOperator(elastic, (N, N))
    res = solve_scalar(op, b[0], rho, T[0], AREA, np.zeros((N, N)), 1e-12, 2000)
    assert res.converged
    K1 = elastic.copy()
    K1[:N * N, N * N:] = K1[N * N:, :N * N] = 0.0          # the scalar form has no K12
    v = kkt_vector(K1, b, rho, T, AREA, res.q, res.domega)
    assert v["coulomb"] == 0 and v["outside"] == 0 and v["force"] < 1e-12, v
    assert v["stick"] < 1e-9 and v["parallel"] < 1e-9 and v["dissipation"] < 1e-9, v
    ref = slsqp_tangential(elastic[:N * N, :N * N], b[0], rho, T[0] / AREA, vector=False)
    np.testing.assert_allclose(res.q, ref, rtol=0, atol=1e-6 * rho.max())


# --------------------------------------------------------------------------- vector form
@pytest.mark.parametrize("frac, angle", [(0.5, 0.0), (0.5, 0.7), (0.9, 0.7), (0.3, 2.5)])
def test_solve_vector_elastic_contact_laws_and_slsqp(elastic, frac, angle):
    """Elastic 6 x 6 operator (K12 ≠ 0), b a random known displacement (0.1 µm),
    T = frac Σμp Δ at ``angle`` [rad] from x1, tolerance 1e-10: the contact laws hold
    (Coulomb to rounding, no traction outside, force to 1e-12, stick and slip conditions
    to 1e-8 of max|Aq + b|; measured 6e-9 at most) and SLSQP finds the same q within
    1e-6 μp0 (measured 1e-8 at most)."""
    rho = hertz_bound()
    b = np.random.default_rng(0).standard_normal((2, N, N)) * 1e-7 * (rho > 0)
    T = frac * rho.sum() * AREA * np.array([np.cos(angle), np.sin(angle)])
    op = DenseOperator(elastic, (N, N))
    res = solve_vector(op, b, rho, T, AREA, np.zeros((2, N, N)), 1e-10, 5000)
    assert res.converged
    v = kkt_vector(elastic, b, rho, T, AREA, res.q, res.domega)
    assert v["coulomb"] < 1e-15 and v["outside"] == 0 and v["force"] < 1e-12, v
    assert v["stick"] < 1e-8 and v["parallel"] < 1e-8 and v["dissipation"] < 1e-8, v
    np.testing.assert_allclose(res.Aq, op.tangential_vector(res.q), rtol=0,
                               atol=1e-12 * np.abs(res.Aq).max())
    ref = slsqp_tangential(elastic, b, rho, T / AREA, vector=True)
    np.testing.assert_allclose(res.q, ref, rtol=0, atol=1e-6 * rho.max())


def test_solve_vector_without_cross_terms_is_the_scalar_form(elastic):
    """K12 = 0, b2 = 0, T2 = 0: q2 = 0 solves the vector problem, so both forms give the same
    q1 and Δω1 (within 1e-10 μp0 and 1e-10 of max|Aq + b|; measured 1e-15, 5e-16)."""
    K = elastic.copy()
    K[:N * N, N * N:] = K[N * N:, :N * N] = 0.0
    rho = hertz_bound()
    b = np.zeros((2, N, N))
    b[0] = np.random.default_rng(2).standard_normal((N, N)) * 1e-7 * (rho > 0)
    T = np.array([0.6 * rho.sum() * AREA, 0.0])
    op = DenseOperator(K, (N, N))
    vec = solve_vector(op, b, rho, T, AREA, np.zeros((2, N, N)), 1e-10, 5000)
    sca = solve_scalar(op, b[0], rho, T[0], AREA, np.zeros((N, N)), 1e-12, 2000)
    assert vec.converged and sca.converged
    np.testing.assert_allclose(vec.q, sca.q, rtol=0, atol=1e-10 * rho.max())
    g = np.abs(sca.Aq[0] + b[0]).max()
    np.testing.assert_allclose(vec.domega, sca.domega, rtol=0, atol=1e-10 * g)


@pytest.mark.parametrize("bound_scale", [0.0, 0.5])
def test_a_force_the_bounds_cannot_carry_has_a_finite_residual(elastic, bound_scale):
    """Elastic 6 x 6, |T| = C (the Hertz bound's capacity Σμp Δ) at 37°, on bounds
    scaled to carry 0 (an open contact) or C/2. Both forms stop not converged with the
    share of the force not carried, relative to the larger of Σμp and the force: the
    one-component form (T1 = 0.8 C) exactly (0.8 − 0.5)/0.8 = 0.375, or 1 with no bound;
    the vector form's worst row between 0.44 (a sum of |q| <= C/2 misses the (0.8, 0.6) C
    row pair by at least C/(2√2) in one component, over 0.8 C) and 1, exactly 1 with no
    bound. Was: residual 0.0 'above' the tolerance with no bound (and the coupling step
    divided by the zero capacity: 2.85e+299)."""
    rho = hertz_bound() * bound_scale
    cap = float(hertz_bound().sum()) * AREA
    T = cap * np.array([0.8, 0.6])
    op = DenseOperator(elastic, (N, N))
    b = np.zeros((2, N, N))
    s = solve_scalar(op, b[0], rho, T[0], AREA, np.zeros((N, N)), 1e-9, 400)
    v = solve_vector(op, b, rho, T, AREA, np.zeros((2, N, N)), 1e-9, 400)
    assert not s.converged and not v.converged
    if bound_scale == 0.0:
        assert s.residual == 1.0 and v.residual == 1.0
    else:
        assert s.residual == pytest.approx(0.375, rel=1e-9)
        assert 0.44 <= v.residual <= 1.0


def test_warm_starts_and_iteration_cap(elastic):
    """Elastic 6 x 6, T = 0.5 Σμp Δ at 37°. Scalar form from its own solution with A q0:
    one iteration, one operator application, q unchanged to 1e-13 μp0 (measured 4e-14). Vector
    form from its own solution: converged again at the same q within 1e-8 μp0 (its stopping test is
    the step size, so the restart is not a fixed point: measured 16-70 iterations to
    re-converge at tolerance 1e-10 and q moved by up to 2e-9 μp0). A cap of 2 iterations
    from zero reports converged=False for both forms."""
    rho = hertz_bound()
    b = np.random.default_rng(3).standard_normal((2, N, N)) * 1e-7 * (rho > 0)
    T = 0.5 * rho.sum() * AREA * np.array([0.8, 0.6])
    op = DenseOperator(elastic, (N, N))
    ref = solve_scalar(op, b[0], rho, T[0], AREA, np.zeros((N, N)), 1e-12, 2000)
    assert ref.converged
    op.calls = 0
    again = solve_scalar(op, b[0], rho, T[0], AREA, ref.q[0], 1e-12, 2000, Aq0=ref.Aq[0])
    assert again.converged and again.iterations == 1 and op.calls == 1
    np.testing.assert_allclose(again.q, ref.q, rtol=0, atol=1e-13 * rho.max())
    ref = solve_vector(op, b, rho, T, AREA, np.zeros((2, N, N)), 1e-10, 5000)
    assert ref.converged
    again = solve_vector(op, b, rho, T, AREA, ref.q, 1e-10, 5000, Aq0=ref.Aq)
    assert again.converged
    np.testing.assert_allclose(again.q, ref.q, rtol=0, atol=1e-8 * rho.max())
    assert not solve_vector(op, b, rho, T, AREA, np.zeros((2, N, N)), 1e-10, 2).converged
    assert not solve_scalar(op, b[0], rho, T[0], AREA, np.zeros((N, N)), 1e-12, 2).converged


@pytest.fixture(scope="module")
def full_slip(elastic):
    """Radial known displacement 3x the largest displacement μp can cause, T1 = 0.3 Σμp Δ:
    every cell of the 24 slips (measured), outwards, shifted along x1. Returns (ρ, b, T, the
    vector solution)."""
    rho = hertz_bound()
    X1, X2 = grid_coordinates()
    u_scale = float(np.abs(elastic @ np.concatenate([rho.ravel(), rho.ravel()])).max())
    b = -3.0 * u_scale * np.stack([X1, X2]) / RADIUS * (rho > 0)
    T = np.array([0.3 * rho.sum() * AREA, 0.0])
    # the CG stalls without stick cells; max_iter sets the budget of each CG try before the
    # projected-gradient fallback (5000 gives the same q in 2548 iterations, 400 in 248)
    res = solve_vector(DenseOperator(elastic, (N, N)), b, rho, T, AREA, np.zeros((2, N, N)),
                       1e-10, 400)
    return rho, b, T, res


def test_solve_vector_full_slip_traction(elastic, full_slip):
    """Every cell slips (no stick cell pins Δω): q still satisfies Coulomb, the force and
    SLSQP's solution within 1e-6 μp0 (measured 1.4e-7)."""
    rho, b, T, res = full_slip
    assert res.converged
    assert np.all(np.hypot(res.q[0], res.q[1])[rho > 0] >= rho[rho > 0] * (1 - 1e-9))
    v = kkt_vector(elastic, b, rho, T, AREA, res.q, res.domega)
    assert v["coulomb"] < 1e-15 and v["force"] < 1e-12, v
    ref = slsqp_tangential(elastic, b, rho, T / AREA, vector=True)
    np.testing.assert_allclose(res.q, ref, rtol=0, atol=1e-6 * rho.max())


def test_solve_vector_full_slip_multiplier(elastic, full_slip):
    """With every cell slipping, Δω is still the multiplier of the force constraint: the
    slip increments Δs = Δω − (Aq + b) must be parallel to q and dissipating. Reference:
    the Δω that best aligns them, by least squares over the cells (its misalignment:
    measured 4e-11 of max|Aq + b|)."""
    rho, b, T, res = full_slip
    g = (elastic @ res.q.reshape(-1)).reshape(res.q.shape) + b
    cells = rho > 0
    qh = res.q[:, cells] / np.hypot(res.q[0], res.q[1])[cells]
    # Δs × q̂ = 0  <=>  Δω1 q̂2 − Δω2 q̂1 = g1 q̂2 − g2 q̂1
    lam, *_ = np.linalg.lstsq(np.stack([qh[1], -qh[0]], axis=1),
                              g[0, cells] * qh[1] - g[1, cells] * qh[0], rcond=None)
    assert kkt_vector(elastic, b, rho, T, AREA, res.q, lam)["parallel"] < 1e-8
    v = kkt_vector(elastic, b, rho, T, AREA, res.q, res.domega)
    assert v["parallel"] < 1e-8 and v["dissipation"] < 1e-8, v
    np.testing.assert_allclose(res.domega, lam, rtol=0, atol=1e-8 * np.abs(lam).max())


@pytest.mark.parametrize("form, regime", [
    ("scalar", "partial slip"), ("vector", "partial slip"),
    ("scalar", "full slip"), ("vector", "full slip"),
])
def test_multiplier_follows_a_rigid_shift(elastic, form, regime):
    """Adding a constant c to the known displacement b of the contact cells is a rigid shift:
    it leaves q unchanged (1e-8 μp0) and adds c to Δω (1e-8 of max|Aq + b|), whatever the
    slip pattern. c = 0.3 of the largest displacement μp causes (2.6e-7 m). Partial slip:
    the random b of the contact-law tests, T = 0.5 Σμp Δ; full slip: an outward radial b
    three times that displacement with T = 0 (scalar: every cell at ±μp, the force balanced
    by symmetry) or T1 = 0.3 Σμp Δ (vector, every cell slips)."""
    rho = hertz_bound()
    cells = rho > 0
    X1, X2 = grid_coordinates()
    u_scale = float(np.abs(elastic @ np.concatenate([rho.ravel(), rho.ravel()])).max())
    if regime == "partial slip":
        b = np.random.default_rng(1).standard_normal((2, N, N)) * 1e-7 * cells
        frac = 0.5
    else:
        b = -3.0 * u_scale * np.stack([X1, X2]) / RADIUS * cells
        frac = 0.0 if form == "scalar" else 0.3
    budget = 5000 if regime == "partial slip" else 400     # see the full_slip fixture
    T = np.array([frac * rho.sum() * AREA, 0.0])
    c = 0.3 * u_scale * np.array([1.0, -0.5])
    op = DenseOperator(elastic, (N, N))
    if form == "scalar":
        solve = lambda bb: solve_scalar(op, bb[0], rho, T[0], AREA, np.zeros((N, N)), 1e-12, 2000)  # noqa: E731
        c[1] = 0.0
    else:
        solve = lambda bb: solve_vector(op, bb, rho, T, AREA, np.zeros((2, N, N)), 1e-10, budget)  # noqa: E731
    r0 = solve(b)
    r1 = solve(b + c[:, None, None] * cells)
    assert r0.converged and r1.converged
    np.testing.assert_allclose(r1.q, r0.q, rtol=0, atol=1e-8 * rho.max())
    g = float(np.abs(r0.Aq + b).max())
    np.testing.assert_allclose(r1.domega - r0.domega, c, rtol=0, atol=1e-8 * g)


# --------------------------------------------------------------------------- disk projections
_FLOATS = st.floats(-5.0, 5.0, allow_subnormal=False)


def _cells(n, values=_FLOATS):
    return st.lists(values, min_size=n, max_size=n).map(np.array)


@st.composite
def disk_sets(draw, max_n=10):
    """(y (2, 1, n), ρ (1, n), target (2,)) with |target| < Σρ; some ρ = 0."""
    n = draw(st.integers(1, max_n))
    y = np.stack([draw(_cells(n)), draw(_cells(n))])[:, None, :]
    values = st.sampled_from([0.0, 0.5, 1.0]) | st.floats(0.0, 2.0, allow_subnormal=False)
    rho = draw(_cells(n, values))[None, :]
    frac = draw(st.floats(0.0, 0.999))
    angle = draw(st.floats(0.0, 2 * np.pi))
    target = frac * rho.sum() * np.array([np.cos(angle), np.sin(angle)])
    return y, rho, target


@settings(max_examples=50)
@given(disk_sets())
def test_disk_project_is_the_cellwise_projection(data):
    """Per cell: |P| ≤ ρ (1 + 1e-15), P = y where |y| ≤ ρ, P = ρ y/|y| (radial) outside and
    flagged; idempotent; variational inequality ⟨y − P, z − P⟩ ≤ 1e-12 |y| ρ for z on the
    disk's rim at 8 angles."""
    y, rho, _ = data
    P, over = disk_project(y, rho)
    mag = np.hypot(y[0], y[1])
    pm = np.hypot(P[0], P[1])
    assert np.all(pm <= rho * (1 + 1e-15))
    np.testing.assert_array_equal(over, mag > rho)
    np.testing.assert_array_equal(P[:, ~over], y[:, ~over])
    np.testing.assert_allclose(P[:, over] * mag[over], y[:, over] * rho[over], rtol=1e-14,
                               atol=1e-300)
    np.testing.assert_allclose(disk_project(P, rho)[0], P, rtol=1e-15, atol=0)
    for phi in np.linspace(0, 2 * np.pi, 8, endpoint=False):
        z = rho * np.array([np.cos(phi), np.sin(phi)])[:, None, None]
        vi = ((y - P) * (z - P)).sum(axis=0)
        assert np.all(vi <= 1e-12 * (1 + mag) * (1 + rho))


RIM_CASE = (np.array([[[0.0, 1.0]], [[0.0, 1.0]]]), np.array([[0.5, 0.5]]), np.array([0.5, 0.0]))
def test_project_disks_sum_every_cell_on_the_rim():
    """The smallest case hypothesis found: the projection is finite, feasible and equals
    SLSQP's within 1e-8."""
    y, rho, target = RIM_CASE
    P = project_disks_sum(y, rho, target)
    assert np.all(np.isfinite(P))
    ref = slsqp_tangential(np.eye(4), -y, rho, target, vector=True)
    np.testing.assert_allclose(P, ref, rtol=0, atol=1e-8)


@settings(max_examples=100)
@given(disk_sets(), st.lists(st.floats(-1.0, 1.0), min_size=20, max_size=20),
       st.floats(0.0, 1.0))
@example(RIM_CASE, [0.0] * 20, 0.0)
def test_project_disks_sum_is_a_euclidean_projection(data, direction, step):
    """P = project_disks_sum(y, ρ, target): |P_i| ≤ ρ_i (1 + 1e-12), P = 0 where ρ = 0,
    |ΣP − target| ≤ 1e-12 (Σρ + |y|); idempotent within the same tolerance; variational
    inequality ⟨y − P, z − P⟩ ≤ |y − P| (1e-9 |z − P| + tol) for a feasible z built without
    the projection (the target shared in proportion to ρ, moved along a zero-sum direction
    by a fraction of the largest step the triangle inequality allows)."""
    y, rho, target = data
    n = rho.size
    P = project_disks_sum(y, rho, target)
    tol = 1e-12 * (rho.sum() + np.abs(y).sum() + 1.0)
    assert np.all(np.hypot(P[0], P[1]) <= rho * (1 + 1e-12))
    assert np.all(P[:, rho == 0] == 0)
    np.testing.assert_allclose(P.sum(axis=(1, 2)), target, rtol=0, atol=tol)
    np.testing.assert_allclose(project_disks_sum(P, rho, target), P, rtol=0, atol=tol)
    cells = rho > 0
    z = np.zeros_like(y)
    z[:, cells] = target[:, None] * rho[cells] / rho.sum()
    d = np.zeros_like(y)
    d[:, cells] = np.asarray(direction[:2 * n]).reshape(2, n)[:, cells.ravel()]
    if cells.any():
        d[:, cells] -= d[:, cells].mean(axis=1, keepdims=True)
    dm = np.hypot(d[0], d[1])
    room = np.where(dm > 0, (rho - np.hypot(z[0], z[1])) / np.where(dm > 0, dm, 1.0), np.inf)
    s = float(room.min()) if np.isfinite(room.min()) else 0.0
    z = z + step * s * d
    assert np.all(np.hypot(z[0], z[1]) <= rho * (1 + 1e-12))
    yp, zp = (y - P).ravel(), (z - P).ravel()
    assert float(yp @ zp) <= np.linalg.norm(yp) * (1e-9 * np.linalg.norm(zp) + tol)


@pytest.mark.parametrize("seed", range(3))
def test_project_disks_sum_equals_slsqp(seed):
    """The projection is the minimiser of ½|x − y|² over the disks with the sum: SLSQP on
    the same problem (10 cells, one with ρ = 0) agrees within 1e-6 max ρ (measured 1e-9)."""
    rng = np.random.default_rng(seed)
    y = 2.0 * rng.standard_normal((2, 2, 5))
    rho = rng.uniform(0.2, 1.0, (2, 5))
    rho[0, 0] = 0.0
    target = 0.6 * rho.sum() * np.array([np.cos(seed), np.sin(seed)])
    P = project_disks_sum(y, rho, target)
    ref = slsqp_tangential(np.eye(20), -y, rho, target, vector=True)
    np.testing.assert_allclose(P, ref, rtol=0, atol=1e-6 * rho.max())


# --------------------------------------------------------------------------- rows, control
@pytest.mark.parametrize("form", ["scalar", "vector"])
def test_a_force_beyond_the_bounds_is_not_converged(elastic, form):
    """|T| = 1.2 Σμp Δ (elastic 6 x 6): converged is False, q finite and within the
    bounds (once the scalar form reported convergence carrying only Σμp Δ and the vector
    form returned NaN)."""
    rho = hertz_bound()
    b = np.random.default_rng(4).standard_normal((2, N, N)) * 1e-7 * (rho > 0)
    T = np.array([1.2 * rho.sum() * AREA, 0.0])
    op = DenseOperator(elastic, (N, N))
    if form == "scalar":
        res = solve_scalar(op, b[0], rho, T[0], AREA, np.zeros((N, N)), 1e-10, 400)
    else:
        res = solve_vector(op, b, rho, T, AREA, np.zeros((2, N, N)), 1e-10, 400)
    assert not res.converged
    assert np.all(np.isfinite(res.q)) and np.all(np.hypot(*res.q) <= rho * (1 + 1e-12))


def twist_rows(T, M3, with_force=True):
    """The force rows (T [N]) and the torque row Σ(q2 x1 − q1 x2) Δ = M3 [N m] on the
    6 x 6 grid, the arms normalised by the half side L."""
    X1, X2 = grid_coordinates()
    L = float(np.abs(X1).max())
    rows = [np.stack([-X2, X1]) / L]
    targets = [M3 / AREA / L]
    if with_force:
        force = force_rows((N, N), T, AREA)
        rows = list(force.rows) + rows
        targets = list(force.target) + targets
    return Constraints(np.array(rows), targets), L


@pytest.mark.parametrize("M_frac", [0.0, 0.4, -0.7])
def test_solve_vector_with_a_torque_row(elastic, M_frac):
    """T = 0.3 Σμp Δ along 0.7 rad with M3 = M_frac Σ μp r Δ (r from the centre): the
    rows hold (1e-12), Coulomb to rounding, and SLSQP with the same three equality rows
    finds the same q within 1e-6 μp0 (measured 2e-9 at most); the stick cells' slip
    increment Δs = Δω + Δφ3 (−x2, x1) − (Aq + b) vanishes (1e-8 of max|Aq + b|)."""
    rho = hertz_bound()
    X1, X2 = grid_coordinates()
    b = np.random.default_rng(5).standard_normal((2, N, N)) * 1e-7 * (rho > 0)
    T = 0.3 * rho.sum() * AREA * np.array([np.cos(0.7), np.sin(0.7)])
    M3 = M_frac * float(np.sum(rho * np.hypot(X1, X2))) * AREA
    C, L = twist_rows(T, M3)
    op = DenseOperator(elastic, (N, N))
    res = solve_vector(op, b, rho, None, AREA, np.zeros((2, N, N)), 1e-11, 5000, rows=C)
    assert res.converged and res.multipliers.shape == (3,)
    assert np.abs(C.residual(res.q)).max() <= 1e-12 * C.rows.shape[-1] ** 2 * rho.max()
    assert np.all(np.hypot(*res.q) <= rho * (1 + 1e-15))
    g = (elastic @ res.q.reshape(-1)).reshape(res.q.shape) + b
    slip = C.field(res.multipliers) - g
    stick = (rho > 0) & (np.hypot(*res.q) < rho * (1 - 1e-6))
    assert stick.any()
    assert np.abs(slip[:, stick]).max() <= 1e-8 * np.abs(g).max()
    cells = np.flatnonzero(rho.ravel() > 0)
    m = cells.size
    idx = np.concatenate([cells, N * N + cells])
    unit_q = float(rho.max())
    unit_a = float(np.abs(elastic).max())
    K = elastic[np.ix_(idx, idx)] / unit_a
    bn = b.reshape(-1)[idx] / (unit_q * unit_a)
    r = rho.ravel()[cells] / unit_q
    Cm = C.rows.reshape(3, -1)[:, idx]
    ref = minimize(lambda x: 0.5 * x @ K @ x + bn @ x, np.zeros(2 * m),
                   jac=lambda x: K @ x + bn, method="SLSQP",
                   constraints=[{"type": "eq", "fun": lambda x: Cm @ x - C.target / unit_q,
                                 "jac": lambda x: Cm},
                                {"type": "ineq", "fun": lambda x: r ** 2 - x[:m] ** 2 - x[m:] ** 2,
                                 "jac": lambda x: np.hstack([np.diag(-2 * x[:m]),
                                                             np.diag(-2 * x[m:])])}],
                   options={"ftol": 1e-15, "maxiter": 1000})
    q = np.zeros(2 * N * N)
    q[idx] = ref.x * unit_q
    np.testing.assert_allclose(res.q, q.reshape(res.q.shape), rtol=0, atol=1e-6 * rho.max())


def test_displacement_control_slides_as_a_whole(elastic):
    """No row (the rigid motion known and in b), a uniform known slip of 3 times the
    largest displacement μp causes: every contact cell slips, q = μp along the slip
    increment Δs = −(Aq + b) (parallel to 1e-9 of max|Aq + b|, dissipating), and the
    scalar form with the same b (q2 = 0) sits at +-μp with the sign of its slip."""
    rho = hertz_bound()
    u_scale = float(np.abs(elastic @ np.concatenate([rho.ravel(), rho.ravel()])).max())
    b = -3.0 * u_scale * np.stack([np.full((N, N), 0.8), np.full((N, N), 0.6)]) * (rho > 0)
    op = DenseOperator(elastic, (N, N))
    res = solve_vector(op, b, rho, None, AREA, np.zeros((2, N, N)), 1e-11, 2000,
                       rows=Constraints.none((2, N, N)))
    assert res.converged
    v = kkt_vector(elastic, b, rho, np.zeros(2), AREA, res.q, np.zeros(2))
    assert np.all(np.hypot(*res.q)[rho > 0] >= rho[rho > 0] * (1 - 1e-9))
    assert v["parallel"] < 1e-9 and v["dissipation"] == 0 and v["coulomb"] < 1e-15
    sca = solve_scalar(op, b[0], rho, None, AREA, np.zeros((N, N)), 1e-12, 2000)
    assert sca.converged
    g = sca.Aq[0] + b[0]
    np.testing.assert_array_equal(sca.q[0][rho > 0], rho[rho > 0] * np.sign(-g[rho > 0]))


@pytest.mark.parametrize("seed", range(4))
def test_disk_cg_equals_the_exact_active_set_solution(seed):
    """disk_cg through its narrow interface (operator, start, bounds, rows, options,
    ledger) on a problem whose disks act as boxes: A = diag(K11, I) on a 2 x 4 grid,
    b2 = 0 and T2 = 0, so q2 = 0 and |q1| ≤ ρ is the scalar problem, solved exactly by
    enumerating the active sets (1-5 of the 8 cells on their bound). With the default
    ledger: q1 within 1e-12 of it and q2 = 0 to 1e-12 (measured 1.3e-15 and 0 in 7-11
    iterations), and the result's Ax is A times its own x to 1e-12; so it is with every
    correction deferred (defer = 1e300: a search blind to its projections, whose point
    is not compared) and folded in at the end (``exact``); where ``follow`` moves the
    solve on, x is the move's point, ``iterate`` the solution, ``move`` the decision, and
    Ax the point's product."""
    from contactpipe.solver.blocks import DirectOperator
    from contactpipe.solver.cg import Start
    from contactpipe.solver.disk_cg import DiskOptions, disk_cg, disk_start
    from contactpipe.solver.ledger import Ledger, Move
    rng = np.random.default_rng(40 + seed)
    K11 = spd_matrix(rng, 8)
    dense = np.block([[K11, np.zeros((8, 8))], [np.zeros((8, 8)), np.eye(8)]])
    A = DirectOperator(lambda x: (dense @ x.ravel()).reshape(x.shape))
    rho = rng.uniform(0.2, 1.0, (2, 4))
    b = np.stack([rng.standard_normal((2, 4)), np.zeros((2, 4))])
    area = 0.5
    T1 = float(rng.uniform(-0.8, 0.8) * rho.sum() * area)
    con = force_rows((2, 4), [T1, 0.0], area)
    q = disk_start(np.zeros((2, 2, 4)), rho, con, 1e-13)
    x_ex, _ = box_qp_exact(K11, b[0].ravel(), -rho.ravel(), rho.ravel(), T1 / area)
    opt = DiskOptions(1e-13, 2000, a_self=float(np.diag(K11).mean()), scale=float(rho.sum()))
    res = disk_cg(A, b, Start(q, A(q)), rho, con, opt)
    assert res.converged and res.move is None
    np.testing.assert_allclose(res.x[0].ravel(), x_ex, rtol=0, atol=1e-12)
    assert np.abs(res.x[1]).max() <= 1e-12
    np.testing.assert_allclose(res.Ax, A(res.x), rtol=0, atol=1e-12 * np.abs(res.Ax).max())
    blind = disk_cg(A, b, Start(q, A(q)), rho, con, opt, Ledger(update=True, defer=1e300))
    np.testing.assert_allclose(blind.Ax, A(blind.x), rtol=0,
                               atol=1e-12 * np.abs(blind.Ax).max())
    shifted = 0.5 * res.x                              # a point the caller moves on to
    moved = disk_cg(A, b, Start(q, A(q)), rho, con, opt,
                    Ledger(update=True, defer=0.1, follow=lambda x: Move(shifted, "next")))
    assert moved.converged and moved.move.verdict == "next" and moved.x is shifted
    np.testing.assert_allclose(moved.iterate[0].ravel(), x_ex, rtol=0, atol=1e-12)
    np.testing.assert_allclose(moved.Ax, A(shifted), rtol=0,
                               atol=1e-12 * np.abs(moved.Ax).max())
