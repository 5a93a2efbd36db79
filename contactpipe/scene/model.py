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
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from . import friction_map, geometry as _geometry
from .. import materials
from ..exceptions import SceneError
from .._util.files import loads_toml
from .parts import (MAX_STEPS, MATERIALS, SHAPES, BodySpec, Fretting, Friction,
                          Geometry, Grid, Load, Output, Solver, TimeMesh)
from .tables import Field, Reader, show

__all__ = ["Scene", "Geometry", "BodySpec", "Friction", "Load", "Fretting", "Grid",
           "TimeMesh", "Solver", "Output", "SceneError", "hertz_semi_axes", "contact_reach",
           "contact_shifts", "auto_grid_size", "AUTO_MARGIN", "AUTO_PUNCH_FACTOR"]

#: Hertz margin of ``grid.size = "auto"``: side = 2 * margin * contact semi-axis.
AUTO_MARGIN = 1.5
#: ``grid.size = "auto"`` for a flat punch: side = this times the punch radius.
AUTO_PUNCH_FACTOR = 2.5

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
)
PARTS = tuple(f.name for f in FIELDS[1:])
TOP_KEYS = tuple(f.name for f in FIELDS)


# ----------------------------------------------------------------------------- Hertz size

def _log(x: float) -> float:
    return math.log(x) if x > 0 else -math.inf


def _exp(x: float) -> float:
    """exp(x) without OverflowError: inf beyond the float range."""
    return math.inf if x > 709.0 else math.exp(x)


def _creep_factor(spec, window: float, moduli: str) -> float:
    """The creep factor phi of a body in the Hertz estimate [1]: of its normal compliance
    (1 - nu)/G, which with ``bulk = "elastic"`` creeps by its own function
    (:attr:`contactpipe.materials.Body.normal_creep`, larger than phi early on for
    Kelvin-Voigt)."""
    if spec.material != "viscoelastic":
        return 1.0
    creep = spec.body().normal_creep
    with np.errstate(all="ignore"):
        if moduli == "window":
            phi = float(creep.max_over(window))
            # NaN only from inf * 0 of a vanishing time constant: an unbounded creep
            return math.inf if math.isnan(phi) else phi
        phi0 = float(creep.phi0)
    return phi0 if phi0 > 0 else 1.0


def hertz_semi_axes(geometry, indenter, halfspace, load, moduli: str = "window"):
    """Semi-axes (a1, a2) [m] of the largest contact of a load program, by Hertz theory.

    The one estimate of the contact size (automatic grid, accuracy presets, figure
    scales). Sphere and ellipsoid: a = (3 W_max R / (4 E*))^(1/3), W_max the largest
    normal force of the program [N], 1/E* = sum over the bodies of phi (1 - nu^2) / E
    with E the instantaneous (glassy) modulus [Pa]; an ellipsoid takes the equivalent
    radius R = sqrt(R1 R2) and a_i = a (R_i / R)^(2/3), whose axis ratio (R1/R2)^(2/3)
    is within 4 % of exact Hertz theory for R1/R2 <= 10. Flat punch: (R, R), the flat
    end. Under approach control (``load.normal_approach``, largest value omega, plus
    R_i phi^2 / 2 of a rotation) the contact is a_i = sqrt(R_i omega), whatever the moduli.
    The creep factor is that of the normal compliance (1 - nu)/G (``bulk = "elastic"``:
    :attr:`contactpipe.materials.Body.normal_creep`). A tilt's shift of the contact is not
    included (:func:`contact_reach` adds it). Computed in logarithms: extreme constants
    give 0 or inf, never a warning.

    Parameters
    ----------
    geometry : Geometry
    indenter, halfspace : BodySpec
    load : Load
    moduli : {"window", "instantaneous"}
        The creep factor phi of a viscoelastic body: its largest over the load window
        (the contact at its largest, the default), or phi(0) (1 where phi(0) = 0).

    Returns
    -------
    (float, float) or None
        (a1, a2) [m] along x1, x2; None for a surface (no estimate).
    """
    if geometry.shape == "surface":
        return None
    if geometry.shape == "flat_punch":
        return geometry.radius, geometry.radius
    if moduli not in ("window", "instantaneous"):
        raise ValueError(f"moduli must be 'window' or 'instantaneous', got {moduli!r}")
    window = load.window
    logs = []
    for spec in (indenter, halfspace):
        if spec.material != "rigid":
            phi = _creep_factor(spec, window, moduli)
            logs.append(_log(phi) + math.log1p(-spec.poisson ** 2) - _log(spec.young))
    top = max(logs, default=-math.inf)
    if top in (math.inf, -math.inf):
        log_c = top
    else:
        log_c = top + math.log(sum(math.exp(x - top) for x in logs))
    radii = (geometry.radius,) * 2 if geometry.shape == "sphere" else geometry.radii
    log_r = 0.5 * (_log(radii[0]) + _log(radii[1]))
    if load.normal_approach is not None:
        # the approach is imposed: delta = a^2 / R whatever the moduli; a tilt phi adds
        # R phi^2 / 2 to it (the gap is the paraboloid moved by R phi)
        t = load.knots()[0]
        omega = _knot_values(load.normal_approach, t)
        for key, r in (("rotation2", radii[0]), ("rotation1", radii[1])):
            if getattr(load, key) is not None:
                omega = omega + 0.5 * r * _knot_values(getattr(load, key), t) ** 2
        omega = float(np.max(omega))
        return tuple(_exp(0.5 * (_log(r) + _log(omega))) for r in radii)
    w_max = float(np.max(load.knots()[1]))
    log_a = (math.log(0.75) + _log(w_max) + log_r + log_c) / 3.0
    return tuple(_exp(log_a + (2.0 / 3.0) * (_log(r) - log_r)) for r in radii)


#: Tilt rows: (moment key, rotation key, axis the contact moves along (0: x1, 1: x2)).
_TILTS = (("moment2", "rotation2", 0), ("moment1", "rotation1", 1))


def contact_shifts(geometry, load):
    """How far a tilt moves the contact along x1 and x2 [m]: a sphere or an ellipsoid
    keeps its Hertz contact, moved by e = M/W under a moment (the pressure centre) or by
    R phi under a rotation (R_i of an ellipsoid along the axis), at most at a knot (M/W
    and phi are monotonic between knots). A flat punch's contact stays on its flat end
    (0), a surface has no estimate (None).

    Returns
    -------
    tuple of two (|shift| [m], key, value, t [s], shift [m]) or None
        The largest |shift| along x1 and x2, the key and its value at the knot t where
        it happens, and the signed shift: (0.0, None, None, None, 0.0) without a tilt or
        where W is not known (approach control).
    """
    if geometry.shape == "surface":
        return None
    t, W = load.knots()[:2]
    out = [(0.0, None, None, None, 0.0)] * 2
    if geometry.shape == "flat_punch":
        return tuple(out)
    radii = (geometry.radius,) * 2 if geometry.shape == "sphere" else geometry.radii
    for mkey, rkey, ax in _TILTS:
        moment, rotation = getattr(load, mkey), getattr(load, rkey)
        if moment is not None:
            values, key = _knot_values(moment, t), f"load.{mkey}"
            with np.errstate(invalid="ignore", divide="ignore"):
                shift = values / W
        elif rotation is not None:
            values, key = _knot_values(rotation, t), f"load.{rkey}"
            shift = radii[ax] * values
        else:
            continue
        size = np.abs(shift)
        if np.isnan(size).all():
            continue                                  # W unknown: approach control
        k = int(np.nanargmax(size))
        out[ax] = (float(size[k]), key, float(values[k]), float(t[k]), float(shift[k]))
    return tuple(out)


def contact_reach(geometry, indenter, halfspace, load):
    """How far from the centre the largest contact of a load program reaches along x1
    and x2 [m]: the Hertz semi-axes (:func:`hertz_semi_axes`, the most compliant creep
    factor over the window) plus the largest shift of a tilt (:func:`contact_shifts`);
    a flat punch's radius; None for a surface."""
    if geometry.shape == "surface":
        return None
    a = hertz_semi_axes(geometry, indenter, halfspace, load)
    shifts = contact_shifts(geometry, load)
    return tuple(float(ai + s[0]) for ai, s in zip(a, shifts))


def auto_grid_size(geometry, indenter, halfspace, load):
    """Grid sides (L1, L2) [m] of ``grid.size = "auto"``: 2 * :data:`AUTO_MARGIN` times
    the reach of the largest contact (:func:`contact_reach`: the Hertz semi-axes plus
    a tilt's shift), or :data:`AUTO_PUNCH_FACTOR` times a flat punch's radius; None for
    a surface."""
    if geometry.shape == "surface":
        return None
    if geometry.shape == "flat_punch":
        side = AUTO_PUNCH_FACTOR * geometry.radius
        return side, side
    reach = contact_reach(geometry, indenter, halfspace, load)
    return tuple(float(2 * AUTO_MARGIN * r) for r in reach)


# ----------------------------------------------------------------------------- rules across parts

def _check_scene(p: dict, problems: list):
    """Checks across parts; returns the TimeMesh with ``steps`` resolved."""
    with np.errstate(all="ignore"):  # extreme but valid constants must not warn
        _check_bodies(p, problems)
        _check_rigid_start(p, problems)
        _check_sliding(p, problems)
        _check_tables(p, problems)
        time = _resolve_time(p, problems)
        _check_step_start_stability(p, time, problems)
        _check_grid(p, problems)
        if not problems:
            _check_friction_map(p, problems)
            _check_tilts(p, problems)
            _check_reach(p, problems)
            _check_twist(p, problems)
    return time


def _check_bodies(p, problems):
    ind, half, solver = p["indenter"], p["halfspace"], p["solver"]
    if ind is None or half is None:
        return
    if ind.material == "rigid" and half.material == "rigid":
        problems.append("indenter.material and halfspace.material are both 'rigid': "
                        "nothing can deform; make at least one body elastic or "
                        "viscoelastic")
    if solver is not None and solver.time_rule == "step_start":
        for side, spec in (("indenter", ind), ("halfspace", half)):
            if spec.material == "viscoelastic" and spec.creep_function().phi0 == 0:
                problems.append(
                    f"solver.time_rule = 'step_start' with {side}.creep = {spec.creep!r}"
                    f" (phi(0) = 0, no instantaneous elasticity): the step-start rule "
                    f"gives a rigid response. Use time_rule = \"auto\"")


def _check_rigid_start(p, problems):
    """Without instantaneous elasticity on either body (rigid, or phi(0) = 0), nothing
    deforms at t0: an approach or a tilt imposed there would need an infinite force."""
    load = p["load"]
    bodies = [(side, p[side]) for side in ("indenter", "halfspace")]
    if load is None or any(spec is None for _, spec in bodies):
        return
    soft = [(side, spec) for side, spec in bodies if spec.material != "rigid"]
    if not soft or any(spec.material == "elastic" or spec.creep_function().phi0 != 0
                       for _, spec in soft):
        return                            # both rigid: refused above
    prog = load.programs()
    why = ", ".join(f"{side}.creep = {spec.creep!r} (phi(0) = 0)" for side, spec in soft)
    why += "".join(f", a rigid {side}" for side, spec in bodies if spec.material == "rigid")
    for i, key, unit in ((0, "normal_approach", "m"), (3, "rotation1", "rad"),
                         (4, "rotation2", "rad")):
        value = prog.motion[i, 0]
        if np.isfinite(value) and value != 0 and (i > 0 or value > 0):
            problems.append(
                f"load.{key} = {value:g} {unit} at t = {prog.t[0]:g} s with {why}: no body "
                f"has instantaneous elasticity, so a step there needs an infinite force; "
                f"ramp it from 0 (one value per load.time knot, the first 0)")
            return


def _check_step_start_stability(p, time, problems):
    """The step-start rule is explicit: refuse a time step at or above its stability bound
    (materials.step_start_stable_step), naming the bound and the steps that keep below it."""
    load, solver = p["load"], p["solver"]
    if (load is None or time is None or not time.steps or solver is None
            or solver.time_rule != "step_start"):
        return
    window = load.window
    dt = window / time.steps
    for side in ("indenter", "halfspace"):
        spec = p[side]
        if spec is None or spec.material != "viscoelastic":
            continue
        creep = spec.creep_function()
        if creep.phi0 == 0:
            continue                      # refused above with its own message
        # with a varying Poisson ratio the normal compliance has its own bound too
        bound = min(materials.step_start_stable_step(c) for c in spec.body().rule_creeps)
        if dt >= bound:
            steps = math.floor(window / bound) + 1
            problems.append(
                f"solver.time_rule = 'step_start' is unstable for {side}.creep = "
                f"{spec.creep!r}: the time step {dt:.6g} s is not below its stability "
                f"bound {bound:.6g} s (the error grows every step); take time.steps >= "
                f"{steps} or solver.time_rule = \"auto\"")


def _check_sliding(p, problems):
    load, fric = p["load"], p["friction"]
    if load is None or fric is None:
        return
    t, W, T1, T2 = load.knots()
    T = np.hypot(T1, T2)
    limit = fric.largest * W           # NaN where W or T is displacement-controlled
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
            f"{limit[k]:g} N (mu = {fric.largest:g}{' at most' if fric.mapped else ''}, "
            f"load.normal_force W = {W[k]:g} N): gross sliding has no static solution. "
            f"Lower the force or raise mu.")


def _grid_axes(p):
    """Cell centres (x1, x2) [m] of the scene's grid (size "auto" resolved), or None."""
    geo, grid, ind, half, load = (p[k] for k in ("geometry", "grid", "indenter",
                                                 "halfspace", "load"))
    if grid is None:
        return None
    if grid.size == "auto":
        if geo is None or geo.shape == "surface" or None in (ind, half, load):
            return None
        grid = Grid.make(points=grid.points, size=auto_grid_size(geo, ind, half, load))
    return grid.coordinates()


def _check_friction_map(p, problems):
    """A mapped mu must cover the grid."""
    fric = p["friction"]
    if fric is None or not fric.mapped:
        return
    axes = _grid_axes(p)
    if axes is not None:
        problems.extend(friction_map.check_mu_file(fric.mu, *axes))


def _check_tilts(p, problems):
    """A flat punch whose resultant M/W lies beyond its flat end would tip: the contact
    opens (a tilted punch under a force or an approach lifts on one side: valid)."""
    geo, load = p["geometry"], p["load"]
    if geo is None or load is None or geo.shape != "flat_punch":
        return
    t, W = load.knots()[:2]
    for mkey, _rkey, ax in _TILTS:
        moment = getattr(load, mkey)
        if moment is None:
            continue
        with np.errstate(invalid="ignore", divide="ignore"):
            shift = _knot_values(moment, t) / W
        if not np.isfinite(shift).any() and not np.isinf(shift).any():
            continue
        k = int(np.nanargmax(np.abs(shift)))
        e = float(shift[k])
        if abs(e) >= geo.radius:
            problems.append(
                f"load.{mkey} = {show(float(_knot_values(moment, t)[k]))} at t = {t[k]:g} s "
                f"puts its pressure centre M/W at {e:.4g} m along {('x1', 'x2')[ax]}, beyond "
                f"the flat punch's radius {geo.radius:g} m: the punch would tip and the "
                f"contact open; keep |M/W| below the radius")


def _reach_why(geo, load, window) -> str:
    """Where the estimate of the contact's size comes from, for messages."""
    if geo.shape == "flat_punch":
        return "the flat punch's radius"
    if load.normal_approach is not None:
        return "a = sqrt(R omega3) under the largest load.normal_approach"
    t, W = load.knots()[:2]
    k = int(np.argmax(W))
    return (f"the Hertz semi-axis of the largest load.normal_force, W = {W[k]:g} N at "
            f"t = {t[k]:g} s, with each body's largest creep factor over the {window:g} s "
            f"window")


def _check_reach(p, problems):
    """A fixed grid must hold the largest contact of the program (:func:`contact_reach`,
    a tilt's shift included) a cell inside its edge: decided here from the estimate, not
    at the step where the contact would reach the edge. ``grid.size_check = false``
    leaves it to the run (a :class:`~contactpipe.GridError` at that step)."""
    geo, grid, load = p["geometry"], p["grid"], p["load"]
    if geo is None or grid is None or load is None or grid.size_check is False:
        return
    if geo.shape == "surface" or p["indenter"] is None or p["halfspace"] is None:
        return
    if geo.shape == "flat_punch" and grid.size == "auto":
        return                  # the punch's own end: its outermost cells' centres lie at
        #                         1.09 radii or more for N >= 8, off the contact
    for body in (p["indenter"], p["halfspace"]):
        E, nu = getattr(body, "young", None), getattr(body, "poisson", None)
        if E is not None and nu is not None and not 0 < E / (2 * (1 + nu)) < math.inf:
            return              # a modulus that rounds to 0: refused with its own reason
    reach = contact_reach(geo, p["indenter"], p["halfspace"], load)
    size = grid.size if grid.size != "auto" else \
        auto_grid_size(geo, p["indenter"], p["halfspace"], load)
    if any(math.isnan(r) for r in reach) or not all(math.isfinite(L) for L in size):
        return                  # an estimate out of range: refused by _check_grid for "auto"
    allowed = [L / 2 - L / n for L, n in zip(size, grid.points)]
    over = [ax for ax in (0, 1) if reach[ax] > allowed[ax]]
    if not over:
        return
    need = [r / (0.5 - 1.0 / n) for r, n in zip(reach, grid.points)]
    need = [max(n, L) for n, L in zip(need, size)]
    ax = over[0]
    name = ("x1", "x2")[ax]
    shifts = contact_shifts(geo, load)
    fix = (f"give grid.size = [{need[0]:.4g}, {need[1]:.4g}] m or more, or \"auto\" "
           f"(grid.size_check = false leaves it to the run)")
    edge = (f"past the {allowed[ax]:.4g} m the grid allows (its half-side less one cell: "
            f"the contact must stay a cell inside the edge, or it opens there)")
    semi = reach[ax] - shifts[ax][0]
    if shifts[ax][0] > 0:
        _shift, key, value, tk, e = shifts[ax]
        if math.isinf(e):
            problems.append(
                f"{key} = {show(value)} at t = {tk:g} s meets load.normal_force W = 0 there: "
                f"no normal force carries the moment (M/W is infinite); apply a moment only "
                f"where W > 0")
            return
        what = "its pressure centre M/W" if key.startswith("load.moment") else \
            "the contact, by R phi,"
        problems.append(
            f"{key} = {show(value)} at t = {tk:g} s moves {what} {e:.4g} m along {name}: "
            f"with its Hertz semi-axis {semi:.4g} m the contact would reach "
            f"{reach[ax]:.4g} m from the centre, {edge}; keep the shift below "
            f"{max(allowed[ax] - semi, 0.0):.4g} m, or {fix}")
        return
    shown = show([float(x) for x in grid.size]) if grid.size != "auto" else "'auto'"
    why = _reach_why(geo, load, load.window)
    problems.append(
        f"grid.size = {shown} m is too small for grid.points = "
        f"{show(list(grid.points))}: the largest contact is estimated to reach "
        f"{reach[ax]:.4g} m from the centre along {name} ({why}), {edge}; {fix}")


def _knot_values(values, t):
    """A program key's values at the knots (a scalar is a step)."""
    if isinstance(values, tuple):
        return np.array(values, dtype=float)
    return np.full(np.shape(t), float(values))


def _check_twist(p, problems):
    """A force-controlled torque at or above that of full sliding (Lubkin: 3 pi mu W a / 16
    for a Hertz contact, pi mu W a / 4 for a flat punch) has no static solution."""
    geo, load, fric = p["geometry"], p["load"], p["friction"]
    if load is None or load.moment3 is None or geo is None or fric is None \
            or geo.shape not in ("sphere", "flat_punch"):
        return
    t, W = load.knots()[:2]
    if np.isnan(W).any():
        return
    M = np.abs(_knot_values(load.moment3, t))
    if geo.shape == "sphere":
        a_max = hertz_semi_axes(geo, p["indenter"], p["halfspace"], load)[0]
        a = a_max * (W / max(float(W.max()), 1e-300)) ** (1.0 / 3.0)
        limit = 3.0 * np.pi * fric.largest * W * a / 16.0
        how = "3 pi mu W a / 16 (Lubkin, Hertz a)"
    else:
        a = np.full(W.shape, geo.radius)
        limit = np.pi * fric.largest * W * a / 4.0
        how = "pi mu W a / 4 (flat punch)"
    over = np.flatnonzero((M > 0) & (M >= limit))
    if over.size:
        k = over[0]
        problems.append(
            f"load.moment3 reaches {M[k]:g} N m at t = {t[k]:g} s, at or above the torque "
            f"of full sliding {how} = {limit[k]:.4g} N m (mu = {fric.largest:g}, W = "
            f"{W[k]:g} N, a = {a[k]:.4g} m): gross slip has no static solution under force "
            f"control. Lower the moment, or impose the rotation (load.rotation3)")


def _check_tables(p, problems):
    """A creep table, or the data of a fitted one, must reach the end of the load window:
    phi is unknown (a fit unfounded) past it."""
    load = p["load"]
    if load is None:
        return
    window = load.window
    for side in ("indenter", "halfspace"):
        spec = p[side]
        if spec is not None and spec.creep == "fit":
            span = materials.table_time_span(spec.file, spec.table_kind)
            if span < window:
                reach = ("1/(2 pi f_min)" if spec.table_kind == "dynamic"
                         else "its last time")
                problems.append(
                    f"{side}.file = {show(spec.file)}: the {spec.table_kind} data reach "
                    f"t = {span:g} s ({reach}), before the end of the load window "
                    f"(load.time spans {window:g} s): the fitted creep function is not "
                    f"founded on data there; give data up to t >= {window:g} s")
        if spec is None or spec.creep != "tabulated":
            continue
        last = spec.creep_function().last_time
        if last < window:
            problems.append(
                f"{side}.table ends at t = {last:g} s, before the end of the load window "
                f"(load.time spans {window:g} s): phi(t) is not known past the table's "
                f"last row; extend the table to t >= {window:g} s")


def _resolve_time(p, problems):
    load, time = p["load"], p["time"]
    if load is None or time is None:
        return time
    t = load.knots()[0]
    intervals = len(t) - 1
    if time.steps is None:
        steps = load.default_steps()
        if steps is None:
            knots = show([float(x) for x in t])
            problems.append(
                f"time.steps is required here: no uniform mesh of at most {MAX_STEPS} "
                f"steps holds every load knot (load.time = {knots} s), so there is no "
                f"default; give time.steps (knots between instants are cut off)")
            return None
        return TimeMesh.make(steps=steps)
    if intervals == 0 and time.steps != 0:
        problems.append(f"time.steps = {time.steps} needs a load program with a "
                        f"duration, but load.time has a single knot: leave out "
                        f"time.steps (one instant) or add knots")
    elif intervals > 0 and time.steps < 1:
        problems.append(f"time.steps must be an integer >= 1, got {time.steps}")
    return time


def _check_grid(p, problems):
    geo, grid = p["geometry"], p["grid"]
    if geo is None or grid is None:
        return
    ind, half, load = p["indenter"], p["halfspace"], p["load"]
    if grid.size == "auto":
        if geo.shape == "surface":
            problems.append("grid.size = 'auto' is not available for geometry.shape = "
                            "'surface' (no Hertz estimate); give grid.size = [L1, L2] in m")
        elif geo.shape == "flat_punch" or None not in (ind, half, load):
            size = auto_grid_size(geo, ind, half, load)
            if not all(math.isfinite(s) and s > 0 for s in size):
                problems.append(f"grid.size = 'auto': the Hertz estimate gives sides "
                                f"{size} m, not finite and > 0; give grid.size = [L1, L2] "
                                f"in m")
    elif geo.shape == "surface":
        found = _geometry.check_surface(geo.file, *grid.coordinates())
        problems.extend(found)
        if not found and load is not None and grid.size_check is not False:
            _check_surface_reach(geo, grid, load, problems)


def _check_surface_reach(geo, grid, load, problems):
    """A surface under ``load.normal_approach``: the contact of a paraboloid reaches where
    the gap is its least value h0 plus half the approach beyond it (a^2 = R omega), exact
    for a flat end too; an outermost cell of the grid within that (the tilts' rigid
    rotation included) would be in contact, so the scene is refused. Under a force there
    is no estimate: the run checks the edge."""
    if load.normal_approach is None:
        return
    x1, x2, h, h0 = _geometry.surface_edge(geo.file, *grid.coordinates())
    t = load.knots()[0]
    omega = _knot_values(load.normal_approach, t)
    tilt = [_knot_values(getattr(load, k), t) if getattr(load, k) is not None
            else np.zeros(t.shape) for k in ("rotation1", "rotation2")]
    for k in range(t.size):
        if omega[k] <= h0:
            continue
        eff = h - tilt[0][k] * x2 - tilt[1][k] * x1 - h0
        hit = np.flatnonzero(eff <= 0.5 * (omega[k] - h0))
        if hit.size:
            i = hit[int(np.argmin(eff[hit]))]
            problems.append(
                f"grid.size = {show([float(v) for v in grid.size])} m is too small for "
                f"load.normal_approach = {omega[k]:.4g} m at t = {t[k]:g} s: at the grid's "
                f"outermost cell ({x1[i]:.4g}, {x2[i]:.4g}) m the gap of geometry.file is "
                f"{eff[i]:.4g} m above its least value, within half the approach beyond it "
                f"({0.5 * (omega[k] - h0):.4g} m), where a paraboloid's contact reaches: "
                f"the contact would reach the grid's edge; enlarge grid.size or lower the "
                f"approach (grid.size_check = false leaves it to the run)")
            return


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
        given = dict(name=name, geometry=geometry, indenter=indenter, halfspace=halfspace,
                     friction=friction, load=load, grid=grid, time=time, solver=solver,
                     output=output, **unknown)
        problems = []
        r = Reader(given, "", problems, title="the scene")
        r.check_keys(FIELDS)
        parts = r.read(FIELDS)
        parts["time"] = _check_scene(parts, problems)
        if problems:
            raise SceneError(problems)
        for key in TOP_KEYS:
            object.__setattr__(self, key, parts[key])

    # -- construction ------------------------------------------------------------------

    @classmethod
    def from_dict(cls, d, base_dir=None) -> "Scene":
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
    def from_toml_text(cls, text: str, base_dir=None) -> "Scene":
        """A scene from TOML text; a relative ``geometry.file`` is taken relative to
        ``base_dir`` (default: the current directory)."""
        return cls.from_dict(loads_toml(text, "the scene"), base_dir)

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
        return cls.from_dict(loads_toml(text, path), os.path.dirname(os.path.abspath(path)))

    # -- output ------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The scene as nested plain dicts (lists, floats, ints, str, bool), complete with
        defaults resolved; ``Scene.from_dict(s.to_dict()) == s``. ``None`` values (e.g.
        ``solver.accuracy``) are left out, as TOML has no null."""
        d = {"name": self.name}
        for key in PARTS:
            d[key] = getattr(self, key).to_dict()
        return d

    def to_toml(self) -> str:
        """The scene as TOML text; reading it back gives an equal scene."""
        d = self.to_dict()
        import tomli_w                   # only to write: validation reads with tomllib
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
        return self.load.instants(self.time.steps)


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
