"""The scene: one simulation, frozen and validated on construction, TOML in and out.

A :class:`Scene` holds the parts of a scene file as frozen dataclasses
(:mod:`contactpipe.scene.parts`): :class:`Geometry`, two :class:`BodySpec` (``indenter`` =
body 1, ``halfspace`` = body 2), :class:`Friction`, :class:`Load` (with an optional
:class:`Fretting` preset), :class:`Grid`, :class:`TimeMesh`, :class:`Solver` and
:class:`Output`. The file format is documented in ``docs/scene-file.md``.

Construction validates everything and raises one :class:`~contactpipe.SceneError`
listing *every* problem found; each message names the dotted field, the value given
and what is allowed::

    scene = Scene.from_toml("scene.toml")     # or Scene(**nested_dict), Scene.from_dict
    scene.to_dict()                            # complete, defaults resolved, plain types
    scene.to_toml()                            # TOML text that reads back equal
    scene.digest()                             # 16 hex chars identifying the simulation
    scene.replace({"friction.mu": 0.2, "load.fretting.window": 2.0})

Each table is read by the table-driven reader of :mod:`contactpipe.scene.tables`; this module
adds the rules across parts: two rigid bodies, the step-start rule without instantaneous
elasticity or at or above its stability bound, gross sliding, the default time mesh (the
least uniform mesh that holds every load knot), a creep table (or the data of a fitted one)
that must reach the end of the load window, and the grid: the automatic one and a given
one must hold the estimated largest contact, a tilt's shift included (:func:`contact_reach`).

TOML has no null: keys whose value is ``None`` (e.g. ``solver.accuracy``) are left out of
:meth:`Scene.to_dict`, and ``None`` given for a key means "absent".

Units: SI (m, s, N, Pa) everywhere.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .._util.files import loads_toml
from ..exceptions import SceneError
from .checks import check_scene
from .parts import (
    MATERIALS,
    SHAPES,
    BodySpec,
    Fretting,
    Friction,
    Geometry,
    Grid,
    Load,
    Output,
    Solver,
    TimeMesh,
)
from .reach import (
    AUTO_MARGIN,
    AUTO_PUNCH_FACTOR,
    auto_grid_size,
    contact_reach,
    contact_shifts,
    hertz_semi_axes,
)
from .tables import Field, Reader, show
from .wear import Wear, check_wear

__all__ = ["Scene", "Geometry", "BodySpec", "Friction", "Load", "Fretting", "Grid",
           "TimeMesh", "Solver", "Output", "Wear", "SceneError", "hertz_semi_axes",
           "contact_reach",
           "contact_shifts", "auto_grid_size", "AUTO_MARGIN", "AUTO_PUNCH_FACTOR"]


#: The top level of a scene file: its name and its tables, in file order.
FIELDS = (
    Field("name", "string", "a non-empty string", ok=bool, default="scene"),
    Field("geometry", "table", "shape = " + " | ".join(SHAPES), part=Geometry,
          required=True),
    Field("indenter", "table", "material = " + " | ".join(MATERIALS), part=BodySpec,
          required=True),
    Field("halfspace", "table", "material = " + " | ".join(MATERIALS), part=BodySpec,
          required=True),
    Field("friction", "table", "mu", part=Friction, default=Friction()),
    Field("load", "table", "time [s], normal_force [N], ...", part=Load, required=True),
    Field("grid", "table", "points = [N1, N2], size = [L1, L2] [m]", part=Grid,
          required=True),
    Field("time", "table", "steps", part=TimeMesh, default=TimeMesh()),
    Field("solver", "table", "solver options", part=Solver, default=Solver()),
    Field("output", "table", "stride, precision, compress", part=Output, default=Output()),
    Field("wear", "table", "law, coefficient [1/Pa], cycles, jump", part=Wear),
)
PARTS = tuple(f.name for f in FIELDS[1:])
TOP_KEYS = tuple(f.name for f in FIELDS)


# ----------------------------------------------------------------------------- scene

@dataclass(frozen=True, init=False)
class Scene:
    """One simulation: geometry, bodies, friction, load, grid, time mesh, solver, output.

    ``Scene(**d)`` takes the nested-dict form of the scene file (sub-tables as dicts, or
    the part objects themselves), validates everything and raises one
    :class:`~contactpipe.SceneError` listing every problem. The stored scene is
    normalised: numbers are floats (ints accepted), lists are tuples, defaults are
    resolved (``time.steps``, ``geometry.height``, a fitted body's ``young``) and
    ``geometry.file`` and a body's ``file`` are absolute (a relative one is taken relative
    to the current directory here, to the scene file's folder in :meth:`from_toml`).

    Parameters
    ----------
    name : str
        A label, "scene" by default.
    geometry, indenter, halfspace, load, grid : dict or part
        Required tables.
    friction, time, solver, output : dict or part, optional
        Absent: defaults (mu = 0; the least uniform mesh that holds every load knot;
        solver and output defaults).
    wear : dict or Wear, optional
        Fretting wear over many repetitions of the load program (docs/wear.md); absent:
        no wear, one pass of the program.
    """

    name: str
    geometry: Geometry
    indenter: BodySpec
    halfspace: BodySpec
    friction: Friction
    load: Load
    grid: Grid
    time: TimeMesh
    solver: Solver
    output: Output
    wear: Wear | None

    def __init__(self, /, name="scene", geometry=None, indenter=None, halfspace=None,
                 friction=None, load=None, grid=None, time=None, solver=None, output=None,
                 wear=None, **unknown):
        given = dict(name=name, geometry=geometry, indenter=indenter, halfspace=halfspace,
                     friction=friction, load=load, grid=grid, time=time, solver=solver,
                     output=output, wear=wear, **unknown)
        problems: list[str] = []
        r = Reader(given, "", problems, title="the scene")
        r.check_keys(FIELDS)
        parts = r.read(FIELDS)
        parts["time"] = check_scene(parts, problems)
        check_wear(parts, problems)
        if problems:
            raise SceneError(problems)
        for key in TOP_KEYS:
            object.__setattr__(self, key, parts[key])

    # -- construction ------------------------------------------------------------------

    @classmethod
    def from_dict(cls, d, base_dir=None) -> Scene:
        """A scene from its nested-dict form (as :meth:`to_dict` gives or TOML reads); a
        relative ``geometry.file`` or ``friction.mu`` file is taken relative to
        ``base_dir`` (default: the current directory)."""
        if not isinstance(d, Mapping):
            raise SceneError(f"a scene must be a table (dict), got {show(d)}")
        bad = [k for k in d if not isinstance(k, str)]
        if bad:
            raise SceneError(f"scene keys must be strings, got {show(bad)}; allowed keys: "
                             f"{', '.join(TOP_KEYS)}")
        d = dict(d)
        if base_dir is not None:     # files of the scene's tables, relative to its folder
            for table, key in (("geometry", "file"), ("indenter", "file"),
                               ("halfspace", "file"), ("friction", "mu")):
                part = d.get(table)
                if isinstance(part, Mapping) and isinstance(part.get(key), str):
                    file = os.path.expanduser(part[key])
                    if not os.path.isabs(file):
                        d[table] = {**part, key: os.path.join(
                            os.path.abspath(os.fspath(base_dir)), file)}
        return cls(**d)

    @classmethod
    def from_toml_text(cls, text: str, base_dir=None) -> Scene:
        """A scene from TOML text; a relative ``geometry.file`` is taken relative to
        ``base_dir`` (default: the current directory)."""
        return cls.from_dict(loads_toml(text, "the scene"), base_dir)

    @classmethod
    def from_toml(cls, path) -> Scene:
        """A scene from a TOML file; a relative ``geometry.file`` is taken relative to
        the scene file's folder."""
        path = os.fspath(path)
        with open(path, "rb") as f:
            raw = f.read()
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SceneError(f"{path}: not a UTF-8 text file ({exc})") from None
        return cls.from_dict(loads_toml(text, path), os.path.dirname(os.path.abspath(path)))

    # -- output ------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The scene as nested plain dicts (lists, floats, ints, str, bool), complete with
        defaults resolved; ``Scene.from_dict(s.to_dict()) == s``. ``None`` values (e.g.
        ``solver.accuracy``) are left out, as TOML has no null."""
        d = {"name": self.name}
        for key in PARTS:
            part = getattr(self, key)
            if part is not None:        # an optional table absent ([wear])
                d[key] = part.to_dict()
        return d

    def to_toml(self) -> str:
        """The scene as TOML text; reading it back gives an equal scene."""
        d = self.to_dict()
        import tomli_w  # only to write: validation reads with tomllib
        text = tomli_w.dumps(d)
        compact = _compact_arrays(text)
        return compact if loads_toml(compact) == loads_toml(text) else text

    def digest(self) -> str:
        """A stable identifier of the simulation: 16 hex characters of the sha256 of
        :meth:`to_dict` as canonical JSON (sorted keys, no spaces).

        Everything counts except ``[output]`` (stride, precision and compression change
        the archive, not the physics), ``name`` and the solver options included. A
        surface file counts by its content (its sha256), not its path, so moving it does
        not change the digest and editing it does. Independent of key order, process and
        platform. A friction map (``friction.mu`` a file) counts by its content too.
        """
        d = self.to_dict()
        del d["output"]
        for part in ("geometry", "indenter", "halfspace"):  # a file counts by its content
            if d[part].get("file") is not None:
                d[part]["file"] = _file_digest(d[part]["file"])
        if self.friction.mapped:
            d["friction"]["mu"] = _file_digest(self.friction.mu)
        text = json.dumps(d, sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]

    def input_files(self) -> list:
        """The files the scene reads, as absolute paths: a surface's gap file, a body's
        fitted material table, a friction map (what no output may overwrite)."""
        files = [getattr(part, "file", None)
                 for part in (self.geometry, self.indenter, self.halfspace)]
        if self.friction.mapped:
            files.append(self.friction.mu)
        return [f for f in files if f]

    def replace(self, changes) -> Scene:
        """A new, validated scene with some values changed.

        Parameters
        ----------
        changes : dict
            Dotted paths to new values, e.g. ``{"friction.mu": 0.2,
            "load.fretting.window": 2.0, "halfspace.relaxation_time": 0.5}``. A value of
            ``None`` removes the key (back to its default). Tables on the way are created.

        Notes
        -----
        Works on :meth:`to_dict`. Derived defaults equal to their derivation
        (``time.steps`` = the least mesh holding every knot, a flat punch's ``height`` =
        radius)
        are derived again from the changed scene, unless ``changes`` sets them.
        """
        if not isinstance(changes, Mapping):
            raise SceneError(f"changes must be a dict of dotted paths to values, got "
                             f"{show(changes)}")
        d = self.to_dict()
        if d["time"].get("steps") == self.load.default_steps():
            del d["time"]["steps"]
        if self.geometry.shape == "flat_punch" and self.geometry.height == self.geometry.radius:
            del d["geometry"]["height"]
        for side in ("indenter", "halfspace"):        # a fitted modulus is derived again
            if getattr(self, side).creep == "fit":
                del d[side]["young"]
        problems = []
        for path, value in changes.items():
            if not isinstance(path, str) or not path or "" in path.split("."):
                problems.append(f"change {path!r}: a change's key must be a dotted "
                                f"path such as 'friction.mu'")
                continue
            parts = path.split(".")
            node = d
            for i, part in enumerate(parts[:-1]):
                nxt = node.get(part)
                if nxt is None:
                    nxt = node[part] = {}
                elif not isinstance(nxt, dict):
                    problems.append(f"cannot set {path!r}: {'.'.join(parts[:i + 1])} is "
                                    f"{show(nxt)}, not a table")
                    break
                node = nxt
            else:
                if value is None:
                    node.pop(parts[-1], None)
                else:
                    node[parts[-1]] = value
        if problems:
            raise SceneError(problems)
        return Scene.from_dict(d)

    # -- derived quantities ------------------------------------------------------------

    def resolved_grid_size(self):
        """Grid side lengths (L1, L2) [m]: as given, or for ``size = "auto"`` a Hertz
        estimate of the largest contact over the window with margin 1.5 on its reach
        (side = 3 (a_max + a tilt's shift); a flat punch: 2.5 radius;
        :func:`auto_grid_size`)."""
        if self.grid.size != "auto":
            return tuple(self.grid.size)
        with np.errstate(all="ignore"):
            return auto_grid_size(self.geometry, self.indenter, self.halfspace, self.load)

    def resolved_grid(self) -> Grid:
        """The grid with its size resolved (see :meth:`resolved_grid_size`)."""
        if self.grid.size != "auto":
            return self.grid
        return Grid.make(points=self.grid.points, size=self.resolved_grid_size())

    def hertz_semi_axes(self, moduli: str = "window"):
        """Hertz semi-axes (a1, a2) [m] of the scene's largest contact
        (:func:`hertz_semi_axes`); None for a surface."""
        with np.errstate(all="ignore"):
            return hertz_semi_axes(self.geometry, self.indenter, self.halfspace, self.load,
                                   moduli)

    def instants(self):
        """The load program on the scene's time mesh: (t [s], W, T1, T2 [N]) arrays of
        length ``time.steps`` + 1."""
        steps = self.time.steps
        if steps is None:                   # not after reading: a scene stores the number
            steps = self.load.default_steps()
        return self.load.instants(steps)


def _file_digest(path) -> str:
    """'sha256:' and the hex digest of a file's content."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return "sha256:" + h.hexdigest()


#: A multi-line array of tomli_w whose items are numbers or inline arrays of numbers.
_ARRAY = re.compile(r"\[\n((?:[ \t]*(?:[^\[\]\n]|\[[^\[\]\n]*\])*,\n)+)[ \t]*\]")


def _compact_arrays(text: str) -> str:
    """tomli_w writes one array item a line; put arrays of numbers on one line."""
    def inline(m):
        return "[" + ", ".join(item.strip().rstrip(",") for item in m.group(1).splitlines()) + "]"

    while True:
        new = _ARRAY.sub(inline, text)
        if new == text:
            return text
        text = new
