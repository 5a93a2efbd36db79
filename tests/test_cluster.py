"""A sweep on a real dask cluster whose worker does not share the client's disk.

The test starts a ``dask scheduler`` and a ``dask worker`` process of its own (not a
LocalCluster): the worker has its own working directory, its own ``--local-directory``
and its own ``TMPDIR``, and an audit hook (a ``--preload`` module) that records every
file the worker opens, renames, creates or removes under the sweep's output folder or
its own TMPDIR. The worker is never told the output folder: it simulates into its TMPDIR
and sends each archive back; the client checks it and writes it.
"""
import json
import os
import pathlib
import subprocess
import sys
import time

import numpy as np
import pytest

from contactpipe.archive import open_archive
from contactpipe.pipeline.sweep import open_sweep, sweep
from contactpipe.scene import Scene
from contactpipe.testing import TINY_SCENES

distributed = pytest.importorskip("distributed")

ROOT = pathlib.Path(__file__).resolve().parents[1]
START_TIMEOUT_S = 120

AUDIT = '''
"""Preloaded into the worker: record file events under the watched folders."""
import os
import sys

_LOG = os.environ["CONTACTPIPE_AUDIT_LOG"]
_WATCH = tuple(os.path.realpath(p) for p in
               os.environ["CONTACTPIPE_AUDIT_WATCH"].split(os.pathsep))
_EVENTS = ("open", "os.rename", "os.mkdir", "os.remove", "os.rmdir", "os.truncate",
           "os.link", "os.symlink", "shutil.copyfile", "shutil.move")


def _hook(event, args):
    if event not in _EVENTS:
        return
    for a in args[:2]:
        if isinstance(a, (str, bytes, os.PathLike)):
            p = os.path.realpath(os.fsdecode(os.fspath(a)))
            if p.startswith(_WATCH):
                with open(_LOG, "a", encoding="utf-8") as f:
                    f.write(f"{event}\\t{p}\\n")


sys.addaudithook(_hook)
'''


def _stop(proc):
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture(scope="module")
def remote(tmp_path_factory):
    """A scheduler and one worker, each a process of its own; the worker in a folder of
    its own with its own TMPDIR. Yields (address, worker folder, worker TMPDIR, audit
    log, client folder)."""
    root = tmp_path_factory.mktemp("cluster")
    client_dir = root / "client"             # the sweep's output goes under here
    worker_dir = root / "worker"
    for d in (client_dir, worker_dir / "tmp", worker_dir / "local", root / "scheduler"):
        d.mkdir(parents=True)
    (worker_dir / "audit_preload.py").write_text(AUDIT)
    log = worker_dir / "audit.log"
    log.write_text("")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in
                                        env.get("PYTHONPATH", "").split(os.pathsep) if p])
    scheduler_file = root / "scheduler.json"
    scheduler = subprocess.Popen(
        [sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1", "--port", "0",
         "--no-dashboard", "--scheduler-file", str(scheduler_file)],
        cwd=root / "scheduler", env=env, stdout=subprocess.DEVNULL,
        stderr=open(root / "scheduler.log", "wb"))
    worker = None
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while not scheduler_file.exists() and time.monotonic() < deadline:
            assert scheduler.poll() is None, (root / "scheduler.log").read_text()[-2000:]
            time.sleep(0.2)
        assert scheduler_file.exists(), "the dask scheduler did not start"
        time.sleep(0.2)                                   # the file is written whole
        address = json.loads(scheduler_file.read_text())["address"]
        worker_env = dict(env, TMPDIR=str(worker_dir / "tmp"),
                          CONTACTPIPE_AUDIT_LOG=str(log),
                          CONTACTPIPE_AUDIT_WATCH=os.pathsep.join(
                              [str(client_dir), str(worker_dir / "tmp"),
                               str(worker_dir / "local")]))
        worker = subprocess.Popen(
            [sys.executable, "-m", "dask", "worker", address, "--nworkers", "1",
             "--nthreads", "1", "--no-nanny", "--no-dashboard",
             "--local-directory", str(worker_dir / "local"),
             "--preload", str(worker_dir / "audit_preload.py")],
            cwd=worker_dir, env=worker_env, stdout=subprocess.DEVNULL,
            stderr=open(root / "worker.log", "wb"))
        with distributed.Client(address, timeout="60s") as c:
            c.wait_for_workers(1, timeout=START_TIMEOUT_S)
            assert set(c.run(os.getcwd).values()) == {str(worker_dir)}   # its own cwd
        yield address, worker_dir, worker_dir / "tmp", log, client_dir
    finally:
        if worker is not None:
            _stop(worker)
        _stop(scheduler)


def test_sweep_on_workers_without_the_clients_disk(remote, monkeypatch):
    address, worker_dir, worker_tmp, log, client_dir = remote
    monkeypatch.chdir(client_dir)                    # the client's cwd is not the worker's
    out = client_dir / "runs"
    base = Scene.from_toml_text(TINY_SCENES["creep"])
    axes = {"load.normal_force": [800.0, 1200.0]}
    res = sweep(base, axes, out, scheduler=address, progress=False)
    assert res.ok, [str(m) for m in res.failed]
    assert len(res.computed) == 2 and not res.skipped

    # the archives came back whole, each holding its member's scene
    for m in res.members:
        with open_archive(out / m.file) as ds:
            assert Scene.from_toml_text(ds.attrs["scene"]).digest() == m.digest
    sw = open_sweep(out)
    np.testing.assert_allclose(sw["W"].isel(time=-1).values, [800.0, 1200.0], rtol=1e-6)
    sw.close()
    assert not list(out.glob(".*.part*"))

    # the worker never touched the output folder; it did work in its own scratch folder
    # under its dask local directory (where `dask worker --local-directory` puts it), not
    # in the system temporary folder
    events = [line.split("\t") for line in log.read_text().splitlines()]
    under_out = [e for e in events if e[1].startswith(os.path.realpath(out))]
    assert under_out == [], under_out
    local = worker_dir / "local"
    in_local = [e for e in events if e[1].startswith(os.path.realpath(local))]
    assert any(e[0] == "os.rename" and e[1].endswith("member.nc") for e in in_local), \
        "the audit hook saw no archive written in the worker's local directory: " + \
        repr(events[:20])
    assert not [e for e in events if e[1].startswith(os.path.realpath(worker_tmp))]
    assert list(worker_tmp.iterdir()) == []
    assert not list(local.rglob("*.nc")) and not list(local.glob("contactpipe-member-*"))

    # resuming is decided on the client: nothing to recompute
    again = sweep(base, axes, out, scheduler=address, progress=False)
    assert again.ok and not again.computed and len(again.skipped) == 2
