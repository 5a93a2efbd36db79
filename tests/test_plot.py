"""The plotting stage: every figure is a PNG of the expected pixel size; the standard set
follows the archive; sweeps plot one curve per member; the CLI."""
import io

import numpy as np
import pytest
import xarray as xr
from helpers import fretting_scene
from matplotlib.image import imread

import contactpipe as cp
from contactpipe.exceptions import ArchiveError
from contactpipe.pipeline.cli import main as cli_main
from contactpipe.pipeline.figures import plot, sweeps
from contactpipe.pipeline.inputs import centre_rows
from contactpipe.post.stress import save_stress

SHAPE = (500, 800, 4)      # 8 x 5 in at 100 dpi, RGBA


def creep_scene():
    """tiny-creep: a rigid sphere on a Maxwell half-space, frictionless, step load."""
    return cp.Scene(
        name="tiny-creep",
        geometry={"shape": "sphere", "radius": 0.018},
        indenter={"material": "rigid"},
        halfspace={"material": "viscoelastic", "young": 105e9, "poisson": 0.3,
                   "creep": "maxwell", "relaxation_time": 1.0},
        load={"time": [0.0, 1.0], "normal_force": 1000.0},
        grid={"points": [24, 24], "size": [2.4e-3, 2.4e-3]},
        time={"steps": 10})


def visco_fretting_scene():
    """tiny-fretting: rigid sphere on a compressible Maxwell body, a fretting loop."""
    return creep_scene().replace({
        "name": "tiny-fretting", "friction.mu": 0.1,
        "load.time": [0.0, 0.2, 0.6, 1.0],
        "load.tangential_force": [0.0, 90.0, -90.0, 90.0],
        "grid.size": [2.0e-3, 2.0e-3], "time.steps": 20})


@pytest.fixture(scope="module")
def archives(tmp_path_factory):
    folder = tmp_path_factory.mktemp("plot")
    return {
        "md": cp.simulate(fretting_scene(n=32, steps=20), folder / "md.nc"),
        "fretting": cp.simulate(visco_fretting_scene(), folder / "fretting.nc"),
        "creep": cp.simulate(creep_scene(), folder / "creep.nc"),
        "folder": folder,
    }


def draw(plot_function, obj, path, *args, **kwargs):
    """Draw with a plot function (it returns the Figure), then save it as the CLI does."""
    return plot.save_figure(plot_function(obj, *args, **kwargs), path)


def check_png(path):
    assert path.exists() and path.stat().st_size > 5_000, path
    image = imread(path)
    assert image.shape == SHAPE, (path, image.shape)
    assert image[..., :3].std() > 0.01, "a blank figure"


@pytest.mark.parametrize("kind", ["md", "fretting", "creep"])
def test_profiles(archives, tmp_path, kind):
    path = draw(plot.plot_profiles, archives[kind], tmp_path / "p.png")
    assert path == tmp_path / "p.png"
    check_png(path)


def test_profiles_instants(archives, tmp_path):
    ds = archives["md"]
    check_png(draw(plot.plot_profiles, ds, tmp_path / "a.png", instants=[4, -1]))
    check_png(draw(plot.plot_profiles, ds, tmp_path / "b.png", instants=[0.6], closed_form=False))
    with pytest.raises(ValueError, match="out of range"):
        draw(plot.plot_profiles, ds, tmp_path / "c.png", instants=[99])


def test_default_instants_include_turning_points(archives):
    # 20 steps over [0, 1]: T1 turns at t = 0.2 (k = 4) and t = 0.6 (k = 12)
    ks = plot._default_instants(archives["md"])
    assert {4, 12, 20} <= set(ks) and len(ks) == 5 and 0 not in ks
    assert plot._default_instants(archives["creep"]) == [0, 2, 5, 8, 10]


def test_centre_rows():
    assert list(centre_rows(np.array([-1.5, -0.5, 0.5, 1.5]))) == [1, 2]
    assert list(centre_rows(np.array([-1.0, 0.0, 1.0]))) == [1]


@pytest.mark.parametrize("kind", ["fretting", "creep"])
def test_maps(archives, tmp_path, kind):
    check_png(draw(plot.plot_maps, archives[kind], tmp_path / "m.png"))


def test_maps_instant(archives, tmp_path):
    check_png(draw(plot.plot_maps, archives["md"], tmp_path / "m.png", instant=3))
    with pytest.raises(ValueError, match="out of range"):
        draw(plot.plot_maps, archives["md"], tmp_path / "x.png", instant=-50)


def test_hysteresis(archives, tmp_path):
    check_png(draw(plot.plot_hysteresis, archives["md"], tmp_path / "h.png"))
    check_png(draw(plot.plot_hysteresis, archives["folder"] / "fretting.nc", tmp_path / "v.png"))
    with pytest.raises(ArchiveError, match="frictionless"):
        draw(plot.plot_hysteresis, archives["creep"], tmp_path / "no.png")
    assert not (tmp_path / "no.png").exists()


@pytest.mark.parametrize("kind", ["md", "creep"])
def test_radii(archives, tmp_path, kind):
    check_png(draw(plot.plot_radii, archives[kind], tmp_path / "r.png"))


def test_standard_figures(archives, tmp_path):
    frictional = plot.standard_figures(archives["fretting"], tmp_path / "f", prefix="run_")
    assert [p.name for p in frictional] == ["run_profiles.png", "run_maps.png",
                                            "run_hysteresis.png", "run_radii.png"]
    frictionless = plot.standard_figures(archives["creep"], tmp_path / "c")
    assert [p.name for p in frictionless] == ["profiles.png", "maps.png", "radii.png"]
    for p in frictional + frictionless:
        check_png(p)
    assert sorted(x.name for x in (tmp_path / "c").iterdir()) == \
        ["maps.png", "profiles.png", "radii.png"]          # nothing else, no .part


def test_sweep_along_mu(tmp_path):
    members = [cp.simulate(fretting_scene(n=16, steps=6, size=4.0, mu=mu))
               for mu in (0.1, 0.12, 0.15)]
    sw = xr.concat(members, dim=xr.DataArray([0.1, 0.12, 0.15], dims="mu", name="mu"),
                   combine_attrs="drop_conflicts")
    check_png(draw(plot.plot_sweep, sw, tmp_path / "s.png"))
    assert sweeps._member_label(sw, {"mu": 1}) == "mu = 0.12"
    check_png(draw(plot.plot_sweep, sw, tmp_path / "d.png", variable="dissipation"))
    check_png(draw(plot.plot_sweep, sw, tmp_path / "p.png", variable="p"))     # max over x1, x2
    with pytest.raises(ArchiveError, match="not in the sweep"):
        draw(plot.plot_sweep, sw, tmp_path / "x.png", variable="nope")


def test_sweep_on_t_norm(archives, tmp_path):
    """Members with different windows, aligned on t_norm, each keeping its own time."""
    members = []
    for ds in (archives["creep"], archives["creep"]):
        t = ds["time"].values
        members.append(ds.assign_coords(t_norm=("time", (t - t[0]) / (t[-1] - t[0])))
                       .swap_dims(time="t_norm"))
    members[1] = members[1].assign_coords(time=("t_norm", 2 * members[1]["time"].values))
    sw = xr.concat(members, dim=xr.DataArray([1.0, 2.0], dims="tau_ratio"),
                   combine_attrs="drop_conflicts")
    assert sw["time"].ndim == 2
    check_png(draw(plot.plot_sweep, sw, tmp_path / "t.png"))
    # a zip sweep: one dimension "member", the axes as coordinates along it
    zipped = sw.rename(tau_ratio="member").drop_vars("member").assign_coords(
        tau_ratio=("member", [1.0, 2.0]), mu=("member", [0.0, 0.1]))
    label = sweeps._member_label(zipped, {"member": 1})
    assert sorted(label.split(", ")) == ["mu = 0.1", "tau_ratio = 2"]
    check_png(draw(plot.plot_sweep, zipped, tmp_path / "z.png", variable="W"))


def test_cli_plot(archives, tmp_path, capsys):
    path = str(archives["folder"] / "fretting.nc")
    assert cli_main(["plot", path, "-o", str(tmp_path / "p.png")]) == 0
    check_png(tmp_path / "p.png")
    creep = str(archives["folder"] / "creep.nc")
    assert cli_main(["plot", creep, "-o", str(tmp_path / "all"), "--kind", "all"]) == 0
    assert sorted(p.name for p in (tmp_path / "all").iterdir()) == \
        ["maps.png", "profiles.png", "radii.png"]
    assert "wrote" in capsys.readouterr().out


def test_cli_plot_errors(archives, tmp_path, capsys):
    status = cli_main(["plot", str(tmp_path / "absent.nc"), "-o", str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    assert status != 0 and len(err.strip().splitlines()) == 1
    assert "no such archive" in err
    creep = str(archives["folder"] / "creep.nc")
    status = cli_main(["plot", creep, "-o", str(tmp_path / "h.png"), "--kind", "hysteresis"])
    err = capsys.readouterr().err
    assert status != 0 and "frictionless" in err and len(err.strip().splitlines()) == 1


def test_plot_functions_return_the_figure_and_write_nothing(archives, tmp_path,
                                                            monkeypatch):
    """Each function draws into the axes or figure it is given and returns the Figure;
    only save_figure writes."""
    from matplotlib.figure import Figure
    monkeypatch.chdir(tmp_path)
    ds = archives["md"]
    for fig in (plot.plot_profiles(ds), plot.plot_maps(ds), plot.plot_hysteresis(ds),
                plot.plot_radii(ds)):
        assert isinstance(fig, Figure) and fig.axes
    outer = Figure(figsize=plot.FIGSIZE, dpi=plot.DPI)
    left, right = outer.subplots(1, 2)
    assert plot.plot_hysteresis(ds, ax=left) is outer
    assert plot.plot_radii(ds, ax=right) is outer
    assert len(outer.axes) == 2 and left.lines and right.lines
    given = Figure()
    assert plot.plot_profiles(ds, fig=given) is given and len(given.axes) == 2  # p and q1
    assert plot.plot_maps(ds, fig=Figure()).axes
    assert list(tmp_path.iterdir()) == []
    check_png(plot.save_figure(plot.plot_radii(archives["folder"] / "md.nc"),
                               tmp_path / "sub" / "r.png"))


def test_profiles_against_a_reference_archive(archives, tmp_path):
    fig = plot.plot_profiles(archives["md"], reference=archives["folder"] / "md.nc")
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "reference archive" in labels
    check_png(plot.save_figure(fig, tmp_path / "ref.png"))


def test_standard_figures_refuse_a_file_as_folder(archives, tmp_path):
    from contactpipe.exceptions import OutputPathError
    (tmp_path / "f").write_text("x")
    with pytest.raises(OutputPathError, match="is a file, not a folder"):
        plot.standard_figures(archives["creep"], tmp_path / "f")
    assert (tmp_path / "f").read_text() == "x"


# --------------------------------------------------------------------------- stress kind

@pytest.fixture(scope="module")
def stress_file(archives):
    """A stress file of the tiny fretting archive: every instant, three depths."""
    st = cp.subsurface_stress(archives["fretting"], [0.0, 5e-5, 1.5e-4], time="all")
    return save_stress(st, archives["folder"] / "stress.nc")


def titles(fig):
    return " ".join(ax.get_title() for ax in fig.axes)


def test_stress_kind(stress_file, tmp_path, capsys):
    """A stress file's default kind is stress: the von Mises section through the centre
    and the surface map, 800 x 500 pixels like every figure; --variable and --instant
    choose the field and the instant."""
    assert plot.input_kind(stress_file) == "stress"
    assert cli_main(["plot", str(stress_file), "-o", str(tmp_path / "s.png")]) == 0
    check_png(tmp_path / "s.png")
    assert cli_main(["plot", str(stress_file), "-o", str(tmp_path / "t.png"), "--kind",
                     "stress", "--variable", "s13", "--instant", "4"]) == 0
    check_png(tmp_path / "t.png")
    assert capsys.readouterr().out.count("wrote") == 2
    fig = plot.plot_stress(stress_file)
    assert len(fig.axes) == 4 and "von_mises at x2" in titles(fig)    # 2 panels, 2 bars
    assert "t = 1 s" in titles(fig)
    assert "t = 0.2 s" in titles(plot.plot_stress(stress_file, "s13", instant=4))


def test_stress_kind_draws_a_criterion(archives, tmp_path):
    """A dataset holding a criterion (a fatigue result, or a stress file with one) is
    drawn by the criterion's main field unless told otherwise."""
    st = cp.subsurface_stress(archives["fretting"], [0.0, 1e-4], time="all")
    fi = cp.fatigue(st.isel(time=slice(4, None)), "amplitude")
    assert "equivalent_amplitude at x2" in titles(plot.plot_stress(fi))
    merged = st.merge(fi.drop_vars(["maximum", "maximum_x1", "maximum_x2", "maximum_x3"]))
    merged.attrs = dict(st.attrs, criterion_field=fi.attrs["criterion_field"])
    check_png(plot.save_figure(plot.plot_stress(merged), tmp_path / "c.png"))
    assert "equivalent_amplitude" in titles(plot.plot_stress(merged))
    assert "von_mises" in titles(plot.plot_stress(merged, "von_mises"))
    with pytest.raises(ValueError, match="field 'p' is not in the dataset"):
        plot.plot_stress(merged, "p")


@pytest.mark.parametrize("source, kind, name", [
    ("archive", "stress", "an archive"),
    ("stress", "profiles", "a stress file"),
    ("stress", "all", "a stress file"),
    ("stress", "sweep", "a stress file"),
    ("sweep", "maps", "a sweep folder"),
    ("sweep", "stress", "a sweep folder"),
])
def test_kind_that_does_not_apply_is_one_line_exit_2(archives, stress_file, tmp_path, capsys,
                                                     source, kind, name):
    sweep_dir = tmp_path / "sweep"
    sweep_dir.mkdir()
    path = {"archive": archives["folder"] / "fretting.nc", "stress": stress_file,
            "sweep": sweep_dir}[source]
    out = tmp_path / "x.png"
    assert cli_main(["plot", str(path), "-o", str(out), "--kind", kind]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert f"--kind {kind} does not apply to {name} ({path})" in err
    assert "a stress file takes stress" in err and "a sweep folder takes sweep" in err
    assert not out.exists() and list(sweep_dir.iterdir()) == []


def test_inputs_are_opened_one_way(archives, stress_file, tmp_path):
    """A path given to a figure is opened as what it holds; the wrong kind of input is
    one ArchiveError naming both."""
    with plot.open_input(stress_file) as (kind, ds):
        assert kind == "stress" and "von_mises" in ds
    with plot.open_input(archives["folder"] / "creep.nc") as (kind, ds):
        assert kind == "archive" and "p" in ds
    with pytest.raises(ArchiveError, match=r"stress.nc is a stress file, not an archive"):
        plot.plot_profiles(stress_file)
    with pytest.raises(ArchiveError, match=r"creep.nc is an archive, not a stress file"):
        plot.plot_stress(archives["folder"] / "creep.nc")
    with pytest.raises(ArchiveError, match=r"is a sweep folder, not an archive"):
        plot.plot_radii(tmp_path)
    with pytest.raises(ArchiveError, match="no such archive"):
        plot.plot_radii(tmp_path / "absent.nc")


# --------------------------------------------------------------------------- legibility

def test_sweep_shows_an_area_in_mm2_without_an_offset(tmp_path):
    """The overlay of contact_area reads 'contact area [mm²]' with the values in mm²
    (0.4-0.8 mm² here), not 'contact_area (contact area) [m2]' over a 1e-6 multiplier."""
    members = [cp.simulate(fretting_scene(n=16, steps=6, size=4.0, mu=mu))
               for mu in (0.1, 0.15)]
    sw = xr.concat(members, dim=xr.DataArray([0.1, 0.15], dims="mu", name="mu"),
                   combine_attrs="drop_conflicts")
    fig = plot.plot_sweep(sw)
    ax = fig.axes[0]
    fig.canvas.draw()
    assert ax.get_ylabel() == "contact area [mm²]"
    assert ax.yaxis.get_offset_text().get_text() == ""
    top = max(float(np.max(line.get_ydata())) for line in ax.lines)
    assert top == pytest.approx(float(sw.contact_area.max()) * 1e6, rel=1e-12)
    assert plot.plot_sweep(sw, "omega1").axes[0].get_ylabel().endswith("[µm]")


def test_maps_fill_the_figure(archives):
    """The three maps side by side, their colour bars beneath: each map at least 200
    pixels wide of the 800 (they were 155, with 40 % of the figure empty)."""
    for kind in ("md", "creep"):
        fig = plot.plot_maps(archives[kind])
        fig.savefig(io.BytesIO(), format="png", dpi=plot.DPI)     # lays the figure out
        maps = [a for a in fig.axes if a.get_title()]
        assert [a.get_title() for a in maps] == ["pressure p", "shear traction |q|",
                                                 "status"]
        widths = [a.get_window_extent().width for a in maps]
        assert min(widths) > 200, widths
        tops = {round(a.get_window_extent().y1) for a in maps}
        assert len(tops) == 1, tops                    # aligned, frictionless or not


def test_closed_form_is_drawn_on_top(archives):
    """The closed form's curves are black dashes above every numerical curve."""
    for fig in (plot.plot_profiles(archives["md"]), plot.plot_radii(archives["md"]),
                plot.plot_hysteresis(archives["md"])):
        for ax in fig.axes:
            closed = [ln for ln in ax.lines
                      if ln.get_linestyle() == "--" and len(ln.get_xdata())]
            numerical = [ln for ln in ax.lines if ln.get_marker() not in ("None", None, "")]
            assert closed and numerical
            assert min(ln.get_zorder() for ln in closed) > max(
                ln.get_zorder() for ln in numerical)


def test_stress_section_starts_at_the_surface(stress_file):
    """The x1-x3 section runs from the surface (x3 = 0 at the top) to the deepest depth
    (0.15 mm), not from half a depth step above the surface; the colour bar names the
    field in mathtext."""
    fig = plot.plot_stress(stress_file)
    section = fig.axes[0]
    assert section.get_ylim() == pytest.approx((0.15, 0.0), abs=1e-12)
    bars = [a.get_ylabel() for a in fig.axes if a.get_ylabel().endswith("[MPa]")]
    assert bars and all(r"$\sigma_\mathrm{vM}$" in b for b in bars), bars
