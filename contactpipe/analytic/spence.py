"""Spence's frictional Hertz problem: the stick radius of a sphere pressed with friction.

Two dissimilar elastic bodies (Dundurs β ≠ 0) pressed together with a monotonically
growing normal load, friction μ at the interface, no tangential load (Spence 1975,
[S75]_; [J85]_ §5.2). The pressure moves the two surfaces radially by different amounts;
friction resists it, with a radial shear: a central disk of radius c sticks, the annulus
c < r < a slips with |q| = μp. Spence showed that c/a = λ stays constant while the load
grows. It is governed by μ/|β| (the shear the coupling asks for over the shear friction
allows), and, less, by |β| itself: the shear's own pull on the pressure is a β² term
(at μ/|β| = 0.5972, λ = 0.50 for |β| = 1/2, 0.575 for 1/3, 0.595 for 1/4, 0.62 for 0.1).

How λ is found here (the reduction is Spence's; the last step is numerical)
---------------------------------------------------------------------------
Relative displacements of the pair under an axisymmetric pressure p(r) and radial shear
q(r) (tractions on body 2, ``docs/conventions.md``), in units of
A = (1 − ν1)/G1 + (1 − ν2)/G2 (so A = 2/E*):

    u_z(r) = N[p](r) + β ∫_r^∞ q dρ,      u_r(r) = N1[q](r) + β (1/r) ∫_0^r p ρ dρ,

N and N1 the half-space operators of symbol 1/k on axisymmetric scalar (order-0 Hankel)
and radial (order-1 Hankel) fields: a radial field is longitudinal, on which the in-plane
operator is (1 − ν)/(G k) like the normal one, so ν enters through A and β only. The
coupling terms follow from the point-load kernels (u_r = −(1 − 2ν)F/(4πG r) under a
normal force F, by Gauss's theorem in the plane; u_z from a radial shear by reciprocity
and an integration by parts). A ring of unit line density at radius ρ gives, with
m = 4rρ/(r + ρ)² and K, E the complete elliptic integrals of parameter m,

    N:  (2/π) ρ K/(r + ρ),        N1:  (2/π) ρ/(r + ρ) · [(2/m)(K − E) − K].

Spence's argument: the load grows with the contact radius a; differentiate in a. The
increments P = ∂p/∂a, Q = ∂q/∂a solve, on the contact disk r < a,

    N[P] + β ∫_r^a Q dρ = dδ/da (a constant)         (the normal condition)
    N1[Q] + β (1/r) ∫_0^r P ρ dρ = 0    r < c      (stick: no slip increment)
    Q = ±μ P                             c < r < a  (slip: |q| = μp throughout)

a frictional flat punch of radius a, the same problem at every a up to scale: hence
c/a is constant. Here this problem is solved on a = 1 with n rings of constant P, Q
(collocation at the ring centres; the ring integrals by Gauss-Legendre, graded at the
log singularity r = ρ). Too small a stick disk leaves slip rings next to it whose shear
μP does not oppose their slip increment (−u_r's); too large a one needs |Q| > μP on its
edge rings. λ is the edge of the smallest central set of stick rings for which every slip
ring's shear opposes its slip (to 1/n), and |Q| <= μP is checked on its stick rings (the
two conditions meet at the same ring).

Checks (``tests/test_analytic.py``): without coupling the flat punch's
P = 2/(π √(1 − r²)) (to 0.12 % over r < a/2 at n = 200); λ → 0 as μ/|β| → 0 and λ → 1
as μ/|β| grows; λ converges in n (|β| = 1/2, μ/|β| = 0.4, 0.5972, 2: 0.22 / 0.50 / 0.96
to 0.97 at n = 50 ... 400, within 1/n). Against the vector form of the solver
(``tests/test_spence.py``): the stick radius within 0.5 cell of λ a while the load grows,
at |β| = 1/2 (μ = 0.2, 0.2986, 0.4) and 1/3 (where λ = 0.575, not μ/|β|'s 0.50 at
|β| = 1/2). Spence's own tables were not at hand; this is a numerical solution of his
reduced problem, not his closed form. At μ = 0.2986 on a rigid sphere and a ν = 0
half-space (β = −1/2), the issue's case, λ = 0.500.

References
----------
.. [S75] D. A. Spence, "The Hertz contact problem with finite friction", J. Elasticity 5
   (1975) 297-319.
.. [J85] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, §5.2.
"""
from __future__ import annotations

import functools
import math

import numpy as np
from scipy import special

__all__ = ["spence_increments", "spence_stick_ratio"]

#: Rings of the reference solution: λ to 1/200 (0.5 % of a).
RINGS = 200


def _kernels(r, rho):
    """(N, N1) ring kernels at radius ``r`` from a unit ring at ``rho`` (broadcast)."""
    m = np.minimum(4.0 * r * rho / (r + rho) ** 2, 1.0 - 1e-16)   # m = 1 only at r = ρ
    K, E = special.ellipk(m), special.ellipe(m)
    normal = (2.0 / math.pi) * rho * K / (r + rho)
    with np.errstate(divide="ignore", invalid="ignore"):
        radial = (2.0 / math.pi) * rho / (r + rho) * ((2.0 / m) * (K - E) - K)
    return normal, np.where(m > 0, radial, 0.0)


@functools.lru_cache(maxsize=4)
def _matrices(n):
    """Collocation matrices of N, N1 and the two coupling integrals on n rings of r < 1."""
    h = 1.0 / n
    edges = np.linspace(0.0, 1.0, n + 1)
    r = 0.5 * (edges[1:] + edges[:-1])
    x, w = np.polynomial.legendre.leggauss(8)
    Z, R = np.empty((n, n)), np.empty((n, n))
    for j in range(n):
        rho = edges[j] + 0.5 * h * (x + 1.0)
        kz, kr = _kernels(r[:, None], rho[None, :])
        Z[:, j], R[:, j] = kz @ (0.5 * h * w), kr @ (0.5 * h * w)
    # the neighbours (|i - j| <= 2), log-singular at r = ρ: 32-point Gauss-Legendre, on the
    # ring itself split at r and graded as ρ = r ± t² (smooth in t)
    x, w = np.polynomial.legendre.leggauss(32)
    t, wt = 0.5 * (x + 1.0), 0.5 * w
    for d in (-2, -1, 1, 2):
        i = np.arange(max(0, -d), min(n, n - d))
        rho = edges[i + d][:, None] + h * t[None, :]
        kz, kr = _kernels(r[i][:, None], rho)
        Z[i, i + d], R[i, i + d] = h * kz @ wt, h * kr @ wt
    side = math.sqrt(0.5 * h) * t                           # t in [0, √(h/2)]
    dz = np.zeros(n)
    dr = np.zeros(n)
    for sign in (-1.0, 1.0):
        rho = r[:, None] + sign * side[None, :] ** 2
        kz, kr = _kernels(r[:, None], rho)
        jac = 2.0 * side * math.sqrt(0.5 * h) * wt          # dρ = 2t dt, t = √(h/2) τ
        dz += kz @ jac
        dr += kr @ jac
    Z[np.arange(n), np.arange(n)], R[np.arange(n), np.arange(n)] = dz, dr
    above = np.triu(np.full((n, n), h), 1) + np.diag(np.full(n, 0.5 * h))   # ∫_r^1 Q dρ
    below = np.tril(r[None, :] * h / r[:, None], -1) + \
        np.diag((r ** 2 - edges[:-1] ** 2) / (2.0 * r))                    # (1/r)∫_0^r Pρ dρ
    return r, Z, R, above, below


def spence_increments(mu, beta, stick_rings, n=RINGS):
    """The load increments (P, Q) of Spence's problem on the unit disk, with the central
    ``stick_rings`` rings stuck and the others slipping.

    Parameters
    ----------
    mu : float
        Friction coefficient [1], > 0.
    beta : float
        Dundurs β of the pair [1], 0 < |β| <= 1/2 (its sign flips Q only).
    stick_rings : int
        Rings (of ``n``) in the stick disk, from the centre.
    n : int
        Rings over the contact radius.

    Returns
    -------
    (r, P, Q, U) : ndarrays (n,)
        Ring centres r/a [1]; the pressure and shear increments per unit approach rate
        (dδ/da = 1, in units of 1/A); U the radial displacement increment (0 on the
        stick rings).
    """
    n = int(n)
    r, Z, R, above, below = _matrices(n)
    mu, beta, k = float(mu), float(beta), int(stick_rings)
    A = np.zeros((2 * n, 2 * n))
    b = np.zeros(2 * n)
    A[:n, :n], A[:n, n:], b[:n] = Z, beta * above, 1.0
    A[n:, n:], A[n:, :n] = R, beta * below
    if k < n:
        # slip rings: Q = s μ P, s the sign of the full-stick shear at the edge
        s = np.sign(np.linalg.solve(A, b)[-1])
        A[n + k:] = 0.0
        A[n + np.arange(k, n), n + np.arange(k, n)] = 1.0
        A[n + np.arange(k, n), np.arange(k, n)] = -s * mu
    x = np.linalg.solve(A, b)
    P, Q = x[:n], x[n:]
    return r, P, Q, R @ Q + beta * below @ P


def spence_stick_ratio(mu, beta, n=RINGS) -> float:
    """The stick radius over the contact radius, c/a = λ [1], of a Hertz contact of
    dissimilar bodies under a monotonically growing normal load with friction μ
    (Spence 1975): constant during loading.

    Parameters
    ----------
    mu : float
        Friction coefficient [1], >= 0.
    beta : float
        Dundurs β of the pair [1], |β| <= 1/2 (``docs/conventions.md``; −1/2 for a rigid
        sphere on a ν = 0 half-space); its sign does not matter.
    n : int
        Rings of the reference solution (module docstring); λ is exact to 1/n.

    Returns
    -------
    float
        λ in [0, 1]: 0 without friction, 1 where the whole contact sticks (β = 0: nothing
        to resist).

    Raises
    ------
    ValueError
        ``mu`` negative or NaN, or |β| > 1/2.
    """
    mu, b = float(mu), abs(float(beta))
    if not mu >= 0:
        raise ValueError(f"mu = {mu!r}: must be a number >= 0")
    if not b <= 0.5:
        raise ValueError(f"beta = {beta!r}: the Dundurs beta lies in [-1/2, 1/2]")
    if mu == 0:
        return 0.0
    if b == 0 or math.isinf(mu):
        return 1.0
    n = int(n)

    def opposes(k):              # the shear of every slip ring opposes its slip increment
        _, P, Q, U = spence_increments(mu, b, k, n)
        prod = Q[k:] * U[k:]
        return bool(np.all(prod <= 1e-12 * np.max(np.abs(Q)) * np.max(np.abs(U)))), P, Q

    # the first stick disk whose slip rings all oppose: scanned up from a little below
    # the answer on a grid four times coarser (the answers agree to 1/50 from n = 50 on)
    start = 0
    if n >= 100:
        start = max(0, round(n * spence_stick_ratio(mu, b, n // 4)) - 8)
        while start > 0 and opposes(start)[0]:
            start = max(0, start - 8)
    for k in range(start, n + 1):
        ok, P, Q = opposes(k)
        if ok:
            break
    if np.any(np.abs(Q[:k]) > mu * P[:k] * (1 + 1e-9)):
        raise ArithmeticError(f"Spence's problem, mu = {mu}, beta = {beta}: its stick disk "
                              f"needs a shear above mu p (n = {n})")
    return k / n
