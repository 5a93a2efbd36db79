"""Sweeps: dask execution, t_norm alignment, resume after a kill, corrupt members, failures,
zip mode, derived parameters, validation, locking, sweep files."""
import fcntl
import importlib
import json
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from contactpipe.archive import open_archive
from contactpipe.exceptions import ArchiveError, SceneError
from contactpipe.pipeline import cli
from contactpipe.pipeline.sweep import (
    SweepLockedError,
    open_sweep,
    register_parameter,
    sweep,
    with_window,
)
from contactpipe.pipeline.sweep.config import load_sweep_file, read_sweep_file
from contactpipe.scene import Scene
from contactpipe.testing import TINY_SCENES

ROOT = pathlib.Path(__file__).resolve().parents[1]

# the module (``contactpipe.pipeline.sweep`` the attribute is the function)
sweep_mod = importlib.import_module("contactpipe.pipeline.sweep.driver")
parameters_mod = importlib.import_module("contactpipe.pipeline.sweep.parameters")

# the 24 x 24 scenes of shared/examples, as contactpipe.testing carries them
FRETTING = TINY_SCENES["fretting"]

CREEP = TINY_SCENES["creep"]

# 1e5 N puts the contact of tiny-creep off its 2.4 mm grid: GridError at the first step
TOO_BIG = 1.0e5


@pytest.fixture(scope="module")
def client():
    """A real LocalCluster: two worker processes, one thread each."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture
def fretting():
    return Scene.from_toml_text(FRETTING)


@pytest.fixture
def creep():
    return Scene.from_toml_text(CREEP)


@pytest.fixture
def registry():
    """Restore the derived-parameter registry after a test registers one."""
    saved = dict(parameters_mod._PARAMETERS)
    yield
    parameters_mod._PARAMETERS.clear()
    parameters_mod._PARAMETERS.update(saved)


def stamps(folder):
    """{name: (inode, mtime_ns)} of the member archives in ``folder``."""
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns)
            for p in pathlib.Path(folder).glob("*.nc")}


def leftovers(folder):
    return sorted(p.name for p in pathlib.Path(folder).iterdir() if p.name.endswith(".part"))


# ----------------------------------------------------------------------- distribution

def test_local_cluster_tau_ratio_by_mu(client, fretting, tmp_path):
    out = tmp_path / "runs"
    axes = {"tau_ratio": [0.5, 1.0], "friction.mu": [0.1, 0.2]}
    res = sweep(fretting, axes, out, client=client, progress=False)
    assert res.ok, [str(m) for m in res.failed]
    assert len(res.computed) == 4 and not res.skipped
    # member archives are named by the digest of their scene
    for tau in (0.5, 1.0):
        for mu in (0.1, 0.2):
            scene = with_window(fretting.replace({"friction.mu": mu}), tau * 1.0)
            assert (out / f"{scene.digest()}.nc").is_file()
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["mode"] == "product"
    assert manifest["axes"] == {"tau_ratio": [0.5, 1.0], "friction.mu": [0.1, 0.2]}
    assert manifest["dims"] == {"tau_ratio": "tau_ratio", "friction.mu": "mu"}
    assert Scene.from_toml_text(manifest["base_scene"]) == fretting
    assert [m["status"] for m in manifest["members"]] == ["done"] * 4
    assert all(m["file"] == m["digest"] + ".nc" and m["wall_time_s"] > 0
               for m in manifest["members"])
    assert [m["values"] for m in manifest["members"]] == [
        {"tau_ratio": 0.5, "friction.mu": 0.1}, {"tau_ratio": 0.5, "friction.mu": 0.2},
        {"tau_ratio": 1.0, "friction.mu": 0.1}, {"tau_ratio": 1.0, "friction.mu": 0.2}]

    sw = open_sweep(out)
    try:
        assert sw["p"].dims == ("tau_ratio", "mu", "t_norm", "x1", "x2")
        assert sw["W"].dims == ("tau_ratio", "mu", "t_norm")
        np.testing.assert_array_equal(sw["tau_ratio"].values, [0.5, 1.0])
        np.testing.assert_array_equal(sw["mu"].values, [0.1, 0.2])
        np.testing.assert_allclose(sw["t_norm"].values, np.linspace(0, 1, 21), atol=1e-12)
        assert sw["t_norm"].attrs["units"] == "1"
        # each member keeps its own time: the window is tau_ratio x relaxation time (1 s)
        assert "time" in sw.coords and "tau_ratio" in sw["time"].dims
        np.testing.assert_allclose(sw["time"].sel(tau_ratio=0.5).values,
                                   np.linspace(0, 0.5, 21), atol=1e-12)
        np.testing.assert_allclose(sw["time"].sel(tau_ratio=1.0).values,
                                   np.linspace(0, 1.0, 21), atol=1e-12)
        assert sw["p"].chunks is not None                     # still lazy
        assert sw.attrs["sweep_mode"] == "product"
        assert json.loads(sw.attrs["sweep_axes"]) == manifest["axes"]
        assert sw.attrs["base_scene"] == manifest["base_scene"]
        # one member, back from the combined dataset, equals its own archive
        digest = str(sw["digest"].sel(tau_ratio=0.5, mu=0.2).values)
        one = open_archive(out / f"{digest}.nc")
        np.testing.assert_array_equal(sw["p"].sel(tau_ratio=0.5, mu=0.2).values,
                                      one["p"].values)
        np.testing.assert_array_equal(sw["status"].sel(tau_ratio=0.5, mu=0.2).values,
                                      one["status"].values)
        assert sw["status"].dtype == np.int8
        one.close()
        # the fretting loop reaches the same normalised instants in both windows
        assert float(sw["T1"].sel(tau_ratio=0.5, mu=0.1).isel(t_norm=4)) == \
            pytest.approx(90.0, rel=1e-6)
    finally:
        sw.close()

    # idempotent: a second run skips every member and rewrites nothing
    before = stamps(out)
    again = sweep(fretting, axes, out, client=client, progress=False)
    assert again.ok and not again.computed and len(again.skipped) == 4
    assert stamps(out) == before


KILL_SCRIPT = """
import sys
from contactpipe.scene import Scene
from contactpipe.pipeline.sweep import sweep

if __name__ == "__main__":
    base = Scene.from_toml_text(sys.argv[2]).replace({"time.steps": 60})
    sweep(base, {"friction.mu": [0.10, 0.11, 0.12, 0.13, 0.14, 0.15]}, sys.argv[1],
          n_workers=1, progress=False)
"""


def test_sigkill_mid_sweep_then_resume(client, fretting, tmp_path):
    out = tmp_path / "runs"
    script = tmp_path / "killme.py"
    script.write_text(KILL_SCRIPT)
    proc = subprocess.Popen([sys.executable, str(script), str(out), FRETTING],
                            start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline and proc.poll() is None:
            # kill once an archive has landed and the next member is half-written
            if out.is_dir() and any(out.glob("*.nc")) and any(out.glob(".*.nc.*.part")):
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the sweep ended before it could be killed: " + \
            proc.stderr.read().decode()[-2000:]
        assert any(out.glob("*.nc")), "no member archive landed within 90 s"
        assert any(out.glob(".*.nc.*.part")), "no member was being written"
    finally:
        os.killpg(proc.pid, signal.SIGKILL)          # the sweep, its cluster, its workers
        proc.wait()
    time.sleep(0.2)
    landed = stamps(out)
    assert 1 <= len(landed) < 6, landed
    assert leftovers(out), "the kill should have left a half-written temporary file"
    for name in landed:                              # a landed archive is whole
        open_archive(out / name).close()

    res = sweep(fretting.replace({"time.steps": 60}),
                {"friction.mu": [0.10, 0.11, 0.12, 0.13, 0.14, 0.15]}, out,
                client=client, progress=False)
    assert res.ok, [str(m) for m in res.failed]
    assert {m.file for m in res.skipped} == set(landed)
    assert len(res.computed) == 6 - len(landed)
    after = stamps(out)
    assert len(after) == 6
    assert {k: after[k] for k in landed} == landed   # not recomputed, not rewritten
    for name in after:
        open_archive(out / name).close()
    assert leftovers(out) == []                      # the re-run cleaned the killed temps
    manifest = json.loads((out / "manifest.json").read_text())
    assert [m["status"] for m in manifest["members"]] == ["done"] * 6


# ----------------------------------------------------------------------- corruption

def test_truncated_and_garbage_members_are_recomputed(creep, tmp_path):
    out = tmp_path / "runs"
    axes = {"load.normal_force": [500.0, 1000.0, 1500.0]}
    res = sweep(creep, axes, out, scheduler="synchronous", progress=False)
    assert res.ok and len(res.computed) == 3
    files = [out / m.file for m in res.members]
    truncated, garbage, intact = files
    size = truncated.stat().st_size
    with open(truncated, "r+b") as f:
        f.truncate(size // 2)
    garbage.write_bytes(np.random.default_rng(0).bytes(4096))
    for bad in (truncated, garbage):
        with pytest.raises(ArchiveError, match=bad.name):
            open_archive(bad)
    with pytest.raises(ArchiveError, match=r"sweep member load.normal_force=500 .*"
                                           + truncated.name):
        open_sweep(out)
    kept = intact.stat().st_mtime_ns

    again = sweep(creep, axes, out, scheduler="synchronous", progress=False)
    assert again.ok
    assert sorted(m.file for m in again.computed) == sorted([truncated.name, garbage.name])
    assert [m.file for m in again.skipped] == [intact.name]
    assert intact.stat().st_mtime_ns == kept
    for p in files:
        open_archive(p).close()
    sw = open_sweep(out)
    assert sw["W"].dims == ("normal_force", "time")
    np.testing.assert_allclose(sw["W"].isel(time=-1).values, [500.0, 1000.0, 1500.0],
                               rtol=1e-6)
    sw.close()


# ----------------------------------------------------------------------- failures

def test_failing_member_others_complete_cli_exit_1(client, tmp_path, capsys):
    sweep_file = tmp_path / "sweep.toml"
    inline = CREEP.replace("\n[", "\n[scene.").replace('name = "tiny-creep"',
                                                      '[scene]\nname = "tiny-creep"')
    # left to the run: the member off its grid fails with a GridError, the others land
    inline = inline.replace("size = [2.4e-3, 2.4e-3]",
                            "size = [2.4e-3, 2.4e-3]\nsize_check = false")
    sweep_file.write_text(f'mode = "product"\n{inline}\n[axes]\n'
                          f'load.normal_force = [1000.0, {TOO_BIG}]\n')
    out = tmp_path / "runs"
    code = cli.main(["sweep", str(sweep_file), "-o", str(out), "--no-progress",
                     "--scheduler", client.scheduler.address])
    captured = capsys.readouterr()
    assert code == 1
    assert "1 computed, 0 skipped, 1 failed" in captured.out
    assert "load.normal_force=100000" in captured.err and "GridError" in captured.err
    manifest = json.loads((out / "manifest.json").read_text())
    status = {m["values"]["load.normal_force"]: m for m in manifest["members"]}
    assert status[1000.0]["status"] == "done"
    assert status[TOO_BIG]["status"] == "failed"
    assert status[TOO_BIG]["error"].startswith("GridError: ")
    assert "\n" not in status[TOO_BIG]["error"]
    assert (out / status[1000.0]["file"]).is_file()
    assert not (out / status[TOO_BIG]["file"]).exists()
    assert leftovers(out) == []

    with pytest.raises(ArchiveError, match=r"1 of 2 sweep members are not done.*"
                                           r"load.normal_force=100000.*allow_missing"):
        open_sweep(out)
    sw = open_sweep(out, allow_missing=True)
    np.testing.assert_array_equal(sw["normal_force"].values, [1000.0])
    assert "missing_members" in sw.attrs and "GridError" in sw.attrs["missing_members"]
    sw.close()

    # the Python API says the same
    base, axes, mode = load_sweep_file(sweep_file)
    res = sweep(base, axes, out, scheduler="synchronous", progress=False)
    assert not res.ok
    assert [m.values for m in res.failed] == [{"load.normal_force": TOO_BIG}]
    assert "GridError" in res.failed[0].error
    assert [m.values for m in res.skipped] == [{"load.normal_force": 1000.0}]


# ----------------------------------------------------------------------- zip, derived

def test_zip_mode_with_registered_parameter(creep, tmp_path, registry):
    @register_parameter("load_scale")
    def load_scale(scene, value):
        return scene.replace({"load.normal_force": 1000.0 * value})

    out = tmp_path / "zip"
    axes = {"load_scale": [0.5, 1.0, 2.0], "halfspace.relaxation_time": [1.0, 2.0, 4.0]}
    res = sweep(creep, axes, out, mode="zip", scheduler="synchronous", progress=False)
    assert res.ok and len(res.computed) == 3
    sw = open_sweep(out)
    assert sw["p"].dims == ("member", "time", "x1", "x2")
    np.testing.assert_array_equal(sw["load_scale"].values, [0.5, 1.0, 2.0])
    np.testing.assert_array_equal(sw["relaxation_time"].values, [1.0, 2.0, 4.0])
    assert sw["load_scale"].dims == ("member",)
    np.testing.assert_allclose(sw["W"].isel(time=0).values, [500.0, 1000.0, 2000.0],
                               rtol=1e-6)
    # a longer relaxation time creeps less over the same window
    grow = (sw["contact_area"].isel(time=-1) / sw["contact_area"].isel(time=0)).values
    assert grow[0] > grow[1] > grow[2] >= 1.0
    sw.close()

    # an ad-hoc derived parameter: (values, func)
    out2 = tmp_path / "adhoc"
    res = sweep(creep, {"w": ([800.0, 1200.0],
                              lambda s, v: s.replace({"load.normal_force": v}))},
                out2, scheduler="synchronous", progress=False)
    assert res.ok
    sw = open_sweep(out2)
    np.testing.assert_allclose(sw["W"].isel(time=0).values, [800.0, 1200.0], rtol=1e-6)
    sw.close()

    with pytest.raises(SceneError, match="zip.*equal lengths.*load_scale: 2.*"
                                         "relaxation_time: 3"):
        sweep(creep, {"load_scale": [1.0, 2.0],
                      "halfspace.relaxation_time": [1.0, 2.0, 3.0]},
              tmp_path / "bad", mode="zip", scheduler="synchronous")


def test_tau_ratio_stretches_the_window(fretting, creep):
    s = sweep_mod.tau_ratio(creep.replace({"halfspace.relaxation_time": 2.0}), 0.25)
    assert s.load.time == (0.0, 0.5) and s.time.steps == creep.time.steps
    s = sweep_mod.tau_ratio(fretting, 3.0)
    np.testing.assert_allclose(s.load.time, [0.0, 0.6, 1.8, 3.0])
    elastic = creep.replace({"halfspace.creep": None, "halfspace.relaxation_time": None,
                             "halfspace.material": "elastic"})
    with pytest.raises(SceneError, match="no body has a relaxation or retardation time"):
        sweep_mod.tau_ratio(elastic, 1.0)


def test_validation_names_axis_and_value_before_any_work(fretting, creep, tmp_path):
    out = tmp_path / "never"
    with pytest.raises(SceneError) as info:
        sweep(fretting, {"friction.mu": [0.1, -0.5], "tau_ratio": [1.0, -2.0]}, out,
              scheduler="synchronous")
    msg = str(info.value)
    assert "friction.mu=-0.5" in msg and "friction.mu must be" in msg
    assert "tau_ratio=-2" in msg and "tau_ratio must be a finite number > 0" in msg
    assert not out.exists()                                 # nothing started

    with pytest.raises(SceneError, match="axis 'bogus' is neither a dotted scene path"):
        sweep(creep, {"bogus": [1, 2]}, out, scheduler="synchronous")
    with pytest.raises(SceneError, match="axis tau_ratio=1: no body has a relaxation"):
        sweep(creep.replace({"halfspace.material": "elastic", "halfspace.creep": None,
                             "halfspace.relaxation_time": None}),
              {"tau_ratio": [1.0]}, out, scheduler="synchronous")
    with pytest.raises(SceneError, match="axis friction.mu: values must be a non-empty list"):
        sweep(creep, {"friction.mu": []}, out, scheduler="synchronous")
    with pytest.raises(SceneError, match="mode must be one of product, zip"):
        sweep(creep, {"friction.mu": [0.1]}, out, mode="cartesian")
    with pytest.raises(SceneError, match="distinct"):
        sweep(creep, {"friction.mu": [0.1, 0.1]}, out, scheduler="synchronous")
    assert not out.exists()


def test_lock_refuses_a_second_sweep(creep, tmp_path):
    out = tmp_path / "runs"
    out.mkdir()
    fd = os.open(out / ".sweep.lock", os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, b"pid 4242 since 2026-01-01T00:00:00+00:00\n")
        with pytest.raises(SweepLockedError,
                           match=r"another sweep holds the lock .*\.sweep\.lock \(pid 4242"):
            sweep(creep, {"load.normal_force": [900.0]}, out, scheduler="synchronous",
                  progress=False)
    finally:
        os.close(fd)
    assert not (out / "manifest.json").exists()
    res = sweep(creep, {"load.normal_force": [900.0]}, out, scheduler="synchronous",
                progress=False)
    assert res.ok and len(res.computed) == 1


# ----------------------------------------------------------------------- sweep files

def test_sweep_file_relative_base_and_dotted_axes(tmp_path, creep):
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "creep.toml").write_text(CREEP)
    f = tmp_path / "sweep.toml"
    f.write_text(textwrap.dedent("""
        base = "scenes/creep.toml"
        mode = "zip"
        [axes]
        "friction.mu" = [0.0, 0.1]
        load.normal_force = [500.0, 600.0]
        [dask]
        scheduler = "tcp://127.0.0.1:8786"
        n_workers = 3
    """))
    base, axes, mode = load_sweep_file(f)
    assert base == creep and mode == "zip"
    assert axes == {"friction.mu": [0.0, 0.1], "load.normal_force": [500.0, 600.0]}
    sf = read_sweep_file(f)
    assert sf.scheduler == "tcp://127.0.0.1:8786" and sf.n_workers == 3

    bad = tmp_path / "bad.toml"
    bad.write_text('base = "missing.toml"\nmode = "grid"\nspeed = 1\n[axes]\nmu = 0.1\n')
    with pytest.raises(SceneError) as info:
        load_sweep_file(bad)
    msg = str(info.value)
    for part in ("no such scene file", "mode must be one of product, zip",
                 "unknown key 'speed'", "axes.mu must be a non-empty list"):
        assert part in msg
    assert cli.main(["sweep", str(bad), "-o", str(tmp_path / "x")]) == 2


def test_public_names_resolve():
    """``cp.sweep`` and ``cp.open_sweep`` (the public API) in a fresh interpreter."""
    code = ("import contactpipe as cp; assert callable(cp.sweep), cp.sweep; "
            "assert callable(cp.open_sweep); assert cp.sweep.__name__ == 'sweep'; "
            "assert cp.open_sweep.__name__ == 'open_sweep'")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr[-1500:]


def test_members_on_their_own_grids(tmp_path):
    """A tau_ratio sweep with grid.size = "auto": each member's grid grows with its window,
    so the members keep their cell centres as x1_cell, x2_cell along the axis (no NaN
    padding from a union of coordinates)."""
    base = Scene.from_toml_text(CREEP).replace({"grid.size": "auto", "time.steps": 4})
    res = sweep(base, {"tau_ratio": [0.5, 2.0]}, tmp_path / "sw", scheduler="synchronous",
                progress=False)
    assert res.ok
    sw = open_sweep(tmp_path / "sw")
    assert dict(sw.sizes)["x1"] == 24 and sw.x1_cell.dims == ("tau_ratio", "x1")
    side = sw.x1_cell.max("x1") - sw.x1_cell.min("x1")
    assert float(side.sel(tau_ratio=2.0)) > float(side.sel(tau_ratio=0.5))
    assert not bool(np.isnan(sw.p.values).any())
    assert "per member" in sw.attrs["sweep_grid"]


# --------------------------------------------------------------------------- scripts

SCRIPT = textwrap.dedent("""
    import contactpipe as cp
    from contactpipe.testing import TINY_SCENES
    {guard}
    base = cp.Scene.from_toml_text(TINY_SCENES["creep"])
    res = cp.sweep(base, {{"friction.mu": [0.1, 0.2]}}, "out", n_workers=1, progress=False)
    print(res.summary())
""")


def run_script(tmp_path, guard: bool):
    text = SCRIPT.format(guard="if __name__ == '__main__':" if guard else "")
    if guard:        # the body indented under the guard
        head, body = text.split("if __name__ == '__main__':\n")
        text = head + "if __name__ == '__main__':\n" + textwrap.indent(body, "    ")
    script = tmp_path / "study.py"
    script.write_text(text)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    return subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                          text=True, env=env, timeout=600)


def test_a_script_without_the_main_guard_says_so_in_one_line(tmp_path):
    """A script that calls cp.sweep at its top level, run as `python study.py`: the
    LocalCluster's worker imports it again, and that import stops with one line naming the
    guard (not a lock error); the script fails naming the guard too, and no member ran."""
    res = run_script(tmp_path, guard=False)
    assert res.returncode == 1
    line = ("contactpipe: error: cp.sweep was called while a worker process re-imported "
            "your script; put the call under if __name__ == \"__main__\":")
    # the worker's one line (dask may add its own warnings, e.g. a dashboard port in use)
    assert res.stderr.splitlines().count(line) == 1, res.stderr
    assert "holds the lock" not in res.stderr and "SweepLockedError" not in res.stderr
    assert res.stderr.strip().splitlines()[-1].startswith(
        "contactpipe.exceptions.ContactpipeError: the LocalCluster's 1 worker process(es) "
        "failed to start")
    assert 'must be called under if __name__ == "__main__":' in res.stderr.splitlines()[-1]
    assert not list((tmp_path / "out").glob("*.nc"))


@pytest.mark.slow
def test_the_readme_guard_lets_the_script_sweep(tmp_path):
    """The same script under `if __name__ == "__main__":` (as the README shows) runs both
    members."""
    res = run_script(tmp_path, guard=True)
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith("2 members: 2 computed, 0 skipped, 0 failed")


# --------------------------------------------------------------------------- scratch

def test_members_sent_back_are_simulated_in_the_worker_scratch_and_swept(tmp_path,
                                                                           monkeypatch):
    """A member simulated away from out_dir (shared_disk=False) is written under the
    worker's local directory, not the system's temporary folder; a worker killed mid-run
    (SIGKILL) leaves its scratch folder there, and the next member removes it."""
    local = tmp_path / "local"
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(TINY_SCENES["creep"].replace("steps = 10", "steps = 400"))
    runner = textwrap.dedent("""
        import os, signal, sys, types
        import distributed
        from contactpipe.pipeline.sweep import execute
        from contactpipe.scene import Scene
        worker = types.SimpleNamespace(local_directory=sys.argv[2])
        distributed.get_worker = lambda: worker
        def step(k, t, rec):
            if k == 5:
                os.kill(os.getpid(), signal.SIGKILL)     # a worker killed mid-member
        real = execute.simulate
        execute.simulate = lambda *a, **kw: real(*a, **{**kw, "on_step": step})
        execute._simulate(Scene.from_toml(sys.argv[1]), None)
    """)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    proc = subprocess.Popen([sys.executable, "-c", runner, str(scene_file), str(local)],
                            stderr=subprocess.PIPE, text=True, env=env)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == -signal.SIGKILL, err
    left = list(local.iterdir())
    assert len(left) == 1 and left[0].name.startswith(f"contactpipe-member-{proc.pid}-")
    assert [p.name for p in left[0].iterdir()][0].startswith(".member.nc.")
    import distributed

    from contactpipe.pipeline.sweep import execute
    monkeypatch.setattr(distributed, "get_worker",
                        lambda: type("W", (), {"local_directory": str(local)})())
    assert execute.scratch_root() == local
    data = execute._simulate(Scene.from_toml_text(TINY_SCENES["creep"]), None)
    assert data[:4] == b"\x89HDF"
    assert list(local.iterdir()) == []
