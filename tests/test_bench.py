"""``contactpipe bench``: the table it prints and writes (structure and consistency only;
speed is never asserted: the wall times are the machine's of the moment)."""
import csv
import math

import pytest

from contactpipe.pipeline import cli
from contactpipe.pipeline.cli import bench

FIGURES = ("pairs_per_step", "ms_per_step", "pair_ms", "floor_ms_per_step",
           "wall_over_floor", "first_instant_pairs", "run_pairs", "run_s", "cpus")
RTOL = 2e-5        # the file keeps six significant digits


def _read(path):
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        return reader.fieldnames, list(reader)


def test_fretting_table_is_written_whole_and_consistent(tmp_path, capsys):
    """16², 5 steps, both bodies and both forms: four rows of every column, every figure
    finite and positive, floor = pairs × pair time, wall / floor = wall / floor, the run's
    pairs = the first instant's + the estimate's + steps × pairs a step, and the run's time
    at least the steps' (they are part of it)."""
    out = tmp_path / "results" / "bench-fretting.csv"
    assert cli.main(["bench", "fretting", "--grids", "16", "--steps", "5",
                     "--csv", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "wall/floor" in printed and f"wrote {out}" in printed
    header, rows = _read(out)
    assert tuple(header) == bench.COLUMNS
    assert {(r["pair"], r["form"]) for r in rows} == {
        (p, f) for p in ("steel/steel β=0", "steel/Al β≠0") for f in ("scalar", "vector")}
    assert not list(tmp_path.glob("results/.*"))                # no temporary file left
    for r in rows:
        v = {k: float(r[k]) for k in FIGURES}
        assert all(math.isfinite(x) and x > 0 for x in v.values()), r
        assert r["case"] == "fretting" and r["grid"] == "16" and r["steps"] == "5", r
        assert float(r["tolerance"]) == 1e-9 and r["date"] and r["commit"], r
        assert float(r["load_average"]) >= 0, r
        assert v["floor_ms_per_step"] == pytest.approx(v["pairs_per_step"] * v["pair_ms"],
                                                       rel=RTOL)
        assert v["wall_over_floor"] == pytest.approx(
            v["ms_per_step"] / v["floor_ms_per_step"], rel=RTOL)
        assert v["run_pairs"] == pytest.approx(
            v["first_instant_pairs"] + float(r["preload_estimate_pairs"])
            + 5 * v["pairs_per_step"], rel=RTOL)
        assert v["run_s"] * 1e3 >= 5 * v["ms_per_step"] * (1 - RTOL), r
        # a step cannot take less time than its transforms: a sanity bound, with room for
        # the pair being timed in a quieter moment than the run
        assert v["wall_over_floor"] >= 0.5, r
    steel_al = [r for r in rows if r["pair"] == "steel/Al β≠0"]
    assert all(int(r["preload_estimate_pairs"]) > 0 for r in steel_al)   # frictional preload


def test_quick_run_writes_no_table_without_csv(capsys):
    """``--quick`` prints the table and leaves the checked-in files as they were."""
    target = bench.default_table_path("normal")
    assert target.name == "bench-normal.csv" and target.parent.name == "results"
    before = target.stat().st_mtime_ns if target.exists() else None
    assert cli.main(["bench", "normal", "--quick"]) == 0
    printed = capsys.readouterr().out
    assert "no table written" in printed and "16x16" in printed
    assert (target.stat().st_mtime_ns if target.exists() else None) == before


@pytest.mark.parametrize("argv, words", [
    (["--grids", "1"], ("--grids 1", "≥ 2")),
    (["--steps", "0"], ("--steps 0", "≥ 1")),
    (["nonsense"], ("'nonsense'", "fretting")),
])
def test_bad_arguments_are_refused_in_one_line(capsys, argv, words):
    assert cli.main(["bench", *argv]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and all(w in err for w in words), err


def test_a_folder_as_table_is_refused_before_any_run(tmp_path, capsys):
    """``--csv`` naming a folder: exit 2, one line naming the option, nothing run."""
    assert cli.main(["bench", "fretting", "--csv", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert "--csv" in captured.err and len(captured.err.strip().splitlines()) == 1
    assert captured.out == "" and list(tmp_path.iterdir()) == []


def _pairs(out):
    """{(pair, form): pairs a step} of a written fretting table."""
    return {(r["pair"], r["form"]): float(r["pairs_per_step"]) for r in _read(out)[1]}


def test_tuning_switches_a_feature_off_for_the_run(tmp_path, capsys):
    """``--tuning joint=false``: the coupled pair (steel/Al, 16², 5 steps) runs on block
    Gauss-Seidel passes alone, so its FFT pairs a step (deterministic) rise (measured
    40.4 -> 67.6 scalar, 72.2 -> 124.6 vector), while the uncoupled pair (steel/steel,
    β = 0: no joint solve) spends exactly the pairs of the default run (13.2, 38.2)."""
    args = ["bench", "fretting", "--grids", "16", "--steps", "5", "--csv"]
    assert cli.main([*args, str(tmp_path / "default.csv")]) == 0
    assert cli.main([*args, str(tmp_path / "off.csv"), "--tuning", "joint=false"]) == 0
    capsys.readouterr()
    default, off = _pairs(tmp_path / "default.csv"), _pairs(tmp_path / "off.csv")
    for form in ("scalar", "vector"):
        assert off[("steel/steel β=0", form)] == default[("steel/steel β=0", form)]
        assert off[("steel/Al β≠0", form)] > 1.2 * default[("steel/Al β≠0", form)]


@pytest.mark.parametrize("item, words", [
    ("jointt=false", ("'jointt=false'", "joint, halves, defer")),
    ("defer=abc", ("defer='abc'", "a number")),
    ("joint=maybe", ("joint='maybe'", "true or false")),
])
def test_bad_tuning_is_refused_in_one_line(capsys, item, words):
    """A misspelt switch, or a value of the wrong kind: exit 2, one line naming it and
    what is allowed, nothing run."""
    assert cli.main(["bench", "fretting", "--quick", "--tuning", item]) == 2
    captured = capsys.readouterr()
    assert len(captured.err.strip().splitlines()) == 1, captured.err
    assert all(w in captured.err for w in words), captured.err
    assert captured.out == ""
