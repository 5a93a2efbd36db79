"""Resumable runs: a long run interrupted (SIGKILL, Ctrl-C) and resumed ends identical to
an uninterrupted one; a damaged resume state (checkpoint, part file) starts afresh with one
warning and completes."""
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time
import warnings

import numpy as np
import pytest

import contactpipe as cp
from contactpipe.simulation import ResumeNotice, ResumeWarning
from contactpipe.testing import TINY_SCENES

ROOT = pathlib.Path(__file__).resolve().parents[1]

SCENE = TINY_SCENES["fretting"].replace("steps = 20", "steps = 200")

RUNNER = textwrap.dedent("""
    import sys, time, contactpipe as cp
    sc = cp.Scene.from_toml(sys.argv[1])
    def slow(k, t, rec):
        if k >= 20:
            time.sleep(0.02)                 # give the test time to kill us mid-run
    cp.simulate(sc, sys.argv[2], resume=True, checkpoint_seconds=0.0, on_step=slow)
""")


def test_kill_and_resume(tmp_path):
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(SCENE)
    target = tmp_path / "run.nc"
    ckpt = tmp_path / ".run.nc.ckpt.npz"
    part = tmp_path / ".run.nc.resumable.part"
    proc = subprocess.Popen([sys.executable, "-c", RUNNER, str(scene_file), str(target)],
                            start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline and not ckpt.exists():
        time.sleep(0.05)
    time.sleep(0.5)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert not target.exists() and part.exists() and ckpt.exists()
    with np.load(ckpt) as z:
        k_done = int(z["k"])
    assert 0 < k_done < 200
    scene = cp.Scene.from_toml(scene_file)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ResumeWarning)     # resumed, not started afresh
        resumed = cp.simulate(scene, target, resume=True)
    assert not ckpt.exists() and not part.exists()
    reference = cp.simulate(scene)
    assert resumed.sizes["time"] == 201
    # the two processes may plan their FFTs differently (FFTW_MEASURE times candidates), so
    # rounding differs and the iterative solves agree to their tolerance (1e-9), not bitwise:
    # measured 1.4e-9 of max p, 5e-9 of max q1. Compare at 1e-7 of each variable's scale.
    resumed = resumed.load()
    for name in ("p", "q1", "q2", "u1", "u3", "h", "s1", "W", "T1", "omega1", "omega3",
                 "contact_area", "stick_area", "dissipation"):
        ref = reference[name].values
        scale = max(float(np.abs(ref).max()), 1e-300)
        np.testing.assert_allclose(resumed[name].values, ref, rtol=0, atol=1e-7 * scale,
                                   err_msg=name)
    np.testing.assert_array_equal(resumed.time.values, reference.time.values)


def test_resume_without_checkpoint_starts_afresh(tmp_path):
    scene = cp.Scene.from_toml_text(SCENE.replace("steps = 200", "steps = 5"))
    ds = cp.simulate(scene, tmp_path / "a.nc", resume=True)
    assert ds.sizes["time"] == 6
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nc"]


# --------------------------------------------------------------------------- damaged state

def interrupted(tmp_path, at=8, steps=20):
    """A resumable run stopped by Ctrl-C after instant ``at``: its part file and
    checkpoint stay beside the target."""
    scene = cp.Scene.from_toml_text(SCENE.replace("steps = 200", f"steps = {steps}"))
    target = tmp_path / "run.nc"

    def stop(k, t, rec):
        if k == at:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        cp.simulate(scene, target, resume=True, checkpoint_seconds=0.0, on_step=stop)
    part, ckpt = tmp_path / ".run.nc.resumable.part", tmp_path / ".run.nc.ckpt.npz"
    assert part.exists() and ckpt.exists() and not target.exists()
    return scene, target, part, ckpt


def assert_same_run(ds, reference):
    ds = ds.load()
    for name in ("p", "q1", "u3", "s1", "W", "T1", "omega1", "dissipation"):
        ref = reference[name].values
        np.testing.assert_allclose(ds[name].values, ref, rtol=0,
                                   atol=1e-7 * max(float(np.abs(ref).max()), 1e-300),
                                   err_msg=name)


def test_ctrl_c_then_resume_continues(tmp_path):
    """Ctrl-C after instant 8 checkpoints instant 8 (the state between two instants is
    whole), and the resume says it continues from there."""
    scene, target, part, ckpt = interrupted(tmp_path)
    with np.load(ckpt) as z:
        assert int(z["k"]) == 8 and int(z["written"]) == 9      # the instant reached
    with pytest.warns(ResumeNotice, match=r"run\.nc: resuming from instant 8 of 20 "
                                          r"\(t = 0\.4 s\), its checkpoint \(9 instants"):
        ds = cp.simulate(scene, target, resume=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]
    assert_same_run(ds, cp.simulate(scene))


@pytest.mark.parametrize("damage", ["garbage", "truncated", "empty", "keys_missing"])
def test_a_damaged_checkpoint_starts_afresh(tmp_path, damage):
    scene, target, part, ckpt = interrupted(tmp_path)
    data = ckpt.read_bytes()
    if damage == "garbage":
        ckpt.write_bytes(b"not a checkpoint" * 10)
    elif damage == "truncated":
        ckpt.write_bytes(data[: len(data) // 2])
    elif damage == "empty":
        ckpt.write_bytes(b"")
    else:
        with np.load(ckpt) as z:
            kept = {k: z[k] for k in z.files if k not in ("k", "p")}
        with open(ckpt, "wb") as f:
            np.savez(f, **kept)
    with pytest.warns(ResumeWarning, match=r"run.nc: the resume state is damaged "
                                           r"\(.*\); starting afresh"):
        ds = cp.simulate(scene, target, resume=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]
    assert_same_run(ds, cp.simulate(scene))


@pytest.mark.parametrize("damage", ["truncated", "garbage", "missing"])
def test_a_damaged_part_file_starts_afresh(tmp_path, damage):
    scene, target, part, ckpt = interrupted(tmp_path)
    if damage == "truncated":
        data = part.read_bytes()
        part.write_bytes(data[: len(data) // 2])
    elif damage == "garbage":
        part.write_bytes(np.random.default_rng(0).bytes(4096))
    else:
        part.unlink()
    if damage == "missing":
        ds = cp.simulate(scene, target, resume=True)     # no part: a fresh start, silently
    else:
        with pytest.warns(ResumeWarning, match=r"cannot resume from \.run\.nc\.resumable"
                                               r"\.part.*starting afresh"):
            ds = cp.simulate(scene, target, resume=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]
    assert_same_run(ds, cp.simulate(scene))
    cp.open_archive(target, verify=True)


def test_damaged_resume_state_through_the_command_line(tmp_path):
    """`run --resume` over a corrupt checkpoint: one warning line, exit 0, a valid archive."""
    scene, target, part, ckpt = interrupted(tmp_path)
    ckpt.write_bytes(b"\x00" * 100)
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(scene.to_toml())
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    res = subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", "run",
                          str(scene_file), "-o", str(target), "--resume", "--no-progress"],
                         capture_output=True, text=True, env=env, timeout=600)
    assert res.returncode == 0, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("contactpipe: warning: ")
    assert "the resume state is damaged" in lines[0] and "starting afresh" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc", "scene.toml"]
    cp.open_archive(target, verify=True)


def test_a_checkpoint_without_the_increments_resumes(tmp_path):
    """A checkpoint keeps the last instant's shear and pressure increments (the start of
    the next instant along a straight load path); one written before they were kept
    resumes, its next instant started from q and p as they are, and the run agrees with
    an uninterrupted one within 1e-7 of each variable's scale."""
    scene, target, part, ckpt = interrupted(tmp_path)
    with np.load(ckpt) as z:
        assert z["dq"].shape == z["q"].shape and np.any(z["dq"])
        assert z["dp"].shape == z["p"].shape and np.any(z["dp"])
        kept = {k: z[k] for k in z.files if k not in ("dq", "dp")}
    with open(ckpt, "wb") as f:
        np.savez(f, **kept)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ResumeWarning)     # resumed, not started afresh
        ds = cp.simulate(scene, target, resume=True)
    assert_same_run(ds, cp.simulate(scene))


# --------------------------------------------------------------------------- the command line

#: `contactpipe run` whose run_scene (simulate, the archive not reopened) sends itself
#: SIGTERM right after instant STOP_AT (the checkpoint cadence stays the default 30 s:
#: none falls due in so short a run).
SIGNALLING_RUNNER = textwrap.dedent("""
    import os, signal, sys
    import contactpipe.pipeline.cli as cli
    import contactpipe.simulation as sim      # the CLI imports run_scene from it per run
    real, stop = sim.run_scene, int(os.environ["STOP_AT"])
    def run_scene(*args, **kwargs):
        def on_step(k, t, record):
            if k == stop:
                os.kill(os.getpid(), signal.SIGTERM)
        return real(*args, on_step=on_step, **kwargs)
    sim.run_scene = run_scene
    sys.exit(cli.main(sys.argv[1:]))
""")


def test_sigterm_checkpoints_the_instant_reached_and_resume_says_so(tmp_path):
    """SIGTERM after instant 23 of 40 (long before the 30 s checkpoint falls due): the run
    checkpoints instant 23, exits 143 saying where --resume continues; the resume says it
    starts from instant 23 (not 0) and ends equal to an uninterrupted run (1e-7 of each
    variable's scale)."""
    scene = cp.Scene.from_toml_text(SCENE.replace("steps = 200", "steps = 40"))
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(scene.to_toml())
    target = tmp_path / "run.nc"
    env = {**os.environ, "STOP_AT": "23", "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    args = ["run", str(scene_file), "-o", str(target), "--resume", "--no-progress"]
    first = subprocess.run([sys.executable, "-c", SIGNALLING_RUNNER, *args],
                           capture_output=True, text=True, env=env, timeout=600)
    assert first.returncode == 143, first.stderr
    assert first.stderr.strip() == ("contactpipe: interrupted (SIGTERM); --resume continues "
                                    "from instant 23 of 40 (t = 0.575 s)")
    with np.load(tmp_path / ".run.nc.ckpt.npz") as z:
        assert int(z["k"]) == 23 and int(z["written"]) == 24
    second = subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", *args],
                            capture_output=True, text=True, env=env, timeout=600)
    assert second.returncode == 0, second.stderr
    assert second.stderr.strip() == ("contactpipe: run.nc: resuming from instant 23 of 40 "
                                     "(t = 0.575 s), its checkpoint (24 instants written)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc", "scene.toml"]
    ds = cp.open_archive(target, verify=True)
    assert ds.sizes["time"] == 41
    assert_same_run(ds, cp.simulate(scene))


def test_a_checkpoint_killed_while_written_is_cleaned_up_by_the_resume(tmp_path):
    """SIGKILL while a checkpoint is being written leaves its temporary file
    (``..run.nc.ckpt.npz.<pid>-<token>.part``) beside the previous checkpoint; the
    resumed run removes it and completes."""
    scene = cp.Scene.from_toml_text(SCENE.replace("steps = 200", "steps = 20"))
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(scene.to_toml())
    target = tmp_path / "run.nc"
    runner = textwrap.dedent("""
        import os, signal, sys, numpy as np, contactpipe as cp
        real, saves = np.savez, []
        def savez(f, **arrays):                   # only checkpoints call it here
            saves.append(1)
            if len(saves) == 6:                   # the sixth checkpoint: killed half-way
                f.write(b"PK" * 1000)
                f.flush()
                os.kill(os.getpid(), signal.SIGKILL)
            real(f, **arrays)
        np.savez = savez
        sc = cp.Scene.from_toml(sys.argv[1])
        cp.simulate(sc, sys.argv[2], resume=True, checkpoint_seconds=0.0)
    """)
    proc = subprocess.run([sys.executable, "-c", runner, str(scene_file), str(target)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    left = sorted(p.name for p in tmp_path.glob("..run.nc.ckpt.npz.*.part"))
    assert len(left) == 1, sorted(p.name for p in tmp_path.iterdir())
    with np.load(tmp_path / ".run.nc.ckpt.npz") as z:
        assert int(z["k"]) == 4                     # the fifth checkpoint stands
    with pytest.warns(ResumeNotice, match="resuming from instant 4 of 20"):
        ds = cp.simulate(scene, target, resume=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc", "scene.toml"]
    assert_same_run(ds, cp.simulate(scene))


@pytest.mark.parametrize("which", ["part", "checkpoint"])
def test_a_fifo_in_place_of_the_resume_state_is_refused(tmp_path, which):
    """A FIFO where the part file or the checkpoint should be: one line naming it, exit 2,
    at once (reading it would block for ever), the FIFO left alone."""
    scene = cp.Scene.from_toml_text(SCENE.replace("steps = 200", "steps = 5"))
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(scene.to_toml())
    name = ".run.nc.resumable.part" if which == "part" else ".run.nc.ckpt.npz"
    os.mkfifo(tmp_path / name)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    res = subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", "run",
                          str(scene_file), "-o", str(tmp_path / "run.nc"), "--resume",
                          "--no-progress"], capture_output=True, text=True, env=env,
                         timeout=120)
    assert res.returncode == 2, res.stderr
    assert res.stderr.strip() == (f"contactpipe: error: {tmp_path / name} is not a regular "
                                  f"file (a FIFO, a device or a folder): a resumable run "
                                  f"keeps its state there; remove it")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([name, "scene.toml"])
