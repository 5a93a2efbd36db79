"""The documentation stands on its own and says what the code does.

* No file of the package, the docs, the README, the tests, the studies, the benchmarks or
  the examples cites a section of a document that is not in the repository (the project's
  contract and design notes): they say it in their own words.
* ``contactpipe sweep --help`` and ``contactpipe compare --help`` are short (the module
  docstrings are developer documentation) and show examples.
* docs/time-integration.md, section 3: on a fixed grid a sphere's pressure field converges
  at second order where the contact grows slowly (Maxwell), and not at all in the maximum
  norm at its front where it grows fast (Kelvin-Voigt), while the interior converges.
* docs/scene-file.md, docs/stress.md: the stress stage refuses a body whose Poisson ratio
  varies in time (bulk = "elastic").
"""
import math
import pathlib
import re

import numpy as np
import pytest

import contactpipe as cp
from contactpipe.pipeline import cli
from contactpipe.testing import creep_laws

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCANNED = ["contactpipe", "docs", "tests", "studies", "benchmarks", "examples", "README.md"]
SUFFIXES = {".py", ".md", ".toml", ".txt", ".rst", ".cfg"}
# Spelled in pieces so that this file does not match itself.
CITATION = re.compile("CONTR" + r"ACT\b|" + "DES" + r"IGN *§|the " + "contr" + "act's")


def _scanned_files():
    for name in SCANNED:
        path = ROOT / name
        if path.is_file():
            yield path
        elif path.is_dir():
            yield from (p for p in sorted(path.rglob("*"))
                        if p.is_file() and p.suffix in SUFFIXES and "__pycache__" not in p.parts)


def test_no_citation_of_documents_outside_the_repository():
    hits = [f"{p.relative_to(ROOT)}:{i}: {line.strip()}"
            for p in _scanned_files()
            for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
            if CITATION.search(line)]
    assert not hits, ("these lines cite the contract or the design notes, which are not in "
                      "the repository; say it in the docs' own words:\n" + "\n".join(hits))


@pytest.mark.parametrize("command", ["sweep", "compare"])
def test_stage_help_is_short_with_examples(command, capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main([command, "--help"])
    assert exit_info.value.code == 0
    text = capsys.readouterr().out
    lines = text.splitlines()
    assert len(lines) < 40, f"`contactpipe {command} --help` has {len(lines)} lines (< 40)"
    assert "Example" in text
    examples = [ln for ln in lines if ln.strip().startswith(f"contactpipe {command} ")]
    assert len(examples) >= 2, f"`contactpipe {command} --help` shows {len(examples)} examples"
    assert ":func:" not in text and "``" not in text    # not the developer docstring


# --------------------------------------------------------------------------- the front
E, NU, R, W = 105e9, 0.3, 0.018, 1000.0
LAWS = creep_laws(E)


def _sphere_differences(law, rule, n=32, steps=(20, 40, 80, 160)):
    """Successive differences of a rigid sphere's pressure field on ``law`` (W stepped,
    window 2 tau, n^2 auto) at the common instants, largest over the grid and over
    inside 0.8 a(t), over p_max, for t >= 0.25 tau (Kelvin-Voigt: 0.5 tau)."""
    runs = []
    for s in steps:
        scene = cp.Scene(name=f"front-{law}", geometry={"shape": "sphere", "radius": R},
                         indenter={"material": "rigid"},
                         halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                                    **LAWS[law][0]},
                         load={"time": [0.0, 2.0], "normal_force": W},
                         grid={"points": [n, n], "size": "auto"}, time={"steps": s},
                         solver={"time_rule": rule, "tolerance": 1e-10})
        ds = cp.simulate(scene)
        runs.append(ds.p.values)
    p = [run[:: 2 ** i] for i, run in enumerate(runs)]
    t = np.linspace(0.0, 2.0, steps[0] + 1)
    late = t >= (0.5 if law == "kelvin_voigt" else 0.25)
    x1, x2 = ds.x1.values, ds.x2.values
    r = np.hypot(*np.meshgrid(x1, x2, indexing="ij"))
    a = np.sqrt((p[-1][late] > 0).sum(axis=(1, 2)) / math.pi) * (x1[1] - x1[0])
    inside = r[None] < 0.8 * a[:, None, None]
    p_max = p[-1][late].max()
    diffs = [np.abs(p[i][late] - p[i + 1][late]) for i in range(len(p) - 1)]
    return ([float(d.max() / p_max) for d in diffs],
            [float((d * inside).max() / p_max) for d in diffs])


def test_sphere_field_converges_where_the_contact_grows_slowly():
    """Maxwell, "linear" (= auto), 32^2: second order over the whole field, front included
    (measured 2.0e-3 / 3.9e-4 / 9.4e-5 of p_max: orders 2.3, 2.1)."""
    whole, _ = _sphere_differences("maxwell", "linear")
    orders = [math.log2(whole[i] / whole[i + 1]) for i in range(len(whole) - 1)]
    assert min(orders) >= 1.8, f"Maxwell sphere field: orders {orders} (docs: second order)"


def test_sphere_front_does_not_converge_for_kelvin_voigt():
    """Kelvin-Voigt, "bdf2" (= auto), 32^2: the largest difference, at the front, stays
    above 0.3 p_max from 20 to 160 steps (measured 0.64 / 0.62 / 0.44), while inside 0.8 a
    the field converges (measured 0.12 / 9.7e-3 / 8.2e-3 of p_max)."""
    whole, inside = _sphere_differences("kelvin_voigt", "bdf2")
    assert min(whole) > 0.3, f"Kelvin-Voigt front: {whole} of p_max (docs: no convergence)"
    assert inside[-1] < 0.02 and inside[-1] < inside[0] / 5, (
        f"Kelvin-Voigt inside 0.8 a: {inside} of p_max (docs: converges)")


# --------------------------------------------------------------------------- bulk = elastic
def test_stress_stage_refuses_a_varying_poisson_ratio(tmp_path, capsys):
    """docs/scene-file.md and docs/stress.md: the stress stage refuses a body with
    bulk = "elastic" (exit status 2 from `contactpipe stress`, nothing written), and
    cp.subsurface_stress evaluates one fixed ratio only when given poisson=."""
    scene = cp.Scene(name="bulk", geometry={"shape": "sphere", "radius": R},
                     indenter={"material": "rigid"},
                     halfspace={"material": "viscoelastic", "young": E, "poisson": NU,
                                "creep": "maxwell", "relaxation_time": 1.0,
                                "bulk": "elastic"},
                     load={"time": [0.0, 1.0], "normal_force": W},
                     grid={"points": [16, 16], "size": "auto"}, time={"steps": 2})
    archive = tmp_path / "bulk.nc"
    cp.simulate(scene, archive).close()
    out = tmp_path / "stress.nc"
    status = cli.main(["stress", str(archive), "-o", str(out), "--x3", "0,1e-4"])
    err = capsys.readouterr().err
    assert status == 2 and "bulk = 'elastic'" in err and not out.exists(), (status, err)
    with cp.open_archive(archive) as ds:
        with pytest.raises(ValueError, match="bulk = 'elastic'"):
            cp.subsurface_stress(ds, [1e-4])
        st = cp.subsurface_stress(ds, [1e-4], poisson=0.45)
        assert st.attrs["poisson"] == 0.45


# --------------------------------------------------------------------------- README figures
def _readme_figures():
    import importlib.util
    path = ROOT / "benchmarks" / "readme_figures.py"
    spec = importlib.util.spec_from_file_location("readme_figures", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _readme_block(module):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert text.count(module.BEGIN) == 1 and text.count(module.END) == 1
    return text.split(module.BEGIN)[1].split(module.END)[0].strip()


def test_readme_speed_table_comes_from_the_results_file():
    """The README's speed table is the rendering of benchmarks/results/readme.csv, or, in
    a tree where that file was not written yet, says so (it never shows other figures)."""
    rf = _readme_figures()
    block = _readme_block(rf)
    if rf.RESULTS.exists():
        assert block == rf.render(*rf.read_csv(rf.RESULTS)), (
            "README speed table differs from benchmarks/results/readme.csv: run "
            "python benchmarks/readme_figures.py --render benchmarks/results/readme.csv")
    else:
        assert "|" not in block and "--update-readme" in block, block


def test_readme_figures_quick_run(tmp_path, capsys):
    """The script runs every case on 16² and writes a file it can render: every quantity
    finite, every pair count a positive whole number, every case and form present."""
    rf = _readme_figures()
    out = tmp_path / "readme.csv"
    assert rf.main(["--quick", "--out", str(out)]) == 0
    header, rows = rf.read_csv(out)
    assert any("--quick" in line for line in header)
    values = {(r["case"], r["form"], r["quantity"]): float(r["value"]) for r in rows}
    assert all(math.isfinite(v) for v in values.values())
    pairs = [v for (_, _, q), v in values.items() if q.endswith("_pairs")]   # counts
    assert pairs and all(v == int(v) and v >= 0 for v in pairs)
    assert values[("fretting", "scalar", "preload_estimate_pairs")] > 0   # steel/Al row
    assert {(c, f) for c, f, _ in values} >= {
        ("normal", "normal"), ("fretting", "scalar"), ("fretting", "vector"),
        ("paper-fig3", "scalar"), ("paper-fig3", "vector"), ("fig3-study", "tau=1t'"),
        ("fig3-study", "tau=2t'"), ("memory", "normal")}
    table = rf.render(header, rows)
    assert table.count("\n| ") == 12 and "fig3_maxwell.py" in table     # header + 11 rows
    with pytest.raises(SystemExit):                   # a quick run never touches the README
        rf.main(["--quick", "--update-readme", "--out", str(out)])


# --------------------------------------------------------------------------- decision record
RECORD = ROOT / "docs" / "design-choices.md"
RESULTS = ROOT / "benchmarks" / "results"
RESULT_COLUMNS = ["decision", "case", "grid", "steps", "tolerance", "quantity", "baseline",
                  "value", "value_high", "unit", "status", "note", "measured_on"]
FIELDS = ("Decision", "Why", "Measured", "Rejected")
ENTRY = re.compile(r"^### (D\d+)\. \S")


def _record_entries():
    """{number: [the entry's lines after its heading]} of the decision record."""
    entries, current = {}, None
    for line in RECORD.read_text(encoding="utf-8").splitlines():
        if line.startswith("#"):
            match = ENTRY.match(line)
            current = match.group(1) if match else None
            if current is not None:
                assert current not in entries, f"{current} appears twice in {RECORD.name}"
                entries[current] = []
        elif current is not None and line.strip():
            entries[current].append(line)
    return entries


def test_decision_record_is_short_with_four_fields_per_entry():
    """docs/design-choices.md is at most 250 lines, and each entry ("### Dn. title") is
    exactly four one-line fields: Decision, Why, Measured, Rejected."""
    n_lines = len(RECORD.read_text(encoding="utf-8").splitlines())
    assert n_lines <= 250, f"{RECORD.name} has {n_lines} lines (at most 250)"
    entries = _record_entries()
    assert len(entries) >= 20, sorted(entries)
    bad = {number: lines for number, lines in entries.items()
           if [ln.split(":", 1)[0] for ln in lines] != [f"- {f}" for f in FIELDS]
           or any(len(ln.split(":", 1)[1].strip()) < 2 for ln in lines)}
    assert not bad, f"entries without exactly the fields {FIELDS}, one line each: {bad}"


def _csv(path):
    import csv
    with path.open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        return reader.fieldnames, list(reader)


def test_decision_record_figures_are_in_the_results_files():
    """Every CSV the record cites ("file.csv (D7)", or "(D1, D13)" for another entry's rows)
    is a file under benchmarks/results/ that parses with the record's columns (numbers where
    numbers belong, status kept or rejected) and holds rows of the entries named; an entry's
    Measured field cites rows of its own, or says with a dash that it has no figure."""
    cited = set()
    for number, lines in _record_entries().items():
        text, measured = " ".join(lines), lines[2]
        refs = re.findall(r"((?:[a-z_]+\.csv(?:, )?)+) \(([^)]*)\)", text)
        names = set(re.findall(r"([a-z_]+\.csv)", text))
        assert names == {n for files, _ in refs for n in re.findall(r"[a-z_]+\.csv", files)}, (
            f"{number}: a CSV cited without the entries whose rows it means")
        assert names or measured.startswith("- Measured: —"), (number, measured)
        own = False
        for files, decisions in refs:
            wanted = set(re.findall(r"D\d+", decisions)) or {number}
            for name in re.findall(r"[a-z_]+\.csv", files):
                path = RESULTS / name
                assert path.is_file(), f"{number} cites {name}, not in benchmarks/results/"
                header, rows = _csv(path)
                assert header == RESULT_COLUMNS, (name, header)
                assert any(r["decision"] in wanted for r in rows), (number, name, wanted)
                own |= any(r["decision"] == number for r in rows) and f"results/{name}" in measured
                cited.add(name)
        assert own or not names, f"{number}: Measured cites no benchmarks/results/ rows of its own"
    assert cited, f"{RECORD.name} cites no results file"
    for name in cited:
        _, rows = _csv(RESULTS / name)
        for r in rows:
            assert r["status"] in ("kept", "rejected"), (name, r)
            assert math.isfinite(float(r["value"])), (name, r)
            for key in ("baseline", "value_high", "tolerance"):
                assert r[key] == "" or math.isfinite(float(r[key])), (name, key, r)
            assert re.fullmatch(r"\d{4}-\d\d-\d\d [0-9a-f]{7}", r["measured_on"]), (name, r)


# Where a document names a module or a test by its short path.
_SHORT = {"solver/": "contactpipe/", "pipeline/": "contactpipe/", "archive/": "contactpipe/",
          "materials/": "contactpipe/", "analytic/": "contactpipe/", "test_": "tests/"}
# Written by a command the document names, and absent until it is run (the README says so
# where it is absent: test_readme_speed_table_comes_from_the_results_file).
_OUTPUTS = {"benchmarks/results/readme.csv"}
_PATH = re.compile(r"(?<![\w./-])((?:\.\./)*[a-z0-9_][a-z0-9_./-]*\.(?:md|py|csv|toml|txt))\b")


def test_documents_cite_only_files_in_the_repository():
    """README.md, docs/*.md and studies/README.md cite no file that is not in the
    repository: every path they give (in code spans and links) exists, none reaches
    outside the repository (../), and every link's target exists."""
    documents = [ROOT / "README.md", ROOT / "studies" / "README.md",
                 *sorted((ROOT / "docs").glob("*.md"))]
    missing = []
    for doc in documents:
        text = doc.read_text(encoding="utf-8")
        spans = re.findall(r"`([^`\n]+)`", text) + re.findall(r"\]\(([^)\s#]+)\)", text)
        for span in spans:
            for path in _PATH.findall(span):
                if path.startswith("../") or path.startswith("/"):
                    missing.append(f"{doc.relative_to(ROOT)}: {path} (outside the repository)")
                    continue
                if "/" not in path and not path.startswith("test_"):
                    continue                                  # a bare file name in prose
                full = next((p + path for s, p in _SHORT.items() if path.startswith(s)), path)
                if not (ROOT / full).exists() and full not in _OUTPUTS:
                    missing.append(f"{doc.relative_to(ROOT)}: {path}")
        for target in re.findall(r"\[[^\]\n]*\]\(([^)\s#]+)\)", text):
            if "://" in target or not re.search(r"[./]", target):
                continue                                      # a web address, or math: L[f](s)
            if not (doc.parent / target).exists():
                if (doc.parent / target).resolve().relative_to(ROOT).as_posix() not in _OUTPUTS:
                    missing.append(f"{doc.relative_to(ROOT)}: link to {target}")
    assert not missing, "documents cite files not in the repository:\n" + "\n".join(missing)


def test_readme_phase_table_is_the_results_file_rounded():
    """The README's table of where a step goes ("Where the rest of a step goes") shows
    benchmarks/results/bench-phases.csv: each figure is the file's, rounded as printed
    (half a unit of its last digit), and the date and commit it names are the file's."""
    _, rows = _csv(RESULTS / "bench-phases.csv")
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("Where the rest of a step goes")[1].split("\n\n* ")[0]
    assert f"on {rows[0]['date'][:10]} at commit {rows[0]['commit']}" in section
    lines = [ln for ln in section.splitlines() if ln.startswith("| ") and "---" not in ln]
    columns = ("floor_ms_per_step", "transforms_ms_per_step", "filters_ms_per_step",
               "products_ms_per_step", "inners_ms_per_step", "rest_ms_per_step",
               "ms_per_step", "wall_over_floor", "spectral_over_floor")
    assert len(lines) == 1 + len(rows)                        # a header and a row each
    for line, row in zip(lines[1:], rows, strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        assert cells[1] == f"{row['grid']}²", (cells, row)
        for shown, column in zip(cells[2:], columns, strict=True):
            decimals = len(shown.split(".")[1]) if "." in shown else 0
            assert abs(float(shown) - float(row[column])) <= 0.5 * 10.0 ** -decimals + 1e-12, (
                column, shown, row[column])
