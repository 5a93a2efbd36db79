"""The pipeline's configuration files: the sweep file and the pipeline file.

Both are read by the table-driven reader of :mod:`contactpipe.scene.tables`, as the scene is:
each table is described by data (:data:`SWEEP_FIELDS`, :data:`DASK_FIELDS`,
:data:`PIPELINE_FIELDS`, ...), unknown keys get a "did you mean", and every problem of a
file is reported at once in one :class:`~contactpipe.SceneError`, each naming the file,
the dotted field, the value given and what is allowed. The formats are documented in
``docs/scene-file.md``.

Sweep file (docs/scene-file.md, with the ``[dask]`` table)::

    base = "scene.toml"        # relative to this file; or an inline [scene] table
    mode = "product"           # product | zip
    [axes]
    "friction.mu" = [0.05, 0.1]
    tau_ratio = [0.5, 1.0, 2.0]
    [dask]                     # optional
    scheduler = "tcp://10.0.0.5:8786"   # or "synchronous"; absent or "": a LocalCluster
    n_workers = 4
    threads_per_worker = 1
    retries = 0

Pipeline file::

    name = "paper-fig3"
    out = "runs/paper-fig3"        # relative to this file (or inside [sweep])
    [sweep]
    file = "sweep.toml"            # or inline: base, [sweep.scene], mode, [sweep.axes]
    [compare]
    reference = "closed_form"      # or "none", or an archive path
    [plot]
    figures = ["profiles", "hysteresis", "radii", "sweep"]
    variables = ["contact_area"]
    [stress]                       # optional: a subsurface-stress product per member
    depths = [0.0, 1e-4, 2e-4]     # m; or {max = 1e-3, count = 11} (from min = 0)
    body = "halfspace"             # or "indenter"
    time = "all"                   # "last" (default), "all" or a list of times [s]
    criterion = "crossland"        # none | amplitude | crossland | dang_van | swt
    torsion_limit = 400e6          # the criterion's constants [Pa]
    bending_limit = 600e6
    cycle = [0.2, 1.0]             # s: the instants the criterion runs over (default all);
                                   # or cycle_norm = [0.2, 1.0], in t_norm of each member
    [dask]                         # overrides the sweep file's [dask]
    scheduler = ""
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import pathlib
from collections.abc import Mapping

import numpy as np

from ..._util.files import read_toml
from ...exceptions import SceneError
from ...nomenclature import CYCLE_SERIES, HISTORY, SERIES, VARIABLES
from ...post.fatigue import CRITERIA
from ...post.stress import BODIES, MAX_DEPTH_SIDES
from ...scene import Scene
from ...scene.parts import MAX_SIDE
from ...scene.tables import Field, Reader, did_you_mean, nesting_depth, show
from .members import MODES

__all__ = ["SweepFile", "PipelineSpec", "StressSpec", "read_sweep_file", "load_sweep_file",
           "read_sweep_table", "read_dask_table", "read_stress_table", "read_pipeline_file",
           "flatten_axes", "MODES", "CLOSED_FORM", "MEMBER_FIGURES", "FIGURES",
           "DEFAULT_FIGURES", "SWEEP_FIELDS", "DASK_FIELDS", "PIPELINE_FIELDS",
           "COMPARE_FIELDS", "PLOT_FIELDS", "STRESS_FIELDS", "DEPTH_FIELDS",
           "CONSTANT_FIELDS", "STRESS_CRITERIA", "MAX_AXIS_DEPTH", "MAX_DEPTHS"]

CLOSED_FORM = "closed_form"
MEMBER_FIGURES = ("profiles", "hysteresis", "radii", "maps", "wear", "rough")
FIGURES = MEMBER_FIGURES + ("sweep",)
DEFAULT_FIGURES = ("profiles", "hysteresis", "radii", "sweep")
#: How deep an axis value may nest (a list of [T1, T2] pairs is 2 deep).
MAX_AXIS_DEPTH = 8
#: Caps on the cluster's sizes, against absurd values.
MAX_WORKERS = 1024
MAX_RETRIES = 100
#: Cap on the depths of a stress product.
MAX_DEPTHS = 10_000
#: The deepest depth any member can take [m]: 1000 sides of the largest grid a scene
#: allows (each member refuses more than 1000 of its own sides).
DEEPEST = MAX_DEPTH_SIDES * MAX_SIDE

_INT_1 = "an integer >= 1"

DASK_FIELDS = (
    Field("scheduler", "string", "a scheduler address such as 'tcp://host:8786', "
                                 "'synchronous' or '' (a LocalCluster)"),
    Field("n_workers", "integer", _INT_1, ok=lambda n: n >= 1, cap=MAX_WORKERS,
          cap_why="LocalCluster worker processes"),
    Field("threads_per_worker", "integer", _INT_1, ok=lambda n: n >= 1, cap=MAX_WORKERS,
          cap_why="threads of each worker"),
    Field("retries", "integer", "an integer >= 0", ok=lambda n: n >= 0, cap=MAX_RETRIES,
          cap_why="extra attempts of a failing member"),
)

SWEEP_FIELDS = (
    Field("base", "string", "the path of a scene file (relative to this file)", ok=bool),
    Field("scene", "table", "the scene's tables"),
    Field("mode", "choice", "one of " + ", ".join(MODES), options=MODES, default="product"),
    Field("axes", "table", "axis = [values]"),
    Field("dask", "table", ", ".join(f.name for f in DASK_FIELDS)),
    Field("name", "string", "a non-empty string", ok=bool),
)
#: Keys of an inline sweep inside a pipeline file's [sweep] table (besides file, out).
INLINE_SWEEP = ("base", "scene", "mode", "axes")

PIPELINE_FIELDS = (
    Field("name", "string", "a non-empty string", ok=bool),
    Field("out", "string", "a folder path", ok=bool),
    Field("sweep", "table", "file = \"sweep.toml\", or base and [sweep.axes]"),
    Field("compare", "table", "reference"),
    Field("plot", "table", "figures, variables"),
    Field("stress", "table", "depths, body, time, criterion and its constants"),
    Field("dask", "table", ", ".join(f.name for f in DASK_FIELDS)),
)
COMPARE_FIELDS = (
    Field("reference", "string", "\"closed_form\", \"none\" or an archive path", ok=bool,
          default=CLOSED_FORM),
)
PLOT_FIELDS = (
    Field("figures", "strings", "a list of names from " + ", ".join(FIGURES),
          default=DEFAULT_FIGURES),
    Field("variables", ("string", "strings"), "a list of series names", ok=bool,
          min_length=1, default=("contact_area",)),
)


STRESS_CRITERIA = ("none",) + tuple(CRITERIA)
_PA = "a finite number > 0 [Pa]"
#: Fatigue limits allowed [Pa]: every material's lies well inside; far outside, the
#: criteria's indices overflow (1e308) or divide by nearly nothing (1e-300).
LIMIT_RANGE = (1e3, 1e12)
_LIMIT = f"a number from {LIMIT_RANGE[0]:g} to {LIMIT_RANGE[1]:g} [Pa]"
#: The criteria's constants (:func:`contactpipe.fatigue`); which apply to which criterion
#: is read from :data:`contactpipe.post.fatigue.CRITERIA`.
CONSTANT_FIELDS = (
    Field("torsion_limit", "number", _LIMIT + ", the fully reversed torsion fatigue limit",
          ok=lambda x: LIMIT_RANGE[0] <= x <= LIMIT_RANGE[1], unit="Pa"),
    Field("bending_limit", "number", _LIMIT + ", the fully reversed bending fatigue limit",
          ok=lambda x: LIMIT_RANGE[0] <= x <= LIMIT_RANGE[1], unit="Pa"),
    Field("young", "number", _PA + ", Young's modulus", ok=lambda x: x > 0, unit="Pa"),
    Field("poisson", "number", "a number in [0, 0.5]", ok=lambda x: 0 <= x <= 0.5, unit="1"),
    Field("plane_step", "number", "an angle in [1, 90] [deg] (the smallest, 1, already "
          "makes about 20 600 planes; finer grids do not fit in memory)",
          ok=lambda x: 1 <= x <= 90, unit="deg"),
    Field("shear_amplitude", "choice", options=("mcb", "longest_chord")),
    Field("tolerance", "number", "a number in (0, 0.01]", ok=lambda x: 0 < x <= 0.01,
          unit="1"),
)
STRESS_FIELDS = (
    Field("depths", ("numbers", "table"), f"a list of depths from 0 to {DEEPEST:g} [m], or "
          "a table {max = [m], count = [1], min = [m] (default 0)}",
          ok=lambda z: 0 <= z <= DEEPEST,
          min_length=1, unit="m",
          check=lambda v, key: (f"{key} holds {len(v)} depths: above the cap of "
                                f"{MAX_DEPTHS}" if len(v) > MAX_DEPTHS else None)),
    Field("body", "choice", options=BODIES, default="halfspace"),
    Field("time", "numbers", "'last', 'all' or a list of times [s] of the archive",
          options=("last", "all"), min_length=1, default="last", unit="s"),
    Field("criterion", "string", "one of " + ", ".join(map(repr, STRESS_CRITERIA)),
          default="none",
          check=lambda v, key: None if v in STRESS_CRITERIA else (
              f"{key} = {v!r} is not a criterion{did_you_mean(v, STRESS_CRITERIA)}; "
              f"allowed: {', '.join(STRESS_CRITERIA)}")),
    Field("cycle", "numbers", "[t_start, t_end] [s], t_start < t_end: the instants the "
          "criterion runs over", length=2, unit="s",
          check=lambda v, key: None if v[0] < v[1] else f"{key} = {list(v)}: t_start must "
                                                        "be < t_end"),
    Field("cycle_norm", "numbers", "[a, b], 0 <= a < b <= 1: the instants with a <= t_norm "
          "<= b, t_norm = (t - t_first)/(t_last - t_first) over the member's archive",
          ok=lambda x: 0 <= x <= 1, length=2, unit="1",
          check=lambda v, key: None if v[0] < v[1] else f"{key} = {list(v)}: a must be < b"),
    Field("precision", "choice", options=("float64", "float32"), default="float64"),
    Field("figure", "bool", default=True),
) + CONSTANT_FIELDS
DEPTH_FIELDS = (
    Field("max", "number", f"a number > 0 and <= {DEEPEST:g} [m]",
          ok=lambda x: 0 < x <= DEEPEST, required=True, unit="m"),
    Field("count", "integer", "an integer >= 2", ok=lambda n: n >= 2, required=True,
          cap=MAX_DEPTHS, cap_why="depths of the stress product"),
    Field("min", "number", "a finite number >= 0 [m]", ok=lambda x: x >= 0, default=0.0,
          unit="m"),
)


@dataclasses.dataclass(frozen=True)
class StressSpec:
    """The ``[stress]`` table of a pipeline file, read and validated
    (:func:`read_stress_table`): the subsurface-stress product of each member.

    Attributes
    ----------
    depths : tuple of float
        Depths into the body [m], ascending, distinct.
    body : str
        "halfspace" or "indenter".
    time : str or tuple of float
        "last", "all" or times [s] of the archive.
    criterion : str or None
        A criterion of :func:`contactpipe.fatigue`, or None.
    constants : tuple of (str, object)
        The criterion's constants as given, sorted by name.
    cycle : tuple of float or None
        (t_start, t_end) [s]: the instants the criterion runs over; None: all.
    cycle_norm : tuple of float or None
        (a, b): the same in t_norm = (t - t_first)/(t_last - t_first) of the member's
        archive (the sweep's t_norm), for members whose windows differ.
    precision : str
        Storage type of the stresses.
    figure : bool
        Draw ``figures/<digest>-stress.png``.
    """

    depths: tuple
    body: str = "halfspace"
    time: str | tuple = "last"
    criterion: str | None = None
    constants: tuple = ()
    cycle: tuple | None = None
    cycle_norm: tuple | None = None
    precision: str = "float64"
    figure: bool = True

    def settings(self) -> dict:
        """Everything that decides the product's content (not whether a figure is
        drawn), as JSON-ready values."""
        return {"depths": list(self.depths), "body": self.body,
                "time": self.time if isinstance(self.time, str) else list(self.time),
                "criterion": self.criterion, "constants": dict(self.constants),
                "cycle": None if self.cycle is None else list(self.cycle),
                "cycle_norm": None if self.cycle_norm is None else list(self.cycle_norm),
                "precision": self.precision}

    def digest(self) -> str:
        """A stable hash of :meth:`settings` (16 hex digits): a product whose stored
        digest differs is recomputed."""
        text = json.dumps(self.settings(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclasses.dataclass
class SweepFile:
    """A sweep file, read and validated (:func:`read_sweep_file`)."""

    path: pathlib.Path | None
    base: Scene
    axes: dict
    mode: str = "product"
    scheduler: str | None = None
    n_workers: int | None = None
    threads_per_worker: int = 1
    retries: int = 0


@dataclasses.dataclass
class PipelineSpec:
    """A pipeline file, read and validated (:func:`read_pipeline_file`)."""

    path: pathlib.Path
    name: str
    out: pathlib.Path
    base: Scene
    axes: dict
    mode: str = "product"
    reference: str | pathlib.Path | None = CLOSED_FORM   # CLOSED_FORM, a path, or None
    figures: tuple = DEFAULT_FIGURES
    variables: tuple = ("contact_area",)
    stress: StressSpec | None = None
    scheduler: str | None = None
    n_workers: int | None = None
    threads_per_worker: int = 1
    retries: int = 0


def _field(fields, name) -> Field:
    return next(f for f in fields if f.name == name)


def _relative(value: str, here: pathlib.Path) -> pathlib.Path:
    p = pathlib.Path(value).expanduser()
    return p if p.is_absolute() else here / p


# ----------------------------------------------------------------------------- sweep files

def flatten_axes(table: Mapping, prefix: str = "") -> dict:
    """Axes as {dotted name: values}, in file order: a TOML dotted key
    (``friction.mu = [...]``) is a nested table, read back as the axis ``"friction.mu"``."""
    out = {}
    stack = [(prefix, iter(table.items()))]
    while stack:                      # depth first, without recursion
        pre, items = stack[-1]
        for k, v in items:
            if isinstance(v, Mapping):
                stack.append((f"{pre}{k}.", iter(v.items())))
                break
            out[f"{pre}{k}"] = v
        else:
            stack.pop()
    return out


def read_dask_table(raw, where: str, problems: list) -> dict:
    """Validate a ``[dask]`` table; returns {scheduler, n_workers, threads_per_worker,
    retries} for the keys given (an empty ``scheduler`` is left out: a LocalCluster)."""
    if raw is None:
        return {}
    if not isinstance(raw, Mapping):
        problems.append(f"{where} must be a table (dict) with "
                        f"{', '.join(f.name for f in DASK_FIELDS)}, got {show(raw)}")
        return {}
    r = Reader(raw, where, problems)
    r.check_keys(DASK_FIELDS)
    out = {}
    for f in DASK_FIELDS:
        if r.has(f.name):
            v = r.value(f)
            if isinstance(v, str):
                v = v.strip() or None
            if v is not None:
                out[f.name] = v
    return out


def _read_axes(r: Reader, problems: list) -> dict:
    raw = r.raw.get("axes")
    where = f"[{r.key('axes')}]"
    if raw is None:
        problems.append(f"{where} is missing: give at least one axis, e.g. "
                        f"\"friction.mu\" = [0.05, 0.1]")
        return {}
    if not isinstance(raw, Mapping) or not raw:
        problems.append(f"{where} must be a table of axis = [values], got {show(raw)}")
        return {}
    axes = {}
    for k, v in flatten_axes(raw).items():
        key = f"{r.key('axes')}.{k}"
        if not isinstance(v, list) or not v:
            problems.append(f"{key} must be a non-empty list of values, got {show(v)}")
        elif nesting_depth(v, MAX_AXIS_DEPTH) > MAX_AXIS_DEPTH:
            problems.append(f"{key} nests its values more than {MAX_AXIS_DEPTH} levels "
                            f"deep, got {show(v)}; an axis value is a number, a string or "
                            f"a short list")
        else:
            axes[k] = v
    return axes


def _read_base(r: Reader, base_dir: pathlib.Path, problems: list):
    """The base scene of a sweep table: a scene file (``base``) or an inline table."""
    base_key, scene_key = r.key("base"), r.key("scene")
    if r.has("base") and r.has("scene"):
        problems.append(f"{base_key} and an inline [{scene_key}] table cannot both be "
                        f"given; keep one")
        return None
    if r.has("base"):
        v = r.value(_field(SWEEP_FIELDS, "base"))
        if v is None:
            return None
        p = _relative(v, base_dir)
        if not p.is_file():
            problems.append(f"{base_key} = {v!r}: no such scene file ({p})")
            return None
        try:
            return Scene.from_toml(p)
        except SceneError as err:
            problems.extend(f"{base_key} ({p.name}): {q}" for q in err.problems)
        return None
    if r.has("scene"):
        v = r.value(_field(SWEEP_FIELDS, "scene"))
        if v is None:
            return None
        try:
            return Scene.from_dict(v, base_dir=base_dir)
        except SceneError as err:
            problems.extend(f"{scene_key}: {q}" for q in err.problems)
        return None
    problems.append(f"{base_key} is missing: give a scene file (base = \"scene.toml\") "
                    f"or an inline [{scene_key}] table")
    return None


def read_sweep_table(d: Mapping, path: str, base_dir: pathlib.Path, problems: list,
                     allowed=None):
    """(base Scene or None, axes, mode) of a sweep table; problems appended.

    ``path`` is the table's dotted name ("" for a sweep file, "sweep" inline in a
    pipeline file); ``allowed`` the names of the keys it may hold (default: those of
    :data:`SWEEP_FIELDS`).
    """
    r = Reader(d, path, problems, title="the sweep file")
    r.check_keys(SWEEP_FIELDS if allowed is None else allowed)
    base = _read_base(r, base_dir, problems)
    mode = r.value(_field(SWEEP_FIELDS, "mode")) or "product"
    axes = _read_axes(r, problems)
    if r.has("name"):
        r.value(_field(SWEEP_FIELDS, "name"))
    return base, axes, mode


def read_sweep_file(path) -> SweepFile:
    """Read and validate a sweep file (docs/scene-file.md, with the ``[dask]`` table).

    Raises
    ------
    SceneError
        Every problem of the file (unknown keys, a missing base, bad axes or mode, a bad
        base scene), each prefixed with the file's name; FileNotFoundError when it does
        not exist.
    """
    path = pathlib.Path(path)
    d = read_toml(path, "sweep")
    problems = []
    base, axes, mode = read_sweep_table(d, "", path.resolve().parent, problems)
    dask = read_dask_table(d.get("dask"), "dask", problems)
    if problems:
        raise SceneError([f"{path.name}: {p}" for p in problems])
    return SweepFile(path=path, base=base, axes=axes, mode=mode, **dask)


def load_sweep_file(path):
    """(base Scene, axes, mode) of a sweep file (docs/scene-file.md); :func:`read_sweep_file`."""
    sf = read_sweep_file(path)
    return sf.base, sf.axes, sf.mode


# ----------------------------------------------------------------------------- pipeline files

def _read_pipeline_sweep(r: Reader, here: pathlib.Path, problems: list) -> dict:
    """The [sweep] table of a pipeline file: {base, axes, mode, dask, out}."""
    out = {"base": None, "axes": None, "mode": "product", "dask": {},
           "out": r.raw.get("out")}
    sw = r.raw.get("sweep")
    if sw is None:
        problems.append("[sweep] is missing: give file = \"sweep.toml\" or an inline "
                        "base = \"scene.toml\" with [sweep.axes]")
        return out
    sw = r.value(_field(PIPELINE_FIELDS, "sweep"))
    if sw is None:
        return out
    if "out" in sw:
        if out["out"] is not None:
            problems.append("out is given twice (top level and [sweep]); keep one")
        out["out"] = sw.pop("out")
    if "file" not in sw:
        out["base"], out["axes"], out["mode"] = read_sweep_table(
            sw, "sweep", here, problems, allowed=INLINE_SWEEP + ("file", "out"))
        return out
    extra = [k for k in sw if k != "file"]
    if extra:
        problems.append(f"sweep.file cannot be combined with sweep."
                        f"{', sweep.'.join(map(str, extra))}: put them in the sweep file")
    v = sw["file"]
    if not isinstance(v, str) or not v:
        problems.append(f"sweep.file must be the path of a sweep file, got {show(v)}")
        return out
    p = _relative(v, here)
    if not p.is_file():
        problems.append(f"sweep.file = {v!r}: no such sweep file ({p})")
        return out
    try:
        sf = read_sweep_file(p)
    except SceneError as err:
        problems.extend(f"sweep.file: {q}" for q in err.problems)
        return out
    out["base"], out["axes"], out["mode"] = sf.base, sf.axes, sf.mode
    out["dask"] = {k: getattr(sf, k) for k in
                   ("scheduler", "n_workers", "threads_per_worker", "retries")}
    return out


def _read_out(value, here: pathlib.Path, problems: list):
    if value is None:
        problems.append("out is missing: the folder of the member archives and products, "
                        "e.g. out = \"runs/paper-fig3\" (relative to this file)")
        return None
    if not isinstance(value, str) or not value:
        problems.append(f"out must be a folder path, got {show(value)}")
        return None
    return _relative(value, here)


def _read_compare(r: Reader, here: pathlib.Path, problems: list):
    """The reference of [compare]: CLOSED_FORM, None ("none") or an archive path."""
    cmp_ = r.value(_field(PIPELINE_FIELDS, "compare")) if r.has("compare") else {}
    if cmp_ is None:
        return CLOSED_FORM
    c = Reader(cmp_, "compare", problems)
    c.check_keys(COMPARE_FIELDS)
    v = c.value(COMPARE_FIELDS[0])
    if v is None or v == CLOSED_FORM:
        return CLOSED_FORM
    if v == "none":
        return None
    p = _relative(v, here)
    if not p.is_file():
        problems.append(f"compare.reference = {v!r}: no such archive ({p}); give an "
                        f"archive path, \"closed_form\" or \"none\"")
    return p


def _read_plot(r: Reader, problems: list):
    """(figures, variables) of [plot]."""
    figures, variables = DEFAULT_FIGURES, ("contact_area",)
    plot = r.value(_field(PIPELINE_FIELDS, "plot")) if r.has("plot") else {}
    if plot is None:
        return figures, variables
    p = Reader(plot, "plot", problems)
    p.check_keys(PLOT_FIELDS)
    v = p.value(PLOT_FIELDS[0])
    if v is not None:
        bad = [x for x in v if x not in FIGURES]
        for x in bad:
            problems.append(f"plot.figures: unknown figure {x!r}{did_you_mean(x, FIGURES)}; "
                            f"allowed: {', '.join(FIGURES)}")
        figures = tuple(dict.fromkeys(x for x in v if x in FIGURES))
    v = p.value(PLOT_FIELDS[1])
    if v is not None:
        v = (v,) if isinstance(v, str) else v
        series = [k for k, e in VARIABLES.items() if e["dims"] == SERIES] + \
            [k for k, e in HISTORY.items() if e["dims"] == CYCLE_SERIES]
        bad = [x for x in v if x not in series]
        if bad:
            problems.append(f"plot.variables: {', '.join(map(repr, bad))} is not a series "
                            f"of the archive (over time, or over cycle for a wear run); "
                            f"allowed: {', '.join(series)}")
        variables = tuple(v)
    return figures, variables


def _read_depths(r: Reader):
    """The depths of [stress] (required): a list, or {max, count, min} spread evenly."""
    f = _field(STRESS_FIELDS, "depths")
    if not r.has("depths"):
        r.missing("depths", "", f.wording)
        return None
    v = r.value(f)
    if v is None:
        return None
    if not isinstance(v, dict):
        return tuple(float(z) for z in np.unique(v))
    d = Reader(v, r.key("depths"), r.problems)
    d.check_keys(DEPTH_FIELDS)
    spec = d.read(DEPTH_FIELDS)
    if None in spec.values():
        return None
    if not spec["min"] < spec["max"]:
        d.add(f"{d.key('min')} = {spec['min']!r} must be < {d.key('max')} = {spec['max']!r}")
        return None
    return tuple(float(z) for z in np.linspace(spec["min"], spec["max"], spec["count"]))


def _read_constants(r: Reader, criterion):
    """The constants of [stress] that ``criterion`` takes: its required ones must be
    given, those it does not take are refused."""
    _, _, _, required, optional = CRITERIA.get(criterion, (None, None, None, {}, {}))
    need = f" for criterion = {criterion!r}"
    out = {}
    for f in CONSTANT_FIELDS:
        if f.name not in required and f.name not in optional:
            r.forbid(f.name, f"by criterion = {criterion or 'none'!r}")
            continue
        v = r.value(f, need=need, required=f.name in required)
        if v is not None:
            out[f.name] = v
    return tuple(sorted(out.items()))


def read_stress_table(raw, problems: list) -> StressSpec | None:
    """Validate a pipeline file's ``[stress]`` table (module docstring); None when it has
    problems (appended to ``problems``)."""
    before = len(problems)
    r = Reader(raw, "stress", problems)
    r.check_keys(STRESS_FIELDS)
    depths = _read_depths(r)
    values = r.read([f for f in STRESS_FIELDS if f.name in
                     ("body", "time", "criterion", "cycle", "cycle_norm", "precision",
                      "figure")])
    criterion = None if values["criterion"] in (None, "none") else values["criterion"]
    if values["criterion"] is None:           # refused above: its constants are unknown
        return None
    constants = _read_constants(r, criterion)
    time = values["time"]
    if criterion is None:
        r.forbid("cycle", "without a criterion")
        r.forbid("cycle_norm", "without a criterion")
    else:
        if r.has("cycle") and r.has("cycle_norm"):
            r.add("stress.cycle and stress.cycle_norm cannot both be given; keep one")
        if time == "last" or (isinstance(time, tuple) and len(set(time)) < 2):
            r.add(f"stress.criterion = {criterion!r} needs the stress over a cycle: give "
                  f"stress.time = \"all\" or a list of at least 2 times [s], got "
                  f"{time if isinstance(time, str) else list(time)!r}")
    if len(problems) > before:
        return None
    if isinstance(time, tuple):
        time = tuple(float(t) for t in np.unique(time))
    return StressSpec(depths=depths, body=values["body"], time=time, criterion=criterion,
                      constants=constants, cycle=values["cycle"],
                      cycle_norm=values["cycle_norm"], precision=values["precision"],
                      figure=values["figure"])


def read_pipeline_file(path) -> PipelineSpec:
    """Read and validate a pipeline file (module docstring).

    Raises
    ------
    SceneError
        Every problem of the file, each prefixed with the file's name (unknown keys,
        no sweep, no out, a bad sweep or scene, unknown figures, a missing reference
        archive).
    FileNotFoundError
        The file does not exist.
    """
    path = pathlib.Path(path)
    d = read_toml(path, "pipeline")
    here = path.resolve().parent
    problems = []
    r = Reader(d, "", problems, title="the pipeline file")
    r.check_keys(PIPELINE_FIELDS)
    name = r.value(_field(PIPELINE_FIELDS, "name")) or path.stem
    sw = _read_pipeline_sweep(r, here, problems)
    out = _read_out(sw["out"], here, problems)
    reference = _read_compare(r, here, problems)
    figures, variables = _read_plot(r, problems)
    stress = None
    if r.has("stress"):
        table = r.value(_field(PIPELINE_FIELDS, "stress"))
        stress = None if table is None else read_stress_table(table, problems)
    dask = dict(sw["dask"])
    dask.update(read_dask_table(d.get("dask"), "dask", problems))
    if problems:
        raise SceneError([f"{path.name}: {p}" for p in problems])
    dask = {k: v for k, v in dask.items() if v is not None}
    return PipelineSpec(path=path, name=name, out=out, base=sw["base"], axes=sw["axes"],
                        mode=sw["mode"], reference=reference, figures=figures,
                        variables=variables, stress=stress, **dask)
