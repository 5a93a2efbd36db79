"""The table-driven reader (contactpipe.scene.tables) and the tables it reads: the scene's parts,
the sweep file, the [dask] table and the pipeline file."""
import copy
import dataclasses
import difflib
import math
import pathlib
import re
import tempfile

import numpy as np
import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from contactpipe._util.files import loads_toml
from contactpipe.exceptions import SceneError
from contactpipe.pipeline.sweep import config
from contactpipe.scene import Scene
from contactpipe.scene import parts as scene_parts
from contactpipe.scene.model import FIELDS as SCENE_FIELDS
from contactpipe.scene.tables import Field, Reader, nesting_depth, show
from contactpipe.scene.wear import Wear
from contactpipe.testing import TINY_SCENES

PARTS = [scene_parts.Geometry, scene_parts.BodySpec, scene_parts.Friction,
         scene_parts.Fretting, scene_parts.Load, scene_parts.Grid, scene_parts.TimeMesh,
         scene_parts.Solver, scene_parts.Output, Wear]


# ----------------------------------------------------------------------------- the reader

MU = Field("mu", "number", "a finite number >= 0", ok=lambda x: x >= 0, default=0.0)
N = Field("n", "integer", "an integer >= 1", ok=lambda n: n >= 1, cap=100, cap_why="why",
          required=True)
RULE = Field("rule", "choice", options=("linear", "step_start"), default="linear")
SIZE = Field("size", "numbers", "two numbers > 0 or 'auto'", ok=lambda x: x > 0, length=2,
             options=("auto",))
FORCE = Field("force", ("number", "numbers"), "a force or a list", ok=lambda x: x >= 0)
TABLE = (MU, N, RULE, SIZE, FORCE)


def read(raw, path="t"):
    problems = []
    r = Reader(raw, path, problems)
    r.check_keys(TABLE)
    return r.read(TABLE), problems


def test_one_loop_reads_defaults_and_values():
    values, problems = read({"n": 3, "size": [1, 2.5], "force": [0, 1]})
    assert problems == []
    assert values == {"mu": 0.0, "n": 3, "rule": "linear", "size": (1.0, 2.5),
                      "force": (0.0, 1.0)}
    assert read({"n": 1, "size": "auto", "force": 2})[0]["size"] == "auto"
    assert read({"n": 1, "force": 2})[0]["force"] == 2.0
    assert read({"n": 1, "mu": None})[0]["mu"] == 0.0          # None is absent


def test_every_problem_is_collected_and_named():
    _, problems = read({"mu": -1, "n": True, "rule": "quadratic", "size": [1],
                        "force": "1 kN", "colour": 1})
    assert problems == [
        "unknown key 't.colour'; allowed keys in [t]: mu, n, rule, size, force",
        "t.mu must be a finite number >= 0, got -1",
        "t.n must be an integer >= 1, got True (a boolean)",
        "t.rule must be one of 'linear', 'step_start', got 'quadratic'",
        "t.size must be two numbers > 0 or 'auto', got [1]",
        "t.force must be a force or a list, got '1 kN' (a string)",
    ]
    assert read({})[1] == ["t.n is required: an integer >= 1"]


def test_unknown_keys_get_did_you_mean():
    _, problems = read({"n": 1, "rul": "linear"})
    assert problems == ["unknown key 't.rul' (did you mean 'rule'?); allowed keys in [t]: "
                        "mu, n, rule, size, force"]
    problems = []
    Reader({"nme": 1}, "", problems, title="the sweep file").check_keys(["name", "mode"])
    assert problems == ["unknown key 'nme' (did you mean 'name'?) at the top level of the "
                        "sweep file; allowed keys: name, mode"]


def test_cap_is_its_own_message():
    _, problems = read({"n": 10**9})
    assert problems == ["t.n = 1000000000 is above the cap of 100: why"]


def test_show_is_one_short_line_for_any_value():
    deep = []
    for _ in range(5000):
        deep = [deep]
    for v in (deep, list(range(10**5)), "x" * 10**6, {"a": deep}, np.zeros((500, 500)),
              10**400):
        s = show(v)
        assert "\n" not in s and len(s) <= 80
    assert show("a", typed=True) == "'a' (a string)"
    assert show(True, typed=True) == "True (a boolean)"
    assert show([0.0, 0.6]) == "[0.0, 0.6]"


def test_nesting_depth_counts_without_recursion():
    deep = 1
    for _ in range(100_000):
        deep = [deep]
    assert nesting_depth(deep, limit=64) == 65
    assert nesting_depth(3) == 0 and nesting_depth([]) == 1 and nesting_depth([[1], 2]) == 2
    assert nesting_depth({"a": {"b": [1]}}) == 3


@pytest.mark.parametrize("part", PARTS, ids=lambda p: p.__name__)
def test_each_part_describes_exactly_its_fields(part):
    """FIELDS (the table's description) and the dataclass agree, in file order."""
    assert [f.name for f in part.FIELDS] == [f.name for f in dataclasses.fields(part)]
    for f in part.FIELDS:
        assert f.wording, f.name
        kinds = f.kind if isinstance(f.kind, tuple) else (f.kind,)
        assert all(k in ("number", "integer", "choice", "bool", "string", "path",
                         "numbers", "integers", "strings", "pairs", "table") for k in kinds)
    assert [f.name for f in SCENE_FIELDS] == ["name", "geometry", "indenter", "halfspace",
                                              "friction", "load", "grid", "time", "solver",
                                              "output", "wear"]


# ----------------------------------------------------------------------------- every table

BASE = loads_toml(TINY_SCENES["fretting"])
PRESET = copy.deepcopy(BASE)
del PRESET["load"]["time"], PRESET["load"]["tangential_force"]
PRESET["load"]["fretting"] = {"amplitude": 90.0, "window": 1.0}

#: (dotted path of a table, its fields, the base scene holding it)
SCENE_TABLES = [("", SCENE_FIELDS, BASE)] + [
    (path, part.FIELDS, PRESET if path.startswith("load") else BASE)
    for path, part in [("geometry", scene_parts.Geometry), ("indenter", scene_parts.BodySpec),
                       ("halfspace", scene_parts.BodySpec), ("friction", scene_parts.Friction),
                       ("load", scene_parts.Load), ("load.fretting", scene_parts.Fretting),
                       ("grid", scene_parts.Grid), ("time", scene_parts.TimeMesh),
                       ("solver", scene_parts.Solver), ("output", scene_parts.Output)]]

CREEP_TOML = TINY_SCENES["creep"]


def _node(d, path):
    for k in path.split(".") if path else ():
        d = d.setdefault(k, {})
    return d


def _scene_problems(d):
    try:
        Scene.from_dict(d)
    except SceneError as err:
        return err.problems
    return []


def _file_problems(kind, d):
    """Problems of a sweep file or a pipeline file holding ``d`` (next to a valid scene
    and sweep file)."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        (tmp / "scene.toml").write_text(CREEP_TOML)
        (tmp / "sweep.toml").write_text('base = "scene.toml"\n[axes]\n"friction.mu" = [0.1]\n')
        f = tmp / f"{kind}.toml"
        f.write_text(tomli_w.dumps(d))
        try:
            (config.read_sweep_file if kind == "sweep" else config.read_pipeline_file)(f)
        except SceneError as err:
            return [p.split(": ", 1)[1] for p in err.problems]
    return []


SWEEP = {"base": "scene.toml", "mode": "zip", "axes": {"friction.mu": [0.1, 0.2]},
         "dask": {"scheduler": "synchronous", "n_workers": 2}}
PIPELINE = {"name": "p", "out": "runs", "sweep": {"file": "sweep.toml"},
            "compare": {"reference": "none"}, "plot": {"figures": ["profiles"]},
            "dask": {"n_workers": 2}, "stress": {"depths": [0.0, 1e-4]}}
#: (file kind, dotted path of a table, its fields, the file's dict)
FILE_TABLES = [("sweep", "", config.SWEEP_FIELDS, SWEEP),
               ("sweep", "dask", config.DASK_FIELDS, SWEEP),
               ("pipeline", "", config.PIPELINE_FIELDS, PIPELINE),
               ("pipeline", "compare", config.COMPARE_FIELDS, PIPELINE),
               ("pipeline", "plot", config.PLOT_FIELDS, PIPELINE),
               ("pipeline", "dask", config.DASK_FIELDS, PIPELINE),
               ("pipeline", "stress", config.STRESS_FIELDS, PIPELINE)]


def test_the_bases_are_valid():
    assert _scene_problems(BASE) == [] and _scene_problems(PRESET) == []
    assert _file_problems("sweep", SWEEP) == [] and _file_problems("pipeline", PIPELINE) == []


key_names = st.text(st.sampled_from("abcdefghijklmnopqrstuvwxyz_"), min_size=1, max_size=14)


def _typo(draw, allowed):
    """An allowed key of 4+ letters with one letter changed, or a random key."""
    long = [k for k in allowed if len(k) >= 4]
    if long and draw(st.booleans()):
        k = draw(st.sampled_from(long))
        i = draw(st.integers(0, len(k) - 1))
        return k[:i] + draw(st.sampled_from("xqz")) + k[i + 1:], True
    return draw(key_names), False


def _assert_unknown(problems, path, key, allowed, typo):
    dotted = f"{path}.{key}" if path else key
    hits = [p for p in problems if p.startswith(f"unknown key {dotted!r}")]
    assert len(hits) == 1, (dotted, problems)
    assert hits[0].endswith(", ".join(allowed)), hits[0]
    if typo or difflib.get_close_matches(key, allowed, n=1):
        assert "(did you mean '" in hits[0], hits[0]


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_unknown_keys_in_scene_tables(data):
    path, fields, base = data.draw(st.sampled_from(SCENE_TABLES))
    allowed = [f.name for f in fields]
    key, typo = _typo(data.draw, allowed)
    if key in allowed:
        return
    d = copy.deepcopy(base)
    _node(d, path)[key] = 1.0
    _assert_unknown(_scene_problems(d), path, key, allowed, typo)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_unknown_keys_in_sweep_and_pipeline_files(data):
    kind, path, fields, base = data.draw(st.sampled_from(FILE_TABLES))
    allowed = [f.name for f in fields]
    key, typo = _typo(data.draw, allowed)
    if key in allowed:
        return
    d = copy.deepcopy(base)
    _node(d, path)[key] = 1
    _assert_unknown(_file_problems(kind, d), path, key, allowed, typo)


#: Values of every type; a field is given those its own kind refuses.
JUNK = st.one_of(st.text(max_size=5), st.booleans(), st.integers(-10**6, 10**6),
                 st.floats(allow_nan=False), st.just(float("nan")),
                 st.lists(st.one_of(st.integers(), st.text(max_size=2)), max_size=3),
                 st.lists(st.lists(st.floats(allow_nan=False), max_size=3), max_size=2),
                 st.dictionaries(st.text(max_size=3), st.integers(), max_size=2))


def _names(problems, dotted) -> bool:
    """Some problem names the dotted field (as a whole name, not a part of another)."""
    pat = re.compile(rf"(^|[ '\[]){re.escape(dotted)}($|[ .'\]=:])")
    return any(pat.search(p) for p in problems)


def _refused(f, value) -> bool:
    """The field alone refuses the value (its kind, range or cap)."""
    problems = []
    Reader({f.name: value}, "t", problems).value(f)
    return bool(problems)


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.filter_too_much])
@given(st.data())
def test_wrong_types_in_scene_tables_name_the_field(data):
    path, fields, base = data.draw(st.sampled_from(SCENE_TABLES))
    f = data.draw(st.sampled_from([f for f in fields if f.part is None or path == ""]))
    value = data.draw(JUNK.filter(lambda v: _refused(f, v)))
    d = copy.deepcopy(base)
    _node(d, path)[f.name] = value
    dotted = f"{path}.{f.name}" if path else f.name
    problems = _scene_problems(d)
    assert _names(problems, dotted), (dotted, value, problems)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                 HealthCheck.filter_too_much])
@given(st.data())
def test_wrong_types_in_sweep_and_pipeline_files_name_the_field(data):
    kind, path, fields, base = data.draw(st.sampled_from(FILE_TABLES))
    f = data.draw(st.sampled_from(fields))
    value = data.draw(JUNK.filter(lambda v: _refused(f, v) and not (
        isinstance(v, float) and math.isnan(v))))       # TOML writes no NaN in a list
    d = copy.deepcopy(base)
    _node(d, path)[f.name] = value
    dotted = f"{path}.{f.name}" if path else f.name
    problems = _file_problems(kind, d)
    assert _names(problems, dotted), (dotted, value, problems)
