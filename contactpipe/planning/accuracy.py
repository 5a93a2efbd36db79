"""Accuracy presets: choose the grid and the time steps for an error target.

A scene may ask for ``solver.accuracy = "fast" | "balanced" | "accurate"``; the grid
points, the number of time steps and the frictional preload's sub-steps are then chosen
here (the values written in the scene file for ``grid.points``, ``time.steps`` and
``solver.preload_substeps`` are replaced, the last by "auto" with the preset's target:
:func:`choose_preload`; the archive records the choice in its attributes and its
``scene`` text). Each preset is a number of cells across
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

from ..exceptions import SceneError
from ..materials import ExponentialCreep
from ..scene.parts import MAX_POINTS, MAX_STEPS, MIN_POINTS, knot_steps
from ..solver.memory import resolve_body_rule

__all__ = ["PRESETS", "Preset", "resolve_accuracy", "knot_multiple", "preload_fractions",
           "preload_error", "choose_preload", "PRELOAD_TARGET", "PRELOAD_AUTO_MAX"]

#: The largest step count :func:`knot_multiple` looks for.
MAX_KNOT_MULTIPLE = 100_000


@dataclass(frozen=True)
class Preset:
    """What a preset asks for, and the error it was measured to reach."""

    cells_across_contact: int     # cells across the largest contact diameter
    steps_per_cycle: int          # steps per full cycle of the tangential program
    steps_per_relaxation: int     # steps per relaxation/retardation time of the bodies
    target: float                 # relative error reached (stick radius, traction, a³)
    #: steps per relaxation/retardation time and per cycle when a body's memory takes the
    #: rule "bdf2" (creep laws with little instantaneous elasticity under "auto")
    steps_per_relaxation_bdf2: int = 0
    steps_per_cycle_bdf2: int = 0


# measured by studies/speed_accuracy.py (second-order time rule): the cheapest runs whose
# stick-radius, traction, loop, energy and Lee-Radok a³ errors all stay within the target
# on every finer grid and mesh measured (studies/README.md); steps are then raised so that
# every knot of the load program lies on the time mesh (see resolve_accuracy)
# A body whose memory takes "bdf2" (Kelvin-Voigt, Zener E0/Einf = 100 under "auto"; any law
# with an explicit "bdf2") needs more steps: Lee-Radok a^3 of a ramp 0 -> W over tau held
# to 2 tau, 192^2 auto: 1.2 / 0.39 / 0.12 / 0.036 % at 5 / 10 / 20 / 40 steps per tau for
# both (Maxwell and Zener E0/Einf = 3 with "bdf2": 0.48 and 0.29 % at 5, 64^2), where
# "linear" gives 0.02-0.09 %; the Maxwell fretting loop (tau = t', 48^2) with "bdf2"
# reaches 5 / 1 / 0.2 % with 16 / 32 / 64 steps per cycle (studies/README.md).
PRESETS = {
    "fast": Preset(cells_across_contact=16, steps_per_cycle=4, steps_per_relaxation=5,
                   target=0.05, steps_per_relaxation_bdf2=5, steps_per_cycle_bdf2=16),
    "balanced": Preset(cells_across_contact=64, steps_per_cycle=4, steps_per_relaxation=5,
                       target=0.01, steps_per_relaxation_bdf2=10, steps_per_cycle_bdf2=32),
    "accurate": Preset(cells_across_contact=171, steps_per_cycle=32, steps_per_relaxation=40,
                       target=0.002, steps_per_relaxation_bdf2=40, steps_per_cycle_bdf2=64),
}
#: A term of a creep function counts for the steps per time constant when its amplitude
#: is at least this fraction of phi's largest value over the window [1] (a fitted series
#: carries negligible terms at every fixed time).
TERM_FRACTION = 0.01


def _tangential_cycles(scene) -> float:
    """Full cycles of the tangential program: the path length of |T| over 4 T_max (of
    the imposed displacement when the tangential freedom is displacement-controlled)."""
    prog = scene.load.programs()
    T1, T2 = prog.force[1:3] if prog.is_force(1) else prog.motion[1:3]
    T = np.hypot(np.asarray(T1, float), np.asarray(T2, float))
    if T.max() == 0:
        return 0.0
    path = (np.abs(np.diff(np.asarray(T1, float))).sum()
            + np.abs(np.diff(np.asarray(T2, float))).sum())
    return float(path / (4.0 * T.max()))


def _characteristic_times(scene):
    """The time constants of the bodies' creep functions [s] (of their normal compliance
    too when the Poisson ratio varies), each with the body: 1/b of a dashpot and the tau_i
    of terms of at least :data:`TERM_FRACTION` of phi's largest value over the window.
    A tabulated phi has none."""
    out = []
    window = scene.load.window
    for spec in (scene.indenter, scene.halfspace):
        body = spec.body()
        if not body.has_memory or not isinstance(body.creep, ExponentialCreep):
            continue
        for creep in body.rule_creeps:
            scale = creep.max_over(window) if window > 0 else abs(creep.phi0)
            if not np.isfinite(scale):      # extreme constants: keep every term
                scale = 0.0
            found = ([1.0 / creep.b] if creep.b > 0 else []) + [
                float(tau) for d, tau in zip(creep.d, creep.tau, strict=True)
                if abs(d) >= TERM_FRACTION * scale]
            out.extend((t, body) for t in found if 0.0 < t < np.inf)
    return out


def _wanted_steps(pre, scene, knots, cycles, times) -> float:
    """The steps the tangential cycles and the bodies' time constants ask for: per cycle
    and per the shortest time constant, with the "bdf2" columns when a body's memory takes
    "bdf2" at the step this gives."""
    window = scene.load.window

    def want(per_cycle, per_time):
        w = float(knots)
        if cycles > 0:
            w = max(w, per_cycle * cycles)
        if times and knots > 0:
            w = max(w, per_time * window / min(t for t, _ in times))
        return w

    plain = want(pre.steps_per_cycle, pre.steps_per_relaxation)
    if knots > 0 and times:
        dt = window / max(plain, 1.0)
        rule = scene.solver.time_rule
        if any(resolve_body_rule(b.rule_creeps, dt, rule) == "bdf2" for _, b in times):
            return max(plain, want(pre.steps_per_cycle_bdf2, pre.steps_per_relaxation_bdf2))
    return plain


def knot_multiple(scene) -> int:
    """The least step count whose uniform mesh holds every knot of the load program
    (:func:`contactpipe.scene.parts.knot_steps`; 0 when none exists below 100 000)."""
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
    if scene.geometry.shape in ("surface", "rough"):
        raise SceneError(f"solver.accuracy with geometry.shape = {scene.geometry.shape!r}: "
                         f"the contact size cannot be estimated; give grid.points and "
                         f"time.steps instead")
    # the largest contact's semi-axes (a flat punch: its radius) and the grid's sides
    a_max = scene.hertz_semi_axes()
    side = scene.resolved_grid_size()
    if not all(math.isfinite(x) and x > 0 for x in tuple(a_max) + tuple(side)):
        raise SceneError(f"solver.accuracy = {name!r}: the Hertz estimate of the largest "
                         f"contact gives semi-axes {tuple(a_max)} m on sides {tuple(side)} "
                         f"m, not finite and > 0; give grid.points and time.steps instead")
    points = []
    for L, a in zip(side, a_max, strict=True):
        cells = pre.cells_across_contact * (L / a) / 2.0          # inf when a << L
        n = MAX_POINTS if cells >= MAX_POINTS else int(math.ceil(cells))
        n += n % 2
        points.append(min(max(n, MIN_POINTS), MAX_POINTS))
    knots = len(scene.load.knots()[0]) - 1
    with np.errstate(all="ignore"):       # extreme but valid constants must not warn
        want = _wanted_steps(pre, scene, knots, _tangential_cycles(scene),
                             _characteristic_times(scene))
    if want > MAX_STEPS:
        raise SceneError(f"solver.accuracy = {name!r} asks for {want:.3g} time steps "
                         f"({pre.steps_per_cycle} per load cycle, "
                         f"{pre.steps_per_relaxation} per relaxation time), above the cap "
                         f"of {MAX_STEPS}; give time.steps, or a shorter load window")
    steps = _on_knots(scene, int(math.ceil(want)))
    changes = {"grid.points": points, "solver.preload_substeps": "auto"}
    if knots > 0:
        changes["time.steps"] = steps
    resolved = scene.replace(changes)
    note = (f"accuracy preset '{name}' (target {pre.target:g}): {points[0]}x{points[1]} cells "
            f"({pre.cells_across_contact} across the largest contact), "
            f"{steps} steps")
    return resolved, note


# --------------------------------------------------------------------------- preload path
#: Error target of ``solver.preload_substeps = "auto"`` without an accuracy preset [1].
PRELOAD_TARGET = 0.01
#: The most sub-steps ``"auto"`` takes.
PRELOAD_AUTO_MAX = 1024


def preload_fractions(n: int) -> np.ndarray:
    """The load fractions of a preload in ``n`` sub-steps, (k/n)^2 for k = 1..n.

    Under a growing load the contact radius grows like W^(1/3): uniform fractions give the
    first sub-step half the final radius and converge slowly; squared fractions spread
    the growth of the radius (measured at 32^2 and 64^2, rigid sphere on Maxwell,
    nu = 0.3: the q field 1.5-5 times closer to a 256-sub-step path than uniform fractions
    at 8-64 sub-steps, about first order; docs/time-integration.md section 7)."""
    k = np.arange(1, int(n) + 1, dtype=float)
    return (k / float(n)) ** 2


def preload_error(coarse, fine, m_coarse, m_fine, n, mu):
    """The estimated error of the q field after an ``n``-sub-step preload, from the paths
    of ``m_coarse`` and ``m_fine`` sub-steps (each (q, p), or None), assuming an error C/m:
    C = |q_fine - q_coarse| / (1/m_coarse - 1/m_fine), error C/n. The norm is the rms over
    the cells in contact in either path of |q| (both components), over mu p_max [1];
    None without both paths or without contact. Measured to over-estimate the error
    against a 256-sub-step path by 1.1-3 times (docs/time-integration.md section 7)."""
    if coarse is None or fine is None:
        return None
    (q0, p0), (q1, p1) = coarse, fine
    contact = (p0 > 0) | (p1 > 0)
    scale = float(np.max(mu * p1))
    if not contact.any() or scale <= 0:
        return None
    diff = np.sqrt(np.mean(np.sum((q1 - q0) ** 2, axis=0)[contact]))
    return float(diff / (1.0 / m_coarse - 1.0 / m_fine) / n / scale)


def choose_preload(setting, path, mu, target=PRELOAD_TARGET):
    """The sub-step count of a frictional preload and the estimated error of its q field.

    Parameters
    ----------
    setting : int or "auto"
        ``solver.preload_substeps``: a count n, or "auto": n doubles from 8 until the
        estimate is within ``target``, at most :data:`PRELOAD_AUTO_MAX`.
    path : callable
        ``path(m)`` -> (q, p) after a preload in m sub-steps from the unloaded state [Pa],
        or None when it does not converge.
    mu : float or ndarray
        Friction coefficient [1].
    target : float
        The error target of "auto" [1].

    Returns
    -------
    (int, float or None)
        n, and the error of its q field estimated from the paths of n/4 and n/2
        sub-steps (:func:`preload_error`; None for n < 4 or a path that does not
        converge). Cost: the paths of n/4 and n/2 (explicit n), of 2, 4, ..., n/2
        ("auto"), on top of the run's own.
    """
    paths = {}

    def get(m):
        if m not in paths:
            paths[m] = path(m)
        return paths[m]

    if setting == "auto":
        n = PRELOAD_AUTO_MAX
        m = 4
        while 2 * m <= PRELOAD_AUTO_MAX:
            est = preload_error(get(m // 2), get(m), m // 2, m, 2 * m, mu)
            if est is not None and est <= target:
                n = 2 * m
                break
            m *= 2
    else:
        n = int(setting)
    if n < 4:
        return n, None
    return n, preload_error(get(n // 4), get(n // 2), n // 4, n // 2, n, mu)
