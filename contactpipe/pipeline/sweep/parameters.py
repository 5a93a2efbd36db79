"""Derived sweep parameters: axes that are not a dotted scene path.

A derived parameter is a function ``func(scene, value) -> Scene`` registered by name;
the sweep applies it to every member (:mod:`contactpipe.pipeline.sweep.members`). Built in:

``tau_ratio``
    The load window tau = ``tau_ratio`` x the relaxation time of the first viscoelastic
    body that has one (indenter first): ``relaxation_time`` of a Maxwell body (or of a
    Prony body's dashpot), ``retardation_time`` of a Zener or Kelvin-Voigt body. The load
    knots are stretched proportionally from ``time[0]`` (or ``load.fretting.window`` is
    set), so the shape of the program and the number of steps stay the same.

``delta_amplitude``
    The amplitude delta* [m] of a displacement-controlled tangential program: the base
    scene's ``load.tangential_displacement`` knots are scaled so that their largest
    |omega| is ``delta_amplitude`` (the shape of the program, its knots and steps stay).
``delta_ratio``
    The same amplitude given as delta*/delta_gs [1], delta_gs = 3 mu W C / (16 a) the
    member's own closed-form partial / gross slip boundary
    (:func:`contactpipe.post.fretting.closed_form_boundary`: a sphere, elastic or rigid bodies,
    a scalar mu > 0, a constant normal force), after the dotted axes are applied (so a
    swept mu or W moves delta_gs with it).

Users register their own with :func:`register_parameter`.
"""
from __future__ import annotations

import math
import numbers
from collections.abc import Callable

from ...exceptions import SceneError

__all__ = ["register_parameter", "derived_parameters", "registered", "relaxation_time",
           "with_window", "tau_ratio", "with_amplitude", "delta_amplitude", "delta_ratio"]

_PARAMETERS: dict[str, Callable] = {}


def register_parameter(name: str):
    """Register a derived sweep parameter under ``name`` (a decorator).

    The function is called as ``func(scene, value)`` and returns a new validated
    :class:`~contactpipe.Scene` (typically ``scene.replace({...})``). Raise
    :class:`~contactpipe.SceneError` (or ``ValueError``) for a value it cannot take; the
    sweep reports it with the axis and value.

    >>> from contactpipe.pipeline.sweep import register_parameter
    >>> @register_parameter("load_scale")
    ... def load_scale(scene, value):
    ...     return scene.replace({"load.normal_force": value * scene.load.normal_force})
    >>> cp.sweep(base, {"load_scale": [0.5, 1, 2]}, "runs/")

    Names are global to the process that builds the sweep (the members' scenes are built
    there; workers only receive finished scenes).
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise SceneError(f"a derived parameter name must be an identifier (no dots: "
                         f"dotted names are scene paths), got {name!r}")

    def decorate(func):
        if not callable(func):
            raise TypeError(f"register_parameter({name!r}) decorates a function "
                            f"(scene, value) -> Scene, got {func!r}")
        _PARAMETERS[name] = func
        return func
    return decorate


def derived_parameters() -> dict[str, Callable]:
    """The registered derived parameters, name -> function (a copy)."""
    return dict(_PARAMETERS)


def relaxation_time(scene) -> tuple[str, float]:
    """(dotted key, value [s]) of the time ``tau_ratio`` refers to.

    The first viscoelastic body (indenter, then half-space) with one: Maxwell
    ``relaxation_time``, a Prony body's ``relaxation_time`` (its dashpot), Zener or
    Kelvin-Voigt ``retardation_time``.

    Raises
    ------
    SceneError
        No body has such a time (elastic or rigid bodies, tabulated creep, Prony without
        a dashpot).
    """
    seen = []
    for key in ("indenter", "halfspace"):
        body = getattr(scene, key)
        if body.material != "viscoelastic":
            seen.append(f"{key} is {body.material}")
            continue
        if body.creep in ("maxwell", "prony") and body.relaxation_time is not None:
            return f"{key}.relaxation_time", float(body.relaxation_time)
        if body.creep in ("zener", "kelvin_voigt") and body.retardation_time is not None:
            return f"{key}.retardation_time", float(body.retardation_time)
        seen.append(f"{key} is viscoelastic ({body.creep}) without a relaxation or "
                    f"retardation time")
    raise SceneError(f"no body has a relaxation or retardation time ({'; '.join(seen)}): "
                     f"tau_ratio needs a Maxwell, Zener or Kelvin-Voigt body or a Prony "
                     f"body with relaxation_time")


def with_window(scene, window: float):
    """The scene with its load program stretched to last ``window`` [s].

    ``load.fretting.window`` is set for a fretting preset; otherwise every knot of
    ``load.time`` moves proportionally away from ``time[0]``, which stays put.
    """
    window = float(window)
    if not math.isfinite(window) or window <= 0:
        raise SceneError(f"the load window must be a finite number > 0 [s], got {window:g}")
    load = scene.load
    if load.fretting is not None:
        return scene.replace({"load.fretting.window": window})
    t = [float(x) for x in load.time]
    old = t[-1] - t[0]
    if old <= 0:
        raise SceneError(f"load.time = {t} has a single knot: there is no window to "
                         f"stretch; give at least two knots")
    new = [t[0] + (x - t[0]) * (window / old) for x in t]
    new[-1] = t[0] + window
    return scene.replace({"load.time": new})


@register_parameter("tau_ratio")
def tau_ratio(scene, value):
    """Load window tau = ``value`` x the relaxation time (:func:`relaxation_time`)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(float(value)) or float(value) <= 0:
        raise SceneError(f"tau_ratio must be a finite number > 0, got {value!r}")
    _, t_rel = relaxation_time(scene)
    return with_window(scene, float(value) * t_rel)


def _positive(name, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(float(value)) or float(value) <= 0:
        raise SceneError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def with_amplitude(scene, amplitude: float):
    """The scene with its ``load.tangential_displacement`` program scaled so that its
    largest |omega| (over both components) is ``amplitude`` [m].

    Raises
    ------
    SceneError
        The scene has no displacement-controlled tangential program, or one that is 0
        throughout.
    """
    values = scene.load.tangential_displacement
    if values is None:
        raise SceneError("the scene has no load.tangential_displacement (a displacement-"
                         "controlled tangential program) whose amplitude could be set; give "
                         "the base scene one, e.g. [0, 1e-6, -1e-6, 1e-6] [m]")
    flat = [abs(float(x)) for v in (values if isinstance(values, tuple) else (values,))
            for x in (v if isinstance(v, tuple) else (v,))]
    largest = max(flat)
    if largest == 0:
        raise SceneError("load.tangential_displacement is 0 throughout: there is no "
                         "amplitude to scale; give the program its shape, e.g. "
                         "[0, 1, -1, 1] x 1e-6 m")
    f = float(amplitude) / largest

    def scaled(v):
        return [scaled(x) for x in v] if isinstance(v, (tuple, list)) else float(v) * f

    return scene.replace({"load.tangential_displacement": scaled(values)})


@register_parameter("delta_amplitude")
def delta_amplitude(scene, value):
    """Displacement amplitude delta* = ``value`` [m] (:func:`with_amplitude`)."""
    return with_amplitude(scene, _positive("delta_amplitude", value))


@register_parameter("delta_ratio")
def delta_ratio(scene, value):
    """Displacement amplitude delta* = ``value`` x delta_gs, the member's closed-form
    partial / gross slip boundary (:func:`contactpipe.post.fretting.closed_form_boundary`)."""
    from ...post.fretting import closed_form_boundary  # scipy: only for this parameter
    ratio = _positive("delta_ratio", value)
    d_gs, why = closed_form_boundary(scene)
    if not math.isfinite(d_gs):
        raise SceneError(f"delta_ratio needs the closed-form boundary delta_gs of the "
                         f"scene, which has none: {why}; sweep delta_amplitude [m] instead")
    return with_amplitude(scene, ratio * d_gs)


def registered(name: str) -> Callable | None:
    """The function registered under ``name``, or None."""
    return _PARAMETERS.get(name)
