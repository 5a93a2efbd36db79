"""Bodies and their constitutive laws: rigid, elastic, linear viscoelastic.

By default a viscoelastic body has a constant Poisson ratio, so its creep function factors
as ``Phi(t) = (1 + nu) / E * phi(t)`` (paper eq. 9; the paper's Phi is half the shear
creep compliance J(t) = phi(t)/G = 2 (1 + nu) phi(t)/E), where ``E`` is the
*instantaneous* (glassy) Young modulus and ``phi`` the normalised creep function
(phi(0) = 1).  The one exception is Kelvin-Voigt, which has no instantaneous elasticity:
there ``E`` is the long-term modulus and phi(t) = 1 - exp(-t/tau) starts at zero.

With ``bulk = "elastic"`` (:class:`Body`) phi is the shear creep compliance instead,
J(t) = phi(t)/G, while the bulk modulus K = E/(3(1 - 2 nu)) keeps the value it has where
phi = 1: the Poisson ratio then varies in time (towards 1/2 as the shear modulus relaxes),
and the influence coefficients split into parts with their own creep functions
(:func:`elastic_bulk_parts`).

Every normalised creep function here has the form

    phi(t) = a + b t + sum_i d_i exp(-t / tau_i)          [1]

which is what makes the O(N)-per-step recursion of :mod:`contactpipe.solver.memory` possible.
A tabulated creep function (:class:`TabulatedCreep`) is also offered; it needs the
direct (O(k N) per step) Boltzmann sum. Measured data (a creep or relaxation table, or
storage and loss moduli over frequency) give a Prony series of that form through
:func:`fit_creep_compliance`, :func:`fit_relaxation_modulus` and :func:`fit_dynamic_moduli`.
:func:`step_start_stable_step` is the largest stable step of the paper's step-start rule.

The creep functions live in :mod:`contactpipe.materials.creep`, the fits and table files
in :mod:`contactpipe.materials.fitting`; everything public is imported here.

Units: moduli [Pa], times [s]; phi is dimensionless.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .creep import (
    ELASTIC,
    ExponentialCreep,
    TabulatedCreep,
    bulk_ratio,
    combine,
    elastic_bulk_parts,
    kelvin_voigt,
    maxwell,
    prony,
    relaxation_from_creep,
    step_start_stable_step,
    zener,
)
from .fitting import (
    FIT_TOLERANCE,
    TABLE_KINDS,
    PronyFit,
    compliance_error,
    fit_creep_compliance,
    fit_dynamic_moduli,
    fit_relaxation_modulus,
    fit_table_file,
    read_table_file,
    table_time_span,
)

__all__ = [
    "ExponentialCreep", "TabulatedCreep", "ELASTIC", "maxwell", "kelvin_voigt", "zener",
    "prony", "Body", "dundurs_beta", "composite_modulus", "step_start_stable_step",
    "PronyFit", "fit_creep_compliance", "fit_relaxation_modulus", "fit_dynamic_moduli",
    "combine", "relaxation_from_creep", "bulk_ratio", "elastic_bulk_parts", "BULK",
    "TABLE_KINDS", "read_table_file", "fit_table_file", "table_time_span",
    "compliance_error", "FIT_TOLERANCE",
]


#: How a viscoelastic body's bulk modulus behaves: "creep" (it creeps with the shear
#: modulus, the same phi: a constant Poisson ratio, paper eq. 9) or "elastic".
BULK = ("creep", "elastic")


@dataclass(frozen=True)
class Body:
    """One contacting body.

    Parameters
    ----------
    kind : {"rigid", "elastic", "viscoelastic"}
    young : float
        Young modulus [Pa]; the instantaneous (glassy) one for a viscoelastic body,
        except Kelvin-Voigt where it is the long-term modulus. Unused when rigid.
    poisson : float
        Poisson ratio [1], in [0, 0.5]; with ``bulk = "elastic"`` its value where phi = 1.
    creep : ExponentialCreep or TabulatedCreep
        Normalised creep function phi(t); :data:`ELASTIC` for elastic or rigid bodies.
    bulk : {"creep", "elastic"}
        "creep" (default): every compliance creeps with phi, nu is constant (paper
        eq. 9). "elastic": phi is the shear compliance J(t)/J at phi = 1, the bulk
        modulus E/(3(1 - 2 nu)) does not creep, nu(t) varies (:func:`elastic_bulk_parts`).
    """

    kind: str = "elastic"
    young: float = np.inf
    poisson: float = 0.3
    creep: object = field(default=ELASTIC)
    bulk: str = "creep"

    @property
    def rigid(self) -> bool:
        return self.kind == "rigid"

    @property
    def has_memory(self) -> bool:
        return self.kind == "viscoelastic" and not self.creep.is_elastic

    @property
    def split(self) -> bool:
        """True when the Poisson ratio varies in time: the kernels split into a shear part
        and a Poisson part with their own creep functions (:attr:`part_creeps`)."""
        return self.has_memory and self.bulk == "elastic" and self.poisson < 0.5

    @property
    def part_creeps(self) -> tuple:
        """The normalised creep functions of the body's kernel parts [1]: (phi,) for a
        constant Poisson ratio (one kernel set, :func:`~contactpipe.solver.influence.body_kernels`),
        (phi_shear, phi_poisson) when :attr:`split`
        (:func:`~contactpipe.solver.influence.body_kernel_parts`)."""
        if self.split:
            return elastic_bulk_parts(self.creep, float(self.poisson))
        return (self.creep,)

    @property
    def normal_creep(self):
        """The normal compliance (1 - nu)/G as a creep function, normalised by its value
        where phi = 1 [1]: phi itself for a constant Poisson ratio. A rigid sphere's
        normal contact (Lee-Radok) depends on this function alone."""
        if not self.split:
            return self.creep
        shear, part = self.part_creeps
        return combine([(1.0 / (1.0 - self.poisson), shear),
                        (-1.0 / (1.0 - self.poisson), part)], "normal")

    @property
    def coupling_creep(self):
        """The coupling compliance (1 - 2 nu)/G as a creep function, normalised like
        :attr:`normal_creep` [1] (phi for a constant Poisson ratio)."""
        if not self.split:
            return self.creep
        shear, part = self.part_creeps
        w = 1.0 / (1.0 - 2.0 * self.poisson)
        return combine([(w, shear), (-2.0 * w, part)], "coupling")

    @property
    def rule_creeps(self) -> tuple:
        """The compliances a time rule must integrate well [1]: phi, and with a varying
        Poisson ratio the normal compliance too."""
        return (self.creep, self.normal_creep) if self.split else (self.creep,)

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)) [Pa]; inf for a rigid body."""
        return np.inf if self.rigid else self.young / (2.0 * (1.0 + self.poisson))

    @property
    def normal_compliance(self) -> float:
        """(1 - nu^2)/E [1/Pa]; 0 for a rigid body."""
        return 0.0 if self.rigid else (1.0 - self.poisson ** 2) / self.young

    @property
    def coupling_compliance(self) -> float:
        """(1 - 2 nu)/G [1/Pa], the factor of the normal-tangential coupling terms."""
        return 0.0 if self.rigid else (1.0 - 2.0 * self.poisson) / self.shear_modulus


def composite_modulus(b1: Body, b2: Body, phi1: float = 1.0, phi2: float = 1.0) -> float:
    """Composite modulus E* [Pa]: 1/E* = phi1 (1-nu1^2)/E1 + phi2 (1-nu2^2)/E2."""
    c = phi1 * b1.normal_compliance + phi2 * b2.normal_compliance
    return np.inf if c == 0 else 1.0 / c


def dundurs_beta(b1: Body, b2: Body) -> float:
    """Dundurs' second parameter (instantaneous moduli), with body 1 the indenter.

    beta = [(1-2nu1)/G1 - (1-2nu2)/G2] / (2 [(1-nu1)/G1 + (1-nu2)/G2]).
    Zero for identical materials, for two incompressible bodies, and for a rigid body on
    an incompressible one: then normal and tangential problems do not couple.
    """
    num = b1.coupling_compliance - b2.coupling_compliance
    den1 = 0.0 if b1.rigid else 2.0 * (1.0 - b1.poisson) / b1.shear_modulus
    den2 = 0.0 if b2.rigid else 2.0 * (1.0 - b2.poisson) / b2.shear_modulus
    den = den1 + den2
    return 0.0 if den == 0 else 0.5 * num / (0.5 * den)
