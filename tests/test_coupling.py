"""The middle loop (solver.coupling.solve_instant) on plain arrays: passes, contact laws of
the converged instant, and failures that name the sub-problem.

One instant of a sphere (R = 18 mm) pressed by W = 1 kN and sheared by T1 = 0.5 mu W
(mu = 0.1) on a 32 x 32 grid over 4 a_Hertz, starting from rest, solved at tolerance 1e-9.
"""
import functools
import warnings
from dataclasses import replace

import numpy as np
import pytest
from helpers import A_HERTZ, MU, STEEL, W, fretting_scene, make_scene

import contactpipe as cp
from contactpipe.simulation import grid_coordinates
from contactpipe.solver.coupling import Previous, Tolerances, solve_instant
from contactpipe.solver.normal import solve_normal
from contactpipe.solver.operator import ContactOperator, body_spectra, convolver
from contactpipe.solver.options import TUNING

ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}
TOL = 1e-9
T1 = 0.5 * MU * W
LIMITS = Tolerances(TOL, 2000, 100)


def instant(indenter, halfspace, n=32, tangential="scalar"):
    """(op, gap, U, cell, plan, Previous at rest) of the scene's first instant."""
    scene = make_scene(indenter=indenter, halfspace=halfspace, friction={"mu": MU},
                       load={"time": [0.0, 1.0], "normal_force": W,
                             "tangential_force": [T1, T1]},
                       grid={"points": [n, n], "size": [4 * A_HERTZ, 4 * A_HERTZ]},
                       solver={"tangential": tangential})
    x1, x2, d1, d2 = grid_coordinates(scene)
    gap = np.asarray(scene.geometry.gap(x1, x2), dtype=float)
    conv = convolver(n, n, "scipy", 1)
    spectra = [body_spectra(b, n, n, d1, d2, "scipy", 1)
               for b in (scene.indenter.body(), scene.halfspace.body())]
    op = ContactOperator(*spectra, 1.0, 1.0, conv)
    rest = Previous(np.zeros((2, n, n)), np.zeros((3, n, n)), np.zeros((n, n)))
    return op, gap, np.zeros((3, n, n)), d1 * d2, cp.plan(scene), rest


def test_identical_bodies_take_one_pass():
    """beta = 0 (steel on steel): no coupling loop, one normal and one tangential solve."""
    op, gap, U, cell, plan, rest = instant(STEEL, STEEL)
    assert plan.coupling == "none"
    res = solve_instant(op, gap, U, W, [T1, 0.0], cell, MU, plan, rest, LIMITS)
    assert res.converged and res.failed == ""
    assert res.passes == 1


@pytest.mark.parametrize("tangential", ["scalar", "vector"])
def test_steel_on_aluminium_converges_to_both_laws(tangential):
    """beta != 0: the passes settle (measured: 7 one-component, 6 vector) on a state where
    the normal and the tangential problems both hold:

    * p >= 0, sum p cell = W and sum q1 cell = T1 to 1e-9 relative (measured 5e-16);
    * the gap h = gap + u3 - omega3 is >= -1e-9 max|u3| everywhere and within 1e-6 max|u3|
      of zero where p > 0 (measured 1.3e-10 and 1e-10: the CG tolerance acts on the force
      balance);
    * |q| <= mu p (1 + 1e-9);
    * stick cells (|q| < mu p) do not slip: |domega - u_in-plane| <= 1e-6 max|u_in-plane|
      (measured 1.2e-10 and 1.4e-9; along x1 only for the one-component form, which leaves
      u2 free);
    * re-solving the normal problem against the final shear moves the pressure by
      sum |dp| cell / W < tolerance 1e-9 (measured 2.4e-10 and 1.0e-10).
    """
    op, gap, U, cell, plan, rest = instant(STEEL, ALUMINIUM, tangential=tangential)
    assert plan.coupling == "gauss_seidel" and plan.tangential == tangential
    res = solve_instant(op, gap, U, W, [T1, 0.0], cell, MU, plan, rest, LIMITS)
    assert res.converged, (res.failed, res.residual)
    assert 1 < res.passes <= LIMITS.max_passes
    p, q, u = res.p, res.q, res.u
    assert p.min() >= 0.0
    assert abs(p.sum() * cell - W) <= 1e-9 * W
    assert abs(q[0].sum() * cell - T1) <= 1e-9 * W
    assert abs(q[1].sum() * cell) <= 1e-9 * W
    h = gap + u[2] - res.omega3
    scale = np.abs(u[2]).max()
    assert h.min() >= -1e-9 * scale, h.min() / scale
    assert np.abs(h[p > 0]).max() <= 1e-6 * scale, np.abs(h[p > 0]).max() / scale
    qn = np.hypot(q[0], q[1])
    assert np.all(qn <= MU * p * (1 + 1e-9))
    stick = (p > 0) & (qn < MU * p * (1 - 1e-6))
    assert stick.any()
    slip = res.domega[:, None, None] - u[:2]            # from rest: u_prev = 0
    held = slice(0, 2) if tangential == "vector" else slice(0, 1)   # scalar: q2 = 0 only
    assert np.abs(slip[held][:, stick]).max() <= 1e-6 * np.abs(u[:2]).max()
    # the normal problem, solved again under the final shear, hardly moves
    u3q = op.coupling_to_normal(q[0], q[1] if tangential == "vector" else None)
    again = solve_normal(op, gap + U[2] + u3q, W, cell, p, TOL, LIMITS.max_iter)
    assert again.converged
    change = np.abs(again.p - p).sum() * cell / W
    assert change < TOL, change


def test_failures_name_the_sub_problem():
    """Each way an instant can stop says which solve stopped."""
    op, gap, U, cell, plan, rest = instant(STEEL, ALUMINIUM)
    res = solve_instant(op, gap, U, W, [T1, 0.0], cell, MU, plan, rest,
                        Tolerances(TOL, 3, 100))
    assert not res.converged and res.failed == "normal" and res.residual > TOL
    res = solve_instant(op, gap, U, W, [T1, 0.0], cell, MU, plan, rest,
                        Tolerances(TOL, 2000, 1))
    assert not res.converged and res.failed == "coupling" and res.passes == 1
    # the residual is the pressure change the next pass measured, not a placeholder
    assert TOL < res.residual < 1.0
    # a tangential force above mu W: no shear within the bounds carries it (alone, the
    # one-component solver clipped q to mu p and carried mu W; the vector one gave NaN)
    for tangential in ("scalar", "vector"):
        op, gap, U, cell, plan, rest = instant(STEEL, ALUMINIUM, tangential=tangential)
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            res = solve_instant(op, gap, U, W, [1.5 * MU * W, 0.0], cell, MU, plan, rest,
                                LIMITS)
        assert not res.converged and res.failed == "sliding"
        assert res.residual == pytest.approx(1 / 3, rel=1e-12)    # (|T| - mu W) / |T|
        assert res.sliding == pytest.approx((W, 1.5 * MU * W, MU * W), rel=1e-12)


def test_the_previous_normal_solution_is_reused_as_is():
    """Previous.normal (no coupling, same W) skips the normal solve: no iterations spent
    on it, the same pressure object."""
    op, gap, U, cell, plan, rest = instant(STEEL, STEEL)
    first = solve_instant(op, gap, U, W, [T1, 0.0], cell, MU, plan, rest, LIMITS)
    again = solve_instant(op, gap, U, W, [T1, 0.0], cell, MU, plan,
                          Previous(first.q, first.u, first.p, first.normal), LIMITS)
    assert again.converged and again.p is first.normal.p
    assert again.iterations < first.iterations


def test_simulate_names_the_failed_sub_problem():
    """simulate turns a failure into one ConvergenceError naming the solve and the step."""
    scene = make_scene(indenter=STEEL, halfspace=ALUMINIUM, friction={"mu": MU},
                       load={"time": [0.0, 1.0], "normal_force": W,
                             "tangential_force": [0.0, T1]},
                       grid={"points": [24, 24], "size": [4 * A_HERTZ, 4 * A_HERTZ]},
                       solver={"max_coupling_passes": 1})
    with pytest.raises(cp.ConvergenceError, match=r"^coupling problem at step 0 \(t = 0 s\)"
                                                   r".*did not settle in 1 pass \(the last "
                                                   r"one left the pressure moving by "
                                                   r"0\.\d+ of W"):
        cp.simulate(scene)
    scene = scene.replace({"solver.max_iterations": 2, "solver.max_coupling_passes": 100})
    with pytest.raises(cp.ConvergenceError, match=r"^normal problem at step 0 .* stopped "
                                                   r"after \d+ iterations"):
        cp.simulate(scene)


@functools.cache
def _vector_path(plain, precondition=True):
    """Four instants of a steel on aluminium pair (32 x 32, vector form, tolerance 1e-9):
    T1 = 0.5, 0.8, 0.2, -0.5 mu W from rest, each from the one before; ``plain`` without
    the warm starts that follow the bound and without the lagged A q of the vector CG;
    ``precondition`` False: the vector CG with TangCG's diagonal scaling alone, every
    pass's A q exact."""
    tuning = replace(TUNING, joint=False)                           # the passes themselves
    if plain:
        tuning = replace(tuning, follow_bound=False, defer=0.0, snap=0.0)
    if plain or not precondition:
        tuning = replace(tuning, precondition=precondition, lagged_passes=False)
    limits = replace(LIMITS, tuning=tuning)
    op, gap, U, cell, plan, prev = instant(STEEL, ALUMINIUM, tangential="vector")
    pairs0, out = op.conv.pairs, []
    for t in (T1, 0.8 * MU * W, 0.2 * MU * W, -0.5 * MU * W):
        res = solve_instant(op, gap, U, W, [t, 0.0], cell, MU, plan, prev, limits)
        assert res.converged
        prev = Previous(res.q, res.u, res.p)
        out.append(res)
    return out, op.conv.pairs - pairs0


def test_preconditioned_vector_passes_reach_the_diagonally_scaled_instants():
    """The vector CG with its shifted (−Δ)^½ filter, and the passes before an instant's
    last keeping a lagged A q, reach the instants of the CG with TangCG's diagonal scaling
    alone: p within 1e-7 max p and q within 1e-7 mu max p at every instant (measured
    4.9e-11 and 5.8e-9), for fewer FFT pairs (measured 596 against 747; 686 against 921
    before the filter's two bands and the per-cell turn limit)."""
    fast, _ = _vector_path(False)
    slow, _ = _vector_path(False, precondition=False)
    for a, b in zip(fast, slow, strict=True):
        scale = float(b.p.max())
        assert np.abs(a.p - b.p).max() <= 1e-7 * scale
        assert np.abs(a.q - b.q).max() <= 1e-7 * MU * scale


@functools.cache
def _coarse_runs(switch):
    """Steel on steel fretting, 32², 10 steps (T moves by a quarter of T* a step), vector
    form: the run at tolerance 1e-12, the run as it is, and the run with the Tuning
    ``switch`` off."""
    def run(tuning=TUNING, **solver):
        return cp.simulate(fretting_scene(n=32, steps=10, **solver), tangential="vector",
                           tuning=tuning)
    return run(solver={"tolerance": 1e-12}), run(), run(replace(TUNING, **{switch: False}))


def _coarse_vector_steps_without(switch, replaced_accurate=True):
    """The runs of :func:`_coarse_runs`: the run as it is reaches the instants of the
    tolerance-1e-12 run (p within 1e-7 max p, q within 1e-7 mu max p, the same stick/slip
    status), so does the replaced run where ``replaced_accurate`` (else its stick/slip
    status only). Returns (as it is, replaced)."""
    ref, fast, slow = _coarse_runs(switch)
    scale = float(ref.p.max())
    for ds, check in ((fast, True), (slow, replaced_accurate)):
        assert int((ds.status != ref.status).sum()) == 0
        if check:
            assert float(np.abs(ds.p - ref.p).max()) <= 1e-7 * scale
            for n in ("q1", "q2"):
                assert float(np.abs(ds[n] - ref[n]).max()) <= 1e-7 * MU * scale
    return fast, slow


def test_the_circles_curvature_in_the_line_search_reaches_coarse_vector_steps_sooner():
    """Coarse steps turn many cells at once. The vector CG's line search along the circles
    (tᵀ(A + D) t, D the circles' curvature on turning cells) reaches the tolerance-1e-12
    instants (measured: p 4.7e-11 of p0, q 8.1e-10 of μp0) in fewer iterations than the
    line search along the tangents alone (tᵀA t) (measured 142 against 1 002-1 195 after
    the first instant, as the FFT plans round; 151 against 211 before the two-band filter
    and the per-cell turn limit; bound 0.8 of them), which converges linearly and so
    stops, its last step small, short of them (q 3.0-4.7e-7 of μp0 from the sixth instant
    on; the same stick/slip status)."""
    fast, slow = _coarse_vector_steps_without("curved_line_search", replaced_accurate=False)
    assert fast.iterations.values[1:].sum() < 0.8 * slow.iterations.values[1:].sum()


def test_the_filter_shifted_along_the_slip_tangents_reaches_vector_steps_sooner():
    """The vector CG's filter shifted by the circles' curvature along the turning cells'
    tangents only (under fretting along x1: on x2, not x1; :func:`disk_cg.slip_axes`)
    reaches the tolerance-1e-12 instants, as the filter shifted alike on both components
    does (measured: p 4.7e-11, q 8.1e-10 against 1.1e-9, no cell's status differs), for
    fewer FFT pairs (measured 489 against
    523 after the first instant, bound 0.98 of them: with the filter in two bands, both
    components shifted take as many iterations but filter two fields more; before the
    bands, 151 against 168 iterations; 64² steel on aluminium, 40 steps: 101.5 against
    107.4 FFT pairs a step; :func:`test_vector_faster_paths_save_fft_pairs`)."""
    _coarse_vector_steps_without("shift_along_tangents")


def test_vector_warm_starts_reach_the_plain_instants():
    """The vector form's cheaper passes (slip cells kept on their moved bound, A q lagged
    by at most a tenth of the tolerance) reach the instants of the plain passes: p within
    1e-7 max p and q within 1e-7 mu max p at every instant (measured 8.1e-12 and 1.6e-9),
    for fewer FFT pairs (measured 587 against 1362, both with the filtered vector CG and
    its corrections folded into its steps; 686 against 3110 before)."""
    fast, _ = _vector_path(False)
    plain, _ = _vector_path(True)
    for a, b in zip(fast, plain, strict=True):
        scale = float(b.p.max())
        assert np.abs(a.p - b.p).max() <= 1e-7 * scale
        assert np.abs(a.q - b.q).max() <= 1e-7 * MU * scale


@pytest.mark.bench
def test_vector_faster_paths_save_fft_pairs():
    """The same runs' FFT pairs: the filtered vector CG and the warm starts spend fewer
    than the diagonally scaled passes and the plain passes (measured 596 against 747, 587
    against 1362, four instants at 32²); the filter shifted along the slip tangents under
    0.98 of the one shifted on both components after the first instant (measured 489
    against 523, 32² fretting, 10 steps)."""
    _, fast = _vector_path(False)
    _, scaled = _vector_path(False, precondition=False)
    _, plain = _vector_path(True)
    assert fast < scaled and fast < plain
    _, tangents, both = _coarse_runs("shift_along_tangents")
    assert tangents.fft_pairs.values[1:].sum() < 0.98 * both.fft_pairs.values[1:].sum()
