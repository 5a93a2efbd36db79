"""``contactpipe bench phases``: the table it prints and writes (structure and consistency
only; speed is never asserted). --quick: the five cases at 16², 5 steps."""
import cProfile
import csv
import pstats

import numpy as np
import pytest

from contactpipe.pipeline import cli
from contactpipe.pipeline.cli import bench_phases
from contactpipe.solver.convolution import HAVE_PYFFTW, Convolver

RTOL = 2e-5        # the file keeps six significant digits
PHASES = ("transforms", "filters", "products", "inners")

needs_pyfftw = pytest.mark.skipif(not HAVE_PYFFTW, reason="the phases are timed in pyFFTW")


def _table(folder, *options):
    """(header, rows) of ``contactpipe bench phases --quick`` with ``options``."""
    out = folder / "bench-phases.csv"
    assert cli.main(["bench", "phases", "--quick", "--csv", str(out), *options]) == 0
    with open(out, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        return reader.fieldnames, list(reader)


@pytest.fixture(scope="module")
def quick_table(tmp_path_factory):
    return _table(tmp_path_factory.mktemp("phases"))


@needs_pyfftw
def test_phase_table_is_written_whole_and_consistent(quick_table):
    header, rows = quick_table
    assert tuple(header) == bench_phases.PHASE_COLUMNS
    assert [(r["case"], r["pair"], r["form"]) for r in rows] == [
        ("fretting", "steel/Al", "scalar"), ("fretting", "steel/Al", "scalar"),
        ("fretting", "steel/Al", "vector"), ("fretting", "steel/steel", "vector"),
        ("paper-fig3", "rigid/Maxwell", "scalar")]
    for r in rows:
        v = {c: float(r[c]) for c in bench_phases.PHASE_COLUMNS if c.endswith(
            ("_per_step", "_ms", "_floor", "_spectral"))}
        assert r["grid"] == "16" and r["steps"] == "5" and r["date"] and r["commit"], r
        parts = [v[f"{p}_ms_per_step"] for p in PHASES]
        # every phase ran: the joint solves and the vector CGs filter, take products and
        # Parseval inners; none took longer than the step itself
        assert all(0.0 < x < v["ms_per_step"] for x in parts), r
        assert v["spectral_ms_per_step"] == pytest.approx(sum(parts), rel=RTOL)
        assert v["rest_ms_per_step"] == pytest.approx(
            v["ms_per_step"] - v["spectral_ms_per_step"], rel=1e-4, abs=1e-5)
        assert v["floor_ms_per_step"] == pytest.approx(v["pairs_per_step"] * v["pair_ms"],
                                                       rel=RTOL)
        for ratio, num, den in (("wall_over_floor", "ms_per_step", "floor_ms_per_step"),
                                ("spectral_over_floor", "spectral_ms_per_step",
                                 "floor_ms_per_step"),
                                ("wall_over_spectral", "ms_per_step", "spectral_ms_per_step")):
            assert v[ratio] == pytest.approx(v[num] / v[den], rel=1e-4), (r, ratio)


@needs_pyfftw
def test_tuning_reaches_the_phase_runs(quick_table, tmp_path):
    """--tuning halves=false: the one-component joint solves apply their operator whole,
    so they take more FFT pairs and no Parseval inner; the vector form, whose operator is
    always applied in halves, is unchanged in pairs."""
    _, rows = _table(tmp_path, "--tuning", "halves=false")
    for default, whole in zip(quick_table[1], rows, strict=True):
        pairs = float(default["pairs_per_step"]), float(whole["pairs_per_step"])
        if whole["form"] == "scalar":
            assert pairs[1] > pairs[0] and float(whole["inners_ms_per_step"]) == 0.0, whole
        else:
            assert pairs[1] == pairs[0] and float(whole["inners_ms_per_step"]) > 0.0, whole


@needs_pyfftw
def test_the_phases_are_read_from_the_functions_that_ran():
    """The profile's time is summed over the functions named and no other: a convolution
    counts as an entry point, its transforms inside it, the filter it did not call
    counts nothing."""
    conv = Convolver(16, 16, backend="pyfftw")
    khat = conv.kernel_spectrum(np.ones((32, 32)))
    x = np.random.default_rng(0).normal(size=(16, 16))
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(20):
        conv.convolve(khat, x)
    prof.disable()
    stats = pstats.Stats(prof)
    f = bench_phases.spectral_functions()
    entry, transforms = (bench_phases._seconds(stats, f[k]) for k in ("entry", "transforms"))
    assert 0.0 < transforms < entry
    assert bench_phases._seconds(stats, f["filters"]) == 0.0
    calls = {k[2]: v[1] for k, v in stats.stats.items()}
    assert calls["convolve"] == 20 and calls["_execute_forward"] == 20


def test_phases_refuse_scipy_and_other_cases_in_one_table(tmp_path, capsys):
    """Refused, exit 2 and one line naming the option and what is allowed, nothing run:
    the phases time pyFFTW's plans, and their table has columns of its own."""
    assert cli.main(["bench", "phases", "--quick", "--fft", "scipy"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--fft scipy" in err and "allowed" in err
    out = tmp_path / "mixed.csv"
    assert cli.main(["bench", "phases", "normal", "--quick", "--csv", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "run phases alone" in err
    assert not out.exists()


@needs_pyfftw
def test_phases_refuse_to_run_beside_another_profiler(monkeypatch, capsys):
    """Where cProfile cannot start (Python 3.12+ refuses a second profiler, e.g. coverage's
    sys.monitoring core): refused, exit 2, one line saying so, before any profiled run."""
    class Busy(cProfile.Profile):
        def enable(self, *a, **k):
            raise ValueError("Another profiling tool is already active")
    monkeypatch.setattr(bench_phases.cProfile, "Profile", Busy)
    assert cli.main(["bench", "phases", "--quick"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "another profiler" in err, err
