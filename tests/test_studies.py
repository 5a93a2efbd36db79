"""The studies (studies/*.py) run end to end: a --quick smoke run of each into a temporary
folder (seconds), and the full-size runs marked slow (minutes; ``pytest -m slow``)."""
import json
import pathlib
import sys

import numpy as np
import pytest
import xarray as xr

STUDIES = pathlib.Path(__file__).resolve().parents[1] / "studies"
if str(STUDIES) not in sys.path:
    sys.path.insert(0, str(STUDIES))

import extremes  # noqa: E402
import fig1_loading  # noqa: E402
import fig2_elastic_fretting  # noqa: E402
import fig3_maxwell  # noqa: E402
import fretting_map  # noqa: E402
import speed_accuracy  # noqa: E402
import time_integration  # noqa: E402

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def assert_png(path, min_bytes=5000):
    path = pathlib.Path(path)
    assert path.is_file(), f"{path} missing"
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC, f"{path} is not a PNG"
    assert len(data) > min_bytes, f"{path} is nearly empty ({len(data)} bytes)"


def assert_archive(path, variables=("p",)):
    path = pathlib.Path(path)
    assert path.is_file(), f"{path} missing"
    with xr.open_dataset(path) as ds:
        for v in variables:
            assert v in ds, f"{path}: no variable {v}"
            assert np.all(np.isfinite(ds[v].values)), f"{path}: NaN/inf in {v}"


# --------------------------------------------------------------------------- quick
def test_fig1_quick(tmp_path):
    out = fig1_loading.main(["--quick", "--out", str(tmp_path)])
    assert_png(out["png"])
    with xr.open_dataset(out["nc"]) as ds:
        assert float(ds.T1.max()) == pytest.approx(90.0)
        assert float(ds.T1.min()) == pytest.approx(-90.0)
        assert np.all(ds.W.values == 1000.0)


def test_fig2_quick(tmp_path):
    out = fig2_elastic_fretting.main(["--quick", "--out", str(tmp_path)])
    assert_png(out["png"])
    assert_archive(out["nc"], ("p", "q1", "s1", "omega1"))
    s = out["summary"]
    # 32 x 32 over 3 a_H, 10 steps: measured traction 0.48 % of mu p0 (kink cells out),
    # stick radius 0.22 cells, energy 0.13 %
    assert s["md_traction"] < 0.02 and s["md_stick_cells"] < 2 and s["md_energy"] < 0.02
    assert max(s["force_W"], s["force_T"]) < 1e-9


def test_fig3_quick(tmp_path):
    out = fig3_maxwell.main(["--quick", "--out", str(tmp_path)])
    assert_png(out["png"])
    for nc in out["nc"]:
        assert_archive(nc, ("p", "q1", "omega3"))
    for info in out["summary"]:
        assert info["margin_cells"] >= 1          # the auto grid keeps the contact inside
        assert max(info["force_W"], info["force_T"]) < 1e-9
        # 24 x 24, 10 steps: a^3 from the approach within 0.3 % of Lee-Radok (measured)
        assert info["a_omega3_err"] < 0.02


def test_speed_accuracy_quick(tmp_path):
    out = speed_accuracy.main(["--quick", "--out", str(tmp_path)])
    assert_png(out["png"], min_bytes=20000)
    for key in ("csv", "nc", "presets"):
        assert pathlib.Path(out[key]).is_file()
    pre = json.loads(pathlib.Path(out["presets"]).read_text())["presets"]
    assert set(pre) == {"fast", "balanced", "accurate"}
    assert pre["fast"]["cells_across_contact"] is not None
    with xr.open_dataset(out["nc"]) as ds:
        assert ds.sizes["run"] == len(out["rows"])
        assert np.all(np.isfinite(ds.error.values))
    # the step-start rule is first order: worse than the linear rule on the ramp
    rows = out["rows"]
    err = {(r["time_rule"], r["steps"]): r["error"] for r in rows
           if r["measure"] == "lr_ramp_a3" and r["grid"] == 16}
    assert err[("step_start", 10)] > 3 * err[("linear", 10)]
    # creep laws with little instantaneous elasticity are measured for the presets' "bdf2"
    # column: "auto" takes "bdf2" for them (its rows repeat the bdf2 run)
    for case in ("lr_kv", "lr_zener100"):
        got = {(r["time_rule"], r["steps"]): r["error"] for r in rows
               if r["measure"] == f"{case}_a3" and r["grid"] == 16}
        assert got and all(np.isfinite(v) for v in got.values())
        assert got[("auto", 10)] == got[("bdf2", 10)]


def test_time_integration_quick(tmp_path):
    """studies/time_integration.py --quick runs end to end (seconds) and its rows say what
    tests/test_time_integration.py says: "bdf2" has no hole on the Kelvin-Voigt case,
    "linear" has; the pressure fields of its Lee-Radok rows (Kelvin-Voigt included, from
    analytic.lee_radok_pressure) are finite."""
    out = time_integration.main(["--quick", "--out", str(tmp_path)])
    assert_png(out["png"])
    assert pathlib.Path(out["csv"]).is_file()
    holes = {r["rule"]: r["holes"] for r in out["rows"]
             if r["part"] == "lee_radok" and r["law"] == "kelvin_voigt"}
    assert holes["bdf2"] == 0 and holes["auto"] == 0 and holes["linear"] > 0
    fields = [r["value"] for r in out["rows"] if r["part"] == "lee_radok"]
    assert fields and all(np.isfinite(f) for f in fields)


def test_extremes_quick(tmp_path):
    out = extremes.main(["--quick", "--out", str(tmp_path)])
    assert pathlib.Path(out["csv"]).is_file()
    failed = [(r.case, r.outcome, r.measured) for r in out["results"] if not r.passed]
    assert not failed, failed
    # converged cases left archives, diagnostics none
    for r in out["results"]:
        if r.outcome == "converged":
            assert any((tmp_path / "extremes").glob("*.nc"))


def test_fretting_map_quick(tmp_path):
    """studies/fretting_map.py --quick (16², 4 steps per quarter, 3 amplitudes x 2 mu, in
    this process): the map, the regime table, every member's regime that of the closed
    form (measured: all 6 agree; the largest |A - A_cf| 0.008, bound 0.03)."""
    out = fretting_map.main(["--quick", "--out", str(tmp_path), "--scheduler",
                             "synchronous"])
    assert_png(out["png"], min_bytes=20000)
    assert pathlib.Path(out["csv"]).is_file()
    s = out["summary"]
    assert s["members"] == 6 and s["disagree"] == 0
    assert s["max_A_error"] < 0.03


# --------------------------------------------------------------------------- full size
@pytest.mark.slow
def test_fig2_full(tmp_path):
    """128 x 128 over 3 a_H, 40 steps: measured traction 0.43 % of mu p0 along x1 through
    the centre (kink cells out; plain 4.6 %, RMS 0.65 %); as contactpipe compare measures
    it (every cell), 7.0 %, away from the stick/slip circles and the edge 1.4 %; stick
    radius 0.20 cells, loop and energy 2e-5."""
    out = fig2_elastic_fretting.main(["--out", str(tmp_path)])
    assert_png(out["png"])
    s = out["summary"]
    assert s["md_traction"] < 0.02 and s["md_stick_cells"] < 2
    assert s["compare_err_q1_max"] < 0.10 and s["compare_err_q1_max_interior"] < 0.02
    assert s["md_loop"] < 0.02 and s["md_energy"] < 0.02
    assert s["hertz_p0"] < 0.01


@pytest.mark.slow
def test_fig3_full(tmp_path):
    """128 x 128 auto grid, 200 steps, tau = t' and 2 t' (about 90 s)."""
    out = fig3_maxwell.main(["--out", str(tmp_path)])
    assert_png(out["png"])
    for info in out["summary"]:
        assert info["margin_cells"] >= 5
        assert max(info["force_W"], info["force_T"]) < 1e-9
        assert info["a_omega3_err"] < 0.01


@pytest.mark.slow
def test_speed_accuracy_full(tmp_path):
    out = speed_accuracy.main(["--out", str(tmp_path)])
    assert_png(out["png"], min_bytes=20000)
    pre = json.loads(pathlib.Path(out["presets"]).read_text())["presets"]
    assert pre["fast"]["reached"] and pre["balanced"]["reached"]


@pytest.mark.slow
def test_extremes_full(tmp_path):
    out = extremes.main(["--out", str(tmp_path)])
    failed = [(r.case, r.outcome, r.measured) for r in out["results"] if not r.passed]
    assert not failed, failed


@pytest.mark.slow
def test_fretting_map_full(tmp_path):
    """32², 8 steps per quarter, 7 amplitudes x 5 mu on a LocalCluster: measured all 35
    members in the closed form's regime, the largest |A - A_cf| 0.006 (bound 0.02)."""
    out = fretting_map.main(["--out", str(tmp_path)])
    assert_png(out["png"], min_bytes=20000)
    s = out["summary"]
    assert s["members"] == 35 and s["disagree"] == 0 and s["max_A_error"] < 0.02
