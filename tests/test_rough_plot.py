"""The ``rough`` figure: maps with the stick and slip clusters, the contact-area and stick
fractions, from a real 32^2 rough-sphere fretting run and from synthetic 512^2 archives;
the figure reads only the instants it draws from an archive file."""
import re
import time

import numpy as np
import pytest
from helpers import A_HERTZ, MU, R, W, make_scene
from matplotlib.image import imread
from rough_archive import rough_dataset

import contactpipe as cp
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.pipeline.figures import plot, rough
from contactpipe.post.clusters import contact_clusters

N = 32
SIDE = 3 * A_HERTZ
COUNTS = re.compile(r"status: (\d+) contact, (\d+) stick, (\d+) slip clusters")


@pytest.fixture(scope="module")
def rough_run(tmp_path_factory):
    """A fretting loop T: 0 -> 0.6 mu W -> -0.6 mu W on a generated rough sphere
    (H = 0.8, rms slope 0.02, R = 18 mm), 32^2 cells, 4 steps, written to a file."""
    geo = {"shape": "rough", "hurst": 0.8, "rms_slope": 0.02, "seed": 1,
           "wavelengths": [SIDE / 2, 6 * SIDE / N], "form": "sphere", "radius": R}
    ts = 0.6 * MU * W
    scene = make_scene(geometry=geo, friction={"mu": MU},
                       load={"time": [0.0, 0.5, 1.0], "normal_force": W,
                             "tangential_force": [0.0, ts, -ts]},
                       grid={"points": [N, N], "size": [SIDE, SIDE]}, time={"steps": 4})
    path = tmp_path_factory.mktemp("rough") / "rough.nc"
    cp.simulate(scene, path)
    return path


def _panels(fig):
    """(status map, fractions, counts) Axes of a rough figure."""
    titled = {ax.get_title().split(":")[0].split(" ")[0]: ax for ax in fig.axes}
    return titled["status"], titled["fractions"], titled["edge-connected"]


def _title_counts(fig):
    return tuple(int(c) for c in COUNTS.search(_panels(fig)[0].get_title()).groups())


def _lines(where):
    """The labelled lines of an Axes, or of every Axes of a Figure (twin axes included)."""
    axes = where.axes if hasattr(where, "savefig") else [where]
    return {line.get_label(): line for ax in axes for line in ax.get_lines()}


def test_rough_figure_of_a_real_run(rough_run, tmp_path):
    """From the 32^2 run's file: the PNG is 800 x 500 pixels; the maps are at the peak
    |T1| (the default); the title's cluster counts are contact_clusters' at that instant;
    the fractions plotted are contact_area / (32^2 cell areas) and stick_area /
    contact_area of the archive (to 1e-12), against time since W is held."""
    out = plot.save_figure(plot.plot_rough(rough_run), tmp_path / "rough.png")
    assert imread(out).shape[:2] == (500, 800)
    with cp.open_archive(rough_run) as ds:
        ds = ds.load()
    k = int(np.argmax(np.abs(ds.T1.values)))
    assert k == rough.rough_instant(ds) and 0 < k < ds.sizes["time"] - 1
    fig = plot.plot_rough(ds)
    want = contact_clusters(ds).isel(time=k)
    assert _title_counts(fig) == (int(want.contact_clusters), int(want.stick_clusters),
                                  int(want.slip_clusters))
    assert want.stick_clusters >= 1 and want.slip_clusters >= 1
    d = float(ds.x1[1] - ds.x1[0])
    lines = _lines(fig)
    ca, sa = ds.contact_area.values, ds.stick_area.values
    np.testing.assert_allclose(lines["contact area / grid area"].get_ydata(),
                               ca / (N * N * d * d), rtol=1e-12)
    np.testing.assert_allclose(lines["stick area / contact area"].get_ydata(), sa / ca,
                               rtol=1e-12)
    np.testing.assert_array_equal(lines["contact area / grid area"].get_xdata(),
                                  ds.time.values)
    assert "W = " in _panels(fig)[1].get_title()


def test_rough_figure_reads_only_the_instants_drawn(rough_run, monkeypatch):
    """The archive opens with one chunk per instant of a field, and drawing the maps at
    instant 2 reads p from the file at that instant only (every netCDF read of p is
    recorded)."""
    from xarray.backends.netCDF4_ import NetCDF4ArrayWrapper
    with cp.open_archive(rough_run) as ds:
        assert set(ds.p.chunks[0]) == {1} and ds.p.chunks[1:] == ((N,), (N,))
    read = []
    original = NetCDF4ArrayWrapper._getitem

    def spy(self, key):
        if self.variable_name == "p":
            read.append(key[0])
        return original(self, key)

    monkeypatch.setattr(NetCDF4ArrayWrapper, "_getitem", spy)
    plot.plot_rough(rough_run, 2)
    steps = set()
    for key in read:
        steps.update(range(key.start or 0, key.stop)[::key.step or 1]
                     if isinstance(key, slice) else np.atleast_1d(key).tolist())
    assert steps == {2}


def test_rough_figure_at_512_is_quick_and_exact(tmp_path):
    """A synthetic 512^2 archive of 6 instants (W rising) draws and saves in < 5 s; the
    fractions are plotted against W and equal the archive's; the title's counts equal
    contact_clusters' at the last instant (no tangential load: the default)."""
    ds = rough_dataset(512)
    start = time.perf_counter()
    fig = plot.plot_rough(ds)
    plot.save_figure(fig, tmp_path / "r512.png")
    assert time.perf_counter() - start < 5.0
    want = contact_clusters(ds).isel(time=-1)
    assert _title_counts(fig) == (int(want.contact_clusters), int(want.stick_clusters),
                                  int(want.slip_clusters))
    assert want.contact_clusters > 10
    lines = _lines(fig)
    area = 512 * 512 * float(ds.x1[1] - ds.x1[0]) ** 2
    frac = lines["contact area / grid area"]
    np.testing.assert_allclose(frac.get_ydata(), ds.contact_area.values / area, rtol=1e-12)
    np.testing.assert_array_equal(frac.get_xdata(), ds.W.values)
    np.testing.assert_allclose(lines["stick area / contact area"].get_ydata(),
                               ds.stick_area.values / ds.contact_area.values, rtol=1e-12)
    counts = _lines(_panels(fig)[2])
    per_instant = contact_clusters(ds)
    np.testing.assert_array_equal(counts["stick"].get_ydata(), per_instant.stick_clusters)


def test_rough_figure_strides_the_cluster_counts():
    """Over 60 instants the counts are taken at 24 of them, the first and last included,
    and the maps default to the peak of T1 (the last instant here)."""
    ds = rough_dataset(64, steps=60, constant_load=True)
    fig = plot.plot_rough(ds)
    x = _lines(_panels(fig)[2])["contact"].get_xdata()
    assert len(x) == rough.CLUSTER_INSTANTS and x[0] == ds.time[0] and x[-1] == ds.time[-1]
    assert "24 of 60 instants" in _panels(fig)[2].get_title()


def test_a_smooth_archive_plots_without_h0(tmp_path):
    """Any archive plots: a smooth sphere's (no h0) gives the pressure and status maps
    only, one contact cluster at the last instant; a frictionless one names its status
    separated or contact, its fraction panel and counts have no stick, and its fractions
    are against W, which rises."""
    from helpers import fretting_scene
    ds = cp.simulate(fretting_scene(n=16, steps=5))
    assert "h0" not in ds
    fig = plot.plot_rough(ds)
    titles = [ax.get_title() for ax in fig.axes]
    assert "initial gap h0" not in titles and "pressure p" in titles
    assert _title_counts(fig)[0] == 1
    smooth = cp.simulate(make_scene(grid={"points": [16, 16]}, time={"steps": 2},
                                    load={"time": [0.0, 1.0], "normal_force": [W / 4, W]}))
    assert "stick_area" not in smooth
    fig = plot.plot_rough(smooth)
    assert _panels(fig)[0].get_title() == "status: 1 contact clusters (frictionless)"
    lines = _lines(fig)
    assert "stick area / contact area" not in lines and "stick" not in lines
    np.testing.assert_array_equal(lines["contact area / grid area"].get_xdata(),
                                  smooth.W.values)


def test_cli_draws_rough_and_all_includes_it(rough_run, tmp_path, capsys):
    """``--kind rough`` writes the PNG (exit 0); ``--kind all`` adds rough.png for an
    archive with h0."""
    fig = tmp_path / "r.png"
    assert cli_main(["plot", str(rough_run), "-o", str(fig), "--kind", "rough"]) == 0
    assert imread(fig).shape[:2] == (500, 800)
    assert cli_main(["plot", str(rough_run), "-o", str(tmp_path / "all"),
                     "--kind", "all"]) == 0
    assert (tmp_path / "all" / "rough.png").is_file()


def test_pipeline_draws_the_rough_figure_of_each_member(tmp_path, capsys):
    """contactpipe pipeline over a rough sphere (16^2 cells, 2 steps, two seeds) with
    plot.figures = ["rough", "sweep"]: each member gets its rough figure."""
    geo = {"shape": "rough", "hurst": 0.8, "rms_slope": 0.02, "seed": 1,
           "wavelengths": [SIDE / 2, 4 * SIDE / 16], "form": "sphere", "radius": R}
    base = make_scene(geometry=geo, grid={"points": [16, 16], "size": [SIDE, SIDE]},
                      time={"steps": 2})
    (tmp_path / "base.toml").write_text(base.to_toml())
    (tmp_path / "pipeline.toml").write_text(
        'name = "rough-pipe"\nout = "runs"\n[sweep]\nbase = "base.toml"\n'
        '[sweep.axes]\n"geometry.seed" = [1, 2]\n'
        '[plot]\nfigures = ["rough", "sweep"]\n')
    assert cli_main(["pipeline", str(tmp_path / "pipeline.toml"), "--scheduler",
                     "synchronous", "--no-progress"]) == 0
    assert "0 failed" in capsys.readouterr().out
    figs = sorted((tmp_path / "runs" / "figures").glob("*-rough.png"))
    assert len(figs) == 2 and all(imread(f).shape[:2] == (500, 800) for f in figs)


def test_rough_figure_refuses_a_bad_value_it_draws(rough_run, tmp_path, capsys):
    """A NaN written into p at instant 2 of a copy of the run: the figure at instant 2 is
    refused in one line naming p and step 2 (CLI exit 2, nothing written), while the
    figure at instant 1, which does not read instant 2 of p, still draws."""
    import shutil

    import netCDF4

    from contactpipe.exceptions import ArchiveError
    bad = tmp_path / "bad.nc"
    shutil.copy(rough_run, bad)
    with netCDF4.Dataset(bad, "a") as nc:
        nc["p"][2, 0, 0] = np.nan
    with pytest.raises(ArchiveError, match=r"p holds NaN or inf at 1 time step\(s\), "
                                           r"first at step 2"):
        plot.plot_rough(bad, 2)
    plot.plot_rough(bad, 1)
    out = tmp_path / "bad.png"
    assert cli_main(["plot", str(bad), "-o", str(out), "--kind", "rough",
                     "--instant", "2"]) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "damaged archive" in err
