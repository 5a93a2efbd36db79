"""The comparison stage: archives against closed forms (Hertz, Lee-Radok,
Mindlin-Deresiewicz) and against each other; the error table and its files; the CLI."""

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from helpers import A_HERTZ, E_STAR_STEEL, MU, R, W, fretting_scene, make_scene

import contactpipe as cp
from contactpipe import analytic as an
from contactpipe.exceptions import ArchiveError, SceneError
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.pipeline.compare import compare
from contactpipe.pipeline.compare.reference import closed_form_for, iwan_dissipation

MD_VARIABLES = ("err_p_max", "err_p_rms", "err_contact_radius", "err_omega3", "err_q1_max",
                "err_q1_max_interior", "err_q1_rms", "err_stick_radius_cells", "err_omega1",
                "err_dissipation")


def creep_scene(**changes):
    """tiny-creep: a rigid sphere on a Maxwell half-space, frictionless, step load."""
    sc = cp.Scene(
        name="tiny-creep",
        geometry={"shape": "sphere", "radius": 0.018},
        indenter={"material": "rigid"},
        halfspace={"material": "viscoelastic", "young": 105e9, "poisson": 0.3,
                   "creep": "maxwell", "relaxation_time": 1.0},
        friction={"mu": 0.0},
        load={"time": [0.0, 1.0], "normal_force": 1000.0},
        grid={"points": [24, 24], "size": [2.4e-3, 2.4e-3]},
        time={"steps": 10})
    return sc.replace(changes) if changes else sc


@pytest.fixture(scope="module")
def archives(tmp_path_factory):
    """Small archives, made once: elastic fretting (48 x 48 over 3 aH, 40 steps),
    tiny-creep (24 x 24, 10 steps) and Hertz (64 x 64 over 4 aH, one instant)."""
    folder = tmp_path_factory.mktemp("compare")
    out = {}
    out["md"] = cp.simulate(fretting_scene(n=48, steps=40), folder / "md.nc")
    out["creep"] = cp.simulate(creep_scene(), folder / "creep.nc")
    out["hertz"] = cp.simulate(make_scene(load={"time": [0.0], "normal_force": W},
                                          time=None), folder / "hertz.nc")
    out["folder"] = folder
    return out


# --------------------------------------------------------------------------- choice

def test_closed_form_for(archives):
    assert closed_form_for(archives["md"]) == "mindlin_deresiewicz"
    assert closed_form_for(archives["creep"]) == "lee_radok"
    assert closed_form_for(archives["hertz"]) == "hertz"
    assert closed_form_for(archives["folder"] / "hertz.nc") == "hertz"      # a path
    punch = make_scene(geometry={"shape": "flat_punch", "radius": 0.4e-3})
    assert closed_form_for(punch) == "flat_punch"
    ellipsoid_t = fretting_scene(n=16, steps=4).replace(      # its contact: 1.41 a_H along
        {"geometry": {"shape": "ellipsoid", "radii": [0.036, 0.018]}, "grid.size": "auto"})
    assert closed_form_for(ellipsoid_t) is None
    # a rigid sphere on a compressible Maxwell body with friction and fretting
    visco_fretting = creep_scene(**{"friction.mu": 0.1,
                                    "load.time": [0.0, 0.2, 0.6, 1.0],
                                    "load.tangential_force": [0.0, 90.0, -90.0, 90.0]})
    assert closed_form_for(visco_fretting) is None
    # friction without a tangential load on identical bodies: no shear, so Hertz
    assert closed_form_for(make_scene(friction={"mu": 0.2})) == "hertz"


# --------------------------------------------------------------------------- Mindlin-Deresiewicz

def test_mindlin_deresiewicz_errors(archives):
    table = compare(archives["md"])
    assert table.attrs["closed_form"] == "mindlin_deresiewicz"
    for name in MD_VARIABLES:
        assert name in table, name
        assert np.all(np.isfinite(table[name].values)), name
    assert table["err_dissipation"].ndim == 0
    assert table.sizes["time"] == 41
    assert list(table.attrs["grid_points"]) == [48, 48]
    assert table.attrs["steps"] == 40
    assert "mindlin_deresiewicz" in table.attrs["summary"]
    err = {k: float(table[k].max()) for k in MD_VARIABLES}
    # Measured on 48 x 48 cells over 3 aH (16 cells per contact radius), 40 steps:
    # p_max 0.050 (the cells the contact edge cuts), q1_max 0.11 (every cell: the cells a
    # stick/slip circle cuts), q1_max_interior 0.024, q1_rms 0.021, p_rms 0.0071,
    # contact radius 0.0046, stick radius 0.22 cells, omega1 2.8e-4, omega3 2.3e-4,
    # dissipation 1.2e-4.
    assert err["err_p_max"] < 0.06, f"Hertz pressure: {err['err_p_max']:.3g}"
    assert err["err_p_rms"] < 0.01
    assert err["err_q1_max"] < 0.15, f"MD traction: {err['err_q1_max']:.3g}"
    assert err["err_q1_max_interior"] < 0.04
    assert err["err_q1_rms"] < 0.03
    # the headline is the largest error over every cell and instant, nothing left out:
    # max |q1 - cell average of q_MD| / (mu p0), by hand
    ds = archives["md"]
    h = an.hertz_sphere(W, R, E_STAR_STEEL)
    x1, x2 = ds.x1.values, ds.x2.values
    d = float(x1[1] - x1[0])
    by_hand = 0.0
    for k in range(ds.sizes["time"]):
        q_md = an.cell_average(lambda u, v, hist=ds.T1.values[:k + 1]:
                               an.mindlin_deresiewicz_traction(np.hypot(u, v), hist, MU, W,
                                                               h.contact_radius,
                                                               h.max_pressure),
                               x1[:, None], x2[None, :], d, d)
        by_hand = max(by_hand, float(np.abs(ds.q1.values[k] - q_md).max()))
    by_hand /= MU * h.max_pressure
    assert err["err_q1_max"] == pytest.approx(by_hand, rel=1e-6)
    assert f"q1_max {err['err_q1_max']:.3g}" in table.attrs["summary"]
    assert err["err_contact_radius"] < 0.01
    assert err["err_stick_radius_cells"] <= 1.0, "Cattaneo stick radius, in cells"
    assert err["err_omega1"] < 2e-3, "Mindlin tangential compliance loop"
    assert err["err_omega3"] < 2e-3, "Hertz approach"
    assert err["err_dissipation"] < 2e-3, "Mindlin-Deresiewicz energy"


def test_iwan_dissipation_matches_johnson_energy_per_cycle():
    mu, a, C = 0.1, A_HERTZ, an.tangential_compliance_sum(210e9, 0.3, 210e9, 0.3)
    Ts = 0.9 * mu * W
    hist = np.concatenate([np.linspace(0, Ts, 5), np.linspace(Ts, -Ts, 9)[1:],
                           np.linspace(-Ts, Ts, 9)[1:]])
    omega = an.tangential_displacement(hist, mu, W, a, C, all_instants=True)
    D = iwan_dissipation(omega, mu * W, 3 * mu * W * C / (16 * a))
    cycle = D[-1] - D[4]              # the state at the end equals that at the first peak
    assert cycle == pytest.approx(an.energy_per_cycle(Ts, mu, W, a, C), rel=1e-6)


def test_table_files(archives, tmp_path):
    nc, csv = tmp_path / "t" / "errors.nc", tmp_path / "errors.csv"
    table = compare(archives["folder"] / "md.nc", out=nc)
    compare(archives["md"], out=csv)
    back = xr.open_dataset(nc)
    assert back.attrs["closed_form"] == "mindlin_deresiewicz"
    np.testing.assert_allclose(back["err_q1_max"].values, table["err_q1_max"].values)
    assert float(back["err_dissipation"]) == pytest.approx(float(table["err_dissipation"]))
    back.close()
    frame = pd.read_csv(csv, comment="#")
    assert len(frame) == 41
    assert {"time", "t_norm", "err_p_max", "err_q1_max"} <= set(frame.columns)
    np.testing.assert_allclose(frame["err_q1_max"], table["err_q1_max"].values, rtol=1e-8)
    header = csv.read_text().splitlines()[:30]
    assert any(line.startswith("# err_dissipation = ") for line in header)
    assert any(line.startswith("# closed_form: mindlin_deresiewicz") for line in header)
    assert not list(tmp_path.rglob("*.part"))
    with pytest.raises(ArchiveError, match=r"\.nc\) or CSV"):
        compare(archives["md"], out=tmp_path / "errors.txt")


# --------------------------------------------------------------------------- Lee-Radok, Hertz

def test_lee_radok(archives):
    table = compare(archives["creep"])
    assert table.attrs["closed_form"] == "lee_radok"
    err = {k: float(table[k].max()) for k in table.data_vars}
    # Measured on tiny-creep (24 x 24 cells of 0.1 mm, 5 to 7 cells per contact radius,
    # 10 steps): contact radius 0.066 (cell counting), p_rms 0.047, p_max 0.16 (cells cut
    # by the growing edge), omega3 2.1e-3. On 96 x 96, 40 steps: 0.0089, 0.014, 0.097.
    assert err["err_contact_radius"] < 0.1, "Lee-Radok contact radius"
    assert err["err_p_rms"] < 0.07, "Lee-Radok pressure"
    assert err["err_p_max"] < 0.25
    assert err["err_omega3"] < 5e-3
    assert table["err_contact_radius"].values[0] < 0.05      # the instantaneous Hertz


def test_hertz(archives):
    table = compare(archives["hertz"])
    assert table.attrs["closed_form"] == "hertz"
    assert table.sizes["time"] == 1
    err = {k: float(table[k].max()) for k in table.data_vars}
    # Measured on 64 x 64 cells over 4 aH (16 cells per radius): p_max 0.049 (edge
    # cells), p_rms 0.0070, contact radius 0.0048, omega3 2.3e-4.
    assert err["err_p_max"] < 0.06, "Hertz pressure"
    assert err["err_p_rms"] < 0.01
    assert err["err_contact_radius"] < 0.01, "Hertz contact radius"
    assert err["err_omega3"] < 1e-3, "Hertz approach"


# --------------------------------------------------------------------------- archive vs archive

def test_against_itself_is_zero(archives):
    table = compare(archives["md"], archives["folder"] / "md.nc")
    assert table.attrs["closed_form"] == "none"
    assert {"err_p_max", "err_q1_max", "err_status", "err_T1", "err_omega1",
            "err_contact_radius", "err_dissipation"} <= set(table.data_vars)
    assert "err_iterations" not in table
    for name, v in table.data_vars.items():
        assert np.all(v.values == 0), name


def test_rounding_noise_reads_as_noise(archives):
    """Two runs of one scene that differ by rounding only (1e-12 of each variable's own
    size, and a torque that is noise in both: 1e-11 N m on 1e-18) compare with errors at
    the rounding level: every difference is relative to at least 1e-6 of the contact's own
    scale of its unit (p0, W, W a, the approach...), not to max |reference| alone (which
    read the torque's noise as an error of order 1). A quantity of real size is still
    measured against its own size: T1 (at most 0.09 W here) off by 1 % reads 1 %, not the
    0.09 % a floor of W would make of it."""
    ds = archives["md"].load()
    rng = np.random.default_rng(1)
    noisy = ds.copy(deep=True)
    for name, v in ds.data_vars.items():
        if v.dtype.kind == "f" and name not in ("status",):
            size = float(np.abs(v).max())
            noisy[name] = v + 1e-12 * size * rng.standard_normal(v.shape)
    noisy["M3"] = ds["M3"] + 1e-11 * rng.standard_normal(ds.sizes["time"])
    noisy["phi3"] = ds["phi3"] + 1e-20 * rng.standard_normal(ds.sizes["time"])
    assert float(np.abs(ds["M3"]).max()) < 1e-15            # the torque is noise here
    table = compare(noisy, ds)
    worst = {k: float(np.nanmax(v.values)) for k, v in table.data_vars.items()
             if k not in ("err_status", "err_stick_radius_cells")}
    assert max(v for k, v in worst.items() if k != "err_M3") < 1e-9, worst
    # M3's floor is 1e-6 W a (1 kN x 0.49 mm): 1e-11 N m of noise reads ~2e-5
    assert worst["err_M3"] < 1e-4
    assert "N m" in table.attrs["scale_floors"]
    off = ds.copy(deep=True)
    off["T1"] = 1.01 * ds["T1"]
    off["dissipation"] = 1.01 * ds["dissipation"]
    real = compare(off, ds)
    assert float(real["err_T1"].max()) == pytest.approx(0.01, rel=1e-6)
    assert float(real["err_dissipation"]) == pytest.approx(0.01, rel=1e-6)


def test_against_a_different_archive(archives):
    other = cp.simulate(creep_scene(**{"halfspace.relaxation_time": 1.5}))
    table = compare(archives["creep"], other)
    assert float(table["err_p_max"].max()) > 1e-3
    assert float(table["err_contact_radius"].max()) > 1e-3
    assert table["err_p_max"].values[0] == pytest.approx(0.0, abs=1e-12)   # t = 0: elastic


def test_against_another_grid_and_window(archives):
    """A coarser reference on a window twice as long: interpolated in x1, x2 and t_norm."""
    ref = cp.simulate(fretting_scene(n=24, steps=10).replace(
        {"load.time": [0.0, 0.4, 1.2, 2.0]}))
    table = compare(archives["md"], ref)
    assert table.attrs["time_axis"] == "t_norm"
    assert np.all(np.isfinite(table["err_p_rms"].values))
    # rate-independent elastic contact: only the discretisations differ (measured 0.032)
    assert float(table["err_p_rms"].max()) < 0.06
    assert float(table["err_T1"].max()) < 1e-8


# --------------------------------------------------------------------------- refusals

def test_no_closed_form(tmp_path):
    sc = fretting_scene(n=16, steps=2, size=4.0).replace(
        {"geometry": {"shape": "ellipsoid", "radii": [0.036, 0.018]}})
    ds = cp.simulate(sc)
    with pytest.raises(SceneError) as info:
        compare(ds)
    msg = str(info.value)
    # short: the nearest candidate's first unmet condition and what to do instead
    assert len(msg) < 200 and "\n" not in msg, msg
    assert msg.endswith(": no closed form applies (nearest: hertz needs no shear); "
                        "compare with a reference archive: contactpipe compare ARCHIVE.nc "
                        "REFERENCE.nc")


def test_missing_archive(tmp_path):
    with pytest.raises(ArchiveError, match="no such archive"):
        compare(tmp_path / "absent.nc")


# --------------------------------------------------------------------------- CLI

def test_cli_compare(archives, tmp_path, capsys):
    path = archives["folder"] / "md.nc"
    table, fig = tmp_path / "e.csv", tmp_path / "e.png"
    assert cli_main(["compare", str(path), "-o", str(table), "--figure", str(fig)]) == 0
    out = capsys.readouterr().out
    assert "err_q1_max" in out and "mindlin_deresiewicz" in out
    assert table.exists() and fig.stat().st_size > 10_000
    assert cli_main(["compare", str(path), str(path), "-o", str(tmp_path / "s.nc")]) == 0
    assert (tmp_path / "s.nc").exists()


def test_cli_compare_into_a_closed_pipe(archives):
    """``contactpipe compare ... | head -1``: the reader leaves before the table is
    written; the command stops quietly (status 141, 128 + SIGPIPE), no traceback."""
    path = archives["folder"] / "md.nc"
    proc = subprocess.Popen([sys.executable, "-m", "contactpipe.pipeline.cli", "compare",
                             str(path), str(path)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    proc.stdout.close()                       # as head does once it has its line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert err == "", err


def test_cli_compare_missing(tmp_path, capsys):
    status = cli_main(["compare", str(tmp_path / "absent.nc")])
    err = capsys.readouterr().err
    assert status != 0
    assert len(err.strip().splitlines()) == 1
    assert "absent.nc" in err and "no such archive" in err
