"""The joint solve and the ledger of deferred products, against the paths they replace: each
must give the answer of the path it replaces to within the tolerance.

* the joint solves over (p, q1) and (p, q1, q2) (:mod:`contactpipe.solver.joint`)
  against block Gauss-Seidel passes;
* the preconditioned tangential CG against the plain one, and the exact placement of the
  slip cells on their moved bound that it needs (:func:`follow_bound`);
* the self-similar warm start of the preload's sub-steps
  (:mod:`contactpipe.solver.warm_start`) against the unstretched start;
* the block force rows of the joint solve (:class:`BlockSums`) against their definitions;
* the joint solve's deferred projection products (``Tuning.defer``) against exact ones.

FFT pairs and times are benchmark figures (``contactpipe bench fretting paper-fig3``),
not asserted here.
"""
import functools
from dataclasses import replace

import numpy as np
import pytest
from helpers import A_HERTZ, MU, P0_HERTZ, W, fretting_scene, make_scene

import contactpipe as cp
from contactpipe.nomenclature import STATUS_SLIP, STATUS_STICK
from contactpipe.solver import coupling, joint
from contactpipe.solver.cg import BlockSums, BoxOptions, box_cg
from contactpipe.solver.coupling import Previous, follow_bound
from contactpipe.solver.options import TUNING

#: The block Gauss-Seidel passes alone (no joint solve).
NO_JOINT = replace(TUNING, joint=False)

ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}
MAXWELL = {"material": "viscoelastic", "young": 105e9, "poisson": 0.3, "creep": "maxwell",
           "relaxation_time": 1.0}
TOL = 1e-10
#: The scenes ask for the one-component form, whose joint solve most tests here exercise
#: ("auto" runs the vector form on them: a frictional preload on a coupled pair); the
#: vector form's tests ask for it by the override.
SOLVER = {"tolerance": TOL, "tangential": "scalar"}


def steel_on_aluminium(n=32, steps=20):
    return fretting_scene(n=n, steps=steps, halfspace=dict(ALUMINIUM), solver=dict(SOLVER))


def rigid_on_maxwell(n=32, steps=20):
    """Paper fig. 3 with the coupling of nu = 0.3 (beta = 0.29; the glassy composite
    modulus is the steel pair's, so 3 a_H is its window too)."""
    return fretting_scene(n=n, steps=steps, indenter={"material": "rigid"},
                          halfspace=dict(MAXWELL), solver=dict(SOLVER))


def fields(ds):
    return ds.p.values, ds.q1.values, ds.omega1.values


def assert_same(a, b, p_tol, q_tol):
    pa, qa, wa = fields(a)
    pb, qb, wb = fields(b)
    p0 = pa.max()
    assert np.abs(pa - pb).max() <= p_tol * p0, np.abs(pa - pb).max() / p0
    assert np.abs(qa - qb).max() <= q_tol * MU * p0, np.abs(qa - qb).max() / (MU * p0)
    assert np.abs(wa - wb).max() <= q_tol * np.abs(wa).max()


def _watch(monkeypatch, name):
    """The results of the coupling module's joint solve ``name`` (``solve_joint`` or
    ``solve_joint_vector``), one per call, in a list."""
    seen, real = [], getattr(joint, name)

    def watched(*a, **k):
        seen.append(real(*a, **k))
        return seen[-1]

    monkeypatch.setattr(coupling, name, watched)
    return seen


@pytest.mark.parametrize("build", [steel_on_aluminium, rigid_on_maxwell],
                         ids=["steel-on-aluminium", "rigid-on-maxwell"])
def test_joint_solve_gives_the_gauss_seidel_answer(build, monkeypatch):
    """32², 20 steps, tolerance 1e-10, preload and fretting loop: the joint solve runs (on
    every instant and preload sub-step) and its p, q1 and ω1 are the block
    Gauss-Seidel passes' within 1e-7 of p0 and μp0 (measured 8.2e-11 / 1.9e-9 steel on
    aluminium, 5.2e-11 / 5.5e-10 rigid on Maxwell; the joint shear is put on the final
    bound by :func:`joint.finish`, without the tangential solve that ends the passes)."""
    calls = _watch(monkeypatch, "solve_joint")
    fast = cp.simulate(build())
    assert len(calls) >= fast.sizes["time"] + fast.attrs["preload_substeps"] - 1
    slow = cp.simulate(build(), tuning=NO_JOINT)
    assert_same(fast, slow, 1e-7, 1e-7)


def test_joint_finish_keeps_coulomb_and_the_force_rows_exact():
    """After :func:`joint.finish` (no tangential solve), steel on aluminium, 32², 20 steps:
    |q1| <= μp with no excess at all, every slipping cell (status 2) on its bound to 1e-12
    of μp0, and Σq1 Δ = T1, Σp Δ = W to 1e-12 of W at every instant."""
    ds = cp.simulate(steel_on_aluminium())
    p, q1 = ds.p.values, ds.q1.values
    cell = float((ds.x1[1] - ds.x1[0]) * (ds.x2[1] - ds.x2[0]))
    w = float(ds.W.max())
    assert (np.abs(q1) - MU * p).max() <= 0.0
    slip = ds.status.values == STATUS_SLIP
    assert slip.any()
    assert np.abs(np.abs(q1[slip]) - MU * p[slip]).max() <= 1e-12 * MU * p.max()
    assert np.abs(q1.sum(axis=(1, 2)) * cell - ds.T1.values).max() <= 1e-12 * w
    assert np.abs(p.sum(axis=(1, 2)) * cell - ds.W.values).max() <= 1e-12 * w


def vector_fields(ds):
    return ds.p.values, ds.q1.values, ds.q2.values, ds.omega1.values, ds.omega2.values


@pytest.mark.parametrize("build", [steel_on_aluminium, rigid_on_maxwell],
                         ids=["steel-on-aluminium", "rigid-on-maxwell"])
def test_joint_vector_solve_gives_the_gauss_seidel_answer(build, monkeypatch):
    """Vector form, 32², 20 steps, tolerance 1e-10, preload (its first sub-step from
    nothing in contact) and fretting loop: the joint solve over (p, q1, q2) runs on every
    instant and preload sub-step, and its p, q1, q2 are the block Gauss-Seidel passes'
    within 1e-7 of p0 and μp0, ω1 within 1e-7 of its largest (measured 1.3e-10 / 6.9e-10 /
    1.3e-11 steel on aluminium, 1.5e-10 / 2.0e-9 / 4.7e-11 rigid on Maxwell), the same
    stick/slip status."""
    calls = _watch(monkeypatch, "solve_joint_vector")
    fast = cp.simulate(build(), tangential="vector")
    assert len(calls) >= fast.sizes["time"] + fast.attrs["preload_substeps"] - 1
    slow = cp.simulate(build(), tangential="vector", tuning=NO_JOINT)
    p, q1, q2, w1, _ = vector_fields(fast)
    pb, q1b, q2b, w1b, _ = vector_fields(slow)
    p0 = pb.max()
    assert np.abs(p - pb).max() <= 1e-7 * p0
    assert np.abs(q1 - q1b).max() <= 1e-7 * MU * p0
    assert np.abs(q2 - q2b).max() <= 1e-7 * MU * p0
    assert np.abs(w1 - w1b).max() <= 1e-7 * np.abs(w1b).max()
    assert int((fast.status != slow.status).sum()) == 0


def test_joint_vector_finish_keeps_coulomb_and_the_force_rows_exact():
    """After :func:`joint.finish_vector` (no tangential solve), steel on aluminium, 32²,
    20 steps, vector form: |q| <= μp to rounding (1e-12 of μp0), every slipping cell on
    its bound to 1e-12 of μp0, Σq Δ = T and Σp Δ = W to 1e-12 of W at every instant."""
    ds = cp.simulate(steel_on_aluminium(), tangential="vector")
    p, q1, q2 = ds.p.values, ds.q1.values, ds.q2.values
    mag = np.hypot(q1, q2)
    cell = float((ds.x1[1] - ds.x1[0]) * (ds.x2[1] - ds.x2[0]))
    w, mp0 = float(ds.W.max()), MU * p.max()
    assert (mag - MU * p).max() <= 1e-12 * mp0
    slip = ds.status.values == STATUS_SLIP
    assert slip.any()
    assert np.abs(mag[slip] - MU * p[slip]).max() <= 1e-12 * mp0
    assert np.abs(q1.sum(axis=(1, 2)) * cell - ds.T1.values).max() <= 1e-12 * w
    assert np.abs(q2.sum(axis=(1, 2)) * cell - ds.T2.values).max() <= 1e-12 * w
    assert np.abs(p.sum(axis=(1, 2)) * cell - ds.W.values).max() <= 1e-12 * w


def _oblique_load(fraction):
    """Steel on aluminium, 32² over 3 a, T = fraction x μW at 30° to x1 in one step."""
    T = fraction * MU * W
    return make_scene(halfspace=dict(ALUMINIUM), friction={"mu": MU},
                      load={"time": [0.0, 1.0], "normal_force": W,
                            "tangential_force": [[0.0, 0.0], [T * np.cos(np.pi / 6),
                                                              T * np.sin(np.pi / 6)]]},
                      grid={"points": [32, 32], "size": [3 * A_HERTZ, 3 * A_HERTZ]},
                      time={"steps": 2}, solver={"tolerance": TOL})


def test_joint_vector_solve_near_gross_slip(monkeypatch):
    """T = 0.95 μW at 30° to x1 (steel on aluminium, vector form, 32²): 21 of 565 contact
    cells still stick, the slip's direction turns across the contact; the joint solve
    converges on its own, and its fields are the Gauss-Seidel passes' within 1e-7 of p0
    and μp0 (measured 1.7e-10 / 9.3e-10)."""
    seen = _watch(monkeypatch, "solve_joint_vector")
    fast = cp.simulate(_oblique_load(0.95), tangential="vector")
    assert all(res.converged for res in seen)
    status = fast.status.values[-1]
    assert 0 < np.count_nonzero(status == STATUS_STICK) <= 0.05 * np.count_nonzero(status > 0)
    slow = cp.simulate(_oblique_load(0.95), tangential="vector", tuning=NO_JOINT)
    p0 = slow.p.values.max()
    assert np.abs(fast.p.values - slow.p.values).max() <= 1e-7 * p0
    for c in ("q1", "q2"):
        assert np.abs(fast[c].values - slow[c].values).max() <= 1e-7 * MU * p0


def test_joint_vector_solve_hands_gross_slip_to_the_passes(monkeypatch):
    """T = 0.98 μW at 30° to x1: every contact cell slips. The joint solve's projected CG
    stalls on the turning circles there (17 passes, 652 iterations before this rule), so
    a pass that leaves no cell sticking hands the instant to the Gauss-Seidel passes,
    whose vector solves have the projected gradient: after one pass, and the instant
    solved, every cell on its bound (to 1e-12 of μp0) and Σq Δ = T."""
    seen = _watch(monkeypatch, "solve_joint_vector")
    ds = cp.simulate(_oblique_load(0.98), tangential="vector")
    assert not seen[-1].converged and seen[-1].passes == 1
    p, q1, q2 = (ds[c].values[-1] for c in ("p", "q1", "q2"))
    contact = p > 0
    assert np.all(ds.status.values[-1][contact] == STATUS_SLIP)
    mag = np.hypot(q1, q2)
    assert np.abs(mag - MU * p)[contact].max() <= 1e-12 * MU * p.max()
    cell = float((ds.x1[1] - ds.x1[0]) * (ds.x2[1] - ds.x2[0]))
    assert abs(q1.sum() * cell - float(ds.T1[-1])) <= 1e-12 * W
    assert abs(q2.sum() * cell - float(ds.T2[-1])) <= 1e-12 * W


def test_preconditioned_tangential_gives_the_plain_answer():
    """Steel on aluminium, 32², 20 steps, tolerance 1e-10, block Gauss-Seidel: the
    preconditioned scalar CG against the plain one, within 1e-7 of p0 and μp0 (measured
    5.5e-12 / 8.0e-10)."""
    fast = cp.simulate(steel_on_aluminium(), tuning=NO_JOINT)
    slow = cp.simulate(steel_on_aluminium(), tuning=replace(NO_JOINT, precondition=False))
    assert_same(fast, slow, 1e-7, 1e-7)


def test_self_similar_start_of_the_preload():
    """Rigid sphere on Maxwell, 32², 20 steps: the preload's sub-steps started from the
    stretched fields give the fields of the unstretched start within 1e-7 of p0 and μp0
    (measured 1.0e-11 / 1.2e-10),
    and a Hertz pressure stretched from W/4 to W (64² over 4a) is within 3 % of Hertz at W
    in Σ|Δp| / Σp (measured 2.1 %; the unstretched one, scaled to W, is off by 97 %)."""
    fast = cp.simulate(rigid_on_maxwell())
    slow = cp.simulate(rigid_on_maxwell(), tuning=replace(TUNING, self_similar_starts=False))
    assert_same(fast, slow, 1e-7, 1e-7)

    from contactpipe.solver.warm_start import self_similar_start
    n, span = 64, 4 * A_HERTZ
    x = (np.arange(n) + 0.5) * span / n - span / 2
    r2 = x[:, None] ** 2 + x[None, :] ** 2

    def hertz(scale):                    # W scaled by `scale`: a, p0 by its cube root
        a, p0 = A_HERTZ * scale ** (1 / 3), P0_HERTZ * scale ** (1 / 3)
        return p0 * np.sqrt(np.clip(1 - r2 / a ** 2, 0, None))

    prev = Previous(np.zeros((2, n, n)), np.zeros((3, n, n)), hertz(0.25))
    started = self_similar_start(prev, 4.0, 1 / 3).p_guess
    target = hertz(1.0)
    as_it_was = hertz(0.25) * target.sum() / hertz(0.25).sum()    # the CG's own rescaling
    assert np.abs(started - target).sum() < 0.03 * target.sum()
    assert np.abs(as_it_was - target).sum() > 0.9 * target.sum()


@functools.cache
def _continued(form):
    """Steel on aluminium fretting, 32², 20 steps, each instant started as it is and
    with the continued starts off."""
    return (cp.simulate(steel_on_aluminium(), tangential=form),
            cp.simulate(steel_on_aluminium(), tangential=form,
                        tuning=replace(TUNING, continued_starts=False)))


@pytest.mark.parametrize("form", ["scalar", "vector"])
def test_tractions_continued_along_a_straight_load_path(form):
    """Steel on aluminium fretting, 32², 20 steps: starting each instant of a straight
    stretch from q(k−1) + c (q(k−1) − q(k−2)), and its joint solve from the pressure
    continued alike, gives the instants of the plain start within 1e-7 of p0 and μp0
    (measured 2.4e-11 / 1.6e-9 scalar, 5.7e-11 / 3.2e-9 vector) for fewer FFT pairs
    after the first instant (measured 1 157 against 1 182 scalar, 1 984 against 2 145
    vector; at 128² and 40 steps 61.6 against 67.2 and 130.5 against 142.7 a step; the
    pairs: :func:`test_continued_starts_save_fft_pairs`)."""
    fast, slow = _continued(form)
    assert_same(fast, slow, 1e-7, 1e-7)


@pytest.mark.bench
@pytest.mark.parametrize("form", ["scalar", "vector"])
def test_continued_starts_save_fft_pairs(form):
    fast, slow = _continued(form)
    assert fast.fft_pairs.values[1:].sum() < slow.fft_pairs.values[1:].sum()


def test_continued_start_moves_the_starts_alone():
    """q + c dq and the joint solve's pressure start p + c dp (clipped at 0) where c > 0;
    the pressure the normal solves start from, the displacement and the motions as they
    were; nothing moved for c = 0 or zero increments, the pressure start only with dp."""
    from contactpipe.solver.warm_start import continued_start
    rng = np.random.default_rng(3)
    prev = Previous(rng.normal(size=(2, 8, 8)), rng.normal(size=(3, 8, 8)),
                    rng.random((8, 8)), None, np.zeros(6))
    dq, dp = rng.normal(size=(2, 8, 8)), rng.normal(size=(8, 8))
    out = continued_start(prev, dq, 0.5, dp)
    np.testing.assert_array_equal(out.q, prev.q + 0.5 * dq)
    np.testing.assert_array_equal(out.p_start, np.maximum(prev.p_guess + 0.5 * dp, 0.0))
    assert out.p_start.min() == 0.0 < out.p_start.max()       # some cells clipped
    assert out.u is prev.u and out.p_guess is prev.p_guess and out.motion is prev.motion
    assert continued_start(prev, dq, 0.5).p_start is None
    assert continued_start(prev, dq, 0.0, dp) is prev
    assert continued_start(prev, np.zeros_like(dq), 1.0, np.zeros_like(dp)) is prev
    only_p = continued_start(prev, np.zeros_like(dq), 1.0, dp)
    assert only_p.q is prev.q and only_p.p_start is not None


def test_follow_bound_puts_slip_cells_on_the_new_bound():
    """Scalar form: a slip cell lands on ±new exactly (a ratio new/old would round about
    half of them inside, where the CG takes them for stick cells); stick cells stay."""
    rng = np.random.default_rng(1)
    old = rng.uniform(1.0, 2.0, (16, 16))
    new = old * rng.uniform(0.9, 1.1, (16, 16))
    q = np.zeros((2, 16, 16))
    q[0] = np.where(rng.random((16, 16)) < 0.5, old * np.sign(rng.normal(size=(16, 16))),
                    0.3 * old)
    out = follow_bound(q, old, new)
    slip = np.abs(q[0]) == old
    assert np.array_equal(np.abs(out[0][slip]), new[slip])
    assert np.array_equal(np.sign(out[0]), np.sign(q[0]))
    assert np.array_equal(out[0][~slip], q[0][~slip])


def _folded(monkeypatch):
    """Wrap the joint solve's box_cg and the ledger's hand-over of deferred products: a
    list that records, per box_cg call, whether its result has an A x (the joint solve
    asks for an exact one), and whether deferred products were handed over to be folded
    into a step."""
    from contactpipe.solver import ledger
    seen, real, flush = [], joint.box_cg, ledger.Deferred.flush
    folded = []

    def recorded(*a, **k):
        folded.clear()
        res = real(*a, **k)
        seen.append((res.Ax is None, any(folded)))
        return res

    def handed(self):
        out = flush(self)
        folded.append(out is not None)
        return out

    monkeypatch.setattr(joint, "box_cg", recorded)
    monkeypatch.setattr(ledger.Deferred, "flush", handed)
    return seen


def test_deferred_projection_products_give_the_same_answer(monkeypatch):
    """Steel on aluminium, 32², 20 steps, tolerance 1e-10: the joint passes with the
    products of small projections deferred (``Tuning.defer``, the default) and with every
    product exact (defer = 0) give p, q1 and ω1 within 1e-7 of p0 and μp0 (measured
    1.7e-11 / 8.0e-10, ω1 2.6e-11), and some projections were deferred."""
    from contactpipe.solver.ledger import Deferred
    kept, real = [], Deferred.take

    def take(self, d, norm):                # records each projection the lag kept
        out = real(self, d, norm)
        kept.append(out is None)
        return out

    monkeypatch.setattr(Deferred, "take", take)
    deferred = cp.simulate(steel_on_aluminium())
    assert any(kept)
    kept.clear()
    exact = cp.simulate(steel_on_aluminium(), tuning=replace(TUNING, defer=0.0))
    assert kept and not any(kept)
    assert_same(deferred, exact, 1e-7, 1e-7)


def test_joint_solve_ends_with_an_exact_product(monkeypatch):
    """The bookkeeping of deferred products, pushed to its extreme: every projection's
    product deferred (defer = 1e300; steel on aluminium, 32², the Spence shear of W alone
    at tolerance 1e-6, where the last pass too ends with some left out, folded into its
    last step). The result's A x is still the product of its own (p, q1) to 1e-13, as
    with defer = 0, and ω3 is the mean of the exact gap over the contact cells (its
    multiplier) to 1e-12. (The answer itself is compared at the default defer, above: a
    search that never sees its projections is not the solver's.)"""
    from test_coupling import ALUMINIUM as AL
    from test_coupling import STEEL, W, instant

    from contactpipe.solver.normal import solve_normal
    op, gap, U, cell, _, _ = instant(STEEL, AL)
    start = solve_normal(op, gap, W, cell, np.zeros_like(gap), 1e-3, 2000).p
    b = np.stack([gap + U[2], U[0]])
    k = op.k
    for defer in (0.0, 1e300):
        seen = _folded(monkeypatch)
        j = joint.solve_joint(op, b, W, 0.0, cell, MU, start, np.zeros_like(gap), 1e-6,
                              2000, 100, replace(TUNING, defer=defer))
        assert j.converged
        assert seen[-1] == (False, defer > 0)
        exact = op.conv.convolve_matrix([[k["33"], k["31"]], [k["13"], k["11"]]],
                                        [j.p, j.q])
        assert np.abs(j.Ax - exact).max() <= 1e-13 * np.abs(exact).max()
        g = exact[0] + b[0]
        assert j.omega3 == pytest.approx(g[j.p > 0].mean(), rel=1e-12)
        assert np.all(np.abs(j.q) <= j.bound * (1 + 1e-12))    # within its bound


def test_joint_vector_solve_ends_with_an_exact_product():
    """The vector joint solve's deferred projection products, pushed to their extreme
    (``Tuning.defer`` = 1e300: every correction deferred; steel on aluminium, 32², W with
    T = (0.3, 0.2) μW at tolerance 1e-6): its A x is the product of its own (p, q) to
    1e-13 of its largest, ω3 the mean of the exact gap over the contact cells to 1e-12, and
    |q| within the bound of the last pass."""
    from test_coupling import ALUMINIUM as AL
    from test_coupling import STEEL, W, instant

    from contactpipe.solver.normal import solve_normal
    op, gap, U, cell, _, _ = instant(STEEL, AL, tangential="vector")
    start = solve_normal(op, gap, W, cell, np.zeros_like(gap), 1e-3, 2000).p
    b = np.stack([gap + U[2], U[0], U[1]])
    k = op.k
    j = joint.solve_joint_vector(op, b, W, [0.3 * MU * W, 0.2 * MU * W], cell, MU, start,
                                 np.zeros((2,) + gap.shape), 1e-6, 2000, 100,
                                 replace(TUNING, defer=1e300))
    assert j.converged
    exact = op.conv.convolve_matrix([[k["33"], k["31"], k["32"]],
                                     [k["13"], k["11"], k["12"]],
                                     [k["23"], k["21"], k["22"]]], [j.p, j.q[0], j.q[1]])
    assert np.abs(j.Ax - exact).max() <= 1e-13 * np.abs(exact).max()
    g = exact[0] + b[0]
    assert j.omega3 == pytest.approx(g[j.p > 0].mean(), rel=1e-12)
    assert np.all(np.hypot(j.q[0], j.q[1]) <= j.bound * (1 + 1e-12))


def test_block_sums_weights_are_the_mask_cast_once():
    """BlockSums.weights: the mask as 0/1 floats, cast once per mask object (the same
    array handed back for the same mask, a fresh cast for another, with its own counts),
    and the fit and keep taken with them equal, bit for bit, the products with the
    boolean mask and the means over boolean-indexed cells to 1e-15."""
    rng = np.random.default_rng(5)
    rows = BlockSums([1.0, 2.0])
    g = rng.normal(size=(2, 8, 8))
    a, b = rng.random((2, 2, 8, 8)) < 0.4
    w = rows.weights(a)
    assert w.dtype == float and np.array_equal(w, a.astype(float))
    assert rows.weights(a) is w                       # the same mask: no second cast
    lam = rows.fit(g, b)                              # another mask: cast afresh
    assert np.array_equal(rows.weights(b), b.astype(float))
    assert lam == pytest.approx([g[0][b[0]].mean(), g[1][b[1]].mean()], rel=1e-15)
    means = np.array([g[k][b[k]].mean() for k in range(2)]).reshape(2, 1, 1)
    z = rows.keep(g, b)
    assert np.array_equal(z, g - np.multiply(b, rows.field(rows.fit(g, b))))
    assert np.abs(z - (g - b * means)).max() < 1e-15 * np.abs(g).max()


def test_block_sums_rows():
    """Each block its own row: the multipliers are the means over each block's own cells,
    a kept direction sums to zero per block, a restored iterate meets both rows within
    its bounds; and box_cg with them solves a small two-block problem to the exact
    solution (a dense active-set reference: the same answer within 1e-8)."""
    rng = np.random.default_rng(2)
    rows = BlockSums([3.0, -1.0])
    g = rng.normal(size=(2, 6, 6))
    cells = rng.random((2, 6, 6)) < 0.5
    lam = rows.fit(g, cells)
    assert lam == pytest.approx([g[0][cells[0]].mean(), g[1][cells[1]].mean()])
    z = rows.keep(g, cells)
    assert abs(z[0][cells[0]].sum()) < 1e-12 and abs(z[1][cells[1]].sum()) < 1e-12
    assert np.array_equal(z[~cells], g[~cells])
    lo = np.stack([np.zeros((6, 6)), -np.full((6, 6), 0.2)])
    hi = np.stack([np.full((6, 6), np.inf), np.full((6, 6), 0.2)])
    x = rows.restore(np.clip(g, lo, hi), lo, hi, (g > lo) & (g < hi))
    assert rows.residual(x) == pytest.approx([0, 0], abs=1e-12)
    assert np.all(x >= lo) and np.all(x <= hi)

    # a symmetric positive definite two-block operator, x = (p, q) on 6 x 6 cells: the
    # solution meets the optimality conditions of each block with its own multiplier
    # (zero reduced gradient on free cells, signs at the bounds) to rounding, and agrees
    # with scipy's SLSQP (itself accurate to about 1e-8 here) within 1e-6
    m = 72
    B = rng.normal(size=(m, m))
    A = B @ B.T / m + np.eye(m)
    b = rng.normal(size=m)
    def apply(v):
        return (A @ v.ravel()).reshape(2, 6, 6)
    res = box_cg(apply, b.reshape(2, 6, 6), lo, hi, rows, np.zeros((2, 6, 6)),
                 BoxOptions(tol=1e-14, max_iter=5000, restore="shift"))
    assert res.converged
    assert rows.residual(res.x) == pytest.approx([0, 0], abs=1e-12)
    g = apply(res.x) + b.reshape(2, 6, 6)
    free = (res.x > lo) & (res.x < hi)
    gr = g - rows.field(rows.fit(g, free))
    assert np.abs(gr[free]).max() < 1e-10
    assert gr[res.x <= lo].min(initial=0.0) > -1e-10
    assert gr[res.x >= hi].max(initial=0.0) < 1e-10
    ref = _dense_box_qp(A, b, lo.ravel(), hi.ravel(), [3.0, -1.0])
    assert np.abs(res.x.ravel() - ref).max() < 1e-6


def _dense_box_qp(A, b, lo, hi, targets):
    """min ½xᵀAx + bᵀx, lo ≤ x ≤ hi, Σ over each half = its target: scipy's SLSQP."""
    from scipy.optimize import minimize
    m = b.size
    cons = [{"type": "eq", "fun": (lambda x, k=k: x[k * m // 2:(k + 1) * m // 2].sum()
                                   - targets[k])} for k in range(2)]
    x0 = np.concatenate([np.full(m // 2, targets[0] / (m // 2)), np.zeros(m // 2)])
    r = minimize(lambda x: 0.5 * x @ A @ x + b @ x, x0, jac=lambda x: A @ x + b,
                 bounds=list(zip(lo, np.where(np.isinf(hi), None, hi), strict=True)),
                 constraints=cons,
                 method="SLSQP", options={"ftol": 1e-15, "maxiter": 2000})
    return r.x


def test_joint_vector_solve_folds_its_corrections_into_its_steps():
    """Each step of the vector joint solve transforms back once, whatever it projected: its
    projection's correction, the next pass's start and the final state on the last
    pressure's bound ride on the step's inverse transforms, so that the whole solve spends
    three inverse transforms per iteration and three for the first A x (steel on
    aluminium, 32², T = (0.3, 0.2) μW, tolerance 1e-8); its A x is the product of its own
    (p, q) to 1e-13 of its largest."""
    from test_coupling import ALUMINIUM as AL
    from test_coupling import STEEL, W, instant

    from contactpipe.solver.normal import solve_normal
    op, gap, U, cell, _, _ = instant(STEEL, AL, tangential="vector")
    start = solve_normal(op, gap, W, cell, np.zeros_like(gap), 1e-3, 2000).p
    b = np.stack([gap + U[2], U[0], U[1]])
    op.conv.reset_counts()
    j = joint.solve_joint_vector(op, b, W, [0.3 * MU * W, 0.2 * MU * W], cell, MU, start,
                                 np.zeros((2,) + gap.shape), 1e-8, 2000, 100)
    assert j.converged and j.passes > 1
    assert op.conv.inverse_count == 3 * (j.iterations + 1)
    k = op.k
    exact = op.conv.convolve_matrix([[k["33"], k["31"], k["32"]],
                                     [k["13"], k["11"], k["12"]],
                                     [k["23"], k["21"], k["22"]]], [j.p, j.q[0], j.q[1]])
    assert np.abs(j.Ax - exact).max() <= 1e-13 * np.abs(exact).max()
    assert np.all(np.hypot(j.q[0], j.q[1]) <= j.bound * (1 + 1e-12))
    np.testing.assert_array_equal(j.bound, MU * j.p)     # on its own pressure's bound


@functools.cache
def _halves_and_whole():
    """The scalar joint solve of steel on aluminium (32², T = 0.5 μW, tolerance 1e-10)
    with its operator applied in halves and whole: (halves, its pairs, its inverse
    transforms, the exact A x of its (p, q1), whole, its pairs)."""
    from test_coupling import ALUMINIUM as AL
    from test_coupling import STEEL, W, instant

    from contactpipe.solver.normal import solve_normal
    op, gap, U, cell, _, _ = instant(STEEL, AL)
    start = solve_normal(op, gap, W, cell, np.zeros_like(gap), 1e-3, 2000).p
    b = np.stack([gap + U[2], U[0]])

    def run(tuning=TUNING):
        op.conv.reset_counts()
        j = joint.solve_joint(op, b, W, 0.5 * MU * W, cell, MU, start, np.zeros_like(gap),
                              1e-10, 2000, 100, tuning)
        assert j.converged
        return j, op.conv.pairs, op.conv.inverse_count

    halves, halves_pairs, inverse = run()
    exact_Ax = op.conv.convolve_matrix([[op.k["33"], op.k["31"]], [op.k["13"], op.k["11"]]],
                                       [halves.p, halves.q])
    whole, whole_pairs, _ = run(replace(TUNING, halves=False))
    return halves, halves_pairs, inverse, exact_Ax, whole, whole_pairs


def test_scalar_joint_steps_fold_their_projection_products():
    """The scalar joint solve's box_cg applies its operator in halves (a
    :class:`BlockOperator`): a projection's correction rides on the step's inverse
    transforms, and so does the next pass's start (``follow``). Against whole products (a
    plain callable; steel on aluminium, 32², T = 0.5 μW, tolerance 1e-10) it reaches the
    same (p, q1) (measured 1.8e-14 and 1.1e-14 of p's largest and μ times it; bound 1e-9)
    in as many iterations (18, 5 passes), for fewer FFT pairs (measured 52 against 60),
    and spends two inverse transforms per iteration and two for its first A x: the final
    state, q1 on its own pressure's bound, rides on the last step too, and A x is the
    product of that (p, q1) to 1e-13 of its largest."""
    halves, _, inverse, exact, whole, _ = _halves_and_whole()
    assert inverse == 2 * (halves.iterations + 1)
    np.testing.assert_array_equal(halves.bound, MU * halves.p)   # its own pressure's bound
    assert np.abs(halves.Ax - exact).max() <= 1e-13 * np.abs(exact).max()
    assert halves.iterations == whole.iterations
    assert np.abs(halves.p - whole.p).max() <= 1e-9 * whole.p.max()
    assert np.abs(halves.q - whole.q).max() <= 1e-9 * MU * whole.p.max()


@pytest.mark.bench
def test_scalar_joint_steps_in_halves_save_fft_pairs():
    """The same two solves' FFT pairs: in halves fewer than whole (measured 52 against
    60)."""
    _, halves_pairs, _, _, _, whole_pairs = _halves_and_whole()
    assert halves_pairs < whole_pairs
