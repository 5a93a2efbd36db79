"""`contactpipe run` and cp.simulate as a new user tries them: bad output paths, two
resumable runs on one target, runs too large for the memory, termination signals,
extreme constants. Each ends in one line (exit 2 for bad input, 3 for a held lock,
128 + the signal number when terminated) and touches no file it should not."""
import os
import pathlib
import re
import resource
import signal
import stat
import subprocess
import sys
import time
import warnings

import helpers
import numpy as np
import pytest

import contactpipe as cp
import contactpipe.simulation.march as simulation
from contactpipe._util.files import exclusive_lock
from contactpipe.archive import ArchiveWriter, resume_lock
from contactpipe.exceptions import ArchiveError, OutputPathError, SceneError
from contactpipe.nomenclature import variables_for
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.planning import check_resources, estimate_resources
from contactpipe.planning.accuracy import resolve_accuracy
from contactpipe.testing import TINY_SCENES, assert_contact_laws

ROOT = pathlib.Path(__file__).resolve().parents[1]
TINY = cp.Scene.from_toml_text(TINY_SCENES["creep"])


def env():
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}


def cli(*args, preexec_fn=None, timeout=300):
    return subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", *map(str, args)],
                          capture_output=True, text=True, env=env(), timeout=timeout,
                          preexec_fn=preexec_fn)


def one_line(stderr):
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


@pytest.fixture
def scene_file(tmp_path):
    f = tmp_path / "scene.toml"
    f.write_text(TINY_SCENES["creep"])
    return f


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if a run gets past its path check (the first work it does after the
    check is resolving the accuracy preset)."""
    def refuse(*args, **kwargs):
        raise AssertionError("the run started although its output path is refused")
    monkeypatch.setattr(simulation, "resolve_accuracy", refuse)


# --------------------------------------------------------------------------- output paths

def test_dev_null_is_refused_before_any_work(scene_file, no_work, capsys):
    before = os.stat("/dev/null")
    assert cli_main(["run", str(scene_file), "-o", "/dev/null", "--no-progress"]) == 2
    line = one_line(capsys.readouterr().err)
    assert "/dev/null is not a regular file" in line
    after = os.stat("/dev/null")
    assert stat.S_ISCHR(after.st_mode) and after.st_rdev == before.st_rdev
    with pytest.raises(OutputPathError, match="not a regular file"):
        cp.simulate(TINY, "/dev/null")


def test_other_special_files_are_refused(scene_file, tmp_path, no_work, capsys):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    targets = [fifo]
    node = tmp_path / "null-device"
    try:
        os.mknod(node, stat.S_IFCHR | 0o666, os.makedev(1, 3))
        targets.append(node)
    except (PermissionError, OSError):
        pass                          # no CAP_MKNOD here: the FIFO stands for them
    for target in targets:
        kind = os.stat(target).st_mode
        assert cli_main(["run", str(scene_file), "-o", str(target), "--no-progress"]) == 2
        assert "is not a regular file" in one_line(capsys.readouterr().err)
        assert os.stat(target).st_mode == kind
        assert cli_main(["run", str(scene_file), "-o", str(tmp_path / "ok.nc"),
                         "--figure", str(target), "--no-progress"]) == 2
        assert "figure (--figure)" in one_line(capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["scene.toml"] + [t.name for t in targets])


def test_the_scene_file_itself_is_refused(scene_file, no_work, capsys):
    text = scene_file.read_text()
    assert cli_main(["run", str(scene_file), "-o", str(scene_file), "--no-progress"]) == 2
    assert "is the input file" in one_line(capsys.readouterr().err)
    assert cli_main(["run", str(scene_file), "-o", str(scene_file.with_suffix(".nc")),
                     "--figure", str(scene_file), "--no-progress"]) == 2
    assert "is the input file" in one_line(capsys.readouterr().err)
    assert scene_file.read_text() == text
    assert not scene_file.with_suffix(".nc").exists()


def test_an_existing_directory_and_an_empty_path_are_refused(scene_file, tmp_path, no_work,
                                                             capsys):
    folder = tmp_path / "out"
    folder.mkdir()
    assert cli_main(["run", str(scene_file), "-o", str(folder), "--no-progress"]) == 2
    assert "is an existing directory" in one_line(capsys.readouterr().err)
    assert cli_main(["run", str(scene_file), "-o", "", "--no-progress"]) == 2
    assert "path is empty" in one_line(capsys.readouterr().err)
    assert cli_main(["run", str(scene_file), "-o", str(tmp_path / "a.nc"), "--figure", "",
                     "--no-progress"]) == 2
    assert "path is empty" in one_line(capsys.readouterr().err)
    assert cli_main(["run", str(scene_file), "-o", str(tmp_path / "a.nc"), "--figure",
                     str(tmp_path / "a.nc"), "--no-progress"]) == 2
    assert "is also the archive" in one_line(capsys.readouterr().err)
    for bad in (folder, ""):
        with pytest.raises(OutputPathError):
            cp.simulate(TINY, bad)
    assert list(folder.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "scene.toml"]


def test_bad_output_path_through_a_fresh_process(scene_file, tmp_path):
    res = cli("run", scene_file, "-o", tmp_path, "--no-progress")
    assert res.returncode == 2
    assert "is an existing directory" in one_line(res.stderr)


# --------------------------------------------------------------------------- resume lock

def test_a_second_resumable_run_gets_one_line_and_touches_nothing(scene_file, tmp_path,
                                                                   capsys):
    """While another process holds the resume lock of the target (here: this test),
    `run --resume` exits with 3 and leaves the folder exactly as it was."""
    target = tmp_path / "run.nc"
    part = tmp_path / ".run.nc.resumable.part"
    part.write_bytes(b"the other run's part file")
    with exclusive_lock(resume_lock(target), "test"):
        listing = {p.name: (p.stat().st_size, p.stat().st_mtime_ns)
                   for p in tmp_path.iterdir()}
        assert cli_main(["run", str(scene_file), "-o", str(target), "--resume",
                         "--no-progress"]) == 3
        line = one_line(capsys.readouterr().err)
        assert "another resumable run of run.nc holds the lock" in line
        assert {p.name: (p.stat().st_size, p.stat().st_mtime_ns)
                for p in tmp_path.iterdir()} == listing
        with pytest.raises(simulation.ResumeLockedError):
            cp.simulate(TINY, target, resume=True)
    assert part.read_bytes() == b"the other run's part file"
    # the lock released, the run goes ahead (the stale part file is not of a checkpoint)
    assert cli_main(["run", str(scene_file), "-o", str(target), "--resume",
                     "--no-progress"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc", "scene.toml"]
    cp.open_archive(target, verify=True)


def slow_scene_file(tmp_path, steps=3000):
    """A fretting run of a few minutes on 24 x 24 cells (it is stopped long before)."""
    f = tmp_path / "slow.toml"
    f.write_text(TINY_SCENES["fretting"].replace("steps = 20", f"steps = {steps}"))
    return f


def wait_for(predicate, proc, seconds=120):
    deadline = time.time() + seconds
    while time.time() < deadline:
        if predicate():
            return
        if proc.poll() is not None:
            raise AssertionError(f"the run ended early: {proc.stderr.read()}")
        time.sleep(0.05)
    raise AssertionError("timed out")


def start_run(*args):
    return subprocess.Popen([sys.executable, "-m", "contactpipe.pipeline.cli", "run",
                             *map(str, args), "--no-progress"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env(),
                            start_new_session=True)


def test_two_concurrent_resumable_runs(tmp_path):
    """Two real processes: the second exits with 3 at once; the first, terminated, keeps a
    part file the next run resumes or restarts into a valid archive."""
    scene = slow_scene_file(tmp_path)
    target = tmp_path / "run.nc"
    first = start_run(scene, "-o", target, "--resume")
    try:
        wait_for(lambda: (tmp_path / ".run.nc.resumable.part").exists(), first)
        second = cli("run", scene, "-o", target, "--resume", "--no-progress")
        assert second.returncode == 3
        assert "holds the lock" in one_line(second.stderr)
        assert first.poll() is None
    finally:
        first.send_signal(signal.SIGTERM)
        first.wait(timeout=60)
    assert first.returncode == 128 + signal.SIGTERM
    assert not target.exists() and (tmp_path / ".run.nc.resumable.part").exists()
    short = tmp_path / "short.toml"
    short.write_text(scene.read_text().replace("steps = 3000", "steps = 10"))
    res = cli("run", short, "-o", target, "--resume", "--no-progress")
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc", "short.toml", "slow.toml"]
    assert cp.open_archive(target, verify=True).sizes["time"] == 11


# --------------------------------------------------------------------------- signals

@pytest.mark.parametrize("signame", ["SIGTERM", "SIGHUP"])
def test_termination_signals_clean_up_like_ctrl_c(signame, tmp_path):
    """A run terminated mid-way exits with 128 + the signal number after one line, and
    leaves no temporary file and no archive."""
    signum = getattr(signal, signame)
    scene = slow_scene_file(tmp_path)
    target = tmp_path / "run.nc"
    proc = start_run(scene, "-o", target)
    try:
        wait_for(lambda: list(tmp_path.glob(".run.nc.*.part")), proc)
        time.sleep(0.5)
        assert proc.poll() is None
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 128 + signum
    assert one_line(err) == f"contactpipe: interrupted ({signame})"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["slow.toml"]


def test_terminated_resumable_run_keeps_its_state(tmp_path):
    """SIGTERM on a resumable run keeps the part file and the checkpoint, as Ctrl-C does;
    resumed, the run completes."""
    scene = slow_scene_file(tmp_path, steps=400)
    target = tmp_path / "run.nc"
    runner = ("import sys, contactpipe as cp\n"
              "from contactpipe.pipeline.cli import main\n"
              "import contactpipe.simulation.march as s\n"
              "s.run_scene.__kwdefaults__['checkpoint_seconds'] = 0.0\n"
              "sys.exit(main(sys.argv[1:]))\n")
    proc = subprocess.Popen([sys.executable, "-c", runner, "run", str(scene), "-o",
                             str(target), "--resume", "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env(), start_new_session=True)
    try:
        wait_for(lambda: (tmp_path / ".run.nc.ckpt.npz").exists(), proc)
        time.sleep(0.3)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, err
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [".run.nc.ckpt.npz", ".run.nc.resumable.part", "slow.toml"], names
    with np.load(tmp_path / ".run.nc.ckpt.npz") as z:
        assert 0 <= int(z["k"]) < 400
    ds = cp.simulate(cp.Scene.from_toml(scene), target, resume=True)
    assert ds.sizes["time"] == 401
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc", "slow.toml"]


# --------------------------------------------------------------------------- resources

def huge(scene=TINY, n=4096):
    return scene.replace({"grid.points": [n, n]})


def test_estimate_grows_with_the_grid_and_is_refused_beyond_the_limit():
    small = estimate_resources(TINY, cp.plan(TINY))
    big = estimate_resources(huge(), cp.plan(huge()))
    ratio = (big.memory_bytes - big.parts["base"]) / (small.memory_bytes - small.parts["base"])
    assert big.grid == (4096, 4096) and big.memory_bytes > 6 * 2**30
    assert ratio > 1000                          # 16.7 M cells against 576 (plus the fixed)
    assert check_resources(small, available=2**30) is small
    with pytest.raises(SceneError, match=r"^the run needs about .* GiB \(\d+\.\d KiB per cell; "
                                         r"operators .*\) and "
                                         r"at least .* for 11 instants on 4096x4096 cells, "
                                         r"but only 6.0 GiB is available \(given limit\); "
                                         r"use fewer grid.points"):
        check_resources(big, available=6 * 2**30)


def limit_address_space():
    resource.setrlimit(resource.RLIMIT_AS, (6 * 2**30, 6 * 2**30))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS as on Linux")
def test_4096_grid_under_a_6_gb_address_space(tmp_path):
    scene = tmp_path / "big.toml"
    scene.write_text(huge().to_toml())
    res = cli("run", scene, "-o", tmp_path / "big.nc", "--no-progress",
              preexec_fn=limit_address_space)
    assert res.returncode == 2, res.stderr
    line = one_line(res.stderr)
    assert "4096x4096 cells" in line and "address space left under RLIMIT_AS" in line
    assert "use fewer grid.points" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.toml"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS as on Linux")
def test_an_accuracy_preset_that_picks_a_huge_grid(tmp_path):
    """solver.accuracy = 'accurate' on a grid 100 times the contact picks 4096 x 4096 by
    itself; the estimate is made after that choice."""
    scene = TINY.replace({"solver.accuracy": "accurate", "grid.size": [0.1, 0.1]})
    resolved, note = resolve_accuracy(scene)
    assert resolved.grid.points == (4096, 4096), note
    f = tmp_path / "preset.toml"
    f.write_text(scene.to_toml())
    res = cli("run", f, "-o", tmp_path / "p.nc", "--no-progress",
              preexec_fn=limit_address_space)
    assert res.returncode == 2, res.stderr
    assert "4096x4096 cells" in one_line(res.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["preset.toml"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self of Linux")
def test_the_estimate_bounds_a_measured_peak(tmp_path):
    """The calibration holds: a 128 x 128 fretting run (rigid on Maxwell, coupled, 5 steps)
    peaks below its estimate (measured 61.6-62.2 MiB against 70.5 MiB estimated, the
    windows of the contact and the archive writer's three instants included). The peak is
    the resident high-water mark (VmHWM) after resetting it (/proc/self/clear_refs), so
    the imports' own peak does not count (nor that of dask.array and scipy.ndimage,
    which the run imports where it uses them: xarray to open the archive, the preload's
    self-similar start)."""
    code = ("import re, contactpipe as cp\n"
            "import contactpipe.simulation  # import contactpipe is lazy: load it first\n"
            "import dask.array, scipy.ndimage  # the run imports them where used: imports\n"
            "from contactpipe.testing import TINY_SCENES\n"
            "from contactpipe.planning import estimate_resources\n"
            "sc = cp.Scene.from_toml_text(TINY_SCENES['fretting']).replace("
            "{'grid.points': [128, 128], 'time.steps': 5})\n"
            "kb = lambda key: int(re.search(key + r':\\s+(\\d+)', "
            "open('/proc/self/status').read()).group(1)) * 1024\n"
            "open('/proc/self/clear_refs', 'w').write('5')\n"
            "before = kb('VmRSS')\n"
            f"cp.simulate(sc, {str(tmp_path / 'm.nc')!r})\n"
            "print(kb('VmHWM') - before, estimate_resources(sc).memory_bytes)\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env(), timeout=600)
    if res.returncode and "clear_refs" in res.stderr:
        pytest.skip("the peak cannot be reset here (/proc/self/clear_refs)")
    assert res.returncode == 0, res.stderr
    measured, estimate = map(int, res.stdout.split())
    assert 0 < measured < estimate, (measured, estimate)


# --------------------------------------------------------------------------- small traps

def test_extreme_constants_end_in_one_line_without_runtime_warnings(tmp_path):
    """Moduli, relaxation times, forces and time spans at the edge of float64: the kernels,
    the history or the solvers' inner products would overflow (numpy warned, and the run
    ended on a NaN residual or a NaN refused by the writer); the run refuses the scene
    before solving, in one line, and numpy stays silent. (Their contacts would not fit the
    grid either: that check, made first, is left to the run here.)"""
    cases = {"halfspace.young": 1e-300, "halfspace.relaxation_time": 1e-300,
             "load.time": [0.0, 1e300], "load.normal_force": 1e300}
    for key, value in cases.items():
        f = tmp_path / "x.toml"
        f.write_text(TINY.replace({key: value, "grid.size_check": False}).to_toml())
        res = cli("run", f, "-o", tmp_path / "x.nc", "--no-progress")
        assert res.returncode == 2, (key, res.stderr)
        assert re.search("overflow|beyond float64", one_line(res.stderr))
        assert not (tmp_path / "x.nc").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        for key, value in cases.items():
            with pytest.raises(SceneError, match="overflow|beyond float64"):
                cp.simulate(TINY.replace({key: value, "grid.size_check": False}))


def test_float32_overflow_is_refused_without_a_warning(tmp_path):
    """A value beyond float32 in a float32 archive: refused by the writer, in words."""
    names = variables_for(False)
    w = ArchiveWriter(tmp_path / "f.nc", np.arange(3.0), np.arange(2.0), names,
                      {"scene": "", "models": "normal"}, precision="float32")
    values = {n: np.zeros((3, 2)) if n in ("p", "u3", "h", "status") else 0.0 for n in names}
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(ArchiveError, match="p: exceeds the range of float32"):
            w.append(0.0, {**values, "p": np.full((3, 2), 1e39)})
    w.abort()


def test_off_knot_warning_stays_short_for_100000_cycles():
    """A fretting preset of 100 000 cycles whose knots miss the mesh: the warning names the
    first 5 knots and counts the others (it listed all 200 001 knots, 2 MB, before)."""
    d = TINY.to_dict()
    d.update(friction={"mu": 0.1}, time={"steps": 7},
             load={"normal_force": 1000.0,
                   "fretting": {"amplitude": 50.0, "window": 1.0, "cycles": 100_000}})
    scene = cp.Scene(**d)
    with pytest.warns(UserWarning, match=r"load knots at t = [^,]+, [^,]+, [^,]+, [^,]+, "
                                         r"[^,]+ and \d+ more s fall between") as record:
        with pytest.raises(cp.ContactpipeError):
            cp.simulate(scene.replace({"solver.max_iterations": 1}))
    assert all(len(str(w.message)) < 400 for w in record)


# --------------------------------------------------------------------------- the publish

#: `contactpipe run` several times in one process, each with Ctrl-C (SIGINT) sent at one
#: moment around the archive's publication: MODE "readback" (while the written file is
#: read back and checked), "fsync" (inside the publication, while the file is flushed to
#: disk before its rename), "rename" (in the same instant as the rename: the signals are
#: held back from the last check to the end of the rename), "after" (once the rename is
#: done), or "timer" (from another thread, DELAY seconds after the publication starts, so
#: that it lands anywhere in or after it). Prints "code=N" per run: its exit status.
PUBLISH_RUNNER = r"""
import os, signal, sys, threading
import contactpipe.archive.writer as writer
import contactpipe._util.files as files
from contactpipe.pipeline.cli import main
mode, scene, out, delays = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
real_rename, real_problems, real_publish = os.replace, writer._written_problems, writer.publish
real_fsync = files.fsync_file
timer = []
def kill():
    os.kill(os.getpid(), signal.SIGINT)
def problems(*args, **kwargs):
    if mode == "readback":
        kill()
    return real_problems(*args, **kwargs)
def fsync(path):
    if mode == "fsync":
        kill()
    real_fsync(path)
def rename(src, dst):
    if mode == "rename":
        kill()
    real_rename(src, dst)
    if mode == "after":
        kill()
def publish(*args, **kwargs):
    if mode == "timer":
        timer.append(threading.Timer(float(delays[run]), kill))
        timer[-1].start()
    real_publish(*args, **kwargs)
    if timer:
        timer.pop().join()         # the signal is sent before the run ends
files.fsync_file = fsync
writer._written_problems, writer.publish, files.os = problems, publish, type(
    "os", (), {**{k: getattr(os, k) for k in dir(os) if not k.startswith("__")},
               "replace": staticmethod(rename)})
for run in range(len(delays) or 1):
    code = main(["run", scene, "-o", os.path.join(out, f"run{run}.nc"), "--no-progress"])
    print(f"code={code}", flush=True)
"""


def publish_runs(tmp_path, mode, delays=()):
    scene = tmp_path / "scene.toml"
    scene.write_text(TINY_SCENES["creep"].replace("steps = 10", "steps = 2"))
    out = tmp_path / "out"
    out.mkdir()
    res = subprocess.run([sys.executable, "-c", PUBLISH_RUNNER, mode, str(scene), str(out),
                          *map(str, delays)], capture_output=True, text=True, env=env(),
                         timeout=600)
    assert res.returncode == 0, res.stderr
    assert "Exception ignored" not in res.stderr and "Traceback" not in res.stderr
    codes = [int(w[5:]) for w in res.stdout.split() if w.startswith("code=")]
    return codes, res.stderr.splitlines(), out


@pytest.mark.parametrize("mode", ["readback", "fsync"])
def test_ctrl_c_before_the_rename_publishes_nothing(tmp_path, mode):
    """Ctrl-C while the archive is read back, or inside its publication before the rename
    (its fsync): exit 130, one line, no archive and no temporary file."""
    codes, lines, out = publish_runs(tmp_path, mode)
    assert codes == [130]
    assert lines == ["contactpipe: interrupted (SIGINT)"]
    assert sorted(p.name for p in out.iterdir()) == []


@pytest.mark.parametrize("mode", ["rename", "after"])
def test_ctrl_c_after_the_rename_completes_the_run(tmp_path, mode):
    """Ctrl-C once the archive is renamed into place (or in the instant of the rename,
    held back until it is done): the run is complete (exit 0, a valid archive) and one
    line says the signal came after the publication."""
    codes, lines, out = publish_runs(tmp_path, mode)
    assert codes == [0]
    assert lines == ["contactpipe: SIGINT came after the output was published: the run "
                     "is complete"]
    assert sorted(p.name for p in out.iterdir()) == ["run0.nc"]
    cp.open_archive(out / "run0.nc", verify=True)


def test_ctrl_c_timed_around_the_publish_is_never_lost(tmp_path):
    """Ctrl-C from another thread 0 to 3 ms after the publication starts (12 runs): each
    run either exits 130 with no archive or exits 0 with a valid archive and the line
    saying the signal came after; never 0 in silence, never a temporary file left."""
    delays = [i * 2.5e-4 for i in range(12)]
    codes, lines, out = publish_runs(tmp_path, "timer", delays)
    assert len(codes) == 12 and set(codes) <= {0, 130}, codes
    late = "contactpipe: SIGINT came after the output was published: the run is complete"
    assert lines == [late if c == 0 else "contactpipe: interrupted (SIGINT)" for c in codes]
    assert sorted(p.name for p in out.iterdir()) == sorted(f"run{i}.nc" for i, c in
                                                           enumerate(codes) if c == 0)
    for i, c in enumerate(codes):
        if c == 0:
            cp.open_archive(out / f"run{i}.nc", verify=True)


# --------------------------------------------------------------------------- solver failures
# A solve that stops says why with finite figures: never a residual of inf (or 1e299) or an
# overflow blamed on ordinary constants (issue 42, items 13 and 25).

ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}


def _figure(name, text):
    """The number after 'name = ' (or 'name ') in a message."""
    m = re.search(re.escape(name) + r" =? ?(-?[0-9.]+(?:e[-+]?\d+)?|inf|nan)", text)
    assert m, (name, text)
    return float(m.group(1))


ELLIPSOID_TOML = """
[geometry]
shape = "ellipsoid"
radii = [0.2283, 0.0890]
[indenter]
material = "rigid"
[halfspace]
material = "elastic"
young = 50.6e9
poisson = 0.109
[friction]
mu = 0.1
[load]
time = [0.0, 1.3, 1.6]
normal_force = 5431.6
[grid]
points = [16, 48]
size = [3.32e-4, 3.15e-3]
[time]
steps = 26
[solver]
max_coupling_passes = 1
fft = "scipy"
"""

SPHERE_TOML = """
[geometry]
shape = "sphere"
radius = 2.367e-3
[indenter]
material = "elastic"
young = 17.26e6
poisson = 0.5
[halfspace]
material = "elastic"
young = 1.669e6
poisson = 0.3
[friction]
mu = 0.3
[load]
normal_approach = 1.8046e-7
rotation1 = 2.488e-6
fretting = {amplitude = 0.5068, window = 0.02203, cycles = 2, direction = 161.7}
[grid]
points = [12, 16]
size = [4.965e-3, 1.590e-4]
[time]
steps = 16
[solver]
fft = "scipy"
"""


def test_open_contact_under_an_approach_is_gross_sliding_not_an_overflow():
    """The issue's sphere (R = 2.367 mm, approach 0.18 µm, 12 x 16 cells of 414 x 10 µm):
    the Hertz contact, a = sqrt(R omega3) = 20.7 µm, lies between the cell centres
    (the nearest at x1 = ±207 µm, gap 9.0 µm >> omega3), so the approach leaves the
    contact open, W = 0, and the fretting force at step 1 has nothing to hold it. Was:
    'tangential problem ... residual 2.85e+299'. Now a GrossSlidingError naming the
    step, |T| (the program's value there), mu W = 0 and the open contact."""
    scene = cp.Scene.from_toml_text(SPHERE_TOML)
    a = np.sqrt(2.367e-3 * 1.8046e-7)
    assert a < 0.5 * 4.965e-3 / 12                  # within the central cells' gap
    program = scene.load.programs(16)
    T1 = float(np.hypot(program.force[1, 1], program.force[2, 1]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")              # the off-knot warning of the mesh
        with pytest.raises(cp.GrossSlidingError) as err:
            cp.simulate(scene)
    text = str(err.value)
    assert text.startswith("at step 1 (t = ")
    assert _figure("|T|", text) == pytest.approx(T1, rel=1e-5)
    assert _figure("mu W", text) == 0.0 and _figure("W", text.split("(mu")[1]) == 0.0
    assert "the contact is open" in text and "load.normal_approach" in text
    assert "overflow" not in text and "e+299" not in text and "inf" not in text


def test_issue_ellipsoid_names_the_grid_not_an_overflow():
    """The issue's ellipsoid (rigid on 50.6 GPa, W = 5431.6 N, 16 x 48 cells over
    0.332 x 3.15 mm, one coupling pass): the Hertz contact, semi-axes 3.08 x 1.64 mm,
    is ten times the grid's half side along x1, so the contact is cut by the grid's
    edge. Was: 'coupling problem ... residual inf ... overflowed float64'. Now the scene
    is refused when read, naming grid.size and the least size that fits; with the check
    left to the run (grid.size_check = false), the GridError naming the edge and the
    stopped solve."""
    with pytest.raises(cp.SceneError, match=r"^grid\.size = \[0\.000332, 0\.00315\] m is "
                                            r"too small .*give grid\.size = "):
        cp.Scene.from_toml_text(ELLIPSOID_TOML)
    scene = cp.Scene.from_toml_text(ELLIPSOID_TOML.replace(
        "[grid]", "[grid]\nsize_check = false"))
    a1, a2 = scene.hertz_semi_axes()
    assert a1 == pytest.approx(3.08e-3, rel=0.01) and a1 > 9 * 0.5 * 3.32e-4
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(cp.GridError, match=r"^step 0 \(t = 0 s\): the contact reached "
                                               r"the edge of the grid .*stopped short"):
            cp.simulate(scene)


def test_one_coupling_pass_settles_a_steady_step_and_reports_finite_changes():
    """Steel on aluminium (beta != 0), W = 1 kN, 24², mu = 0.1. A frictionless preload
    then the same W with friction: step 1 moves the pressure by less than the tolerance,
    which one pass settles (was: 'residual inf'). A frictional preload needs passes:
    with 1, 2 or 3 allowed it stops with the pressure change the next pass measured,
    finite, each pass cutting it by over 100 (Gauss-Seidel's contraction; measured
    4.2e-3, 8.9e-6, 7.7e-8 of W)."""
    base = dict(indenter=dict(helpers.STEEL), halfspace=dict(ALUMINIUM),
                friction={"mu": 0.1},
                grid={"points": [24, 24], "size": [4 * helpers.A_HERTZ] * 2})
    ds = cp.simulate(helpers.make_scene(
        **base, load={"time": [0.0, 1.0], "normal_force": helpers.W,
                      "preload": "frictionless"},
        solver={"max_coupling_passes": 1, "fft": "scipy"}))
    p0, p1 = ds["p"].isel(time=0).values, ds["p"].isel(time=1).values
    cell = (4 * helpers.A_HERTZ / 24) ** 2
    assert np.abs(p1 - p0).sum() * cell / helpers.W < 1e-9      # the solver's tolerance
    changes = []
    for passes in (1, 2, 3):
        with pytest.raises(cp.ConvergenceError) as err:
            cp.simulate(helpers.make_scene(
                **base, load={"time": [0.0, 1.0], "normal_force": helpers.W},
                solver={"max_coupling_passes": passes, "fft": "scipy"}))
        text = str(err.value)
        assert f"did not settle in {passes} pass" in text and "overflow" not in text
        changes.append(_figure("residual", text))
        assert _figure("moving by", text) == changes[-1]
    assert all(np.isfinite(changes)) and 1e-9 < changes[-1]
    assert changes[0] > 100 * changes[1] > 100 * 100 * changes[2]


def test_approach_control_with_t_above_mu_w_names_gross_sliding():
    """Steel on steel (R = 18 mm), the approach of Hertz's W = 1 kN held, T1 to 0.75 and
    then 1.5 mu W. Under approach control W is an outcome, so the scene is valid and
    step 2 finds |T| above mu W: a GrossSlidingError naming the step, its time, |T|,
    mu and the W reached, which is Hertz's (4/3) E* R^½ omega3^1.5 within 2 % (32²
    over 4a). Was: 'tangential problem ... residual 0.5'."""
    omega3 = helpers.A_HERTZ ** 2 / helpers.R
    W_hertz = 4 / 3 * helpers.E_STAR_STEEL * np.sqrt(helpers.R) * omega3 ** 1.5
    assert W_hertz == pytest.approx(helpers.W, rel=1e-12)
    mu = 0.1
    scene = helpers.make_scene(
        friction={"mu": mu},
        load={"time": [0.0, 1.0, 2.0], "normal_approach": omega3,
              "tangential_force": [0.0, 0.75 * mu * W_hertz, 1.5 * mu * W_hertz]},
        grid={"points": [32, 32], "size": [4 * helpers.A_HERTZ] * 2},
        time={"steps": 2}, solver={"fft": "scipy"})
    with pytest.raises(cp.GrossSlidingError) as err:
        cp.simulate(scene)
    text = str(err.value)
    assert text.startswith("at step 2 (t = 2 s) the tangential force |T| = 150 N reaches")
    W = _figure("W", text.split("(mu")[1])
    assert W == pytest.approx(W_hertz, rel=0.02)
    assert _figure("mu W", text) == pytest.approx(mu * W, rel=1e-5)
    assert f"(mu = {mu:g}, W = " in text
    assert "gross sliding under force control has no static solution" in text
    assert "residual" not in text


def test_a_solve_that_stops_on_a_contact_cut_by_the_grid_names_the_grid():
    """A flat punch of radius 1.3 mm on 29 x 10 cells of 0.19 x 4.87 mm: no cell centre
    lies on the flat end, so the gap is the punch's height in every cell and the whole
    grid presses, edges included. A solve that stops there (here after
    solver.max_iterations = 30; a random scene's stalled for 8362 iterations) is a
    GridError naming the edge and the stopped normal problem, not a bare ConvergenceError
    (was: 'normal problem ... stopped after 30 iterations, residual 6.86e-09')."""
    scene = helpers.make_scene(
        geometry={"shape": "flat_punch", "radius": 1.3e-3}, indenter={"material": "rigid"},
        halfspace=dict(helpers.STEEL), load={"time": [0.0, 1.0], "normal_force": 1.0},
        grid={"points": [29, 10], "size": [5.6e-3, 48.7e-3]},
        solver={"max_iterations": 30, "fft": "scipy"})
    assert 1.3e-3 < 0.5 * 48.7e-3 / 10                # below half a cell along x2
    with pytest.raises(cp.GridError, match=r"^step 0 \(t = 0 s\): the contact reached the "
                                           r"edge of the grid .*and the normal problem "
                                           r"stopped short of its tolerance there"):
        cp.simulate(scene)


def test_kelvin_voigt_under_a_frictionless_preload_on_a_coupled_pair():
    """A rigid sphere on a Kelvin-Voigt half-space (nu = 0.3: the pair couples), W = 100 N
    as a frictionless preload, 24² auto grid, 4 steps. At t0 the body has no
    instantaneous elasticity, so the force goes to the cells of least gap (the 4 central
    ones) and the rigid instant moves nothing in-plane; the contact then grows as the
    body creeps (measured 164, 192, 208, 208 cells), W held and every contact law
    holding. Was: a
    TypeError from the rigid instant's missing coupling kernels."""
    scene = helpers.make_scene(
        indenter={"material": "rigid"},
        halfspace={"material": "viscoelastic", "young": 1.0e9, "poisson": 0.3,
                   "creep": "kelvin_voigt", "retardation_time": 0.2},
        friction={"mu": 0.1},
        load={"time": [0.0, 1.0], "normal_force": 100.0, "preload": "frictionless"},
        grid={"points": [24, 24], "size": "auto"}, time={"steps": 4},
        solver={"fft": "scipy"})
    ds = cp.simulate(scene)
    assert "coupling=gauss_seidel" in ds.attrs["models"]
    assert_contact_laws(ds)
    cell = float(np.prod(ds.attrs["grid_spacing_m"]))
    p = ds["p"].values
    np.testing.assert_allclose(p.sum(axis=(1, 2)) * cell, 100.0, rtol=1e-9)   # W held
    cells = [int(np.count_nonzero(pk)) for pk in p]
    assert cells[0] == 4 and cells[1] > 4 and cells == sorted(cells)


def test_kelvin_voigt_under_approach_control_starts_from_rest_or_says_why():
    """A rigid sphere on a Kelvin-Voigt half-space (no instantaneous elasticity), 24²,
    4 steps over 1 s. An approach ramped from 0 to 20 µm is valid: at t0 nothing is
    asked and nothing touches (p = 0, W = 0), after it W grows as the body creeps
    (measured 6.4 to 27 N), the laws holding (was: 'normal problem ... residual inf').
    An approach of 20 µm as a step at t0 has no solution (a rigid instant would need an
    infinite pressure): the scene is refused when read, in one line saying so."""
    kv = {"material": "viscoelastic", "young": 1.0e9, "poisson": 0.5,
          "creep": "kelvin_voigt", "retardation_time": 0.2}

    def scene(approach):
        return helpers.make_scene(
            indenter={"material": "rigid"}, halfspace=kv, friction={"mu": 0.1},
            load={"time": [0.0, 1.0], "normal_approach": approach},
            grid={"points": [24, 24], "size": [4e-3, 4e-3]}, time={"steps": 4},
            solver={"fft": "scipy"})

    ds = cp.simulate(scene([0.0, 2e-5]))
    assert_contact_laws(ds)
    W = ds["W"].values
    assert W[0] == 0.0 and np.all(np.diff(W) > 0.0)
    assert not ds["p"].isel(time=0).values.any()
    with pytest.raises(cp.SceneError) as err:          # refused when the scene is read
        scene(2e-5)
    text = str(err.value)
    assert text.startswith("load.normal_approach = 2e-05 m at t = 0 s")
    assert "no body has instantaneous elasticity" in text and "\n" not in text


def test_a_moment_on_a_contact_one_cell_wide_converges():
    """A rigid sphere (R = 46.4 mm) on a 76 MPa half-space, W = 723 N, M1 = -0.413 N m,
    tilted by rotation2 = -0.0388 rad, on 9 x 38 cells of 266 x 2.33 mm: the contact is
    one cell wide along x1 and two cells long, as many free cells as the force rows (W,
    M1), and the CG's active set cycled between cell pairs (Σ|Δp| = 2 Σp at every step,
    2000 iterations: 'normal problem ... residual 2'). The projected-gradient fallback
    ends it: W and M1 reached to 1e-9, the pressure centre at M1/W."""
    scene = helpers.make_scene(
        geometry={"shape": "sphere", "radius": 0.04643979929216626},
        indenter={"material": "rigid"},
        halfspace={"material": "elastic", "young": 75998621.96315412, "poisson": 0.0},
        load={"time": [0.0, 1.0], "normal_force": 722.9615772888106,
              "moment1": -0.4132465727632563, "rotation2": -0.03883761879150109},
        grid={"points": [9, 38], "size": [2.392623189594096, 0.08865769085942814]},
        solver={"fft": "scipy"})
    ds = cp.simulate(scene)
    W, M1 = 722.9615772888106, -0.4132465727632563
    np.testing.assert_allclose(ds["W"].values, W, rtol=1e-9)
    np.testing.assert_allclose(ds["M1"].values, M1, rtol=1e-9)
    p = ds["p"].values[-1]
    x2 = ds["x2"].values
    assert np.all(p >= 0.0)
    assert (p.sum(axis=0) * x2).sum() / p.sum() == pytest.approx(M1 / W, rel=1e-9)


@pytest.mark.parametrize("nu, start", [(0.0, 0.0), (0.5, 0.0), (0.3, 5e-8)])
def test_kelvin_voigt_under_a_tangential_displacement(nu, start):
    """A rigid sphere on a Kelvin-Voigt half-space (nu = 0, 0.3: the pair couples; 0.5:
    it does not), W = 10 N, mu = 0.5, the tangential displacement from `start` to 2 µm
    over 4 steps, 24² auto grid, frictional preload. At t0 the body has no instantaneous
    elasticity: a displacement that does not move leaves the shear at rest (T1 = 0), one
    that moves makes the rigid instant slide as a whole (T1 = mu W exactly). After it the
    body creeps and every contact law holds. Was: NaN shear refused by the archive
    (q ∝ p T/W with T NaN under displacement control) or a TypeError (the coupling
    kernels of the rigid instant)."""
    scene = helpers.make_scene(
        indenter={"material": "rigid"},
        halfspace={"material": "viscoelastic", "young": 1.0e9, "poisson": nu,
                   "creep": "kelvin_voigt", "retardation_time": 0.2},
        friction={"mu": 0.5},
        load={"time": [0.0, 1.0], "normal_force": 10.0,
              "tangential_displacement": [start, 2e-6]},
        grid={"points": [24, 24], "size": "auto"}, time={"steps": 4},
        solver={"fft": "scipy"})
    ds = cp.simulate(scene)
    assert_contact_laws(ds)
    T1 = ds["T1"].values
    assert T1[0] == pytest.approx(0.5 * 10.0 if start else 0.0, rel=1e-12, abs=1e-12)
    assert np.all(np.isfinite(ds["q1"].values)) and np.all(T1[1:] > 0.0)
