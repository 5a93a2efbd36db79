"""One conjugate-gradient solve over (p, q1) for a coupled instant (the scalar form), or
over (p, q1, q2) (the vector form, :func:`solve_joint_vector`).

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
the two force rows as :class:`~contactpipe.solver.cg.BlockSums` and each block filtered by
the inverse of its own model symbol as preconditioner (K̂33 and the anisotropic K̂11:
:meth:`~contactpipe.solver.operator.ContactOperator.joint_preconditioner`): one operator
application is two FFT pairs (two forward transforms, four kernel products, two inverse),
the preconditioner half of one (two fields filtered on the unpadded grid). The operator
is applied in halves (:class:`~contactpipe.solver.blocks.BlockOperator`): a projection's
correction, and where a pass converges the next pass's start (its slip cells on their
moved bound, box_cg's ``follow``), ride on the step's inverse transforms, at the cost of
their forward transforms.

Only the bound g = μp is then lagged. A pass moves the slip cells' shear by μ δp and the
pressure answers through K31 only, so a pass cuts the pressure change by about μβ
(measured about 1/100 with exact inner solves, steel on aluminium); block Gauss-Seidel
cuts it by β²-like factors of 1/20-1/50. Inner tolerances follow the same inexact
schedule as the block Gauss-Seidel passes; the passes stop when one at the full tolerance
moves p by less than the tolerance, or by so little that the next would at the contraction
just measured. A projection that moves the iterate by less than a tenth of the pass's
inner tolerance leaves its product out of A x until a larger one, or the next pass's start,
takes it in (``Tuning.defer``; the last pass's are taken in before its A x is returned).
:func:`finish` then puts the shear on the final pressure's bound, so that
Coulomb's law holds exactly, and builds the displacement from the products the solve
kept (docs/design-choices.md, "The coupled instant").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .blocks import BlockOperator
from .cg import BlockSums, BoxOptions, Start, box_cg, disk_project, feasible_start
from .disk_cg import DiskOptions, PressureBlock, disk_cg, disk_start, restore_rows
from .ledger import Ledger, Move
from .options import TUNING
from .projection import on_bound
from .tangential import follow_bound, force_rows, multipliers, scalar_multiplier, sliding

__all__ = ["JointResult", "finish", "finish_vector", "solve_joint", "solve_joint_vector"]

@dataclass
class JointResult:
    p: np.ndarray           # (N1, N2) pressure [Pa]
    q: np.ndarray           # shear [Pa] within ``bound``: (N1, N2) q1 of the scalar
                            # form, (2, N1, N2) q of the vector form
    bound: np.ndarray       # (N1, N2) μ p of its own pressure where converged (the
                            # shear's slip cells on it), else the last pass's bound [Pa]
    omega3: float           # normal approach [m] (the p row's multiplier)
    Ax: np.ndarray          # (u3, u1) = (K33 p + K31 q1, K13 p + K11 q1) [m], or
                            # (u3, u1, u2) from (p, q) for the vector form
    iterations: int
    passes: int
    converged: bool
    residual: float         # the failing solve's residual, or the last pressure change


class _Schedule:
    """The joint passes' inexact schedule and their end, for both forms.

    ``inner`` is the next pass's inner tolerance: the first pass's
    (``tuning.joint_first_pass_tolerance``: the first pass answers the new load and the
    moved bound at once, and its pressure change, about 1e-3, sets the next pass's
    tolerance anyway; 1e-4 cost 4-11 % more FFT pairs, docs/design-choices.md) at first,
    then ``tuning.joint_pass_fraction`` of the last pressure change, never looser than the
    pass before nor tighter than the full one, and the full one once within
    ``tuning.joint_full_within`` of it, so that the pass may be the last. ``change`` is
    the last pass's Σ|Δp| Δ / W [1]."""

    def __init__(self, tol, tuning=TUNING):
        self.tuning = tuning
        self.tol, self.inner = tol, max(tol, tuning.joint_first_pass_tolerance)
        self.change = np.inf

    def last_allowed(self, passes, max_passes):
        """The last pass allowed runs at the full tolerance: only such a pass can settle
        (a limit of one pass or two would otherwise never let the step settle)."""
        if passes >= max_passes:
            self.inner = self.tol

    def settled(self, p_new, p, W, cell_area) -> bool:
        """Record a converged pass that moved p to ``p_new`` [Pa]; True when the passes
        end: a pass at the full tolerance moved p by less than it, or by so little that
        the next one, at the contraction just measured, would (the lag of the bound is
        then below the tolerance)."""
        tol, last, old = self.tol, self.inner == self.tol, self.change
        self.change = change = float(np.abs(p_new - p).sum()) * cell_area / max(W, 1e-300)
        inner = min(self.inner, max(tol, self.tuning.joint_pass_fraction * change))
        self.inner = tol if inner < self.tuning.joint_full_within * tol else inner
        return last and (change < tol or (0.0 < old < np.inf
                                          and change * min(1.0, change / old) < tol))


def solve_joint(op, b, W, T1, cell_area, mu, p0, q0, tol, max_iter,
                max_passes, tuning=TUNING) -> JointResult:
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
    tuning : Tuning
        The passes' schedule, the deferral of projection products, the halves.

    Returns
    -------
    JointResult
        ``q`` on the final bound ``bound`` = μ p (the last pass's end folded into its
        last step), ``Ax`` (u3, u1) of (p, q1); ``converged`` False when a solve stopped
        or the passes did not settle.
    """
    conv, k = op.conv, op.k
    # the shear is solved as s = q1 / μ, of the pressure's size, so that the stacked
    # convergence measure Σ|Δ(p, s)| / Σ|(p, s)| holds the shear to the tolerance of the
    # tangential solve (Σ|Δq1| / Σμp) and not only to μ times it; with the preconditioner
    # scaled alike the iterates are those of the unscaled problem
    blocks = [[k["33"], mu * k["31"]], [mu * k["13"], mu * mu * k["11"]]]
    shape = (2,) + p0.shape

    apply = _operator(conv, blocks, tuning)   # a zero block (a start's update): no transform

    filter_ = op.joint_filter(1.0 / (mu * mu))
    work = np.empty(shape)          # box_cg keeps no filtered field past its iteration

    def precondition(v):
        return filter_(v, out=work)

    b = np.stack([b[0], mu * b[1]])
    rows = BlockSums([W / cell_area, T1 / cell_area / mu])
    zero, inf = np.zeros_like(p0), np.full_like(p0, np.inf)
    p, s = np.array(p0, dtype=float), np.array(q0, dtype=float) / mu
    # a pass's start: from the second pass on, box_cg's ``follow``'s, whose product Ax is
    x, Ax, its, plan = np.stack([p, s]), None, 0, _Schedule(tol, tuning)
    for passes in range(1, max_passes + 1):
        plan.last_allowed(passes, max_passes)
        lag = p                                   # the bound of s: |s| <= p (lagged)
        lo, hi = np.stack([zero, -lag]), np.stack([inf, lag])
        follow = _scalar_follow(plan, lag, W, cell_area, rows)
        res = box_cg(apply, b, lo, hi, rows, Start(x, Ax, x),
                     BoxOptions(plan.inner, max_iter, "shift", precondition=precondition),
                     Ledger(update=True, defer=tuning.defer, follow=follow, exact=True))
        assert res.Ax is not None                 # an exact ledger leaves A x whole
        its += res.iterations
        if not res.converged:
            return JointResult(p, mu * s, mu * lag, np.nan, res.Ax, its, passes, False,
                               res.residual)
        assert res.iterate is not None and res.move is not None   # converged: follow ran
        p, s, Ax, x = res.iterate[0], res.iterate[1], res.Ax, res.x
        if res.move.verdict == "settled":
            s = x[1]                               # the final state, folded in
            omega3 = float(np.asarray(res.multiplier)[0])   # rows given: an (m,) array
            Ax = np.stack([Ax[0], Ax[1] / mu])     # (K33 p + K31 q1, K13 p + K11 q1)
            return JointResult(p, mu * s, mu * p, omega3, Ax, its, passes, True,
                               plan.change)
    assert Ax is not None                         # a pass ran (max_passes >= 1)
    return JointResult(p, mu * s, mu * lag, np.nan, Ax, its, max_passes, False,
                       plan.change)


def _scalar_follow(plan, lag, W, cell_area, rows):
    """The scalar pass's ``follow`` (bound |s| <= ``lag``, W [N] over cells Δ [m²]): the
    converged (p, s) -> the next pass's start (the slip cells on their moved bound, the
    rows restored as box_cg would: "next"), or after the last pass ("settled") the
    instant's final state (the shear on its own pressure's bound, as :func:`finish` puts
    it; no point where it is there)."""
    def follow(x):
        p_new = x[0]
        s_new = follow_bound(x[1], lag, p_new)
        if plan.settled(p_new, lag, W, cell_area):
            np.clip(s_new, -p_new, p_new, out=s_new)
            return Move(None if np.array_equal(s_new, x[1]) else np.stack([p_new, s_new]),
                        "settled")
        zero, inf = np.zeros_like(p_new), np.full_like(p_new, np.inf)
        return Move(feasible_start(np.stack([p_new, s_new]), np.stack([zero, -p_new]),
                                   np.stack([inf, p_new]), rows, "shift"), "next")
    return follow


def _vector_follow(plan, lag, load, con, snap):
    """The vector pass's ``follow`` (bound |s| <= ``lag``; ``load`` = (W [N], Δ [m²])): the
    converged (p, s) -> the next pass's start, its slip cells on their moved bound
    ("next"), or the instant's final state ("settled", :func:`_final_shear`); where no
    cell sticks, no move ("sliding")."""
    def follow(xc):
        p_new, s_new = xc[0], xc[1:]
        settled = plan.settled(p_new, lag, *load)
        if sliding(s_new, lag):
            return Move(xc, "sliding")
        if settled:
            s_next = _final_shear(s_new, lag, p_new, con)
        else:
            s_next = disk_start(follow_bound(s_new, lag, p_new), p_new, con, plan.inner, snap)
        return Move(np.concatenate([p_new[None], s_next]), "settled" if settled else "next")
    return follow


def _vector_operator(op, mu):
    """The vector joint solve's operator over (p, s1, s2), s = q/μ, in halves."""
    k = op.k
    return BlockOperator(op.conv, [[k["33"], mu * k["31"], mu * k["32"]],
                                   [mu * k["13"], mu * mu * k["11"], mu * mu * k["12"]],
                                   [mu * k["23"], mu * mu * k["21"], mu * mu * k["22"]]])


def _operator(conv, blocks, tuning):
    """The joint solve's block operator: applied in halves (``tuning.halves``), else
    as whole products (a zero block skipped)."""
    if tuning.halves:
        return BlockOperator(conv, blocks)
    return lambda x, out=None: conv.convolve_matrix(blocks, [f if f.any() else None
                                                             for f in x], out=out)


def finish(op, j: JointResult, b1):
    """The scalar joint solution's shear, displacement and rigid shift: the solve already
    put the shear on the bound of its own final pressure (folded into its last step, as
    :func:`solve_joint_vector` does), so this adds u2, which the one-component CG does
    not carry, and fits the force row's multiplier.

    Parameters
    ----------
    op : ContactOperator
        The instant's operator.
    j : JointResult
        A converged :func:`solve_joint`.
    b1 : ndarray (N1, N2)
        U1 − u1(k−1) [m], the known in-plane displacement less the previous instant's.

    Returns
    -------
    q1 : ndarray (N1, N2)
        The shear [Pa], |q1| <= μ p with the slip cells on the bound.
    u : ndarray (3, N1, N2)
        The displacement [m] from the tractions (K [q1, 0, p]): the kept products
        K13 p + K11 q1 and K33 p + K31 q1, and u2 = K21 q1 + K23 p (one block product of
        two forward transforms and one inverse: 1.5 FFT pairs).
    domega1 : float
        The tangential rigid shift increment Δω1 [m], the force row's multiplier.
    """
    k = op.k
    u = np.empty((3,) + j.q.shape)
    u[0], u[2] = j.Ax[1], j.Ax[0]
    u[1] = op.conv.convolve_matrix([[k["21"], k["23"]]], [j.q, j.p])[0]
    return j.q, u, scalar_multiplier(u[0] + b1, j.q, j.bound)


def solve_joint_vector(op, b, W, T, cell_area, mu, p0, q0, tol, max_iter,
                       max_passes, tuning=TUNING) -> JointResult:
    """The coupled instant of the vector form under force control of W and T (uniform μ):
    one problem over x = (p, s1, s2), s = q/μ, with the bound |s| ≤ p_lag held per pass,

        minimise  ½ xᵀ A x + bᵀ x,   A = [[K33, μK31, μK32], [μK13, μ²K11, μ²K12],
                                          [μK23, μ²K21, μ²K22]],
        subject to  p ≥ 0,  |s| ≤ p_lag per cell,  Σp = W/Δ,  Σs = T/(μΔ),

    by the projected CG of :func:`contactpipe.solver.disk_cg.disk_cg` with its pressure
    block: one operator application is three FFT pairs, the filters three quarters of one
    (one where the tangents' component is filtered in two bands). The passes, their
    inexact schedule and their end are :func:`solve_joint`'s (:class:`_Schedule`). Where
    a pass converges its iterate moves on (the CG's ``follow``): to the next pass's start,
    the slip cells on their moved bound, or, after the last pass, to the final state, the
    shear on the bound of its own pressure (:func:`_final_shear`); the move's product
    rides on the pass's last step (the shear's two forward transforms, no inverse), so
    the instant spends three inverse transforms per iteration and three for its start.

    Parameters
    ----------
    op : ContactOperator
        Operator of the instant; not rigid.
    b : ndarray (3, N1, N2)
        hi + U3, and U1 − u1(k−1), U2 − u2(k−1) [m].
    W, T : float, array_like (2,)
        Normal force [N], > 0; tangential force [N], |T| ≤ μW.
    cell_area, mu :
        [m²], uniform friction coefficient [1].
    p0, q0 : ndarray
        Warm starts [Pa]: pressure (N1, N2), in contact somewhere; shear (2, N1, N2).
    tol, max_iter, max_passes :
        As in :class:`contactpipe.solver.coupling.Tolerances`.
    tuning : Tuning
        The passes' schedule, the deferral of projection products, the halves.

    Returns
    -------
    JointResult
        ``q`` (2, N1, N2) on the final bound ``bound`` = μ p, ``Ax`` (u3, u1, u2) [m] of
        (p, q); ``converged`` False when a pass stopped or the passes did not settle.
    """
    A = _vector_operator(op, mu)
    M = op.tangential_preconditioner()
    pressure = PressureBlock(W / cell_area, op.corner("11") / op.corner("33"))
    con = force_rows(p0.shape, np.asarray(T, dtype=float) / mu, cell_area)
    a_self = op.self_influence("11")
    b = np.stack([b[0], mu * b[1], mu * b[2]])
    p = np.maximum(np.asarray(p0, dtype=float), 0.0)
    p *= pressure.target / p.sum()
    plan = _Schedule(tol, tuning)
    x = np.concatenate([p[None], disk_start(np.asarray(q0, dtype=float) / mu, p, con,
                                            plan.inner, tuning.snap)])
    Ax, its = A(x), 0
    for passes in range(1, max_passes + 1):
        plan.last_allowed(passes, max_passes)
        lag = x[0]                                # the bound of s: |s| <= p (lagged)
        follow = _vector_follow(plan, lag, (W, cell_area), con, tuning.snap)
        res = disk_cg(A, b, Start(x, Ax), lag, con,
                      DiskOptions(plan.inner, max_iter, M, a_self, unit=mu, tuning=tuning),
                      Ledger(update=True, defer=tuning.defer, follow=follow), pressure)
        assert res.Ax is not None                 # an exact ledger leaves A x whole
        its += res.iterations
        verdict = res.move.verdict if res.move is not None else ""
        if not res.converged or verdict == "sliding":
            # sliding: no cell sticks, and the projected CG stalls on the turning circles
            # (a gross-slip instant took many passes: docs/design-choices.md, D2); the
            # passes' vector solves have the projected gradient for it
            y = res.x
            return JointResult(y[0], mu * y[1:], mu * lag, np.nan, res.Ax, its, passes,
                               False, res.residual if not res.converged else plan.change)
        x, Ax = res.x, res.Ax
        if verdict == "settled":
            p = x[0]
            omega3 = pressure.residual(Ax[0] + b[0], p)[3]
            Ax = np.stack([Ax[0], Ax[1] / mu, Ax[2] / mu])       # (u3, u1, u2)
            return JointResult(p, mu * x[1:], mu * p, omega3, Ax, its, passes, True,
                               plan.change)
    return JointResult(x[0], mu * x[1:], mu * lag, np.nan, Ax, its, max_passes, False,
                       plan.change)


def _final_shear(s, lag, p, con):
    """The shear of the last pass on the bound of its own pressure, without another
    solve: the slip cells follow the bound (:func:`follow_bound`), a cell beyond it is
    projected back onto its disk, and the rows are met again by a shift of the stick
    cells (:func:`contactpipe.solver.disk_cg.restore_rows`); in s = q/μ units.

    The last pass held the shear within the bound of the pass before, which differs from
    the final one by less than the tolerance, so this moves s by the tolerance's order."""
    s, _ = disk_project(np.where(p > 0, follow_bound(s, lag, p), 0.0), p)
    mag = np.hypot(s[0], s[1])
    return restore_rows(s, p, con, (p > 0) & ~on_bound(mag, p))


def finish_vector(j: JointResult, b12, T, cell_area):
    """The vector joint solution's shear, displacement and rigid shift: the solve already
    put the shear on the bound of its own final pressure (:func:`_final_shear`, folded
    into its last step), so this only reorders the kept products and fits the multipliers.

    Parameters
    ----------
    j : JointResult
        A converged :func:`solve_joint_vector`.
    b12 : ndarray (2, N1, N2)
        U − u(k−1) in the plane [m].
    T : array_like (2,)
        Tangential force [N].
    cell_area : float
        [m²]

    Returns
    -------
    q : ndarray (2, N1, N2)
        The shear [Pa], |q| <= μ p with the slip cells on the bound.
    u : ndarray (3, N1, N2)
        (u1, u2, u3) from the tractions [m].
    domega : ndarray (2,)
        The rigid shift increment Δω [m], the force rows' multipliers.
    """
    u = np.stack([j.Ax[1], j.Ax[2], j.Ax[0]])
    con = force_rows(j.bound.shape, T, cell_area)
    return j.q, u, multipliers(con, u[:2] + b12, j.q, j.bound)
