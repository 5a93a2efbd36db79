"""Multiaxial fatigue indicators over a loading cycle, point by point of a stress field.

    >>> st = cp.subsurface_stress(ds, x3=depths, time="all").sel(time=slice(0.2, 1.0))
    >>> fi = cp.fatigue(st, "crossland", torsion_limit=300e6, bending_limit=450e6)
    >>> fi.crossland_index.max(), fi.maximum_x1, fi.maximum_x3

The stress history of every point over the instants of ``stress_ds`` (one cycle: select it
with ``.sel(time=...)``) gives a field over (x3, x1, x2), its maximum and where it is.

Criteria (:data:`CRITERIA`; constants are keyword arguments, SI units):

``amplitude``
    Per component the amplitude (max - min)/2 and mean (max + min)/2 over the cycle;
    the von Mises equivalent amplitude ``sqrt(3) sqrt(J2,a)`` (main field) and the mean and
    largest hydrostatic stress.
``crossland`` (constants ``torsion_limit`` t_-1 and ``bending_limit`` f_-1 [Pa], the
fully reversed fatigue limits)
    ``sqrt(J2,a) + alpha sigma_h,max <= beta`` with alpha = 3 t/f - sqrt(3), beta = t.
    Main field: the index ``(sqrt(J2,a) + alpha sigma_h,max) / beta`` (> 1: cracks
    expected).
``dang_van`` (the same constants)
    ``max_t [tau(t) + a sigma_h(t)] <= b`` with a = 3 t/f - 3/2, b = t; tau(t) is the
    Tresca shear (half the spread of the principal values) of the mesoscopic deviator
    s(t) - s*, s* the centre of the deviatoric path. Main field: the index (divided by b).
``swt`` (constant ``young`` E [Pa]; ``poisson`` from the dataset unless given)
    Smith-Watson-Topper on the critical plane: ``max_n sigma_n,max(n) * eps_a(n)`` [Pa]
    over plane normals n, with the normal strain eps_n = ((1 + nu) sigma_n - nu tr
    sigma)/E of the elastic stress; planes where sigma_n,max <= 0 count 0. Normals on a
    ``plane_step`` degree grid of the hemisphere (default 10, at least 1: finer grids do
    not fit in memory), then refined twice around the best one (steps / 4, / 16). Also the
    normal of the critical plane.

Shear amplitude sqrt(J2,a) and the centre s* (Crossland, Dang Van, amplitude): by default
the **minimum circumscribed ball** (MCB) of the deviatoric path, in the 5-D space where the
Euclidean norm is sqrt(J2) (Papadopoulos' construction). It is solved per point by a
Frank-Wolfe iteration with away steps (Yildirim 2008) to a certified relative accuracy
``tolerance`` (default 1e-9, on the radius: the iteration stops when the largest
distance is within (1 + tolerance) of a lower bound of the optimal radius).
``shear_amplitude="longest_chord"`` takes half the longest chord and its midpoint
instead (equal to the MCB for proportional and for elliptical paths, smaller otherwise).

References
----------
.. [C56] B. Crossland, "Effect of large hydrostatic pressures on the torsional fatigue
   strength of an alloy steel", Proc. Int. Conf. Fatigue of Metals, London, 1956.
.. [DV89] K. Dang Van, B. Griveau, O. Message, "On a new multiaxial fatigue limit
   criterion", in *Biaxial and Multiaxial Fatigue*, EGF 3, 1989, 479-496.
.. [P97] I. V. Papadopoulos et al., "A comparative study of multiaxial high-cycle fatigue
   criteria for metals", Int. J. Fatigue 19 (1997) 219-235.
.. [SWT70] K. N. Smith, P. Watson, T. H. Topper, "A stress-strain function for the
   fatigue of metals", J. Mater. 5 (1970) 767-778.
.. [Y08] E. A. Yildirim, "Two algorithms for the minimum enclosing ball problem", SIAM J.
   Optim. 19 (2008) 1368-1391. doi:10.1137/070690419
"""
from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._version import __version__

__all__ = ["fatigue", "CRITERIA", "min_ball", "longest_chord", "deviatoric_coordinates",
           "plane_normals"]

COMPONENTS = ("s11", "s22", "s33", "s12", "s13", "s23")
SQRT3 = math.sqrt(3.0)
#: Bound of the working memory per block of points [bytes].
BLOCK_BYTES = 64 * 2 ** 20
#: The finest ``plane_step`` of the SWT criterion [deg]: about 20 600 planes, an array
#: of 165 MB per 1000 instants for a single point (a step of 1e-4 would be ~4e12 planes).
MIN_PLANE_STEP = 1.0


def _planes(step) -> int:
    """About how many planes :func:`plane_normals` makes for ``step`` degrees."""
    return int(round(4 * math.pi / 2 / math.radians(step) ** 2, -2))


# --------------------------------------------------------------------------- geometry

def deviatoric_coordinates(s):
    """The deviator of stresses ``s[..., 6]`` (COMPONENTS order) as 5-D vectors.

    ``u = ((s11 - s22)/2, (2 s33 - s11 - s22)/(2 sqrt 3), s12, s13, s23)``: an orthonormal
    parametrisation in which ``|u|^2 = J2`` [Pa^2].
    """
    s = np.asarray(s, dtype=float)
    return np.stack([(s[..., 0] - s[..., 1]) / 2,
                     (2 * s[..., 2] - s[..., 0] - s[..., 1]) / (2 * SQRT3),
                     s[..., 3], s[..., 4], s[..., 5]], axis=-1)


def _deviator_tensor(u):
    """3x3 deviators from 5-D vectors u[..., 5] (inverse of deviatoric_coordinates)."""
    d33 = 2 * u[..., 1] / SQRT3
    d11 = (-d33 + 2 * u[..., 0]) / 2
    d22 = (-d33 - 2 * u[..., 0]) / 2
    t = np.empty(u.shape[:-1] + (3, 3))
    t[..., 0, 0], t[..., 1, 1], t[..., 2, 2] = d11, d22, d33
    t[..., 0, 1] = t[..., 1, 0] = u[..., 2]
    t[..., 0, 2] = t[..., 2, 0] = u[..., 3]
    t[..., 1, 2] = t[..., 2, 1] = u[..., 4]
    return t


def _polish(Q, u, limit, rounds=12):
    """Exact balls from approximate weights, by pivoting on a guessed support.

    The support S starts as the points of positive weight when there are at most d + 1,
    else the points within (1 - eta) of the largest distance from the current centre
    (eta from the current duality gap). Each round puts the centre in
    the affine hull of S, equidistant from its points (:func:`_circumcentre`); a point of
    S with a negative barycentric weight leaves S, else the furthest point outside the
    ball joins it (pushing out the point of least weight when S has d + 1 points). A set
    is accepted only with the certificate of :func:`min_ball`: weights >= 0 and the
    largest distance from their centre within (1 + tolerance) of the dual bound.
    Returns (ok (m,), u (m, k)): the weights of the accepted sets replaced.
    """
    m, k, d = Q.shape
    c = np.matmul(u[:, None, :], Q)[:, 0]
    dist2 = ((Q - c[:, None]) ** 2).sum(-1)
    top = dist2.max(1)
    gamma = (u * dist2).sum(1)
    eta = np.clip(8 * (top / np.where(gamma > 0, gamma, 1) - 1), 1e-10, 0.05)
    sup = dist2 >= (1 - eta[:, None]) * top[:, None]
    # the weights' own support when it is small enough: near-copies of a support point
    # (a path that dwells) lie within eta of the largest distance and crowd the guess
    own = u > 1e-12
    small = (own.sum(1) >= 2) & (own.sum(1) <= d + 1)
    sup[small] = own[small]
    over = sup.sum(1) > d + 1                   # too many: keep the d + 1 furthest
    if over.any():
        far = np.argsort(-dist2[over], axis=1)[:, :d + 1]
        sup[over] = False
        sup[np.repeat(np.flatnonzero(over), d + 1), far.ravel()] = True
    ok = np.zeros(m, bool)
    u = u.copy()
    todo = np.arange(m)
    for _ in range(rounds):
        if todo.size == 0:
            break
        w, centre, r2 = _circumcentre(Q[todo], sup[todo])
        d2 = ((Q[todo] - centre[:, None]) ** 2).sum(-1)
        wmin = np.where(sup[todo], w, np.inf)
        neg = np.isfinite(r2) & (wmin.min(1) < -1e-12)
        # certificate, as in min_ball: weights >= 0 give a dual bound gamma <= r*^2
        wc = np.clip(w, 0.0, None)
        wc /= np.where(wc.sum(1) > 0, wc.sum(1), 1.0)[:, None]
        cw = np.matmul(wc[:, None, :], Q[todo])[:, 0]
        dw = ((Q[todo] - cw[:, None]) ** 2).sum(-1)
        inside = np.isfinite(r2) & ~neg & (dw.max(1) <= (1 + limit) * (wc * dw).sum(1))
        acc = todo[inside]
        ok[acc] = True
        u[acc] = wc[inside]
        # pivot the others
        i_neg = todo[neg]
        sup[i_neg, np.argmin(wmin[neg], axis=1)] = False
        grow = np.isfinite(r2) & ~neg & ~inside
        i_g = todo[grow]
        full = sup[i_g].sum(1) >= d + 1
        if full.any():
            least = np.argmin(np.where(sup[i_g[full]], w[grow][full], np.inf), axis=1)
            sup[i_g[full], least] = False
        sup[i_g, np.argmax(d2[grow], axis=1)] = True
        todo = todo[neg | grow]
    return ok, u


def _circumcentre(Q, sup):
    """Centre in the affine hull of the points ``sup`` (m, k), equidistant from them.

    Returns the barycentric weights (m, k) (0 off the support), the centre (m, d) and
    the squared radius (m,) (inf where the support has < 2 or > d + 1 points). A
    degenerate support (affinely dependent points) gets the least-norm solution: the
    caller's certificate decides whether it is the ball.
    """
    m, k, d = Q.shape
    size = sup.sum(1)
    order = np.argsort(~sup, axis=1, kind="stable")[:, :d + 1]      # support first
    pts = Q[np.arange(m)[:, None], order]                           # (m, d+1, d)
    valid = np.arange(d + 1)[None, :] < size[:, None]
    p0 = pts[:, 0]
    e = pts[:, 1:] - p0[:, None]
    slot = valid[:, 1:]
    A = 2 * np.matmul(e, e.transpose(0, 2, 1))
    A = np.where(slot[:, :, None] & slot[:, None, :], A, 0.0)
    A[:, np.arange(d), np.arange(d)] += np.where(slot, 0.0, 1.0)
    rhs = np.where(slot, (e ** 2).sum(-1), 0.0)       # 2 e_i . x = |e_i|^2, x = c - p0
    alpha = np.matmul(np.linalg.pinv(A), rhs[..., None])[..., 0]   # min-norm if degenerate
    x = np.matmul(alpha[:, None, :], e)[:, 0]
    centre = p0 + x
    wsup = np.concatenate([1 - alpha.sum(1, keepdims=True), alpha], axis=1)   # barycentric
    wsup = np.where(valid, wsup, 0.0)
    w = np.zeros((m, k))
    w[np.repeat(np.arange(m), d + 1), order.ravel()] = wsup.ravel()
    r2 = np.where((size >= 2) & (size <= d + 1) & np.all(np.isfinite(wsup), 1),
                  (x ** 2).sum(-1), np.inf)
    return w, centre, r2


def _advance_sets(act, u, pc, b, tiny, limit, column):
    """One step of each active set of :func:`min_ball`: towards its furthest point
    (Frank-Wolfe) or away from its nearest supporting one, with the exact line search;
    ``u`` (weights) and ``pc`` (products q_i . c) are updated in place. Returns the sets
    still short of the tolerance (none when every set has reached it)."""
    ua, pa = u[act], pc[act]
    cc = (ua * pa).sum(1)
    dist2 = b[act] - 2 * pa + cc[:, None]
    gamma = (ua * dist2).sum(1)
    r = np.arange(len(act))
    j = np.argmax(dist2, axis=1)
    dj = dist2[r, j]
    pos = gamma > 0
    dplus = np.where(pos, dj / np.where(pos, gamma, 1.0) - 1.0, np.inf)
    done = (dplus <= limit) | (dj <= tiny[act])
    if np.all(done):
        return act[:0]
    keep = ~done
    act, ua, pa, dist2, gamma, j, dplus = (act[keep], ua[keep], pa[keep], dist2[keep],
                                           gamma[keep], j[keep], dplus[keep])
    r = np.arange(len(act))
    masked = np.where(ua > 0, dist2, np.inf)
    kk = np.argmin(masked, axis=1)
    dminus = 1.0 - masked[r, kk] / np.where(gamma > 0, gamma, 1.0)
    fwd = dplus >= dminus
    # a single support point (gamma = 0): the line search gives lam = 1/2
    lam_f = np.where(np.isinf(dplus), 0.5,
                     dplus / (2 * (1 + np.where(np.isinf(dplus), 0.0, dplus))))
    uk = ua[r, kk]
    lam_a = np.minimum(dminus / (2 * (1 - np.minimum(dminus, 1 - 1e-16))),
                       uk / np.maximum(1 - uk, 1e-300))
    scale = np.where(fwd, 1 - lam_f, 1 + lam_a)
    ua = ua * scale[:, None]
    pa = pa * scale[:, None]
    f, a = r[fwd], r[~fwd]
    ua[f, j[fwd]] += lam_f[fwd]
    pa[f] += lam_f[fwd][:, None] * column(act[f], j[fwd])
    ua[a, kk[~fwd]] -= lam_a[~fwd]
    pa[a] -= lam_a[~fwd][:, None] * column(act[a], kk[~fwd])
    u[act] = np.clip(ua, 0.0, None)
    pc[act] = pa
    return act


def min_ball(points, tolerance=1e-9, max_iter=100000):
    """Minimum enclosing balls of many small point sets (Frank-Wolfe with away steps).

    Parameters
    ----------
    points : ndarray
        (m, k, d): m independent sets of k points in d dimensions.
    tolerance : float
        Certified relative accuracy of the radii.
    max_iter : int
        Iterations at most; a set that has not converged raises.

    Returns
    -------
    centre : ndarray (m, d)
    radius : ndarray (m,)
        The largest distance from ``centre`` to the set's points, within a factor
        (1 + tolerance) of the smallest possible.

    Raises
    ------
    RuntimeError
        Some set did not reach the tolerance in ``max_iter`` iterations.

    Notes
    -----
    Dual form (Yildirim 2008, algorithm 2): weights u on the simplex, centre c = sum u_i
    p_i, gamma = sum u_i |p_i - c|^2 <= r*^2 <= max_i |p_i - c|^2. Each step moves
    weight towards the furthest point or away from the nearest supporting one, with the
    exact line search; O(k d) work per set and step (the products p_i . c are updated
    with one column of the Gram matrix, and recomputed at each polish against drift;
    points are shifted to their mean first). After 8 steps, then every 16, the support is read
    off the weights and the exact ball through it is found by pivoting (:func:`_polish`),
    accepted only where it satisfies the optimality conditions: most sets finish there.
    """
    P = np.asarray(points, dtype=float)
    m, k, _ = P.shape
    shift = P.mean(axis=1, keepdims=True)
    Q = P - shift
    b = (Q * Q).sum(-1)                                   # |q_i|^2

    def products(rows, weights):                          # q_i . c for c = sum u_j q_j
        c = np.matmul(weights[:, None, :], Q[rows])[:, 0]
        return np.matmul(Q[rows], c[:, :, None])[..., 0]

    def column(rows, j):                                  # q_i . q_j
        return np.matmul(Q[rows], Q[rows, j][:, :, None])[..., 0]

    rows = np.arange(m)
    ia = np.argmax(b, axis=1)
    ib = np.argmax(b - 2 * column(rows, ia) + b[rows, ia][:, None], axis=1)
    u = np.zeros((m, k))
    u[rows, ia] += 0.5
    u[rows, ib] += 0.5
    limit = (1.0 + tolerance) ** 2 - 1.0
    tiny = 1e-30 * np.maximum(b.max(1), 1e-300)
    act = rows
    pc = products(rows, u)
    for it in range(max_iter):
        if it % 16 == 7:
            ok, unew = _polish(Q[act], u[act], limit)
            u[act] = unew
            pc[act] = products(act, u[act])
            act = act[~ok]
            if act.size == 0:
                break
        act = _advance_sets(act, u, pc, b, tiny, limit, column)
        if act.size == 0:
            break
    else:
        raise RuntimeError(f"minimum enclosing ball: {len(act)} point sets did not "
                           f"reach the relative tolerance {tolerance:g} in {max_iter} "
                           "iterations")
    u /= u.sum(1, keepdims=True)
    centre = np.matmul(u[:, None, :], Q)[:, 0]
    radius = np.sqrt(((Q - centre[:, None]) ** 2).sum(-1).max(1))
    return centre + shift[:, 0], radius


def longest_chord(points):
    """Half the longest chord of each point set and its midpoint: (centre, radius).

    ``points``: (m, k, d). O(k^2) per set.
    """
    P = np.asarray(points, dtype=float)
    m, k, _ = P.shape
    best = np.full(m, -1.0)
    ia = np.zeros(m, dtype=int)
    ib = np.zeros(m, dtype=int)
    for i in range(k):
        d2 = ((P[:, i:i + 1] - P[:, i:]) ** 2).sum(-1)
        jj = np.argmax(d2, axis=1)
        v = d2[np.arange(m), jj]
        better = v > best
        best = np.where(better, v, best)
        ia = np.where(better, i, ia)
        ib = np.where(better, i + jj, ib)
    rows = np.arange(m)
    centre = 0.5 * (P[rows, ia] + P[rows, ib])
    return centre, 0.5 * np.sqrt(best)


def _centre_radius(u, method, tolerance):
    if method == "mcb":
        return min_ball(u, tolerance)
    return longest_chord(u)


def plane_normals(step_deg):
    """Unit normals of planes on a grid of the hemisphere n3 >= 0 (no plane twice).

    Polar angle theta from x3 in steps of ``step_deg`` degrees (0 to 90), azimuth phi
    from x1 on a grid as close to ``step_deg`` as divides the circle; at theta = 90 only
    phi < 180. Returns (normals (m, 3), theta (m,), phi (m,)) with angles in degrees.
    """
    nt = max(1, int(round(90.0 / step_deg)))
    out = [(0.0, 0.0)]
    for i in range(1, nt + 1):
        theta = 90.0 * i / nt
        nphi = max(4, int(round(360.0 * math.sin(math.radians(theta)) / step_deg)))
        for j in range(nphi):
            phi = 360.0 * j / nphi
            if i == nt and phi >= 180.0 - 1e-9:
                continue
            out.append((theta, phi))
    th, ph = (np.array(v) for v in zip(*out, strict=True))
    return _normal(th, ph), th, ph


def _normal(theta, phi):
    t, p = np.radians(theta), np.radians(phi)
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


def _plane_weights(n):
    """w with sigma_n = w . (s11, s22, s33, s12, s13, s23) for normals n[..., 3]."""
    return np.stack([n[..., 0] ** 2, n[..., 1] ** 2, n[..., 2] ** 2, 2 * n[..., 0] * n[..., 1],
                     2 * n[..., 0] * n[..., 2], 2 * n[..., 1] * n[..., 2]], axis=-1)


# --------------------------------------------------------------------------- criteria

def _fatigue_limits(c):
    t, f = c["torsion_limit"], c["bending_limit"]
    if not (t > 0 and f > 0):
        raise ValueError(f"torsion_limit = {t!r} Pa and bending_limit = {f!r} Pa must be > 0")
    return t, f


def _amplitude(s, c):
    """s: (m, nt, 6). Component amplitudes and means, von Mises amplitude, hydrostatic."""
    hi, lo = s.max(1), s.min(1)
    out = {}
    for i, name in enumerate(COMPONENTS):
        out[f"{name}_amplitude"] = (hi[:, i] - lo[:, i]) / 2
        out[f"{name}_mean"] = (hi[:, i] + lo[:, i]) / 2
    _, rad = _centre_radius(deviatoric_coordinates(s), c["shear_amplitude"], c["tolerance"])
    sh = s[..., :3].sum(-1) / 3
    out["equivalent_amplitude"] = SQRT3 * rad
    out["hydrostatic_mean"] = (sh.max(1) + sh.min(1)) / 2
    out["hydrostatic_max"] = sh.max(1)
    return out


def _crossland(s, c):
    t, f = _fatigue_limits(c)
    alpha = 3 * t / f - SQRT3
    _, rad = _centre_radius(deviatoric_coordinates(s), c["shear_amplitude"], c["tolerance"])
    sh_max = s[..., :3].sum(-1).max(1) / 3
    eq = rad + alpha * sh_max
    return {"crossland_index": eq / t, "crossland_stress": eq, "sqrt_j2_amplitude": rad,
            "hydrostatic_max": sh_max}


def _dang_van(s, c):
    t, f = _fatigue_limits(c)
    a = 3 * t / f - 1.5
    u = deviatoric_coordinates(s)
    centre, _ = _centre_radius(u, c["shear_amplitude"], c["tolerance"])
    meso = _deviator_tensor(u - centre[:, None])
    ev = np.linalg.eigvalsh(meso)                        # ascending, (m, nt, 3)
    tau = (ev[..., 2] - ev[..., 0]) / 2
    sh = s[..., :3].sum(-1) / 3
    dv = tau + a * sh
    k = np.argmax(dv, axis=1)
    rows = np.arange(len(k))
    return {"dang_van_index": dv[rows, k] / t, "dang_van_stress": dv[rows, k],
            "mesoscopic_shear": tau[rows, k], "hydrostatic": sh[rows, k]}


def _swt_planes(s, n, young, nu):
    """SWT over planes: s (m, nt, 6), n (m or 1, p, 3) -> (m, p) parameter values."""
    w = _plane_weights(n)                                 # (m|1, p, 6)
    sn = np.matmul(s, w[0].T) if w.shape[0] == 1 else np.matmul(s, w.transpose(0, 2, 1))
    tr = s[..., :3].sum(-1)[..., None]                    # (m, nt, 1)
    en = ((1 + nu) * sn - nu * tr) / young
    return np.clip(sn.max(1), 0.0, None) * (en.max(1) - en.min(1)) / 2


def _swt(s, c):
    young, nu, step = c["young"], c["poisson"], c["plane_step"]
    if not young > 0:
        raise ValueError(f"young = {young!r} Pa: must be > 0")
    normals, theta, phi = plane_normals(step)
    val = _swt_planes(s, normals[None], young, nu)
    best = np.argmax(val, axis=1)
    th, ph = theta[best], phi[best]
    h = float(step)
    for _ in range(2):                                    # refine around the best normal
        h /= 4
        offs = np.array([(i * h, j * h) for i in range(-4, 5) for j in range(-4, 5)])
        tt = th[:, None] + offs[None, :, 0]
        pp = ph[:, None] + offs[None, :, 1]
        val = _swt_planes(s, _normal(tt, pp), young, nu)
        b = np.argmax(val, axis=1)
        rows = np.arange(len(b))
        th, ph = tt[rows, b], pp[rows, b]
    n = _normal(th, ph)
    flip = n[:, 2] < 0                                    # report n3 >= 0
    n[flip] *= -1
    best_val = val[np.arange(len(b)), b]
    return {"swt": best_val, "swt_stress": np.sqrt(young * best_val),
            "plane_n1": n[:, 0], "plane_n2": n[:, 1], "plane_n3": n[:, 2]}


#: criterion -> (function, main field, units of each field, required and default constants)
CRITERIA = {
    "amplitude": (_amplitude, "equivalent_amplitude", {}, {},
                  {"shear_amplitude": "mcb", "tolerance": 1e-9}),
    "crossland": (_crossland, "crossland_index",
                  {"crossland_index": "1", "sqrt_j2_amplitude": "Pa"},
                  {"torsion_limit": "Pa", "bending_limit": "Pa"},
                  {"shear_amplitude": "mcb", "tolerance": 1e-9}),
    "dang_van": (_dang_van, "dang_van_index", {"dang_van_index": "1"},
                 {"torsion_limit": "Pa", "bending_limit": "Pa"},
                 {"shear_amplitude": "mcb", "tolerance": 1e-9}),
    "swt": (_swt, "swt", {"plane_n1": "1", "plane_n2": "1", "plane_n3": "1"},
            {"young": "Pa"}, {"poisson": None, "plane_step": 10.0}),
}

LONG_NAMES = {
    "equivalent_amplitude": "von Mises equivalent stress amplitude sqrt(3 J2,a)",
    "hydrostatic_mean": "mean hydrostatic stress over the cycle",
    "hydrostatic_max": "largest hydrostatic stress over the cycle",
    "crossland_index": "Crossland index (sqrt(J2,a) + alpha sigma_h,max) / t_-1",
    "crossland_stress": "Crossland equivalent stress sqrt(J2,a) + alpha sigma_h,max",
    "sqrt_j2_amplitude": "shear stress amplitude sqrt(J2,a)",
    "dang_van_index": "Dang Van index max_t(tau + a sigma_h) / t_-1",
    "dang_van_stress": "Dang Van equivalent stress max_t(tau + a sigma_h)",
    "mesoscopic_shear": "mesoscopic Tresca shear at the critical instant",
    "hydrostatic": "hydrostatic stress at the critical instant",
    "swt": "Smith-Watson-Topper parameter sigma_n,max eps_a on the critical plane",
    "swt_stress": "SWT equivalent stress sqrt(E sigma_n,max eps_a)",
    "plane_n1": "critical plane normal, component 1",
    "plane_n2": "critical plane normal, component 2",
    "plane_n3": "critical plane normal, component 3 (>= 0)",
}


def _constants(criterion, given, stress_ds):
    if criterion not in CRITERIA:
        raise ValueError(f"criterion = {criterion!r}: allowed "
                         f"{', '.join(map(repr, CRITERIA))}")
    _, _, _, required, defaults = CRITERIA[criterion]
    unknown = sorted(set(given) - set(required) - set(defaults))
    missing = sorted(set(required) - set(given))
    if unknown or missing:
        parts = ([f"unknown constant(s) {', '.join(unknown)}"] if unknown else []) + \
                ([f"missing {', '.join(f'{m} [{required[m]}]' for m in missing)}"]
                 if missing else [])
        raise ValueError(f"criterion {criterion!r}: {'; '.join(parts)} (takes "
                         f"{', '.join(list(required) + list(defaults))})")
    c = dict(defaults, **given)
    for k in required:
        c[k] = float(c[k])
    if "shear_amplitude" in c and c["shear_amplitude"] not in ("mcb", "longest_chord"):
        raise ValueError(f"shear_amplitude = {c['shear_amplitude']!r}: allowed 'mcb', "
                         "'longest_chord'")
    if criterion == "swt":
        if c["poisson"] is None:
            nu = stress_ds.attrs.get("poisson")
            if nu is None:
                raise ValueError("criterion 'swt': the dataset has no 'poisson' attribute; "
                                 "pass poisson=")
            c["poisson"] = float(nu)
        if not MIN_PLANE_STEP <= float(c["plane_step"]) <= 90:
            raise ValueError(f"plane_step = {c['plane_step']!r} degrees: allowed "
                             f"{MIN_PLANE_STEP:g} to 90 (the smallest, {MIN_PLANE_STEP:g}, "
                             f"already holds about {_planes(MIN_PLANE_STEP)} planes, refined "
                             f"twice to 1/16 of the step; a finer grid does not fit in "
                             f"memory)")
        c["plane_step"] = float(c["plane_step"])
    return c


def _check_stress(ds):
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"expected a stress Dataset, got {type(ds).__name__}")
    missing = [c for c in COMPONENTS if c not in ds.data_vars]
    if missing:
        raise ValueError(f"the dataset has no {', '.join(missing)}: give the result of "
                         "cp.subsurface_stress")
    dims = tuple(ds["s11"].dims)
    if dims != ("time", "x3", "x1", "x2"):
        raise ValueError(f"stress dims {dims}, expected ('time', 'x3', 'x1', 'x2')")
    if ds.sizes["time"] < 2:
        raise ValueError(f"the dataset holds {ds.sizes['time']} instant: a fatigue "
                         "criterion needs the stress over a cycle (subsurface_stress(..., "
                         "time='all'), then .sel(time=...) for one cycle)")


def fatigue(stress_ds: xr.Dataset, criterion: str = "crossland", **constants) -> xr.Dataset:
    """A fatigue criterion over the cycle held by a stress dataset, at every point.

    Parameters
    ----------
    stress_ds : xarray.Dataset
        From :func:`contactpipe.subsurface_stress` over (time, x3, x1, x2), holding at
        least two instants: the cycle (its instants, all of them, are the history).
    criterion : {"amplitude", "crossland", "dang_van", "swt"}
        See the module docstring.
    **constants
        The criterion's material constants [Pa] and options: ``torsion_limit``,
        ``bending_limit`` (crossland, dang_van); ``young`` [Pa], ``poisson``,
        ``plane_step`` [deg] (swt); ``shear_amplitude`` ("mcb" | "longest_chord") and
        ``tolerance`` (amplitude, crossland, dang_van).

    Returns
    -------
    xarray.Dataset
        Fields over (x3, x1, x2); the main one (attribute ``criterion_field``) also as
        the scalars ``maximum`` and its position ``maximum_x1``, ``maximum_x2``,
        ``maximum_x3`` [m].

    Notes
    -----
    A lazy (dask) stress dataset is computed one x3 chunk at a time, all instants and
    the six components together; the working memory of the criterion itself is bounded
    by :data:`BLOCK_BYTES` per block of points.

    Raises
    ------
    ValueError
        Unknown criterion, missing or unknown constants, a dataset that is not a stress
        history.
    """
    _check_stress(stress_ds)
    c = _constants(criterion, constants, stress_ds)
    fn, main, units, _, _ = CRITERIA[criterion]
    nt = stress_ds.sizes["time"]
    n1, n2 = stress_ds.sizes["x1"], stress_ds.sizes["x2"]
    per_point = nt * 6 * 8 * (8 if criterion != "swt" else
                              len(plane_normals(c["plane_step"])[0]))
    block = max(1, int(BLOCK_BYTES // per_point))
    fields = None
    nz = stress_ds.sizes["x3"]
    chunks = stress_ds["s11"].chunks
    bounds = np.cumsum((0,) + tuple(chunks[1])) if chunks is not None else np.arange(nz + 1)
    for z0, z1 in zip(bounds[:-1], bounds[1:], strict=True):
        # one read (or one dask computation) of the six components per group of depths
        group = stress_ds[list(COMPONENTS)].isel(x3=slice(int(z0), int(z1))).compute()
        for k in range(int(z0), int(z1)):
            s = np.stack([np.asarray(group[v].isel(x3=k - int(z0)).values, dtype=float)
                          for v in COMPONENTS], axis=-1)            # (nt, n1, n2, 6)
            s = s.reshape(nt, n1 * n2, 6).transpose(1, 0, 2)
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                # an overflow is refused below (_refuse_nonfinite), not warned of
                parts = [fn(s[i:i + block], c) for i in range(0, n1 * n2, block)]
            res = {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
            if fields is None:
                fields = {name: np.empty((nz, n1, n2)) for name in res}
            for name, v in res.items():
                fields[name][k] = v.reshape(n1, n2)
    _refuse_nonfinite(criterion, c, fields)
    return _result(stress_ds, criterion, c, fields, main, units)


def _refuse_nonfinite(criterion, c, fields) -> None:
    """ValueError when a field came out NaN or inf (constants so small or large that the
    criterion overflows, or a stress holding NaN): such a result is never returned."""
    bad = [name for name, v in fields.items() if not np.all(np.isfinite(v))]
    if bad:
        given = ", ".join(f"{k} = {c[k]!r}" for k in ("torsion_limit", "bending_limit",
                                                       "young") if k in c)
        raise ValueError(f"criterion {criterion!r}: {', '.join(bad)} came out NaN or inf"
                         + (f" with {given}" if given else "")
                         + ": give constants of a material (fatigue limits of the order of "
                           "1e6 to 1e10 Pa) and a stress free of NaN")


def _result(stress_ds, criterion, c, fields, main, units) -> xr.Dataset:
    coords = {k: stress_ds[k].variable for k in ("x3", "x1", "x2")}
    data = {name: xr.Variable(("x3", "x1", "x2"), v,
                              {"units": units.get(name, "Pa"),
                               "long_name": LONG_NAMES.get(name, name.replace("_", " "))})
            for name, v in fields.items()}
    out = xr.Dataset(data, coords=coords)
    f = fields[main]
    k, i, j = np.unravel_index(int(np.argmax(f)), f.shape)
    out["maximum"] = xr.Variable((), float(f[k, i, j]),
                                 {"units": units.get(main, "Pa"),
                                  "long_name": f"largest {main}"})
    for name, ax, idx in (("maximum_x1", "x1", i), ("maximum_x2", "x2", j),
                          ("maximum_x3", "x3", k)):
        out[name] = xr.Variable((), float(stress_ds[ax].values[idx]),
                                {"units": "m", "long_name": f"{ax} of the largest {main}"})
    t = stress_ds["time"].values
    consts = {k: v for k, v in c.items()}
    out.attrs = {
        "Conventions": "CF-1.10",
        "title": f"fatigue criterion {criterion}",
        "contactpipe_version": __version__,
        "criterion": criterion,
        "criterion_field": main,
        "constants": "; ".join(f"{k} = {v}" for k, v in consts.items()),
        "cycle": f"{len(t)} instants from {float(t[0]):g} s to {float(t[-1]):g} s",
        "body": stress_ds.attrs.get("body", ""),
    }
    return out
