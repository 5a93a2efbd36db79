"""Closed-form contact solutions, for users and for the validation tests.

Everything is in SI units (m, N, Pa, s, J) and follows ``docs/conventions.md``:
``p > 0`` presses body 2, tangential tractions ``q`` have the sign of the applied
tangential force ``T`` (acting along x1), and the tangential rigid displacement
``omega1`` of body 1 relative to body 2 has the sign of ``T``.

Contents
--------
Normal contact (elastic)
    :func:`composite_modulus`, :func:`hertz_sphere`, :func:`hertz_ellipsoid`,
    :func:`flat_punch`.
Tangential contact (elastic, Hertzian normal pressure, no coupling: beta = 0)
    :func:`cattaneo_mindlin` (monotonic loading),
    :func:`masing_memory`, :func:`mindlin_deresiewicz_traction`, :func:`stick_radius`,
    :func:`tangential_displacement`, :func:`energy_per_cycle` (arbitrary
    piecewise-monotonic history, Mindlin-Deresiewicz / Masing / Jaeger rule),
    :func:`tangential_compliance_sum`.
Displacement control and gross slip (a fretting rig)
    :func:`gross_slip_displacement`, :func:`mindlin_force` (first branch),
    :func:`displacement_loop_force` (any displacement history, with sliding),
    :func:`displacement_energy_per_cycle` (E_MD(mu W) + 4 mu W (delta* - delta_gs)),
    :func:`gross_slip_boundary` (delta_gs(mu, W) of a sphere: the fretting map's boundary),
    :func:`energy_ratio` (Fouvry's A = E/(4 T* delta*) against delta*/delta_gs).
Moments
    :func:`hertz_tilted` (a Hertz contact under tilting moments: moved by M/W, phi = e/R);
    :func:`torsional_compliance`, :func:`torsional_stiffness`, :func:`full_slip_torque`,
    :func:`lubkin_torsion`, :func:`lubkin_moment` (torsion of spheres in partial slip),
    :func:`torsion_loop_moment` (any twist history, Masing's rules on Lubkin's curve).
Frictional indentation of dissimilar bodies (Spence)
    :func:`spence_stick_ratio` (the stick radius over the contact radius of a sphere
    pressed with friction on a dissimilar body, constant while the load grows).
Viscoelastic normal contact (rigid sphere, Lee-Radok)
    :func:`lee_radok_sphere`, :func:`lee_radok_radius`, :func:`relaxation_function`,
    :func:`lee_radok_pressure`.
Fretting wear (sphere, partial slip, force control)
    :func:`fretting_wear_limit` (Popov's limiting worn state: stick radius, pressure,
    approach and wear depth once the slip annulus has worn to zero pressure).
Utility
    :func:`cell_average` (Gauss-Legendre average of a closed-form field over grid cells).

References
----------
.. [J85] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985:
   ch. 3 (pressure distributions on a half-space), §4.2 (Hertz), §7.2-7.3
   (Cattaneo, Mindlin, Mindlin-Deresiewicz; energy loss per cycle eq. 7.64).
.. [MD53] R. D. Mindlin, H. Deresiewicz, "Elastic spheres in contact under varying
   oblique forces", J. Appl. Mech. 20 (1953) 327-344.
.. [LR60] E. H. Lee, J. R. M. Radok, "The contact problem for viscoelastic bodies",
   J. Appl. Mech. 27 (1960) 438-444.
.. [T66] T. C. T. Ting, "The contact stresses between a rigid indenter and a
   viscoelastic half-space", J. Appl. Mech. 33 (1966) 845-854.
.. [S65] I. N. Sneddon, "The relation between load and penetration in the
   axisymmetric Boussinesq problem for a punch of arbitrary profile",
   Int. J. Eng. Sci. 3 (1965) 47-57.
.. [L51] J. L. Lubkin, "The torsion of elastic spheres in contact", J. Appl. Mech. 18
   (1951) 183-187 (and [J85]_ §7.4).
.. [S75] D. A. Spence, "The Hertz contact problem with finite friction", J. Elasticity 5
   (1975) 297-319 (and [J85]_ §5.2).
.. [P14] V. L. Popov, "Analytic solution for the limiting shape of profiles due to
   fretting wear", Sci. Rep. 4 (2014) 3749 (see :mod:`contactpipe.analytic.wear_limit`).
.. [Ja98] J. Jaeger, "A new principle in contact mechanics", J. Tribol. 120 (1998)
   677-684 (superposition of Cattaneo distributions for load histories).
"""
from __future__ import annotations

from ._common import cell_average, composite_modulus, tangential_compliance_sum
from .hertz import (
                    FlatPunch,
                    HertzEllipsoid,
                    HertzSphere,
                    TiltedHertz,
                    flat_punch,
                    hertz_ellipsoid,
                    hertz_sphere,
                    hertz_tilted,
)
from .lee_radok import (
                    LeeRadokContact,
                    lee_radok_pressure,
                    lee_radok_radius,
                    lee_radok_sphere,
                    relaxation_function,
)
from .mindlin import (
                    ENERGY_RATIO_TRANSITION,
                    CattaneoMindlin,
                    cattaneo_mindlin,
                    displacement_energy_per_cycle,
                    displacement_loop_force,
                    energy_per_cycle,
                    energy_ratio,
                    gross_slip_boundary,
                    gross_slip_displacement,
                    masing_memory,
                    mindlin_deresiewicz_traction,
                    mindlin_force,
                    stick_radius,
                    tangential_displacement,
)
from .spence import spence_stick_ratio
from .torsion import (
                    full_slip_torque,
                    lubkin_moment,
                    lubkin_torsion,
                    torsion_loop_moment,
                    torsional_compliance,
                    torsional_stiffness,
)
from .wear_limit import FrettingWearLimit, fretting_wear_limit

__all__ = [
    "composite_modulus", "tangential_compliance_sum",
    "HertzSphere", "hertz_sphere", "TiltedHertz", "hertz_tilted",
    "HertzEllipsoid", "hertz_ellipsoid",
    "FlatPunch", "flat_punch",
    "CattaneoMindlin", "cattaneo_mindlin",
    "masing_memory", "mindlin_deresiewicz_traction", "stick_radius",
    "tangential_displacement", "energy_per_cycle",
    "gross_slip_displacement", "mindlin_force", "displacement_loop_force",
    "displacement_energy_per_cycle", "gross_slip_boundary", "energy_ratio",
    "ENERGY_RATIO_TRANSITION",
    "torsional_compliance", "torsional_stiffness", "full_slip_torque", "lubkin_torsion",
    "lubkin_moment", "torsion_loop_moment",
    "LeeRadokContact", "lee_radok_sphere", "lee_radok_radius", "relaxation_function",
    "lee_radok_pressure",
    "spence_stick_ratio",
    "FrettingWearLimit", "fretting_wear_limit",
    "cell_average",
]
