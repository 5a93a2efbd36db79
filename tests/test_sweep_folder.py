"""A sweep folder edited, swapped or damaged by hand: the manifest is validated on read
(one ArchiveError naming the key), each member archive is checked against its digest,
and a resumed sweep deletes nothing it cannot prove broken."""
import importlib
import json
import os
import shutil
import types

import numpy as np
import pytest

from contactpipe.archive import open_archive
from contactpipe.exceptions import ArchiveError
from contactpipe.pipeline import cli
from contactpipe.pipeline.sweep import archive_state, open_sweep, sweep
from contactpipe.pipeline.sweep.execute import land_member, run_member, workers_share_disk
from contactpipe.pipeline.sweep.manifest import check_manifest, read_manifest
from contactpipe.scene import Scene
from contactpipe.testing import TINY_SCENES

sweep_mod = importlib.import_module("contactpipe.pipeline.sweep.driver")

AXES = {"load.normal_force": [800.0, 1200.0]}


@pytest.fixture(scope="module")
def done_sweep(tmp_path_factory):
    """A finished two-member sweep of tiny-creep (synchronous), kept pristine: tests
    copy it."""
    out = tmp_path_factory.mktemp("sweep") / "runs"
    base = Scene.from_toml_text(TINY_SCENES["creep"])
    res = sweep(base, AXES, out, scheduler="synchronous", progress=False)
    assert res.ok
    return base, out


@pytest.fixture
def folder(done_sweep, tmp_path):
    base, out = done_sweep
    copy = tmp_path / "runs"
    shutil.copytree(out, copy)
    return base, copy


def snapshot(folder):
    """{name: (inode, mtime_ns, size)} of every file in the folder but the lock (whose
    holder line each sweep rewrites)."""
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns, p.stat().st_size)
            for p in folder.iterdir() if p.is_file() and p.name != ".sweep.lock"}


def edit_manifest(folder, change):
    path = folder / "manifest.json"
    manifest = json.loads(path.read_text())
    change(manifest)
    path.write_text(json.dumps(manifest))


def _set(path, value):
    def change(manifest):
        *parents, last = path
        node = manifest
        for key in parents:
            node = node[key]
        if value is KeyError:
            del node[last]
        else:
            node[last] = value
    return change


# ----------------------------------------------------------------------- the manifest

HAND_EDITS = [
    (_set(["members", 0, "digest"], KeyError), r"members\[0\]\.digest must be present"),
    (_set(["members", 1, "status"], 7), r"members\[1\]\.status must be one of pending, "
                                        r"done, failed, got 7"),
    (_set(["members"], {}), r"members must be a list"),
    (_set(["members", 0, "values"], {"friction.mu": 0.1}),
     r"members\[0\]\.values must be an object with a value for each axis"),
    (_set(["members", 0, "values", "load.normal_force"], 999.0),
     r"members\[0\]\.values\.load\.normal_force must be one of axes\.load\.normal_force"),
    (_set(["members", 1, "file"], "../../etc/passwd"), r"members\[1\]\.file must be '"),
    (_set(["members", 0, "digest"], "not-a-digest"), r"members\[0\]\.digest must be 16 "
                                                     r"lowercase hex"),
    (_set(["members", 0, "wall_time_s"], "fast"), r"members\[0\]\.wall_time_s must be null "
                                                  r"or a number"),
    (_set(["members", 1, "index"], True), r"members\[1\]\.index must be an integer"),
    (_set(["dims"], {}), r"dims must be an object with one dimension name per axis"),
    (_set(["axes", "load.normal_force"], 800.0), r"axes\.load\.normal_force must be a "
                                                 r"non-empty list"),
    (_set(["mode"], "cartesian"), r"mode must be one of product, zip"),
    (_set(["format"], 99), r"format must be 1"),
    (_set(["axes"], KeyError), r"missing axes"),
    (lambda m: m["members"].append(dict(m["members"][0])), r"members\[2\] must be a "
                                                          r"member not listed before"),
]


@pytest.mark.parametrize("change, message", HAND_EDITS)
def test_hand_edited_manifest_is_one_line_naming_the_key(folder, change, message):
    _, out = folder
    edit_manifest(out, change)
    with pytest.raises(ArchiveError, match=message) as info:
        open_sweep(out)
    assert "\n" not in str(info.value) and "manifest.json" in str(info.value)


def test_manifest_not_json_or_not_an_object(folder):
    _, out = folder
    (out / "manifest.json").write_text("[1, 2")
    with pytest.raises(ArchiveError, match="unreadable sweep manifest"):
        read_manifest(out)
    (out / "manifest.json").write_text("[1, 2]")
    with pytest.raises(ArchiveError, match="the manifest must be a JSON object"):
        read_manifest(out)
    with pytest.raises(ArchiveError, match="not a sweep folder"):
        read_manifest(out / "nowhere")


def test_hand_edited_manifest_via_the_cli_then_rewritten_by_the_sweep(folder, tmp_path,
                                                                      capsys):
    base, out = folder
    edit_manifest(out, _set(["members", 0, "status"], "finished"))
    code = cli.main(["plot", str(out), "-o", str(tmp_path / "s.png")])
    err = capsys.readouterr().err
    assert code != 0 and len(err.strip().splitlines()) == 1
    assert "members[0].status must be one of" in err
    assert not (tmp_path / "s.png").exists()
    # the sweep rewrites its own manifest: nothing to recompute
    res = sweep(base, AXES, out, scheduler="synchronous", progress=False)
    assert res.ok and not res.computed and len(res.skipped) == 2
    check_manifest(json.loads((out / "manifest.json").read_text()))


# ----------------------------------------------------------------------- swapped members

def test_swapped_members_refused_then_set_aside_and_recomputed(folder):
    base, out = folder
    a, b = (out / m["file"] for m in read_manifest(out)["members"])
    da, db = a.stem, b.stem
    tmp = out / "swap"
    a.rename(tmp)
    b.rename(a)
    tmp.rename(b)
    with pytest.raises(ArchiveError) as info:
        open_sweep(out)
    msg = str(info.value)
    assert f"({da}.nc)" in msg and f"holds the scene of digest {db}, not {da}" in msg

    res = sweep(base, AXES, out, scheduler="synchronous", progress=False)
    assert res.ok and len(res.computed) == 2 and not res.skipped
    assert sorted(p.name for p in res.set_aside) == sorted(
        [f"{da}.nc.foreign-{db}", f"{db}.nc.foreign-{da}"])
    for p in res.set_aside:                          # nothing was lost: still valid archives
        with open_archive(p) as ds:
            assert Scene.from_toml_text(ds.attrs["scene"]).digest() == p.name[-16:]
    sw = open_sweep(out)
    np.testing.assert_allclose(sw["W"].isel(time=-1).values, [800.0, 1200.0], rtol=1e-6)
    sw.close()


def test_archive_state(folder, tmp_path):
    _, out = folder
    a, b = (out / m["file"] for m in read_manifest(out)["members"])
    assert archive_state(a, a.stem)[0] == "valid"
    assert archive_state(a, b.stem) == ("foreign", a.stem)
    assert archive_state(tmp_path / "absent.nc", a.stem) == ("missing", None)
    junk = tmp_path / "junk.nc"
    junk.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))
    state, reason = archive_state(junk, a.stem)
    assert state == "broken" and "junk.nc" in reason


# ----------------------------------------------------------------------- nothing deleted

def test_a_folder_at_a_members_name_stops_the_sweep_untouched(folder):
    base, out = folder
    a = out / read_manifest(out)["members"][0]["file"]
    a.unlink()
    a.mkdir()
    (a / "keep.txt").write_text("mine")
    before = snapshot(out)
    with pytest.raises(ArchiveError, match="not a regular file"):
        sweep(base, AXES, out, scheduler="synchronous", progress=False)
    assert (a / "keep.txt").read_text() == "mine" and snapshot(out) == before


@pytest.mark.parametrize("error", [PermissionError(13, "Permission denied"),
                                   MemoryError("cannot allocate")])
def test_unreadable_member_is_not_judged(folder, monkeypatch, error):
    """A permission or memory error while looking at a member's archive stops the sweep
    with that error; the archive is neither deleted nor replaced."""
    base, out = folder
    a = out / read_manifest(out)["members"][0]["file"]
    a.write_bytes(a.read_bytes()[:1000])             # truncated: broken if it were read
    before = snapshot(out)
    real_open = open

    def failing_open(path, *args, **kwargs):
        if os.fspath(path) == os.fspath(a) and isinstance(error, OSError):
            raise error
        return real_open(path, *args, **kwargs)

    def failing_open_archive(path, *args, **kwargs):
        raise error

    monkeypatch.setattr(sweep_mod, "open", failing_open, raising=False)
    if isinstance(error, MemoryError):
        monkeypatch.setattr(sweep_mod, "open_archive", failing_open_archive)
    with pytest.raises(type(error)):
        sweep(base, AXES, out, scheduler="synchronous", progress=False)
    assert snapshot(out) == before


# ----------------------------------------------------------------------- archives sent back

def test_land_member_checks_what_a_worker_sends(folder, tmp_path):
    _, out = folder
    a, b = (out / m["file"] for m in read_manifest(out)["members"])
    landing = tmp_path / "landing"
    landing.mkdir()
    target = landing / b.name
    res = land_member({"digest": b.stem, "status": "done", "error": None,
                       "archive": a.read_bytes()}, target)
    assert res["status"] == "failed" and f"holds the scene of digest {a.stem}" in res["error"]
    assert "archive" not in res and not target.exists()
    res = land_member({"digest": b.stem, "status": "done", "error": None,
                       "archive": b"garbage" * 100}, target)
    assert res["status"] == "failed" and "not a readable netCDF archive" in res["error"]
    assert list(landing.iterdir()) == []             # no file, no temporary left
    res = land_member({"digest": b.stem, "status": "done", "error": None,
                       "archive": b.read_bytes()}, target)
    assert res["status"] == "done" and target.read_bytes() == b.read_bytes()


def test_run_member_without_a_path_returns_the_archive():
    scene = Scene.from_toml_text(TINY_SCENES["creep"])
    res = run_member(scene, scene.digest())
    assert res["status"] == "done" and res["archive"][:4] == b"\x89HDF"
    bad = scene.replace({"load.normal_force": 1.0e5,            # off the grid, left to
                         "grid.size_check": False})             # the run
    res = run_member(bad, bad.digest())
    assert res["status"] == "failed" and res["error"].startswith("GridError: ")
    assert "archive" not in res


def test_synchronous_sweep_sending_archives_back(tmp_path):
    base = Scene.from_toml_text(TINY_SCENES["creep"])
    res = sweep(base, AXES, tmp_path / "runs", scheduler="synchronous", progress=False,
                shared_disk=False)
    assert res.ok and len(res.computed) == 2
    sw = open_sweep(tmp_path / "runs")
    np.testing.assert_allclose(sw["W"].isel(time=-1).values, [800.0, 1200.0], rtol=1e-6)
    sw.close()


def test_who_writes_the_archives():
    remote = types.SimpleNamespace(cluster=None)      # a client of a scheduler address
    assert workers_share_disk(None, None, None)                    # a LocalCluster here
    assert workers_share_disk(None, None, "synchronous")
    assert not workers_share_disk(None, None, "tcp://10.0.0.5:8786")
    assert not workers_share_disk(None, remote, None)
    assert workers_share_disk(True, remote, "tcp://10.0.0.5:8786")
    assert not workers_share_disk(False, None, None)
