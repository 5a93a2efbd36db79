"""studies/wear_vs_cracking.py runs end to end (--quick: 16², 8 steps a cycle, 1000
cycles, delta*/delta_gs = 0.4, 1.0, 2.5, a dask sweep run synchronously): slow, as it
sweeps three wear lives and evaluates Crossland on six kept loops."""
import csv
import pathlib
import sys

import pytest

STUDIES = pathlib.Path(__file__).resolve().parents[1] / "studies"
if str(STUDIES) not in sys.path:
    sys.path.insert(0, str(STUDIES))

import wear_vs_cracking  # noqa: E402


@pytest.mark.slow
def test_wear_vs_cracking_quick(tmp_path):
    """The table and the figure; the worn volume grows with the amplitude (more slip,
    more wear: 1.1e-7, 2.6e-6, 2.2e-5 mm^3 measured), every member jumps (12 of 1000
    cycles simulated), the Crossland peak sits at the surface at the end of life, and the
    unworn contact's peak grows from partial slip to the gross slip boundary (0.206 to
    0.337 measured)."""
    out = wear_vs_cracking.main(["--quick", "--out", str(tmp_path), "--scheduler",
                                 "synchronous"])
    assert pathlib.Path(out["png"]).stat().st_size > 20000
    with open(out["csv"], newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert [float(r["delta_ratio"]) for r in rows] == [0.4, 1.0, 2.5]
    vol = [float(r["worn_volume_m3"]) for r in rows]
    assert vol[0] < vol[1] < vol[2]
    assert all(int(r["cycles_simulated"]) < int(r["cycles"]) == 1000 for r in rows)
    first = [float(r["crossland_first"]) for r in rows]
    assert first[0] < first[1]
    assert all(float(r["crossland_last_x3_m"]) == 0.0 for r in rows)
