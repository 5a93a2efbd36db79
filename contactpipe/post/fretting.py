"""Fretting loops: their cycles, the energy each dissipates, and the fretting regime.

A fretting test is read from its loop, the tangential force T against the imposed
tangential displacement delta (here the rigid displacement omega1 of body 1 relative to
body 2). :func:`loop_cycles` finds the closed cycles of a displacement history (from one
turning point back to the same displacement through the opposite one); each cycle gives
(:func:`cycle_of`)

* delta* = half the range of delta over the cycle [m] (the displacement amplitude),
* T* = half the range of T over the cycle [N] (the force amplitude; the largest |T| of the
  symmetric loop of a fretting test, and still the amplitude of a loop offset by an earlier
  slide),
* E_d = the loop area, the integral of T d(delta) around the cycle [J] (trapezoids between
  the archive's instants): the energy the friction dissipated, and
* Fouvry's energy ratio A = E_d / (4 T* delta*) [1].

The classification rule (Fouvry, Kapsa & Vincent [F95]_; regimes after Vincent, Berthier
& Godet [V92]_):

* a cycle is in **partial slip** when A < 0.2 and in **gross slip** when A >= 0.2
  (:data:`A_TRANSITION`). For a sphere on a plane 0.2 is the ratio of the
  Mindlin-Deresiewicz loop at the transition delta* = delta_gs
  (:func:`contactpipe.analytic.energy_ratio`; E_MD(mu W) = 0.8 mu W delta_gs), which is
  how [F95]_ chose it;
* a member whose cycles are all partial slip is **partial slip**, all gross slip **gross
  slip**, and one whose cycles change regime (the running condition moves across the
  boundary as the test goes on: [V92]_'s mixed fretting regime) is **mixed**.

The closed-form regime of the same member compares each cycle's delta* with the
boundary delta_gs of Mindlin's elastic sphere (:func:`contactpipe.analytic.gross_slip_boundary`):
partial slip below, gross slip above.

References
----------
.. [F95] S. Fouvry, Ph. Kapsa, L. Vincent, "Analysis of sliding behaviour for fretting
   loadings: determination of transition criteria", Wear 185 (1995) 35-46 (the energy
   ratio A = E_d / (4 delta* Q*) and its transition value 0.2 for a sphere on a plane).
.. [V92] L. Vincent, Y. Berthier, M. Godet, "Testing methods in fretting fatigue: a
   critical appraisal", ASTM STP 1159 (1992) 33-48 (partial slip, mixed and gross slip
   regimes; running condition fretting maps).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import analytic
from ..exceptions import ArchiveError, SceneError
from ..materials import composite_modulus
from ..scene import Scene

__all__ = ["REGIMES", "A_TRANSITION", "Cycle", "FrettingRegime", "turning_points",
           "loop_cycles", "loop_energy", "cycle_of", "regime_of", "closed_form_boundary",
           "boundary_constants",
           "classify_loop", "fretting_regime"]

#: The regimes, from the smallest displacement amplitude to the largest.
REGIMES = ("partial slip", "mixed", "gross slip")
#: Fouvry's transition energy ratio for a sphere on a plane ([F95]_).
A_TRANSITION = analytic.ENERGY_RATIO_TRANSITION
#: Two turning points at the same displacement within this fraction of the range close
#: a cycle.
CLOSE_RTOL = 1e-9


def turning_points(delta) -> np.ndarray:
    """Indices of the turning points of a displacement history: the first sample, every
    sample where the direction reverses (holds skipped), and the last sample."""
    d = np.asarray(delta, float)
    if d.ndim != 1 or d.size == 0:
        raise ValueError(f"delta must be a non-empty 1-D series, got shape {d.shape}")
    points, direction = [0], 0
    for i in range(1, d.size):
        step = d[i] - d[i - 1]
        if step == 0:
            continue
        s = 1 if step > 0 else -1
        if direction and s != direction:
            last = i - 1
            while last > 0 and d[last - 1] == d[last]:       # the first sample of a hold
                last -= 1
            points.append(last)
        direction = s
    if points[-1] != d.size - 1:
        points.append(d.size - 1)
    return np.array(points)


def loop_cycles(delta) -> list[tuple[int, int]]:
    """The closed cycles of a displacement history: (start, stop) instant indices of each
    pair of turning points two apart at the same displacement (within
    :data:`CLOSE_RTOL` of the history's range), in order; e.g. 0 -> d -> -d -> d has one,
    from the first d to the last."""
    d = np.asarray(delta, float)
    tp = turning_points(d)
    span = float(np.ptp(d)) if d.size else 0.0
    out = []
    for j in range(1, len(tp) - 2):
        i0, i2 = tp[j], tp[j + 2]
        if span > 0 and abs(d[i2] - d[i0]) <= CLOSE_RTOL * span:
            out.append((int(i0), int(i2)))
    return out


def loop_energy(delta, force) -> float:
    """The area of a closed loop, the integral of T d(delta) around it [J] (trapezoids;
    positive for a loop run the dissipative way)."""
    d = np.asarray(delta, float)
    t = np.asarray(force, float)
    return float(np.sum(0.5 * (t[1:] + t[:-1]) * np.diff(d)))


@dataclass(frozen=True)
class Cycle:
    """One closed cycle of a fretting loop (module docstring for the definitions).

    Attributes
    ----------
    start, stop : int
        Instant indices of its first and last turning points.
    delta_star : float
        Displacement amplitude delta* [m].
    force_amplitude : float
        T* [N].
    energy : float
        E_d [J].
    ratio : float
        A = E_d / (4 T* delta*) [1].
    regime : str
        "partial slip" (A < 0.2) or "gross slip".
    """

    start: int
    stop: int
    delta_star: float
    force_amplitude: float
    energy: float
    ratio: float
    regime: str


def cycle_of(delta, force, start, stop) -> Cycle:
    """The :class:`Cycle` of the samples ``start`` .. ``stop`` of a loop."""
    d = np.asarray(delta, float)[start:stop + 1]
    t = np.asarray(force, float)[start:stop + 1]
    d_star = 0.5 * float(np.ptp(d))
    t_star = 0.5 * float(np.ptp(t))
    e = abs(loop_energy(d, t))
    ratio = e / (4.0 * t_star * d_star) if t_star > 0 and d_star > 0 else 0.0
    return Cycle(int(start), int(stop), d_star, t_star, e, ratio,
                 "gross slip" if ratio >= A_TRANSITION else "partial slip")


def regime_of(regimes) -> str:
    """A member's regime from its cycles' ("partial slip" / "gross slip"): the common one,
    or "mixed" when they differ."""
    found = set(regimes)
    if not found:
        raise ValueError("no cycle to classify")
    return found.pop() if len(found) == 1 else "mixed"


def boundary_constants(scene: Scene):
    """(R [m], E* [Pa], C [1/Pa]) of a sphere of elastic or rigid bodies: what
    :func:`contactpipe.analytic.gross_slip_boundary` needs besides mu and W; None for
    another geometry or a viscoelastic body."""
    b1, b2 = scene.indenter.body(), scene.halfspace.body()
    if scene.geometry.shape != "sphere" or any(b.kind not in ("rigid", "elastic")
                                               for b in (b1, b2)):
        return None
    return (float(scene.geometry.radius), float(composite_modulus(b1, b2)),
            float(analytic.tangential_compliance_sum(b1.young, b1.poisson, b2.young,
                                                     b2.poisson)))


def closed_form_boundary(scene: Scene) -> tuple[float, str]:
    """(delta_gs [m], "") of a scene's Mindlin contact, or (NaN, why not).

    delta_gs = 3 mu W C / (16 a) (:func:`contactpipe.analytic.gross_slip_boundary`) needs a
    sphere, elastic or rigid bodies (no viscoelastic memory), a scalar mu > 0 and a constant,
    force-controlled W.
    """
    b1, b2 = scene.indenter.body(), scene.halfspace.body()
    _, W, _, _ = scene.load.knots()
    constants = boundary_constants(scene)
    why = []
    if scene.geometry.shape != "sphere":
        why.append(f"geometry.shape = {scene.geometry.shape!r} (needs a sphere)")
    if any(b.kind not in ("rigid", "elastic") for b in (b1, b2)):
        why.append("a viscoelastic body (needs elastic or rigid bodies)")
    if scene.friction.mapped or scene.friction.largest <= 0:
        why.append("friction.mu is a map or 0 (needs a scalar mu > 0)")
    if np.any(np.isnan(W)) or np.any(W != W[0]) or W[0] <= 0:
        why.append("the normal force is not a constant force > 0")
    if why:
        return math.nan, "; ".join(why)
    value = analytic.gross_slip_boundary(float(scene.friction.mu), float(W[0]), *constants)
    return float(value), ""


@dataclass(frozen=True)
class FrettingRegime:
    """The fretting regime of one loop, with its closed-form counterpart.

    Attributes
    ----------
    regime : str
        One of :data:`REGIMES`, from the cycles' energy ratios.
    cycles : tuple of Cycle
    delta_star, force_amplitude, energy, ratio : float
        Those of the last cycle [m, N, J, 1].
    delta_gs : float
        The closed-form boundary [m] (NaN where no closed form applies).
    ratio_closed_form : float
        The Mindlin-Deresiewicz A at the last cycle's delta*/delta_gs (NaN without it).
    regime_closed_form : str
        From each cycle's delta* against delta_gs ("" without it).
    friction_coefficient, normal_force : float
        mu [1] and W [N] of the member (NaN where not a scalar / not constant).
    why_no_closed_form : str
        Why delta_gs is NaN ("" otherwise).
    """

    regime: str
    cycles: tuple
    delta_star: float
    force_amplitude: float
    energy: float
    ratio: float
    delta_gs: float = math.nan
    ratio_closed_form: float = math.nan
    regime_closed_form: str = ""
    friction_coefficient: float = math.nan
    normal_force: float = math.nan
    why_no_closed_form: str = field(default="")


def classify_loop(delta, force, delta_gs=math.nan) -> FrettingRegime:
    """The regime of a loop given as arrays (module docstring for the rule).

    Parameters
    ----------
    delta : array_like
        Imposed tangential displacement [m] at each instant.
    force : array_like
        Tangential force T [N] at the same instants.
    delta_gs : float, optional
        The closed-form boundary [m]; NaN: no closed-form columns.

    Raises
    ------
    ValueError
        The history has no closed cycle (at least 0 -> d -> -d -> d is needed).
    """
    d = np.asarray(delta, float)
    t = np.asarray(force, float)
    if d.shape != t.shape:
        raise ValueError(f"delta and force differ in shape: {d.shape} against {t.shape}")
    spans = loop_cycles(d)
    if not spans:
        raise ValueError("the displacement history has no closed cycle (a fretting loop "
                         "needs at least 0 -> d -> -d -> d)")
    cycles = tuple(cycle_of(d, t, a, b) for a, b in spans)
    last = cycles[-1]
    extra = {}
    if math.isfinite(delta_gs) and delta_gs > 0:
        x = [c.delta_star / delta_gs for c in cycles]
        extra = {"delta_gs": float(delta_gs),
                 "ratio_closed_form": float(analytic.energy_ratio(x[-1])),
                 "regime_closed_form": regime_of(
                     "gross slip" if v > 1.0 else "partial slip" for v in x)}
    return FrettingRegime(regime_of(c.regime for c in cycles), cycles, last.delta_star,
                          last.force_amplitude, last.energy, last.ratio, **extra)


def fretting_regime(ds, axis: int = 1) -> FrettingRegime:
    """The fretting regime of an archive's loop: T and omega along x1 (``axis=1``) or x2.

    The closed-form boundary comes from the archive's ``scene`` attribute
    (:func:`closed_form_boundary`).

    Raises
    ------
    ArchiveError
        No ``T1`` / ``omega1`` (``T2`` / ``omega2``) or no ``scene`` attribute; a loop with
        no closed cycle.
    """
    names = (f"omega{axis}", f"T{axis}")
    missing = [n for n in names if n not in ds]
    if missing:
        raise ArchiveError(f"the archive has no {', '.join(missing)}: not a fretting loop")
    text = ds.attrs.get("scene")
    if not isinstance(text, str):
        raise ArchiveError("the archive has no 'scene' attribute (the scene as TOML text)")
    try:
        scene = Scene.from_toml_text(text)
    except SceneError as err:
        raise ArchiveError(f"the archive's 'scene' attribute is not a valid scene: "
                           f"{err}") from None
    d_gs, why = closed_form_boundary(scene)
    try:
        out = classify_loop(ds[names[0]].values, ds[names[1]].values, d_gs)
    except ValueError as err:
        raise ArchiveError(f"{err} ({names[0]} of scene {scene.name!r})") from None
    mu = float(scene.friction.mu) if not scene.friction.mapped else math.nan
    _, W, _, _ = scene.load.knots()
    w = float(W[0]) if np.all(W == W[0]) else math.nan
    return FrettingRegime(**{**out.__dict__, "friction_coefficient": mu, "normal_force": w,
                             "why_no_closed_form": why})
