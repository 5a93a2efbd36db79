"""``contactpipe bench wear``: the table it prints and writes (structure and consistency
only; speed is never asserted). --quick: 16², 8 steps a cycle, a life of 1000 cycles and
a check of 30 cycles (jump auto against jump 1)."""
import csv
import math

import pytest

from contactpipe.pipeline import cli
from contactpipe.pipeline.cli import bench_wear

RTOL = 2e-5        # the file keeps six significant digits


def test_wear_table_is_written_whole_and_consistent(tmp_path, capsys):
    out = tmp_path / "bench-wear.csv"
    assert cli.main(["bench", "wear", "--quick", "--csv", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "simulated" in printed and f"wrote {out}" in printed
    with open(out, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        header, rows = reader.fieldnames, list(reader)
    assert tuple(header) == bench_wear.WEAR_COLUMNS
    assert [(r["run"], r["cycles"], r["jump"]) for r in rows] == [
        ("life", "1000", "auto"), ("check", "30", "1"), ("check", "30", "auto")]
    life, every, auto = rows
    for r in rows:
        assert r["case"] == "wear" and r["grid"] == "16" and r["steps"] == "8", r
        n, sim = int(r["cycles"]), int(r["cycles_simulated"])
        assert 1 <= sim <= n and r["date"] and r["commit"], r
        assert float(r["ms_per_simulated_cycle"]) == pytest.approx(
            float(r["run_s"]) / sim * 1e3, rel=RTOL)
        assert float(r["max_wear_depth"]) > 0 and float(r["worn_volume"]) > 0
    assert int(every["cycles_simulated"]) == 30          # jump = 1 simulates every cycle
    assert int(life["cycles_simulated"]) < 1000          # the jumps are taken
    # the check wears as much in 30 cycles as the life in 1000: k x 1000 / 30
    assert float(every["coefficient"]) == pytest.approx(float(life["coefficient"]) * 1000 / 30,
                                                        rel=RTOL)
    assert every["depth_error"] == "" and life["volume_error"] == ""
    vol = abs(float(auto["worn_volume"]) - float(every["worn_volume"])) / \
        float(every["worn_volume"])
    # from volumes kept to six digits: each rounded by up to 5e-6 of itself
    assert float(auto["volume_error"]) == pytest.approx(vol, abs=1.1e-5)
    assert math.isfinite(float(auto["depth_error"])) and float(auto["depth_error"]) >= 0


def test_wear_table_has_its_own_columns(tmp_path, capsys):
    """--csv with wear and another case: refused (exit 2, one line), nothing run."""
    out = tmp_path / "mixed.csv"
    assert cli.main(["bench", "wear", "normal", "--quick", "--csv", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "run wear alone" in err
    assert not out.exists()
