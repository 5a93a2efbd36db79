"""Fatigue against wear: a criterion on each kept loop of a wear run (contactpipe.post.
wear_fatigue), on a synthetic archive of the documented wear shape whose loops are one
loop of Hertz-Cattaneo tractions scaled by s = 1 + N/N_last: stress is linear in the
tractions, so Crossland's index scales as s and SWT's parameter as s^2, at the same point."""
import numpy as np
import pytest
import xarray as xr
from wear_archive import wear_dataset

import contactpipe as cp
from contactpipe.exceptions import ArchiveError
from contactpipe.post import wear_fatigue as wf

KEPT = [1, 30, 1000]
SCALE = 1.0 + np.asarray(KEPT) / KEPT[-1]
X3 = [0.0, 5e-5]
CROSSLAND = {"torsion_limit": 300e6, "bending_limit": 450e6}


@pytest.fixture(scope="module")
def ds():
    return wear_dataset(n=16, steps=6, kept=KEPT)


def test_loop_tractions_are_the_kept_loop(ds):
    loop = wf.loop_tractions(ds, 30)
    assert tuple(loop["p"].dims) == ("time", "x1", "x2")
    np.testing.assert_array_equal(loop["q1"].values, ds["loop_q1"].isel(loop_cycle=1).values)
    np.testing.assert_array_equal(loop["time"].values, ds["loop_time"].values)
    with pytest.raises(ValueError, match="keeps the loops of cycles 1, 30, 1000"):
        wf.loop_tractions(ds, 31)


def test_crossland_over_cycles_scales_with_the_loops(ds):
    fc = wf.fatigue_over_cycles(ds, X3, "crossland", poisson=0.3, **CROSSLAND)
    assert list(fc["cycle"].values) == KEPT
    assert fc.attrs["criterion_field"] == "crossland_index"
    # the first loop, by hand: its stress history through cp.fatigue
    st = cp.subsurface_stress(wf.loop_tractions(ds, 1), X3, time="all", poisson=0.3)
    first = float(cp.fatigue(st, "crossland", **CROSSLAND)["maximum"])
    assert float(fc["maximum"][0]) == pytest.approx(first, rel=1e-12)
    np.testing.assert_allclose(fc["maximum"].values / first, SCALE / SCALE[0], rtol=1e-9)
    # the same point (up to the loop's mirror symmetry in x1: ties broken by round-off)
    for ax in ("x1", "x2", "x3"):
        assert np.ptp(np.abs(fc[f"maximum_{ax}"].values)) == 0.0


def test_swt_over_cycles_scales_as_the_square(ds):
    fc = wf.fatigue_over_cycles(ds, X3, "swt", poisson=0.3, young=210e9, plane_step=15)
    m = fc["maximum"].values
    assert np.all(m > 0)
    np.testing.assert_allclose(m / m[0], (SCALE / SCALE[0]) ** 2, rtol=1e-6)


def test_refuses_archives_without_loops():
    with pytest.raises(ArchiveError, match="kept no loop of tractions"):
        wf.fatigue_over_cycles(wear_dataset(n=8, steps=2), X3, poisson=0.3, **CROSSLAND)
    plain = xr.Dataset({"p": (("time", "x1", "x2"), np.zeros((2, 4, 4)))})
    with pytest.raises(ArchiveError, match="not the archive of a wear run"):
        wf.fatigue_over_cycles(plain, X3, poisson=0.3, **CROSSLAND)


def test_parse_constants():
    from contactpipe.pipeline.cli.stress import parse_constants
    assert parse_constants(["torsion_limit=3e8", "shear_amplitude=mcb"]) == \
        {"torsion_limit": 3e8, "shear_amplitude": "mcb"}
    with pytest.raises(ValueError, match="give NAME=VALUE"):
        parse_constants(["torsion_limit"])


def test_cli_over_cycles_refuses_an_archive_without_loops(tmp_path, capsys):
    from helpers import fretting_scene

    from contactpipe.pipeline.cli import main as cli_main
    cp.simulate(fretting_scene(n=16, steps=5), tmp_path / "md.nc").close()
    status = cli_main(["stress", str(tmp_path / "md.nc"), "-o", str(tmp_path / "c.nc"),
                       "--x3", "0", "--over-cycles", "crossland",
                       "--constant", "torsion_limit=300e6", "--constant",
                       "bending_limit=450e6"])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert "not the archive of a wear run" in err
    assert not (tmp_path / "c.nc").exists()


def test_cli_over_cycles_of_a_wear_run(tmp_path, capsys):
    """A real wear run (16², 10 cycles, loops of cycles 1 and 10 kept): the file holds
    the criterion over the kept cycles, equal to cp.fatigue_over_cycles of the archive."""
    from wear_archive import wear_run

    from contactpipe.pipeline.cli import main as cli_main
    archive = wear_run(tmp_path / "wear.nc")
    out = tmp_path / "crossland.nc"
    assert cli_main(["stress", str(archive), "-o", str(out), "--x3", "0,2e-5",
                     "--over-cycles", "crossland", "--constant", "torsion_limit=300e6",
                     "--constant", "bending_limit=450e6"]) == 0
    assert "largest crossland_index" in capsys.readouterr().out
    direct = cp.fatigue_over_cycles(archive, [0.0, 2e-5], "crossland", **CROSSLAND)
    with xr.open_dataset(out) as got:
        assert got["cycle"].values.tolist() == [1, 10]
        np.testing.assert_allclose(got["maximum"].values, direct["maximum"].values,
                                   rtol=1e-12)
        assert np.all(got["maximum"].values > 0)
