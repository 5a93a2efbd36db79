"""The uncoupled normal contact problem (UNC): pressure and contact area under force control.

With every tangential traction and the viscoelastic history known (added to the gap), find
the pressure p >= 0 and the approach omega3 such that the gap closes where p > 0, stays open
elsewhere and the pressure carries W (paper eqs. 1, 3, 5). The solver is Polonsky & Keer's
conjugate-gradient method (:func:`contactpipe.solver.cg.box_cg` with lo = 0, hi = inf).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cg import box_cg

__all__ = ["NormalResult", "solve_normal"]


@dataclass
class NormalResult:
    p: np.ndarray          # pressure [Pa]
    omega3: float          # normal approach [m]
    Ap: np.ndarray         # K33 ⊛ p [m]
    iterations: int
    residual: float
    converged: bool


def solve_normal(op, gap0, W, cell_area, p0, tol, max_iter, Ap0=None) -> NormalResult:
    """Frictionless normal problem under force control (Polonsky & Keer 1999).

    Parameters
    ----------
    op : ContactOperator
    gap0 : ndarray
        Initial gap plus every known normal displacement [m].
    W : float
        Normal force [N].
    p0 : ndarray
        Warm start [Pa].
    Ap0 : ndarray, optional
        K33 ⊛ p0 when known (saves one FFT pair).
    """
    if W <= 0.0:
        return NormalResult(np.zeros_like(gap0), float(gap0.min()), np.zeros_like(gap0), 0,
                            0.0, True)
    if op.rigid:
        # no compliance for this increment (e.g. Kelvin-Voigt at the instant of a step load):
        # the load goes to the cells of least gap, the discrete form of a concentrated force
        lowest = gap0 <= gap0.min() + 1e-12 * max(np.ptp(gap0), 1e-300)
        p = np.where(lowest, W / (cell_area * np.count_nonzero(lowest)), 0.0)
        return NormalResult(p, float(gap0.min()), np.zeros_like(gap0), 0, 0.0, True)
    res = box_cg(op.normal, gap0, np.zeros_like(gap0), np.full_like(gap0, np.inf),
                 W / cell_area, p0, tol=tol, max_iter=max_iter, restore="scale", Ax0=Ap0)
    return NormalResult(res.x, res.multiplier, res.Ax, res.iterations, res.residual,
                        res.converged)
