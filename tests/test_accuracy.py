"""Accuracy presets choose the grid and the steps, and the archive says so."""
import numpy as np
import pytest
from helpers import fretting_scene

import contactpipe as cp
from contactpipe.planning.accuracy import PRESETS, resolve_accuracy


def test_presets_order_and_choice_recorded():
    base = fretting_scene(n=16, steps=4).replace({"grid.size": "auto"})
    chosen = {}
    for name in ("fast", "balanced", "accurate"):
        sc, note = resolve_accuracy(base.replace({"solver.accuracy": name}))
        chosen[name] = (sc.grid.points[0], sc.time.steps)
        assert name in note and str(sc.grid.points[0]) in note
        # cells across the contact diameter (auto side = 3 a) as the preset asks
        assert sc.grid.points[0] >= PRESETS[name].cells_across_contact * 1.5
    assert chosen["fast"] < chosen["balanced"] < chosen["accurate"]


def test_no_preset_leaves_scene_alone():
    sc = fretting_scene(n=16, steps=4)
    assert resolve_accuracy(sc) == (sc, "")


def test_archive_records_preset():
    sc = fretting_scene(n=16, steps=4).replace({"solver.accuracy": "fast"})
    ds = cp.simulate(sc)
    assert "accuracy preset 'fast'" in ds.attrs["accuracy"]
    assert ds.sizes["x1"] == ds.attrs["grid_points"][0] != 16
    # the archived scene re-runs to the same grid
    again = cp.Scene.from_toml_text(ds.attrs["scene"])
    assert resolve_accuracy(again)[0].grid.points == tuple(ds.attrs["grid_points"])


def test_surface_refuses_preset(tmp_path):
    gap = tmp_path / "g.npy"
    np.save(gap, np.zeros((16, 16)))
    sc = fretting_scene(n=16, steps=4).replace(
        {"geometry": {"shape": "surface", "file": str(gap)}, "solver.accuracy": "fast"})
    with pytest.raises(cp.SceneError, match="accuracy"):
        resolve_accuracy(sc)


def test_preset_reads_the_public_hertz_estimate():
    """The preset counts cells across 2 a_max, a_max = Scene.hertz_semi_axes() (the one
    Hertz size estimate of the package)."""
    sc = fretting_scene(n=16, steps=4).replace({"solver.accuracy": "fast"})
    resolved, _ = resolve_accuracy(sc)
    (a1, _a2), (L1, _L2) = sc.hertz_semi_axes(), sc.grid.size
    n = int(np.ceil(PRESETS["fast"].cells_across_contact * L1 / (2 * a1)))
    assert resolved.grid.points[0] == n + n % 2


@pytest.mark.parametrize("changes, match", [
    # 5 steps per relaxation time over 1e9 relaxation times: beyond the step cap (on the
    # automatic grid: the contact creeps 1e9 times the compliance, off a fixed one)
    ({"halfspace": {"material": "viscoelastic", "young": 210e9, "poisson": 0.3,
                    "creep": "maxwell", "relaxation_time": 1e-9}, "grid.size": "auto"},
     r"solver\.accuracy = 'fast' asks for 5e\+09 time steps .* above the cap of 1000000"),
    # a Kelvin-Voigt body that does not creep within the window (phi_max = 1 - exp(-1e-300)
    # = 0 in floats) against a rigid one: no contact size to count cells across
    ({"indenter": {"material": "rigid"},
      "halfspace": {"material": "viscoelastic", "young": 210e9, "poisson": 0.3,
                    "creep": "kelvin_voigt", "retardation_time": 1e300}},
     r"solver\.accuracy = 'fast': the Hertz estimate of the largest contact gives "
     r"semi-axes \(0\.0, 0\.0\) m"),
])
def test_preset_refuses_what_it_cannot_resolve(changes, match):
    """One SceneError, not a ZeroDivisionError or an OverflowError."""
    sc = fretting_scene(n=16, steps=4).replace({"solver.accuracy": "fast", **changes})
    with pytest.raises(cp.SceneError, match=match):
        resolve_accuracy(sc)
