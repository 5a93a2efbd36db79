"""Archives: round trips, precision and compression, atomic writes, refusals (CONTRACT §3)."""
import os
import pathlib
import signal
import subprocess
import sys
import textwrap

import dask.array as da
import numpy as np
import pytest
import xarray as xr

from contactpipe.archive import (
    ArchiveWriter, MemoryWriter, is_complete, open_archive, save, to_dataset, validate,
)
from contactpipe.exceptions import ArchiveError
from contactpipe.nomenclature import VARIABLES

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
    for k, (t, c) in enumerate(zip(TIMES, [0.2, 0.5, -0.5, 0.5])):
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
            "stick_area": float((status == 1).sum() * cell),
            "dissipation": dissipation, "iterations": 10 + k,
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
    big_x1 = np.linspace(-1e-3, 1e-3, 64)
    big_x2 = np.linspace(-1e-3, 1e-3, 64)
    names = [n for n, e in VARIABLES.items() if e["required"]]
    sizes = {}
    for compress in (True, False):
        path = tmp_path / f"c{compress}.nc"
        with ArchiveWriter(path, big_x1, big_x2, names, ATTRS, compress=compress) as w:
            for k in range(3):
                w.append(k, {n: (np.zeros((64, 64)) if VARIABLES[n]["dims"] != ("time",)
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
