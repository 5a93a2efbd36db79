"""The frictional preload as a path (issue 9, item 3): on a coupled pair, friction acts while
the normal load is applied at t0 (Spence), and the first instant's shear depends on the
path. It is resolved in sub-steps graded as (k/n)^2 (accuracy.preload_fractions); the
error of the q field is estimated from the paths of n/4 and n/2 sub-steps and recorded
with n in the archive; ``solver.preload_substeps = "auto"`` picks n for the accuracy
target.

Case: rigid sphere (R = 18 mm) on a Maxwell half-space (E = 105 GPa, nu = 0.3), W = 1 kN
stepped at t0, mu = 0.1, no tangential load, 32^2 auto-sized, tolerance 1e-10. Error: rms
over the contact cells of |q - q_ref| over mu p_max, q_ref the 256-sub-step path (it is
within 3e-4 of a 1024-sub-step one). The figures are of the one-component form, which
the tests ask for (``solver.tangential = "scalar"``): the estimator was calibrated on it.
Under "auto" this scene (a frictional preload on a coupled pair) runs the vector form,
where the same estimate falls below the error at 8 and 16 sub-steps (measured 0.47 % /
0.55 % and 0.16 % / 0.29 %, 0.14 % / 0.13 % at 32): a known gap, not covered here.
"""
import numpy as np
import pytest

import contactpipe as cp
from contactpipe.planning.accuracy import (
    choose_preload,
    preload_error,
    preload_fractions,
    resolve_accuracy,
)
from contactpipe.simulation import preload as simulation

R, W, E, NU, MU = 0.018, 1000.0, 105e9, 0.3, 0.1


def scene(substeps, accuracy=None):
    solver = {"preload_substeps": substeps, "tolerance": 1e-10, "tangential": "scalar"}
    if accuracy:
        solver["accuracy"] = accuracy
    return cp.Scene(name="preload", geometry={"shape": "sphere", "radius": R},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                               "creep": "maxwell", "relaxation_time": 1.0},
                    friction={"mu": MU}, load={"time": [0.0, 1.0], "normal_force": W},
                    grid={"points": [32, 32], "size": "auto"}, time={"steps": 1},
                    solver=solver)


def first_q(ds):
    return np.stack([ds.q1.values[0], ds.q2.values[0] if "q2" in ds else 0 * ds.q1.values[0]])


@pytest.fixture(scope="module")
def reference():
    ds = cp.simulate(scene(256))
    return first_q(ds), ds.p.values[0]


def error(ds, reference):
    q_ref, p_ref = reference
    contact = (p_ref > 0) | (ds.p.values[0] > 0)
    diff = np.sum((first_q(ds) - q_ref) ** 2, axis=0)[contact]
    return float(np.sqrt(diff.mean()) / (MU * p_ref.max()))


def test_fractions():
    f = preload_fractions(8)
    assert f.size == 8 and f[-1] == 1.0 and f[0] == pytest.approx(1 / 64)
    assert np.all(np.diff(f) > 0)
    np.testing.assert_array_equal(preload_fractions(8)[1::2], preload_fractions(4))


def test_explicit_count_and_its_estimate(reference):
    """The explicit count is kept (default 8) and recorded; the error of its q field
    against the fine path is within the recorded estimate (measured 1.4 % against an
    estimate of 3.2 % at 8 sub-steps, 0.49 % against 1.1 % at 32), and halves at least
    from 8 to 32 sub-steps (a first-order path)."""
    errors = {}
    for n in (8, 32):
        ds = cp.simulate(scene(n))
        assert ds.attrs["preload_substeps"] == n
        est = ds.attrs["preload_error_estimate"]
        errors[n] = error(ds, reference)
        assert errors[n] <= est, (n, errors[n], est)
        assert ds.attrs["preload_estimate_fft_pairs"] > 0
    assert errors[8] < 0.02 and errors[32] < 0.5 * errors[8]


def test_auto_meets_the_target(reference):
    """"auto" doubles n from 8 until the estimate is within the target: 1 % without a
    preset (measured: n = 32, estimate 0.55 %, error 0.26 %; the coarser paths of the
    choice cost 3 900 FFT pairs, the run's own preload 3 700)."""
    ds = cp.simulate(scene("auto"))
    n, est = ds.attrs["preload_substeps"], ds.attrs["preload_error_estimate"]
    assert n >= 8 and (n & (n - 1)) == 0 and est <= 0.01
    assert error(ds, reference) <= 0.01


def test_accuracy_preset_sets_auto():
    """An accuracy preset replaces the count by "auto" with its own target."""
    sc, _ = resolve_accuracy(scene(8, accuracy="fast"))
    assert sc.solver.preload_substeps == "auto"


def test_choose_preload_bookkeeping():
    """On a synthetic first-order path q_m = q + C/m the estimate is exact (C/n), "auto"
    stops at the first n whose estimate meets the target, and n < 4 has no estimate."""
    p = np.ones((4, 4))
    calls = []

    def path(m):
        calls.append(m)
        return np.stack([np.full((4, 4), 0.3 / m), np.zeros((4, 4))]), p

    assert choose_preload(16, path, 1.0) == (16, pytest.approx(0.3 / 16))
    assert sorted(calls) == [4, 8]
    assert choose_preload("auto", path, 1.0, target=0.3 / 60)[0] == 64
    assert choose_preload(2, path, 1.0) == (2, None)
    assert preload_error(None, path(4), 2, 4, 8, 1.0) is None


def test_loose_coarser_paths_of_the_estimate(monkeypatch):
    """The estimate's coarser paths are solved to PATH_TOLERANCE of the path's error
    target (1e-5 x 1 % = 1e-7 here, not 1e-10); the run's own path keeps the full
    tolerance at every station: its fields are those of a run whose estimate is solved
    tightly, bit for bit; the recorded estimate moves by less than 1e-6 (measured 3.5e-9)
    and costs fewer FFT pairs (measured 855 -> 617)."""
    loose = cp.simulate(scene(8))
    monkeypatch.setattr(simulation, "PATH_TOLERANCE", 0.0)     # every station at 1e-10
    tight = cp.simulate(scene(8))
    np.testing.assert_array_equal(first_q(loose), first_q(tight))
    np.testing.assert_array_equal(loose.p.values, tight.p.values)
    assert loose.fft_pairs.values[0] == tight.fft_pairs.values[0]
    assert abs(loose.attrs["preload_error_estimate"]
               - tight.attrs["preload_error_estimate"]) < 1e-6
    assert loose.attrs["preload_estimate_fft_pairs"] < tight.attrs["preload_estimate_fft_pairs"]


def test_the_estimate_is_a_function_of_the_problem_not_a_mode_of_it():
    """The preload estimate runs its coarser paths through the instant solver with an
    explicit Path (sub-steps, limits, scratch): the problem has no mode to set or reset
    (its attributes are the same before and after), and two estimates agree bit for bit
    (8 sub-steps on the case above: an error estimate of 3.2 % of mu p_max)."""
    from contactpipe.planning import plan
    from contactpipe.simulation.march import _step
    from contactpipe.simulation.problem import Grid, Operators, Problem

    sc = scene(8)
    pb = Problem(sc, plan(sc))
    assert isinstance(pb.grid, Grid) and isinstance(pb.ops, Operators)
    assert pb.grid.shape == (32, 32) and pb.grid.cell == pytest.approx(pb.grid.d1 * pb.grid.d2)
    before = {k: v for k, v in vars(pb).items() if k != "ops"}
    first = simulation.estimate(pb, _step)
    second = simulation.estimate(pb, _step)
    assert vars(pb).keys() == before.keys() | {"ops"}
    assert all(vars(pb)[k] is v for k, v in before.items())
    assert first["substeps"] == second["substeps"] == 8
    assert first["error"] == second["error"] == pytest.approx(0.0316, abs=5e-4)
    assert first["pairs"] > 0
    # the coarser paths' limits: 1e-5 of the 1 % target, never tighter than the scene's
    assert simulation.coarse_limits(pb).tol == pytest.approx(1e-7)
    assert pb.limits.tol == 1e-10
