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
Viscoelastic normal contact (rigid sphere, Lee-Radok)
    :func:`lee_radok_sphere`, :func:`lee_radok_radius`, :func:`relaxation_function`,
    :func:`lee_radok_pressure`.
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
.. [Ja98] J. Jaeger, "A new principle in contact mechanics", J. Tribol. 120 (1998)
   677-684 (superposition of Cattaneo distributions for load histories).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize, special

from .exceptions import GrossSlidingError

__all__ = [
    "composite_modulus", "tangential_compliance_sum",
    "HertzSphere", "hertz_sphere", "HertzEllipsoid", "hertz_ellipsoid",
    "FlatPunch", "flat_punch",
    "CattaneoMindlin", "cattaneo_mindlin",
    "masing_memory", "mindlin_deresiewicz_traction", "stick_radius",
    "tangential_displacement", "energy_per_cycle",
    "LeeRadokContact", "lee_radok_sphere", "lee_radok_radius", "relaxation_function",
    "lee_radok_pressure",
    "cell_average",
]


# --------------------------------------------------------------------------- helpers
def composite_modulus(young1, poisson1, young2, poisson2) -> float:
    """Hertz composite (plane-strain) modulus E*.

    ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2`` ([J85]_ §4.2); an infinite Young
    modulus stands for a rigid body.

    Parameters
    ----------
    young1, young2 : float
        Young moduli of the two bodies [Pa]; ``np.inf`` for a rigid body.
    poisson1, poisson2 : float
        Poisson ratios [1].

    Returns
    -------
    float
        E* [Pa]; ``inf`` when both bodies are rigid.
    """
    c = 0.0
    for e, nu in ((young1, poisson1), (young2, poisson2)):
        if not np.isinf(e):
            if e <= 0:
                raise ValueError(f"Young modulus must be > 0 [Pa], got {e!r}")
            c += (1.0 - nu ** 2) / e
    return np.inf if c == 0.0 else 1.0 / c


def tangential_compliance_sum(young1, poisson1, young2, poisson2) -> float:
    """Mindlin's tangential compliance sum ``(2 - nu1)/G1 + (2 - nu2)/G2``.

    ``G = E / (2 (1 + nu))``; a rigid body (``E = inf``) contributes 0.

    Parameters
    ----------
    young1, young2 : float
        Young moduli [Pa]; ``np.inf`` for a rigid body.
    poisson1, poisson2 : float
        Poisson ratios [1].

    Returns
    -------
    float
        Compliance sum [1/Pa] used by :func:`tangential_displacement` and
        :func:`energy_per_cycle`.
    """
    c = 0.0
    for e, nu in ((young1, poisson1), (young2, poisson2)):
        if not np.isinf(e):
            g = e / (2.0 * (1.0 + nu))
            c += (2.0 - nu) / g
    return c


def _positive(name, value):
    if not np.all(np.asarray(value) > 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")


def cell_average(f, x1, x2, d1, d2, order: int = 8, radial: bool = False):
    """Average of a closed-form field over rectangular grid cells.

    Each cell ``[x1 - d1/2, x1 + d1/2] x [x2 - d2/2, x2 + d2/2]`` is integrated with an
    ``order x order`` tensor Gauss-Legendre rule and divided by its area ``d1 d2``.
    This is what a piecewise-constant numerical traction should be compared with.
    Do not use it for fields with an integrable singularity inside a cell (see
    :meth:`FlatPunch.cell_average_pressure`); fields with a square-root edge
    (Hertz, Cattaneo) converge, more slowly, in the cells cut by the edge.

    Parameters
    ----------
    f : callable
        Vectorised field ``f(x1, x2)`` (positions [m]) or, with ``radial=True``,
        ``f(r)`` with ``r = hypot(x1, x2)`` [m]. Any units; the average has the same.
    x1, x2 : array_like
        Cell-centre coordinates [m], broadcast against each other (for a grid pass
        ``x1[:, None], x2[None, :]`` or the output of ``np.meshgrid(..., indexing="ij")``).
    d1, d2 : float
        Cell side lengths along x1, x2 [m].
    order : int, optional
        Number of Gauss-Legendre points per direction (default 8).
    radial : bool, optional
        Whether ``f`` takes the radius only.

    Returns
    -------
    ndarray
        Cell averages, shape ``broadcast(x1, x2).shape``.
    """
    x1, x2 = np.broadcast_arrays(np.asarray(x1, float), np.asarray(x2, float))
    nodes, weights = special.roots_legendre(order)
    g1 = x1[..., None, None] + 0.5 * d1 * nodes[:, None]
    g2 = x2[..., None, None] + 0.5 * d2 * nodes[None, :]
    g1, g2 = np.broadcast_arrays(g1, g2)
    vals = f(np.hypot(g1, g2)) if radial else f(g1, g2)
    w = 0.25 * weights[:, None] * weights[None, :]
    return np.sum(np.asarray(vals) * w, axis=(-2, -1))


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
    _positive("normal_force [N]", normal_force)
    _positive("radius [m]", radius)
    _positive("composite_modulus [Pa]", composite_modulus)
    a = (3.0 * normal_force * radius / (4.0 * composite_modulus)) ** (1.0 / 3.0)
    p0 = 3.0 * normal_force / (2.0 * np.pi * a ** 2)
    return HertzSphere(float(normal_force), float(radius), float(composite_modulus),
                       float(a), float(p0), float(a ** 2 / radius))


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
    r1, r2 = (float(v) for v in radii)
    _positive("normal_force [N]", normal_force)
    _positive("radii [m]", (r1, r2))
    _positive("composite_modulus [Pa]", composite_modulus)
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
        log_y = optimize.brentq(g, lo, 0.0, xtol=1e-15, rtol=4 * np.finfo(float).eps,
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
            val, _ = integrate.quad(f, v0, 1.0, epsabs=0.0, epsrel=1e-13, limit=200)
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
    _positive("normal_force [N]", normal_force)
    _positive("radius [m]", radius)
    _positive("composite_modulus [Pa]", composite_modulus)
    return FlatPunch(float(normal_force), float(radius), float(composite_modulus),
                     float(normal_force / (2.0 * radius * composite_modulus)))


# --------------------------------------------------------------------------- Cattaneo
def _check_partial_slip(t, mu_w):
    if not mu_w > 0:
        raise ValueError(f"mu W must be > 0 [N], got {mu_w!r}")
    t = np.asarray(t, float)
    if np.any(np.abs(t) > mu_w * (1.0 + 1e-12)):
        raise GrossSlidingError(
            f"|T| = {np.max(np.abs(t)):.6g} N exceeds mu W = {mu_w:.6g} N: gross sliding, "
            "no partial-slip solution")


def _circle(force, mu_w, a):
    """Stick radius of a Cattaneo distribution carrying |force| [m]."""
    return a * np.clip(1.0 - np.abs(force) / mu_w, 0.0, 1.0) ** (1.0 / 3.0)


def _sqrt_plus(c, r):
    return np.sqrt(np.clip(c * c - r * r, 0.0, None))


def _cattaneo_q(r, force, mu, mu_w, a, p0):
    """Signed Cattaneo traction carrying ``force`` [N]: sign * mu p0/a [sqrt(a^2-r^2)
    - sqrt(c^2-r^2)], c = a (1 - |force|/mu W)^(1/3)."""
    c = _circle(force, mu_w, a)
    return np.sign(force) * mu * p0 / a * (_sqrt_plus(a, r) - _sqrt_plus(c, r))


@dataclass(frozen=True)
class CattaneoMindlin:
    """Cattaneo-Mindlin partial slip under a monotonically applied force T, [J85]_ §7.2.

    Attributes
    ----------
    tangential_force : float
        T [N] along x1, |T| <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        a [m].
    max_pressure : float
        p0 [Pa].
    stick_radius : float
        c = a (1 - |T| / (mu W))^(1/3) [m].
    """

    tangential_force: float
    friction_coefficient: float
    normal_force: float
    contact_radius: float
    max_pressure: float
    stick_radius: float

    def traction(self, r):
        """q1(r) [Pa] = sign(T) mu p0/a [sqrt(a^2 - r^2) - sqrt(c^2 - r^2) (r < c)]."""
        return _cattaneo_q(np.asarray(r, float), self.tangential_force,
                           self.friction_coefficient,
                           self.friction_coefficient * self.normal_force,
                           self.contact_radius, self.max_pressure)


def cattaneo_mindlin(tangential_force, friction_coefficient, normal_force,
                     contact_radius, max_pressure) -> CattaneoMindlin:
    """Cattaneo (1938) - Mindlin (1949) solution, monotonic loading 0 -> T.

    ``c = a (1 - |T|/(mu W))^(1/3)`` and ``q(r) = mu p0/a [sqrt(a^2 - r^2) -
    sqrt(c^2 - r^2)]`` ([J85]_ §7.2); q carries T because
    ``int mu p0/a sqrt(c^2 - r^2) dA = mu W (c/a)^3``, which requires the Hertz
    relation p0 = 3W / (2 pi a^2) between the inputs.

    Parameters
    ----------
    tangential_force : float
        T [N] along x1, |T| <= mu W (:class:`GrossSlidingError` otherwise).
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    max_pressure : float
        Hertz maximum pressure p0 [Pa].

    Returns
    -------
    CattaneoMindlin
    """
    mu_w = friction_coefficient * normal_force
    _check_partial_slip(tangential_force, mu_w)
    return CattaneoMindlin(float(tangential_force), float(friction_coefficient),
                           float(normal_force), float(contact_radius), float(max_pressure),
                           float(_circle(tangential_force, mu_w, contact_radius)))


# --------------------------------------------------------------------------- Mindlin-Deresiewicz
def masing_memory(history):
    """Reversal points still remembered after a tangential force history [N].

    The body starts virgin at T = 0 and follows ``0 -> history[0] -> history[1] ...``,
    linearly (hence monotonically) between samples. A reversal point is pushed when
    the direction changes. Memory is wiped (Masing's rules, [MD53]_, [Ja98]_) when the
    current branch, started at the last reversal T_n, passes the previous one
    T_(n-1): the pair (T_(n-1), T_n) is erased and the branch continues the older
    one. The first reversal T_1 (reached on the virgin curve) is erased when the
    force reaches -T_1, after which the virgin curve is followed again.

    Parameters
    ----------
    history : array_like
        1-D tangential force samples [N], up to and including the current instant.

    Returns
    -------
    reversals : tuple of float
        Remembered reversal points (T_1, ..., T_n) [N] (empty on the virgin curve).
    current : float
        The current force T [N] (``history[-1]``, 0 for an empty history).
    """
    rev, t = (), 0.0
    for rev, t in _memory_states(history):
        pass
    return rev, t


def _memory_states(history):
    """Yield (reversals, current force) after each sample of ``history``."""
    stack: list = []
    prev, direction = 0.0, 0
    for t in np.atleast_1d(np.asarray(history, float)).ravel():
        t = float(t)
        if t != prev:
            d = 1 if t > prev else -1
            if direction != 0 and d != direction:
                stack.append(prev)
            direction = d
            while True:
                if len(stack) >= 2 and d * (t - stack[-2]) >= 0.0:
                    del stack[-2:]
                elif len(stack) == 1 and d * (t + stack[0]) >= 0.0:
                    stack.pop()
                else:
                    break
            prev = t
        yield tuple(stack), prev


def _masing_terms(history):
    """(weight, force) of the superposed Cattaneo terms of the current state.

    Virgin: [(1, T)]. Otherwise [(1, T_1), (2, (T_2 - T_1)/2), ...,
    (2, (T - T_n)/2)]: each reversal adds twice the monotonic solution for half the
    force change since that reversal.
    """
    return _terms_of_state(*masing_memory(history))


def _terms_of_state(rev, t):
    if not rev:
        return [(1.0, t)]
    points = list(rev) + [t]
    terms = [(1.0, rev[0])]
    for k in range(len(points) - 1):
        terms.append((2.0, 0.5 * (points[k + 1] - points[k])))
    return terms


def mindlin_deresiewicz_traction(r, history, friction_coefficient, normal_force,
                                 contact_radius, max_pressure):
    """Tangential traction q1(r) [Pa] at the last instant of a force history.

    Superposition of Cattaneo distributions ([MD53]_, [J85]_ §7.3, [Ja98]_): with
    ``C(r; F) = sign(F) mu p0/a [sqrt(a^2 - r^2) - sqrt(c(F)^2 - r^2)]``,
    ``c(F) = a (1 - |F|/mu W)^(1/3)`` (the monotonic solution carrying F),

    * virgin loading 0 -> T: ``q = C(r; T)``;
    * after reversals T_1 .. T_n (see :func:`masing_memory`):
      ``q = C(r; T_1) + sum_k 2 C(r; (T_(k+1) - T_k)/2)`` with T_(n+1) = T.

    E.g. unloading from T* > 0 to T: with c* = c(T*), c' = a(1 - (T* - T)/(2 mu W))^(1/3),
    ``q = -mu p0/a [sqrt(a^2 - r^2) - 2 sqrt(c'^2 - r^2) + sqrt(c*^2 - r^2)]``, which
    carries T ([J85]_ §7.3; the minus sign is that of an unloading increment:
    q = -mu p in the new slip annulus c' < r < a).

    Parameters
    ----------
    r : array_like
        Radii [m].
    history : array_like
        Tangential force samples T [N] (along x1), up to the current instant; the
        body starts virgin at T = 0. All |T| <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    max_pressure : float
        Hertz maximum pressure p0 = 3W/(2 pi a^2) [Pa].

    Returns
    -------
    ndarray
        q1(r) [Pa], with the sign convention of ``docs/conventions.md``.
    """
    mu_w = friction_coefficient * normal_force
    _check_partial_slip(history, mu_w)
    r = np.asarray(r, float)
    q = np.zeros(r.shape)
    for w, f in _masing_terms(history):
        q = q + w * _cattaneo_q(r, f, friction_coefficient, mu_w, contact_radius,
                                max_pressure)
    return q


def stick_radius(history, friction_coefficient, normal_force, contact_radius) -> float:
    """Radius of the current stick zone [m] after a tangential force history.

    The slip annulus of the current branch is ``c_cur < r < a`` with
    ``c_cur = a (1 - |T|/mu W)^(1/3)`` on the virgin curve and
    ``c_cur = a (1 - |T - T_n|/(2 mu W))^(1/3)`` after the last remembered reversal T_n.
    Inside c_cur nothing slips in the current increment (stick, Delta s = 0).
    ``c_cur`` is the largest of the circles of the remembered branches; the smallest
    (that of the first term) bounds the zone that has never slipped. Equals ``a``
    exactly at a reversal.

    Parameters
    ----------
    history : array_like
        Tangential force samples [N] (see :func:`mindlin_deresiewicz_traction`).
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        a [m].

    Returns
    -------
    float
        c_cur [m].
    """
    mu_w = friction_coefficient * normal_force
    _check_partial_slip(history, mu_w)
    _, f = _masing_terms(history)[-1]
    return float(_circle(f, mu_w, contact_radius))


def _mindlin_delta(force, mu_w, a, compliance_sum):
    """Signed monotonic (virgin) displacement: 3 mu W C/(16 a) [1 - (1 - |F|/mu W)^(2/3)]."""
    x = np.clip(1.0 - np.abs(force) / mu_w, 0.0, 1.0)
    return np.sign(force) * 3.0 * mu_w * compliance_sum / (16.0 * a) * (1.0 - x ** (2.0 / 3.0))


def tangential_displacement(history, friction_coefficient, normal_force, contact_radius,
                            compliance_sum, all_instants: bool = False):
    """Tangential rigid displacement omega1 [m] of body 1 relative to body 2.

    Mindlin's virgin curve ([J85]_ §7.2)
    ``delta(T) = 3 mu W/(16 a) * compliance_sum * [1 - (1 - T/mu W)^(2/3)]``
    and its Masing branches ([MD53]_, [J85]_ §7.3): with the remembered
    reversals T_1 .. T_n, ``delta = delta(T_1) + sum_k 2 delta((T_(k+1) - T_k)/2)``,
    e.g. ``delta = delta* - 2 delta((T* - T)/2)`` on unloading from T*.

    Parameters
    ----------
    history : array_like
        Tangential force samples T [N], body virgin at T = 0, |T| <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    compliance_sum : float
        ``(2 - nu1)/G1 + (2 - nu2)/G2`` [1/Pa] (0 for two rigid bodies), see
        :func:`tangential_compliance_sum`.
    all_instants : bool, optional
        Return the displacement at every sample of ``history`` (one pass) instead of
        at the last one only.

    Returns
    -------
    float or ndarray
        omega1 [m], same sign as T on the virgin curve.
    """
    mu_w = friction_coefficient * normal_force
    hist = np.atleast_1d(np.asarray(history, float)).ravel()
    _check_partial_slip(hist, mu_w)

    def value(state):
        return float(sum(w * _mindlin_delta(f, mu_w, contact_radius, compliance_sum)
                         for w, f in _terms_of_state(*state)))

    if not all_instants:
        return value(masing_memory(hist))
    return np.array([value(state) for state in _memory_states(hist)])


def energy_per_cycle(amplitude, friction_coefficient, normal_force, contact_radius,
                     compliance_sum) -> float:
    """Energy dissipated per full cycle T = +-T* [J] (area of the delta-T loop).

    Integrating the Masing branches, ``E = 4 T* delta(T*) - 8 int_0^T* delta(x) dx``,
    which gives (cf. [J85]_ eq. 7.64, [MD53]_), with tau = T*/(mu W),

    ``E = 9 mu^2 W^2 C / (10 a) * [1 - (1 - tau)^(5/3) - (5 tau / 6)(1 + (1 - tau)^(2/3))]``

    where C is ``compliance_sum``. For small amplitude ``E ~ C T*^3 / (36 a mu W)``.

    Parameters
    ----------
    amplitude : float
        T* [N], 0 <= T* <= mu W.
    friction_coefficient : float
        mu [1].
    normal_force : float
        W [N].
    contact_radius : float
        Hertz contact radius a [m].
    compliance_sum : float
        ``(2 - nu1)/G1 + (2 - nu2)/G2`` [1/Pa].

    Returns
    -------
    float
        Dissipated energy per cycle [J].
    """
    mu_w = friction_coefficient * normal_force
    amplitude = abs(float(amplitude))
    _check_partial_slip(amplitude, mu_w)
    tau = amplitude / mu_w
    s = max(1.0 - tau, 0.0)
    bracket = 1.0 - s ** (5.0 / 3.0) - 5.0 * tau / 6.0 * (1.0 + s ** (2.0 / 3.0))
    return float(9.0 * mu_w ** 2 * compliance_sum / (10.0 * contact_radius) * bracket)


# --------------------------------------------------------------------------- Lee-Radok
@dataclass(frozen=True)
class LeeRadokContact:
    """Rigid sphere on a viscoelastic half-space under a step load ([LR60]_).

    Attributes
    ----------
    t : ndarray
        Times [s] after the load step.
    contact_radius : ndarray
        a(t) [m].
    approach : ndarray
        a(t)^2 / R [m].
    """

    t: np.ndarray
    contact_radius: np.ndarray
    approach: np.ndarray


def lee_radok_sphere(t, normal_force, radius, young, poisson, creep) -> LeeRadokContact:
    """Lee-Radok solution for a step load W applied at t = 0 on a rigid sphere.

    With a constant Poisson ratio the elastic compliance ``(1 - nu^2)/E`` becomes the
    creep function ``(1 - nu^2)/E * phi(t)``; while the contact grows the Hertz
    relations hold with it ([LR60]_):
    ``a(t)^3 = 3 W R (1 - nu^2) phi(t) / (4 E)`` and ``delta(t) = a(t)^2 / R``.

    Parameters
    ----------
    t : array_like
        Times [s]; a = 0 for t < 0.
    normal_force : float
        W [N], applied as a step at t = 0.
    radius : float
        Sphere radius R [m].
    young : float
        Modulus E [Pa] of the normalisation of ``creep`` (instantaneous for most
        models, long-term for Kelvin-Voigt; see :mod:`contactpipe.materials`).
    poisson : float
        Constant Poisson ratio nu [1].
    creep : callable
        Normalised creep function phi(t) [1], non-decreasing (a
        :mod:`contactpipe.materials` creep object).

    Returns
    -------
    LeeRadokContact
    """
    t = np.asarray(t, float)
    phi = np.where(t >= 0.0, creep(np.maximum(t, 0.0)), 0.0)
    a = (3.0 * normal_force * radius * (1.0 - poisson ** 2) * phi / (4.0 * young)) ** (1 / 3)
    return LeeRadokContact(t, a, a ** 2 / radius)


def _creep_integral(creep, u0, u1):
    """int_{u0}^{u1} phi(u) du [s] (exact with the creep object's ``mean`` if any)."""
    if u1 <= u0:
        return 0.0
    if hasattr(creep, "mean"):
        return float(np.squeeze(creep.mean(u0, u1))) * (u1 - u0)
    return integrate.quad(lambda u: float(creep(u)), u0, u1, limit=200)[0]


def lee_radok_radius(t, load_times, load_values, radius, young, poisson, creep):
    """Contact radius a(t) [m] of a rigid sphere under a growing load W(t).

    Hereditary integral of [LR60]_, valid while the contact area does not shrink
    (otherwise see [T66]_; a non-decreasing load and creep function guarantee it):

    ``a(t)^3 = 3 R (1 - nu^2) / (4 E) * int_{0-}^{t} phi(t - s) dW(s)``

    W(t) is 0 before the first knot, jumps to ``load_values[0]`` there (the step is
    included), is linear between knots and constant after the last one; two knots at
    the same time make a further step. The linear pieces are integrated exactly with
    the creep object's ``mean`` (or by :func:`scipy.integrate.quad` for a plain
    callable).

    Parameters
    ----------
    t : array_like
        Times [s].
    load_times : array_like
        Knot times [s], non-decreasing.
    load_values : array_like
        Loads W at the knots [N], >= 0 and non-decreasing.
    radius : float
        Sphere radius R [m].
    young : float
        Modulus E [Pa] normalising ``creep``.
    poisson : float
        Constant Poisson ratio [1].
    creep : callable
        Normalised creep function phi(t) [1].

    Returns
    -------
    ndarray
        a(t) [m], shape of ``t``.
    """
    tk = np.asarray(load_times, float).ravel()
    wk = np.asarray(load_values, float).ravel()
    if tk.size != wk.size or tk.size == 0:
        raise ValueError("load_times and load_values must be non-empty and of equal length")
    if np.any(np.diff(tk) < 0):
        raise ValueError("load_times [s] must be non-decreasing")
    if wk[0] < 0 or np.any(np.diff(wk) < 0):
        raise ValueError("load_values [N] must be >= 0 and non-decreasing "
                         "(Lee-Radok needs a growing contact; see Ting 1966)")
    t = np.asarray(t, float)
    out = np.zeros(t.shape)
    pref = 3.0 * radius * (1.0 - poisson ** 2) / (4.0 * young)
    for idx in np.ndindex(t.shape):
        ti = float(t[idx])
        if ti < tk[0]:
            continue
        acc = wk[0] * float(creep(ti - tk[0]))
        for k in range(tk.size - 1):
            s0, s1 = tk[k], tk[k + 1]
            if s0 > ti:
                break
            dw = wk[k + 1] - wk[k]
            if dw == 0.0:
                continue
            if s1 == s0:                       # a step
                acc += dw * float(creep(ti - s0))
                continue
            se = min(s1, ti)
            acc += dw / (s1 - s0) * _creep_integral(creep, ti - se, ti - s0)
        out[idx] = (pref * acc) ** (1.0 / 3.0)
    return out


def _relaxation_grid(creep, t_end, n_steps):
    """psi on the uniform grid t_j = j t_end / n (j = 0..n), see relaxation_function."""
    s = np.linspace(0.0, t_end, n_steps + 1)
    phi = np.asarray(creep(s), float)
    if phi[0] <= 0.0:
        raise ValueError("phi(0) = 0 (no instantaneous elasticity, e.g. Kelvin-Voigt): "
                         "the relaxation function has a Dirac part; not supported")
    dphi = np.diff(phi)                                  # dphi[k] = phi_{k+1} - phi_k
    psi = np.empty(n_steps + 1)
    psi[0] = 1.0 / phi[0]
    diag = phi[0] + 0.5 * dphi[0] if n_steps else phi[0]
    for n in range(1, n_steps + 1):
        # sum_{k=0}^{n-1} (psi_{n-k} + psi_{n-k-1})/2 dphi_k + psi_n phi_0 = 1
        k = np.arange(n)
        rest = 0.5 * (psi[n - 1 - k] @ dphi[:n])
        if n >= 2:
            rest += 0.5 * (psi[n - k[1:]] @ dphi[1:n])
        psi[n] = (1.0 - rest) / diag
    return s, psi


def relaxation_function(t, creep, n_steps: int = 2000):
    """Normalised relaxation function psi(t) [1] from the creep function phi.

    psi solves the Volterra identity ``int_{0-}^{t} psi(t - s) dphi(s) = 1``, i.e.
    ``psi(t) phi(0) + int_0^t psi(t - s) phi'(s) ds = 1`` (phi * dpsi = H), so that
    the relaxation modulus is ``E/(1 - nu^2) * psi(t)`` when the compliance is
    ``(1 - nu^2)/E * phi(t)``. It is solved by product-trapezoid quadrature of the
    Stieltjes integral on a uniform grid of ``n_steps`` steps over [0, max(t)]
    (second order in the step; the implicit coefficient phi(0) + [phi(h) - phi(0)]/2
    is > 0 for a non-decreasing phi with phi(0) > 0), then interpolated linearly.
    Maxwell (phi = 1 + t/t') gives psi = exp(-t/t').

    Parameters
    ----------
    t : array_like
        Times [s], >= 0.
    creep : callable
        Normalised creep function phi [1] with phi(0) > 0.
    n_steps : int, optional
        Number of time steps of the quadrature (default 2000; cost O(n^2)).

    Returns
    -------
    ndarray
        psi(t) [1].
    """
    t = np.asarray(t, float)
    t_end = float(np.max(t)) if t.size else 0.0
    if t_end <= 0.0:
        return np.full(t.shape, 1.0 / float(creep(0.0)))
    s, psi = _relaxation_grid(creep, t_end, n_steps)
    return np.interp(t, s, psi)


def lee_radok_pressure(r, t, normal_force, radius, young, poisson, creep,
                       n_steps: int = 2000):
    """Contact pressure [Pa] under a rigid sphere, step load W at t = 0 ([LR60]_).

    ``p(r, t) = 2 E / (pi R (1 - nu^2)) int_{0-}^{t} psi(t - s) d h(r, s)``,
    ``h(r, s) = sqrt(a(s)^2 - r^2)`` (0 for r > a(s)), the hereditary form of the Hertz
    pressure ``p = 2 E*/(pi R) sqrt(a^2 - r^2)`` with a(s) from
    :func:`lee_radok_sphere` and psi from :func:`relaxation_function` on the same
    grid. The Stieltjes integral uses the same product-trapezoid rule, so the total
    force equals W to round-off (up to the radial quadrature of the user).

    Parameters
    ----------
    r : array_like
        Radii [m].
    t : float
        Time since the load step [s], >= 0.
    normal_force : float
        W [N].
    radius : float
        Sphere radius R [m].
    young : float
        Modulus E [Pa] normalising ``creep``.
    poisson : float
        Constant Poisson ratio [1].
    creep : callable
        Normalised creep function phi [1], phi(0) > 0.
    n_steps : int, optional
        Number of time steps over [0, t] (default 2000).

    Returns
    -------
    ndarray
        p(r, t) [Pa], shape of ``r``.
    """
    r = np.asarray(r, float)
    t = float(t)
    pref = 2.0 * young / (np.pi * radius * (1.0 - poisson ** 2))
    if t <= 0.0:
        a0 = lee_radok_sphere(0.0, normal_force, radius, young, poisson, creep).contact_radius
        return pref / float(creep(0.0)) * _sqrt_plus(float(a0), r)
    s, psi = _relaxation_grid(creep, t, n_steps)
    a = lee_radok_sphere(s, normal_force, radius, young, poisson, creep).contact_radius
    h = _sqrt_plus(a[:, None], r.ravel()[None, :])      # (n+1, m)
    w = 0.5 * (psi[::-1][:-1] + psi[::-1][1:])          # (psi_{n-k} + psi_{n-k-1})/2
    val = psi[-1] * h[0] + w @ np.diff(h, axis=0)
    return (pref * val).reshape(r.shape)
