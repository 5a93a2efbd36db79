"""The members of a sweep: axes parsed, every combination built into a validated scene.

An axis name is either a dotted path into the scene (``"friction.mu"``,
``"load.normal_force"``, ``"halfspace.relaxation_time"``, ``"time.steps"``; see
:meth:`Scene.replace`) or a derived parameter registered by name
(:mod:`contactpipe.pipeline.sweep.parameters`), or given as ``(values, func)``. Within a member,
the dotted paths are applied first (all at once), then the derived parameters in axis
order, so ``tau_ratio`` sees a swept relaxation time.

``mode="product"`` runs every combination (one dimension per axis); ``mode="zip"`` pairs
the i-th values of every axis (equal lengths; one dimension ``member``). Each member is
named by its scene's :meth:`~contactpipe.Scene.digest`.
"""
from __future__ import annotations

import dataclasses
import itertools
import json
import numbers

from ...exceptions import SceneError
from ...nomenclature import COORDINATES, VARIABLES
from ...scene import Scene
from .parameters import derived_parameters, registered

__all__ = ["Member", "build_members", "dim_names", "jsonable", "show_value", "label_of",
           "coord_value", "MODES", "STATUSES", "MAX_PROBLEMS"]

MODES = ("product", "zip")
#: The states of a member in the manifest.
STATUSES = ("pending", "done", "failed")
#: Problems listed at most in one SceneError (the rest are counted).
MAX_PROBLEMS = 25
#: Names a sweep dimension cannot take (the archive's own dimensions and variables).
RESERVED = frozenset({"time", "t_norm", "x1", "x2", "member", "digest"} | set(VARIABLES)
                     | set(COORDINATES))


@dataclasses.dataclass
class Member:
    """One member of a sweep: its axis values, scene digest, file and outcome."""

    index: int
    values: dict
    digest: str
    file: str
    status: str = "pending"            # pending | done | failed
    error: str | None = None
    wall_time_s: float | None = None
    cpu_time_s: float | None = None
    scene: object = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def label(self) -> str:
        """``tau_ratio=0.5, friction.mu=0.1``."""
        return label_of(self.values)

    def to_json(self) -> dict:
        return {"index": self.index, "values": {k: jsonable(v) for k, v in self.values.items()},
                "digest": self.digest, "file": self.file, "status": self.status,
                "error": self.error, "wall_time_s": self.wall_time_s,
                "cpu_time_s": self.cpu_time_s}

    def __str__(self) -> str:
        text = f"{self.label} ({self.file})"
        return f"{text}: {self.error}" if self.error else text


def jsonable(v):
    """Axis values as plain JSON types (numpy scalars and arrays, tuples -> lists)."""
    if isinstance(v, (str, bool)) or v is None:
        return v
    if isinstance(v, numbers.Integral):
        return int(v)
    if isinstance(v, numbers.Real):
        return float(v)
    if hasattr(v, "tolist"):
        return jsonable(v.tolist())
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    return str(v)


def show_value(v) -> str:
    v = jsonable(v)
    if isinstance(v, float):
        return f"{v:g}"
    return json.dumps(v) if not isinstance(v, str) else repr(v)


def label_of(values: dict) -> str:
    return ", ".join(f"{k}={show_value(v)}" for k, v in values.items())


def coord_value(v):
    """An axis value as a coordinate label (lists become their JSON text)."""
    v = jsonable(v)
    if isinstance(v, (list, dict)):
        return json.dumps(v)
    return v


def dim_names(names) -> dict:
    """Axis -> dimension name: the last part of a dotted path (``friction.mu`` -> ``mu``)
    unless two axes share it or it is taken (``time``, a variable name): then the path
    with underscores (``halfspace_young``)."""
    reserved = RESERVED
    last = {n: n.rsplit(".", 1)[-1] for n in names}
    out = {}
    for n in names:
        d = last[n]
        if list(last.values()).count(d) > 1 or d in reserved:
            d = n.replace(".", "_")
        while d in reserved or d in out.values():
            d += "_axis"
        out[n] = d
    return out


def _parse_axes(axes) -> tuple[list, dict, dict]:
    """names, {name: [values]}, {name: func or None}; SceneError listing every problem."""
    if not isinstance(axes, dict) or not axes:
        raise SceneError(f"axes must be a non-empty dict {{name: [values]}}, got {axes!r}")
    problems, values, funcs = [], {}, {}
    for name, spec in axes.items():
        if not isinstance(name, str) or not name or "" in name.split("."):
            problems.append(f"axis {name!r}: an axis name is a dotted scene path such as "
                            f"'friction.mu' or a derived parameter "
                            f"({', '.join(sorted(derived_parameters()))})")
            continue
        func = registered(name)
        if isinstance(spec, tuple) and len(spec) == 2 and callable(spec[1]):
            spec, func = spec
        if hasattr(spec, "tolist") and not isinstance(spec, (str, bytes)):
            spec = spec.tolist()
        if isinstance(spec, (str, bytes, dict)) or not hasattr(spec, "__iter__"):
            problems.append(f"axis {name}: values must be a non-empty list, got "
                            f"{show_value(spec) if not callable(spec) else repr(spec)}")
            continue
        vals = list(spec)
        if not vals:
            problems.append(f"axis {name}: values must be a non-empty list, got []")
            continue
        if "." not in name and func is None:
            problems.append(f"axis {name!r} is neither a dotted scene path (such as "
                            f"'friction.mu') nor a derived parameter (registered: "
                            f"{', '.join(sorted(derived_parameters()))}); register it with "
                            f"@register_parameter({name!r}) or give (values, func)")
            continue
        values[name], funcs[name] = vals, func
    if problems:
        raise SceneError(problems)
    return list(values), values, funcs


def _combinations(names, values, mode) -> list:
    """The members' value tuples: every combination, or the i-th of each axis (zip)."""
    if mode == "zip":
        lengths = {n: len(values[n]) for n in names}
        if len(set(lengths.values())) > 1:
            raise SceneError("mode = 'zip' needs axes of equal lengths, got "
                             + ", ".join(f"{n}: {k}" for n, k in lengths.items()))
        return list(zip(*(values[n] for n in names), strict=True))
    problems = []
    for n in names:
        labels = [json.dumps(coord_value(v)) for v in values[n]]
        dup = sorted({v for v in labels if labels.count(v) > 1})
        if dup:
            problems.append(f"axis {n}: values must be distinct in mode 'product', "
                            f"got {', '.join(dup)} more than once")
    if problems:
        raise SceneError(problems)
    return list(itertools.product(*(values[n] for n in names)))


def _member_scene(base, vals, dotted, derived, funcs) -> tuple[Scene | None, list]:
    """(scene, []) of one member, or (None, problems naming axis and value)."""
    scene = base
    try:
        if dotted:
            scene = base.replace({n: jsonable(vals[n]) for n in dotted})
    except SceneError as err:
        problems = []
        for p in err.problems:
            named = [n for n in dotted if n in p] or dotted
            problems.append(f"axis {label_of({n: vals[n] for n in named})}: {p}")
        return None, problems
    except (TypeError, ValueError) as err:
        return None, [f"axis {label_of({n: vals[n] for n in dotted})}: {err}"]
    for n in derived:
        where = f"axis {n}={show_value(vals[n])}"
        try:
            new = funcs[n](scene, vals[n])
        except SceneError as err:
            return None, [f"{where}: {p}" for p in err.problems]
        except (TypeError, ValueError) as err:   # a value the user's function cannot take
            return None, [f"{where}: {type(err).__name__}: {err}"]
        if not isinstance(new, Scene):
            return None, [f"{where}: the derived parameter returned "
                          f"{type(new).__name__}, not a Scene"]
        scene = new
    return scene, []


def build_members(base, axes, mode):
    """Every member of a sweep, its scene validated.

    Returns
    -------
    names : list of str
        The axes, in order.
    values : dict
        ``{axis: [values]}``.
    funcs : dict
        ``{axis: derived-parameter function or None}`` (None: a dotted scene path).
    members : list of Member
        In sweep order, each with its scene and digest.

    Raises
    ------
    SceneError
        Every problem (at most :data:`MAX_PROBLEMS` listed), each naming the axis and
        value, before any work starts. A derived parameter's function may raise
        SceneError, ValueError or TypeError for a value it cannot take; other errors
        (a bug in it) propagate as they are.
    """
    if mode not in MODES:
        raise SceneError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    names, values, funcs = _parse_axes(axes)
    combos = _combinations(names, values, mode)
    dotted = [n for n in names if funcs[n] is None]
    derived = [n for n in names if funcs[n] is not None]
    problems, members = [], []
    for i, combo in enumerate(combos):
        vals = dict(zip(names, combo, strict=True))
        scene, bad = _member_scene(base, vals, dotted, derived, funcs)
        if bad:
            problems.extend(p for p in bad if p not in problems)
            continue
        digest = scene.digest()
        members.append(Member(index=i, values=vals, digest=digest, file=f"{digest}.nc",
                              scene=scene))
    if problems:
        if len(problems) > MAX_PROBLEMS:
            problems = problems[:MAX_PROBLEMS] + [f"... and {len(problems) - MAX_PROBLEMS} "
                                                  f"more"]
        raise SceneError(problems)
    return names, values, funcs, members
