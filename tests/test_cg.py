"""Unit tests of the bound- and force-constrained solvers (contactpipe.solver.cg).

Small dense problems  min ½ xᵀAx + bᵀx  s.t.  lo ≤ x ≤ hi,  Σx = target  with a random
symmetric positive definite A (eigenvalues spread over [1, 50]) applied as ``A @ x``. The
reference is independent of the solvers: the exact active-set enumeration of
:func:`helpers.box_qp_exact` for n ≤ 7, the optimality (KKT) conditions checked directly
and scipy's SLSQP for n = 40. The Euclidean projection ``project_box_sum`` is checked as a
projection (exact QP with A = I, idempotence, feasibility, the variational inequality,
non-expansiveness), partly by hypothesis.
"""
import numpy as np
import pytest
from helpers import box_kkt_violation, box_qp_exact, spd_matrix
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize

from contactpipe.solver.cg import (
    BoxOptions,
    ComponentSums,
    Constraints,
    Start,
    box_cg,
    fista,
    project_box_sum,
    project_rows,
)
from contactpipe.solver.ledger import Ledger


class Counted:
    """``x -> A x`` counting its calls (one call = one FFT pair in the real operator)."""

    def __init__(self, A):
        self.A, self.calls = A, 0

    def __call__(self, x):
        self.calls += 1
        return self.A @ x


def problem(seed, n, kind):
    """(A, b, lo, hi, target) of a random problem.

    two-sided: −c ≤ x ≤ c with c in [0.2, 1] and about 15 % of the cells fixed at 0 (c = 0,
    as outside the contact), target within 80 % of the attainable range (the tangential
    problem); one-sided: 0 ≤ x < ∞, target in [0.1, 5] (the normal problem).
    """
    rng = np.random.default_rng(seed)
    A = spd_matrix(rng, n)
    b = rng.standard_normal(n)
    if kind == "two-sided":
        c = rng.uniform(0.2, 1.0, n)
        c[rng.random(n) < 0.15] = 0.0
        return A, b, -c, c, float(rng.uniform(-0.8, 0.8) * c.sum())
    return A, b, np.zeros(n), np.full(n, np.inf), float(rng.uniform(0.1, 5.0))


def objective(A, b, x):
    return 0.5 * float(x @ A @ x) + float(b @ x)


# --------------------------------------------------------------------------- box_cg
@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("kind, restore", [("two-sided", "shift"), ("one-sided", "scale"),
                                           ("one-sided", "shift")])
def test_box_cg_equals_the_exact_active_set_solution(seed, kind, restore):
    """n = 7, from x0 = 0 (the one-sided start falls back to a uniform x): x within
    1e-12 (max|x*| ~ 1) of the enumerated solution and λ within 1e-12 of its multiplier
    (measured: 7e-16 and 3e-15 at most), converged in fewer than 100 iterations."""
    A, b, lo, hi, target = problem(seed, 7, kind)
    x_ex, lam_ex = box_qp_exact(A, b, lo, hi, target)
    r = box_cg(lambda x: A @ x, b, lo, hi, target, np.zeros(7),
               BoxOptions(tol=1e-12, max_iter=100, restore=restore))
    assert r.converged and r.iterations < 100 and r.residual < 1e-12
    np.testing.assert_allclose(r.x, x_ex, rtol=0, atol=1e-12 * (1 + np.abs(x_ex).max()))
    np.testing.assert_allclose(r.Ax, A @ r.x, rtol=0, atol=1e-12 * np.abs(A @ r.x).max())
    if lam_ex is not None:
        assert r.multiplier == pytest.approx(lam_ex, rel=0, abs=1e-12 * (1 + abs(lam_ex)))
    assert np.all(r.x >= lo) and np.all(r.x <= hi)


def test_box_cg_keeps_fixed_cells_at_their_value():
    """Cells with lo = hi (here 0.3) keep that value; the others solve the reduced problem
    (enumerated reference: x within 1e-12)."""
    A, b, lo, hi, target = problem(3, 7, "two-sided")
    lo, hi = lo.copy(), hi.copy()
    lo[:2] = hi[:2] = 0.3
    x_ex, _ = box_qp_exact(A, b, lo, hi, target)
    r = box_cg(lambda x: A @ x, b, lo, hi, target, np.zeros(7),
               BoxOptions(tol=1e-12, max_iter=100, restore="shift"))
    assert r.converged
    assert np.all(r.x[:2] == 0.3)
    np.testing.assert_allclose(r.x, x_ex, rtol=0, atol=1e-12)


@pytest.mark.parametrize("seed", range(2))
@pytest.mark.parametrize("kind, restore", [("two-sided", "shift"), ("one-sided", "scale")])
def test_box_cg_kkt_and_slsqp_on_forty_cells(seed, kind, restore):
    """n = 40, eigenvalues in [1, 50]: the optimality conditions hold to 1e-11 (bounds and
    force relative to Σ|x|, the residual's signs relative to max|Ax + b|; measured ≤ 5e-15),
    and scipy's SLSQP (ftol 1e-15) lands on the same point within 1e-6 of max|x| (measured
    1.2e-8 at most; SLSQP is the less accurate of the two) with an objective no lower than box_cg's
    by more than 1e-10 |f|."""
    n = 40
    A, b, lo, hi, target = problem(100 + seed, n, kind)
    r = box_cg(lambda x: A @ x, b, lo, hi, target, np.zeros(n),
               BoxOptions(tol=1e-13, max_iter=1000, restore=restore))
    assert r.converged
    assert box_kkt_violation(A, b, lo, hi, target, r.x, r.multiplier) < 1e-11
    ref = minimize(lambda x: objective(A, b, x), np.full(n, target / n),
                   jac=lambda x: A @ x + b, method="SLSQP",
                   bounds=[(l_, None if np.isinf(h_) else h_)
                           for l_, h_ in zip(lo, hi, strict=True)],
                   constraints=[{"type": "eq", "fun": lambda x: x.sum() - target,
                                 "jac": lambda x: np.ones(n)}],
                   options={"ftol": 1e-15, "maxiter": 2000})
    np.testing.assert_allclose(r.x, ref.x, rtol=0, atol=1e-6 * np.abs(ref.x).max())
    f_cg, f_ref = objective(A, b, r.x), objective(A, b, ref.x)
    assert f_cg <= f_ref + 1e-10 * abs(f_ref)


@pytest.mark.parametrize("kind, restore", [("two-sided", "shift"), ("one-sided", "scale")])
def test_box_cg_warm_starts(kind, restore):
    """n = 12. From the solution with its A x0: converged after one iteration and one
    operator application (the documented saving), unchanged to 1e-14; without A x0 one
    application more. From an infeasible start (random, |x0| ~ 5, outside the bounds and
    off the force): the same solution within 1e-12."""
    n = 12
    A, b, lo, hi, target = problem(7, n, kind)
    ref = box_cg(lambda x: A @ x, b, lo, hi, target, np.zeros(n),
                 BoxOptions(tol=1e-13, max_iter=200, restore=restore))
    assert ref.converged
    for Ax0, calls in ((A @ ref.x, 1), (None, 2)):
        op = Counted(A)
        r = box_cg(op, b, lo, hi, target, Start(ref.x, Ax0),
                   BoxOptions(tol=1e-12, max_iter=200, restore=restore))
        assert r.converged and r.iterations == 1 and op.calls == calls
        np.testing.assert_allclose(r.x, ref.x, rtol=0, atol=1e-14 * (1 + np.abs(ref.x).max()))
    x0 = 5.0 * np.random.default_rng(8).standard_normal(n)
    r = box_cg(lambda x: A @ x, b, lo, hi, target, x0,
               BoxOptions(tol=1e-12, max_iter=200, restore=restore))
    assert r.converged
    np.testing.assert_allclose(r.x, ref.x, rtol=0, atol=1e-12 * (1 + np.abs(ref.x).max()))


def test_box_cg_scaled_warm_start_is_one_iteration():
    """One-sided: a start proportional to the solution is restored by the Polonsky-Keer
    scaling alone (converged after one iteration, x within 1e-14)."""
    A, b, lo, hi, target = problem(9, 12, "one-sided")
    ref = box_cg(lambda x: A @ x, b, lo, hi, target, np.zeros(12),
                 BoxOptions(tol=1e-13, max_iter=200))
    r = box_cg(lambda x: A @ x, b, lo, hi, target, Start(3.0 * ref.x, 3.0 * (A @ ref.x)),
               BoxOptions(tol=1e-12, max_iter=200))
    assert r.converged and r.iterations == 1
    np.testing.assert_allclose(r.x, ref.x, rtol=0, atol=1e-14 * (1 + np.abs(ref.x).max()))


@pytest.mark.parametrize("kind, restore", [("two-sided", "shift"), ("one-sided", "scale")])
def test_box_cg_iteration_cap_reports_not_converged(kind, restore):
    """max_iter = 2 on n = 40 (it needs 23 and 35): converged is False, iterations == 2 and
    the residual (measured 0.11 and 0.37) is above the tolerance; the iterate stays feasible
    (bounds exactly, force to 1e-12)."""
    A, b, lo, hi, target = problem(11, 40, kind)
    r = box_cg(lambda x: A @ x, b, lo, hi, target, np.zeros(40),
               BoxOptions(tol=1e-12, max_iter=2, restore=restore))
    assert not r.converged and r.iterations == 2 and r.residual >= 1e-12
    assert np.all(r.x >= lo) and np.all(r.x <= hi)
    assert abs(r.x.sum() - target) <= 1e-12 * np.abs(r.x).sum()


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_box_cg_unattainable_force_is_not_converged(sign):
    """|target| = 1.2 Σc beyond what −c ≤ x ≤ c can carry: every cell at its bound and
    converged False, the residual being the force error 0.2/1.2 (never a silent success);
    |target| = Σc exactly is attainable and converges."""
    A, b, lo, hi, _ = problem(2, 12, "two-sided")
    total = float(hi.sum())
    r = box_cg(lambda x: A @ x, b, lo, hi, sign * 1.2 * total, np.zeros(12),
               BoxOptions(tol=1e-12, max_iter=100, restore="shift"))
    assert not r.converged
    np.testing.assert_array_equal(r.x, hi if sign > 0 else lo)
    assert r.residual == pytest.approx(0.2 / 1.2, rel=1e-12)
    r = box_cg(lambda x: A @ x, b, lo, hi, sign * total, np.zeros(12),
               BoxOptions(tol=1e-12, max_iter=100, restore="shift"))
    assert r.converged
    np.testing.assert_allclose(r.x, hi if sign > 0 else lo, rtol=1e-15)


# --------------------------------------------------------------------------- fista
@pytest.mark.parametrize("seed", range(3))
def test_fista_on_a_box_sum_set(seed):
    """Accelerated projected gradient with L = λmax(A) on the two-sided problem (n = 7,
    cond 50), natural-residual tolerance 1e-12: converged, x within 1e-7 of the enumerated
    solution (measured 5e-11 at most in 140-210 iterations), feasible,
    and A x returned consistent with x to 1e-12. With a cap of 3 iterations: not
    converged, 3 iterations."""
    A, b, lo, hi, target = problem(seed, 7, "two-sided")
    x_ex, _ = box_qp_exact(A, b, lo, hi, target)
    L = float(np.linalg.eigvalsh(A).max())
    project = lambda y: project_box_sum(y, lo, hi, target)  # noqa: E731
    scale = float(hi.sum())
    o = fista(lambda v: A @ v, b, project, np.zeros(7), L, 1e-12, 20000, scale)
    x, Ax, its, err, ok = o.x, o.Ax, o.iterations, o.residual, o.converged
    assert ok and err < 1e-12
    np.testing.assert_allclose(x, x_ex, rtol=0, atol=1e-7)
    assert np.all(x >= lo) and np.all(x <= hi) and abs(x.sum() - target) < 1e-12 * scale
    np.testing.assert_allclose(Ax, A @ x, rtol=0, atol=1e-12 * np.abs(A @ x).max())
    o = fista(lambda v: A @ v, b, project, np.zeros(7), L, 1e-12, 3, scale)
    its, ok = o.iterations, o.converged
    assert not ok and its == 3


# --------------------------------------------------------------------------- project_box_sum
@st.composite
def box_sum_sets(draw, max_n=12):
    """(y, lo, hi, target) with an attainable target: two-sided boxes (some cells fixed,
    lo = hi) with the target anywhere in [Σlo, Σhi], or the one-sided 0 ≤ x < ∞."""
    n = draw(st.integers(1, max_n))
    coords = st.lists(st.floats(-10.0, 10.0), min_size=n, max_size=n)
    y = np.array(draw(coords))
    if draw(st.booleans()):
        return y, np.zeros(n), np.full(n, np.inf), draw(st.floats(0.0, 20.0))
    centre = np.array(draw(st.lists(st.floats(-2.0, 2.0), min_size=n, max_size=n)))
    width = np.array(draw(st.lists(st.sampled_from([0.0, 0.1, 0.5, 1.0, 3.0]) | st.floats(0.0, 3.0),
                                   min_size=n, max_size=n)))
    lo, hi = centre - width, centre + width
    theta = draw(st.floats(0.0, 1.0))
    return y, lo, hi, float(lo.sum() + theta * (hi.sum() - lo.sum()))


def feasible_point(lo, hi, target, weights, direction, step):
    """A point of {lo ≤ z ≤ hi, Σz = target} built without the projection: the target's
    share of each box (two-sided) or positive weights (one-sided), moved along a zero-sum
    direction by a fraction ``step`` of the largest step that stays in the box."""
    if np.isinf(hi).any():
        w = np.asarray(weights) + 1e-3
        return target * w / w.sum()
    span = hi - lo
    theta = (target - lo.sum()) / span.sum() if span.sum() > 0 else 0.0
    z = lo + theta * span
    movable = span > 0
    d = np.where(movable, np.asarray(direction), 0.0)
    if movable.any():
        d[movable] -= d[movable].mean()
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(d > 0, (hi - z) / d, np.where(d < 0, (lo - z) / d, np.inf))
    s_max = float(np.min(room, initial=np.inf))
    return np.clip(z + step * (s_max if np.isfinite(s_max) else 0.0) * d, lo, hi)


def _tol(y, lo, hi, target):
    finite_hi = np.where(np.isfinite(hi), hi, 0.0)
    return 1e-12 * (1.0 + np.abs(y).sum() + np.abs(lo).sum() + np.abs(finite_hi).sum()
                    + abs(target))


@settings(max_examples=100)
@given(box_sum_sets(), st.lists(st.floats(0.0, 1.0), min_size=12, max_size=12),
       st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12), st.floats(0.0, 1.0))
def test_project_box_sum_is_a_euclidean_projection(data, weights, direction, step):
    """For any y and attainable set, P = project_box_sum(y):

    * feasible: lo ≤ P ≤ hi exactly, |ΣP − target| ≤ 1e-12 (1 + Σ|y| + Σ|lo| + Σ|hi| +
      |target|);
    * idempotent: |P(P) − P| within the same tolerance;
    * variational inequality ⟨y − P, z − P⟩ ≤ |y − P| (1e-10 |z − P| + tol) for a feasible
      z built independently (:func:`feasible_point`);
    * non-expansive: |P(y) − P(y')| ≤ |y − y'| (1 + 1e-10) for y' = y + (z − y)/2.
    """
    y, lo, hi, target = data
    n = len(y)
    P = project_box_sum(y, lo, hi, target)
    tol = _tol(y, lo, hi, target)
    assert np.all(P >= lo) and np.all(P <= hi)
    assert abs(P.sum() - target) <= tol
    np.testing.assert_allclose(project_box_sum(P, lo, hi, target), P, rtol=0, atol=tol)
    z = feasible_point(lo, hi, target, weights[:n], direction[:n], step)
    assert np.all(z >= lo) and np.all(z <= hi) and abs(z.sum() - target) <= tol
    yp, zp = y - P, z - P
    # P is exact to tol (its rounding), which moves ⟨y − P, z − P⟩ by up to |y − P| tol
    assert float(yp @ zp) <= np.linalg.norm(yp) * (1e-10 * np.linalg.norm(zp) + tol)
    y2 = y + 0.5 * (z - y)
    P2 = project_box_sum(y2, lo, hi, target)
    assert np.linalg.norm(P - P2) <= np.linalg.norm(y - y2) * (1 + 1e-10) + tol


@settings(max_examples=40)
@given(box_sum_sets(max_n=6))
def test_project_box_sum_equals_the_exact_qp(data):
    """P(y) is the minimiser of ½|x − y|² over the set: the enumerated QP with A = I,
    b = −y (n ≤ 6) gives the same point within 1e-12 (1 + Σ|y| + ...)."""
    y, lo, hi, target = data
    x_ex, _ = box_qp_exact(np.eye(len(y)), -y, lo, hi, target)
    np.testing.assert_allclose(project_box_sum(y, lo, hi, target), x_ex, rtol=0,
                               atol=_tol(y, lo, hi, target))


def test_project_box_sum_limits():
    """Target at either end of the range: every movable cell at that bound; one-sided with
    target 0: zero; a y already in the set is returned unchanged (to 1e-15)."""
    y = np.array([3.0, -1.0, 0.2, 5.0])
    lo, hi = np.array([-1.0, -2.0, 0.0, 1.0]), np.array([1.0, 2.0, 0.0, 1.5])
    np.testing.assert_array_equal(project_box_sum(y, lo, hi, lo.sum()), lo)
    np.testing.assert_array_equal(project_box_sum(y, lo, hi, hi.sum()), hi)
    np.testing.assert_array_equal(project_box_sum(y, np.zeros(4), np.full(4, np.inf), 0.0),
                                  np.zeros(4))
    inside = np.array([0.5, -1.5, 0.0, 1.2])
    np.testing.assert_allclose(project_box_sum(inside, lo, hi, inside.sum()), inside,
                               rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- constraint rows
def rows_kkt_violation(A, b, lo, hi, C, x, lam):
    """The optimality conditions with general rows: bounds, C x = f (relative to Σ|x|),
    and the residual r = Ax + b − Cᵀλ: 0 on free cells, ≥ 0 at lo, ≤ 0 at hi (relative to
    max|Ax + b|)."""
    g = A @ x + b
    r = g - C.field(lam)
    xs = max(float(np.abs(x).sum()), 1e-300)
    gs = max(float(np.abs(g).max()), 1e-300)
    movable = lo < hi
    at_lo, at_hi = movable & (x <= lo), movable & (x >= hi)
    free = movable & ~at_lo & ~at_hi
    return max(float(np.max(np.maximum(lo - x, 0.0), initial=0.0)) / xs,
               float(np.max(np.maximum(x - hi, 0.0), initial=0.0)) / xs,
               float(np.abs(C.residual(x)).max(initial=0.0)) / xs,
               float(np.max(np.abs(r[free]), initial=0.0)) / gs,
               float(np.max(-r[at_lo], initial=0.0)) / gs,
               float(np.max(r[at_hi], initial=0.0)) / gs)


def rows_problem(seed, kind, m):
    """n = 40 cells on a 5 x 8 grid; rows: the sum, then x1 and x2 arms (normalised), as
    the normal problem's W, M2, M1 (one-sided) or the shear's force and torque-like rows
    (two-sided); targets from a feasible point."""
    A, b, lo, hi, _ = problem(200 + seed, 40, kind)
    x1, x2 = np.meshgrid(np.linspace(-1, 1, 5), np.linspace(-1, 1, 8), indexing="ij")
    rows = np.array([np.ones(40), x1.ravel(), x2.ravel()])[:m]
    rng = np.random.default_rng(seed)
    inside = np.where(np.isfinite(hi), lo + (hi - lo) * rng.uniform(0.2, 0.8, 40),
                      rng.uniform(0.0, 2.0, 40))
    return A, b, lo, hi, Constraints(rows, rows @ inside)


@pytest.mark.parametrize("seed", range(2))
@pytest.mark.parametrize("kind, m", [("one-sided", 3), ("one-sided", 2), ("two-sided", 3),
                                     ("two-sided", 1), ("one-sided", 0), ("two-sided", 0)])
def test_box_cg_with_rows_kkt_and_slsqp(seed, kind, m):
    """Up to three rows (or none: a plain bound-constrained problem), n = 40: the
    optimality conditions with the multipliers hold to 1e-10 (measured <= 8e-14) and SLSQP
    (ftol 1e-15) finds the same x within 1e-6 of max|x| (measured <= 4e-8)."""
    A, b, lo, hi, C = rows_problem(seed, kind, m)
    r = box_cg(lambda x: A @ x, b, lo, hi, C, np.zeros(40),
               BoxOptions(tol=1e-13, max_iter=2000,
                          restore="scale" if kind == "one-sided" else "shift"))
    assert r.converged and np.shape(r.multiplier) == (m,)
    assert rows_kkt_violation(A, b, lo, hi, C, r.x, r.multiplier) < 1e-10
    cons = [{"type": "eq", "fun": (lambda x, i=i: C.rows[i] @ x - C.target[i]),
             "jac": (lambda x, i=i: C.rows[i])} for i in range(m)]
    ref = minimize(lambda x: objective(A, b, x), np.clip(np.full(40, 0.1), lo, hi),
                   jac=lambda x: A @ x + b, method="SLSQP",
                   bounds=[(l_, None if np.isinf(h_) else h_)
                           for l_, h_ in zip(lo, hi, strict=True)],
                   constraints=cons, options={"ftol": 1e-15, "maxiter": 2000})
    np.testing.assert_allclose(r.x, ref.x, rtol=0, atol=1e-6 * np.abs(ref.x).max())


def test_box_cg_one_sum_row_equals_the_force_target():
    """Constraints with the single sum row solve the same problem as the float target:
    the same x within 1e-12 of max|x| and the same multiplier (1e-12 of max|Ax + b|)."""
    for kind, restore in (("one-sided", "scale"), ("two-sided", "shift")):
        A, b, lo, hi, target = problem(3, 20, kind)
        ref = box_cg(lambda x, A=A: A @ x, b, lo, hi, target, np.zeros(20),
                     BoxOptions(tol=1e-13, max_iter=500, restore=restore))
        r = box_cg(lambda x, A=A: A @ x, b, lo, hi, Constraints([np.ones(20)], [target]),
                   np.zeros(20), BoxOptions(tol=1e-13, max_iter=500, restore=restore))
        assert r.converged and ref.converged
        np.testing.assert_allclose(r.x, ref.x, rtol=0, atol=1e-12 * np.abs(ref.x).max())
        g = np.abs(A @ ref.x + b).max()
        assert r.multiplier[0] == pytest.approx(ref.multiplier, rel=0, abs=1e-12 * g)


def test_box_cg_without_rows_opens_entirely():
    """No row, b > 0 everywhere (a gap open everywhere under approach control): x = 0 is
    the answer, converged at once from zero and from a loaded start."""
    A, _, lo, hi, _ = problem(4, 12, "one-sided")
    b = np.linspace(0.1, 1.0, 12)
    for x0 in (np.zeros(12), np.full(12, 3.0)):
        r = box_cg(lambda x: A @ x, b, lo, hi, Constraints.none((12,)), x0,
                   BoxOptions(tol=1e-12, max_iter=100))
        assert r.converged and np.all(r.x == 0)


def test_box_cg_never_converges_on_nan():
    """An operator that returns NaN: converged is False and the residual not finite or
    above the tolerance, with or without rows."""
    A, b, lo, hi, target = problem(5, 12, "two-sided")

    def broken(x):
        return np.full_like(x, np.nan)

    for t in (target, Constraints([np.ones(12)], [target]), Constraints.none((12,))):
        r = box_cg(broken, b, lo, hi, t, np.zeros(12),
                   BoxOptions(tol=1e-9, max_iter=50, restore="shift"))
        assert not r.converged


@settings(max_examples=40)
@given(st.integers(0, 10_000), st.sampled_from(["box", "disk"]), st.integers(1, 3))
def test_project_rows_is_the_euclidean_projection(seed, kind, m):
    """project_rows against SLSQP's projection (min |x − y|² over the set and the rows,
    ftol 1e-15) on 8 cells, targets from a feasible point: within 1e-6 of the data's scale
    (SLSQP's accuracy), the rows met to 1e-12, no cell outside its set."""
    rng = np.random.default_rng(seed)
    n = 8
    shape = (2, 4) if kind == "box" else (2, 2, 4)
    y = rng.standard_normal(shape)
    if kind == "box":
        lo, hi = -rng.uniform(0.2, 1.0, (2, 4)), rng.uniform(0.2, 1.0, (2, 4))
        inside = lo + (hi - lo) * rng.uniform(0.2, 0.8, (2, 4))
        rows = rng.standard_normal((m, 2, 4))
        rho = None
    else:
        rho = rng.uniform(0.2, 1.0, (2, 4))
        ang, rad = rng.uniform(0, 2 * np.pi, (2, 4)), rng.uniform(0.1, 0.8, (2, 4))
        inside = np.stack([rad * rho * np.cos(ang), rad * rho * np.sin(ang)])
        rows = rng.standard_normal((m, 2, 2, 4))
        lo = hi = None
    C = Constraints(rows, [float(np.sum(r * inside)) for r in rows])
    cells = np.ones((2, 4), dtype=bool)
    P = project_rows(y, C, cells, kind, lo=lo, hi=hi, rho=rho)
    assert np.abs(C.residual(P)).max() <= 1e-12 * (1 + np.abs(y).sum())
    flat = y.ravel()
    if kind == "box":
        bounds = list(zip(lo.ravel(), hi.ravel(), strict=True))
        ineq = []
    else:
        bounds = None
        ineq = [{"type": "ineq", "fun": lambda x: rho.ravel() ** 2 - x[:n] ** 2 - x[n:] ** 2}]
    eq = [{"type": "eq", "fun": (lambda x, r=r, f=f: r.ravel() @ x - f)}
          for r, f in zip(rows, C.target, strict=True)]
    ref = minimize(lambda x: 0.5 * np.sum((x - flat) ** 2), inside.ravel(),
                   jac=lambda x: x - flat, method="SLSQP", bounds=bounds,
                   constraints=eq + ineq, options={"ftol": 1e-15, "maxiter": 1000})
    np.testing.assert_allclose(P.ravel(), ref.x, rtol=0, atol=1e-6 * (1 + np.abs(y).max()))
    if kind == "box":
        assert np.all(P >= lo) and np.all(P <= hi)
    else:
        assert np.all(np.hypot(P[0], P[1]) <= rho * (1 + 1e-12))


@pytest.mark.parametrize("overshoot", [1e11, 1e13, 1e14])
def test_rows_restored_exactly_after_a_far_overshoot(overshoot):
    """The first step of a cold start overshoots far (a tilted sphere's normal solve on a
    37 x 14 grid: two cells at ~1e11 Pa against a row target of 7.8e4 Pa); the
    projection onto {p >= 0, Σp = f} must still meet the row to rounding of the result,
    here 1e-13 of f (the dual iteration alone stopped at 1e-14 of Σ|y|: 9.2e-9 of f at
    1e13, 1.6e-8 at 1e14, above the solver's tolerance 1e-9, and the CG, whose
    directions keep C x, could never converge). The answer is the exact projection:
    the largest cell takes all of f (the others' y are below the common shift)."""
    shape = (37, 14)
    f = 78236.79563938
    x = np.zeros(shape)
    x[18, 6], x[18, 7], x[3, 3] = 1.2 * overshoot, 0.9 * overshoot, 0.7 * overshoot
    C = Constraints(np.ones((1,) + shape), [f])
    lo, hi = np.zeros(shape), np.full(shape, np.inf)
    out = C.restore(x, lo, hi, (x > lo) & (x < hi), lo < hi)
    assert abs(out.sum() - f) <= 1e-13 * f
    assert out[18, 6] == pytest.approx(f, rel=1e-13)
    assert np.count_nonzero(out) == 1 and np.all(out >= 0.0)


# --------------------------------------------------------------------------- preconditioned
@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("kind, restore", [("two-sided", "shift"), ("one-sided", "scale")])
def test_preconditioned_box_cg_equals_the_exact_active_set_solution(seed, kind, restore):
    """n = 7, with a preconditioner M = (A + E)⁻¹, E a random symmetric perturbation of
    norm λmin(A)/2 (M symmetric positive definite, not A⁻¹): the same point as the
    enumerated solution within 1e-12 and the same multiplier (measured: 9e-16)."""
    A, b, lo, hi, target = problem(seed, 7, kind)
    rng = np.random.default_rng(50 + seed)
    E = rng.standard_normal((7, 7))
    E = 0.5 * np.linalg.eigvalsh(A).min() * (E + E.T) / np.linalg.norm(E + E.T, 2)
    M = np.linalg.inv(A + E)
    assert np.linalg.eigvalsh(M).min() > 0 and np.abs(M @ A - np.eye(7)).max() > 1e-3
    x_ex, lam_ex = box_qp_exact(A, b, lo, hi, target)
    r = box_cg(lambda x: A @ x, b, lo, hi, target, np.zeros(7),
               BoxOptions(tol=1e-12, max_iter=100, restore=restore, precondition=lambda v: M @ v))
    assert r.converged and r.residual < 1e-12
    np.testing.assert_allclose(r.x, x_ex, rtol=0, atol=1e-12 * (1 + np.abs(x_ex).max()))
    np.testing.assert_allclose(r.Ax, A @ r.x, rtol=0, atol=1e-12 * np.abs(A @ r.x).max())
    if lam_ex is not None:
        assert r.multiplier == pytest.approx(lam_ex, rel=0, abs=1e-12 * (1 + abs(lam_ex)))


@pytest.mark.parametrize("seed", range(3))
def test_preconditioned_box_cg_with_rows_meets_kkt(seed):
    """n = 40 one-sided, two constraint rows (a sum and a moment): the preconditioned
    iteration (M = A⁻¹ of a perturbed A) lands on the plain one's point within 1e-9 of
    max|x| (measured 1e-13) and keeps both rows to 1e-10 (relative)."""
    n = 40
    A, b, lo, hi, _ = problem(200 + seed, n, "one-sided")
    arm = np.linspace(-1.0, 1.0, n)
    con = Constraints([np.ones(n), arm], [3.0, 0.4])
    plain = box_cg(lambda x: A @ x, b, lo, hi, con, np.zeros(n),
                   BoxOptions(tol=1e-13, max_iter=2000))
    M = np.linalg.inv(A + np.diag(np.random.default_rng(seed).uniform(0, 5, n)))
    fast = box_cg(lambda x: A @ x, b, lo, hi, con, np.zeros(n),
                  BoxOptions(tol=1e-13, max_iter=2000, precondition=lambda v: M @ v))
    assert plain.converged and fast.converged
    np.testing.assert_allclose(fast.x, plain.x, rtol=0, atol=1e-9 * np.abs(plain.x).max())
    np.testing.assert_allclose(con.residual(fast.x), 0.0, atol=1e-10 * 3.0)


@pytest.mark.parametrize("seed", range(3))
def test_box_cg_deferred_products_keep_the_contract(seed):
    """``update`` with ``defer``, n = 40 two-sided: every projection's product deferred
    (defer = 1e300), the result's A x is still A times its own x to rounding (1e-12 of its
    largest): what waited is folded into the converged last step; without ``exact`` the
    result says it has no A x (None) rather than a lagged one; with ``defer`` = 0, A x is
    exact too; with the default-sized 0.1 the point is the exact one's (defer = 0) within
    1e-9 of max|x|."""
    A, b, lo, hi, target = problem(300 + seed, 40, "two-sided")
    x0 = np.zeros(40)
    opt = BoxOptions(tol=1e-11, max_iter=2000, restore="shift")

    def solve(defer=0.0, exact=False):
        return box_cg(lambda x: A @ x, b, lo, hi, target, x0, opt,
                      Ledger(update=True, defer=defer, exact=exact))

    lagged = solve(1e300)
    assert lagged.converged and lagged.Ax is None
    all_ = solve(1e300, exact=True)
    assert all_.converged
    np.testing.assert_array_equal(all_.x, lagged.x)
    np.testing.assert_allclose(all_.Ax, A @ all_.x, rtol=0, atol=1e-12 * np.abs(all_.Ax).max())
    exact = solve()
    assert exact.converged
    np.testing.assert_allclose(exact.Ax, A @ exact.x, rtol=0, atol=1e-12 * np.abs(exact.Ax).max())
    some = solve(0.1)
    assert some.converged
    np.testing.assert_allclose(some.x, exact.x, rtol=0, atol=1e-9 * np.abs(exact.x).max())


@pytest.mark.parametrize("need_shift", [0.05, 0.6])
def test_restore_by_shift_is_one_clipped_shift_of_the_free_cells(need_shift):
    """_restore_by_shift (the force restore after a projection): Σx = target to 1e-12, every
    cell within its bounds, the held cells untouched, and the free cells moved by one common
    shift c, clipped at their bounds. A small deficit (0.05 per free cell) is met by the
    plain shift with no cell crossing a bound; a larger one (0.6) sends cells to their bounds
    and needs the root-finder. The result equals the Euclidean projection of the free cells
    onto {bounds, Σ = need} (project_box_sum) to 1e-12."""
    from contactpipe.solver.cg import _restore_by_shift
    rng = np.random.default_rng(11)
    n = 200
    hi = rng.uniform(1.0, 2.0, n)
    lo = -hi
    x = rng.uniform(-0.9, 0.9, n) * hi
    free = rng.random(n) < 0.7
    x[~free] = np.where(rng.random((~free).sum()) < 0.5, lo[~free], hi[~free])
    target = x.sum() + need_shift * free.sum()
    out = _restore_by_shift(x.copy(), lo, hi, target, free)
    assert abs(out.sum() - target) <= 1e-12 * np.abs(out).sum()
    assert np.all(out >= lo) and np.all(out <= hi)
    np.testing.assert_array_equal(out[~free], x[~free])
    d = (out - x)[free]
    inside = (out[free] > lo[free]) & (out[free] < hi[free])
    assert inside.any()
    c = d[inside].mean()
    np.testing.assert_allclose(d[inside], c, rtol=0, atol=1e-12)
    assert np.all(np.abs(d[~inside]) <= abs(c) + 1e-12)       # clipped: moved less than c
    crossed = int((~inside).sum())
    assert (crossed == 0) if need_shift < 0.1 else (crossed > 0)
    ref = project_box_sum(x[free], lo[free], hi[free], target - x[~free].sum())
    np.testing.assert_allclose(out[free], ref, rtol=0, atol=1e-12)


def test_block_sums_restore_leaves_a_block_that_holds():
    """BlockSums.restore: a block whose sum is off by rounding only is returned bit for bit
    (so that the update of A x after a projection can skip it); a block that is off is
    shifted back onto its row."""
    from contactpipe.solver.cg import BlockSums
    rng = np.random.default_rng(12)
    x = np.stack([rng.uniform(0.1, 1.0, (6, 5)), rng.uniform(-0.5, 0.5, (6, 5))])
    lo = np.stack([np.zeros((6, 5)), -np.ones((6, 5))])
    hi = np.stack([np.full((6, 5), np.inf), np.ones((6, 5))])
    target = [float(x[0].sum()) * (1 + 1e-15), float(x[1].sum()) + 0.3]
    free = (x > lo) & (x < hi)
    out = BlockSums(target).restore(x, lo, hi, free)
    np.testing.assert_array_equal(out[0], x[0])
    assert abs(out[1].sum() - target[1]) <= 1e-12 * np.abs(out[1]).sum()
    assert not np.array_equal(out[1], x[1])


@pytest.mark.parametrize("seed", range(4))
def test_component_sums_match_the_dense_rows_bit_for_bit(seed):
    """ComponentSums (the vector form's force rows Σq1, Σq2) against the same rows as dense
    Constraints: the multipliers, the rigid field, the sums and the kept direction agree
    bit for bit on random fields and masks (16 x 12 cells)."""
    rng = np.random.default_rng(seed)
    shape = (16, 12)
    target = rng.normal(size=2) * 10.0
    fast = ComponentSums(target, shape)
    rows = np.zeros((2, 2) + shape)
    rows[0, 0] = rows[1, 1] = 1.0
    dense = Constraints(rows, target, sums=True)
    g, z = rng.normal(size=(2, 2) + shape)
    cells = rng.random(shape) < 0.4
    lam = dense.fit(g, cells)
    assert np.array_equal(fast.fit(g, cells), lam)
    assert np.array_equal(g - fast.field(lam), g - dense.field(lam))
    assert np.array_equal(fast.sums_of(z), dense.sums_of(z))
    assert np.array_equal(fast.keep(z, cells), dense.keep(z, cells))
    assert np.array_equal(fast.fit(g, np.zeros(shape, bool)), np.zeros(2))
    np.testing.assert_allclose(fast.sums_of(fast.keep(z, cells)), 0.0, atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_component_sums_shift_is_the_disk_projection_or_declines(seed):
    """ComponentSums.shift is project_rows' projection onto {|x| <= rho, Σx = f} of the
    moving cells where a uniform shift keeps them in their disks (closed form, to 1e-12 of
    the target), and None where a cell would leave its disk."""
    rng = np.random.default_rng(seed)
    shape = (10, 8)
    rho = rng.uniform(1.0, 2.0, shape)
    y = 0.3 * rng.normal(size=(2,) + shape)
    cells = rng.random(shape) < 0.5
    C = ComponentSums(y.reshape(2, -1).sum(axis=1) + rng.normal(size=2), shape)
    x = C.shift(y, cells, rho)
    assert x is not None
    P = project_rows(y, C, cells, "disk", rho=rho)
    np.testing.assert_allclose(x, P, atol=1e-12 * float(np.abs(C.target).max() + 1.0))
    np.testing.assert_allclose(C.sums_of(x), C.target, rtol=1e-12)
    assert np.array_equal(x[:, ~cells], y[:, ~cells])
    far = ComponentSums(C.target + 50.0 * np.count_nonzero(cells), shape)
    assert far.shift(y, cells, rho) is None
    assert C.shift(y, np.zeros(shape, bool), rho) is None
