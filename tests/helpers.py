"""Shared test helpers: the paper's elastic constants, small scene builders, and an
independent reference for the small dense quadratic programs of the solver unit tests.

Imported by the test modules as ``from helpers import ...`` (``tests/`` is on the path
through ``pythonpath`` in pyproject's ``[tool.pytest.ini_options]``); fixtures stay in
``conftest.py``. No test depends on ../shared.
"""
import itertools

import numpy as np
from scipy import integrate

import contactpipe as cp
from contactpipe import analytic as an

__all__ = ["STEEL", "R", "W", "MU", "E_STAR_STEEL", "A_HERTZ", "P0_HERTZ", "make_scene",
           "fretting_scene", "spd_matrix", "box_qp_exact", "box_kkt_violation", "radial_force",
           "md_circles"]

# the paper's elastic case: steel on steel, R = 18 mm, W = 1 kN
# (Hertz: p0 = 1.996 GPa, a = 0.489 mm)
STEEL = {"material": "elastic", "young": 210e9, "poisson": 0.3}
R, W, MU = 0.018, 1000.0, 0.1
E_STAR_STEEL = 1.0 / (2 * (1 - 0.3 ** 2) / 210e9)
A_HERTZ = (3 * W * R / (4 * E_STAR_STEEL)) ** (1 / 3)
P0_HERTZ = 3 * W / (2 * np.pi * A_HERTZ ** 2)


def make_scene(**over):
    """A scene with sensible defaults; keyword tables replace or extend the defaults.

    ``geometry``, ``indenter``, ``halfspace`` and ``load`` are replaced as a whole, the
    other tables (``grid``, ``time``, ...) are merged into the defaults; ``None`` removes
    a table.
    """
    d = {
        "name": "test",
        "geometry": {"shape": "sphere", "radius": R},
        "indenter": dict(STEEL),
        "halfspace": dict(STEEL),
        "load": {"time": [0.0, 1.0], "normal_force": W},
        "grid": {"points": [64, 64], "size": [4 * A_HERTZ, 4 * A_HERTZ]},
        "time": {"steps": 1},
    }
    for k, v in over.items():
        if v is None:
            d.pop(k, None)
        elif (isinstance(v, dict) and isinstance(d.get(k), dict)
              and k not in ("indenter", "halfspace", "load", "geometry")):
            d[k] = {**d[k], **v}
        else:
            d[k] = v
    return cp.Scene(**d)


def fretting_scene(n=128, steps=40, size=3.0, mu=MU, amplitude=0.9, **over):
    """The paper's elastic fretting loop: T: 0 -> +T* -> -T* -> +T* with T* = 0.9 mu W."""
    Ts = amplitude * mu * W
    return make_scene(friction={"mu": mu},
                      load={"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W,
                            "tangential_force": [0.0, Ts, -Ts, Ts]},
                      grid={"points": [n, n], "size": [size * A_HERTZ, size * A_HERTZ]},
                      time={"steps": steps}, **over)


# --------------------------------------------------------------------------- small dense QPs
def spd_matrix(rng, n, cond=50.0):
    """A random symmetric positive definite n x n matrix with eigenvalues spread
    geometrically over [1, cond] (random orthogonal eigenvectors)."""
    q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return (q * np.geomspace(1.0, cond, n)) @ q.T


def box_qp_exact(A, b, lo, hi, target):
    """Exact minimiser of ½ xᵀAx + bᵀx over {lo ≤ x ≤ hi, Σx = target} by enumerating the
    active sets (3ᵐ for m movable cells: each at lo, free or at hi; for m ≤ 8), independent of
    the CG.

    For each guess the free cells solve the equality-constrained KKT system; the guess is
    the solution when the free cells lie within their bounds and the residual
    r = Ax + b − λ has the signs of the optimality conditions (r ≥ 0 at lo, r ≤ 0 at hi).
    A strictly convex problem has exactly one such point.

    Returns
    -------
    x : ndarray
    multiplier : float or None
        λ; None when every movable cell is at a bound (λ is then not unique).
    """
    A, b, lo, hi = (np.asarray(v, float) for v in (A, b, lo, hi))
    n = len(b)
    movable = lo < hi
    finite_hi = np.where(np.isfinite(hi), hi, 0)
    scale = 1.0 + np.abs(b).max() + np.abs(A).max() * (np.abs(finite_hi).max()
                                                        + np.abs(lo).max() + abs(target))
    for states in itertools.product((0, 1, 2), repeat=int(movable.sum())):
        st = np.zeros(n, int)
        st[movable] = states
        if np.any((st == 2) & ~np.isfinite(hi)):
            continue
        x = np.where(st == 2, hi, lo).astype(float)
        free = st == 1
        k = int(free.sum())
        if k == 0:
            if abs(x.sum() - target) > 1e-12 * (abs(target) + np.abs(x).sum() + 1e-300):
                continue
            g = A @ x + b
            at_lo, at_hi = movable & (st == 0), movable & (st == 2)
            lam_max = g[at_lo].min() if at_lo.any() else np.inf     # r ≥ 0 at lo
            lam_min = g[at_hi].max() if at_hi.any() else -np.inf    # r ≤ 0 at hi
            if lam_min <= lam_max + 1e-12 * scale:
                return x, None
            continue
        kkt = np.zeros((k + 1, k + 1))
        kkt[:k, :k] = A[np.ix_(free, free)]
        kkt[:k, k] = -1.0
        kkt[k, :k] = 1.0
        rhs = np.concatenate([-(b[free] + A[np.ix_(free, ~free)] @ x[~free]),
                              [target - x[~free].sum()]])
        sol = np.linalg.solve(kkt, rhs)
        x[free] = sol[:k]
        lam = float(sol[k])
        if np.any(x[free] < lo[free]) or np.any(x[free] > hi[free]):
            continue
        r = A @ x + b - lam
        if (np.any(r[movable & (st == 0)] < -1e-12 * scale)
                or np.any(r[movable & (st == 2)] > 1e-12 * scale)):
            continue
        return x, lam
    raise AssertionError("no active set satisfies the optimality conditions")


def box_kkt_violation(A, b, lo, hi, target, x, lam):
    """Largest violation of the optimality conditions of the box- and sum-constrained QP
    at (x, λ), relative: bounds and Σx = target relative to Σ|x|; the residual
    r = Ax + b − λ (r = 0 on free cells, ≥ 0 at lo, ≤ 0 at hi) relative to max|Ax + b|."""
    g = A @ x + b
    r = g - lam
    xs = max(float(np.abs(x).sum()), abs(target), 1e-300)
    gs = max(float(np.abs(g).max()), 1e-300)
    movable = lo < hi
    at_lo = movable & (x <= lo)
    at_hi = movable & (x >= hi)
    free = movable & ~at_lo & ~at_hi
    parts = [
        float(np.max(np.maximum(lo - x, 0.0), initial=0.0)) / xs,
        float(np.max(np.maximum(x - hi, 0.0), initial=0.0)) / xs,
        abs(float(x.sum()) - target) / xs,
        float(np.max(np.abs(r[free]), initial=0.0)) / gs,
        float(np.max(-r[at_lo], initial=0.0)) / gs,
        float(np.max(r[at_hi], initial=0.0)) / gs,
    ]
    return max(parts)


# --------------------------------------------------------------------------- closed forms
def radial_force(f, a, breaks=(), epsabs=0.0):
    """int_0^a 2 pi r f(r) dr, split at the given radii (quad: epsrel 1e-12, epsabs)."""
    pts = sorted({0.0, a, *[float(b) for b in breaks if 0.0 < b < a]})
    total = 0.0
    for lo, hi in zip(pts[:-1], pts[1:], strict=True):
        total += integrate.quad(lambda r: 2 * np.pi * r * float(f(r)), lo, hi,
                                epsabs=epsabs, epsrel=1e-12, limit=200)[0]
    return total


def md_circles(history, a, mu_w):
    """Radii [m] of the stick/slip circles of the Mindlin-Deresiewicz traction after a
    tangential force history: one per superposed Cattaneo term (where q has a kink)."""
    rev, t = an.masing_memory(history)
    pts = list(rev) + [t]
    out = [a * (1 - abs(pts[0]) / mu_w) ** (1 / 3)]
    out += [a * (1 - abs(pts[k + 1] - pts[k]) / (2 * mu_w)) ** (1 / 3)
            for k in range(len(pts) - 1)]
    return out
