"""Fretting wear over many cycles ([wear]): the scene's checks, the wear laws' energy
identities with cycle jumps, the worn gap, the archive's history over ``cycle``, the kept
loops of tractions, cycle jumping against every-cycle simulation (elastic and Zener), and
that an interrupted wear run writes nothing.

The elastic case: a rigid sphere R = 10 mm on a steel-like half-space (E = 200 GPa,
ν = 0.3), W = 100 N, μ = 0.5, T = 0 → 40 → 0 → −40 → 0 N (partial slip) per 1 s cycle in
8 steps, on 16 x 16 cells of a 0.7 mm square (a = 0.15 mm).
"""
import math

import numpy as np
import pytest

import contactpipe as cp
from contactpipe.archive import open_archive, validate

MU_ = 0.5
BASE = {
    "name": "wear",
    "geometry": {"shape": "sphere", "radius": 0.01},
    "indenter": {"material": "rigid"},
    "halfspace": {"material": "elastic", "young": 200e9, "poisson": 0.3},
    "friction": {"mu": MU_},
    "load": {"time": [0.0, 0.25, 0.5, 0.75, 1.0], "normal_force": 100.0,
             "tangential_force": [0.0, 40.0, 0.0, -40.0, 0.0]},
    "grid": {"points": [16, 16], "size": [7e-4, 7e-4]},
    "time": {"steps": 8},
}
#: a rigid ball on a Zener polymer (E0 = 4 GPa, E∞ = 1 GPa, τ = 2 s): W = 10 N, ±3 N
ZENER = {**BASE,
         "halfspace": {"material": "viscoelastic", "young": 4e9, "poisson": 0.3,
                       "creep": "zener", "relaxed_young": 1e9, "retardation_time": 2.0},
         "load": {"time": [0.0, 0.25, 0.5, 0.75, 1.0], "normal_force": 10.0,
                  "tangential_force": [0.0, 3.0, 0.0, -3.0, 0.0]},
         "grid": {"points": [16, 16], "size": [2e-3, 2e-3]}}


def scene(base=BASE, **wear):
    return cp.Scene(**base, wear={"coefficient": 2e-13, "cycles": 20, **wear})


# ----------------------------------------------------------------------------- the scene

@pytest.mark.parametrize("change, key", [
    ({"coefficient": -1e-14}, "wear.coefficient"),
    ({"coefficient": math.inf}, "wear.coefficient"),
    ({"coefficient": [1e-14, math.nan]}, "wear.coefficient"),
    ({"coefficient": [1e-14, -1e-14]}, "wear.coefficient"),
    ({"coefficient": "big"}, "wear.coefficient"),
    ({"cycles": 0}, "wear.cycles"),
    ({"cycles": 2.5}, "wear.cycles"),
    ({"cycles": 10 ** 10}, "wear.cycles"),
    ({"jump": 0}, "wear.jump"),
    ({"jump": "often"}, "wear.jump"),
    ({"jump": 2.5}, "wear.jump"),
    ({"law": "usury"}, "wear.law"),
    ({"keep_tractions": -1}, "wear.keep_tractions"),
])
def test_bad_wear_keys_get_one_line_naming_the_key(change, key):
    with pytest.raises(cp.SceneError) as e:
        scene(**change)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(key), msg


def test_a_program_that_does_not_close_is_refused():
    load = {**BASE["load"], "tangential_force": [0.0, 40.0, 0.0, -40.0, -10.0]}
    with pytest.raises(cp.SceneError) as e:
        scene({**BASE, "load": load})
    msg = str(e.value)
    assert "\n" not in msg and "load.tangential_force" in msg and "end where it starts" in msg
    approach = {"time": [0.0, 1.0], "normal_approach": [1e-6, 2e-6]}
    with pytest.raises(cp.SceneError, match="load.normal_approach"):
        scene({**BASE, "load": approach})


def test_wear_without_friction_is_refused():
    no_friction = {**BASE, "friction": None,
                   "load": {"time": [0.0, 1.0], "normal_force": 100.0}}
    with pytest.raises(cp.SceneError) as e:
        scene(no_friction)
    assert "\n" not in str(e.value) and "[wear] needs friction" in str(e.value)


def test_a_jump_over_a_tabulated_creep_function_is_refused():
    table = {"material": "viscoelastic", "young": 4e9, "poisson": 0.3,
             "creep": "tabulated", "table": [[0.0, 1.0], [1.0, 2.0], [100.0, 4.0]]}
    with pytest.raises(cp.SceneError) as e:
        scene({**ZENER, "halfspace": table}, jump=5)
    assert "\n" not in str(e.value) and str(e.value).startswith("wear.jump = 5")
    assert scene({**ZENER, "halfspace": table}, jump=1).wear.jump == 1


def test_wear_table_round_trips_and_is_absent_otherwise():
    s = scene(law="energy", coefficient=[1e-14, 3e-14], jump=7, keep_tractions=2)
    assert cp.Scene.from_toml_text(s.to_toml()) == s
    assert s.wear.coefficients == (1e-14, 3e-14)
    plain = cp.Scene(**BASE)
    assert plain.wear is None and "wear" not in plain.to_dict()


# ----------------------------------------------------------------------------- identities

def _identity_error(ds, k_sum, law):
    """Largest relative departure of worn_volume from its dissipation identity (exact
    up to the solver's tolerance, and the jumps extrapolate both alike: measured 2e-16
    to 1e-15; asserted below 1e-6, within the issue's 1 %)."""
    factor = k_sum / MU_ if law == "archard" else k_sum
    V = ds.worn_volume.values
    E = ds.cumulative_dissipation.values
    return float(np.max(np.abs(V - factor * E)) / V[-1])


def test_archard_identity_with_jumps():
    ds = cp.simulate(scene(cycles=30, jump=7))
    # the first cycle (a start-up from the unloaded state) is never jumped from
    assert ds.attrs["cycles_simulated"] == 6 and ds.attrs["wear_law"] == "archard"
    assert list(ds.cycle.values) == [1, 2, 9, 16, 23, 30]
    assert _identity_error(ds, 2e-13, "archard") < 1e-6
    assert np.all(np.diff(ds.worn_volume.values) > 0)
    assert "wear=archard" in ds.attrs["models"]
    assert validate(ds) == []


@pytest.mark.parametrize("k", [3e-13, [1e-13, 2e-13]])
def test_energy_identity_one_body_and_both(k):
    ds = cp.simulate(scene(law="energy", coefficient=k, cycles=30, jump=4))
    k_sum = float(np.sum(k))
    assert _identity_error(ds, k_sum, "energy") < 1e-6
    assert ds.attrs["cycles_simulated"] == 9


def test_gross_slip_under_displacement_control():
    """Imposed ω1 = 0 → 3 µm → 0 → −3 µm → 0 slides the whole contact; Archard's
    identity holds and the centre wears (it slips)."""
    load = {"time": [0.0, 0.25, 0.5, 0.75, 1.0], "normal_force": 100.0,
            "tangential_displacement": [0.0, 3e-6, 0.0, -3e-6, 0.0]}
    ds = cp.simulate(scene({**BASE, "load": load}, cycles=12, jump=3))
    assert _identity_error(ds, 2e-13, "archard") < 1e-6
    depth = ds.wear_depth.values[-1]
    assert depth[8, 8] > 0.5 * depth.max()            # the centre cell slides too
    assert float(ds.stick_area.min()) == 0.0


def test_worn_depth_opens_the_gap():
    """The normal force dips to 40 N mid-cycle, and the worn slip annulus lifts off (24 x
    24 cells of 0.5 mm: 68 worn cells): there the archive's gap is hi + wear_depth + u3 −
    ω3, the worn depth lying between its records at the ends of cycles 5 and 6 (an unworn
    gap would be short by it)."""
    load = {**BASE["load"], "normal_force": [100.0, 100.0, 40.0, 100.0, 100.0]}
    grid = {"points": [24, 24], "size": [5e-4, 5e-4]}
    ds = cp.simulate(scene({**BASE, "load": load, "grid": grid}, cycles=6, jump=1))
    assert list(ds.cycle.values) == [1, 2, 3, 4, 5, 6]
    hi = cp.Scene(**BASE).geometry.gap(ds.x1.values, ds.x2.values)
    mid = ds.sel(time=5.5)
    out = mid.p.values == 0
    base = hi + mid.u3.values - float(mid.omega3)
    low, high = base + ds.wear_depth.values[-2], base + ds.wear_depth.values[-1]
    lifted = out & (ds.wear_depth.values[-2] > 0.2 * ds.wear_depth.values[-2].max())
    assert lifted.sum() >= 40
    h = mid.h.values[lifted]
    assert np.all(h >= low[lifted] - 1e-13) and np.all(h <= high[lifted] + 1e-13)
    assert np.all(h - base[lifted] > 0.5 * ds.wear_depth.values[-2][lifted])


# ----------------------------------------------------------------------------- the archive

def test_archive_of_a_wear_run(tmp_path):
    path = tmp_path / "wear.nc"
    ds = cp.simulate(scene(cycles=9, jump=2, keep_tractions=3), path)
    back = open_archive(path)
    assert back.attrs["complete"] == "true" and int(back.attrs["cycles_simulated"]) == 6
    assert list(back.cycle.values) == [1, 2, 4, 6, 8, 9]
    assert back.cycle.values[0] == 1 and back.cycle.values[-1] == 9
    assert back.wear_depth.dims == ("cycle", "x1", "x2")
    assert back.wear_depth.attrs["units"] == "m" and back.worn_volume.attrs["units"] == "m3"
    # the last simulated cycle (cycle 9) over time, absolute from t0: 8 s .. 9 s
    assert np.allclose(back.time.values, 8.0 + np.linspace(0.0, 1.0, 9))
    cell = float(np.diff(back.x1)[0] * np.diff(back.x2)[0])
    assert np.allclose(back.worn_volume, back.wear_depth.sum(("x1", "x2")) * cell, rtol=1e-12)
    # the kept loops: cycles 1, 4 (the first simulated at or after the target 3) and 9
    assert list(back.loop_cycle.values) == [1, 4, 9]
    assert back.loop_p.dims == ("loop_cycle", "loop_time", "x1", "x2")
    assert np.allclose(back.loop_time.values, np.linspace(0.0, 1.0, 9))
    assert np.array_equal(back.loop_p.values[-1], back.p.values)
    assert np.array_equal(back.loop_q1.values[-1], back.q1.values)
    assert float(back.cycle_p_max[-1]) == pytest.approx(float(back.p.max()), rel=1e-12)
    assert float(back.cycle_stick_area[-1]) == pytest.approx(float(back.stick_area.min()))
    assert float(ds.worn_volume[-1]) == float(back.worn_volume[-1])


def test_records_are_log_spaced_besides_the_jumps(monkeypatch):
    from contactpipe.simulation import cycles
    marks = sorted(cycles.record_cycles(100_000))
    assert marks[0] == 1 and marks[-1] == 100_000 and len(marks) <= cycles.RECORDS
    ratios = np.array(marks[1:]) / np.array(marks[:-1])
    assert ratios[-10:].max() < 1.2                       # 10^(5/99) = 1.12 apart
    assert cycles.record_cycles(40) == set(range(1, 41))
    monkeypatch.setattr(cycles, "RECORDS", 6)             # 6 records of 20 cycles
    coarse = {**BASE, "grid": {"points": [12, 12], "size": [6e-4, 6e-4]},
              "time": {"steps": 4}}
    ds = cp.simulate(scene(coarse, cycles=20, jump=1))    # every cycle simulated
    assert list(ds.cycle.values) == [1, 2, 3, 6, 11, 20]
    assert ds.attrs["cycles_simulated"] == 20
    jumped = cp.simulate(scene(coarse, cycles=20, jump=8))   # and each cycle a jump leaves
    assert list(jumped.cycle.values) == [1, 2, 10, 18, 20]


def test_an_interrupted_wear_run_writes_nothing(tmp_path):
    path = tmp_path / "wear.nc"

    def stop(k, t, record):
        if t > 2.5:
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        cp.simulate(scene(cycles=6, jump=1), path, on_step=stop)
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- cycle jumps

def _against_every_cycle(base, **wear):
    auto = cp.simulate(scene(base, jump="auto", **wear))
    every = cp.simulate(scene(base, jump=1, **wear))
    da, de = auto.wear_depth.values[-1], every.wear_depth.values[-1]
    depth_err = float(np.abs(da - de).max() / de.max())
    volume_err = abs(float(auto.worn_volume[-1]) / float(every.worn_volume[-1]) - 1)
    return auto, every, depth_err, volume_err


@pytest.mark.slow
def test_auto_jump_against_every_cycle_elastic():
    """300 cycles, k = 2e-13 1/Pa: measured 34 cycles simulated, depth within 0.29 % of
    its maximum, volume within 0.29 %."""
    auto, every, depth_err, volume_err = _against_every_cycle(BASE, cycles=300)
    assert every.attrs["cycles_simulated"] == 300
    assert auto.attrs["cycles_simulated"] <= 60
    assert depth_err < 0.02 and volume_err < 0.01
    assert _identity_error(auto, 2e-13, "archard") < 1e-6


@pytest.mark.slow
def test_zener_wear_against_every_cycle():
    """A rigid ball on a Zener polymer, energy law, 60 cycles of 1 s (τ = 2 s: the creep
    settles over the first cycles): measured 22 cycles simulated, volume within 0.8 %,
    depth within 2 % of its maximum; the identity holds with jumps."""
    auto, every, depth_err, volume_err = _against_every_cycle(
        ZENER, law="energy", coefficient=2e-12, cycles=60)
    assert auto.attrs["cycles_simulated"] < 40
    assert depth_err < 0.02 and volume_err < 0.01
    assert _identity_error(auto, 2e-12, "energy") < 1e-6
    assert float(auto.omega3[-1]) == pytest.approx(float(every.omega3[-1]), rel=1e-3)


def test_zener_wear_runs_with_fixed_jumps():
    """The Zener ball with jump = 3 over 13 cycles (1, 2, 5, 8, 11, 13 simulated): the
    identity holds, and the memory advanced over the jumps leaves the approach and the
    pressure of the last cycle close to every-cycle simulation (measured: 0.37 % and
    0.34 % of p_max). The worn volume of a fixed jump through the creep's start-up
    (τ = 2 s: the wear rate falls by half over the first cycles) is 10 % high, which
    is what jump = "auto" is for (test_zener_wear_against_every_cycle)."""
    jumped = cp.simulate(scene(ZENER, law="energy", coefficient=2e-12, cycles=13, jump=3))
    every = cp.simulate(scene(ZENER, law="energy", coefficient=2e-12, cycles=13, jump=1))
    assert jumped.attrs["cycles_simulated"] == 6
    assert _identity_error(jumped, 2e-12, "energy") < 1e-6
    assert float(jumped.omega3[-1]) == pytest.approx(float(every.omega3[-1]), rel=5e-3)
    p_err = np.abs(jumped.p.values[-1] - every.p.values[-1]).max() / every.p.values.max()
    assert p_err < 0.01


def test_a_wear_run_resumes_from_its_checkpoint(tmp_path):
    """Interrupted inside cycle 8 (cycles 1, 2, 5, 8, 11, 12 simulated), a resumable
    wear run checkpoints the state it reached after cycle 7 and writes nothing; run
    again, it resumes there and ends with what an uninterrupted run gives."""
    from contactpipe.exceptions import ResumeNotice
    path = tmp_path / "wear.nc"
    s = scene(cycles=12, jump=3, keep_tractions=3)

    def stop(k, t, record):
        if t > 7.3:
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt) as e:
        cp.simulate(s, path, resume=True, on_step=stop)
    assert e.value.resume_from == "cycle 8 of 12"
    assert not path.exists() and (tmp_path / ".wear.nc.ckpt.npz").is_file()
    with pytest.warns(ResumeNotice, match="after cycle 7 of 12"):
        resumed = cp.simulate(s, path, resume=True)
    whole = cp.simulate(s)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wear.nc"]
    assert int(resumed.attrs["cycles_simulated"]) == whole.attrs["cycles_simulated"] == 6
    assert list(resumed.cycle.values) == list(whole.cycle.values) == [1, 2, 5, 8, 11, 12]
    assert list(resumed.loop_cycle.values) == list(whole.loop_cycle.values)
    scale = float(whole.wear_depth.max())
    assert np.abs(resumed.wear_depth.values - whole.wear_depth.values).max() < 1e-6 * scale
    assert np.allclose(resumed.cumulative_dissipation, whole.cumulative_dissipation,
                       rtol=1e-6)
    assert np.allclose(resumed.p, whole.p, rtol=0, atol=1e-6 * float(whole.p.max()))


def test_maxwell_creep_goes_on_over_the_jumps():
    """A rigid ball on a Maxwell polymer (E = 4 GPa, t' = 20 s) creeps on under its
    constant W: the dashpot's integral advanced over the jumps keeps the approach of the
    last cycle within 1e-3 of every-cycle simulation (measured 6.6e-5; left as it is,
    12.7 % short), while the ball sinks by 1.8 % over the run."""
    maxwell = {**ZENER, "grid": {"points": [16, 16], "size": [3e-3, 3e-3]},
               "halfspace": {"material": "viscoelastic", "young": 4e9, "poisson": 0.3,
                             "creep": "maxwell", "relaxation_time": 20.0}}
    every = cp.simulate(scene(maxwell, law="energy", coefficient=1e-13, cycles=13, jump=1))
    jumped = cp.simulate(scene(maxwell, law="energy", coefficient=1e-13, cycles=13, jump=3))
    assert jumped.attrs["cycles_simulated"] == 6
    w_every, w_jumped = float(every.omega3[-1]), float(jumped.omega3[-1])
    assert abs(w_jumped / w_every - 1) < 1e-3
    assert w_every - float(every.omega3[0]) > 0.015 * w_every
    assert _identity_error(jumped, 1e-13, "energy") < 1e-6


def test_the_progress_bar_counts_cycles_and_shows_the_jump(capsys):
    """30 cycles at jump 7 (simulated: 1, 2, 9, 16, 23, 30): the bar ends at 30/30 cycles,
    not at instants, and names the last jump taken."""
    cp.simulate(scene(cycles=30, jump=7), progress=True)
    err = capsys.readouterr().err
    last = err.replace("\r", "\n").strip().splitlines()[-1]
    assert "30/30" in last and "cycle" in last
    assert "jump=7" in last


def test_a_worn_rough_surface_keeps_its_initial_gap():
    """A wear run on a generated rough surface (16², 8 steps a cycle, 12 cycles, jump 3)
    archives ``h0`` like any rough run: the unworn gap the scene generates, not the worn
    one the run ends with."""
    rough = {**BASE, "geometry": {"shape": "rough", "hurst": 0.8, "rms_slope": 0.01,
                                  "wavelengths": [3e-4, 1.2e-4], "seed": 4,
                                  "form": "sphere", "radius": 0.01}}
    sc = scene(rough, cycles=12, jump=3)
    ds = cp.simulate(sc)
    gap = sc.geometry.gap(ds.x1.values, ds.x2.values)
    assert "h0" in ds and float(ds.wear_depth[-1].max()) > 0
    np.testing.assert_array_equal(ds.h0.values, gap)
    assert validate(ds) == []
