"""One conjugate-gradient solve over (p, q1) for a coupled instant (the scalar form).

Block Gauss-Seidel (:func:`contactpipe.solver.coupling.solve_instant`) lags two things
from pass to pass: the coupling displacements (u3 from q through K31, u1 from p through
K13) and the friction bound μp. The coupling terms are linear and symmetric (reciprocity:
⟨p, K31 ⊛ q⟩ = ⟨q, K13 ⊛ p⟩), so with the bound held the instant is one bound-constrained
quadratic problem over the stacked tractions x = (p, q1),

    minimise  ½ xᵀ A x + bᵀ x,   A = [[K33, K31], [K13, K11]],   b = (hi + U3, U1 − u1(k−1)),
    subject to  p ≥ 0,  −g ≤ q1 ≤ g,  Σp = W/Δ,  Σq1 = T1/Δ,

whose optimality conditions are the contact laws of both problems at once (closed gap
under pressure; no slip increment in stick, a slip increment against the shear on the
bound), with multipliers (ω3, Δω1). :func:`contactpipe.solver.cg.box_cg` solves it with
the two force rows as :class:`~contactpipe.solver.cg.BlockSums` and the (−Δ)^½ filter on
each block as preconditioner: one operator application is two FFT pairs (two forward
transforms, four kernel products, two inverse), the preconditioner half of one (two
fields filtered on the unpadded grid).

Only the bound g = μp is then lagged. A pass moves the slip cells' shear by μ δp and the
pressure answers through K31 only, so a pass cuts the pressure change by about μβ
(measured about 1/100 with exact inner solves, steel on aluminium); block Gauss-Seidel
cuts it by β²-like factors of 1/20-1/50. Inner tolerances follow the same inexact
schedule as the block Gauss-Seidel passes; the passes stop when one at the full tolerance
moves p by less than the tolerance, or by so little that the next would at the contraction
just measured. A projection that moves the iterate by less than a tenth of the pass's
inner tolerance leaves its product out of A x until a larger one, or the next pass's start,
takes it in (:data:`DEFER`; the last pass's are taken in before its A x is returned).
:func:`finish` then puts the shear on the final pressure's bound, so that
Coulomb's law holds exactly, and builds the displacement from the products the solve
kept (docs/design-choices.md, "The coupled instant").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cg import BlockSums, box_cg
from .tangential import follow_bound, scalar_multiplier

__all__ = ["JointResult", "finish", "solve_joint"]

#: Loosest inner tolerance, that of the first pass [1] (never below the caller's): the
#: first pass answers the new load and the moved bound at once, and its pressure change
#: (about 1e-3) sets the next pass's tolerance anyway; 1e-4 (the block Gauss-Seidel
#: passes' value) cost 4-11 % more FFT pairs (docs/design-choices.md).
FIRST_PASS_TOLERANCE = 1e-3
#: Inner tolerance of a later pass, as a fraction of the last relative pressure change [1].
PASS_TOLERANCE_FRACTION = 1e-2
#: A pass whose inner tolerance would be within this factor of the full one runs at the
#: full tolerance, so that it can be the last [1].
FULL_WITHIN = 10.0
#: A projection that moves the iterate by less than this fraction of the pass's inner
#: tolerance leaves its product out of A x until the next one that does not, or the next
#: pass's start, takes it in (``box_cg(defer=...)``) [1].
DEFER = 0.1


@dataclass
class JointResult:
    p: np.ndarray           # (N1, N2) pressure [Pa]
    q1: np.ndarray          # (N1, N2) shear [Pa], within the bound of the last pass
    bound: np.ndarray       # (N1, N2) that bound, μ p of the pass before [Pa]
    omega3: float           # normal approach [m] (the p row's multiplier)
    Ax: np.ndarray          # (2, N1, N2) (K33 p + K31 q1, K13 p + K11 q1) [m]
    iterations: int
    passes: int
    converged: bool
    residual: float         # the failing solve's residual, or the last pressure change


def solve_joint(op, b, W, T1, cell_area, mu, p0, q0, tol, max_iter,
                max_passes) -> JointResult:
    """The coupled instant of the scalar form under force control of W and T1.

    Parameters
    ----------
    op : ContactOperator
        Operator of the instant (its creep weights included); not rigid.
    b : ndarray (2, N1, N2)
        The known normal gap hi + U3 and the known in-plane displacement less the
        previous instant's, U1 − u1(k−1) [m].
    W, T1 : float
        Normal and tangential force [N]; |T1| within the bounds' capacity.
    cell_area : float
        [m²]
    mu : float or ndarray (N1, N2)
        Friction coefficient [1].
    p0, q0 : ndarray (N1, N2)
        Warm starts [Pa]: the previous instant's pressure (in contact somewhere) and shear.
    tol, max_iter, max_passes :
        As in :class:`contactpipe.solver.coupling.Tolerances`.

    Returns
    -------
    JointResult
        ``converged`` False when a solve stopped or the passes did not settle.
    """
    conv, k = op.conv, op.k
    # the shear is solved as s = q1 / μ, of the pressure's size, so that the stacked
    # convergence measure Σ|Δ(p, s)| / Σ|(p, s)| holds the shear to the tolerance of the
    # tangential solve (Σ|Δq1| / Σμp) and not only to μ times it; with the preconditioner
    # scaled alike the iterates are those of the unscaled problem
    blocks = [[k["33"], mu * k["31"]], [mu * k["13"], mu * mu * k["11"]]]
    shape = (2,) + p0.shape

    def apply(x):                 # a zero block (a start's update) costs no transform
        return conv.convolve_matrix(blocks, [x[0] if x[0].any() else None,
                                             x[1] if x[1].any() else None],
                                    out=np.empty(shape))

    filter_ = op.normal_preconditioner()

    def precondition(v):
        z = filter_(v, out=np.empty(shape))
        z[1] /= mu * mu
        return z

    b = np.stack([b[0], mu * b[1]])
    rows = BlockSums([W / cell_area, T1 / cell_area / mu])
    zero, inf = np.zeros_like(p0), np.full_like(p0, np.inf)
    p, s = np.array(p0, dtype=float), np.array(q0, dtype=float) / mu
    lag_old, Ax, its, change = None, None, 0, np.inf
    pending = None          # the last pass's projections not yet in its A x
    inner = max(tol, FIRST_PASS_TOLERANCE)
    for passes in range(1, max_passes + 1):
        lag = p                                   # the bound of s: |s| <= p (lagged)
        lo, hi = np.stack([zero, -lag]), np.stack([inf, lag])
        Ax_of = None
        if lag_old is not None:                   # slip cells stay on their moved bound
            moved = follow_bound(s, lag_old, lag)
            if not np.array_equal(moved, s) or pending is not None:
                # A x of the moved start, updated by the shear block alone (1.5 FFT pairs
                # instead of 2 for a new product; the start's force rows move s only),
                # and by what the last pass left out of it
                Ax_of, s = np.stack([p, s]), moved
                if pending is not None:
                    Ax_of -= pending
        res = box_cg(apply, b, lo, hi, rows, np.stack([p, s]), tol=inner,
                     max_iter=max_iter, restore="shift", Ax0=Ax, precondition=precondition,
                     Ax0_of=Ax_of, update=True, defer=DEFER)
        pending = res.pending
        its += res.iterations
        if not res.converged:
            return JointResult(p, mu * s, mu * lag, np.nan, res.Ax, its, passes, False,
                               res.residual)
        change_old = change
        change = float(np.abs(res.x[0] - p).sum()) * cell_area / max(W, 1e-300)
        p, s, Ax = res.x[0], res.x[1], res.Ax
        last = inner == tol
        inner = min(inner, max(tol, PASS_TOLERANCE_FRACTION * change))
        if inner < FULL_WITHIN * tol:       # near the end: this pass may be the last
            inner = tol
        lag_old = lag
        # settled: a pass at the full tolerance moved p by less than it, or by so little
        # that the next one, at the contraction just measured, would (the lag of the
        # bound is then below the tolerance)
        if last and (change < tol or (0.0 < change_old < np.inf
                                      and change * min(1.0, change / change_old) < tol)):
            omega3 = float(res.multiplier[0])
            if pending is not None:               # the product made exact at the end
                Ax = Ax + apply(pending)
                omega3 = float(rows.fit(Ax + b, (res.x > lo) & (res.x < hi))[0])
            Ax = np.stack([Ax[0], Ax[1] / mu])     # (K33 p + K31 q1, K13 p + K11 q1)
            return JointResult(p, mu * s, mu * lag, omega3, Ax, its, passes, True, change)
    return JointResult(p, mu * s, mu * lag_old, np.nan, Ax, its, max_passes, False, change)


def finish(op, j: JointResult, mu, b1):
    """The joint solution on the bound of its own final pressure, without another solve.

    The last pass held the shear within μ p of the pass before, which differs from the
    final μ p by less than the tolerance: the slip cells move onto the final bound
    (:func:`follow_bound`) and a cell beyond it is clipped back, a change of q1 of the
    tolerance's order (a tangential solve against the final pressure, which this
    replaces, moved q1 as little and cost about 4 FFT pairs more).

    Parameters
    ----------
    op : ContactOperator
        The instant's operator.
    j : JointResult
        A converged joint solve.
    mu : float
        Friction coefficient [1].
    b1 : ndarray (N1, N2)
        U1 − u1(k−1) [m], the known in-plane displacement less the previous instant's.

    Returns
    -------
    q1 : ndarray (N1, N2)
        The shear [Pa], |q1| <= μ p with the slip cells on the bound.
    u : ndarray (3, N1, N2)
        The displacement [m] from the tractions (K [q1, 0, p]): the kept products
        K33 p + K31 q1 and K13 p + K11 q1 mended for the change of q1, and
        u2 = K21 q1 + K23 p (one block product: 1.5 FFT pairs, 3 when q1 moved).
    domega1 : float
        The tangential rigid shift increment Δω1 [m], the force row's multiplier.
    """
    k = op.k
    bound = mu * j.p
    q1 = np.clip(follow_bound(j.q1, j.bound, bound), -bound, bound)
    dq = q1 - j.q1
    u = np.empty((3,) + q1.shape)
    if dq.any():
        d = op.conv.convolve_matrix([[k["11"], None, None], [None, k["21"], k["23"]],
                                     [k["31"], None, None]], [dq, q1, j.p])
        u[0] = j.Ax[1] + d[0]
        u[1] = d[1]
        u[2] = j.Ax[0] + d[2]
    else:
        u[0], u[2] = j.Ax[1], j.Ax[0]
        u[1] = op.conv.convolve_matrix([[k["21"], k["23"]]], [q1, j.p])[0]
    return q1, u, scalar_multiplier(u[0] + b1, q1, bound)
