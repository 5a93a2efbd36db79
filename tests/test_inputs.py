"""The pipeline's lowest modules: what the stages read from an archive
(:mod:`contactpipe.pipeline.inputs`), the closed-form lookup
(:mod:`contactpipe.pipeline.compare.reference`) and the sweep's members and derived parameters."""
import math

import numpy as np
import pytest

import contactpipe as cp
from contactpipe.exceptions import ArchiveError, SceneError
from contactpipe.pipeline.compare.reference import (
    cell_average_field,
    diagnose,
    no_closed_form_message,
)
from contactpipe.pipeline.inputs import grid_of, radius_of_area, scene_digest, scene_of
from contactpipe.pipeline.sweep.members import build_members, dim_names
from contactpipe.pipeline.sweep.parameters import registered
from contactpipe.testing import tiny_scene


@pytest.fixture(scope="module")
def creep(tmp_path_factory):
    path = tmp_path_factory.mktemp("inputs") / "creep.nc"
    return tiny_scene("creep"), cp.simulate(tiny_scene("creep"), path), path


def test_scene_of(creep):
    scene, ds, path = creep
    assert scene_of(scene) is scene
    assert scene_of(ds) == scene and scene_of(path) == scene
    assert scene_digest(path) == scene_digest(ds) == scene.digest()
    with pytest.raises(ArchiveError, match="no 'scene' attribute"):
        scene_of(ds.drop_attrs())
    bad = ds.copy()
    bad.attrs["scene"] = "name = 1\n[geometry]\nshape = 'cube'\n"
    with pytest.raises(ArchiveError, match="'scene' attribute is not a valid scene"):
        scene_of(bad)
    with pytest.raises(ArchiveError, match="no such archive"):
        scene_of(path.with_name("absent.nc"))


def test_grid_of(creep):
    scene, ds, _ = creep
    x1, x2, d1, d2 = grid_of(ds)
    assert (d1, d2) == pytest.approx(scene.resolved_grid().spacing(), rel=1e-12)
    # one cell along x2: the spacing comes from the attribute, else from the scene
    row = ds.isel(x2=[12])
    assert grid_of(row)[3] == pytest.approx(d2, rel=1e-12)
    row.attrs.pop("grid_spacing_m", None)
    assert grid_of(row)[3] == pytest.approx(d2, rel=1e-12)


def test_radius_of_area():
    assert radius_of_area(math.pi * 4.0) == pytest.approx(2.0, rel=1e-15)
    assert radius_of_area(-1e-30) == 0.0


def test_diagnose_says_why_each_closed_form_does_not_apply():
    assert diagnose(tiny_scene("creep")) == ("lee_radok", {
        "hertz": ["needs elastic or rigid bodies, got indenter.material = 'rigid', "
                  "halfspace.material = 'viscoelastic'"],
        "flat_punch": ["needs geometry.shape = 'flat_punch', got 'sphere'",
                       "needs elastic or rigid bodies, got indenter.material = 'rigid', "
                       "halfspace.material = 'viscoelastic'"]})
    scene = tiny_scene("fretting")
    name, why = diagnose(scene)
    assert name is None and set(why) == {"hertz", "flat_punch", "lee_radok",
                                         "mindlin_deresiewicz", "hertz_tilted",
                                         "lubkin_torsion", "mindlin_displacement"}
    msg = no_closed_form_message(scene, why, "run.nc")
    assert msg.startswith("run.nc: no closed form applies (nearest: hertz needs elastic "
                          "or rigid bodies (+1 more))")
    assert "contactpipe compare ARCHIVE.nc REFERENCE.nc" in msg and "\n" not in msg
    assert len(msg) < 200


def test_cell_average_field():
    x = (np.arange(8) - 3.5) * 0.25
    out = cell_average_field(lambda a, b: 2.0 + 0 * a * b, x, x, 0.25, 0.25, radius=0.4)
    inside = (np.abs(x)[:, None] - 0.125 < 0.4) & (np.abs(x)[None, :] - 0.125 < 0.4)
    np.testing.assert_allclose(out[inside], 2.0, rtol=1e-12)
    assert np.all(out[~inside] == 0.0)


def test_members_and_the_users_derived_parameters():
    base = tiny_scene("creep")
    assert registered("tau_ratio") is not None and registered("nope") is None
    names, values, funcs, members = build_members(
        base, {"friction.mu": [0.0, 0.1], "halfspace.relaxation_time": [1.0]}, "product")
    assert [m.values for m in members] == [
        {"friction.mu": 0.0, "halfspace.relaxation_time": 1.0},
        {"friction.mu": 0.1, "halfspace.relaxation_time": 1.0}]
    assert all(m.file == f"{m.scene.digest()}.nc" for m in members)
    assert dim_names(names) == {"friction.mu": "mu",
                                "halfspace.relaxation_time": "relaxation_time"}
    assert dim_names(["indenter.young", "halfspace.young"]) == {
        "indenter.young": "indenter_young", "halfspace.young": "halfspace_young"}

    def wrong_type(scene, value):
        return scene.replace({"load.normal_force": value * "x"})

    with pytest.raises(SceneError, match="axis w=2: TypeError"):
        build_members(base, {"w": ([2.0], wrong_type)}, "product")

    def buggy(scene, value):
        return {}["no such key"]

    with pytest.raises(KeyError):            # a bug in the user's function is not hidden
        build_members(base, {"w": ([1.0], buggy)}, "product")
