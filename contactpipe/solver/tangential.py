"""The uncoupled tangential contact problem (UTC): stick and slip under force control.

Given the pressure p (so the traction bound μp), the known part of the relative in-plane
displacement and the state of the previous instant, find the shear traction q and the
rigid shift increment Δω such that (paper eqs. 2, 4, 6; docs/conventions.md)

    Σ q Δ = T,
    stick (|q| < μp):  Δs = Δω − Δu = 0,
    slip  (|q| = μp):  q ∥ Δs and q·Δs ≥ 0 (friction dissipates).

Working on the slip *increment* is what remembers the path: a fretting loop's unloading
branch differs from its loading branch. This is the minimisation of
½ qᵀAq + (u_known − u_prev)ᵀq under |q| ≤ μp and Σq = T/Δ, whose multiplier is Δω and
whose residual is −Δs.

Two forms:

* ``scalar`` — the Cattaneo-Mindlin form: q2 = 0, a two-sided bound −μp ≤ q1 ≤ μp, solved
  by the bound-constrained CG of :mod:`contactpipe.solver.cg` (one FFT pair per iteration).
  An approximation (it neglects the x2 slip condition, so s2 = 0 by construction): the
  neglected q2 is small when the load is along x1 (test_tangential measures it).
* ``vector`` — the full problem with a disk |q| ≤ μp per cell: projected conjugate
  gradients in the spirit of Vollebregt's TangCG (2014): conjugate directions on the
  stick cells and on slip cells whose residual points inwards; slip cells keep |q| = μp
  and turn towards the slip direction; the force is restored by a clipped shift of the
  stick cells. Two FFT pairs per operator application.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cg import box_cg, fista, project_box_sum

__all__ = ["TangentialResult", "solve_scalar", "solve_vector", "disk_project"]


@dataclass
class TangentialResult:
    q: np.ndarray            # (2, N1, N2) shear traction [Pa]
    domega: np.ndarray       # (2,) rigid shift increment Δω [m]
    Aq: np.ndarray           # (2, N1, N2) A q [m] (u1 only, u2 = 0 for the scalar form)
    iterations: int
    residual: float
    converged: bool


def solve_scalar(op, b1, bound, T1, cell_area, q0, tol, max_iter, Aq0=None):
    """Cattaneo-Mindlin form (q2 = 0).

    Parameters
    ----------
    op : ContactOperator
        Provides ``tangential_scalar`` (K11 ⊛ q1).
    b1 : ndarray
        Known in-plane displacement minus the previous one, u1_known − u1(k−1) [m].
    bound : ndarray
        μp [Pa] (zero outside the contact).
    T1 : float
        Tangential force [N].
    q0 : ndarray
        Warm start for q1 [Pa].
    """
    scale = max(float(bound.sum()), 1e-300)
    target = T1 / cell_area

    def cg(x0, Ax0, tol_, budget):
        r = box_cg(op.tangential_scalar, b1, -bound, bound, target, x0, tol=tol_,
                   max_iter=budget, restore="shift", scale=scale, Ax0=Ax0)
        return r.x, r.Ax, r.iterations, r.residual, r.converged

    def pg(x0, Ax0, tol_, budget):
        return fista(op.tangential_scalar, b1,
                     lambda y: project_box_sum(y, -bound, bound, target), x0,
                     op.tangential_norm(1), tol_, budget, scale, Ax0=Ax0)

    x, Ax, its, err, ok = _cg_with_fallback(cg, pg, q0, Aq0, tol, max_iter)
    stick = (bound > 0) & (np.abs(x) < bound * (1.0 - 1e-12))
    lam = float(_multiplier((Ax + b1)[None], stick)[0])
    q = np.zeros((2,) + b1.shape)
    q[0] = x
    Aq = np.zeros_like(q)
    Aq[0] = Ax
    return TangentialResult(q=q, domega=np.array([lam, 0.0]), Aq=Aq, iterations=its,
                            residual=err, converged=ok)


def disk_project(q, rho):
    """Radial projection of each cell's vector onto the disk |q| ≤ rho. Returns (q, at_bound)."""
    mag = np.hypot(q[0], q[1])
    over = mag > rho
    if over.any():
        f = np.where(over, rho / np.where(mag > 0, mag, 1.0), 1.0)
        q = q * f
    return q, over


def _restore_vector(q, rho, target, stick):
    """Shift the stick cells by one vector c (then project) so that Σq = target (2,)."""
    for cells in (stick, rho > 0):
        n = int(np.count_nonzero(cells))
        if n == 0:
            continue
        c = np.zeros(2)
        for _ in range(100):
            y = q[:, cells] + c[:, None]
            y, _ = disk_project(y, rho[cells])
            total = y.sum(axis=1) + q[:, ~cells].sum(axis=1)
            f = total - target
            if np.abs(f).max() <= 1e-13 * (np.abs(target).max() + rho.sum()):
                break
            inside = np.count_nonzero(np.hypot(y[0], y[1]) < rho[cells]) or n
            c -= f / inside
        out = q.copy()
        out[:, cells] = y
        if np.abs(out.sum(axis=(1, 2)) - target).max() <= 1e-11 * (np.abs(target).max() + rho.sum()):
            return out
        q = out
    return q


def _vector_cg(op, b, bound, T, cell_area, q0, tol, max_iter, Aq0=None):
    """Full vector form by projected CG (the fast path of :func:`solve_vector`, same
    parameters).

    Notes
    -----
    Preconditioned projected conjugate gradients over all contact cells at once:

    * stick cells (|q| < μp), and slip cells whose residual points into the disk (they
      re-enter), move along the residual;
    * the other slip cells may only turn on their circle |q| = μp: the variable is their
      slip angle θ (Zhao, Vollebregt & Oosterlee 2014, "A fast nonlinear conjugate
      gradient based method for 3D frictional contact problems"), with the diagonal
      preconditioner 1/(ρ²a + ρ|r·q̂|) — a the self-influence, r the residual; the second
      term is the curvature of the circle — which in q-space scales the tangential residual
      by ρa/(ρa + |r·q̂|) relative to a stick cell; the previous direction is transported
      to the current tangents;
    * after the exact line search, stick cells pushed past the disk are projected radially
      (they join the slip set) and turning cells are put back on their circles; the force
      is restored by a shift of the stick cells.

    Each iteration costs one operator application (two FFT pairs) and a second one when
    a projection changed the iterate.
    """
    target = np.asarray(T, dtype=float) / cell_area
    rho = bound
    movable = rho > 0
    a_self = op.self_influence("11")
    q, _ = disk_project(np.where(movable, q0, 0.0), rho)
    q = _restore_vector(q, rho, target, movable & (np.hypot(q[0], q[1]) < rho))
    Aq = op.tangential_vector(q) if (Aq0 is None or not np.array_equal(q, q0)) else Aq0
    scale = max(float(rho.sum()), 1e-300)
    t = np.zeros_like(q)
    rz_old = 1.0
    sets_old = None
    err = np.inf
    lam = np.zeros(2)
    it = 0
    for it in range(1, max_iter + 1):
        g = Aq + b
        mag = np.hypot(q[0], q[1])
        at_bound = movable & (mag >= rho * (1.0 - 1e-12))
        stick = movable & ~at_bound
        if stick.any():
            lam = g[:, stick].mean(axis=1)
        gr = g - lam[:, None, None]
        qhat = np.where(at_bound, q / np.where(mag > 0, mag, 1.0), 0.0)
        radial = qhat[0] * gr[0] + qhat[1] * gr[1]
        released = at_bound & (radial > 0)
        turning = at_bound & ~released
        free = stick | released
        # preconditioned residual z
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.where(turning, rho * a_self / (rho * a_self + np.abs(radial)), 1.0)
        gt = np.where(turning, gr - radial * qhat, gr)
        z = np.where(free | turning, gt * w, 0.0)
        if free.any():          # keep Σ z = 0: the force stays put along the direction
            z[:, free] -= (z.sum(axis=(1, 2)) / np.count_nonzero(free))[:, None]
        rz = float(np.sum(gt * z))
        if rz <= 0.0:
            err = 0.0
            break
        sets = (free, turning)
        reset = (released.any() or sets_old is None
                 or not (np.array_equal(free, sets_old[0])
                         and np.array_equal(turning, sets_old[1])))
        if reset:
            t = z
        else:
            # transport the old direction onto the current tangents of turning cells
            tr = qhat[0] * t[0] + qhat[1] * t[1]
            t_old = np.where(turning, t - tr * qhat, t)
            t = z + (rz / rz_old) * t_old
        rz_old = rz
        sets_old = sets
        r = op.tangential_vector(t)
        denom = float(np.sum(r * t))
        if denom <= 0.0:
            err = 0.0
            break
        tau = float(np.sum(gr * t)) / denom
        if turning.any():       # no cell turns by more than half a radian in one step
            spin = np.hypot(t[0], t[1]) / np.where(rho > 0, rho, 1.0)
            spin_max = float(spin[turning].max())
            if tau * spin_max > 0.5:
                tau = 0.5 / spin_max
                sets_old = None
        q_new = q - tau * t
        m = np.hypot(q_new[0], q_new[1])
        over = movable & (m > rho)
        fix = over | (turning & (m > 0))
        if fix.any():
            q_new[:, fix] *= rho[fix] / m[fix]
            q_new = _restore_vector(q_new, rho, target, stick & ~over)
            err = np.abs(q_new - q).sum() / scale
            q = q_new
            Aq = op.tangential_vector(q)
        else:
            err = np.abs(q_new - q).sum() / scale
            q = q_new
            Aq = Aq - tau * r
        if err < tol:
            break
    g = Aq + b
    mag = np.hypot(q[0], q[1])
    stick = movable & (mag < rho * (1.0 - 1e-12))
    if stick.any():
        lam = g[:, stick].mean(axis=1)
    return TangentialResult(q=q, domega=lam, Aq=Aq, iterations=it, residual=float(err),
                            converged=bool(err < tol))


def project_disks_sum(y, rho, target):
    """Euclidean projection of y (2, N1, N2) onto {|x_i| ≤ rho_i, Σ x_i = target}.

    x_i = P_disk(y_i − ν) with the multiplier ν (2,) found by Newton's method on the
    monotone map ν ↦ Σ P_disk(y_i − ν) (its Jacobian is Σ of the disk projections'
    Jacobians: I inside, (ρ/|z|)(I − ẑẑᵀ) on the rim).
    """
    cells = rho > 0
    ys, rs = y[:, cells], rho[cells]
    nu = (ys.sum(axis=1) - target) / max(np.count_nonzero(cells), 1)
    for _ in range(100):
        z = ys - nu[:, None]
        m = np.hypot(z[0], z[1])
        out = m > rs
        f = np.where(out, rs / np.where(m > 0, m, 1.0), 1.0)
        x = z * f
        res = x.sum(axis=1) - target
        if np.abs(res).max() <= 1e-13 * (np.abs(target).max() + rs.sum()):
            break
        zh = np.where(out, z / np.where(m > 0, m, 1.0), 0.0)
        J = np.eye(2) * np.count_nonzero(~out)
        fo = f[out]
        J = J + np.array([[np.sum(fo * (1 - zh[0, out] ** 2)), -np.sum(fo * zh[0, out] * zh[1, out])],
                          [-np.sum(fo * zh[0, out] * zh[1, out]), np.sum(fo * (1 - zh[1, out] ** 2))]])
        try:
            step = np.linalg.solve(J + 1e-14 * np.trace(J) * np.eye(2), res)
        except np.linalg.LinAlgError:
            step = res / max(np.count_nonzero(cells), 1)
        nu = nu + step
    xout = np.zeros_like(y)
    xout[:, cells] = x
    return xout


def _cg_with_fallback(cg, pg, x0, Ax0, tol, max_iter):
    """CG first; where it stalls, the projected gradient to a loose tolerance (it finds the
    slip/stick pattern that pins the multiplier), then CG again from there; the projected
    gradient, which always converges, finishes if CG stalls a second time.

    ``cg`` and ``pg`` take (x0, Ax0, tol, budget) and return (x, Ax, iterations, residual,
    converged). Returns the same tuple, iterations summed.
    """
    budget = max(1, max_iter // 4)
    x, Ax, its, err, ok = cg(x0, Ax0, tol, budget)
    if ok:
        return x, Ax, its, err, ok
    x, Ax, more, err, _ = pg(x, Ax, max(tol, 1e-6), budget)
    its += more
    x, Ax, more, err, ok = cg(x, Ax, tol, budget)
    its += more
    if ok:
        return x, Ax, its, err, ok
    x, Ax, more, err, ok = pg(x, Ax, tol, max(1, max_iter - its))
    return x, Ax, its + more, err, ok


def _multiplier(g, stick):
    return g[..., stick].mean(axis=-1) if stick.any() else np.zeros(g.shape[:-2])


def solve_vector(op, b, bound, T, cell_area, q0, tol, max_iter, Aq0=None):
    """Full vector form: disk constraint |q| ≤ μp per cell.

    Parameters
    ----------
    op : ContactOperator
        Provides ``tangential_vector`` ([K11 K12; K21 K22] ⊛ q).
    b : ndarray (2, N1, N2)
        Known in-plane displacement minus the previous one [m].
    bound : ndarray (N1, N2)
        μp [Pa].
    T : array_like (2,)
        Tangential force [N].
    q0 : ndarray (2, N1, N2)
        Warm start [Pa].

    Notes
    -----
    The preconditioned projected CG (:func:`_vector_cg`) runs first; where it stalls —
    typically when (almost) every cell slips and the multiplier Δω is not pinned by stick
    cells — see :func:`_cg_with_fallback`.
    """
    target = np.asarray(T, dtype=float) / cell_area
    scale = max(float(bound.sum()), 1e-300)

    def cg(x0, Ax0, tol_, budget):
        r = _vector_cg(op, b, bound, T, cell_area, x0, tol_, budget, Ax0)
        return r.q, r.Aq, r.iterations, r.residual, r.converged

    def pg(x0, Ax0, tol_, budget):
        return fista(op.tangential_vector, b, lambda y: project_disks_sum(y, bound, target),
                     x0, op.tangential_norm(2), tol_, budget, scale, Ax0=Ax0)

    q, Aq, its, err, ok = _cg_with_fallback(cg, pg, q0, Aq0, tol, max_iter)
    stick = (bound > 0) & (np.hypot(q[0], q[1]) < bound * (1.0 - 1e-12))
    return TangentialResult(q=q, domega=_multiplier(Aq + b, stick), Aq=Aq,
                            iterations=its, residual=err, converged=ok)
