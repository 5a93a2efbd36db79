"""The package's layers (pyproject's import-linter contracts) hold: no import cycle, and
imports flow from the pipeline stages down to the numerical core only."""
import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_import_layers_are_kept():
    pytest.importorskip("importlinter")
    r = subprocess.run([sys.executable, "-c", "from importlinter.cli import lint_imports_command; "
                        "lint_imports_command()"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]


MAX_MODULE_LINES = 900
MAX_FUNCTION_LINES = 120


def _sources():
    return sorted((ROOT / "contactpipe").rglob("*.py"))


def test_modules_stay_small():
    """One purpose per module: none over 900 lines."""
    long = {str(p.relative_to(ROOT)): p.read_text().count("\n") for p in _sources()}
    over = {k: n for k, n in long.items() if n > MAX_MODULE_LINES}
    assert not over, f"modules over {MAX_MODULE_LINES} lines: {over}"


def test_functions_stay_short():
    """No function or method over 120 lines."""

    over = {}
    for p in _sources():
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    over[f"{p.relative_to(ROOT)}:{node.name}"] = n
    assert not over, f"functions over {MAX_FUNCTION_LINES} lines: {over}"


def _solver_names(tree):
    """Local names a test module binds to modules of contactpipe.solver."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "contactpipe.solver":
            names |= {a.asname or a.name for a in node.names}
        elif isinstance(node, ast.Import):
            names |= {a.asname or a.name for a in node.names
                      if a.name.startswith("contactpipe.solver.")}
    return names


def test_no_test_patches_a_solver_constant():
    """The solver core's switches and constants are data (solver/options.py: Tuning),
    passed down explicitly: no test sets a module constant of contactpipe.solver, by
    ``monkeypatch.setattr(module, "NAME", ...)`` or by assignment."""
    found = []
    for p in sorted((ROOT / "tests").glob("*.py")):
        tree = ast.parse(p.read_text())
        solver = _solver_names(tree)
        for node in ast.walk(tree):
            targets = []
            if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "setattr" \
                    and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant):
                targets.append((node.args[0], str(node.args[1].value)))
            elif isinstance(node, ast.Assign):
                targets += [(t.value, t.attr) for t in node.targets
                            if isinstance(t, ast.Attribute)]
            for obj, attr in targets:
                if isinstance(obj, ast.Name) and obj.id in solver and attr.isupper():
                    found.append(f"{p.name}:{node.lineno} {obj.id}.{attr}")
    assert not found, f"solver constants patched: {found}"


MAX_CG_PARAMETERS = 8
MAX_SOLVER_FUNCTION_LINES = 80


def test_cg_interfaces_stay_narrow():
    """The bound-constrained CGs take the operator, the bounds, the start and a small set
    of options (box_cg: apply, b, lo, hi, target, start, options, ledger; disk_cg: A, b,
    start, rho, con, options, ledger, pressure): at most 8 parameters each (they took 17
    and 15)."""
    import inspect

    from contactpipe.solver.cg import box_cg
    from contactpipe.solver.disk_cg import disk_cg
    counts = {f.__name__: len(inspect.signature(f).parameters) for f in (box_cg, disk_cg)}
    assert max(counts.values()) <= MAX_CG_PARAMETERS, counts



def test_solver_functions_stay_short():
    """No function or method of contactpipe/solver/ over 80 lines (the core is read more
    than it is written)."""
    over = {}
    for p in sorted((ROOT / "contactpipe" / "solver").glob("*.py")):
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_SOLVER_FUNCTION_LINES:
                    over[f"{p.name}:{node.name}"] = n
    assert not over, f"solver functions over {MAX_SOLVER_FUNCTION_LINES} lines: {over}"
