"""Accuracy presets choose the grid and the steps, and the archive says so."""
import numpy as np
import pytest

import contactpipe as cp
from contactpipe.accuracy import PRESETS, resolve_accuracy

from helpers import fretting_scene


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
