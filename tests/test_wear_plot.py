"""The wear figure (contactpipe plot ARCHIVE --kind wear): it renders from an archive of
the documented wear shape, with and without kept loops of tractions, and refuses an archive
that is not one of a wear run with a one-line reason."""
import numpy as np
import pytest
from helpers import fretting_scene
from matplotlib.image import imread
from wear_archive import wear_dataset

import contactpipe as cp
from contactpipe.exceptions import ArchiveError
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.pipeline.figures import plot, wear

SHAPE = (500, 800, 4)      # 8 x 5 in at 100 dpi, RGBA


def check_png(path):
    assert path.exists() and path.stat().st_size > 5_000, path
    image = imread(path)
    assert image.shape == SHAPE, (path, image.shape)
    assert image[..., :3].std() > 0.01, "a blank figure"


@pytest.mark.parametrize("kept", [None, [1, 30, 1000]])
def test_wear_figure_renders(tmp_path, kept):
    ds = wear_dataset(kept=kept)
    fig = plot.plot_wear(ds)
    axes = fig.get_axes()
    # six panels, the colour bar of the map and the energy's twin axis
    assert len(axes) == 8
    profiles = [ln for ln in axes[0].get_lines() if ln.get_label().startswith("N =")]
    shown = [int(ln.get_label().split("= ")[1].replace(",", "")) for ln in profiles]
    assert shown[0] == 1 and shown[-1] == 1000 and len(shown) == 5
    # the deepest point drawn is the archive's deepest wear at the last cycle, through
    # the centre row (even grid: the two middle rows averaged), in um
    rows = ds["wear_depth"].isel(cycle=-1, x2=[11, 12]).values.mean(axis=1)
    assert -np.min(profiles[-1].get_ydata()) == pytest.approx(rows.max() * 1e6, rel=1e-12)
    pressure = [ln.get_label() for ln in axes[2].get_lines()]
    assert pressure == (["N = 1", "N = 30", "N = 1,000"] if kept else
                        ["last simulated cycle (of 7 solved)"])
    check_png(plot.save_figure(fig, tmp_path / "wear.png"))


def test_wear_history_is_the_archive(tmp_path):
    ds = wear_dataset()
    fig = plot.plot_wear(ds)
    vol = fig.get_axes()[3].get_lines()[0]
    np.testing.assert_allclose(vol.get_xdata(), ds["cycle"].values)
    np.testing.assert_allclose(vol.get_ydata(), ds["worn_volume"].values * 1e9, rtol=1e-14)


def test_wear_figure_refuses_other_archives():
    ds = wear_dataset().drop_dims("cycle")
    with pytest.raises(ArchiveError, match="no 'cycle' dimension") as err:
        plot.plot_wear(ds)
    assert "\n" not in str(err.value)
    with pytest.raises(ArchiveError, match="lacks cycle_stick_area"):
        plot.plot_wear(wear_dataset().drop_vars("cycle_stick_area"))
    assert not wear.is_wear_archive(ds) and wear.is_wear_archive(wear_dataset())


def test_cli_refuses_a_non_wear_archive(tmp_path, capsys):
    archive = cp.simulate(fretting_scene(n=16, steps=5), tmp_path / "md.nc")
    archive.close()
    status = cli_main(["plot", str(tmp_path / "md.nc"), "-o", str(tmp_path / "w.png"),
                       "--kind", "wear"])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert "wear run" in err and "no 'cycle' dimension" in err
    assert not (tmp_path / "w.png").exists()


def test_cli_draws_a_wear_run(tmp_path, capsys):
    """A real wear run (16², 10 cycles, two kept loops) through the command line."""
    from wear_archive import wear_run
    archive = wear_run(tmp_path / "wear.nc")
    assert cli_main(["plot", str(archive), "-o", str(tmp_path / "w.png"), "--kind",
                     "wear"]) == 0
    assert "wrote" in capsys.readouterr().out
    check_png(tmp_path / "w.png")
    fig = plot.plot_wear(archive)
    assert [ln.get_label() for ln in fig.get_axes()[2].get_lines()] == ["N = 1", "N = 10"]
    # --kind all adds the wear figure for a wear run
    written = plot.standard_figures(archive, tmp_path / "all")
    assert [p.name for p in written] == ["profiles.png", "maps.png", "hysteresis.png",
                                         "radii.png", "wear.png"]
    check_png(written[-1])
