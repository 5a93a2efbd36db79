"""Every switch and constant of the solver core in one frozen object, passed down
explicitly: the coupled instant (:func:`contactpipe.solver.coupling.solve_instant`) takes
it with its limits (:class:`contactpipe.solver.coupling.Tolerances`), hands it to the
joint solves and the tangential solves, and they to the CGs. Tests and ``contactpipe
bench`` turn features off by passing a changed copy (``dataclasses.replace(TUNING,
joint=False)``), never by patching a module.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

__all__ = ["TUNING", "Tuning", "tuning_from"]


@dataclass(frozen=True)
class Tuning:
    """The solver core's switches and constants (all dimensionless).

    Attributes
    ----------
    joint : bool
        A coupled instant under force control is solved as one problem over (p, q)
        (:mod:`contactpipe.solver.joint`); False: block Gauss-Seidel passes alone.
    halves : bool
        The joint solves apply their block operator in halves
        (:class:`~contactpipe.solver.blocks.BlockOperator`: a projection's correction
        costs its forward transforms only); False: whole products.
    defer : float
        A CG leaves the products of projections out of A x while their changes, summed,
        stay within ``defer`` x its tolerance (:class:`~contactpipe.solver.ledger.Deferred`);
        0: every product exact.
    follow_bound : bool
        A Gauss-Seidel pass starts its shear with the slip cells on their moved bound
        (:func:`~contactpipe.solver.tangential.follow_bound`); False: as the last pass
        left it.
    lagged_passes : bool
        A vector Gauss-Seidel pass that is not the instant's last may leave its last
        circle corrections out of its product (which the next pass does not use); False:
        every pass's product exact.
    self_similar_starts : bool
        A preload sub-step starts from the last one's fields stretched to its load
        (:func:`~contactpipe.solver.warm_start.self_similar_start`); False: as they were.
    continued_starts : bool
        An instant on a straight load path starts from the last one's shear (and the joint
        solve's pressure) moved on along their increments
        (:func:`~contactpipe.solver.warm_start.continued_start`); False: as they were.
    precondition : bool
        The tangential CGs filter their direction by the operator's model symbol; False:
        plain (scalar) or diagonally scaled (vector) CG.
    curvature_shift : float
        The vector CG's filter is shifted by this fraction of the turning cells' median
        circle curvature (docs/design-choices.md, D16).
    shift_along_tangents : bool
        The shift acts along the turning cells' tangents only
        (:func:`~contactpipe.solver.disk_cg.slip_axes`); False: on both components alike.
    curved_line_search : bool
        The vector CG's line search takes the circles' curvature in
        (:func:`~contactpipe.solver.disk_cg.curved`); False: along the tangents alone.
    band_gate : float
        An axis whose shift exceeds this fraction of the self-influence is filtered in two
        bands (:func:`~contactpipe.solver.disk_cg.direction`).
    low_band : float
        The low band's cells are scaled as at this multiple of the shift.
    snap : float
        A warm start's cell within ``snap`` x tol (relative) of its disk's edge starts on
        it (:func:`~contactpipe.solver.disk_cg.disk_start`).
    spin : float
        The largest angle [rad] a turning cell may turn in one vector CG step.
    stall : int
        Iterations without halving the best step before the vector CG stops.
    joint_first_pass_tolerance : float
        Loosest inner tolerance of a joint solve's first pass (never below the caller's).
    joint_pass_fraction : float
        A later joint pass's inner tolerance, as a fraction of the last pressure change.
    joint_full_within : float
        A joint pass whose inner tolerance would be within this factor of the full one
        runs at the full one.
    passes_first_tolerance : float
        Loosest inner tolerance of the first block Gauss-Seidel passes.
    passes_tolerance_fraction : float
        A later Gauss-Seidel pass's inner tolerance, as a fraction of the last pressure
        change.
    cold_start_tolerance : float
        Tolerance of the normal solve that starts a joint solve from nothing in contact.
    """

    joint: bool = True
    halves: bool = True
    defer: float = 0.1
    follow_bound: bool = True
    lagged_passes: bool = True
    self_similar_starts: bool = True
    continued_starts: bool = True
    precondition: bool = True
    curvature_shift: float = 0.3
    shift_along_tangents: bool = True
    curved_line_search: bool = True
    band_gate: float = 0.5
    low_band: float = 8.0
    snap: float = 0.1
    spin: float = 0.5
    stall: int = 50
    joint_first_pass_tolerance: float = 1e-3
    joint_pass_fraction: float = 1e-2
    joint_full_within: float = 10.0
    passes_first_tolerance: float = 1e-4
    passes_tolerance_fraction: float = 1e-3
    cold_start_tolerance: float = 1e-3


#: The defaults.
TUNING = Tuning()


def tuning_from(items) -> Tuning:
    """A :class:`Tuning` from ``NAME=VALUE`` strings (``contactpipe bench --tuning``):
    booleans as true/false (or 1/0), numbers as Python floats or integers. Raises
    ValueError naming the field and what is allowed."""
    fields = {f.name: f for f in dataclasses.fields(Tuning)}
    changes: dict[str, Any] = {}            # field name: its new value (bool, int, float)
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip().replace("-", "_")
        if not sep or name not in fields:
            raise ValueError(f"tuning {item!r}: expected NAME=VALUE with NAME one of "
                             f"{', '.join(fields)}")
        kind = type(getattr(TUNING, name))
        if kind is bool:
            low = text.strip().lower()
            if low not in ("true", "false", "1", "0"):
                raise ValueError(f"tuning {name}={text!r}: expected true or false")
            changes[name] = low in ("true", "1")
            continue
        try:
            changes[name] = kind(float(text)) if kind is int else float(text)
        except ValueError:
            raise ValueError(f"tuning {name}={text!r}: expected a number") from None
    return dataclasses.replace(TUNING, **changes)
