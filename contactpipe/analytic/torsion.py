"""Torsion of elastic spheres in contact: Lubkin's partial slip (Hertzian pressure).

Two spheres pressed by W (Hertz contact radius a, peak pressure p0 = 3W/(2 pi a^2)) are
twisted by a relative rotation beta about their common normal; Coulomb friction mu.
The circumferential shear of an axisymmetric contact causes circumferential displacement
only, independent of Poisson's ratio and with no normal-tangential coupling, so only the
shear moduli enter, through the torsional compliance C = 1/G1 + 1/G2 (a rigid body adds 0).

* Stuck (beta -> 0): q(r) = 3 M r / (4 pi a^3 sqrt(a^2 - r^2)) and the stiffness
  M/beta = 16 a^3 / (3 C) ([J85]_ §7.4; each body 16 G a^3/3).
* Full slip (beta -> inf): q = mu p everywhere and M = 3 pi mu W a / 16.
* Partial slip ([L51]_, [J85]_ §7.4): stick for r < c, slip (q = mu p) in c < r < a. The
  traction is a superposition of rigid-disc twists of radii s in (c, a) (a disc of radius
  s twisted by dbeta carries (4 G dbeta / pi) r / sqrt(s^2 - r^2) and turns every point
  inside it rigidly), whose density is fixed by q = mu p in the slip annulus; the stick
  zone then turns rigidly by beta. With B(s) = int_s^a p(r) dr / sqrt(r^2 - s^2)
  = p0 [K(k) - E(k)], k^2 = 1 - s^2/a^2 (complete elliptic integrals):

      beta(c) = mu C B(c) / 2,
      M(c)    = (8 mu / 3) [c^3 B(c) + 3 int_c^a s^2 B(s) ds].

  These are Lubkin's elliptic-integral curves; the slip in the annulus points along the
  rotation (friction dissipates) and |q| < mu p in the stick zone. Limits: c -> a gives
  the stuck stiffness, c -> 0 the full-slip torque (beta grows without bound).

Units: SI (m, N, Pa, rad, N m).

References
----------
.. [L51] J. L. Lubkin, "The torsion of elastic spheres in contact", J. Appl. Mech. 18
   (1951) 183-187.
.. [J85] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, §7.4.
.. [D54] H. Deresiewicz, "Contact of elastic spheres under an oscillating torsional
   couple", J. Appl. Mech. 21 (1954) 52-56.
"""
from __future__ import annotations

import numpy as np
from scipy import special

from ._common import check_positive, masing_loop

__all__ = ["torsional_compliance", "torsional_stiffness", "full_slip_torque",
           "lubkin_torsion", "lubkin_moment", "torsion_loop_moment"]


def torsional_compliance(young1, poisson1, young2, poisson2) -> float:
    """C = 1/G1 + 1/G2 [1/Pa], G = E / (2 (1 + nu)); a rigid body (E = inf) adds 0."""
    c = 0.0
    for e, nu in ((young1, poisson1), (young2, poisson2)):
        if not np.isinf(e):
            check_positive("Young modulus", e)
            c += 2.0 * (1.0 + nu) / e
    return c


def torsional_stiffness(contact_radius, compliance) -> float:
    """Stuck torsional stiffness M/beta = 16 a^3 / (3 C) [N m/rad] ([J85]_ §7.4).

    Parameters
    ----------
    contact_radius : float
        a [m].
    compliance : float
        C = 1/G1 + 1/G2 [1/Pa] (:func:`torsional_compliance`).
    """
    check_positive("contact_radius", contact_radius)
    check_positive("compliance", compliance)
    return 16.0 * contact_radius ** 3 / (3.0 * compliance)


def full_slip_torque(friction_coefficient, normal_force, contact_radius) -> float:
    """Torque of full sliding under Hertzian pressure, 3 pi mu W a / 16 [N m]
    (integral of mu p r over the contact)."""
    return 3.0 * np.pi * friction_coefficient * normal_force * contact_radius / 16.0


def _b(s, a, p0):
    """B(s) = int_s^a p dr / sqrt(r^2 - s^2) = p0 [K(k) - E(k)], k^2 = 1 - s^2/a^2 [Pa]."""
    p = (np.asarray(s, float) / a) ** 2
    return p0 * (special.ellipkm1(p) - special.ellipe(1.0 - p))


def lubkin_torsion(stick_ratio, friction_coefficient, normal_force, contact_radius,
                   compliance):
    """Lubkin's torque-twist curve, parametrised by the stick radius ratio c/a.

    Parameters
    ----------
    stick_ratio : float or array_like
        c/a in [0, 1]: 1 stuck (no twist), 0 full slip.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    compliance : float
        C = 1/G1 + 1/G2 [1/Pa].

    Returns
    -------
    twist, moment : ndarray
        beta [rad] (inf at c = 0) and M [N m] (0 at c = a, 3 pi mu W a / 16 at c = 0).
    """
    from scipy.integrate import quad  # scipy.integrate loads scipy.optimize: ~0.3 s
    a = float(contact_radius)
    check_positive("contact_radius", a)
    mu, W = float(friction_coefficient), float(normal_force)
    p0 = 3.0 * W / (2.0 * np.pi * a * a)
    ratio = np.atleast_1d(np.asarray(stick_ratio, float))
    if np.any((ratio < 0) | (ratio > 1)):
        raise ValueError(f"stick_ratio must lie in [0, 1], got {stick_ratio!r}")
    twist = np.empty(ratio.shape)
    moment = np.empty(ratio.shape)
    for i, r in enumerate(ratio.ravel()):
        c = r * a
        bc = _b(c, a, p0) if c > 0 else np.inf
        tail, _ = quad(lambda s: s * s * _b(s, a, p0), c, a, limit=200,
                                 epsabs=0.0, epsrel=1e-12)
        twist.flat[i] = 0.5 * mu * compliance * bc
        moment.flat[i] = 8.0 * mu / 3.0 * ((c ** 3 * bc if c > 0 else 0.0) + 3.0 * tail)
    shape = np.shape(stick_ratio)
    return twist.reshape(shape), moment.reshape(shape)


def lubkin_moment(twist, friction_coefficient, normal_force, contact_radius, compliance):
    """Torque M [N m] at a twist beta [rad] (monotonic loading from rest), from
    :func:`lubkin_torsion` by solving beta(c) = |beta| for c (sign of beta kept)."""
    from scipy.optimize import brentq  # ~0.3 s to import: only when needed
    a = float(contact_radius)
    mu, W = float(friction_coefficient), float(normal_force)
    p0 = 3.0 * W / (2.0 * np.pi * a * a)
    beta = np.atleast_1d(np.asarray(twist, float))
    out = np.zeros(beta.shape)
    for i, b in enumerate(beta.ravel()):
        if b == 0.0:
            continue
        target = abs(b)

        def gap(r, target=target):
            return 0.5 * mu * compliance * _b(r * a, a, p0) - target

        lo = 1e-300                          # beta(c) grows like log(1/c) as c -> 0
        if gap(lo) <= 0:
            out.flat[i] = np.sign(b) * full_slip_torque(mu, W, a)
            continue
        r = brentq(gap, lo, 1.0, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        out.flat[i] = np.sign(b) * lubkin_torsion(r, mu, W, a, compliance)[1]
    return out.reshape(np.shape(twist)) if np.ndim(twist) else float(out[0])


def torsion_loop_moment(history, friction_coefficient, normal_force, contact_radius,
                        compliance):
    """Torque M [N m] at every sample of a twist history (rotation control, from rest).

    Masing's rules on Lubkin's virgin curve M_v = :func:`lubkin_moment` (Deresiewicz's
    oscillating torsion, [D54]_, [J85]_ §7.4): from the last remembered reversal
    (beta_r, M_r) the branch is ``M = M_r + s 2 M_v(|beta - beta_r| / 2)`` (s the
    direction); a branch that reaches the one it left wipes both reversals, and one that
    passes -beta_r after a single reversal rejoins the (odd) virgin curve. The stick zone
    never vanishes at a finite twist, so the torque only tends to 3 pi mu W a / 16.

    Parameters
    ----------
    history : array_like
        beta [rad] samples, linear between samples, from rest at 0.
    friction_coefficient, normal_force, contact_radius, compliance
        mu [1], W [N], a [m], C = 1/G1 + 1/G2 [1/Pa].

    Returns
    -------
    ndarray
        M [N m] at each sample.
    """
    def virgin(b):
        return float(lubkin_moment(b, friction_coefficient, normal_force, contact_radius,
                                   compliance))

    return masing_loop(history, virgin)
