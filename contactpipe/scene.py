"""The scene: one simulation, frozen and validated on construction, TOML in and out.

A :class:`Scene` holds the parts of a scene file (CONTRACT §2) as frozen dataclasses:
:class:`Geometry`, two :class:`BodySpec` (``indenter`` = body 1, ``halfspace`` = body 2),
:class:`Friction`, :class:`Load` (with an optional :class:`Fretting` preset),
:class:`Grid`, :class:`TimeMesh`, :class:`Solver` and :class:`Output`.

Construction validates everything and raises one :class:`~contactpipe.SceneError`
listing *every* problem found; each message names the dotted field, the value given
and what is allowed::

    scene = Scene.from_toml("scene.toml")     # or Scene(**nested_dict), Scene.from_dict
    scene.to_dict()                            # complete, defaults resolved, plain types
    scene.to_toml()                            # TOML text that reads back equal
    scene.digest()                             # 16 hex chars identifying the simulation
    scene.replace({"friction.mu": 0.2, "load.fretting.window": 2.0})

Extensions to the contract's format (documented here, never contradicting it):

- ``creep = "tabulated"`` with ``table = [[t, phi], ...]``: ascending times [s] starting
  at t = 0, phi >= 0 non-decreasing, > 0 after t = 0 (phi(0) = 0 models a body without
  instantaneous elasticity, like Kelvin-Voigt). ``young`` is the modulus phi is
  normalised by.
- ``[load.fretting]``: a fretting-loop preset (see :class:`Fretting`) that replaces
  ``load.time`` and ``load.tangential_force``.
- ``geometry.height`` for a flat punch (gap outside the flat end, default the radius).
- ``grid.size = "auto"``: a side from a Hertz estimate (:meth:`Scene.resolved_grid_size`).
- ``[solver]`` and ``[output]`` options beyond ``tolerance`` (see :class:`Solver`,
  :class:`Output`).

TOML has no null: keys whose value is ``None`` (e.g. ``solver.accuracy``) are left out of
:meth:`Scene.to_dict`, and ``None`` given for a key means "absent".

Units: SI (m, s, N, Pa) everywhere.
"""
from __future__ import annotations

import dataclasses
import difflib
import hashlib
import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np
import tomli_w

from . import geometry as _geometry
from . import materials
from .exceptions import SceneError
from .files import loads_toml

__all__ = ["Scene", "Geometry", "BodySpec", "Friction", "Load", "Fretting", "Grid",
           "TimeMesh", "Solver", "Output", "SceneError"]

SHAPES = ("sphere", "ellipsoid", "flat_punch", "surface")
MATERIALS = ("rigid", "elastic", "viscoelastic")
CREEP_MODELS = ("maxwell", "kelvin_voigt", "zener", "prony", "tabulated")
PRELOADS = ("frictional", "frictionless")
TIME_RULES = ("linear", "step_start")
TANGENTIAL_MODELS = ("auto", "scalar", "vector")
FFT_BACKENDS = ("auto", "pyfftw", "scipy")
ACCURACIES = ("fast", "balanced", "accurate")
PRECISIONS = ("float64", "float32")
MIN_POINTS, MAX_POINTS = 8, 4096
MAX_TOLERANCE = 1e-2
MAX_CYCLES = 100_000

#: Keys each shape requires and allows.
_SHAPE_KEYS = {
    "sphere": (("radius",), ()),
    "ellipsoid": (("radii",), ()),
    "flat_punch": (("radius",), ("height",)),
    "surface": (("file",), ()),
}
_GEOMETRY_KEYS = ("shape", "radius", "radii", "file", "height")

#: Keys each creep model requires and allows (CONTRACT §2 table, plus ``tabulated``).
_CREEP_KEYS = {
    "maxwell": (("relaxation_time",), ()),
    "kelvin_voigt": (("retardation_time",), ()),
    "zener": (("relaxed_young", "retardation_time"), ()),
    "prony": (("terms",), ("relaxation_time",)),
    "tabulated": (("table",), ()),
}
_MODEL_KEYS = ("relaxation_time", "retardation_time", "relaxed_young", "terms", "table")
_BODY_KEYS = ("material", "young", "poisson", "creep") + _MODEL_KEYS

#: Hertz margin of ``grid.size = "auto"``: side = 2 * margin * contact radius.
AUTO_MARGIN = 1.5
#: ``grid.size = "auto"`` for a flat punch: side = this times the punch radius.
AUTO_PUNCH_FACTOR = 2.5

_MISSING = object()


# ----------------------------------------------------------------------------- helpers

def _show(v, typed=False) -> str:
    """A value as given, for an error message; ``typed`` points out a string or a
    boolean given where a number is needed."""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if typed and isinstance(v, (bool, np.bool_)):
        return f"{v!r} (a boolean)"
    if typed and isinstance(v, str):
        return f"{v!r} (a string)"
    s = repr(v)
    return s if len(s) <= 80 else s[:77] + "..."


def _is_number(v) -> bool:
    return (isinstance(v, (int, float, np.integer, np.floating))
            and not isinstance(v, (bool, np.bool_)))


def _is_integer(v) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))


def _to_float(v):
    """float(v) for a number (-0.0 read as 0.0), inf when too large for a float."""
    try:
        return float(v) + 0.0
    except OverflowError:
        return math.inf


def _is_sequence(v) -> bool:
    return isinstance(v, (list, tuple)) or (isinstance(v, np.ndarray) and v.ndim >= 1)


def _as_list(v) -> list:
    return v.tolist() if isinstance(v, np.ndarray) else list(v)


def _positive(x):
    return x > 0


def _plain(v):
    """Tuples -> lists, recursively (TOML and JSON want lists)."""
    if isinstance(v, (tuple, list)):
        return [_plain(x) for x in v]
    return v


def _fields(obj) -> dict:
    return {f.name: getattr(obj, f.name) for f in fields(obj)}


def _make(cls, **values):
    """An instance of a frozen dataclass from already validated values (no re-check)."""
    obj = object.__new__(cls)
    for f in fields(cls):
        object.__setattr__(obj, f.name, values.get(f.name))
    return obj


def _validate_self(obj, reader, path):
    """Validate a part constructed directly (``Geometry(...)``) and normalise it."""
    problems = []
    new = reader(_fields(obj), path, problems)
    if problems or new is None:
        raise SceneError(problems or [f"{path}: invalid"])
    for f in fields(obj):
        object.__setattr__(obj, f.name, getattr(new, f.name))


def _section_dict(obj) -> dict:
    """A part as a plain dict without its ``None`` values."""
    out = {}
    for k, v in _fields(obj).items():
        if v is None:
            continue
        out[k] = v.to_dict() if dataclasses.is_dataclass(v) else _plain(v)
    return out


class _Reader:
    """Reads one table of a scene, appending a message per problem to ``problems``."""

    def __init__(self, raw, path, problems):
        self.raw = {k: v for k, v in raw.items() if v is not None}
        self.path = path
        self.problems = problems
        self.ok = True

    def key(self, k) -> str:
        return f"{self.path}.{k}" if self.path else str(k)

    def add(self, message: str):
        self.problems.append(message)
        self.ok = False

    def has(self, k) -> bool:
        return k in self.raw

    def check_keys(self, allowed):
        for k in self.raw:
            if k in allowed:
                continue
            close = difflib.get_close_matches(str(k), allowed, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            self.add(f"unknown key {self.key(k)!r}{hint}; allowed keys in [{self.path}]: "
                     f"{', '.join(allowed)}")

    def missing(self, k, need, what):
        self.add(f"{self.key(k)} is required{need}: {what}")

    def forbid(self, k, why):
        if k in self.raw:
            self.add(f"{self.key(k)} = {_show(self.raw[k])} is not used {why}; remove it")

    def number(self, k, what, ok=lambda x: True, need=None, default=None):
        """A finite float; ``need`` is None (optional) or the 'required ...' context."""
        v = self.raw.get(k, _MISSING)
        if v is _MISSING:
            if need is not None:
                self.missing(k, need, what)
            return default
        x = _to_float(v) if _is_number(v) else None
        if x is None or not math.isfinite(x) or not ok(x):
            self.add(f"{self.key(k)} must be {what}, got {_show(v, typed=True)}")
            return None
        return x

    def integer(self, k, what, ok=lambda n: True, need=None, default=None):
        v = self.raw.get(k, _MISSING)
        if v is _MISSING:
            if need is not None:
                self.missing(k, need, what)
            return default
        if not _is_integer(v) or not ok(int(v)):
            self.add(f"{self.key(k)} must be {what}, got {_show(v, typed=True)}")
            return None
        return int(v)

    def choice(self, k, options, need=None, default=None):
        what = "one of " + ", ".join(repr(o) for o in options)
        v = self.raw.get(k, _MISSING)
        if v is _MISSING:
            if need is not None:
                self.missing(k, need, what)
            return default
        if not isinstance(v, str) or v not in options:
            self.add(f"{self.key(k)} must be {what}, got {_show(v)}")
            return None
        return v

    def numbers(self, k, what, need=None, ok=lambda x: True):
        """A list of finite floats, as a tuple."""
        v = self.raw.get(k, _MISSING)
        if v is _MISSING:
            if need is not None:
                self.missing(k, need, what)
            return None
        if not _is_sequence(v):
            self.add(f"{self.key(k)} must be {what}, got {_show(v, typed=True)}")
            return None
        items = _as_list(v)
        vals = [_to_float(x) if _is_number(x) else None for x in items]
        if any(x is None or not math.isfinite(x) or not ok(x) for x in vals):
            self.add(f"{self.key(k)} must be {what}, got {_show(v)}")
            return None
        return tuple(vals)

    def pairs(self, k, what, need=None):
        """A non-empty list of [a, b] pairs of finite floats, as a tuple of tuples."""
        v = self.raw.get(k, _MISSING)
        if v is _MISSING:
            if need is not None:
                self.missing(k, need, what)
            return None
        rows = _as_list(v) if _is_sequence(v) else None
        good = rows is not None and len(rows) > 0
        out = []
        for row in rows or ():
            if not (_is_sequence(row) and len(row) == 2 and all(_is_number(x) for x in row)):
                good = False
                break
            a, b = (_to_float(x) for x in row)
            if not (math.isfinite(a) and math.isfinite(b)):
                good = False
                break
            out.append((a, b))
        if not good:
            self.add(f"{self.key(k)} must be {what}, got {_show(v, typed=True)}")
            return None
        return tuple(out)


def _table(value, path, cls, required, problems, what):
    """The raw dict of one table: from a dict, a part instance, or absent."""
    if value is None:
        if required:
            problems.append(f"{path} is required: a table [{path}] with {what}")
            return None
        return {}
    if isinstance(value, cls):
        return _fields(value)
    if isinstance(value, Mapping):
        return dict(value)
    problems.append(f"{path} must be a table (dict) with {what}, got {_show(value)}")
    return None


# ----------------------------------------------------------------------------- geometry

def _read_geometry(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(_GEOMETRY_KEYS)
    shape = r.choice("shape", SHAPES, need="")
    if shape is None:
        return None
    req, opt = _SHAPE_KEYS[shape]
    takes = ", ".join(req + opt)
    for k in _GEOMETRY_KEYS[1:]:
        if k not in req + opt:
            r.forbid(k, f"by shape = {shape!r} (it takes: {takes})")
    radius = radii = file = height = None
    ctx = f" for shape = {shape!r}"
    if "radius" in req:
        radius = r.number("radius", "a finite number > 0 [m]", _positive, need=ctx)
    if "height" in opt:
        height = r.number("height", "a finite number > 0 [m]", _positive)
        if height is None and not r.has("height"):
            height = radius
    if "radii" in req:
        radii = r.numbers("radii", "two finite numbers > 0 [m], [R1, R2] along x1, x2",
                          need=ctx, ok=_positive)
        if radii is not None and len(radii) != 2:
            r.add(f"{r.key('radii')} must be two finite numbers > 0 [m], [R1, R2] along "
                  f"x1, x2, got {_show(raw['radii'])}")
            radii = None
    if "file" in req:
        v = r.raw.get("file", _MISSING)
        what = "the path of a netCDF file (variable 'gap' over x1, x2 [m]) or a .npy array"
        if v is _MISSING:
            r.missing("file", ctx, what)
        elif not isinstance(v, (str, os.PathLike)) or not os.fspath(v):
            r.add(f"{r.key('file')} must be {what}, got {_show(v)}")
        else:
            file = os.path.abspath(os.path.expanduser(os.fspath(v)))
            bad = _geometry.check_surface(file)
            for msg in bad:
                r.add(msg)
    if not r.ok:
        return None
    return _make(Geometry, shape=shape, radius=radius, radii=radii, file=file, height=height)


@dataclass(frozen=True)
class Geometry:
    """Composite initial gap of the two bodies; first contact at the origin.

    Parameters
    ----------
    shape : {"sphere", "ellipsoid", "flat_punch", "surface"}
    radius : float, optional
        Sphere radius, or radius of the flat punch's end [m].
    radii : (float, float), optional
        Ellipsoid principal radii (R1 along x1, R2 along x2) [m].
    file : str, optional
        Surface file (netCDF variable ``gap`` over x1, x2, or a ``.npy`` on the grid);
        stored as an absolute path.
    height : float, optional
        Flat punch only: gap outside the flat end [m]; default the radius.
    """

    shape: str
    radius: float | None = None
    radii: tuple | None = None
    file: str | None = None
    height: float | None = None

    def __post_init__(self):
        _validate_self(self, _read_geometry, "geometry")

    def gap(self, x1, x2):
        """Initial gap (N1, N2) [m] at the cell centres ``x1`` (N1,), ``x2`` (N2,) [m]."""
        if self.shape == "sphere":
            return _geometry.sphere_gap(x1, x2, self.radius)
        if self.shape == "ellipsoid":
            return _geometry.ellipsoid_gap(x1, x2, self.radii)
        if self.shape == "flat_punch":
            return _geometry.flat_punch_gap(x1, x2, self.radius, self.height)
        return _geometry.surface_gap(x1, x2, self.file)

    def to_dict(self) -> dict:
        return _section_dict(self)


# ----------------------------------------------------------------------------- bodies

def _read_body(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(_BODY_KEYS)
    material = r.choice("material", MATERIALS, need="")
    if material is None:
        return None
    if material == "rigid":
        for k in _BODY_KEYS[1:]:
            r.forbid(k, "by a rigid body (material = 'rigid' takes no constants)")
        return _make(BodySpec, material="rigid") if r.ok else None
    ctx = f" for material = {material!r}"
    young = r.number("young", "a finite number > 0 [Pa]", _positive, need=ctx)
    poisson = r.number("poisson", "a number in [0, 0.5]", lambda x: 0.0 <= x <= 0.5,
                       need=ctx)
    if material == "elastic":
        for k in ("creep",) + _MODEL_KEYS:
            r.forbid(k, "by an elastic body (creep keys need material = 'viscoelastic')")
        if not r.ok:
            return None
        return _make(BodySpec, material="elastic", young=young, poisson=poisson)
    creep = r.choice("creep", CREEP_MODELS, need=ctx)
    if creep is None:
        return None
    req, opt = _CREEP_KEYS[creep]
    for k in _MODEL_KEYS:
        if k not in req + opt:
            r.forbid(k, f"by creep = {creep!r} (it takes: {', '.join(req + opt)})")
    ctx = f" for creep = {creep!r}"
    vals = {}
    for k, what in (("relaxation_time", "t' = eta / G, a finite number > 0 [s]"),
                    ("retardation_time", "tau, a finite number > 0 [s]"),
                    ("relaxed_young", "E_inf, a finite number > 0 [Pa] below young")):
        if k in req + opt:
            vals[k] = r.number(k, what, _positive, need=ctx if k in req else None)
    if creep == "zener" and young is not None and vals.get("relaxed_young") is not None:
        if vals["relaxed_young"] >= young:
            r.add(f"{r.key('relaxed_young')} must be below {r.key('young')} = {young:g} Pa "
                  f"(the relaxed modulus E_inf < the instantaneous E0), got "
                  f"{vals['relaxed_young']:g}")
    if creep == "prony":
        what = "a non-empty list of [c, tau] pairs with c > 0 and tau > 0 [s]"
        terms = r.pairs("terms", what, need=ctx)
        if terms is not None and not all(c > 0 and t > 0 for c, t in terms):
            r.add(f"{r.key('terms')} must be {what}, got {_show(raw['terms'])}")
            terms = None
        vals["terms"] = terms
    if creep == "tabulated":
        vals["table"] = _check_table(r, ctx)
    if not r.ok:
        return None
    return _make(BodySpec, material="viscoelastic", young=young, poisson=poisson,
                 creep=creep, **vals)


def _check_table(r, ctx):
    what = ("a list of at least 2 [t, phi] rows: t [s] ascending from 0, phi [1] "
            "non-decreasing, > 0 after t = 0")
    table = r.pairs("table", what, need=ctx)
    if table is None:
        return None
    key = r.key("table")
    t = [row[0] for row in table]
    phi = [row[1] for row in table]
    before = len(r.problems)
    if len(table) < 2:
        r.add(f"{key} must be {what}, got {len(table)} row")
    if t[0] != 0.0:
        r.add(f"{key} must start at t = 0, got t = {t[0]:g} s in its first row")
    if any(b <= a for a, b in zip(t, t[1:])):
        r.add(f"{key} times must be strictly ascending, got t = {_show(t)}")
    if any(b < a for a, b in zip(phi, phi[1:])):
        r.add(f"{key} phi must not decrease (a creep function grows with time), "
              f"got phi = {_show(phi)}")
    if phi[0] < 0 or any(p <= 0 for p in phi[1:]):
        r.add(f"{key} phi must be > 0 (it may be 0 at t = 0 only), got phi = {_show(phi)}")
    return table if len(r.problems) == before else None


@dataclass(frozen=True)
class BodySpec:
    """One body's material, as the scene file gives it.

    Parameters
    ----------
    material : {"rigid", "elastic", "viscoelastic"}
        A rigid body takes no constants.
    young : float
        Young modulus [Pa]: the instantaneous (glassy) one for a viscoelastic body, the
        long-term one for Kelvin-Voigt, the one phi is normalised by for a table.
    poisson : float
        Poisson ratio [1], in [0, 0.5]; constant in time.
    creep : {"maxwell", "kelvin_voigt", "zener", "prony", "tabulated"}
        Viscoelastic only; each model takes exactly its keys (CONTRACT §2 table).
    relaxation_time : float
        t' [s] (maxwell; optional dashpot of prony).
    retardation_time : float
        tau [s] (kelvin_voigt, zener).
    relaxed_young : float
        E_inf < young [Pa] (zener).
    terms : tuple of (c, tau)
        Prony terms, c > 0 [1], tau > 0 [s].
    table : tuple of (t, phi)
        Tabulated phi(t): t [s] ascending from 0, phi non-decreasing, > 0 after t = 0.
    """

    material: str
    young: float | None = None
    poisson: float | None = None
    creep: str | None = None
    relaxation_time: float | None = None
    retardation_time: float | None = None
    relaxed_young: float | None = None
    terms: tuple | None = None
    table: tuple | None = None

    def __post_init__(self):
        _validate_self(self, _read_body, "body")

    def creep_function(self):
        """The normalised creep function phi(t) (:data:`materials.ELASTIC` if none)."""
        if self.material != "viscoelastic":
            return materials.ELASTIC
        if self.creep == "maxwell":
            return materials.maxwell(self.relaxation_time)
        if self.creep == "kelvin_voigt":
            return materials.kelvin_voigt(self.retardation_time)
        if self.creep == "zener":
            return materials.zener(self.young, self.relaxed_young, self.retardation_time)
        if self.creep == "prony":
            return materials.prony(self.terms, self.relaxation_time)
        t, phi = zip(*self.table)
        return materials.TabulatedCreep(t=tuple(t), phi=tuple(phi))

    def body(self) -> materials.Body:
        """The :class:`materials.Body` this spec describes."""
        if self.material == "rigid":
            return materials.Body(kind="rigid")
        return materials.Body(kind=self.material, young=self.young, poisson=self.poisson,
                              creep=self.creep_function())

    def to_dict(self) -> dict:
        return _section_dict(self)


# ----------------------------------------------------------------------------- friction

def _read_friction(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(("mu",))
    mu = r.number("mu", "a finite number >= 0", lambda x: x >= 0, default=0.0)
    return _make(Friction, mu=mu) if r.ok else None


@dataclass(frozen=True)
class Friction:
    """Coulomb friction between the bodies.

    Parameters
    ----------
    mu : float
        Friction coefficient [1], >= 0; 0 (the default) is frictionless.
    """

    mu: float = 0.0

    def __post_init__(self):
        _validate_self(self, _read_friction, "friction")

    def to_dict(self) -> dict:
        return _section_dict(self)


# ----------------------------------------------------------------------------- load

def _read_fretting(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(("amplitude", "cycles", "window", "direction"))
    amplitude = r.number("amplitude", "T*, a finite number > 0 [N]", _positive, need="")
    window = r.number("window", "tau, the total duration, a finite number > 0 [s]",
                      _positive, need="")
    cycles = r.integer("cycles", f"an integer from 1 to {MAX_CYCLES}",
                       lambda n: 1 <= n <= MAX_CYCLES, default=1)
    direction = r.number("direction", "the angle of T from x1, a finite number [deg]",
                         default=0.0)
    if not r.ok:
        return None
    return _make(Fretting, amplitude=amplitude, window=window, cycles=cycles,
                 direction=direction)


@dataclass(frozen=True)
class Fretting:
    """Fretting-loop preset of the load (``[load.fretting]``).

    The tangential force goes 0 -> +T* -> -T* -> +T* ... at a constant rate under a
    normal force applied as a step at t = 0. Rising to +T* takes one time unit and each
    half cycle two, so ``cycles`` = n takes 1 + 4 n units over ``window``: knots at units
    0, 1, 3, 5, ..., 1 + 4 n. One cycle gives time = [0, tau/5, 3 tau/5, tau] and
    T = [0, T*, -T*, T*].

    Parameters
    ----------
    amplitude : float
        T* [N], > 0.
    window : float
        tau, the total duration [s], > 0.
    cycles : int
        Number of full cycles (-T* and back to +T*), >= 1.
    direction : float
        Angle of the tangential force from x1 [deg]; T1 = T cos, T2 = T sin.
    """

    amplitude: float
    window: float
    cycles: int = 1
    direction: float = 0.0

    def __post_init__(self):
        _validate_self(self, _read_fretting, "load.fretting")

    def knots(self):
        """(time [s], T [N]) at the knots, T signed along ``direction``."""
        units = 1 + 4 * self.cycles
        u = np.array([0] + [1 + 2 * k for k in range(2 * self.cycles + 1)], dtype=float)
        t = u * self.window / units
        T = np.array([0.0] + [self.amplitude * (-1.0) ** k
                              for k in range(2 * self.cycles + 1)])
        return t, T

    def unit_vector(self):
        """(cos, sin) of ``direction``, exact on the axes."""
        a = math.radians(self.direction)
        c, s = math.cos(a), math.sin(a)
        c = 0.0 if abs(c) < 1e-15 else c
        s = 0.0 if abs(s) < 1e-15 else s
        return c, s

    def to_dict(self) -> dict:
        return _section_dict(self)


def _read_load(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(("time", "normal_force", "tangential_force", "preload", "fretting"))
    preload = r.choice("preload", PRELOADS, default="frictional")
    fretting = time = None
    n = None  # number of knots, when known
    if r.has("fretting"):
        fp = f"{path}.fretting"
        ft = _table(r.raw["fretting"], fp, Fretting, True, problems,
                    "amplitude [N], window [s], cycles, direction [deg]")
        fretting = None if ft is None else _read_fretting(ft, fp, problems)
        if fretting is None:
            r.ok = False
        else:
            n = 2 * fretting.cycles + 2
        for k in ("time", "tangential_force"):
            if r.has(k):
                r.add(f"{r.key(k)} = {_show(r.raw[k])} cannot be given with {fp}: the "
                      f"preset makes the time program and the tangential force; remove "
                      f"one of them")
    else:
        what = "a list of at least 1 strictly increasing times [s]"
        time = r.numbers("time", what, need=" (or a [load.fretting] preset)")
        if time is not None and len(time) < 1:
            r.add(f"{r.key('time')} must be {what}, got []")
            time = None
        elif time is not None:
            bad = [i for i in range(1, len(time)) if time[i] <= time[i - 1]]
            if bad:
                i = bad[0]
                r.add(f"{r.key('time')} must be strictly increasing, got {_show(list(time))} "
                      f"(time[{i}] = {time[i]:g} s <= time[{i - 1}] = {time[i - 1]:g} s)")
                time = None
            else:
                n = len(time)
    # normal force: a scalar step, or one value per knot
    key = r.key("normal_force")
    what = ("a force >= 0 [N] (a step at time[0]) or a list with one force >= 0 [N] "
            "per load.time knot")
    v = r.raw.get("normal_force", _MISSING)
    normal = None
    if v is _MISSING:
        r.missing("normal_force", "", what)
    elif _is_number(v):
        x = _to_float(v)
        if not math.isfinite(x) or x < 0:
            r.add(f"{key} must be {what}, got {_show(v, typed=True)}")
        elif x == 0:
            r.add(f"{key} = {_show(v)}: zero normal force leaves nothing in contact; give "
                  f"a force > 0 [N]")
        else:
            normal = x
    elif _is_sequence(v) and fretting is None and not r.has("fretting"):
        normal = r.numbers("normal_force", what, ok=lambda x: x >= 0)
        if normal is not None:
            if n is not None and len(normal) != n:
                r.add(f"{key} has {len(normal)} values but load.time has {n} knots: give "
                      f"one value per knot, or a scalar (a step at time[0])")
                normal = None
            elif not any(x > 0 for x in normal):
                r.add(f"{key} is zero at every knot, got {_show(v)}: nothing is in contact; "
                      f"give a force > 0 [N]")
                normal = None
    elif _is_sequence(v):
        r.add(f"{key} must be a scalar (a step at t = 0) with {path}.fretting, got {_show(v)}")
    else:
        r.add(f"{key} must be {what}, got {_show(v, typed=True)}")
    # tangential force: forces along x1, or [T1, T2] pairs, one per knot
    tangential = None
    if r.has("tangential_force") and not r.has("fretting"):
        v = r.raw["tangential_force"]
        key = r.key("tangential_force")
        what = ("a list of forces [N] along x1 or a list of [T1, T2] pairs [N], one per "
                "load.time knot")
        items = _as_list(v) if _is_sequence(v) else None
        if items is not None and items and all(_is_number(x) for x in items):
            tangential = r.numbers("tangential_force", what)
        elif items is not None and items and all(_is_sequence(x) for x in items):
            tangential = r.pairs("tangential_force", what)
        else:
            r.add(f"{key} must be {what}, got {_show(v, typed=True)}")
        if tangential is not None and n is not None and len(tangential) != n:
            r.add(f"{key} has {len(tangential)} values but load.time has {n} knots: give "
                  f"one value per knot")
            tangential = None
    if not r.ok:
        return None
    return _make(Load, time=time, normal_force=normal, tangential_force=tangential,
                 preload=preload, fretting=fretting)


@dataclass(frozen=True)
class Load:
    """The load program, piecewise linear through knots.

    Parameters
    ----------
    time : tuple of float
        Knot times [s], strictly increasing (at least one). Absent (None) with
        ``fretting``: read the program through :meth:`knots` / :meth:`instants`, which
        serve both forms.
    normal_force : float or tuple of float
        W [N]: a scalar is a step applied at time[0] (W = value at every instant,
        time[0] included); a list gives one value per knot.
    tangential_force : tuple, optional
        T [N] per knot: floats along x1 (T2 = 0), or (T1, T2) pairs. Absent: none.
    preload : {"frictional", "frictionless"}
        Whether friction acts during the normal preload.
    fretting : Fretting, optional
        A fretting-loop preset instead of ``time`` and ``tangential_force``.
    """

    time: tuple | None = None
    normal_force: float | tuple | None = None
    tangential_force: tuple | None = None
    preload: str = "frictional"
    fretting: Fretting | None = None

    def __post_init__(self):
        _validate_self(self, _read_load, "load")

    @property
    def step_load(self) -> bool:
        """True when the normal force is a scalar step at time[0]."""
        return not isinstance(self.normal_force, tuple)

    def knots(self):
        """The program at its knots: (time [s], W [N], T1 [N], T2 [N]) float arrays."""
        if self.fretting is not None:
            t, T = self.fretting.knots()
            c, s = self.fretting.unit_vector()
            T1, T2 = T * c, T * s
        else:
            t = np.array(self.time, dtype=float)
            tf = self.tangential_force
            if tf is None:
                T1 = np.zeros_like(t)
                T2 = np.zeros_like(t)
            elif isinstance(tf[0], tuple):
                T1 = np.array([p[0] for p in tf], dtype=float)
                T2 = np.array([p[1] for p in tf], dtype=float)
            else:
                T1 = np.array(tf, dtype=float)
                T2 = np.zeros_like(t)
        if self.step_load:
            W = np.full(t.shape, self.normal_force, dtype=float)
        else:
            W = np.array(self.normal_force, dtype=float)
        return t, W, T1, T2

    def instants(self, steps: int):
        """The program on the uniform mesh of ``steps`` + 1 instants from time[0] to
        time[-1], interpolated linearly between knots: (t [s], W [N], T1 [N], T2 [N])."""
        t, W, T1, T2 = self.knots()
        tm = np.linspace(t[0], t[-1], int(steps) + 1)
        return tm, np.interp(tm, t, W), np.interp(tm, t, T1), np.interp(tm, t, T2)

    @property
    def window(self) -> float:
        """Duration of the program, time[-1] - time[0] [s]."""
        t = self.knots()[0]
        return float(t[-1] - t[0])

    def to_dict(self) -> dict:
        return _section_dict(self)


# ----------------------------------------------------------------------------- grid, time

def _read_grid(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(("points", "size"))
    points = size = None
    what = f"two integers [N1, N2], each from {MIN_POINTS} to {MAX_POINTS}"
    v = r.raw.get("points", _MISSING)
    if v is _MISSING:
        r.missing("points", "", what)
    elif (_is_sequence(v) and len(_as_list(v)) == 2
          and all(_is_integer(x) and MIN_POINTS <= x <= MAX_POINTS for x in _as_list(v))):
        points = tuple(int(x) for x in _as_list(v))
    else:
        r.add(f"{r.key('points')} must be {what}, got {_show(v, typed=True)}")
    what = "two finite numbers > 0 [m], [L1, L2] the full side lengths, or 'auto'"
    v = r.raw.get("size", _MISSING)
    if v is _MISSING:
        r.missing("size", "", what)
    elif isinstance(v, str) and v == "auto":
        size = "auto"
    else:
        size = r.numbers("size", what, ok=_positive)
        if size is not None and len(size) != 2:
            r.add(f"{r.key('size')} must be {what}, got {_show(v, typed=True)}")
            size = None
    if not r.ok:
        return None
    return _make(Grid, points=points, size=size)


@dataclass(frozen=True)
class Grid:
    """The computational grid on the common plane, centred on the first contact point.

    Parameters
    ----------
    points : (int, int)
        Cells (N1, N2) along x1, x2, each from 8 to 4096.
    size : (float, float) or "auto"
        Full side lengths (L1, L2) [m], or "auto" for a Hertz estimate
        (:meth:`Scene.resolved_grid_size`).
    """

    points: tuple
    size: tuple | str

    def __post_init__(self):
        _validate_self(self, _read_grid, "grid")

    def _size(self):
        if self.size == "auto":
            raise SceneError("grid.size is 'auto': the grid alone cannot size itself; use "
                             "Scene.resolved_grid() or give grid.size = [L1, L2] in m")
        return self.size

    def spacing(self):
        """Cell sizes (d1, d2) = (L1/N1, L2/N2) [m]."""
        L1, L2 = self._size()
        return L1 / self.points[0], L2 / self.points[1]

    def coordinates(self):
        """Cell centres (x1 (N1,), x2 (N2,)) [m]: x = -L/2 + (i + 1/2) L/N, ascending."""
        return tuple(-L / 2 + (np.arange(N) + 0.5) * (L / N)
                     for N, L in zip(self.points, self._size()))

    def to_dict(self) -> dict:
        return _section_dict(self)


def _read_time(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(("steps",))
    steps = r.integer("steps", "an integer >= 1 (0 only for a single-knot load)",
                      lambda n: n >= 0)
    return _make(TimeMesh, steps=steps) if r.ok else None


@dataclass(frozen=True)
class TimeMesh:
    """The uniform temporal mesh: ``steps`` + 1 instants from time[0] to time[-1].

    Parameters
    ----------
    steps : int, optional
        Number of steps, >= 1. Absent: one step per load-knot interval (a scene stores
        the resolved number; 0 for a single-knot load, a single instant).
    """

    steps: int | None = None

    def __post_init__(self):
        _validate_self(self, _read_time, "time")

    def to_dict(self) -> dict:
        return _section_dict(self)


# ----------------------------------------------------------------------------- solver, output

def _read_solver(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(("tolerance", "max_iterations", "time_rule", "tangential",
                  "max_coupling_passes", "preload_substeps", "fft", "threads", "accuracy"))
    at_least_1 = "an integer >= 1"
    one = lambda n: n >= 1  # noqa: E731
    v = dict(
        tolerance=r.number("tolerance", f"a number in (0, {MAX_TOLERANCE:g}]",
                           lambda x: 0 < x <= MAX_TOLERANCE, default=1e-9),
        max_iterations=r.integer("max_iterations", at_least_1, one, default=2000),
        time_rule=r.choice("time_rule", TIME_RULES, default="linear"),
        tangential=r.choice("tangential", TANGENTIAL_MODELS, default="auto"),
        max_coupling_passes=r.integer("max_coupling_passes", at_least_1, one, default=100),
        preload_substeps=r.integer("preload_substeps", at_least_1, one, default=8),
        fft=r.choice("fft", FFT_BACKENDS, default="auto"),
        threads=r.integer("threads", at_least_1, one, default=1),
        accuracy=r.choice("accuracy", ACCURACIES, default=None),
    )
    return _make(Solver, **v) if r.ok else None


@dataclass(frozen=True)
class Solver:
    """Solver options.

    Parameters
    ----------
    tolerance : float
        Relative tolerance on the force balance and complementarity, in (0, 1e-2].
    max_iterations : int
        Iteration cap of each inner solve, >= 1.
    time_rule : {"linear", "step_start"}
        Traction within a time step in the viscoelastic history: linear (second order)
        or applied at the step start (the paper's rectangle rule; not for phi(0) = 0).
    tangential : {"auto", "scalar", "vector"}
        Tangential model: chosen from the scene, q2 = 0 (Cattaneo-Mindlin), or both.
    max_coupling_passes : int
        Cap on the normal <-> tangential passes of the middle loop, >= 1.
    preload_substeps : int
        Substeps of the normal preload, >= 1.
    fft : {"auto", "pyfftw", "scipy"}
    threads : int
        FFT threads, >= 1.
    accuracy : {None, "fast", "balanced", "accurate"}
        Ask for an accuracy preset: the grid points and time steps are then chosen by
        :func:`contactpipe.accuracy.resolve_accuracy` (replacing ``grid.points`` and
        ``time.steps``) and the choice is recorded in the archive.
    """

    tolerance: float = 1e-9
    max_iterations: int = 2000
    time_rule: str = "linear"
    tangential: str = "auto"
    max_coupling_passes: int = 100
    preload_substeps: int = 8
    fft: str = "auto"
    threads: int = 1
    accuracy: str | None = None

    def __post_init__(self):
        _validate_self(self, _read_solver, "solver")

    def to_dict(self) -> dict:
        return _section_dict(self)


def _read_output(raw, path, problems):
    r = _Reader(raw, path, problems)
    r.check_keys(("stride", "precision", "compress"))
    stride = r.integer("stride", "an integer >= 1", lambda n: n >= 1, default=1)
    precision = r.choice("precision", PRECISIONS, default="float64")
    compress = r.raw.get("compress", True)
    if not isinstance(compress, (bool, np.bool_)):
        r.add(f"{r.key('compress')} must be true or false, got {_show(compress)}")
    if not r.ok:
        return None
    return _make(Output, stride=stride, precision=precision, compress=bool(compress))


@dataclass(frozen=True)
class Output:
    """Archive options (they change the file, not the physics; not in the digest).

    Parameters
    ----------
    stride : int
        Store every ``stride``-th instant, >= 1.
    precision : {"float64", "float32"}
        Storage type of the fields.
    compress : bool
        zlib compression of the archive.
    """

    stride: int = 1
    precision: str = "float64"
    compress: bool = True

    def __post_init__(self):
        _validate_self(self, _read_output, "output")

    def to_dict(self) -> dict:
        return _section_dict(self)


# ----------------------------------------------------------------------------- scene

#: (key, class, reader, required, what the table holds) of each part, in file order.
_PARTS = (
    ("geometry", Geometry, _read_geometry, True, "shape = " + " | ".join(SHAPES)),
    ("indenter", BodySpec, _read_body, True, "material = " + " | ".join(MATERIALS)),
    ("halfspace", BodySpec, _read_body, True, "material = " + " | ".join(MATERIALS)),
    ("friction", Friction, _read_friction, False, "mu"),
    ("load", Load, _read_load, True, "time [s], normal_force [N], ..."),
    ("grid", Grid, _read_grid, True, "points = [N1, N2], size = [L1, L2] [m]"),
    ("time", TimeMesh, _read_time, False, "steps"),
    ("solver", Solver, _read_solver, False, "solver options"),
    ("output", Output, _read_output, False, "stride, precision, compress"),
)
_TOP_KEYS = ("name",) + tuple(p[0] for p in _PARTS)


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


def _hertz_size(geometry, indenter, halfspace, load):
    """Grid side lengths (L1, L2) [m] from a Hertz estimate of the largest contact.

    Sphere / ellipsoid: a = (3 W_max R / (4 E*))^(1/3) with 1/E* = sum over the bodies of
    phi_max (1 - nu^2) / E, E the instantaneous (glassy) modulus and phi_max the largest
    (most compliant) creep factor over the load window; side = 2 * 1.5 * a. For an
    ellipsoid, the semi-axes follow from the equivalent radius sqrt(R1 R2) as
    a_i = a (R_i / sqrt(R1 R2))^(2/3), whose axis ratio (R1/R2)^(2/3) is within 4 % of
    exact Hertz theory for R1/R2 <= 10.
    Flat punch: 2.5 radius. Surface: None (no estimate).
    """
    if geometry.shape == "surface":
        return None
    if geometry.shape == "flat_punch":
        side = AUTO_PUNCH_FACTOR * geometry.radius
        return side, side
    t, W, _, _ = load.knots()
    window = float(t[-1] - t[0])
    b1, b2 = indenter.body(), halfspace.body()
    phi = [b.creep.max_over(window) if b.kind == "viscoelastic" else 1.0 for b in (b1, b2)]
    with np.errstate(all="ignore"):
        e_star = materials.composite_modulus(b1, b2, phi[0], phi[1])
        radii = ((geometry.radius,) * 2 if geometry.shape == "sphere" else geometry.radii)
        r_eq = math.sqrt(radii[0] * radii[1])
        a = (3.0 * float(W.max()) * r_eq / (4.0 * e_star)) ** (1.0 / 3.0)
        return tuple(float(2 * AUTO_MARGIN * a * (r / r_eq) ** (2.0 / 3.0)) for r in radii)


def _check_scene(p, problems):
    """Checks across parts; returns the TimeMesh with ``steps`` resolved."""
    with np.errstate(all="ignore"):  # extreme but valid constants must not warn
        return _check_parts(p, problems)


def _check_parts(p, problems):
    ind, half, load, fric = p["indenter"], p["halfspace"], p["load"], p["friction"]
    if ind is not None and half is not None:
        if ind.material == "rigid" and half.material == "rigid":
            problems.append("indenter.material and halfspace.material are both 'rigid': "
                            "nothing can deform; make at least one body elastic or "
                            "viscoelastic")
        solver = p["solver"]
        if solver is not None and solver.time_rule == "step_start":
            for side, spec in (("indenter", ind), ("halfspace", half)):
                if spec.material == "viscoelastic" and spec.creep_function().phi0 == 0:
                    problems.append(
                        f"solver.time_rule = 'step_start' with {side}.creep = {spec.creep!r}"
                        f" (phi(0) = 0, no instantaneous elasticity): the step-start rule "
                        f"gives a rigid response. Use time_rule = \"linear\"")
    if load is not None and fric is not None:
        t, W, T1, T2 = load.knots()
        T = np.hypot(T1, T2)
        limit = fric.mu * W
        # |T(t)| - mu W(t) is convex on each segment of the piecewise-linear program
        # (a norm of an affine function minus an affine one), so its largest value on a
        # segment is at a knot: checking the knots checks the whole program.
        over = np.flatnonzero((T > 0) & (T >= limit))
        if over.size:
            k = over[0]
            field = ("load.fretting.amplitude" if load.fretting is not None
                     else "load.tangential_force")
            rel = "above" if T[k] > limit[k] else "equal to"
            problems.append(
                f"{field} reaches {T[k]:g} N at t = {t[k]:g} s, {rel} friction.mu * W = "
                f"{limit[k]:g} N (mu = {fric.mu:g}, load.normal_force W = {W[k]:g} N): "
                f"gross sliding has no static solution. Lower the force or raise mu.")
    time = p["time"]
    if load is not None and time is not None:
        intervals = len(load.knots()[0]) - 1
        if time.steps is None:
            time = _make(TimeMesh, steps=intervals)
        elif intervals == 0 and time.steps != 0:
            problems.append(f"time.steps = {time.steps} needs a load program with a "
                            f"duration, but load.time has a single knot: leave out "
                            f"time.steps (one instant) or add knots")
        elif intervals > 0 and time.steps < 1:
            problems.append(f"time.steps must be an integer >= 1, got {time.steps}")
    geo, grid = p["geometry"], p["grid"]
    if geo is not None and grid is not None and grid.size == "auto":
        if geo.shape == "surface":
            problems.append("grid.size = 'auto' is not available for geometry.shape = "
                            "'surface' (no Hertz estimate); give grid.size = [L1, L2] in m")
        elif geo.shape == "flat_punch" or None not in (ind, half, load):
            size = _hertz_size(geo, ind, half, load)
            if not all(math.isfinite(s) and s > 0 for s in size):
                problems.append(f"grid.size = 'auto': the Hertz estimate gives sides "
                                f"{size} m, not finite and > 0; give grid.size = [L1, L2] "
                                f"in m")
    elif geo is not None and grid is not None and geo.shape == "surface":
        problems.extend(_geometry.check_surface(geo.file, *grid.coordinates()))
    return time


@dataclass(frozen=True, init=False)
class Scene:
    """One simulation: geometry, bodies, friction, load, grid, time mesh, solver, output.

    ``Scene(**d)`` takes the nested-dict form of the scene file (sub-tables as dicts, or
    the part objects themselves), validates everything and raises one
    :class:`~contactpipe.SceneError` listing every problem. The stored scene is
    normalised: numbers are floats (ints accepted), lists are tuples, defaults are
    resolved (``time.steps``, ``geometry.height``) and ``geometry.file`` is absolute (a
    relative one is taken relative to the current directory here, to the scene file's
    folder in :meth:`from_toml`).

    Parameters
    ----------
    name : str
        A label, "scene" by default.
    geometry, indenter, halfspace, load, grid : dict or part
        Required tables.
    friction, time, solver, output : dict or part, optional
        Absent: defaults (mu = 0; one step per load-knot interval; solver and output
        defaults).
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

    def __init__(self, /, name="scene", geometry=None, indenter=None, halfspace=None,
                 friction=None, load=None, grid=None, time=None, solver=None, output=None,
                 **unknown):
        given = dict(geometry=geometry, indenter=indenter, halfspace=halfspace,
                     friction=friction, load=load, grid=grid, time=time, solver=solver,
                     output=output)
        problems = []
        for k in unknown:
            close = difflib.get_close_matches(str(k), _TOP_KEYS, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            problems.append(f"unknown key {k!r}{hint} at the top level of the scene; "
                            f"allowed keys: {', '.join(_TOP_KEYS)}")
        if name is None:
            name = "scene"
        if not isinstance(name, str) or not name:
            problems.append(f"name must be a non-empty string, got {_show(name)}")
        parts = {}
        for key, cls, reader, required, what in _PARTS:
            raw = _table(given[key], key, cls, required, problems, what)
            parts[key] = None if raw is None else reader(raw, key, problems)
        parts["time"] = _check_scene(parts, problems)
        if problems:
            raise SceneError(problems)
        object.__setattr__(self, "name", name)
        for key in given:
            object.__setattr__(self, key, parts[key])

    # -- construction ------------------------------------------------------------------

    @classmethod
    def from_dict(cls, d) -> "Scene":
        """A scene from its nested-dict form (as :meth:`to_dict` gives or TOML reads)."""
        if not isinstance(d, Mapping):
            raise SceneError(f"a scene must be a table (dict), got {_show(d)}")
        bad = [k for k in d if not isinstance(k, str)]
        if bad:
            raise SceneError(f"scene keys must be strings, got {_show(bad)}; allowed keys: "
                             f"{', '.join(_TOP_KEYS)}")
        return cls(**dict(d))

    @classmethod
    def from_toml_text(cls, text: str, base_dir=None) -> "Scene":
        """A scene from TOML text; a relative ``geometry.file`` is taken relative to
        ``base_dir`` (default: the current directory)."""
        return cls._from_toml(text, base_dir, "the scene")

    @classmethod
    def from_toml(cls, path) -> "Scene":
        """A scene from a TOML file; a relative ``geometry.file`` is taken relative to
        the scene file's folder."""
        path = os.fspath(path)
        with open(path, "rb") as f:
            raw = f.read()
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SceneError(f"{path}: not a UTF-8 text file ({exc})") from None
        return cls._from_toml(text, os.path.dirname(os.path.abspath(path)), path)

    @classmethod
    def _from_toml(cls, text, base_dir, source):
        d = loads_toml(text, source)
        geo = d.get("geometry")
        if base_dir is not None and isinstance(geo, dict) and isinstance(geo.get("file"), str):
            file = os.path.expanduser(geo["file"])
            if not os.path.isabs(file):
                geo["file"] = os.path.join(os.path.abspath(os.fspath(base_dir)), file)
        return cls.from_dict(d)

    # -- output ------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The scene as nested plain dicts (lists, floats, ints, str, bool), complete with
        defaults resolved; ``Scene.from_dict(s.to_dict()) == s``. ``None`` values (e.g.
        ``solver.accuracy``) are left out, as TOML has no null."""
        d = {"name": self.name}
        for key, *_ in _PARTS:
            d[key] = getattr(self, key).to_dict()
        return d

    def to_toml(self) -> str:
        """The scene as TOML text; reading it back gives an equal scene."""
        d = self.to_dict()
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
        platform.
        """
        d = self.to_dict()
        del d["output"]
        if self.geometry.shape == "surface":
            h = hashlib.sha256()
            with open(self.geometry.file, "rb") as f:
                for chunk in iter(lambda: f.read(1 << 20), b""):
                    h.update(chunk)
            d["geometry"]["file"] = "sha256:" + h.hexdigest()
        text = json.dumps(d, sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]

    def replace(self, changes) -> "Scene":
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
        (``time.steps`` = number of load intervals, a flat punch's ``height`` = radius)
        are derived again from the changed scene, unless ``changes`` sets them.
        """
        if not isinstance(changes, Mapping):
            raise SceneError(f"changes must be a dict of dotted paths to values, got "
                             f"{_show(changes)}")
        d = self.to_dict()
        if d["time"].get("steps") == len(self.load.knots()[0]) - 1:
            del d["time"]["steps"]
        if self.geometry.shape == "flat_punch" and self.geometry.height == self.geometry.radius:
            del d["geometry"]["height"]
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
                                    f"{_show(nxt)}, not a table")
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
        estimate of the largest contact over the window with margin 1.5 on the radius
        (side = 3 a_max; a flat punch: 2.5 radius). Sphere and ellipsoid use
        a = (3 W_max R phi_max / (4 E*))^(1/3) with the glassy moduli in E*."""
        if self.grid.size != "auto":
            return tuple(self.grid.size)
        return _hertz_size(self.geometry, self.indenter, self.halfspace, self.load)

    def resolved_grid(self) -> Grid:
        """The grid with its size resolved (see :meth:`resolved_grid_size`)."""
        if self.grid.size != "auto":
            return self.grid
        return _make(Grid, points=self.grid.points, size=self.resolved_grid_size())

    def instants(self):
        """The load program on the scene's time mesh: (t [s], W, T1, T2 [N]) arrays of
        length ``time.steps`` + 1."""
        return self.load.instants(self.time.steps)
