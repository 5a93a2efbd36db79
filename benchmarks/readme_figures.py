"""The speed figures the README quotes, measured and written to a file that is checked in.

    python benchmarks/readme_figures.py [--update-readme]        # the full cases (minutes)
    python benchmarks/readme_figures.py --quick --out FILE.csv   # a smoke run (seconds)

Runs the cases of ``contactpipe bench`` that the README's "Speed" section quotes, with one
FFT thread:

``normal``      Hertz normal solve, cold, tolerance 1e-10, 64² / 128² / 256² / 512²;
``fretting``    the fretting loop, 40 steps, steel/steel (β = 0) and steel/aluminium (β ≠ 0),
                one-component form at 64² / 128² / 256², vector form at 64² / 128²: per
                warm step, and the first instant's FFT pairs with those of the frictional
                preload's error estimate;
``paper-fig3``  rigid sphere on Maxwell, coupled, 128², 200 steps end to end, both forms;
``fig3-study``  the two runs of ``studies/fig3_maxwell.py`` (τ = t′ and 2t′, 128², 200
                steps, frictionless preload), timed one by one;
``memory``      the history's cost per step at steps 0-10 and 990-1000 (64², 1000 steps).

and writes every figure to ``benchmarks/results/readme.csv`` (one row per case, pair,
form, grid and quantity; a comment header says when, on how many CPUs and at what load
average). ``--update-readme`` then rewrites the README's table between the markers
``<!-- readme-figures:begin -->`` and ``<!-- readme-figures:end -->`` from that file;
``--render FILE.csv`` prints the table of an existing file. The pair counts are exact and
repeat; the wall times are this machine's on that day (the "floor" column, the time of one
FFT pair on the padded grid, measured beside each run, shows how fast it was, and
"wall / floor", the wall time over pairs × floor, compares across days). The quantities
keep ``contactpipe bench``'s names (its table's columns: ``contactpipe.pipeline.cli.bench``).

``--quick``: 16² grids, 10 steps (the fretting loop and figure 3), 25 steps (memory): a
smoke run of seconds; give ``--out``, so the checked-in file keeps the
full figures.
"""
from __future__ import annotations

import argparse
import csv
import datetime
import io
import math
import os
import pathlib
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # one BLAS thread, as the studies pin it

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results" / "readme.csv"
README = ROOT / "README.md"
BEGIN, END = "<!-- readme-figures:begin -->", "<!-- readme-figures:end -->"
FIELDS = ("case", "pair", "form", "grid", "steps", "quantity", "value")

sys.path.insert(0, str(ROOT / "studies"))      # the study's own scene builder

from contactpipe.pipeline.cli import bench  # noqa: E402
from contactpipe.simulation import simulate  # noqa: E402

FULL = dict(normal=[64, 128, 256, 512], fretting=[64, 128, 256], fretting_steps=40,
            fig3=(128, 200), memory=(64, 1000))
QUICK = dict(normal=[16], fretting=[16], fretting_steps=10, fig3=(16, 10), memory=(16, 25))


def _archived(scene):
    """(seconds, FFT pairs with the preload estimate's) of ``scene`` streamed to an
    archive in a temporary folder."""
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        with simulate(scene, pathlib.Path(tmp) / "fig3.nc") as ds:
            wall = time.perf_counter() - t0
            pairs = int(ds.fft_pairs.values.sum()
                        + ds.attrs.get("preload_estimate_fft_pairs", 0))
    return wall, pairs


def fig3_study(n, steps):
    """The two runs of studies/fig3_maxwell.py (its scenes, its archives streamed to disk),
    each timed: records like bench's."""
    import _common as c  # studies/_common.py: the study's scene, built the same way
    import fig3_maxwell as study
    rows = []
    print(f"studies/fig3_maxwell.py: {n}², {steps} steps per window, archive written")
    for ratio in study.WINDOWS:
        scene = c.maxwell_fretting_scene(n=n, steps=steps, window=ratio * c.RELAXATION_TIME,
                                         name=f"fig3-maxwell-tau{ratio:g}",
                                         preload=study.PRELOAD[0])
        (wall, pairs), floor = bench.pair_ms_around(n, "auto", 1, _archived, scene)
        print(f"  tau = {ratio:g} t': {wall:.1f} s ({pairs:,} FFT pairs, one pair {floor:.3f} "
              f"ms, wall / floor {wall * 1e3 / (pairs * floor):.1f})")
        rows.append(dict(case="fig3-study", pair="rigid/Maxwell", form=f"tau={ratio:g}t'",
                         grid=n, steps=steps, run_s=wall, pair_ms=floor, run_pairs=pairs))
    return rows


def measure(quick: bool) -> list:
    """Every case's records, in the README's order."""
    s = QUICK if quick else FULL
    rows = bench.bench_normal(s["normal"], "auto", 1)
    rows += bench.bench_fretting(s["fretting"], "auto", 1, steps=s["fretting_steps"])
    n, steps = s["fig3"]
    rows += bench.bench_paper_fig3("auto", 1, steps=steps, n=n, forms=("scalar", "vector"))
    rows += fig3_study(n, steps)
    rows += bench.bench_memory("auto", 1, *s["memory"])
    return rows


def long_rows(records) -> list:
    """One row per (case, pair, form, grid, steps, quantity)."""
    keys = ("case", "pair", "form", "grid", "steps")
    out = []
    for r in records:
        for q, v in r.items():
            if q not in keys:
                out.append(dict({k: r.get(k, "") for k in keys}, quantity=q,
                                value=f"{float(v):.6g}"))
    return out


def write_csv(rows, path, header):
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = io.StringIO()
    text.write("".join(f"# {line}\n" for line in header))
    w = csv.DictWriter(text, fieldnames=FIELDS, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(text.getvalue(), encoding="utf-8")
    os.replace(tmp, path)                          # never a half-written file


def read_csv(path):
    """(header comment lines, rows) of a file written by :func:`write_csv`."""
    lines = pathlib.Path(path).read_text(encoding="utf-8").splitlines()
    header = [ln[2:] for ln in lines if ln.startswith("# ")]
    rows = list(csv.DictReader(ln for ln in lines if not ln.startswith("#")))
    return header, rows


# --------------------------------------------------------------------------- the table
LABELS = {
    ("normal", "steel/steel", "normal"): "Hertz normal solve, tolerance 1e-10, cold",
    ("fretting", "steel/steel β=0", "scalar"):
        "fretting loop per warm step, β = 0 (steel/steel), one-component",
    ("fretting", "steel/steel β=0", "vector"): "same, vector form",
    ("fretting", "steel/Al β≠0", "scalar"):
        "fretting loop per step, β ≠ 0 (steel/aluminium), one-component",
    ("fretting", "steel/Al β≠0", "vector"): "same, vector form",
    ("paper-fig3", "rigid/Maxwell", "scalar"):
        "paper figure 3: rigid sphere on Maxwell (ν = 0.3, coupled), end to end",
    ("paper-fig3", "rigid/Maxwell", "vector"): "same, vector form",
    ("fig3-study", "rigid/Maxwell", "tau=1t'"): "`studies/fig3_maxwell.py`, τ = t′",
    ("fig3-study", "rigid/Maxwell", "tau=2t'"): "`studies/fig3_maxwell.py`, τ = 2t′",
    ("memory", "maxwell", "normal"): "viscoelastic history per step, Maxwell",
    ("memory", "prony", "normal"): "viscoelastic history per step, Prony",
}


def _fmt(v, digits=3):
    v = float(v)
    if v == 0 or not math.isfinite(v):
        return f"{v:g}"
    if abs(v) >= 100:
        return f"{v:,.0f}".replace(",", " ")
    return f"{v:.{digits}g}"


def _run_over_floor(q):
    """A whole run's wall time over its pairs' floor."""
    return _fmt(float(q["run_s"]) * 1e3 / (float(q["run_pairs"]) * float(q["pair_ms"])))


def _cells(case, q):
    """(iterations, FFT pairs, first instant, wall, floor, wall / floor) of one row's
    quantities (``contactpipe bench``'s names)."""
    first = (f"{_fmt(q.get('first_instant_pairs', 0))} + "
             f"{_fmt(q.get('preload_estimate_pairs', 0))}")
    if case == "normal":
        return (_fmt(q["iterations_per_step"]), _fmt(q["pairs_per_step"]), "",
                f"{_fmt(q['ms_per_step'])} ms", f"{_fmt(q['pair_ms'])} ms",
                _fmt(q["wall_over_floor"]))
    if case == "fretting":
        return (_fmt(q["iterations_per_step"]), _fmt(q["pairs_per_step"]), first,
                f"{_fmt(q['ms_per_step'])} ms/step", f"{_fmt(q['pair_ms'])} ms",
                _fmt(q["wall_over_floor"]))
    if case == "paper-fig3":
        return (_fmt(q["iterations_per_step"]),
                f"{_fmt(q['pairs_per_step'])} a step after the first instant; "
                f"{_fmt(q['run_pairs'])} in all", first,
                f"{_fmt(q['run_s'])} s" + (f"; into an archive {_fmt(q['file_run_s'])} s"
                                           if q.get("file_run_s") else ""),
                f"{_fmt(q['pair_ms'])} ms", _run_over_floor(q))
    if case == "fig3-study":
        return ("", f"{_fmt(q['run_pairs'])} in all", "", f"{_fmt(q['run_s'])} s",
                f"{_fmt(q['pair_ms'])} ms", _run_over_floor(q))
    return ("", "", "", f"{_fmt(q['ms_per_step_first'])} / {_fmt(q['ms_per_step_last'])} "
            "ms/step (first / last 10 steps)", "", "")


def render(header, rows) -> str:
    """The README's table: one line per case, pair and form, its grids joined by " / "."""
    groups = {}
    for r in rows:
        key = (r["case"], r["pair"], r["form"])
        groups.setdefault(key, {}).setdefault((int(r["grid"]), r["steps"]), {})[
            r["quantity"]] = r["value"]
    lines = [f"Measured by `python benchmarks/readme_figures.py` "
             f"([`benchmarks/results/readme.csv`](benchmarks/results/readme.csv): "
             f"{'; '.join(header)}). First instant: its FFT pairs + those of the frictional "
             "preload's error estimate. Floor: the time of one FFT pair on that grid; "
             "wall / floor: the wall time over pairs × floor, per step after the first "
             "instant where the wall is per step, of the whole run (every pair counted) "
             "where it is the run's.", "",
             "| case | grid, steps | iterations | FFT pairs | first instant | wall | floor "
             "| wall / floor |",
             "|---|---|---|---|---|---|---|---|"]
    for key, by_grid in groups.items():
        grids = sorted(by_grid)
        cells = [_cells(key[0], by_grid[g]) for g in grids]
        steps = {s for _, s in grids if s}
        where = " / ".join(f"{g}²" for g, _ in grids) + (
            f", {' / '.join(sorted(steps))} steps" if steps else "")
        cols = [" / ".join(c[i] for c in cells) if any(c[i] for c in cells) else "—"
                for i in range(6)]
        label = LABELS.get(key, " ".join(key))
        lines.append(f"| {label} | {where} | " + " | ".join(cols) + " |")
    return "\n".join(lines)


def update_readme(block: str, readme=README) -> None:
    text = pathlib.Path(readme).read_text(encoding="utf-8")
    if text.count(BEGIN) != 1 or text.count(END) != 1:
        raise SystemExit(f"{readme}: expected one {BEGIN} and one {END}")
    head, rest = text.split(BEGIN)
    _, tail = rest.split(END)
    pathlib.Path(readme).write_text(f"{head}{BEGIN}\n{block}\n{END}{tail}", encoding="utf-8")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small grids, few steps (seconds)")
    p.add_argument("--out", type=pathlib.Path, default=None,
                   help=f"CSV to write (default {RESULTS.relative_to(ROOT)}; required with "
                        "--quick)")
    p.add_argument("--update-readme", action="store_true",
                   help="rewrite the README's table from the CSV written")
    p.add_argument("--render", type=pathlib.Path, default=None, metavar="FILE.csv",
                   help="print the README's table of an existing file and stop")
    args = p.parse_args(argv)
    if args.render is not None:
        print(render(*read_csv(args.render)))
        return 0
    if args.quick and (args.out is None or args.update_readme):
        p.error("--quick needs --out and takes no --update-readme: the checked-in file and "
                "the README keep the full figures")
    out = args.out or RESULTS
    load0 = os.getloadavg()
    rows = long_rows(measure(args.quick))
    load1 = os.getloadavg()
    header = [f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
              f"{os.cpu_count()} CPUs, one FFT thread",
              f"load average {load0[0]:.1f} before, {load1[0]:.1f} after"
              + (", --quick" if args.quick else "")]
    write_csv(rows, out, header)
    print(f"wrote {out}")
    if args.update_readme:
        update_readme(render(*read_csv(out)))
        print(f"updated {README}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
