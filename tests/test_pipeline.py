"""Batch pipeline: sweep -> compare -> plot -> stress; idempotent (mtimes, and the stress
settings' digest), cron lock (exit 3), failures reported (exit 1), bad files (exit 2)."""
import fcntl
import importlib
import json
import os
import pathlib
import textwrap

import numpy as np
import pytest
import xarray as xr

import contactpipe as cp
from contactpipe.pipeline import cli
from contactpipe.pipeline.cli.run import PipelineLockedError, run_pipeline
from contactpipe.pipeline.sweep.config import read_pipeline_file
from contactpipe.post.stress import open_stress
from contactpipe.testing import TINY_SCENES

CREEP = TINY_SCENES["creep"]


def make_study(root: pathlib.Path, forces=(500.0, 1000.0), figures=None, reference=None,
               stress=None):
    """scenes/creep.toml, sweep.toml and pipeline.toml under ``root``; ``stress``: the
    body of a [stress] table (TOML text). A force too large for the grid is left to the
    run (``grid.size_check = false``): its member fails with a GridError."""
    (root / "scenes").mkdir(parents=True, exist_ok=True)
    scene = CREEP if max(forces) <= 1000.0 else CREEP.replace(
        "size = [2.4e-3, 2.4e-3]", "size = [2.4e-3, 2.4e-3]\nsize_check = false")
    (root / "scenes" / "creep.toml").write_text(scene)
    (root / "sweep.toml").write_text(textwrap.dedent(f"""
        base = "scenes/creep.toml"
        [axes]
        load.normal_force = {list(forces)}
    """))
    extra = ""
    if reference is not None:
        extra += f'[compare]\nreference = "{reference}"\n'
    if figures is not None:
        extra += f"[plot]\nfigures = {json.dumps(list(figures))}\n"
    if stress is not None:
        extra += "[stress]\n" + textwrap.dedent(stress)
    path = root / "pipeline.toml"
    path.write_text(textwrap.dedent("""
        name = "demo"
        [sweep]
        file = "sweep.toml"
        out = "runs/demo"
        [dask]
        scheduler = "synchronous"
    """) + extra)
    return path


def stamps(folder: pathlib.Path):
    """{relative path: (inode, mtime_ns)} of every product and archive."""
    skip = {"summary.json", "manifest.json", ".pipeline.lock", ".sweep.lock"}
    return {str(p.relative_to(folder)): (p.stat().st_ino, p.stat().st_mtime_ns)
            for p in folder.rglob("*") if p.is_file() and p.name not in skip}


def forbid(monkeypatch, module, *names):
    for name in names:
        def boom(*args, _name=name, **kwargs):
            raise AssertionError(f"{module.__name__}.{_name} called on an up-to-date run")
        monkeypatch.setattr(module, name, boom)


def test_second_run_does_nothing_and_stale_products_are_redone(tmp_path, monkeypatch):
    path = make_study(tmp_path, figures=["profiles", "radii", "sweep"])
    out = tmp_path / "runs" / "demo"
    first = run_pipeline(path, progress=False)
    assert first.ok, first.failed
    assert len(first.computed) == 2 and not first.skipped
    digests = sorted(m.digest for m in first.sweep.members)
    for d in digests:
        assert (out / f"{d}.nc").is_file()
        assert (out / "compare" / f"{d}.nc").is_file()       # Lee-Radok applies
        assert (out / "figures" / f"{d}-profiles.png").is_file()
        assert (out / "figures" / f"{d}-radii.png").is_file()
    assert (out / "figures" / "sweep-contact_area.png").is_file()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ok"] and summary["counts"]["computed"] == 2
    assert summary["counts"]["products_written"] == 2 + 4 + 1
    assert {m["compare"]["closed_form"] for m in summary["members"]} == {"lee_radok"}
    before = stamps(out)
    assert not [k for k in before if ".part" in k or "-tmp" in k]

    # nothing changed: no solver, no compare, no figure runs; nothing is rewritten
    compare = importlib.import_module("contactpipe.pipeline.compare.tables")
    plot = importlib.import_module("contactpipe.pipeline.figures.plot")
    simulate = importlib.import_module("contactpipe.simulation")
    forbid(monkeypatch, compare, "compare")
    forbid(monkeypatch, plot, "plot_profiles", "plot_radii", "plot_sweep")
    forbid(monkeypatch, simulate, "simulate")
    second = run_pipeline(path, progress=False)
    assert second.ok, second.failed
    assert not second.computed and len(second.skipped) == 2
    assert second.written == [] and len(second.up_to_date) == 7
    assert stamps(out) == before
    summary = json.loads((out / "summary.json").read_text())
    assert summary["counts"] == {"members": 2, "computed": 0, "skipped": 2, "failed": 0,
                                 "products_written": 0, "products_up_to_date": 7}
    monkeypatch.undo()

    # one member's archive is newer than its products: only those are redone
    calls = []

    def fake_compare(archive, reference=None, *, out=None, figure=None):
        calls.append(("compare", pathlib.Path(archive).name))
        pathlib.Path(out).write_bytes(b"table")

    def fake_plot(kind):
        def draw(ds, *args, **kw):
            calls.append((kind, None))
            return plot.new_figure()
        return draw

    monkeypatch.setattr(compare, "compare", fake_compare)
    for kind in ("profiles", "radii", "sweep"):
        monkeypatch.setattr(plot, f"plot_{kind}", fake_plot(kind))
    forbid(monkeypatch, simulate, "simulate")
    touched = out / f"{digests[0]}.nc"
    later = max(v[1] for v in before.values()) + 1_000_000_000   # after every product
    os.utime(touched, ns=(later, later))
    third = run_pipeline(path, progress=False)
    assert third.ok, third.failed
    assert not third.computed
    assert sorted(calls) == sorted([("compare", touched.name), ("profiles", None),
                                    ("radii", None), ("sweep", None)])
    after = stamps(out)
    changed = sorted(k for k in after if after[k] != before[k])
    assert changed == sorted([f"{digests[0]}.nc", f"compare/{digests[0]}.nc",
                              f"figures/{digests[0]}-profiles.png",
                              f"figures/{digests[0]}-radii.png",
                              "figures/sweep-contact_area.png"])


def test_lock_held_exits_3_with_one_line(tmp_path, capsys):
    path = make_study(tmp_path, figures=[], reference="none")
    out = tmp_path / "runs" / "demo"
    out.mkdir(parents=True)
    fd = os.open(out / ".pipeline.lock", os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, b"pid 12345 since yesterday\n")
        code = cli.main(["pipeline", str(path), "--no-progress"])
        err = capsys.readouterr().err
        with pytest.raises(PipelineLockedError):
            run_pipeline(path, progress=False)
    finally:
        os.close(fd)
    assert code == 3
    assert err.count("\n") == 1 and "another pipeline run holds the lock" in err
    assert "pid 12345" in err
    assert not (out / "manifest.json").exists()              # nothing was done
    # the lock dies with its holder: the next run goes ahead
    assert cli.main(["pipeline", str(path), "--no-progress"]) == 0


def test_failed_member_others_land_exit_1(tmp_path, capsys):
    path = make_study(tmp_path, forces=(1000.0, 1.0e5), figures=["radii"], reference="none")
    out = tmp_path / "runs" / "demo"
    code = cli.main(["pipeline", str(path), "--no-progress"])
    captured = capsys.readouterr()
    assert code == 1
    assert "load.normal_force=100000" in captured.err and "GridError" in captured.err
    summary = json.loads((out / "summary.json").read_text())
    assert not summary["ok"]
    assert [f["member"] for f in summary["failed"]] == ["load.normal_force=100000"]
    assert summary["failed"][0]["stage"] == "simulate"
    good = [m for m in summary["members"] if m["status"] == "done"]
    assert len(good) == 1 and (out / good[0]["file"]).is_file()
    assert (out / "figures" / f"{good[0]['digest']}-radii.png").is_file()


def test_bad_pipeline_file_exit_2(tmp_path, capsys):
    path = tmp_path / "pipeline.toml"
    path.write_text('name = "x"\ncolour = "red"\n[sweep]\nfile = "nope.toml"\n'
                    '[plot]\nfigures = ["profiles", "pie"]\n')
    assert cli.main(["pipeline", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    for part in ("unknown key 'colour'", "no such sweep file", "unknown figure 'pie'",
                 "out is missing"):
        assert part in err
    with pytest.raises(Exception, match="no such sweep file"):
        read_pipeline_file(path)


# --------------------------------------------------------------------------- [stress]

STRESS = """
    depths = {max = 1.5e-4, count = 3}
    time = "all"
    criterion = "crossland"
    torsion_limit = 400e6
    bending_limit = 600e6
    cycle = [0.2, 1.0]
"""


def test_stress_product_computed_once_then_when_its_inputs_change(tmp_path, monkeypatch):
    """The [stress] product of a member (stress and Crossland in one file, and its
    figure): written once and equal to the API's result; nothing redone on a second run;
    redone when the settings (depths, a constant) change or the archive is newer; a
    member whose product fails is reported (stage "stress", exit 1), the others land."""
    path = make_study(tmp_path, forces=(1000.0,), figures=[], reference="none",
                      stress=STRESS)
    out = tmp_path / "runs" / "demo"
    first = run_pipeline(path, progress=False)
    assert first.ok, first.failed
    digest = first.sweep.members[0].digest
    archive, product = out / f"{digest}.nc", out / "stress" / f"{digest}.nc"
    figure = out / "figures" / f"{digest}-stress.png"
    assert sorted(map(str, first.written)) == sorted([str(product), str(figure)])
    assert figure.stat().st_size > 5_000
    depths = [0.0, 7.5e-5, 1.5e-4]
    ref = cp.subsurface_stress(cp.open_archive(archive), depths, time="all").load()
    cross = cp.fatigue(ref.sel(time=slice(0.2, 1.0)), "crossland", torsion_limit=400e6,
                       bending_limit=600e6)
    with open_stress(product) as st:
        assert st.sizes == {"time": 11, "x3": 3, "x1": 24, "x2": 24}
        assert np.allclose(st["von_mises"].values, ref["von_mises"].values, rtol=1e-12,
                           atol=0)
        assert np.allclose(st["crossland_index"].values, cross["crossland_index"].values,
                           rtol=1e-9, atol=0)
        assert st.attrs["criterion"] == "crossland" and "9 instants" in st.attrs["cycle"]
    rec = json.loads((out / "summary.json").read_text())["members"][0]["stress"]
    assert rec["status"] == "written" and rec["figure"] == str(figure)
    assert rec["criterion_maximum"] == pytest.approx(float(cross["maximum"]), rel=1e-9)
    assert rec["von_mises_max"] == pytest.approx(float(ref["von_mises"].max()), rel=1e-12)
    before = stamps(out)

    # nothing changed: no stress work, nothing rewritten
    stress_cmd = importlib.import_module("contactpipe.pipeline.cli.stress")
    plot = importlib.import_module("contactpipe.pipeline.figures.plot")
    forbid(monkeypatch, stress_cmd, "write_stress_product")
    forbid(monkeypatch, plot, "plot_stress")
    second = run_pipeline(path, progress=False)
    assert second.ok and not second.written and len(second.up_to_date) == 2
    assert stamps(out) == before
    summary = json.loads((out / "summary.json").read_text())
    assert summary["members"][0]["stress"]["status"] == "up to date"
    assert summary["stress"]["settings"]["depths"] == depths
    monkeypatch.undo()

    def rerun(stress_table, expect_written=True):
        make_study(tmp_path, forces=(1000.0,), figures=[], reference="none",
                   stress=stress_table)
        res = run_pipeline(path, progress=False)
        assert res.ok, res.failed
        assert not res.computed                                   # the archive is kept
        assert sorted(map(str, res.written)) == \
            (sorted([str(product), str(figure)]) if expect_written else [])
        with open_stress(product) as st:
            return st.sizes["x3"], float(st["maximum"].values)

    # other depths, then another constant: recomputed; back to the same: kept
    assert rerun(STRESS.replace("count = 3", "count = 4"))[0] == 4
    stronger = STRESS.replace("count = 3", "count = 4").replace("400e6", "450e6")
    nz, peak = rerun(stronger)
    assert nz == 4 and peak < rec["criterion_maximum"]
    rerun(stronger, expect_written=False)
    # the cycle in t_norm of the archive (0 to 1 s here): other settings, the same instants
    in_t_norm = stronger.replace("cycle = ", "cycle_norm = ")
    assert rerun(in_t_norm) == (nz, peak)
    # the archive is newer than its product: recomputed
    later = max(v[1] for v in stamps(out).values()) + 1_000_000_000
    os.utime(archive, ns=(later, later))
    rerun(in_t_norm)

    # a product that cannot be made is a failure of that member's stress stage
    make_study(tmp_path, forces=(1000.0,), figures=[], reference="none",
               stress='depths = [0.0]\nbody = "indenter"\n')
    assert cli.main(["pipeline", str(path), "--no-progress"]) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert [f["stage"] for f in summary["failed"]] == ["stress"]
    assert "is rigid" in summary["failed"][0]["error"]
    assert not [p for p in (out / "stress").iterdir() if p.name != product.name]


@pytest.mark.parametrize("table, parts", [
    ("depth = [0.0]\n", ["unknown key 'stress.depth' (did you mean 'depths'?)",
                         "stress.depths is required"]),
    ("depths = [0.0, -1e-4]\nbody = \"ball\"\n",
     ["stress.depths must be a list of depths from 0 to 1e+06 [m]",
      "stress.body must be one of"]),
    ("depths = {max = 1e-4, cont = 3}\n",
     ["unknown key 'stress.depths.cont' (did you mean 'count'?)"]),
    ("depths = [0.0]\ncriterion = \"crosland\"\n",
     ["stress.criterion = 'crosland' is not a criterion (did you mean 'crossland'?)"]),
    ("depths = [0.0]\ncriterion = \"dang_van\"\ntorsion_limit = 4e8\nyoung = 2e11\n",
     ["stress.bending_limit is required for criterion = 'dang_van'",
      "stress.young = 200000000000.0 is not used by criterion = 'dang_van'",
      "needs the stress over a cycle"]),
    ("depths = [0.0]\ntime = \"al\"\ncycle = [1.0, 0.0]\n",
     ["stress.time must be 'last', 'all' or a list of times [s]",
      "stress.cycle = [1.0, 0.0]: t_start must be < t_end"]),
    ("depths = [0.0]\ntime = \"all\"\ncriterion = \"amplitude\"\ncycle = [0.0, 1.0]\n"
     "cycle_norm = [0.0, 1.5]\n",
     ["stress.cycle_norm must be [a, b], 0 <= a < b <= 1",
      "stress.cycle and stress.cycle_norm cannot both be given"]),
    ("depths = [0.0]\ncycle_norm = [0.2, 1.0]\n",
     ["stress.cycle_norm = [0.2, 1.0] is not used without a criterion"]),
    # a plane grid of 1e-4 degrees (~4e12 planes) exhausted the memory (SIGKILL)
    ("depths = [0.0]\ntime = \"all\"\ncriterion = \"swt\"\nyoung = 2e11\n"
     "plane_step = 1e-4\n",
     ["stress.plane_step", "0.0001", "an angle in [1, 90] [deg]"]),
])
def test_bad_stress_table_exit_2(tmp_path, capsys, table, parts):
    path = make_study(tmp_path, forces=(1000.0,), figures=[], reference="none",
                      stress=table)
    assert cli.main(["pipeline", str(path), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    for part in parts:
        assert part in err, (part, err)
    assert not (tmp_path / "runs").exists()                  # nothing run, nothing written


def test_the_examples_stress_table_reads(tmp_path):
    """examples/pipeline.toml's commented-out [stress] block, uncommented, is valid: 13
    depths to 0.6 mm, Crossland over t_norm 0.2 to 1 (the default main job leaves it out)."""
    examples = pathlib.Path(__file__).resolve().parents[1] / "examples"
    for name in ("sweep.toml", "paper-maxwell.toml"):
        (tmp_path / name).write_text((examples / name).read_text())
    text = (examples / "pipeline.toml").read_text()
    assert read_pipeline_file(examples / "pipeline.toml").stress is None
    lines = text.splitlines()
    start = lines.index("# [stress]")
    block = [ln[2:] for ln in lines[start:] if ln.startswith("# ")]
    (tmp_path / "pipeline.toml").write_text("\n".join(lines[:start] + block) + "\n")
    spec = read_pipeline_file(tmp_path / "pipeline.toml").stress
    assert len(spec.depths) == 13 and spec.depths[-1] == pytest.approx(6e-4)
    assert spec.criterion == "crossland" and spec.cycle_norm == (0.2, 1.0)


EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def test_the_example_pipeline_has_a_member_with_a_closed_form():
    """examples/pipeline.toml runs every stage: its fourth member (the Maxwell body under
    the step load alone, mu = 0) is Lee-Radok's problem, so compare/ gets a table; the
    fretting members have no closed form. That member, coarsened to 24 x 24 cells and 20
    steps, compares within the discretisation's error (measured: contact radius 4.7 %,
    approach 0.12 %; the example's 64 x 64 cells, 100 steps: 1.4 %, 0.018 %)."""
    from contactpipe.pipeline.compare import compare
    from contactpipe.pipeline.compare.reference import closed_form_for
    from contactpipe.pipeline.sweep.members import build_members
    spec = read_pipeline_file(EXAMPLES / "pipeline.toml")
    assert spec.reference == "closed_form" and "sweep" in spec.figures
    _, _, _, members = build_members(spec.base, spec.axes, spec.mode)
    forms = [closed_form_for(m.scene) for m in members]
    assert forms == [None, None, None, "lee_radok"], forms
    coarse = members[3].scene.replace({"grid.points": [24, 24], "time.steps": 20})
    table = compare(cp.simulate(coarse))
    assert table.attrs["closed_form"] == "lee_radok"
    assert float(table["err_contact_radius"].max()) < 0.1
    assert float(table["err_omega3"].max()) < 5e-3


@pytest.mark.slow
def test_the_example_pipeline_writes_every_stage(tmp_path):
    """The README's first command, into a temporary folder: archives, compare/ (one
    table, Lee-Radok), the member figures and the sweep overlays (~1 min on 2 cores)."""
    examples = tmp_path / "examples"
    examples.mkdir()
    for name in ("sweep.toml", "paper-maxwell.toml", "pipeline.toml"):
        (examples / name).write_text((EXAMPLES / name).read_text())
    assert cli.main(["pipeline", str(examples / "pipeline.toml"), "--no-progress"]) == 0
    out = tmp_path / "runs" / "paper-fig3"
    tables = list((out / "compare").glob("*.nc"))
    assert len(tables) == 1
    with xr.open_dataset(tables[0]) as tb:
        assert tb.attrs["closed_form"] == "lee_radok"
        assert float(tb["err_contact_radius"].max()) < 0.03
    assert (out / "figures" / "sweep-contact_area.png").exists()
