"""The limiting state of a sphere's fretting wear in partial slip (Dmitriev, Li and Popov).

A sphere (relative radius R, composite modulus E*) pressed by a constant force W and
fretted by a tangential force cycling between +T* and -T* (|T*| < mu W), with no
normal-tangential coupling (nu = 0, or Dundurs beta = 0), wears only where it slips. The
stick zone is Mindlin's circle of radius c = a (1 - T*/(mu W))^(1/3) and never slips; the
slip annulus wears until it carries no pressure, so that nothing slips under load any more
and wear stops. In that limit ([P14]_, [DVPP16]_, derived by the method of dimensionality reduction,
[PH15]_ ch. 3 and 14):

* the stick radius is still c;
* the pressure is zero in r > c;
* in r < c, with the rigid approach d of the unworn stick zone,

      p(r) = (2 E*/(pi R)) sqrt(c^2 - r^2) + (E*/pi) (d - c^2/R) / sqrt(c^2 - r^2),
      d    = W / (2 E* c) + c^2 / (3 R).

In the method of dimensionality reduction the sphere is the 1-D profile g(x) = x^2/R on a
bed of springs of stiffness E* per unit length. The limit keeps g in |x| < c and wears it
flat to the indenter's depth d outside, so that the line load is E* (d - x^2/R) in
|x| < c and 0 beyond; W = 2 E* (d c - c^3/(3R)) gives d, and Abel's transform
p(r) = -(1/pi) int_r^c q'(x) / sqrt(x^2 - r^2) dx of the line load, whose step of
E* (d - c^2/R) at |x| = c gives the flat punch's inverse square root, gives p. The
surface outside the stick zone is worn down to the loaded, pressure-free surface: its
normal displacement there is (2/pi) int_0^c w(x) / sqrt(r^2 - x^2) dx with
w(x) = d - x^2/R, and the wear depth is what closes the gap to it.

References
----------
.. [P14] V. L. Popov, "Analytic solution for the limiting shape of profiles due to
   fretting wear", Sci. Rep. 4 (2014) 3749, doi:10.1038/srep03749 (the limiting shape
   and its pressure, by the method of dimensionality reduction).
.. [DVPP16] A. I. Dmitriev, L. B. Voll, S. G. Psakhie, V. L. Popov, "Universal limiting
   shape of worn profile under multiple-mode fretting conditions: theory and
   experimental evidence", Sci. Rep. 6 (2016) 23231, doi:10.1038/srep23231; with the
   MDR fretting simulations of Dimaki, Dmitriev, Li, Chai and Popov (2014), and the
   review of I. Argatov, Y. S. Chai, Front. Mech. Eng. 6 (2020) 51.
.. [PH15] V. L. Popov, M. Hess, *Method of Dimensionality Reduction in Contact
   Mechanics and Friction*, Springer, 2015.

The formulas are re-derived above and checked in ``tests/test_wear_limit.py``: the
pressure carries W, and the Boussinesq displacement of that pressure is rigid
(d - r^2/(2R)) over the stick zone, so it solves the contact problem it claims to.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._common import check_positive

__all__ = ["FrettingWearLimit", "fretting_wear_limit"]


@dataclass(frozen=True)
class FrettingWearLimit:
    """The limiting worn state of a sphere under force-controlled fretting, [P14]_.

    Attributes
    ----------
    normal_force : float
        W [N].
    radius : float
        Relative radius of curvature R [m] (unworn profile r^2/(2R)).
    composite_modulus : float
        E* [Pa].
    contact_radius : float
        a [m], Hertz's contact radius before wear.
    stick_radius : float
        c = a (1 - T*/(mu W))^(1/3) [m], Mindlin's, which wear does not change.
    approach : float
        d = W/(2 E* c) + c^2/(3R) [m], the rigid approach in the limit (a^2/R before wear).
    """

    normal_force: float
    radius: float
    composite_modulus: float
    contact_radius: float
    stick_radius: float
    approach: float

    @property
    def edge_factor(self) -> float:
        """(E*/pi) (d - c^2/R) [Pa m], the strength of the 1/sqrt(c^2 - r^2) edge term;
        equal to 2 E* (a^3 - c^3) / (3 pi R c), zero without wear (c = a)."""
        c = self.stick_radius
        return self.composite_modulus / np.pi * (self.approach - c ** 2 / self.radius)

    def pressure(self, r):
        """Limiting pressure p(r) [Pa] at radius ``r`` [m]: the formula in r < c, 0 in
        r >= c (the edge term is singular at r = c, integrably)."""
        r = np.asarray(r, float)
        c, es, rr = self.stick_radius, self.composite_modulus, self.radius
        inside = r < c
        s = np.sqrt(np.where(inside, c ** 2 - r ** 2, 1.0))
        p = 2.0 * es / (np.pi * rr) * s + self.edge_factor / s
        return np.where(inside, p, 0.0)

    def displacement(self, r):
        """Normal surface displacement u(r) [m] of the two bodies together under the
        limiting pressure (positive closing the gap): d - r^2/(2R) in r <= c, and
        (2/pi) [(d - r^2/(2R)) arcsin(c/r) + c sqrt(r^2 - c^2)/(2R)] in r > c."""
        r = np.abs(np.asarray(r, float))
        c, d, rr = self.stick_radius, self.approach, self.radius
        out = r > c
        rs = np.where(out, r, 2.0 * c)
        far = 2.0 / np.pi * ((d - rs ** 2 / (2 * rr)) * np.arcsin(c / rs)
                             + c * np.sqrt(rs ** 2 - c ** 2) / (2 * rr))
        return np.where(out, far, d - r ** 2 / (2 * rr))

    def wear_depth(self, r):
        """Limiting wear depth [m] at radius ``r`` [m] (both bodies together): the depth
        that closes the gap d - r^2/(2R) - u(r) to zero where it is positive; zero in the
        stick zone and beyond the scar."""
        r = np.abs(np.asarray(r, float))
        gap = r ** 2 / (2 * self.radius) + self.displacement(r) - self.approach
        return np.where(r > self.stick_radius, np.clip(-gap, 0.0, None), 0.0)

    @property
    def scar_radius(self) -> float:
        """Outer radius [m] of the worn scar: where the limiting wear depth returns to 0."""
        from scipy import optimize
        c = self.stick_radius
        hi = 2.0 * c
        while self.wear_depth(hi) > 0.0:
            hi *= 2.0
        return float(optimize.brentq(
            lambda r: r ** 2 / (2 * self.radius) + self.displacement(r) - self.approach,
            c * (1 + 1e-9), hi, xtol=1e-15 * hi))


def fretting_wear_limit(normal_force, tangential_amplitude, friction_coefficient, radius,
                        composite_modulus) -> FrettingWearLimit:
    """Limiting profile of a sphere fretted in partial slip ([P14]_).

    Parameters
    ----------
    normal_force : float
        Constant normal force W [N], > 0.
    tangential_amplitude : float
        T* [N]: the tangential force cycles between +T* and -T*; 0 <= T* < mu W.
    friction_coefficient : float
        mu [1], > 0.
    radius : float
        Relative radius of curvature R [m], > 0.
    composite_modulus : float
        E* [Pa], > 0 (see :func:`composite_modulus`); the closed form assumes no
        normal-tangential coupling (nu = 0 or elastically similar bodies).

    Returns
    -------
    FrettingWearLimit
        c = a (1 - T*/(mu W))^(1/3), d = W/(2E*c) + c^2/(3R), and the pressure.
    """
    check_positive("normal_force [N]", normal_force)
    check_positive("friction_coefficient [1]", friction_coefficient)
    check_positive("radius [m]", radius)
    check_positive("composite_modulus [Pa]", composite_modulus)
    mu_w = friction_coefficient * normal_force
    t = float(tangential_amplitude)
    if not (np.isfinite(t) and 0.0 <= t < mu_w):
        raise ValueError(f"tangential_amplitude must be in [0, mu W = {mu_w:.6g}) [N] "
                         f"(partial slip), got {tangential_amplitude!r}")
    a = (3.0 * normal_force * radius / (4.0 * composite_modulus)) ** (1.0 / 3.0)
    c = a * (1.0 - t / mu_w) ** (1.0 / 3.0)
    d = normal_force / (2.0 * composite_modulus * c) + c ** 2 / (3.0 * radius)
    return FrettingWearLimit(float(normal_force), float(radius), float(composite_modulus),
                             float(a), float(c), float(d))
