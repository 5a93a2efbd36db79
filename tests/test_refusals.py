"""Bad input through the command line: one line on stderr, no traceback, the README's exit
status (2 bad input, 1 a failed run), and nothing clobbered or published half-right.

The runs are the tiny fretting scene (rigid sphere on a Maxwell half-space, 24 x 24 cells
over 2 mm, 20 steps; contactpipe.testing.TINY_SCENES) unless a test says otherwise.
"""
import json
import os
import pathlib
import subprocess
import sys

import netCDF4
import numpy as np
import pytest
import xarray as xr

import contactpipe as cp
from contactpipe.pipeline import cli
from contactpipe.testing import tiny_scene

ROOT = pathlib.Path(__file__).resolve().parents[1]


def one_line_error(capsys, code, argv):
    """Run the CLI in-process; assert ``code`` and one line on stderr; return it."""
    assert cli.main([str(a) for a in argv]) == code, capsys.readouterr()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("contactpipe: error: "), err[-3000:]
    assert "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    """A folder with the tiny scene (scene.toml), its archive (run.nc), a friction map
    mu.nc (mu = 0.1 over 3 mm x 3 mm), a scene reading it (mapped.toml) and its archive
    (mapped.nc)."""
    d = tmp_path_factory.mktemp("refusals")
    scene = tiny_scene("fretting")
    (d / "scene.toml").write_text(scene.to_toml())
    cp.simulate(scene, d / "run.nc")
    x = np.linspace(-1.5e-3, 1.5e-3, 7)
    xr.Dataset({"mu": (("x1", "x2"), np.full((7, 7), 0.1))},
               coords={"x1": x, "x2": x}).to_netcdf(d / "mu.nc")
    mapped = scene.replace({"friction.mu": str(d / "mu.nc")})
    (d / "mapped.toml").write_text(mapped.to_toml())
    cp.simulate(mapped, d / "mapped.nc")
    return d


def edited_archive(src, dst, edit):
    """A copy of an archive changed in place by ``edit(nc)`` (checksums kept valid)."""
    dst.write_bytes(pathlib.Path(src).read_bytes())
    with netCDF4.Dataset(dst, "a") as nc:
        edit(nc)
    return dst


# ---------------------------------------------------------------- 15: outputs vs inputs

@pytest.mark.parametrize("case", ["figure is the map", "archive is the map",
                                  "figure is the map by another path",
                                  "stress figure is the stress output",
                                  "stress output is the archive's map",
                                  "compare figure is the table"])
def test_no_output_is_an_input_or_another_output(work, tmp_path, capsys, case):
    """Each output is compared by resolved real path with the inputs (the scene and the
    files it reads: here the friction map) and with the other outputs, before any work:
    exit 2, the map's bytes unchanged, nothing written."""
    before = (work / "mu.nc").read_bytes()
    out = tmp_path / "o.nc"
    argv = {
        "figure is the map": ["run", work / "mapped.toml", "-o", out, "--figure", work / "mu.nc"],
        "archive is the map": ["run", work / "mapped.toml", "-o", work / "mu.nc"],
        "figure is the map by another path": [
            "run", work / "mapped.toml", "-o", out, "--figure",
            f"{work}/no-such-folder/../mu.nc"],
        "stress figure is the stress output": [
            "stress", work / "run.nc", "-o", tmp_path / "S.nc", "--x3", "0,1e-4",
            "--figure", tmp_path / "S.nc"],
        "stress output is the archive's map": [
            "stress", work / "mapped.nc", "-o", work / "mu.nc", "--x3", "0"],
        "compare figure is the table": [
            "compare", work / "run.nc", work / "run.nc", "-o", tmp_path / "t.nc",
            "--figure", tmp_path / "t.nc"],
    }[case]
    err = one_line_error(capsys, 2, argv + (["--no-progress"] if argv[0] == "run" else []))
    expected = {"stress figure is the stress output": "is also the stress output (-o)",
                "compare figure is the table": "is also the error table (-o)"}.get(
        case, "is the input file")
    assert expected in err
    assert (work / "mu.nc").read_bytes() == before
    assert sorted(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- 16: never publish NaN

def test_stress_depth_beyond_the_contact_scale_is_refused(work, tmp_path, capsys):
    """--x3 1e300 (NaN from the kernels before) is refused, naming the range allowed:
    0 to 1000 times the grid's larger side (2 mm here: 2 m)."""
    err = one_line_error(capsys, 2, ["stress", work / "run.nc", "-o", tmp_path / "S.nc",
                                     "--x3", "1e300"])
    assert "x3 = 1e+300 m is too deep: depths must be from 0 to 2 m" in err
    assert not (tmp_path / "S.nc").exists()


def test_the_deepest_depth_allowed_is_finite_and_a_point_load(work):
    """At the deepest depth allowed (1000 L, L = 2 mm) the stress is finite and that of
    the resultant point force: Boussinesq's s33 on the axis, -3W/(2 pi z^2), W = 1000 N,
    to 1e-3 (the grid's 24 cells are all within 1e-3 z of the axis)."""
    z = 1000 * 2e-3
    with cp.open_archive(work / "run.nc") as ds:
        st = cp.subsurface_stress(ds, [z], chunks=False)
        w = float(ds["W"].isel(time=-1))
    s33 = st["s33"].isel(time=0, x3=0).values
    assert np.all(np.isfinite(s33))
    np.testing.assert_allclose(s33.min(), -3 * w / (2 * np.pi * z ** 2), rtol=1e-3)


def test_stress_refuses_an_archive_with_negative_pressure(work, tmp_path, capsys):
    """The archive is verified as compare and plot verify it: exit 2, nothing written."""
    bad = edited_archive(work / "run.nc", tmp_path / "neg.nc",
                         lambda nc: nc["p"].__setitem__((3, 12, 12), -1e6))
    err = one_line_error(capsys, 2, ["stress", bad, "-o", tmp_path / "S.nc", "--x3", "0"])
    assert "negative pressure" in err and not (tmp_path / "S.nc").exists()


def _stress_file(work, path, compress=True):
    from contactpipe.post.stress import save_stress
    with cp.open_archive(work / "run.nc") as ds:
        save_stress(cp.subsurface_stress(ds, [0.0, 1e-4], chunks=False), path,
                    compress=compress)
    return path


def test_plot_verifies_stress_files(work, tmp_path, capsys):
    """A stress file holding NaN, and one whose chunk fails its fletcher32 checksum,
    are refused by plot (exit 2, the variable named) instead of drawn."""
    good = _stress_file(work, tmp_path / "good.nc", compress=False)
    nan = edited_archive(good, tmp_path / "nan.nc",
                         lambda nc: nc["s11"].__setitem__((0, 1, 3, 3), np.nan))
    err = one_line_error(capsys, 2, ["plot", nan, "-o", tmp_path / "a.png"])
    assert "damaged stress file: s11 holds NaN or inf" in err
    with netCDF4.Dataset(good) as nc:
        raw = np.asarray(nc["s22"][0, 1], dtype="<f8").tobytes()
    data = bytearray(good.read_bytes())
    at = bytes(data).find(raw)
    assert at > 0
    data[at + len(raw) // 2] ^= 0xFF
    (tmp_path / "flipped.nc").write_bytes(bytes(data))
    err = one_line_error(capsys, 2, ["plot", tmp_path / "flipped.nc", "-o", tmp_path / "b.png"])
    assert "s22: unreadable (checksum mismatch or corrupt chunk)" in err
    assert sorted(p.name for p in tmp_path.glob("*.png")) == []


def test_no_nan_is_written_or_returned(work, tmp_path):
    """save_stress refuses a stress holding NaN (nothing at the target); fatigue refuses
    limits that overflow its indices (1e-300 and 1e308 Pa gave NaN Crossland fields);
    the pipeline file refuses such limits before any work."""
    from contactpipe.pipeline.cli.stress import write_stress_product
    from contactpipe.pipeline.sweep.config import StressSpec
    from contactpipe.post.stress import save_stress
    with pytest.raises(ValueError, match=r"x3 = 1e\+300 m is too deep: depths must be from 0 "
                                         r"to 2 m"):    # the [stress] product: at once
        write_stress_product(work / "run.nc", tmp_path / "product.nc",
                             StressSpec(depths=(1e300,), time="all", criterion="crossland",
                                        constants=(("bending_limit", 6e8),
                                                   ("torsion_limit", 4e8))))
    assert sorted(tmp_path.iterdir()) == []
    with cp.open_archive(work / "run.nc") as ds:
        st = cp.subsurface_stress(ds, [0.0, 1e-4], time="all", chunks=False)
    bad = st.copy(deep=True)
    bad["s12"][0, 0, 5, 5] = np.nan
    with pytest.raises(cp.ArchiveError, match="s12 holds NaN or inf"):
        save_stress(bad, tmp_path / "bad.nc")
    assert not (tmp_path / "bad.nc").exists()
    for limit in (1e-300, 1e308):
        with pytest.raises(ValueError, match="came out NaN or inf"):
            cp.fatigue(st, "crossland", torsion_limit=limit, bending_limit=limit)
    fine = cp.fatigue(st, "crossland", torsion_limit=400e6, bending_limit=600e6)
    assert all(np.all(np.isfinite(fine[v].values)) for v in fine.data_vars)


@pytest.mark.parametrize("table, message", [
    ("depths = [0.0]\ntorsion_limit = 1e-300\n",
     "torsion_limit must be a number from 1000 to 1e+12 [Pa]"),
    ("depths = [0.0]\ntorsion_limit = 1e308\n",
     "torsion_limit must be a number from 1000 to 1e+12 [Pa]"),
    ("depths = [1e300]\ntorsion_limit = 4e8\n",
     "stress.depths must be a list of depths from 0 to 1e+06 [m]"),
], ids=["limit 1e-300", "limit 1e308", "depth 1e300"])
def test_pipeline_refuses_stress_settings_out_of_range(work, tmp_path, capsys, table, message):
    """Fatigue limits outside 1e3..1e12 Pa (NaN Crossland products before) and depths
    beyond 1000 sides of the largest grid allowed (a minute into a RuntimeError before)
    are refused with the pipeline file, before any work: exit 2, nothing made."""
    (tmp_path / "sweep.toml").write_text(f'base = "{work / "scene.toml"}"\n'
                                         '[axes]\n"friction.mu" = [0.1]\n')
    (tmp_path / "pipe.toml").write_text(
        'name = "p"\nout = "out"\n[sweep]\nfile = "sweep.toml"\n[stress]\n'
        f'time = "all"\ncriterion = "crossland"\nbending_limit = 600e6\n{table}')
    err = one_line_error(capsys, 2, ["pipeline", tmp_path / "pipe.toml"])
    assert message in err
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------- 17: no tracebacks

@pytest.mark.parametrize("change, code, message", [
    ({"grid.size": [1e-300, 1e-300]}, 2, "grid.size must be two numbers from 1e-09 to 1000"),
    ({"grid.size": [1e300, 1e300]}, 2, "grid.size must be two numbers from 1e-09 to 1000"),
    ({"halfspace.young": 5e-324}, 2, "halfspace.young = 5e-324: a shear modulus rounds"),
], ids=["grid 1e-300", "grid 1e300", "young 5e-324"])
def test_extreme_scene_values_are_one_line(tmp_path, capsys, change, code, message):
    scene = tmp_path / "s.toml"
    text = tiny_scene("fretting").to_toml()
    for key, value in change.items():
        table, name = key.split(".")
        head, _, tail = text.partition(f"[{table}]\n")
        lines = tail.split("\n")
        lines = [f"{name} = {json.dumps(value)}" if ln.startswith(f"{name} =") else ln
                 for ln in lines]
        text = head + f"[{table}]\n" + "\n".join(lines)
    scene.write_text(text)
    err = one_line_error(capsys, code, ["run", scene, "-o", tmp_path / "x.nc", "--no-progress"])
    assert message in err and not (tmp_path / "x.nc").exists()


def test_a_friction_map_over_dates_is_refused(work, tmp_path, capsys):
    """x1 as datetime64 (a TypeError in interp before): one line naming the coordinate."""
    x = np.linspace(-1.5e-3, 1.5e-3, 7)
    xr.Dataset({"mu": (("x1", "x2"), np.full((7, 7), 0.1))},
               coords={"x1": np.arange(7).astype("datetime64[D]"), "x2": x}
               ).to_netcdf(tmp_path / "dates.nc")
    scene = tmp_path / "s.toml"
    scene.write_text(tiny_scene("fretting").replace(
        {"friction.mu": str(work / "mu.nc")}).to_toml().replace(
        str(work / "mu.nc"), str(tmp_path / "dates.nc")))
    err = one_line_error(capsys, 2, ["run", scene, "-o", tmp_path / "x.nc", "--no-progress"])
    assert "coordinate 'x1' holds datetime64" in err


def test_a_manifest_nested_deep_is_one_line(tmp_path, capsys):
    """plot DIR over a manifest.json nested 100 000 deep: exit 2 (RecursionError before)."""
    (tmp_path / "sw").mkdir()
    (tmp_path / "sw" / "manifest.json").write_text(
        '{"axes": {"friction.mu": ' + "[" * 100000 + "]" * 100000 + "}}")
    err = one_line_error(capsys, 2, ["plot", tmp_path / "sw", "-o", tmp_path / "a.png"])
    assert "nested too deep" in err


def test_output_under_1100_missing_folders(work, tmp_path, capsys):
    """-o under 1100 folders that do not exist yet (a RecursionError before): they are
    made one level at a time and the archive written."""
    out = tmp_path.joinpath(*["a"] * 1100) / "x.nc"
    try:
        assert cli.main(["run", str(work / "scene.toml"), "-o", str(out),
                         "--no-progress"]) == 0
        with cp.open_archive(out) as ds:
            assert ds.sizes["time"] == 21
    finally:                             # shutil.rmtree (pytest's clean-up) recurses too
        for f in out.parent.iterdir() if out.parent.is_dir() else ():
            f.unlink()
        folder = out.parent
        while folder != tmp_path:
            if folder.is_dir():
                folder.rmdir()
            folder = folder.parent


def test_maps_of_an_archive_with_a_friction_map(work, tmp_path, capsys):
    """plot --kind maps of an archive whose mu is a map file ("could not convert string
    to float" before): drawn, exit 0."""
    assert cli.main(["plot", str(work / "mapped.nc"), "--kind", "maps",
                     "-o", str(tmp_path / "m.png")]) == 0
    assert (tmp_path / "m.png").stat().st_size > 1000


# ---------------------------------------------------------------- 19: map units

def test_friction_map_units(work, tmp_path):
    """A map whose coordinates say mm, um or µm gives the metre map's mu exactly (a
    linear mu over x1, interpolated onto the 24 x 24 grid); units of no length (ft,
    s) are refused naming the coordinate."""
    from contactpipe.scene.friction_map import check_mu_file, mu_on_grid
    x = np.linspace(-1.5e-3, 1.5e-3, 7)
    mu = 0.1 + 0.05 * x[:, None] / 1.5e-3 + 0 * x[None, :]
    grid = np.linspace(-1e-3, 1e-3, 24)

    def write(name, scale, units):
        attrs = {} if units is None else {"units": units}
        xr.Dataset({"mu": (("x1", "x2"), mu)},
                   coords={"x1": ("x1", x * scale, attrs), "x2": ("x2", x * scale, attrs)}
                   ).to_netcdf(tmp_path / name)
        return str(tmp_path / name)

    metres = mu_on_grid(write("m.nc", 1.0, None), grid, grid)
    np.testing.assert_allclose(metres[:, 0], 0.1 + 0.05 * grid / 1.5e-3, rtol=1e-12)
    for name, scale, units in (("mm.nc", 1e3, "mm"), ("um.nc", 1e6, "um"),
                               ("micro.nc", 1e6, "\u00b5m"), ("m2.nc", 1.0, "m")):
        np.testing.assert_allclose(mu_on_grid(write(name, scale, units), grid, grid), metres,
                                   rtol=1e-12, atol=0, err_msg=units)
    for units in ("ft", "s"):
        problems = check_mu_file(write(f"{units}.nc", 1.0, units), grid, grid)
        assert problems and f"has units '{units}': allowed m, mm, um" in problems[0]


@pytest.mark.parametrize("units, code", [("mm", 0), ("ft", 2)])
def test_run_with_a_friction_map_in_units(work, tmp_path, capsys, units, code):
    """Through the CLI: a map over +-1.5 mm given in mm, mu = 0.1 + 0.05 x1/(1.5 mm),
    runs with that mu on the cells (to 1e-12; read as metres it was about 0.1 everywhere),
    one in ft is refused in one line naming the coordinate, exit 2."""
    x = np.linspace(-1.5, 1.5, 7)
    xr.Dataset({"mu": (("x1", "x2"), 0.1 + 0.05 * x[:, None] / 1.5 + 0 * x[None, :])},
               coords={"x1": ("x1", x, {"units": units}), "x2": ("x2", x, {"units": units})}
               ).to_netcdf(tmp_path / "map.nc")
    scene = tmp_path / "s.toml"
    scene.write_text((work / "mapped.toml").read_text().replace(
        str(work / "mu.nc"), str(tmp_path / "map.nc")))
    out = tmp_path / "x.nc"
    argv = ["run", scene, "-o", out, "--no-progress"]
    if code:
        err = one_line_error(capsys, code, argv)
        assert "coordinate 'x1' has units 'ft': allowed m, mm, um" in err
        assert not out.exists()
        return
    assert cli.main([str(a) for a in argv]) == 0
    assert "Traceback" not in capsys.readouterr().err
    with cp.open_archive(out) as ds:
        x1 = ds["x1"].values
        np.testing.assert_allclose(ds["mu"].values, np.broadcast_to(
            0.1 + 0.05 * x1[:, None] / 1.5e-3, ds["mu"].shape), rtol=1e-12)


# ---------------------------------------------------------------- 21: start-up

#: Printed last by the code :func:`_in_a_fresh_process` runs: the top-level packages
#: outside the standard library that it loaded.
_THIRD_PARTY = ("print(sorted({m.split('.')[0] for m in sys.modules if not m.startswith('_')}\n"
                "             - set(sys.stdlib_module_names)))\n")


def _in_a_fresh_process(code):
    """Run ``code`` (then :data:`_THIRD_PARTY`) in a new interpreter on this tree: its
    stdout lines and its stderr."""
    r = subprocess.run([sys.executable, "-c", code + _THIRD_PARTY], capture_output=True,
                       text=True, cwd=ROOT, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    return r.stdout.split("\n"), r.stderr


def test_the_validation_path_imports_no_heavy_library(tmp_path):
    """A refused scene is refused without importing dask, distributed, matplotlib,
    xarray, netCDF4 or pyfftw (those took about 1.2 s of the 1.3 s import before): of
    the packages outside the standard library, only numpy is loaded."""
    scene = tmp_path / "bad.toml"
    scene.write_text('[grid]\npoints = "x"\n')
    out, err = _in_a_fresh_process(
        "import sys\nfrom contactpipe.pipeline import cli\n"
        f"code = cli.main(['run', {str(scene)!r}, '-o', {str(tmp_path / 'x.nc')!r}])\n"
        "heavy = ('dask', 'distributed', 'matplotlib', 'xarray', 'netCDF4', 'pyfftw')\n"
        "print(code, sorted(m for m in sys.modules if m.split('.')[0] in heavy))\n")
    assert out[:2] == ["2 []", "['contactpipe', 'numpy']"], "\n".join(out) + err[-2000:]
    assert err.count("\n") == 1 and "grid.points" in err


def test_the_top_level_help_imports_no_stage():
    """``contactpipe --help`` lists the stages from their one-line help without importing
    any stage module (it imported all of them, the sweep driver pulling the solver and
    pyfftw: 1.2-1.5 s, now 0.08-0.09 s): no package outside the standard library is
    loaded but contactpipe itself."""
    out, err = _in_a_fresh_process(
        "import sys, contextlib, io\nfrom contactpipe.pipeline import cli\n"
        "text = io.StringIO()\n"
        "with contextlib.redirect_stdout(text):\n"
        "    try:\n        cli.main(['--help'])\n    except SystemExit as e:\n"
        "        code = e.code\n"
        "stages = sorted(m for m in sys.modules if m.startswith('contactpipe.pipeline.')\n"
        "                and m.split('.')[2] in ('sweep', 'compare', 'figures'))\n"
        "print(code, 'sweep' in text.getvalue(), stages)\n")
    assert out[:2] == ["0 True []", "['contactpipe']"], "\n".join(out) + err[-2000:]


#: What a reading stage never needs: the cluster, the FFTs, the solver, the simulation,
#: the sweep's driver and its runner (which import those), scipy's optimisers and
#: quadratures (0.3 s: the closed forms import them when they call them), the progress bar.
_NOT_READING = ("'distributed', 'pyfftw', 'tqdm', 'scipy.optimize', 'scipy.integrate', "
                "'contactpipe.solver', 'contactpipe.simulation', "
                "'contactpipe.pipeline.sweep.driver', 'contactpipe.pipeline.sweep.execute'")


def _loaded(names=_NOT_READING):
    """Code printing those of ``names`` (modules or packages) that are loaded."""
    return f"print(sorted(set(sys.modules) & {{{names}}}))\n"


def test_the_plot_command_draws_without_the_solver_or_a_cluster(work, tmp_path):
    """``contactpipe plot`` of an archive (the profiles with their closed form, and the
    maps) and of a stress file imports what it reads and draws with (xarray, netCDF4,
    dask's arrays, matplotlib, the figure modules, the closed forms) and none of
    :data:`_NOT_READING`. It imported them all (the figures imported the sweep package,
    whose driver pulled the simulation, pyfftw and dask.distributed; the closed forms
    scipy.optimize; dask looked for a distributed client before each read)."""
    stress = _stress_file(work, tmp_path / "stress.nc")
    figs = [tmp_path / f"{k}.png" for k in ("profiles", "maps", "stress")]
    argv = [["plot", str(work / "run.nc"), "-o", str(figs[0])],
            ["plot", str(work / "run.nc"), "-o", str(figs[1]), "--kind", "maps"],
            ["plot", str(stress), "-o", str(figs[2])]]
    out, err = _in_a_fresh_process(
        "import sys, contextlib, io\nfrom contactpipe.pipeline import cli\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    codes = [cli.main(a) for a in {argv!r}]\n"
        "print(codes)\n" + _loaded())
    assert out[:2] == ["[0, 0, 0]", "[]"], "\n".join(out) + err[-2000:]
    assert {"matplotlib", "netCDF4", "xarray"} <= set(eval(out[2]))   # noqa: S307 - a list
    assert all(f.stat().st_size > 10_000 for f in figs)


def test_the_reading_stages_import_neither_the_solver_nor_a_cluster():
    """The parsers of ``bench``, ``plot`` (every figure module: the fretting map's reads
    the sweep folder), ``compare`` and ``sweep`` (their ``--help``), built in that
    order, import none of :data:`_NOT_READING` but, for ``sweep``, its driver and
    runner: the members run on dask workers, each importing the simulation when it
    starts one. ``bench --help`` loads no package outside the standard library but
    numpy (it loaded the simulation, the solver and pyfftw)."""
    out, err = _in_a_fresh_process(
        "import sys\nfrom contactpipe.pipeline.cli.main import build_parser\n"
        "build_parser('bench')\n" + _THIRD_PARTY + _loaded()
        + "for command in ('plot', 'compare'):\n    build_parser(command)\n" + _loaded()
        + "build_parser('sweep')\n"
        + _loaded(_NOT_READING.split(", 'contactpipe.pipeline.sweep.driver'")[0]))
    assert out[:4] == ["['contactpipe', 'numpy']", "[]", "[]", "[]"], \
        "\n".join(out) + err[-2000:]


def test_the_simulation_imports_no_dask_arrays():
    """``import contactpipe.simulation`` loads pyfftw but not dask or dask.array (pyfftw's
    dask interface imported them: 0.28-0.45 s of 1.00 s, now 0.77 s, 2 cores). The entry
    that kept pyfftw from dask is gone again: dask.array.fft imports afterwards, and
    pyfftw's own interfaces are there."""
    out, err = _in_a_fresh_process(
        "import sys\nimport contactpipe.simulation\n"
        "print('pyfftw' in sys.modules, 'dask.array.fft' in sys.modules,\n"
        "      sorted(set(sys.modules) & {'dask', 'dask.array'}))\n"
        "import dask.array.fft, pyfftw\n"
        "print(dask.array.fft.fft_wrap.__name__, pyfftw.interfaces.numpy_fft.__name__)\n")
    assert out[:2] == ["True False []", "fft_wrap pyfftw.interfaces.numpy_fft"], \
        "\n".join(out) + err[-2000:]


def test_a_simulation_imports_scipy_interpolation_only_where_used():
    """``import contactpipe.simulation`` loads neither scipy.interpolate with the
    scipy.optimize it pulls (0.13-0.17 s; a periodic grid's kernel table imports it when
    built) nor scipy.ndimage (a self-similar preload's start imports it): 0.77 s, now
    0.57 s, 2 cores. An 8 x 8 tiny fretting run in memory (every sub-model, 5 instants)
    then carries the load it is given (W = 1000 N, T1 = 90 N at the end, to 1e-9) without
    scipy.interpolate or scipy.optimize."""
    out, err = _in_a_fresh_process(
        "import sys\nimport contactpipe.simulation\n"
        "print(sorted(set(sys.modules) & {'scipy.interpolate', 'scipy.optimize',\n"
        "                                 'scipy.ndimage'}))\n"
        "import contactpipe as cp\nfrom contactpipe.testing import tiny_scene\n"
        "ds = cp.simulate(tiny_scene('fretting', **{'grid.points': [8, 8], 'time.steps': 5}))\n"
        "cell = float(ds.x1[1] - ds.x1[0]) * float(ds.x2[1] - ds.x2[0])\n"
        "last = ds.isel(time=-1)\n"
        "print(float(last.p.sum()) * cell / 1000.0 - 1.0,\n"
        "      float(last.q1.sum()) * cell / 90.0 - 1.0)\n"
        "print(sorted(set(sys.modules) & {'scipy.interpolate', 'scipy.optimize'}))\n")
    assert out[0] == "[]" and out[2] == "[]", "\n".join(out) + err[-2000:]
    force, shear = (float(v) for v in out[1].split())
    assert abs(force) < 1e-9 and abs(shear) < 1e-9, out[1]


def test_a_run_prints_its_summary_without_dask_arrays(tmp_path, capsys):
    """``contactpipe run`` reads the line it prints (instants, models, wall time) from the
    archive's header with netCDF4; it opened the archive lazily for it, importing dask's
    arrays (0.23 s: examples/paper-elastic.toml 2.16 s end to end, now 1.84 s, 2 cores).
    An 8 x 8 tiny fretting run (5 instants) in a fresh process exits 0 with neither
    dask.array nor matplotlib loaded, and its line names the archive's instants and models;
    with ``--figure`` the profiles are drawn from the archive (a PNG over 10 kB)."""
    scene = tmp_path / "tiny.toml"
    scene.write_text(tiny_scene("fretting", **{"grid.points": [8, 8], "time.steps": 5})
                     .to_toml())
    out, err = _in_a_fresh_process(
        "import sys\nfrom contactpipe.pipeline import cli\n"
        f"code = cli.main(['run', {str(scene)!r}, '-o', {str(tmp_path / 'a.nc')!r},"
        " '--no-progress'])\n"
        "print(code, sorted(set(sys.modules) & {'dask.array', 'matplotlib'}))\n")
    assert out[1] == "0 []", "\n".join(out) + err[-2000:]
    with cp.open_archive(tmp_path / "a.nc") as ds:
        models, wall = ds.attrs["models"], float(ds.attrs["wall_time_s"])
        assert out[0] == (f"wrote {tmp_path / 'a.nc'} ({ds.sizes['time']} instants, "
                          f"{models}, {wall:.2f} s)") and ds.sizes["time"] == 6
    figure = tmp_path / "a.png"
    assert cli.main(["run", str(scene), "-o", str(tmp_path / "b.nc"), "--figure", str(figure),
                     "--no-progress"]) == 0
    assert capsys.readouterr().out.splitlines()[1] == f"wrote {figure}"
    assert figure.stat().st_size > 10_000


def test_a_sweep_member_is_simulated_without_dask_arrays(tmp_path):
    """A sweep's member is simulated into its file and not opened again: opened lazily, it
    imported dask.array (0.23 s) into each worker. An 8 x 8 tiny fretting member
    (5 instants) simulated in a fresh process by the sweep's runner leaves a complete
    archive of 6 instants without dask.array loaded."""
    scene = tmp_path / "tiny.toml"
    scene.write_text(tiny_scene("fretting", **{"grid.points": [8, 8], "time.steps": 5})
                     .to_toml())
    out, err = _in_a_fresh_process(
        "import sys\nfrom contactpipe.pipeline.sweep import execute\n"
        "from contactpipe.scene import Scene\n"
        f"print(execute._simulate(Scene.from_toml({str(scene)!r}), "
        f"{str(tmp_path / 'm.nc')!r}), 'dask.array' in sys.modules)\n")
    assert out[0] == "None False", "\n".join(out) + err[-2000:]
    with cp.open_archive(tmp_path / "m.nc", verify=True) as ds:
        assert ds.sizes["time"] == 6


def test_public_names_load_on_first_use():
    """Every name of contactpipe.__all__ resolves; cp.fatigue stays the function when
    the module of that name is imported."""
    import contactpipe.post.fatigue  # noqa: F401 - binds the submodule's name on the package
    assert callable(cp.fatigue) and cp.fatigue.__name__ == "fatigue"
    for name in cp.__all__:
        assert getattr(cp, name) is not None, name
    assert cp.analytic.hertz is not None
    with pytest.raises(AttributeError):
        _ = cp.no_such_name


# ---------------------------------------------------------------- 23: mixed mu axis

@pytest.mark.parametrize("values", [[0.1, "mu.nc"], ["mu.nc", "mu2.nc"]],
                         ids=["number and map", "two maps"])
def test_a_friction_axis_with_map_files(work, tmp_path, capsys, values):
    """friction.mu = [0.1, "mu.nc"] ran but could not be opened ("mu already exists as
    coordinate or variable name"): the axis coordinate is the values as text on a mixed
    axis, the members' maps are the variable mu_map; open_sweep and plot DIR work."""
    (tmp_path / "mu2.nc").write_bytes((work / "mu.nc").read_bytes())
    (tmp_path / "mu.nc").write_bytes((work / "mu.nc").read_bytes())
    base = tiny_scene("fretting", **{"time.steps": 4, "grid.points": [16, 16]})
    axis = [v if isinstance(v, float) else str(tmp_path / v) for v in values]
    res = cp.sweep(base, {"friction.mu": axis}, tmp_path / "sw", scheduler="synchronous",
                   progress=False)
    assert res.ok
    with cp.open_sweep(tmp_path / "sw") as sw:
        expected = [str(v) for v in axis] if isinstance(values[0], float) else axis
        assert sw["mu"].values.tolist() == expected
        assert sw["mu_map"].dims == ("mu", "x1", "x2")
        assert np.all(sw["mu_map"].sel(mu=expected[-1]).values == 0.1)
        np.testing.assert_array_equal(sw["contact_area"].isel(mu=0).values,
                                      sw["contact_area"].isel(mu=1).values)
    assert cli.main(["plot", str(tmp_path / "sw"), "-o", str(tmp_path / "sw.png")]) == 0


# ---------------------------------------------------------------- 24: exit statuses

def test_bad_arguments_exit_2(work, tmp_path, capsys):
    """A 5000-digit integer, plot --instant 1000 and plot --variable bogus are bad input."""
    scene = tmp_path / "big.toml"
    scene.write_text(tiny_scene("fretting").to_toml().replace("steps = 20",
                                                               "steps = " + "9" * 5000))
    err = one_line_error(capsys, 2, ["run", scene, "-o", tmp_path / "x.nc"])
    assert "Exceeds the limit (4300 digits)" in err
    err = one_line_error(capsys, 2, ["plot", work / "run.nc", "--instant", "1000",
                                     "-o", tmp_path / "a.png"])
    assert "instant 1000 is out of range" in err
    stress = _stress_file(work, tmp_path / "S.nc")
    err = one_line_error(capsys, 2, ["plot", stress, "--variable", "bogus",
                                     "-o", tmp_path / "a.png"])
    assert "field 'bogus' is not in the dataset" in err
    assert not (tmp_path / "a.png").exists()


@pytest.mark.parametrize("command", ["run", "stress", "plot", "compare"])
def test_a_full_disk_is_a_failed_run_everywhere(work, tmp_path, capsys, monkeypatch, command):
    """Publishing the output fails (ENOSPC on the final rename, as a full or read-only
    disk gives): exit 1 for every command, one line, nothing at the target."""
    out = tmp_path / ("o.png" if command == "plot" else "o.nc")
    argv = {"run": ["run", work / "scene.toml", "-o", out, "--no-progress"],
            "stress": ["stress", work / "run.nc", "-o", out, "--x3", "0"],
            "plot": ["plot", work / "run.nc", "-o", out],
            "compare": ["compare", work / "run.nc", work / "run.nc", "-o", out]}[command]

    def full(src, dst):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "replace", full)
    err = one_line_error(capsys, 1, argv)
    assert "No space left on device" in err
    assert not out.exists()
