"""The rules across a scene's parts, checked on construction (:func:`check_scene`): two
rigid bodies, the step-start rule without instantaneous elasticity or at or above its
stability bound, gross sliding, the default time mesh, creep tables that must reach the
end of the load window, and the grid, which must hold the estimated largest contact."""
from __future__ import annotations

import math

import numpy as np

from .. import materials
from . import friction_map
from . import geometry as _geometry
from .parts import MAX_STEPS, TOPOGRAPHIES, Grid, TimeMesh
from .reach import (
    _TILTS,
    _knot_values,
    auto_grid_size,
    contact_reach,
    contact_shifts,
    hertz_semi_axes,
)
from .rough import rough_problems
from .tables import show

__all__ = ["check_scene"]

# ----------------------------------------------------------------------------- rules across parts

def check_scene(p: dict, problems: list):
    """Checks across parts; returns the TimeMesh with ``steps`` resolved."""
    with np.errstate(all="ignore"):  # extreme but valid constants must not warn
        _check_bodies(p, problems)
        _check_rigid_start(p, problems)
        _check_sliding(p, problems)
        _check_tables(p, problems)
        time = _resolve_time(p, problems)
        _check_step_start_stability(p, time, problems)
        _check_grid(p, problems)
        _check_periodic(p, problems)
        if not problems:
            _check_friction_map(p, problems)
            _check_tilts(p, problems)
            _check_reach(p, problems)
            _check_twist(p, problems)
    return time


#: Freedoms without meaning on one period of an infinite surface, and why.
_PERIODIC_REFUSED = {
    "moment1": "a tilt's gap -phi1 x2 is not periodic, and a moment about the period's "
               "centre has no meaning on an infinite surface",
    "moment2": "a tilt's gap -phi2 x1 is not periodic, and a moment about the period's "
               "centre has no meaning on an infinite surface",
    "moment3": "a twist's slip (-phi3 x2, phi3 x1) is not periodic",
    "rotation1": "a tilt's gap -phi1 x2 is not periodic",
    "rotation2": "a tilt's gap -phi2 x1 is not periodic",
    "rotation3": "a twist's slip (-phi3 x2, phi3 x1) is not periodic",
}


def _check_periodic(p, problems):
    """A periodic grid (one period of an infinite surface) has no rotations: the moments
    and rotations of the load are refused, one line each naming the key."""
    grid, load = p["grid"], p["load"]
    if grid is None or not grid.periodic:
        return
    if grid.size == "auto":
        problems.append("grid.size = 'auto' is not available with grid.boundary = "
                        "'periodic': the period is part of the problem, not a margin "
                        "around one contact; give grid.size = [L1, L2] in m")
    if load is None:
        return
    for key, why in _PERIODIC_REFUSED.items():
        if getattr(load, key) is not None:
            problems.append(f"load.{key} is not allowed with grid.boundary = 'periodic': "
                            f"{why}; remove load.{key} (the rotations stay at 0)")


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
        if geo is None or geo.shape in TOPOGRAPHIES or None in (ind, half, load):
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
    if grid.periodic:
        return                  # no edge: the contact may cross the period's sides
    if geo.shape in TOPOGRAPHIES or p["indenter"] is None or p["halfspace"] is None:
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
    allowed = [L / 2 - L / n for L, n in zip(size, grid.points, strict=True)]
    over = [ax for ax in (0, 1) if reach[ax] > allowed[ax]]
    if not over:
        return
    need = [r / (0.5 - 1.0 / n) for r, n in zip(reach, grid.points, strict=True)]
    need = [max(n, L) for n, L in zip(need, size, strict=True)]
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
        if geo.shape in TOPOGRAPHIES:
            problems.append(f"grid.size = 'auto' is not available for geometry.shape = "
                            f"{geo.shape!r} (no Hertz estimate); give grid.size = [L1, L2] "
                            f"in m")
        elif geo.shape == "flat_punch" or None not in (ind, half, load):
            size = auto_grid_size(geo, ind, half, load)
            if not all(math.isfinite(s) and s > 0 for s in size):
                problems.append(f"grid.size = 'auto': the Hertz estimate gives sides "
                                f"{size} m, not finite and > 0; give grid.size = [L1, L2] "
                                f"in m")
    elif geo.shape == "rough":
        problems.extend(rough_problems(geo.wavelengths, *grid.coordinates()))
    elif geo.shape == "surface":
        x1, x2 = grid.coordinates()
        found = _geometry.surface_problems(geo.file, x1, x2, geo.missing, geo.resample)
        problems.extend(found)
        if (not found and load is not None and grid.size_check is not False
                and not grid.periodic and geo.form != "sphere"
                and _geometry.is_gap_file(geo.file)):
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
