"""Stresses beneath a sliding Hertzian (spherical) contact, in closed form (Hamilton 1983).

A half-space carries the Hertz pressure ``p = p0 sqrt(1 - r^2/a^2)`` and, sliding, the
shear ``q1 = mu p`` along +x1 (the traction exerted on the half-space: it drags the
surface towards +x1, so the trailing edge is x1 = -a). Frame x1, x2 in the surface, x3 >= 0
the depth; tension > 0 (docs/conventions.md). Hamilton's explicit equations give the
whole field; with X = x1/a, Y = x2/a, Z = x3/a, r^2 = X^2 + Y^2:

    A = r^2 + Z^2 - 1,  S = sqrt(A^2 + 4 Z^2),  M = sqrt((S + A)/2),  N = sqrt((S - A)/2),
    phi = atan(1/M),    G = M^2 - N^2 + Z M - N,  H = 2 M N + M + Z N,

and each component is ``p0 * n_ij(X, Y, Z) + mu p0 * t_ij(X, Y, Z)`` with the functions
n_ij (normal load) and t_ij (tangential load) of Hamilton's paper (written out in
:func:`_normal_part` and :func:`_tangential_part`). They have removable singularities on
the axis r = 0; there the limits are used (Johnson's eq. 3.45 for the normal part; for
the tangential part only s13 survives on the axis, by symmetry:
``s13 = -(3/2) mu p0 [1 - Z atan(1/Z) - 1/(3 (1 + Z^2))]``, the integral of Cerruti's
shear stress over the Hertz shear). Near the axis the formulas cancel digits (relative
error about 1e-16 (a/r)^4), so for r < 0.02 a each component is interpolated along its
ray, quadratically in r, through the axis value and the closed forms at r = 0.02 a and
0.04 a (the field is smooth there): error below 1e-6 p0.

On the surface the largest tension is at the trailing edge (x1 = -a, x2 = 0):
``s11 = p0 [(1 - 2 nu)/3 + (4 + nu) pi mu / 8]`` (:func:`trailing_edge_tension`).

References
----------
.. [H83] G. M. Hamilton, "Explicit equations for the stresses beneath a sliding spherical
   contact", Proc. Instn Mech. Engrs C 197 (1983) 53-59.
   doi:10.1243/PIME_PROC_1983_197_076_02
.. [HG66] G. M. Hamilton, L. E. Goodman, "The stress field created by a circular sliding
   contact", J. Appl. Mech. 33 (1966) 371-376. doi:10.1115/1.3625051
.. [J85] K. L. Johnson, *Contact Mechanics*, 1985, eq. 3.45 (the Hertz axis).
"""
from __future__ import annotations

import numpy as np

from ._common import check_positive

__all__ = ["hamilton_stress", "trailing_edge_tension", "hertz_axis_stress"]

COMPONENTS = ("s11", "s22", "s33", "s12", "s13", "s23")
# Below this r/a the closed forms (which cancel ~1e-16 (a/r)^4) are replaced by the
# quadratic in r through the axis value and the closed forms at NEAR and 2 NEAR.
NEAR = 0.02


def _auxiliaries(X, Y, Z):
    r2 = X * X + Y * Y
    A = r2 + Z * Z - 1.0
    S = np.sqrt(A * A + 4.0 * Z * Z)
    M = np.sqrt(np.clip(0.5 * (S + A), 0.0, None))
    N = np.sqrt(np.clip(0.5 * (S - A), 0.0, None))
    phi = np.arctan2(1.0, M)
    G = M * M - N * N + Z * M - N
    H = 2.0 * M * N + M + Z * N
    return r2, A, S, M, N, phi, G, H


def _normal_part(X, Y, Z, nu):
    """Hamilton's n_ij: the stress of the Hertz pressure per p0 (off the axis, Z > 0)."""
    r2, A, S, M, N, phi, G, H = _auxiliaries(X, Y, Z)
    x2, y2, z2 = X * X, Y * Y, Z * Z
    common = (1 - nu) * N * z2 - (1 - 2 * nu) / 3 * (N * S + 2 * A * N + 1) - nu * M * Z
    s11 = (1 + nu) * Z * phi + ((y2 - x2) / r2 * common - N * (x2 + 2 * nu * y2)
                                - M * x2 * Z / S) / r2
    s22 = (1 + nu) * Z * phi + ((x2 - y2) / r2 * common - N * (y2 + 2 * nu * x2)
                                - M * y2 * Z / S) / r2
    s33 = -N + Z * M / S
    s12 = (X * Y * (1 - 2 * nu) / r2 ** 2
           * (-N * r2 + 2 / 3 * N * (S + 2 * A) - Z * (Z * N + M) + 2 / 3)
           + X * Y * Z / r2 ** 2 * (-M * r2 / S - Z * N + M))
    gh = Z * H / (G * G + H * H)
    s13 = -Z * X * (N / S - gh)
    s23 = -Z * Y * (N / S - gh)
    return dict(zip(COMPONENTS, (s11, s22, s33, s12, s13, s23), strict=True))


def _tangential_part(X, Y, Z, nu):
    """Hamilton's t_ij: the stress of the shear mu p along +x1, per mu p0 (off the axis)."""
    r2, A, S, M, N, phi, G, H = _auxiliaries(X, Y, Z)
    x2, y2, z2 = X * X, Y * Y, Z * Z
    r4 = r2 * r2
    k = 1 - 2 * nu
    fx = 1.5 - 2 * x2 / r2          # (3/2 - 2 X^2/r^2)
    hx = 0.5 - 2 * x2 / r2          # (1/2 - 2 X^2/r^2)
    hy = 0.5 - 2 * y2 / r2
    s11 = (-X * (nu / 4 + 1) * phi
           + X * M / r4 * (fx * (nu * S - 2 * nu * A + z2) + x2 * z2 / S + 7 * nu * r2 / 4
                           - 2 * nu * x2 + r2)
           + X * Z * N / r4 * (fx * (-k * S / 6 - k * A / 3 - (z2 + 3) / 2) + x2 / S
                               - nu * r2 / 4 - 7 * r2 / 4)
           + 4 * X * Z / (3 * r4) * fx * k)
    s22 = (-3 * nu * X * phi / 4
           + X * M / r4 * (hy * (nu * (S - 2 * A + r2) + z2) + y2 * z2 / S + 3 * nu * r2 / 4)
           + Z * X * N / r4 * (hy * (-k * S / 6 - k * A / 3 - z2 / 2 - 1.5) + y2 / S
                               - 3 * nu * r2 / 4 - r2 / 4)
           + 4 * Z * X / (3 * r4) * hy * k)
    s33 = Z * X * N / (2 * r2) * (1 - (r2 + z2 + 1) / S)
    s12 = (Y / 2 * (nu / 2 - 1) * phi
           + Y * M / r4 * (x2 * z2 / S + nu * ((S - 2 * A) * hx - 2 * x2 + r2 / 4) + r2 / 2
                           + z2 * hx)
           + Y * Z * N / r4 * (hx * (-k * (S / 6 + A / 3) - z2 / 2 - 1.5 - r2 / 2)
                               + nu * r2 / 4 + x2 / S - y2 / 2 - 1.5 * x2)
           + 4 * Y * Z / (3 * r4) * hx * k)
    s13 = (1.5 * Z * phi + Z * M / r2 * (1 + x2 / r2 - x2 / S)
           + N / r2 * (-0.75 * (S + 2 * A) + z2 - 0.75 - r2 / 4 + z2 / 2 * hx))
    s23 = X * Y * Z / (2 * r4) * (M * (0.5 + (z2 / 2 - 1.5 - r2 / 2) / S)
                                  + Z * N / 2 * (-3 + (5 + z2 + r2) / S))
    return dict(zip(COMPONENTS, (s11, s22, s33, s12, s13, s23), strict=True))


def hertz_axis_stress(x3, contact_radius, max_pressure, poisson):
    """Stresses on the axis of a Hertz contact (Johnson eq. 3.45).

    Parameters
    ----------
    x3 : array_like
        Depth [m], >= 0.
    contact_radius : float
        a [m].
    max_pressure : float
        p0 [Pa].
    poisson : float
        nu [1].

    Returns
    -------
    dict
        ``s11 = s22`` (radial and hoop), ``s33`` [Pa], tension > 0.
    """
    z = np.asarray(x3, dtype=float) / float(contact_radius)
    nu = float(poisson)
    p0 = float(max_pressure)
    z_atan = np.where(z > 0, z * np.arctan2(1.0, z), 0.0)
    s_r = p0 * (-(1 + nu) * (1 - z_atan) + 0.5 / (1 + z * z))
    return {"s11": s_r, "s22": s_r.copy(), "s33": -p0 / (1 + z * z)}


def hamilton_stress(x1, x2, x3, contact_radius, max_pressure, friction_coefficient,
                    poisson):
    """The stress field beneath a sliding Hertz contact [H83]_.

    Parameters
    ----------
    x1, x2 : array_like
        Position in the surface plane, from the centre of the contact [m].
    x3 : array_like
        Depth [m], > 0 (at x3 = 0 the closed forms divide by S = 0 on the edge r = a).
    contact_radius : float
        a [m].
    max_pressure : float
        p0 [Pa].
    friction_coefficient : float
        mu [1]; the shear mu p acts on the half-space along +x1. 0 for Hertz alone.
    poisson : float
        nu [1] of the half-space.

    Returns
    -------
    dict
        ``s11, s22, s33, s12, s13, s23`` [Pa], tension > 0, of the broadcast shape.
    """
    check_positive("contact_radius", contact_radius)
    check_positive("max_pressure", max_pressure)
    a = float(contact_radius)
    X, Y, Z = np.broadcast_arrays(*(np.asarray(v, dtype=float) / a for v in (x1, x2, x3)))
    if np.any(Z <= 0):
        raise ValueError("hamilton_stress: x3 must be > 0 (the closed forms are singular "
                         "on the contact edge at the surface)")
    p0 = float(max_pressure)
    mu = float(friction_coefficient)
    nu = float(poisson)
    r = np.hypot(X, Y)
    near = r < NEAR
    out = _off_axis(X, Y, Z, p0, mu, nu)
    if np.any(near):
        Zn = Z[near]
        rn = r[near]
        safe = np.where(rn > 0, rn, 1.0)
        cx = np.where(rn > 0, X[near] / safe, 1.0)
        cy = np.where(rn > 0, Y[near] / safe, 0.0)
        f1 = _off_axis(NEAR * cx, NEAR * cy, Zn, p0, mu, nu)
        f2 = _off_axis(2 * NEAR * cx, 2 * NEAR * cy, Zn, p0, mu, nu)
        f0 = _on_axis(Zn, p0, mu, nu)
        u = rn / NEAR                       # Lagrange in u through u = 0, 1, 2
        l0, l1, l2 = (u - 1) * (u - 2) / 2, -u * (u - 2), u * (u - 1) / 2
        for c in COMPONENTS:
            out[c][near] = l0 * f0[c] + l1 * f1[c] + l2 * f2[c]
    return out


def _off_axis(X, Y, Z, p0, mu, nu):
    with np.errstate(divide="ignore", invalid="ignore"):     # r = 0: replaced by the caller
        n = _normal_part(X, Y, Z, nu)
        t = _tangential_part(X, Y, Z, nu)
    return {c: np.array(p0 * n[c] + mu * p0 * t[c], dtype=float) for c in COMPONENTS}


def _on_axis(Z, p0, mu, nu):
    ax = hertz_axis_stress(Z, 1.0, p0, nu)
    zero = np.zeros_like(Z)
    s13 = -1.5 * mu * p0 * (1 - Z * np.arctan2(1.0, Z) - 1 / (3 * (1 + Z * Z)))
    return {"s11": ax["s11"], "s22": ax["s22"], "s33": ax["s33"], "s12": zero,
            "s13": s13, "s23": zero}


def trailing_edge_tension(max_pressure, friction_coefficient, poisson):
    """Largest surface tension under a sliding Hertz contact, at its trailing edge [Pa].

    ``p0 [(1 - 2 nu)/3 + (4 + nu) pi mu / 8]`` at x1 = -a, x2 = 0, x3 = 0 [H83]_.
    """
    nu = float(poisson)
    return float(max_pressure) * ((1 - 2 * nu) / 3
                                  + (4 + nu) * np.pi * float(friction_coefficient) / 8)
