"""Archives: round trips, precision and compression, atomic writes, refusals."""
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import textwrap
import zlib

import dask.array as da
import netCDF4
import numpy as np
import pytest
import xarray as xr

import contactpipe as cp
from contactpipe.archive import (
    ArchiveWriter,
    MemoryWriter,
    content_problems,
    is_complete,
    open_archive,
    save,
    to_dataset,
    validate,
)
from contactpipe.exceptions import ArchiveError
from contactpipe.nomenclature import STATUS_STICK, VARIABLES
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.testing import TINY_SCENES

ROOT = pathlib.Path(__file__).resolve().parents[1]
CHECKER = ROOT.parent / "shared" / "tools" / "check_contract.py"

N1, N2 = 6, 5
L1, L2 = 1.2e-3, 1.0e-3
X1 = -L1 / 2 + (np.arange(N1) + 0.5) * L1 / N1
X2 = -L2 / 2 + (np.arange(N2) + 0.5) * L2 / N2
TIMES = [0.0, 0.2, 0.6, 1.0]
MU = 0.1
SCENE = 'name = "synthetic"\n\n[friction]\nmu = 0.1\n'
ATTRS = {"scene": SCENE, "models": "normal, tangential, coupling, memory"}
WALL = {"wall_time_s": 1.25}
NAMES = [n for n in VARIABLES if n not in ("coupling_passes", "fft_pairs")]


def synthetic_steps():
    """Four instants of a made-up frictional contact that obeys the contact laws.

    Paraboloidal pressure on a disc, q1 = c mu p (full mu p in the slipping rim), gap zero
    under pressure, slip increments with the sign of q1 in slipping cells.
    """
    cell = (L1 / N1) * (L2 / N2)
    r2 = X1[:, None] ** 2 + X2[None, :] ** 2
    a2 = (0.45e-3) ** 2
    shape = np.clip(1.0 - r2 / a2, 0.0, None)
    inside = shape > 0
    rim = inside & (r2 > 0.5 * a2)
    s1 = np.zeros((N1, N2))
    dissipation = 0.0
    steps = []
    for k, (t, c) in enumerate(zip(TIMES, [0.2, 0.5, -0.5, 0.5], strict=True)):
        p = 1e9 * (1 + 0.1 * k) * shape
        slip = rim if k else np.zeros_like(rim)
        q1 = np.where(slip, np.sign(c) * MU * p, c * MU * p)
        ds1 = np.where(slip, np.sign(c) * 1e-8, 0.0)
        s1 = s1 + ds1
        dissipation += float((q1 * ds1).sum() * cell)
        status = np.where(inside, np.where(slip, 2, 1), 0).astype(np.int8)
        steps.append((t, {
            "p": p, "q1": q1, "q2": np.zeros((N1, N2)),
            "u1": 1e-7 * X1[:, None] * np.ones(N2), "u2": 1e-7 * X2[None, :] * np.ones((N1, 1)),
            "u3": -1e-6 + r2 * 0.0, "h": np.where(inside, 0.0, r2 - a2),
            "s1": s1.copy(), "s2": np.zeros((N1, N2)), "status": status,
            "W": float(p.sum() * cell), "T1": float(q1.sum() * cell), "T2": 0.0,
            "omega1": 1e-7 * c, "omega2": 0.0, "omega3": 1e-6 * (1 + k),
            "contact_area": float(inside.sum() * cell),
            "stick_area": float((status == STATUS_STICK).sum() * cell),
            "dissipation": dissipation, "iterations": 10 + k,
            "M1": float((p * X2[None, :]).sum() * cell),
            "M2": float((p * X1[:, None]).sum() * cell),
            "M3": float((-q1 * X2[None, :]).sum() * cell),
            "phi1": 0.0, "phi2": 0.0, "phi3": 0.0,
        }))
    return steps


def write(path, **kw):
    with ArchiveWriter(path, X1, X2, NAMES, ATTRS, **kw) as w:
        for t, values in synthetic_steps():
            w.append(t, values)
        w.close(WALL)
    return path


def in_memory(**kw):
    w = MemoryWriter(None, X1, X2, NAMES, ATTRS, **kw)
    for t, values in synthetic_steps():
        w.append(t, values)
    return w.close(WALL)


def without_complete(ds):
    assert ds.attrs["complete"] == "true"
    ds = ds.copy()
    del ds.attrs["complete"]
    return ds


def test_writer_round_trip_identical_to_memory_writer(tmp_path):
    path = write(tmp_path / "run.nc")
    ds = open_archive(path)
    assert isinstance(ds["p"].data, da.Array), "fields must be lazy (dask-backed)"
    assert ds["p"].chunks[0] == (1,) * len(TIMES), "one time step per chunk of a field"
    for name in NAMES:
        assert ds[name].attrs["units"] == VARIABLES[name]["units"], name
        assert ds[name].attrs["long_name"]
    for name in ("time", "x1", "x2"):
        assert ds[name].attrs["units"] in ("s", "m")
    assert list(ds["status"].attrs["flag_values"]) == [0, 1, 2]
    assert ds["status"].attrs["flag_meanings"] == "separated stick slip"
    assert ds.attrs["Conventions"] == "CF-1.10"
    assert ds.attrs["contactpipe_version"]
    assert ds.attrs["wall_time_s"] == 1.25
    t, values = synthetic_steps()[2]
    np.testing.assert_array_equal(ds["p"].isel(time=2).values, values["p"])
    assert ds["iterations"].dtype == np.int32 and ds["status"].dtype == np.int8
    xr.testing.assert_identical(without_complete(ds.load()), in_memory())
    ds.close()


@pytest.mark.parametrize("capacity", [1, 2, len(TIMES), 100])
def test_memory_writer_capacity_does_not_change_the_dataset(capacity):
    """The instants kept in arrays of the expected length, doubled when full: the Dataset
    is the one of the default capacity, whatever the hint (fewer than the instants, their
    number, more)."""
    ds = in_memory(capacity=capacity)
    xr.testing.assert_identical(ds, in_memory())
    assert ds.sizes["time"] == len(TIMES)


@pytest.mark.parametrize("capacity", [1, len(TIMES)])
def test_memory_writer_mapped_arrays_give_the_same_dataset(monkeypatch, capacity):
    """Arrays kept on anonymous memory maps (the large ones, here every one) hold the
    same steps as numpy's heap arrays, through the doublings (capacity 1), and the
    Dataset keeps using them after the writer is gone (the map lives with the arrays)."""
    from contactpipe.archive import writer
    heap = in_memory(capacity=capacity)
    monkeypatch.setattr(writer, "MAPPED_BYTES", 1)
    mapped = in_memory(capacity=capacity)
    assert _on_map(mapped["p"].values) and not _on_map(heap["p"].values)
    xr.testing.assert_identical(mapped, heap)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self/statm")
def test_memory_writer_map_is_resident_when_made():
    """A large array's pages are made with its map (MAP_POPULATE), not one fault per page
    as the steps fill it: 32 MiB of steps are resident (to 90 %) before any is written,
    and start as zeros."""
    import mmap

    from contactpipe.archive import writer
    if not hasattr(mmap, "MAP_POPULATE"):
        pytest.skip("no MAP_POPULATE on this system")
    page = os.sysconf("SC_PAGE_SIZE")

    def resident() -> int:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * page
    before = resident()
    a = writer._fresh((32, 256, 512), np.float64)
    grown = resident() - before
    assert _on_map(a) and a.nbytes == 32 * 2**20
    assert grown >= 0.9 * a.nbytes
    assert not a[::7, ::31, ::63].any()

def _on_map(a) -> bool:
    """Whether an array's memory is (a view of) an mmap object."""
    import mmap
    while a is not None:
        if isinstance(a, mmap.mmap):
            return True
        a = getattr(a, "base", None) if not isinstance(a, memoryview) else a.obj
    return False


def test_memory_writer_and_save_round_trip(tmp_path):
    mem = in_memory()
    path = save(mem, tmp_path / "mem.nc")
    assert path == tmp_path / "mem.nc"
    ds = open_archive(path)
    xr.testing.assert_identical(without_complete(ds.load()), mem)
    # a lazily opened archive saves again unchanged
    again = save(open_archive(path), tmp_path / "again.nc")
    xr.testing.assert_identical(open_archive(again).load(), ds.load())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["again.nc", "mem.nc"]


def test_writer_equals_save_of_to_dataset(tmp_path):
    steps = synthetic_steps()
    fields = {n: np.stack([np.asarray(v[n]) for _, v in steps]) for n in NAMES}
    ds = to_dataset(X1, X2, TIMES, fields, {**ATTRS, **WALL})
    assert validate(ds) == []
    saved = open_archive(save(ds, tmp_path / "a.nc")).load()
    streamed = open_archive(write(tmp_path / "b.nc")).load()
    xr.testing.assert_identical(saved, streamed)


def test_float32_and_compression(tmp_path):
    ds = open_archive(write(tmp_path / "f32.nc", precision="float32"))
    assert ds["p"].dtype == np.float32 and ds["W"].dtype == np.float32
    assert ds["status"].dtype == np.int8 and ds["iterations"].dtype == np.int32
    assert ds["x1"].dtype == np.float64 and ds["time"].dtype == np.float64
    assert ds["p"].encoding["zlib"] and ds["p"].encoding["chunksizes"] == (1, N1, N2)
    ref = in_memory()
    for name in NAMES:
        np.testing.assert_allclose(ds[name].values, ref[name].values, rtol=1e-6,
                                   err_msg=name)
    xr.testing.assert_identical(without_complete(ds.load()), in_memory(precision="float32"))

    raw = open_archive(write(tmp_path / "raw.nc", compress=False))
    assert not raw["p"].encoding["zlib"] and raw["p"].dtype == np.float64

    saved = open_archive(save(ref, tmp_path / "s32.nc", precision="float32", compress=False))
    assert saved["p"].dtype == np.float32 and not saved["p"].encoding["zlib"]
    assert saved["status"].dtype == np.int8


def test_compression_shrinks_a_compressible_archive(tmp_path):
    """128² zero fields, 3 instants. (The series are stored uncompressed in chunks of a
    fixed size; with the six moment and rotation series of every archive the fields of a
    64² grid no longer outweigh them, so the grid is 128².)"""
    big_x1 = np.linspace(-1e-3, 1e-3, 128)
    big_x2 = np.linspace(-1e-3, 1e-3, 128)
    names = [n for n, e in VARIABLES.items() if e["required"]]
    sizes = {}
    for compress in (True, False):
        path = tmp_path / f"c{compress}.nc"
        with ArchiveWriter(path, big_x1, big_x2, names, ATTRS, compress=compress) as w:
            for k in range(3):
                w.append(k, {n: (np.zeros((128, 128)) if VARIABLES[n]["dims"] != ("time",)
                                 else 0.0) for n in names})
        sizes[compress] = path.stat().st_size
    assert sizes[True] < sizes[False] / 4, sizes


def test_exception_inside_with_leaves_nothing(tmp_path):
    target = tmp_path / "run.nc"
    with pytest.raises(RuntimeError, match="solver blew up"):
        with ArchiveWriter(target, X1, X2, NAMES, ATTRS) as w:
            for t, values in synthetic_steps()[:2]:
                w.append(t, values)
            assert list(tmp_path.glob(".run.nc.*.part")), "writes go to a hidden .part file"
            raise RuntimeError("solver blew up")
    assert list(tmp_path.iterdir()) == []
    assert not is_complete(target)


def test_abort_keeps_a_previous_archive(tmp_path):
    target = write(tmp_path / "run.nc")
    w = ArchiveWriter(target, X1, X2, NAMES, ATTRS)
    w.append(*synthetic_steps()[0])
    w.abort()
    assert is_complete(target)
    assert open_archive(target).sizes["time"] == len(TIMES)
    assert [p.name for p in tmp_path.iterdir()] == ["run.nc"]


def test_a_step_is_written_as_appended_though_the_caller_reuses_its_arrays(tmp_path):
    """The writer's thread writes an instant after ``append`` returned: it must write the
    values given, not what the caller's arrays hold by then. The thread is held back (the
    netCDF lock taken here) until the caller has overwritten every array it passed."""
    from contactpipe.archive.background import NETCDF_LOCK
    target = tmp_path / "run.nc"
    steps = synthetic_steps()
    with ArchiveWriter(target, X1, X2, NAMES, ATTRS) as w:
        for t, values in steps:
            reused = {k: (v.copy() if isinstance(v, np.ndarray) else v)
                      for k, v in values.items()}
            with NETCDF_LOCK:
                w.append(t, reused)
                for v in reused.values():
                    if isinstance(v, np.ndarray):
                        v[...] = 7                   # the caller's next instant
            w.flush()                                # the thread writes it now
        w.close(WALL)
    with open_archive(target) as ds:
        for k, (_, values) in enumerate(steps):
            for name in ("p", "q1", "s1", "status"):
                np.testing.assert_array_equal(ds[name].isel(time=k).values, values[name])


def test_the_memory_estimate_counts_the_instants_the_writer_holds():
    """The planning's memory estimate counts a streamed archive's writer at its most: the
    two instants its thread's queue keeps and the one being handed over."""
    from contactpipe.archive.background import DEPTH
    from contactpipe.planning.resources import WRITER_INSTANTS
    assert WRITER_INSTANTS == DEPTH + 1


def test_a_failed_write_on_the_thread_is_raised_and_nothing_published(tmp_path, monkeypatch):
    """Fault injection: the writer's thread fails at step 2 (a full disk, say). A later
    call raises it as an ArchiveError naming the archive and the step, and nothing is
    published."""
    import contactpipe.archive.writer as writer
    real = writer._write_instant

    def failing(nc, k, t, arrays):
        if k == 2:
            raise OSError("No space left on device")
        return real(nc, k, t, arrays)

    monkeypatch.setattr(writer, "_write_instant", failing)
    target = tmp_path / "run.nc"
    with pytest.raises(ArchiveError, match=r"run\.nc: writing step 2 failed .*No space left"):
        with ArchiveWriter(target, X1, X2, NAMES, ATTRS) as w:
            for t, values in synthetic_steps():
                w.append(t, values)
            w.close(WALL)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL")
def test_killed_writer_leaves_no_archive(tmp_path):
    target = tmp_path / "killed.nc"
    script = textwrap.dedent(f"""
        import time
        import numpy as np
        from contactpipe.archive import ArchiveWriter
        from contactpipe.nomenclature import VARIABLES
        names = [n for n, e in VARIABLES.items() if e["required"]]
        w = ArchiveWriter({str(target)!r}, np.arange(4.0), np.arange(3.0), names,
                          {{"scene": "", "models": "normal"}})
        for k in range(2):
            w.append(k, {{n: (np.zeros((4, 3)) if len(VARIABLES[n]["dims"]) == 3 else 0.0)
                          for n in names}})
        print("ready", flush=True)
        time.sleep(60)
    """)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = proc.stdout.readline()
        assert line.strip() == "ready", proc.stderr.read() if proc.poll() is not None else line
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        proc.stdout.close()
        proc.stderr.close()
    assert not target.exists()
    assert not is_complete(target)
    with pytest.raises(ArchiveError, match="no such archive.*interrupted write"):
        open_archive(target)
    assert len(list(tmp_path.glob(".killed.nc.*.part"))) == 1


def test_truncated_corrupt_and_incomplete_files_are_refused(tmp_path):
    good = write(tmp_path / "good.nc")
    assert is_complete(good)

    truncated = tmp_path / "truncated.nc"
    data = good.read_bytes()
    truncated.write_bytes(data[: len(data) // 2])
    noise = tmp_path / "noise.nc"
    noise.write_bytes(np.random.default_rng(0).bytes(4096))
    empty = tmp_path / "empty.nc"
    empty.write_bytes(b"")
    for bad in (truncated, noise, empty):
        with pytest.raises(ArchiveError, match=f"{bad.name}: not a readable netCDF") as err:
            open_archive(bad)
        assert "\n" not in str(err.value)
        assert not is_complete(bad)

    unfinished = tmp_path / "unfinished.nc"         # what a plain to_netcdf could leave
    without_complete(open_archive(good).load()).to_netcdf(unfinished)
    with pytest.raises(ArchiveError, match="unfinished.nc: incomplete archive"):
        open_archive(unfinished)
    assert not is_complete(unfinished)

    foreign = tmp_path / "foreign.nc"
    xr.Dataset({"a": ("t", [1.0])}, attrs={"complete": "true"}).to_netcdf(foreign)
    with pytest.raises(ArchiveError, match="foreign.nc: not a contactpipe archive.*'time'"):
        open_archive(foreign)
    assert not is_complete(foreign)

    with pytest.raises(ArchiveError, match="missing.nc: no such archive"):
        open_archive(tmp_path / "missing.nc")
    assert not is_complete(tmp_path / "missing.nc")
    assert isinstance(ArchiveError("x"), OSError)


def test_nan_refused_on_append(tmp_path):
    target = tmp_path / "nan.nc"
    steps = synthetic_steps()
    with ArchiveWriter(target, X1, X2, NAMES, ATTRS) as w:
        w.append(*steps[0])
        bad = dict(steps[1][1])
        bad["q1"] = bad["q1"].copy()
        bad["q1"][2, 3] = np.nan
        with pytest.raises(ArchiveError, match=r"step 1 \(t = 0.2 s\).*q1 holds 1 NaN"):
            w.append(steps[1][0], bad)
        with pytest.raises(ArchiveError, match=r"step 1.*W holds 1 NaN or inf"):
            w.append(steps[1][0], {**steps[1][1], "W": np.inf})
        assert w.steps == 1                         # the refused step left nothing
        w.append(*steps[1])
    ds = open_archive(target)
    assert ds.sizes["time"] == 2 and bool(np.isfinite(ds["q1"]).all())


def test_append_refuses_bad_steps(tmp_path):
    steps = synthetic_steps()
    w = MemoryWriter(None, X1, X2, NAMES, ATTRS)
    w.append(*steps[0])
    with pytest.raises(ArchiveError, match="not after the previous instant"):
        w.append(0.0, steps[1][1])
    with pytest.raises(ArchiveError, match=r"p: shape \(5, 6\), expected \(6, 5\)"):
        w.append(0.2, {**steps[1][1], "p": steps[1][1]["p"].T})
    with pytest.raises(ArchiveError, match="dissipation missing"):
        w.append(0.2, {k: v for k, v in steps[1][1].items() if k != "dissipation"})
    with pytest.raises(ArchiveError, match=r"status: values \[3\] outside flag_values"):
        w.append(0.2, {**steps[1][1], "status": np.full((N1, N2), 3)})
    with pytest.raises(ArchiveError, match="fft_pairs not declared"):
        w.append(0.2, {**steps[1][1], "fft_pairs": 4})


def test_writer_refuses_bad_arguments(tmp_path):
    with pytest.raises(ArchiveError, match="unknown variable 'pressure'"):
        ArchiveWriter(tmp_path / "a.nc", X1, X2, NAMES + ["pressure"], ATTRS)
    with pytest.raises(ArchiveError, match="variable 'h' missing"):
        ArchiveWriter(tmp_path / "a.nc", X1, X2, [n for n in NAMES if n != "h"], ATTRS)
    with pytest.raises(ArchiveError, match="global attribute 'scene' missing"):
        ArchiveWriter(tmp_path / "a.nc", X1, X2, NAMES, {"models": "normal"})
    with pytest.raises(ArchiveError, match="'x1' is not strictly ascending"):
        ArchiveWriter(tmp_path / "a.nc", X1[::-1], X2, NAMES, ATTRS)
    with pytest.raises(ArchiveError, match="precision='float16'"):
        ArchiveWriter(tmp_path / "a.nc", X1, X2, NAMES, ATTRS, precision="float16")
    with pytest.raises(ArchiveError, match="MemoryWriter: path='a.nc', expected None"):
        MemoryWriter("a.nc", X1, X2, NAMES, ATTRS)
    with pytest.raises(ArchiveError, match="no time step appended"):
        with ArchiveWriter(tmp_path / "a.nc", X1, X2, NAMES, ATTRS):
            pass
    assert list(tmp_path.iterdir()) == []


def test_attributes_are_made_storable(tmp_path):
    attrs = {**ATTRS, "converged": True, "note": None, "knots": [0.0, 0.5]}
    with ArchiveWriter(tmp_path / "a.nc", X1, X2, NAMES, attrs) as w:
        for t, values in synthetic_steps():
            w.append(t, values)
    ds = open_archive(tmp_path / "a.nc")
    assert ds.attrs["converged"] == "true" and ds.attrs["note"] == ""
    assert list(ds.attrs["knots"]) == [0.0, 0.5]
    assert ds.attrs["wall_time_s"] >= 0                 # measured when not given

    mem = in_memory()
    mem.attrs["flag"] = False
    save(mem, tmp_path / "b.nc")
    assert open_archive(tmp_path / "b.nc").attrs["flag"] == "false"
    assert mem.attrs["flag"] is False                   # the caller's dataset is untouched


def test_save_refuses_off_schema_datasets_before_writing(tmp_path):
    mem = in_memory()
    no_scene = mem.copy()
    del no_scene.attrs["scene"]
    with pytest.raises(ArchiveError, match="global attribute 'scene' missing"):
        save(no_scene, tmp_path / "a.nc")
    with pytest.raises(ArchiveError, match="dimension 'x2' missing"):
        save(mem.isel(x2=0), tmp_path / "a.nc")
    with pytest.raises(ArchiveError, match=r"p holds NaN or inf at 1 time step\(s\), first at "
                                           r"step 2 \(t = 0.6 s\)"):
        save(mem.where(mem.time != 0.6), tmp_path / "a.nc")
    no_units = mem.copy()
    no_units["h"].attrs = {}
    with pytest.raises(ArchiveError, match="h: units None, expected 'm'"):
        save(no_units, tmp_path / "a.nc")
    with pytest.raises(ArchiveError, match="precision"):
        save(mem, tmp_path / "a.nc", precision="int8")
    assert list(tmp_path.iterdir()) == []


def test_validate_lists_every_problem():
    mem = in_memory()
    assert validate(mem) == []
    broken = mem.drop_vars("W").rename({"omega1": "omega_1"})
    broken.attrs["Conventions"] = "CF-1.6"
    broken.attrs["scene"] = "not = = toml"
    problems = validate(broken)
    assert "variable 'W' missing" in problems
    assert any("unknown variable 'omega_1'" in p for p in problems)
    assert any("'Conventions' = 'CF-1.6'" in p for p in problems)
    assert any("'scene' is not TOML" in p for p in problems)


def test_synthetic_archive_passes_the_outside_checker(tmp_path):
    if not CHECKER.exists():
        pytest.skip(f"{CHECKER} not present (outside the project)")
    path = write(tmp_path / "run.nc")
    res = subprocess.run([sys.executable, str(CHECKER), str(path), "--frictional"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    path32 = save(in_memory(), tmp_path / "run32.nc", precision="float32")
    res = subprocess.run([sys.executable, str(CHECKER), str(path32), "--frictional"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr


# --------------------------------------------------------------------------- damaged archives
# Each case is built with netCDF4 from an archive of a real run (steel on steel, fretting
# loop, 24 x 24 cells, 5 steps: compare and plot succeed on it), then given to
# open_archive(verify=True) and to `contactpipe compare` / `contactpipe plot`: one
# ArchiveError naming the file, the variable, the first bad step and the problem; exit 2,
# one line on stderr, no figure written.

def elastic_fretting(compress=True):
    return cp.Scene.from_toml_text(TINY_SCENES["fretting"]).replace({
        "indenter.material": "elastic", "indenter.young": 210e9, "indenter.poisson": 0.3,
        "halfspace.material": "elastic", "halfspace.young": 210e9,
        "halfspace.creep": None, "halfspace.relaxation_time": None,
        "time.steps": 5, "output.compress": compress})


@pytest.fixture(scope="module")
def good_runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("good")
    return {c: cp.simulate(elastic_fretting(c), folder / f"good-{c}.nc").encoding["source"]
            for c in (True, False)}


def edited(src, dst, edit):
    """A copy of ``src`` changed in place by ``edit(nc)`` (netCDF4, checksums kept valid)."""
    shutil.copyfile(src, dst)
    with netCDF4.Dataset(dst, "a") as nc:
        edit(nc)
    return dst


def copied(src, dst, drop=(), steps=None, attrs=None):
    """A new archive with the variables of ``src`` but ``drop``, its first ``steps``
    instants, and ``attrs`` over its attributes (netCDF4)."""
    with netCDF4.Dataset(src) as a, netCDF4.Dataset(dst, "w") as b:
        for name, dim in a.dimensions.items():
            b.createDimension(name, None if dim.isunlimited() else len(dim))
        for name, v in a.variables.items():
            if name in drop:
                continue
            w = b.createVariable(name, v.dtype, v.dimensions, fill_value=False,
                                 fletcher32=True)
            w.setncatts({k: v.getncattr(k) for k in v.ncattrs()})
            data = v[:] if "time" not in v.dimensions else v[:steps]
            if np.size(data):
                w[:] = data
        b.setncatts({**{k: a.getncattr(k) for k in a.ncattrs()}, **(attrs or {})})
    return dst


def _stored_chunk(data, raw, compressed):
    """(offset, length) of the chunk holding ``raw`` in the file's bytes: as is, or (zlib)
    the deflate stream that inflates to it shuffled (HDF5's order: shuffle, fletcher32,
    deflate)."""
    if not compressed:
        return data.find(raw), len(raw)
    shuffled = np.frombuffer(raw, np.uint8).reshape(-1, 8).T.tobytes()
    for at in range(len(data) - 1):
        if data[at] != 0x78 or data[at + 1] not in (0x01, 0x5E, 0x9C, 0xDA):
            continue                     # not a zlib header
        z = zlib.decompressobj()
        try:
            out = z.decompress(data[at:at + 4 * len(raw)])
        except zlib.error:
            continue
        if out[:len(shuffled)] == shuffled:
            return at, 4 * len(raw) - len(z.unused_data) if z.eof else len(raw) // 4
    return -1, 0


def flipped(src, dst, step, compressed):
    """A copy of ``src`` with one byte flipped inside the stored chunk of q1 at ``step``."""
    with netCDF4.Dataset(src) as nc:
        raw = np.asarray(nc["q1"][step], dtype="<f8").tobytes()
    data = bytearray(pathlib.Path(src).read_bytes())
    at, length = _stored_chunk(bytes(data), raw, compressed)
    assert at >= 0, "the chunk of q1 is not in the file"
    data[at + length // 2] ^= 0xFF
    pathlib.Path(dst).write_bytes(bytes(data))
    return dst


def contact_cell(nc, step):
    p = np.asarray(nc["p"][step])
    return np.unravel_index(int(np.argmax(p)), p.shape), float(p.max())


def _over_coulomb(nc):
    (i, j), pmax = contact_cell(nc, 2)
    nc["q1"][2, i, j] = 0.3 * pmax                   # mu = 0.1


BAD = {
    "nan": (lambda src, dst: edited(src, dst, lambda nc: nc["p"].__setitem__(
        (2, 12, 12), np.nan)), r"p holds NaN or inf at 1 time step\(s\), first at step 2 "
                               r"\(t = 0.4 s\)"),
    "inf": (lambda src, dst: edited(src, dst, lambda nc: nc["W"].__setitem__(1, np.inf)),
            r"W holds NaN or inf at 1 time step\(s\), first at step 1 \(t = 0.2 s\)"),
    "negative_p": (lambda src, dst: edited(src, dst, lambda nc: nc["p"].__setitem__(
        (3, 12, 12), -1e6)), r"p: negative pressure at 1 time step\(s\), first at step 3 "
                             r"\(t = 0.6 s\): min -1e\+06 Pa"),
    "status_7": (lambda src, dst: edited(src, dst, lambda nc: nc["status"].__setitem__(
        (1, 12, 12), 7)), r"status: values outside flag_values \[0, 1, 2\] at 1 time "
                          r"step\(s\), first at step 1 \(t = 0.2 s\): values \[7\]"),
    "coulomb": (lambda src, dst: edited(src, dst, _over_coulomb),
                r"q1, q2: \|q\| > mu p \(mu = 0.1.*first at step 2 \(t = 0.4 s\)"),
    "flipped_raw": (lambda src, dst: flipped(src, dst, 2, compressed=False),
                    r"q1: unreadable \(checksum mismatch or corrupt chunk\) at 1 time "
                    r"step\(s\), first at step 2 \(t = 0.4 s\)"),
    "corrupt_chunk": (lambda src, dst: flipped(src, dst, 3, compressed=True),
                      r"q1: unreadable \(checksum mismatch or corrupt chunk\) at 1 time "
                      r"step\(s\), first at step 3 \(t = 0.6 s\)"),
    "no_q1": (lambda src, dst: copied(src, dst, drop=("q1",)),
              r"variable 'q1' missing: the archive says a tangential model ran"),
    "no_steps": (lambda src, dst: copied(src, dst, steps=0),
                 r"dimension 'time' has size 0"),
    "steps_1e9": (lambda src, dst: copied(src, dst, attrs={"scene": pathlib.Path(
        dst).with_suffix(".toml").read_text()}),
        r"time.steps = 1000000000 and output.stride = 1, which write 1000000001 instants, "
        r"but the archive holds 6"),
}
SCHEMA_CASES = ("no_q1", "no_steps", "steps_1e9")       # refused even without verify


def make_bad(case, good_runs, tmp_path):
    build, _ = BAD[case]
    src = good_runs[case != "flipped_raw"]
    dst = tmp_path / f"bad-{case}.nc"
    if case == "steps_1e9":
        with netCDF4.Dataset(src) as nc:
            scene = nc.getncattr("scene")
        assert "steps = 5\n" in scene
        dst.with_suffix(".toml").write_text(scene.replace("steps = 5\n",
                                                          "steps = 1000000000\n"))
    return build(src, dst)


@pytest.mark.parametrize("case", sorted(BAD))
def test_damaged_archive_is_one_archive_error(case, good_runs, tmp_path):
    bad = make_bad(case, good_runs, tmp_path)
    with pytest.raises(ArchiveError, match=BAD[case][1]) as err:
        open_archive(bad, verify=True)
    message = str(err.value)
    assert "\n" not in message and message.startswith(str(bad))
    if case in SCHEMA_CASES:
        with pytest.raises(ArchiveError, match=BAD[case][1]):
            open_archive(bad)
        assert not is_complete(bad)


@pytest.mark.parametrize("case", sorted(BAD))
def test_compare_and_plot_refuse_a_damaged_archive(case, good_runs, tmp_path, capsys):
    bad = make_bad(case, good_runs, tmp_path)
    figure = tmp_path / "f.png"
    for argv in (["compare", str(bad)], ["plot", str(bad), "-o", str(figure)]):
        assert cli_main(argv) == 2, argv
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1, err
        assert bad.name in err and "Traceback" not in err
    assert not figure.exists()


def test_the_good_archives_pass(good_runs, tmp_path, capsys):
    """The archives the damaged ones are made from: verified, compared and plotted."""
    for path in good_runs.values():
        open_archive(path, verify=True).close()
        assert cli_main(["compare", str(path)]) == 0
        assert cli_main(["plot", str(path), "-o", str(tmp_path / "g.png")]) == 0
    capsys.readouterr()


def test_damaged_archive_through_the_command_line(good_runs, tmp_path):
    """End to end in a fresh process: exit 2, one line, no traceback."""
    bad = make_bad("corrupt_chunk", good_runs, tmp_path)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    res = subprocess.run([sys.executable, "-m", "contactpipe.pipeline.cli", "compare",
                          str(bad)], capture_output=True, text=True, env=env, timeout=300)
    assert res.returncode == 2, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "step 3" in res.stderr


def test_verification_streams_in_bounded_blocks(good_runs):
    """With a budget of one byte the scan reads one instant at a time and finds the same."""
    ds = open_archive(good_runs[True])
    bad = ds.copy(deep=True).load()
    bad["p"][4, 3, 3] = -5.0
    assert content_problems(ds, budget_bytes=1) == []
    assert content_problems(bad, budget_bytes=1) == content_problems(bad)
    assert content_problems(bad)[0].startswith("p: negative pressure at 1 time step(s), "
                                               "first at step 4")


def test_a_writer_never_publishes_what_breaks_the_rules(tmp_path):
    """Values the per-step check lets through (a negative pressure) are found when the
    file is read back at close: nothing is published, no temporary file stays."""
    target = tmp_path / "run.nc"
    steps = synthetic_steps()
    w = ArchiveWriter(target, X1, X2, NAMES, ATTRS)
    for k, (t, values) in enumerate(steps):
        if k == 2:
            values = {**values, "p": values["p"] - 1e8}
        w.append(t, values)
    with pytest.raises(ArchiveError, match=r"run.nc: not published.*p: negative pressure "
                                           r"at 1 time step\(s\), first at step 2"):
        w.close(WALL)
    assert list(tmp_path.iterdir()) == []


def test_every_variable_is_checksummed(tmp_path):
    for compress in (True, False):
        path = write(tmp_path / f"c{compress}.nc", compress=compress)
        with netCDF4.Dataset(path) as nc:
            for name, v in nc.variables.items():
                assert v.filters()["fletcher32"], (compress, name)
        saved = save(in_memory(), tmp_path / f"s{compress}.nc", compress=compress)
        with netCDF4.Dataset(saved) as nc:
            for name, v in nc.variables.items():
                assert v.filters()["fletcher32"], (compress, name)
