"""Long runs are estimated before they start: 10⁶ steps or 10⁵ fretting cycles are
refused in well under a second, naming the estimate and the key that lifts the cap
(``solver.max_hours``), not left to run for hours."""
import time

import pytest

import contactpipe as cp
import contactpipe.simulation.march as simulation
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.planning.resources import (
    DEFAULT_MAX_HOURS,
    PAIR_COST_S,
    TYPICAL_PAIRS,
    check_resources,
    estimate_resources,
)
from contactpipe.testing import TINY_SCENES, tiny_scene

PLENTY = 2 ** 50          # bytes: the memory check out of the way


@pytest.fixture
def no_run(monkeypatch):
    """Fail the test if a run gets past its checks (the march is its first work)."""
    def refuse(*args, **kwargs):
        raise AssertionError("the run started")
    monkeypatch.setattr(simulation, "_march", refuse)


def test_a_million_steps_are_refused_before_the_run(no_run, tmp_path):
    """tiny-fretting (24², coupled, Maxwell; the vector form, as auto picks for a
    frictional preload on a coupled pair) at 10⁶ steps: estimated at about 5.5 h (2.5 x
    the floor pairs, 30 a step, each 0.25 ms beyond its transforms); measured 9.9 ms a
    step at 200 steps on a quiet machine, so about 2.8 h: the estimate is at least that
    and at most 2.5 times it. Refused by cp.simulate within a second."""
    s = tiny_scene("fretting", **{"time.steps": 10 ** 6})
    t0 = time.perf_counter()
    with pytest.raises(cp.SceneError) as err:
        cp.simulate(s, tmp_path / "long.nc")        # streamed: the memory would do
    assert time.perf_counter() - t0 < 1.0
    text = str(err.value)
    assert text.startswith("the run is estimated to take about ")
    assert "1000001 instants on 24x24 cells" in text
    assert "above the cap solver.max_hours = 1 h; set solver.max_hours = " in text
    assert "\n" not in text
    res = estimate_resources(s)
    assert 2.8 * 3600 < res.estimated_seconds < 2.5 * 2.8 * 3600
    # what the estimate is made of: the floor's FFT time, the pairs' cost beyond it
    fft = res.seconds                                   # no history sum here
    assert res.estimated_seconds == pytest.approx(
        TYPICAL_PAIRS * (fft + res.fft_pairs * PAIR_COST_S), rel=1e-12)


def test_the_cap_is_lifted_by_solver_max_hours(no_run, tmp_path):
    s = tiny_scene("fretting", **{"time.steps": 10 ** 6, "solver.max_hours": 12.0})
    assert s.solver.max_hours == 12.0
    res = check_resources(estimate_resources(s), available=PLENTY,
                          max_hours=s.solver.max_hours)
    assert res.estimated_seconds > DEFAULT_MAX_HOURS * 3600
    with pytest.raises(AssertionError, match="the run started"):   # validated, not run
        cp.simulate(s, tmp_path / "long.nc")
    # the default leaves the digest alone; a value changes it (a solver option)
    plain = tiny_scene("fretting")
    assert tiny_scene("fretting", **{"solver.max_hours": None}).digest() == plain.digest()
    assert "max_hours" not in plain.to_toml()


@pytest.mark.parametrize("value", [0.0, -1.0])
def test_max_hours_must_be_positive(value):
    with pytest.raises(cp.SceneError, match=r"solver\.max_hours must be a finite number > 0"):
        tiny_scene("creep", **{"solver.max_hours": value})


def test_a_hundred_thousand_fretting_cycles_are_refused(no_run, tmp_path):
    """10⁵ cycles of the fretting preset on tiny-fretting: 400 001 steps, estimated above
    the 1 h cap."""
    s = tiny_scene("fretting", **{"load.time": None, "load.tangential_force": None,
                                  "load.fretting": {"amplitude": 90.0, "window": 1.0,
                                                    "cycles": 100_000},
                                  "time.steps": None})
    assert s.time.steps == 400_001
    t0 = time.perf_counter()
    with pytest.raises(cp.SceneError, match="solver.max_hours"):
        cp.simulate(s, tmp_path / "long.nc")
    assert time.perf_counter() - t0 < 5.0        # the plan reads 400 002 knots


def test_a_table_grows_quadratically_with_the_steps():
    """A tabulated creep function sums its whole history at every step: k terms at step
    k, steps (steps + 1) / 2 in all; 10⁶ steps are refused (here by the time, 16 days of
    the sum's floor alone, with the memory check out of the way)."""
    tab = tiny_scene("creep", **{"halfspace.creep": "tabulated",
                                 "halfspace.relaxation_time": None,
                                 "halfspace.table": [[0.0, 1.0], [1.0, 2.0]]})
    for steps in (10, 1000):
        res = estimate_resources(tab.replace({"time.steps": steps}))
        assert res.history_terms == steps * (steps + 1) / 2
    exp = estimate_resources(tiny_scene("creep", **{"time.steps": 1000}))
    assert exp.history_terms == 0
    big = tab.replace({"time.steps": 10 ** 6})
    res = estimate_resources(big)
    assert res.seconds > 10 * 86400
    with pytest.raises(cp.SceneError, match=r"days .*direct history sum of 5e\+11 array terms"
                                            r".*a creep law of exponentials"):
        check_resources(res, available=PLENTY)


def test_cli_run_refuses_with_exit_2(tmp_path, no_run, capsys):
    f = tmp_path / "long.toml"
    f.write_text(TINY_SCENES["fretting"].replace("steps = 20", "steps = 1000000"))
    assert cli_main(["run", str(f), "-o", str(tmp_path / "out.nc"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "solver.max_hours" in err
    assert not (tmp_path / "out.nc").exists()


def test_a_sweep_refuses_a_long_member_before_any_work(tmp_path):
    out = tmp_path / "sweep"
    with pytest.raises(cp.SceneError, match=r"^member time\.steps=1000000: the run is "
                                            r"estimated to take about .*solver\.max_hours"):
        cp.sweep(tiny_scene("creep"), {"time.steps": [10, 10 ** 6]}, out,
                 scheduler="synchronous", progress=False)
    assert not out.exists()
