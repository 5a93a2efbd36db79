"""A long run interrupted (SIGKILL) and resumed ends identical to an uninterrupted one."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np

import contactpipe as cp
from contactpipe.testing import TINY_SCENES

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
