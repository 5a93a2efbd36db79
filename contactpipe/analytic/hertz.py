"""Hertz contact of elastic bodies (sphere, ellipsoid) and the rigid flat punch.

References: Johnson, *Contact Mechanics* (1985) §4.2 (Hertz) and ch. 3 (pressure
distributions); Sneddon (1965) for the punch. SI units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

from ._common import check_positive

__all__ = ["HertzSphere", "hertz_sphere", "TiltedHertz", "hertz_tilted", "HertzEllipsoid",
           "hertz_ellipsoid", "FlatPunch", "flat_punch"]


# --------------------------------------------------------------------------- Hertz
@dataclass(frozen=True)
class HertzSphere:
    """Hertz contact of two spheres (or sphere on flat), [J85]_ §4.2.

    Attributes
    ----------
    normal_force : float
        W [N].
    radius : float
        Relative radius of curvature R [m].
    composite_modulus : float
        E* [Pa].
    contact_radius : float
        a = (3 W R / (4 E*))^(1/3) [m].
    max_pressure : float
        p0 = 3 W / (2 pi a^2) [Pa].
    approach : float
        Mutual approach delta = a^2 / R [m] (``omega3`` of the conventions).
    """

    normal_force: float
    radius: float
    composite_modulus: float
    contact_radius: float
    max_pressure: float
    approach: float

    @property
    def mean_pressure(self) -> float:
        """Mean pressure W / (pi a^2) = 2 p0 / 3 [Pa]."""
        return self.normal_force / (np.pi * self.contact_radius ** 2)

    def pressure(self, r):
        """Hertz pressure p0 sqrt(1 - r^2/a^2) [Pa] at radius ``r`` [m]; 0 outside."""
        r = np.asarray(r, float)
        a = self.contact_radius
        return self.max_pressure * np.sqrt(np.clip(1.0 - (r / a) ** 2, 0.0, None))


def hertz_sphere(normal_force, radius, composite_modulus) -> HertzSphere:
    """Hertz solution for a sphere of radius R pressed by W ([J85]_ §4.2).

    Parameters
    ----------
    normal_force : float
        Normal force W [N], > 0.
    radius : float
        Relative radius of curvature ``1/R = 1/R1 + 1/R2`` [m].
    composite_modulus : float
        E* [Pa], see :func:`composite_modulus`.

    Returns
    -------
    HertzSphere
        ``a = (3WR/4E*)^(1/3)``, ``p0 = 3W/(2 pi a^2)``, ``delta = a^2/R``.
    """
    check_positive("normal_force [N]", normal_force)
    check_positive("radius [m]", radius)
    check_positive("composite_modulus [Pa]", composite_modulus)
    a = (3.0 * normal_force * radius / (4.0 * composite_modulus)) ** (1.0 / 3.0)
    p0 = 3.0 * normal_force / (2.0 * np.pi * a ** 2)
    return HertzSphere(float(normal_force), float(radius), float(composite_modulus),
                       float(a), float(p0), float(a ** 2 / radius))


@dataclass(frozen=True)
class TiltedHertz:
    """A Hertz sphere contact under a normal force and tilting moments (frictionless).

    A rotation phi of body 1 adds -phi1 x2 - phi2 x1 to the gap r^2 / (2R) (paper eq. 3):
    the same paraboloid, moved to (R phi2, R phi1) and raised by R (phi1^2 + phi2^2) / 2.
    On a half-space, translation-invariant, the contact is therefore the Hertz contact of
    W moved to that centre: its pressure centre is e = (M2/W, M1/W), so phi2 = M2/(W R),
    phi1 = M1/(W R), and the approach is omega3 = a^2/R - R (phi1^2 + phi2^2)/2.

    Attributes
    ----------
    hertz : HertzSphere
        The centred contact of W.
    centre : (float, float)
        (e1, e2) = (M2/W, M1/W) [m], the pressure centre (and the contact's centre).
    rotation : (float, float)
        (phi1, phi2) [rad].
    approach : float
        omega3 [m].
    """

    hertz: HertzSphere
    centre: tuple
    rotation: tuple
    approach: float

    @property
    def max_pressure(self) -> float:
        """p0 [Pa], that of the centred contact."""
        return self.hertz.max_pressure

    @property
    def contact_radius(self) -> float:
        """a [m], that of the centred contact."""
        return self.hertz.contact_radius

    @property
    def moments(self):
        """(M1, M2) = (W e2, W e1) [N m]."""
        W = self.hertz.normal_force
        return W * self.centre[1], W * self.centre[0]

    def pressure(self, x1, x2):
        """p(x1, x2) [Pa]: the Hertz pressure about the moved centre; 0 outside."""
        return self.hertz.pressure(np.hypot(np.asarray(x1, float) - self.centre[0],
                                            np.asarray(x2, float) - self.centre[1]))


def hertz_tilted(normal_force, moment1, moment2, radius, composite_modulus) -> TiltedHertz:
    """A sphere pressed by W and tilted by moments M1 = ∫p x2 dA, M2 = ∫p x1 dA.

    Parameters
    ----------
    normal_force : float
        W [N], > 0.
    moment1, moment2 : float
        M1, M2 [N m] (any sign; the contact moves to (M2/W, M1/W)).
    radius : float
        Relative radius of curvature R [m].
    composite_modulus : float
        E* [Pa].

    Returns
    -------
    TiltedHertz
        The Hertz contact of W centred at e = (M2/W, M1/W), with phi = (M1, M2)/(W R)
        and omega3 = a^2/R - R |phi|^2 / 2 (see :class:`TiltedHertz`). The rotation is a
        gap term only (small angles), so the result holds while the moved contact stays
        on the body's surface that the gap hi describes.
    """
    hz = hertz_sphere(normal_force, radius, composite_modulus)
    W = float(normal_force)
    e = (float(moment2) / W, float(moment1) / W)
    phi = (e[1] / float(radius), e[0] / float(radius))
    omega3 = hz.approach - float(radius) * (phi[0] ** 2 + phi[1] ** 2) / 2.0
    return TiltedHertz(hz, e, phi, float(omega3))


@dataclass(frozen=True)
class HertzEllipsoid:
    """Hertz elliptical contact, [J85]_ §4.2 (elliptical case).

    Attributes
    ----------
    normal_force : float
        W [N].
    radii : tuple of float
        Relative principal radii (R1, R2) [m] in the x1-x3 and x2-x3 planes.
    composite_modulus : float
        E* [Pa].
    semi_axes : tuple of float
        (a1, a2): semi-axes of the contact ellipse along x1 and x2 [m]. The larger one
        lies along the direction of the larger radius.
    max_pressure : float
        p0 = 3 W / (2 pi a1 a2) [Pa].
    approach : float
        Mutual approach delta [m].
    eccentricity : float
        e = sqrt(1 - (b/a)^2) of the ellipse, b <= a its semi-axes [1].
    """

    normal_force: float
    radii: tuple
    composite_modulus: float
    semi_axes: tuple
    max_pressure: float
    approach: float
    eccentricity: float

    @property
    def equivalent_radius(self) -> float:
        """sqrt(a1 a2) [m], the radius of the circle of equal area."""
        return float(np.sqrt(self.semi_axes[0] * self.semi_axes[1]))

    def pressure(self, x1, x2):
        """p0 sqrt(1 - x1^2/a1^2 - x2^2/a2^2) [Pa] at (x1, x2) [m]; 0 outside."""
        x1 = np.asarray(x1, float)
        x2 = np.asarray(x2, float)
        a1, a2 = self.semi_axes
        return self.max_pressure * np.sqrt(
            np.clip(1.0 - (x1 / a1) ** 2 - (x2 / a2) ** 2, 0.0, None))


def _ellipse_ratio(y):
    """B/A = (a/b)^2 E(e) - K(e) over K(e) - E(e), with y = 1 - e^2 = (b/a)^2.

    Written with Carlson's symmetric integrals, K = R_F(0, y, 1) and
    K - E = (e^2/3) R_D(0, y, 1), which avoids the cancellation of K - E at small e:
    B/A = (3 R_F - R_D) / (y R_D).
    """
    rf = special.elliprf(0.0, y, 1.0)
    rd = special.elliprd(0.0, y, 1.0)
    return (3.0 * rf - rd) / (y * rd)


def hertz_ellipsoid(normal_force, radii, composite_modulus) -> HertzEllipsoid:
    """Hertz solution for two bodies with an elliptical gap (principal axes x1, x2).

    The initial gap is ``h = x1^2/(2 R1) + x2^2/(2 R2)`` with ``A = 1/(2R1)``,
    ``B = 1/(2R2)``. With a >= b the semi-axes and e^2 = 1 - b^2/a^2, the
    displacement under the ellipsoidal pressure ([J85]_ ch. 3, §4.2) gives:

    * ``B/A = [(a/b)^2 E(e) - K(e)] / [K(e) - E(e)]``, where here A <= B are the
      smaller and larger of 1/(2R1), 1/(2R2) (the major axis a lies along the smaller
      curvature), is solved for e by :func:`scipy.optimize.brentq` (in ln(1 - e^2));
    * ``a^3 = 3 W [K(e) - E(e)] / (2 pi A E* e^2)``, b = a sqrt(1 - e^2);
    * ``p0 = 3 W / (2 pi a b)`` and ``delta = p0 b K(e) / E*``.

    K, E are the complete elliptic integrals of parameter m = e^2, evaluated through
    Carlson's R_F, R_D (``K = R_F(0, 1-m, 1)``, ``K - E = m R_D(0, 1-m, 1)/3``) to
    keep full precision when R1 ~ R2. For R1 = R2 the result is :func:`hertz_sphere`.

    Parameters
    ----------
    normal_force : float
        W [N], > 0.
    radii : tuple of float
        (R1, R2): relative principal radii of curvature [m] in the x1-x3 and x2-x3
        planes (``1/R1 = 1/R1' + 1/R1''`` over the two bodies), finite and > 0.
    composite_modulus : float
        E* [Pa].

    Returns
    -------
    HertzEllipsoid
    """
    from scipy.optimize import brentq  # ~0.3 s to import: only when needed
    r1, r2 = (float(v) for v in radii)
    check_positive("normal_force [N]", normal_force)
    check_positive("radii [m]", (r1, r2))
    check_positive("composite_modulus [Pa]", composite_modulus)
    if not (np.isfinite(r1) and np.isfinite(r2)):
        raise ValueError("radii must be finite (a line contact is not an ellipse)")
    r_major, r_minor = max(r1, r2), min(r1, r2)
    ratio = r_major / r_minor               # B/A >= 1
    if ratio == 1.0:
        y = 1.0
    else:
        def g(log_y):
            return _ellipse_ratio(np.exp(log_y)) - ratio
        lo = -1.5 * np.log(ratio) - 1.0
        while g(lo) < 0.0:
            lo *= 2.0
        log_y = brentq(g, lo, 0.0, xtol=1e-15, rtol=4 * np.finfo(float).eps,
                                maxiter=500)
        y = float(np.exp(log_y))
    rf = special.elliprf(0.0, y, 1.0)       # K(e)
    rd = special.elliprd(0.0, y, 1.0)       # 3 (K - E) / e^2
    a_major = (normal_force * r_major * rd / (np.pi * composite_modulus)) ** (1.0 / 3.0)
    b_minor = a_major * np.sqrt(y)
    p0 = 3.0 * normal_force / (2.0 * np.pi * a_major * b_minor)
    approach = p0 * b_minor * rf / composite_modulus
    axes = (a_major, b_minor) if r1 >= r2 else (b_minor, a_major)
    return HertzEllipsoid(float(normal_force), (r1, r2), float(composite_modulus),
                          (float(axes[0]), float(axes[1])), float(p0), float(approach),
                          float(np.sqrt(max(1.0 - y, 0.0))))


# --------------------------------------------------------------------------- flat punch
@dataclass(frozen=True)
class FlatPunch:
    """Flat-ended cylindrical punch of radius a ([S65]_, [J85]_ ch. 3).

    Within the half-space approximation (both bodies half-spaces, as in contactpipe)
    the formulae hold for two elastic bodies with the composite modulus E*; for a
    rigid punch E* = E2 / (1 - nu2^2).

    Attributes
    ----------
    normal_force : float
        W [N].
    contact_radius : float
        Punch radius a [m].
    composite_modulus : float
        E* [Pa].
    approach : float
        delta = W / (2 a E*) [m].
    """

    normal_force: float
    contact_radius: float
    composite_modulus: float
    approach: float

    def pressure(self, r):
        """Pressure W / (2 pi a sqrt(a^2 - r^2)) [Pa] at radius ``r`` [m].

        Infinite at ``r = a`` and 0 for ``r > a``; use :meth:`cell_average_pressure`
        to compare with a discretised solution.
        """
        r = np.asarray(r, float)
        a = self.contact_radius
        with np.errstate(divide="ignore", invalid="ignore"):
            p = self.normal_force / (2.0 * np.pi * a * np.sqrt(a * a - r * r))
        return np.where(r < a, p, np.where(r == a, np.inf, 0.0))

    def _corner(self, x, y):
        """Integral of p over [0, x] x [0, y] [N], for x, y >= 0.

        Integrating over x2 first, ``int_0^y dy / sqrt(a^2 - x^2 - y^2) =
        arcsin(min(1, y / sqrt(a^2 - x^2)))``, bounded. The remaining integrand has a
        square-root cusp at ``x_k = sqrt(a^2 - y^2)`` (where the ring crosses x2 = y),
        removed by the substitution ``x = x_k (1 - v^2)`` before Gauss-Kronrod
        quadrature (:func:`scipy.integrate.quad`); beyond x_k it equals pi/2.
        """
        from scipy.integrate import quad  # scipy.integrate loads scipy.optimize: ~0.3 s
        a = self.contact_radius
        xe = min(x, a)
        xk = np.sqrt(max(a * a - y * y, 0.0))
        total = 0.5 * np.pi * max(xe - xk, 0.0)
        upper = min(xe, xk)
        if upper > 0.0 and y > 0.0:
            def f(v):
                xx = xk * (1.0 - v * v)
                arg = y / np.sqrt(max(a * a - xx * xx, 1e-300))
                return np.arcsin(min(arg, 1.0)) * 2.0 * xk * v
            v0 = np.sqrt(max(1.0 - upper / xk, 0.0))
            val, _ = quad(f, v0, 1.0, epsabs=0.0, epsrel=1e-13, limit=200)
            total += val
        elif y == 0.0:
            total = 0.0
        return self.normal_force / (2.0 * np.pi * a) * total

    def cell_average_pressure(self, x1, x2, d1, d2):
        """Exact pressure averaged over each grid cell [Pa].

        The integral over a cell is assembled from corner integrals
        ``Q(x, y) = int_0^x int_0^y p`` (signed by quadrant symmetry) by
        inclusion-exclusion; ``Q`` is computed by :meth:`_corner` (one analytic
        integration, one quadrature with the singular ring's cusp removed), so the
        cells cut by the singular edge are exact to ~1e-12 relative to W. Cells that
        lie entirely outside the punch are exactly 0, and the cell forces of a grid
        covering the punch add up to W.

        Parameters
        ----------
        x1, x2 : array_like
            Cell-centre coordinates [m], broadcast against each other (pass
            ``x1[:, None], x2[None, :]`` for a grid).
        d1, d2 : float
            Cell side lengths [m].

        Returns
        -------
        ndarray
            Mean pressure of each cell [Pa].
        """
        x1, x2 = np.broadcast_arrays(np.asarray(x1, float), np.asarray(x2, float))
        a = self.contact_radius
        xs = np.stack([x1 - 0.5 * d1, x1 + 0.5 * d1])
        ys = np.stack([x2 - 0.5 * d2, x2 + 0.5 * d2])
        # nearest distance of each cell to the centre: cells entirely outside -> 0
        nx = np.where((xs[0] <= 0) & (xs[1] >= 0), 0.0, np.minimum(abs(xs[0]), abs(xs[1])))
        ny = np.where((ys[0] <= 0) & (ys[1] >= 0), 0.0, np.minimum(abs(ys[0]), abs(ys[1])))
        inside = nx * nx + ny * ny < a * a
        cache = {}

        def q(x, y):
            key = (min(abs(x), a), min(abs(y), a))
            if key not in cache:
                cache[key] = self._corner(*key)
            return np.sign(x) * np.sign(y) * cache[key]

        out = np.zeros(x1.shape)
        for idx in np.ndindex(x1.shape):
            if not inside[idx]:
                continue
            x0_, x1_ = xs[(0,) + idx], xs[(1,) + idx]
            y0_, y1_ = ys[(0,) + idx], ys[(1,) + idx]
            force = q(x1_, y1_) - q(x0_, y1_) - q(x1_, y0_) + q(x0_, y0_)
            out[idx] = force / (d1 * d2)
        return out


def flat_punch(normal_force, radius, composite_modulus) -> FlatPunch:
    """Boussinesq flat punch of radius a ([S65]_; [J85]_ ch. 3).

    Parameters
    ----------
    normal_force : float
        W [N], > 0.
    radius : float
        Punch radius a [m].
    composite_modulus : float
        E* [Pa].

    Returns
    -------
    FlatPunch
        ``delta = W / (2 a E*)``, ``p(r) = W / (2 pi a sqrt(a^2 - r^2))``.
    """
    check_positive("normal_force [N]", normal_force)
    check_positive("radius [m]", radius)
    check_positive("composite_modulus [Pa]", composite_modulus)
    return FlatPunch(float(normal_force), float(radius), float(composite_modulus),
                     float(normal_force / (2.0 * radius * composite_modulus)))


