"""The parts of a scene: one frozen dataclass per table of the scene file.

Each part describes its table as data (``FIELDS``, a tuple of
:class:`~contactpipe.scene.tables.Field`: name, kind, what is allowed, default, unit) and is
read by the one loop of :class:`~contactpipe.scene.tables.Reader`. The rules that tie keys
together are plain functions next to their part: a shape's keys (:class:`Geometry`), a
material's and a creep model's keys (:class:`BodySpec`), the lengths of a load program
(:class:`Load`). Rules across parts (gross sliding, the default time mesh, the automatic
grid) live in :mod:`contactpipe.scene`.

Every part is validated on construction (``Geometry("sphere", radius=-1)`` raises a
:class:`~contactpipe.SceneError`) and written back by :meth:`Part.to_dict`.

Units: SI (m, s, N, Pa) everywhere; angles in degrees.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from .. import materials
from ..exceptions import SceneError
from . import friction_map
from . import geometry as _geometry
from .fit import fit_options, fitted_young
from .load import MAX_CYCLES, PRELOADS, Fretting, Load  # noqa: F401 - the old module had them
from .loading import MAX_STEPS, knot_steps
from .tables import Field, Part, Reader, show

__all__ = ["Part", "Geometry", "BodySpec", "Friction", "Fretting", "Load", "Grid",
           "TimeMesh", "Solver", "Output", "knot_steps", "SHAPES", "MATERIALS",
           "CREEP_MODELS", "MAX_STEPS", "MAX_CYCLES", "MIN_POINTS", "MAX_POINTS"]

SHAPES = ("sphere", "ellipsoid", "flat_punch", "surface", "rough")
#: Shapes of heights on the grid (no Hertz estimate of their contact).
TOPOGRAPHIES = ("surface", "rough")
FORMS = ("flat", "sphere")
MISSING = ("refuse", "fill")
MATERIALS = ("rigid", "elastic", "viscoelastic")
CREEP_MODELS = ("maxwell", "kelvin_voigt", "zener", "prony", "tabulated", "fit")
TIME_RULES = ("auto", "bdf2", "linear", "step_start")
TANGENTIAL_MODELS = ("auto", "scalar", "vector")
FFT_BACKENDS = ("auto", "pyfftw", "scipy")
ACCURACIES = ("fast", "balanced", "accurate")
PRECISIONS = ("float64", "float32")
MIN_POINTS, MAX_POINTS = 8, 4096
#: grid.boundary: a non-periodic half-space (DC-FFT, padded) or one period of a surface
BOUNDARIES = ("free", "periodic")
#: Side lengths a grid may have [m]: a nanometre to a kilometre. Far outside, a cell's
#: area underflows to 0 or its inverse square overflows, and no contact lives there.
MIN_SIDE, MAX_SIDE = 1e-9, 1e3
MAX_TOLERANCE = 1e-2
#: Caps on counts, against absurd sizes (each far beyond a practical simulation).
MAX_PRELOAD_SUBSTEPS = 10_000
MAX_THREADS = 1024

#: Keys each shape requires and allows.
SHAPE_KEYS = {
    "sphere": (("radius",), ()),
    "ellipsoid": (("radii",), ()),
    "flat_punch": (("radius",), ("height",)),
    "surface": (("file",), ("form", "radius", "resample", "missing")),
    "rough": (("hurst", "wavelengths", "seed"), ("rms_slope", "rms_height", "form", "radius")),
}
#: Keys each creep model requires and allows (``tabulated`` and ``fit`` are extensions).
CREEP_KEYS = {
    "maxwell": (("relaxation_time",), ()),
    "kelvin_voigt": (("retardation_time",), ()),
    "zener": (("relaxed_young", "retardation_time"), ()),
    "prony": (("terms",), ("relaxation_time",)),
    "tabulated": (("table",), ()),
    "fit": (("file", "table_kind"), ("terms_per_decade", "time_constants", "free_times",
                                     "fit_tolerance")),
}
FIT_KEYS = CREEP_KEYS["fit"][1]
MODEL_KEYS = ("relaxation_time", "retardation_time", "relaxed_young", "terms", "table",
              "file", "table_kind") + FIT_KEYS


def _positive(x) -> bool:
    return x > 0


def _at_least_1(n) -> bool:
    return n >= 1


# ----------------------------------------------------------------------------- geometry

_POSITIVE_M = "a finite number > 0 [m]"


def _roll_off_first(w, key):
    if w[0] <= w[1]:
        return (f"{key} = {show(list(w))}: the roll-off (first) must be longer than the "
                f"short cut-off (second)")
    return None


def _topography_rules(r, shape, v) -> None:
    """A surface's form takes its radius; a rough surface takes one rms."""
    if v["form"] == "sphere" and v["radius"] is None and not r.has("radius"):
        r.missing("radius", " for form = 'sphere'", _POSITIVE_M)
    elif v["form"] != "sphere" and r.has("radius"):
        r.forbid("radius", f"by shape = {shape!r} without form = 'sphere'")
    if shape == "rough" and (r.has("rms_slope") == r.has("rms_height")):
        r.add(f"{r.key('rms_slope')} or {r.key('rms_height')}: give exactly one of the "
              f"two for shape = 'rough' (got "
              f"{'both' if r.has('rms_slope') else 'neither'})")


@dataclass(frozen=True)
class Geometry(Part):
    """Composite initial gap of the two bodies; first contact at the origin.

    Parameters
    ----------
    shape : {"sphere", "ellipsoid", "flat_punch", "surface", "rough"}
    radius : float, optional
        Sphere radius, or radius of the flat punch's end, or of the sphere a surface
        rides on (``form = "sphere"``) [m].
    radii : (float, float), optional
        Ellipsoid principal radii (R1 along x1, R2 along x2) [m].
    file : str, optional
        Surface file: a gap (netCDF variable ``gap`` over x1, x2, or a ``.npy`` on the
        grid) or measured heights (x3p, sur, opd, plu, sdf, x y z text, netCDF
        ``heights``); stored as an absolute path.
    height : float, optional
        Flat punch only: gap outside the flat end [m]; default the radius.
    form : {"flat", "sphere"}, optional
        Surface and rough: the heights on a plane (absent: flat) or on a sphere.
    resample : bool, optional
        Height files: false takes the file's grid as it is (grid.points and grid.size
        must be the file's); absent or true resamples bilinearly onto the grid.
    missing : {"refuse", "fill"}, optional
        Height files: missing points refused (absent) or given the nearest measured
        height.
    hurst, rms_slope, rms_height, wavelengths, seed : optional
        Rough: Hurst exponent (0, 1), rms slope [1] or rms height [m] (one of the two),
        [roll-off, short cut-off] wavelengths [m], seed of the random phases.
    """

    shape: str
    radius: float | None = None
    radii: tuple | None = None
    file: str | None = None
    height: float | None = None
    form: str | None = None
    resample: bool | None = None
    missing: str | None = None
    hurst: float | None = None
    rms_slope: float | None = None
    rms_height: float | None = None
    wavelengths: tuple | None = None
    seed: int | None = None

    PATH = "geometry"
    FIELDS = (
        Field("shape", "choice", options=SHAPES, required=True),
        Field("radius", "number", _POSITIVE_M, ok=_positive, unit="m"),
        Field("radii", "numbers", "two finite numbers > 0 [m], [R1, R2] along x1, x2",
              ok=_positive, length=2, unit="m"),
        Field("file", "path", "the path of a netCDF file (variable 'gap' over x1, x2 [m]) "
                              "or a .npy array"),
        Field("height", "number", _POSITIVE_M, ok=_positive, unit="m"),
        Field("form", "choice", options=FORMS),
        Field("resample", "bool"),
        Field("missing", "choice", options=MISSING),
        Field("hurst", "number", "a number strictly between 0 and 1",
              ok=lambda h: 0 < h < 1, unit="1"),
        Field("rms_slope", "number", "a finite number > 0 [1]", ok=_positive, unit="1"),
        Field("rms_height", "number", _POSITIVE_M, ok=_positive, unit="m"),
        Field("wavelengths", "numbers", "two finite numbers > 0 [m], [roll-off, short "
              "cut-off], roll-off > cut-off", ok=_positive, length=2, unit="m",
              check=_roll_off_first),
        Field("seed", "integer", "an integer >= 0", ok=lambda n: n >= 0),
    )

    @classmethod
    def read(cls, raw, path, problems):
        r = Reader(raw, path, problems)
        r.check_keys(cls.FIELDS)
        shape = r.value(cls.field("shape"), need="")
        if shape is None:
            return None
        req, opt = SHAPE_KEYS[shape]
        for f in cls.FIELDS[1:]:
            if f.name not in req + opt:
                r.forbid(f.name, f"by shape = {shape!r} (it takes: {', '.join(req + opt)})")
        v = r.read([f for f in cls.FIELDS[1:] if f.name in req + opt],
                   need=f" for shape = {shape!r}", require=req)
        if shape == "flat_punch" and v["height"] is None and not r.has("height"):
            v["height"] = v["radius"]
        if shape in TOPOGRAPHIES:
            _topography_rules(r, shape, v)
        if v.get("file") is not None:
            v["file"] = os.path.abspath(os.path.expanduser(v["file"]))
            r.add(_geometry.surface_problems(v["file"], missing=v["missing"],
                                             resample=v["resample"]))
        return cls.make(shape=shape, **v) if r.ok else None

    def gap(self, x1, x2):
        """Initial gap (N1, N2) [m] at the cell centres ``x1`` (N1,), ``x2`` (N2,) [m]."""
        if self.shape == "sphere":
            return _geometry.sphere_gap(x1, x2, self.radius)
        if self.shape == "ellipsoid":
            return _geometry.ellipsoid_gap(x1, x2, self.radii)
        if self.shape == "flat_punch":
            return _geometry.flat_punch_gap(x1, x2, self.radius, self.height)
        if self.shape == "rough":
            return _geometry.rough_gap(x1, x2, self.hurst, self.wavelengths, self.seed,
                                       self.rms_slope, self.rms_height, self.radius)
        return _geometry.topography_gap(x1, x2, self.file, self.radius, self.missing,
                                        self.resample)


# ----------------------------------------------------------------------------- bodies

_TABLE_WHAT = ("a list of at least 2 [t, phi] rows: t [s] ascending from 0, phi [1] "
               "non-decreasing, > 0 after t = 0")


def _check_table(table, key) -> list:
    """Problems of a tabulated creep function phi(t)."""
    t = [row[0] for row in table]
    phi = [row[1] for row in table]
    out = []
    if len(table) < 2:
        out.append(f"{key} must be {_TABLE_WHAT}, got {len(table)} row")
    if t[0] != 0.0:
        out.append(f"{key} must start at t = 0, got t = {t[0]:g} s in its first row")
    if any(b <= a for a, b in zip(t, t[1:], strict=False)):
        out.append(f"{key} times must be strictly ascending, got t = {show(t)}")
    if any(b < a for a, b in zip(phi, phi[1:], strict=False)):
        out.append(f"{key} phi must not decrease (a creep function grows with time), "
                   f"got phi = {show(phi)}")
    if phi[0] < 0 or any(p <= 0 for p in phi[1:]):
        out.append(f"{key} phi must be > 0 (it may be 0 at t = 0 only), got phi = "
                   f"{show(phi)}")
    return out


@dataclass(frozen=True)
class BodySpec(Part):
    """One body's material, as the scene file gives it.

    Parameters
    ----------
    material : {"rigid", "elastic", "viscoelastic"}
        A rigid body takes no constants.
    young : float
        Young modulus [Pa]: the instantaneous (glassy) one for a viscoelastic body, the
        long-term one for Kelvin-Voigt, the one phi is normalised by for a table; for
        ``creep = "fit"`` the fitted one (derived from the table when absent).
    poisson : float
        Poisson ratio [1], in [0, 0.5]: constant in time, or with ``bulk = "elastic"``
        its value where phi = 1.
    creep : {"maxwell", "kelvin_voigt", "zener", "prony", "tabulated", "fit"}
        Viscoelastic only; each model takes exactly its keys (:data:`CREEP_KEYS`).
    relaxation_time : float
        t' [s] (maxwell; optional dashpot of prony).
    retardation_time : float
        tau [s] (kelvin_voigt, zener).
    relaxed_young : float
        E_inf < young [Pa] (zener).
    terms : tuple of (c, tau)
        Prony terms, c > 0 [1], tau > 0 [s].
    table : tuple of (t, phi)
        Tabulated phi(t): t [s] ascending from 0, phi non-decreasing, > 0 after t = 0;
        it must reach the end of the load window (checked by the scene).
    bulk : {"creep", "elastic"}, optional
        Viscoelastic only. Absent (or "creep"): every compliance creeps with phi, the
        Poisson ratio is constant (paper eq. 9). "elastic": phi is the *shear* creep
        function, the bulk modulus young / (3 (1 - 2 poisson)) does not creep, and the
        Poisson ratio grows in time (:func:`contactpipe.materials.elastic_bulk_parts`).
    file : str
        ``creep = "fit"``: the material table (text or CSV), stored as an absolute path.
    table_kind : {"creep", "relaxation", "dynamic"}
        ``creep = "fit"``: what the file holds (:data:`contactpipe.materials.TABLE_KINDS`);
        tensile data, or shear data with ``bulk = "elastic"``.
    terms_per_decade, time_constants, free_times, fit_tolerance : optional
        ``creep = "fit"``: the fit's log-spaced start (2 per decade) or its time
        constants [s], whether they move from there (true), and the largest error of
        the fitted compliance accepted (:data:`contactpipe.materials.FIT_TOLERANCE`).
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
    bulk: str | None = None
    file: str | None = None
    table_kind: str | None = None
    terms_per_decade: int | None = None
    time_constants: tuple | None = None
    free_times: bool | None = None
    fit_tolerance: float | None = None

    PATH = "body"
    FIELDS = (
        Field("material", "choice", options=MATERIALS, required=True),
        Field("young", "number", "a finite number > 0 [Pa]", ok=_positive, unit="Pa"),
        Field("poisson", "number", "a number in [0, 0.5]", ok=lambda x: 0.0 <= x <= 0.5,
              unit="1"),
        Field("creep", "choice", options=CREEP_MODELS),
        Field("relaxation_time", "number", "t' = eta / G, a finite number > 0 [s]",
              ok=_positive, unit="s"),
        Field("retardation_time", "number", "tau, a finite number > 0 [s]", ok=_positive,
              unit="s"),
        Field("relaxed_young", "number", "E_inf, a finite number > 0 [Pa] below young",
              ok=_positive, unit="Pa"),
        Field("terms", "pairs", "a non-empty list of [c, tau] pairs with c > 0 and tau > 0 "
                                "[s]", ok=lambda p: p[0] > 0 and p[1] > 0, unit="1, s"),
        Field("table", "pairs", _TABLE_WHAT, check=_check_table, unit="s, 1"),
        Field("bulk", "choice", options=materials.BULK),
        Field("file", "path", "the path of a text or CSV table (relative to the scene "
                              "file)"),
        Field("table_kind", "choice", options=tuple(materials.TABLE_KINDS)),
        Field("terms_per_decade", "integer", "an integer from 1 to 100",
              ok=lambda n: 1 <= n <= 100),
        Field("time_constants", "numbers", "a list of finite numbers > 0 [s]",
              ok=_positive, unit="s"),
        Field("free_times", "bool"),
        Field("fit_tolerance", "number", "a finite number > 0 [1]", ok=_positive, unit="1"),
    )

    @classmethod
    def read(cls, raw, path, problems):
        r = Reader(raw, path, problems)
        r.check_keys(cls.FIELDS)
        material = r.value(cls.field("material"), need="")
        if material is None:
            return None
        if material == "rigid":
            for f in cls.FIELDS[1:]:
                r.forbid(f.name, "by a rigid body (material = 'rigid' takes no constants)")
            return cls.make(material="rigid") if r.ok else None
        ctx = f" for material = {material!r}"
        if material == "elastic":
            v = r.read(cls.FIELDS[1:3], need=ctx, require=("young", "poisson"))
            for k in ("creep", "bulk") + MODEL_KEYS:
                r.forbid(k, "by an elastic body (creep keys need material = 'viscoelastic')")
            return cls.make(material="elastic", **v) if r.ok else None
        fit = r.raw.get("creep") == "fit"          # young then comes from the table
        v = r.read(cls.FIELDS[1:3], need=ctx,
                   require=("poisson",) if fit else ("young", "poisson"))
        creep = r.value(cls.field("creep"), need=ctx, required=True)
        if creep is None:
            return None
        req, opt = CREEP_KEYS[creep]
        for k in MODEL_KEYS:
            if k not in req + opt:
                r.forbid(k, f"by creep = {creep!r} (it takes: {', '.join(req + opt)})")
        v.update(r.read([cls.field(k) for k in MODEL_KEYS if k in req + opt],
                        need=f" for creep = {creep!r}", require=req))
        bulk = r.value(cls.field("bulk"))
        v["bulk"] = None if bulk == "creep" else bulk
        if v["bulk"] == "elastic" and creep == "tabulated":
            r.add(f"{r.key('bulk')} = 'elastic' needs a creep law of exponentials "
                  f"(maxwell, kelvin_voigt, zener, prony, fit), not creep = 'tabulated'")
        young, relaxed = v["young"], v.get("relaxed_young")
        if creep == "zener" and young is not None and relaxed is not None and relaxed >= young:
            r.add(f"{r.key('relaxed_young')} must be below {r.key('young')} = {young:g} Pa "
                  f"(the relaxed modulus E_inf < the instantaneous E0), got {relaxed:g}")
        if creep == "fit" and r.ok:
            v["file"] = os.path.abspath(os.path.expanduser(v["file"]))
            v["young"] = fitted_young(r, v)
        return cls.make(material="viscoelastic", creep=creep, **v) if r.ok else None

    def fit(self):
        """The :class:`~contactpipe.materials.PronyFit` of ``creep = "fit"`` (None for the
        other models); cached while the file is unchanged."""
        if self.creep != "fit":
            return None
        return materials.fit_table_file(self._given("file"), self._given("table_kind"),
                                        **fit_options(vars(self)))

    def _given(self, name: str):        # a key read() requires for this material and model
        value = getattr(self, name)
        if value is None:
            model = f", creep = {self.creep!r}" if self.creep else ""
            raise SceneError(f"{self.PATH}.{name} is required for material = "
                             f"{self.material!r}{model}, and is not given")
        return value

    def creep_function(self):
        """The normalised creep function phi(t) (:data:`materials.ELASTIC` if none)."""
        if self.material != "viscoelastic":
            return materials.ELASTIC
        if self.creep == "maxwell":
            return materials.maxwell(self._given("relaxation_time"))
        if self.creep == "kelvin_voigt":
            return materials.kelvin_voigt(self._given("retardation_time"))
        if self.creep == "zener":
            return materials.zener(self._given("young"), self._given("relaxed_young"),
                                   self._given("retardation_time"))
        if self.creep == "prony":
            return materials.prony(self.terms, self.relaxation_time)
        if self.creep == "fit":
            return self.fit().creep
        t, phi = zip(*self._given("table"), strict=True)
        return materials.TabulatedCreep(t=tuple(t), phi=tuple(phi))

    def body(self) -> materials.Body:
        """The :class:`materials.Body` this spec describes."""
        if self.material == "rigid":
            return materials.Body(kind="rigid")
        return materials.Body(kind=self.material, young=self._given("young"),
                              poisson=self._given("poisson"), creep=self.creep_function(),
                              bulk=self.bulk or "creep")


# ----------------------------------------------------------------------------- friction

@dataclass(frozen=True)
class Friction(Part):
    """Coulomb friction between the bodies.

    Parameters
    ----------
    mu : float or str
        Friction coefficient [1], >= 0; 0 (the default) is frictionless. Or the path of
        a netCDF file with a variable ``mu`` over x1, x2 [m]
        (:mod:`contactpipe.scene.friction_map`), stored as an absolute path (relative to
        the scene file in ``Scene.from_toml``).
    """

    mu: float | str = 0.0

    PATH = "friction"
    FIELDS = (Field("mu", "number", "a finite number >= 0", ok=lambda x: x >= 0,
                    default=0.0, unit="1"),)

    @classmethod
    def read(cls, raw, path, problems):
        r = Reader(raw, path, problems)
        r.check_keys(cls.FIELDS)
        mu = r.raw.get("mu")
        if isinstance(mu, (str, os.PathLike)) and os.fspath(mu):
            mu = os.path.abspath(os.path.expanduser(os.fspath(mu)))
            r.add(friction_map.check_mu_file(mu))
            return cls.make(mu=mu) if r.ok else None
        values = r.read(cls.FIELDS)
        return cls.make(**values) if r.ok else None

    @property
    def mapped(self) -> bool:
        """mu is a map read from a file."""
        return isinstance(self.mu, str)

    @property
    def largest(self) -> float:
        """The largest mu [1] (of the map, when mapped): what decides whether there is
        friction at all."""
        if not self.mapped:
            return float(self.mu)
        return float(friction_map.largest(self.mu))

    def on_grid(self, x1, x2):
        """mu at the cell centres: a float, or an (N1, N2) array when mapped [1]."""
        if not self.mapped:
            return float(self.mu)
        return friction_map.mu_on_grid(self.mu, x1, x2)


# ----------------------------------------------------------------------------- grid, time

@dataclass(frozen=True)
class Grid(Part):
    """The computational grid on the common plane, centred on the first contact point.

    Parameters
    ----------
    points : (int, int)
        Cells (N1, N2) along x1, x2, each from 8 to 4096.
    size : (float, float) or "auto"
        Full side lengths (L1, L2) [m], or "auto" for a Hertz estimate
        (:meth:`Scene.resolved_grid_size`).
    size_check : bool, optional
        Absent (true): a scene whose estimated largest contact would not stay a cell
        inside a given size is refused (:func:`contactpipe.scene.contact_reach`). False:
        no such check; the run stops with a GridError at the step whose contact reaches
        the edge. True is stored as absent.
    boundary : {"free", "periodic"}, optional
        "free" (the default, stored as absent): a non-periodic half-space, convolved by
        DC-FFT with zero padding. "periodic": the grid is one period of an infinite
        surface (plain FFT convolution, no padding; the normal force W is the force on
        one period; docs/conventions.md, "Periodic contact").
    """

    points: tuple
    size: tuple | str
    size_check: bool | None = None
    boundary: str | None = None

    PATH = "grid"
    FIELDS = (
        Field("points", "integers", f"two integers [N1, N2], each from {MIN_POINTS} to "
                                    f"{MAX_POINTS}",
              ok=lambda n: MIN_POINTS <= n <= MAX_POINTS, length=2, required=True),
        Field("size", "numbers", f"two numbers from {MIN_SIDE:g} to {MAX_SIDE:g} [m], "
                                 "[L1, L2] the full side lengths, or 'auto'",
              ok=lambda x: MIN_SIDE <= x <= MAX_SIDE, length=2, options=("auto",),
              required=True, unit="m"),
        Field("size_check", "bool"),
        Field("boundary", "choice", options=BOUNDARIES),
    )

    @classmethod
    def read(cls, raw, path, problems):
        grid = super().read(raw, path, problems)
        if grid is not None and grid.size_check is True:
            object.__setattr__(grid, "size_check", None)      # the default, stored absent
        if grid is not None and grid.boundary == "free":
            object.__setattr__(grid, "boundary", None)        # the default, stored absent
        if grid is not None and grid.periodic and any(n % 2 for n in grid.points):
            problems.append(f"{path}.points = {list(grid.points)} must be even numbers for "
                            f"{path}.boundary = 'periodic' (the real FFT of one period, "
                            f"and its coarse grids, halve each side)")
            return None
        return grid

    @property
    def periodic(self) -> bool:
        """The grid is one period of an infinite surface (``boundary = "periodic"``)."""
        return self.boundary == "periodic"

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
        """Cell centres (x1 (N1,), x2 (N2,)) [m]: x = -L/2 + (i + 1/2) L/N, ascending.

        The one implementation of the grid's coordinates (docs/conventions.md, Grid)."""
        return tuple(-L / 2 + (np.arange(N) + 0.5) * (L / N)
                     for N, L in zip(self.points, self._size(), strict=True))


@dataclass(frozen=True)
class TimeMesh(Part):
    """The uniform temporal mesh: ``steps`` + 1 instants from time[0] to time[-1].

    Parameters
    ----------
    steps : int, optional
        Number of steps, from 1 to 1 000 000. Absent: the least number whose mesh holds
        every load knot (:meth:`Load.default_steps`; a scene stores the resolved number;
        0 for a single-knot load, a single instant).
    """

    steps: int | None = None

    PATH = "time"
    FIELDS = (Field("steps", "integer", "an integer >= 1 (0 only for a single-knot load)",
                    ok=lambda n: n >= 0, cap=MAX_STEPS,
                    cap_why="each step is a full contact solve; split a longer program "
                            "into several scenes"),)


# ----------------------------------------------------------------------------- solver, output

_AT_LEAST_1 = "an integer >= 1"


@dataclass(frozen=True)
class Solver(Part):
    """Solver options.

    Parameters
    ----------
    tolerance : float
        Relative tolerance on the force balance and complementarity, in (0, 1e-2].
    max_iterations : int
        Iteration cap of each inner solve, >= 1.
    time_rule : {"auto", "bdf2", "linear", "step_start"}
        Time integration of the viscoelastic history (docs/time-integration.md):
        "bdf2" (exponentially fitted BDF2 on the internal variables: L-stable, second
        order, for every creep law and step), "linear" (traction linear within a step:
        second order, but its error alternates and barely decays for creep laws with
        little instantaneous elasticity), "auto" (the default: "linear" where its error
        keeps its sign for the body's creep law and step, "bdf2" elsewhere), or
        "step_start" (the paper's rule, first order and explicit: refused above its
        stability bound and for phi(0) = 0).
    tangential : {"auto", "scalar", "vector"}
        Tangential model: chosen from the scene, q2 = 0 (Cattaneo-Mindlin), or both.
    max_coupling_passes : int
        Cap on the normal <-> tangential passes of the middle loop, >= 1.
    preload_substeps : int or "auto"
        Sub-steps of a frictional preload (graded, finer where the contact grows fastest),
        from 1 to 10 000, or "auto": as many as the accuracy target asks for
        (``accuracy``'s, else 1 %; docs/time-integration.md).
    fft : {"auto", "pyfftw", "scipy"}
    threads : int
        FFT threads, from 1 to 1024.
    accuracy : {None, "fast", "balanced", "accurate"}
        Ask for an accuracy preset: the grid points and time steps are then chosen by
        :func:`contactpipe.planning.accuracy.resolve_accuracy` (replacing ``grid.points`` and
        ``time.steps``) and the choice is recorded in the archive.
    max_hours : float, optional
        The run time a run may be estimated to take [h], > 0; absent: 1 h
        (:func:`contactpipe.planning.check_resources` refuses a longer one before it
        starts).
    """

    tolerance: float = 1e-9
    max_iterations: int = 2000
    time_rule: str = "auto"
    tangential: str = "auto"
    max_coupling_passes: int = 100
    preload_substeps: int | str = 8
    fft: str = "auto"
    threads: int = 1
    accuracy: str | None = None
    max_hours: float | None = None

    PATH = "solver"
    FIELDS = (
        Field("tolerance", "number", f"a number in (0, {MAX_TOLERANCE:g}]",
              ok=lambda x: 0 < x <= MAX_TOLERANCE, default=1e-9, unit="1"),
        Field("max_iterations", "integer", _AT_LEAST_1, ok=_at_least_1, default=2000),
        Field("time_rule", "choice", options=TIME_RULES, default="auto"),
        Field("tangential", "choice", options=TANGENTIAL_MODELS, default="auto"),
        Field("max_coupling_passes", "integer", _AT_LEAST_1, ok=_at_least_1, default=100),
        Field("preload_substeps", "integer", "an integer >= 1, or 'auto'", ok=_at_least_1,
              default=8, options=("auto",), cap=MAX_PRELOAD_SUBSTEPS,
              cap_why="the preload needs a few substeps; the default is 8"),
        Field("fft", "choice", options=FFT_BACKENDS, default="auto"),
        Field("threads", "integer", _AT_LEAST_1, ok=_at_least_1, default=1,
              cap=MAX_THREADS, cap_why="FFT threads beyond the cores only slow it down"),
        Field("accuracy", "choice", options=ACCURACIES),
        Field("max_hours", "number", "a finite number > 0 [h]", ok=_positive, unit="h"),
    )


@dataclass(frozen=True)
class Output(Part):
    """Archive options (they change the file, not the physics; not in the digest).

    Parameters
    ----------
    stride : int
        Store every ``stride``-th instant, from 1 to 1 000 000.
    precision : {"float64", "float32"}
        Storage type of the fields.
    compress : bool
        zlib compression of the archive.
    """

    stride: int = 1
    precision: str = "float64"
    compress: bool = True

    PATH = "output"
    FIELDS = (
        Field("stride", "integer", _AT_LEAST_1, ok=_at_least_1, default=1, cap=MAX_STEPS,
              cap_why="the largest number of time steps"),
        Field("precision", "choice", options=PRECISIONS, default="float64"),
        Field("compress", "bool", default=True),
    )
