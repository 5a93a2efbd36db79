"""Accuracy presets: choose the grid and the time steps for an error target.

A scene may ask for ``solver.accuracy = "fast" | "balanced" | "accurate"``; the grid
points and the number of time steps are then chosen here (the values written in the scene
file for ``grid.points`` and ``time.steps`` are replaced, and the archive records the
choice in its attributes and its ``scene`` text). Each preset is a number of cells across
the largest contact diameter of the window, a number of steps per loading cycle of the
tangential program, and a number of steps per relaxation (retardation) time of the
viscoelastic bodies. The numbers come from the speed-accuracy study
(``studies/speed_accuracy.py``, table in ``studies/README.md``), which measured the error
against Hertz, Mindlin-Deresiewicz and Lee-Radok with the second-order time rule.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .exceptions import SceneError
from .scene_parts import MAX_POINTS, MAX_STEPS, MIN_POINTS, knot_steps

__all__ = ["PRESETS", "Preset", "resolve_accuracy", "knot_multiple"]

#: The largest step count :func:`knot_multiple` looks for.
MAX_KNOT_MULTIPLE = 100_000


@dataclass(frozen=True)
class Preset:
    """What a preset asks for, and the error it was measured to reach."""

    cells_across_contact: int     # cells across the largest contact diameter
    steps_per_cycle: int          # steps per full cycle of the tangential program
    steps_per_relaxation: int     # steps per relaxation/retardation time of the bodies
    target: float                 # relative error reached (stick radius, traction, a³)


# measured by studies/speed_accuracy.py (second-order time rule): the cheapest runs whose
# stick-radius, traction, loop, energy and Lee-Radok a³ errors all stay within the target
# on every finer grid and mesh measured (studies/README.md); steps are then raised so that
# every knot of the load program lies on the time mesh (see resolve_accuracy)
PRESETS = {
    "fast": Preset(cells_across_contact=16, steps_per_cycle=4, steps_per_relaxation=5,
                   target=0.05),
    "balanced": Preset(cells_across_contact=64, steps_per_cycle=4, steps_per_relaxation=5,
                       target=0.01),
    "accurate": Preset(cells_across_contact=171, steps_per_cycle=32, steps_per_relaxation=40,
                       target=0.002),
}


def _tangential_cycles(scene) -> float:
    """Full cycles of the tangential program: the path length of |T| over 4 T_max (of
    the imposed displacement when the tangential freedom is displacement-controlled)."""
    prog = scene.load.programs()
    T1, T2 = prog.force[1:3] if prog.is_force(1) else prog.motion[1:3]
    T = np.hypot(np.asarray(T1, float), np.asarray(T2, float))
    if T.max() == 0:
        return 0.0
    path = np.abs(np.diff(np.asarray(T1, float))).sum() + np.abs(np.diff(np.asarray(T2, float))).sum()
    return float(path / (4.0 * T.max()))


def _characteristic_times(scene):
    out = []
    for spec in (scene.indenter, scene.halfspace):
        for key in ("relaxation_time", "retardation_time"):
            v = getattr(spec, key, None)
            if v:
                out.append(float(v))
        if getattr(spec, "terms", None):
            out.extend(float(tau) for _, tau in spec.terms)
    return out


def knot_multiple(scene) -> int:
    """The least step count whose uniform mesh holds every knot of the load program
    (:func:`contactpipe.scene_parts.knot_steps`; 0 when none exists below 100 000)."""
    m = knot_steps(scene.load.knots()[0], MAX_KNOT_MULTIPLE)
    return 1 if m == 0 else (m or 0)


def _on_knots(scene, steps):
    m = knot_multiple(scene)
    return steps if m == 0 else int(math.ceil(steps / m)) * m


def resolve_accuracy(scene):
    """The scene with grid points and steps chosen by its accuracy preset (or as is).

    Returns (scene, note): ``note`` says what was chosen, for the archive.
    """
    name = scene.solver.accuracy
    if name is None:
        return scene, ""
    if name not in PRESETS:
        raise SceneError(f"solver.accuracy = {name!r}: allowed {', '.join(PRESETS)}")
    pre = PRESETS[name]
    if scene.geometry.shape == "surface":
        raise SceneError("solver.accuracy with geometry.shape = 'surface': the contact size "
                         "cannot be estimated; give grid.points and time.steps instead")
    # the largest contact's semi-axes (a flat punch: its radius) and the grid's sides
    a_max = scene.hertz_semi_axes()
    side = scene.resolved_grid_size()
    if not all(math.isfinite(x) and x > 0 for x in tuple(a_max) + tuple(side)):
        raise SceneError(f"solver.accuracy = {name!r}: the Hertz estimate of the largest "
                         f"contact gives semi-axes {tuple(a_max)} m on sides {tuple(side)} "
                         f"m, not finite and > 0; give grid.points and time.steps instead")
    points = []
    for L, a in zip(side, a_max):
        cells = pre.cells_across_contact * (L / a) / 2.0          # inf when a << L
        n = MAX_POINTS if cells >= MAX_POINTS else int(math.ceil(cells))
        n += n % 2
        points.append(min(max(n, MIN_POINTS), MAX_POINTS))
    knots = len(scene.load.knots()[0]) - 1
    want = float(knots)
    cycles = _tangential_cycles(scene)
    if cycles > 0:
        want = max(want, pre.steps_per_cycle * cycles)
    times = _characteristic_times(scene)
    if times and knots > 0:
        want = max(want, pre.steps_per_relaxation * scene.load.window / min(times))
    if want > MAX_STEPS:
        raise SceneError(f"solver.accuracy = {name!r} asks for {want:.3g} time steps "
                         f"({pre.steps_per_cycle} per load cycle, "
                         f"{pre.steps_per_relaxation} per relaxation time), above the cap "
                         f"of {MAX_STEPS}; give time.steps, or a shorter load window")
    steps = _on_knots(scene, int(math.ceil(want)))
    changes = {"grid.points": points}
    if knots > 0:
        changes["time.steps"] = steps
    resolved = scene.replace(changes)
    note = (f"accuracy preset '{name}' (target {pre.target:g}): {points[0]}x{points[1]} cells "
            f"({pre.cells_across_contact} across the largest contact), "
            f"{steps} steps")
    return resolved, note
