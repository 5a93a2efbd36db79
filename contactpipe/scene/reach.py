"""How large the contact grows: Hertz estimates of its semi-axes under the largest load
(the creep of a viscoelastic body over the load window included), a tilt's shift, and the
automatic grid size that holds them (:func:`contact_reach`, :func:`auto_grid_size`)."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["hertz_semi_axes", "contact_reach", "contact_shifts", "auto_grid_size",
           "AUTO_MARGIN", "AUTO_PUNCH_FACTOR"]

#: Hertz margin of ``grid.size = "auto"``: side = 2 * margin * contact semi-axis.
AUTO_MARGIN = 1.5
#: ``grid.size = "auto"`` for a flat punch: side = this times the punch radius.
AUTO_PUNCH_FACTOR = 2.5

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
        (a1, a2) [m] along x1, x2; None for a surface or a rough one (no estimate).
    """
    if geometry.shape in ("surface", "rough"):
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
    if geometry.shape in ("surface", "rough"):
        return None
    t, W = load.knots()[:2]
    out: list[tuple[float, str | None, float | None, float | None, float]] = [
        (0.0, None, None, None, 0.0)] * 2
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
    if geometry.shape in ("surface", "rough"):
        return None
    a = hertz_semi_axes(geometry, indenter, halfspace, load)
    shifts = contact_shifts(geometry, load)
    return tuple(float(ai + s[0]) for ai, s in zip(a, shifts, strict=True))


def auto_grid_size(geometry, indenter, halfspace, load):
    """Grid sides (L1, L2) [m] of ``grid.size = "auto"``: 2 * :data:`AUTO_MARGIN` times
    the reach of the largest contact (:func:`contact_reach`: the Hertz semi-axes plus
    a tilt's shift), or :data:`AUTO_PUNCH_FACTOR` times a flat punch's radius; None for
    a surface."""
    if geometry.shape in ("surface", "rough"):
        return None
    if geometry.shape == "flat_punch":
        side = AUTO_PUNCH_FACTOR * geometry.radius
        return side, side
    reach = contact_reach(geometry, indenter, halfspace, load)
    return tuple(float(2 * AUTO_MARGIN * r) for r in reach)


def _knot_values(values, t):
    """A program key's values at the knots (a scalar is a step)."""
    if isinstance(values, tuple):
        return np.array(values, dtype=float)
    return np.full(np.shape(t), float(values))
