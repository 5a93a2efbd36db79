"""simulate(): the archive's Dataset (docs/archive.md), streaming archives, options, errors,
CLI run."""
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from helpers import W, fretting_scene

import contactpipe as cp
from contactpipe.materials import maxwell
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.simulation import State
from contactpipe.solver.memory import make_memory

FIELDS = {"p": "Pa", "u3": "m", "h": "m"}
SERIES = {"W": "N", "omega3": "m", "contact_area": "m2", "iterations": "1"}
FRICTIONAL_FIELDS = {"q1": "Pa", "q2": "Pa", "u1": "m", "u2": "m", "s1": "m", "s2": "m"}
FRICTIONAL_SERIES = {"T1": "N", "T2": "N", "omega1": "m", "omega2": "m", "stick_area": "m2",
                     "dissipation": "J"}


def creep_scene(steps=6, **kw):
    return cp.Scene(name="creep", geometry={"shape": "sphere", "radius": 0.018},
                    indenter={"material": "rigid"},
                    halfspace={"material": "viscoelastic", "young": 105e9, "poisson": 0.3,
                               "creep": "maxwell", "relaxation_time": 1.0},
                    load={"time": [0.0, 1.0], "normal_force": W},
                    grid={"points": [24, 24], "size": [2.4e-3, 2.4e-3]}, time={"steps": steps},
                    **kw)


def check_schema(ds, frictional):
    assert tuple(ds.p.dims) == ("time", "x1", "x2")
    for d in ("time", "x1", "x2"):
        assert d in ds.coords and np.all(np.diff(ds[d].values) > 0)
    want = {**FIELDS, **SERIES, **((FRICTIONAL_FIELDS | FRICTIONAL_SERIES) if frictional else {})}
    for name, unit in want.items():
        assert name in ds, name
        assert ds[name].attrs["units"] == unit, name
    assert ds.status.attrs["flag_meanings"] == "separated stick slip"
    for a in ("Conventions", "contactpipe_version", "scene", "models", "wall_time_s"):
        assert a in ds.attrs
    # the scene attribute re-runs the scene
    assert cp.Scene.from_toml_text(ds.attrs["scene"]).to_dict()["load"] is not None


def test_frictionless_dataset_schema():
    ds = cp.simulate(creep_scene())
    check_schema(ds, frictional=False)
    assert "q1" not in ds and "s1" not in ds          # no tangential model ran
    assert ds.attrs["models"].startswith("normal=polonsky_keer, tangential=none")
    assert ds.sizes["time"] == 7


def test_frictional_dataset_schema():
    ds = cp.simulate(fretting_scene(n=32, steps=10))
    check_schema(ds, frictional=True)
    assert "tangential=scalar" in ds.attrs["models"] and "coupling=none" in ds.attrs["models"]
    assert float(ds.T1[1]) == pytest.approx(45.0, rel=1e-9)    # t = 0.1 s on the 0 -> 90 N ramp


def test_archive_round_trip(tmp_path):
    ds = cp.simulate(creep_scene())
    path = cp.save(ds, tmp_path / "a.nc")
    back = cp.open_archive(path)
    assert back.p.chunks is not None                   # lazy, dask-backed
    xr.testing.assert_allclose(ds, back.load())
    assert back.attrs["scene"] == ds.attrs["scene"]


def test_streamed_archive_equals_in_memory(tmp_path):
    a = cp.simulate(creep_scene())
    b = cp.simulate(creep_scene(), tmp_path / "b.nc")
    xr.testing.assert_allclose(a.drop_vars(["iterations", "fft_pairs"]),
                               b.load().drop_vars(["iterations", "fft_pairs"]))


def test_output_stride_and_float32(tmp_path):
    sc = creep_scene(steps=10, output={"stride": 4, "precision": "float32"})
    ds = cp.simulate(sc, tmp_path / "s.nc")
    np.testing.assert_allclose(ds.time.values, [0.0, 0.4, 0.8, 1.0])   # every 4th and the last
    assert ds.p.dtype == np.float32


def test_interrupted_write_leaves_no_file(tmp_path):
    """A run that fails mid-way (contact reaching the grid edge at a later step) leaves
    nothing at the target path and no temporary file."""
    sc = cp.Scene(name="grows", geometry={"shape": "sphere", "radius": 0.018},
                  indenter={"material": "rigid"},
                  halfspace={"material": "viscoelastic", "young": 105e9, "poisson": 0.3,
                             "creep": "maxwell", "relaxation_time": 0.01},
                  load={"time": [0.0, 1.0], "normal_force": W},
                  grid={"points": [16, 16], "size": [1.6e-3, 1.6e-3], "size_check": False},
                  time={"steps": 10})
    target = tmp_path / "x.nc"
    with pytest.raises(cp.GridError, match="edge of the grid"):
        cp.simulate(sc, target)
    assert not target.exists()
    assert list(tmp_path.iterdir()) == []


def test_no_nan_anywhere():
    ds = cp.simulate(fretting_scene(n=24, steps=5))
    for v in ds.data_vars:
        assert np.all(np.isfinite(ds[v].values)), v


def test_cli_run_writes_archive(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(creep_scene().to_toml())
    out = tmp_path / "o.nc"
    assert cli_main(["run", str(scene), "-o", str(out), "--no-progress"]) == 0
    assert cp.open_archive(out).sizes["time"] == 7


def test_cli_bad_scene_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(creep_scene().to_toml().replace("poisson = 0.3", "poisson = 0.7"))
    r = subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", "run", str(bad), "-o",
                        str(tmp_path / "o.nc")], capture_output=True, text=True)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "halfspace.poisson" in lines[0] and "Traceback" not in r.stderr
    assert not (tmp_path / "o.nc").exists()


def test_cli_missing_file(tmp_path):
    r = subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", "run",
                        str(tmp_path / "no.toml"),
                        "-o", str(tmp_path / "o.nc")], capture_output=True, text=True)
    assert r.returncode != 0 and len(r.stderr.strip().splitlines()) == 1


def test_state_round_trips_through_its_arrays():
    """The arrays a checkpoint keeps restore the State of a viscoelastic run exactly."""
    rng = np.random.default_rng(0)
    memories = [None, make_memory(maxwell(1.0), 0.1, "linear", (3, 4, 5))]
    st = State.initial((4, 5), memories)
    assert st.p.shape == (4, 5) and st.q.shape == (2, 4, 5) and st.u.shape == (3, 4, 5)
    assert st.k == -1 and st.dissipation == 0.0 and st.normal is None
    for _ in range(3):
        memories[1].commit(rng.random((3, 4, 5)))
    st.p, st.q, st.u, st.s = rng.random((4, 5)), rng.random((2, 4, 5)), \
        rng.random((3, 4, 5)), rng.random((2, 4, 5))
    st.omega, st.dissipation = rng.random(3), 1.5
    back = State.initial((4, 5), [None, make_memory(maxwell(1.0), 0.1, "linear", (3, 4, 5))])
    back.restore(st.arrays(), 7)
    assert back.k == 7
    for key, value in st.arrays().items():
        np.testing.assert_array_equal(back.arrays()[key], value, err_msg=key)
    with pytest.raises(ValueError, match=r"q has shape \(2, 5, 4\)"):
        back.restore({**st.arrays(), "q": np.zeros((2, 5, 4))}, 7)


def test_on_step_sees_every_instant_and_the_folder_is_made(tmp_path):
    seen = []
    target = tmp_path / "new" / "folder" / "a.nc"
    ds = cp.simulate(creep_scene(steps=4), target, on_step=lambda k, t, rec: seen.append(
        (k, t, sorted(rec))))
    assert [k for k, _, _ in seen] == [0, 1, 2, 3, 4]
    assert seen[0][2] == sorted(["p", "u3", "h", "status", "W", "omega3", "contact_area",
                                 "iterations", "fft_pairs",
                                 "M1", "M2", "M3", "phi1", "phi2", "phi3"])
    assert ds.sizes["time"] == 5 and target.exists()
