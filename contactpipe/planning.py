"""Which sub-models a scene needs: model only what the scene requires.

One table (:data:`RULES`) states, for each slot, what in the scene requires or forbids a
model; :func:`plan` infers the plan from it and checks user overrides against it. "Nothing
to do" is a named model (``"none"``), so a plan always lists every slot, and the archive
records it (attribute ``models``).

=============  ======================================  ===========================================
slot           model(s)                                 needed when
=============  ======================================  ===========================================
normal         ``polonsky_keer``                        always
tangential     ``scalar`` (Cattaneo-Mindlin, q2 = 0)    μ > 0 and (a tangential load, or coupling)
               ``vector`` (disk |q| ≤ μp)               the same, and T2 ≠ 0 (or asked for)
coupling       ``gauss_seidel`` (normal ↔ tangential)   tangential model and the pair couples
                                                        (Dundurs β ≠ 0 at some instant)
memory         ``recursive`` / ``direct``               a viscoelastic body and > 1 instant
=============  ======================================  ===========================================

With ``solver.tangential = "auto"`` the one-component form runs whenever the tangential
load is along x1: it is several times cheaper and exact for the Cattaneo-Mindlin and
Mindlin-Deresiewicz cases. On a coupled pair (β ≠ 0) it neglects the x2 component of the
shear that the coupling induces (Spence's radial shear during indentation); ask for
``"vector"`` to keep it.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .exceptions import SceneError
from .materials import ExponentialCreep

__all__ = ["Plan", "plan", "pair_couples", "RULES"]

RULES = {
    "normal": ("polonsky_keer",),
    "tangential": ("none", "scalar", "vector"),
    "coupling": ("none", "gauss_seidel"),
    "memory": ("none", "recursive", "direct"),
}


@dataclass(frozen=True)
class Plan:
    """The sub-models a simulation runs (every slot named, "none" when not needed)."""

    normal: str = "polonsky_keer"
    tangential: str = "none"
    coupling: str = "none"
    memory: str = "none"
    time_rule: str = "linear"
    preload: str = "frictional"

    def describe(self) -> str:
        """One line for the archive's ``models`` attribute."""
        parts = [f"normal={self.normal}", f"tangential={self.tangential}",
                 f"coupling={self.coupling}", f"memory={self.memory}"]
        if self.memory != "none":
            parts.append(f"time_rule={self.time_rule}")
        if self.tangential != "none":
            parts.append(f"preload={self.preload}")
        return ", ".join(parts)

    def as_dict(self) -> dict:
        return asdict(self)


def pair_couples(body1, body2) -> bool:
    """True when the normal and tangential problems couple at some instant.

    The coupling kernels of the pair are κ2 φ2(t) − κ1 φ1(t) with κ = (1 − 2ν)/G (eq. 8):
    they vanish identically when both κ are zero (incompressible or rigid bodies) or when
    the bodies are identical (same κ and the same creep function).
    """
    k1, k2 = body1.coupling_compliance, body2.coupling_compliance
    if k1 == 0.0 and k2 == 0.0:
        return False
    if body1.rigid or body2.rigid:
        return True
    return not (np.isclose(k1, k2, rtol=1e-12, atol=0.0) and body1.creep == body2.creep)


def plan(scene, tangential=None, coupling=None) -> Plan:
    """Infer the plan of a scene; optional overrides are checked against the scene.

    Parameters
    ----------
    scene : Scene
    tangential : {"scalar", "vector", "none"}, optional
        Override of the tangential form (``scene.solver.tangential`` otherwise).
    coupling : {"gauss_seidel", "none"}, optional
        Override of the coupling loop. Dropping it on a coupled pair is refused.
    """
    b1, b2 = scene.indenter.body(), scene.halfspace.body()
    mu = scene.friction.mu
    t, _, T1, T2 = scene.load.knots()
    has_T = bool(np.any(np.asarray(T1) != 0) or np.any(np.asarray(T2) != 0))
    has_T2 = bool(np.any(np.asarray(T2) != 0))
    couples = pair_couples(b1, b2)
    needs_tangential = mu > 0 and (has_T or couples)

    choice = tangential or scene.solver.tangential
    if not needs_tangential:
        if choice not in ("auto", "none"):
            raise SceneError(f"tangential={choice!r}: this scene has no shear to solve "
                             f"(mu = {mu}, no tangential load, no normal-tangential coupling)")
        tang = "none"
    elif choice == "auto":
        tang = "vector" if has_T2 else "scalar"
    elif choice == "none":
        raise SceneError("tangential='none': the scene carries shear (friction.mu > 0 with a "
                         "tangential load or a coupled pair); allowed: 'scalar', 'vector', 'auto'")
    elif choice == "scalar" and has_T2:
        raise SceneError("tangential='scalar': load.tangential_force has a component along x2; "
                         "the one-component form cannot carry it. Use 'vector' or 'auto'")
    elif choice in ("scalar", "vector"):
        tang = choice
    else:
        raise SceneError(f"tangential={choice!r}: allowed 'auto', 'scalar', 'vector', 'none'")

    coup = "gauss_seidel" if (tang != "none" and couples) else "none"
    if coupling is not None:
        if coupling == "none" and coup != "none":
            raise SceneError("coupling='none': the pair couples (Dundurs beta != 0) and the "
                             "scene carries shear; dropping the coupling would drop physics")
        if coupling not in RULES["coupling"]:
            raise SceneError(f"coupling={coupling!r}: allowed {RULES['coupling']}")
        if coupling == "gauss_seidel" and coup == "none":
            raise SceneError("coupling='gauss_seidel': nothing to couple in this scene "
                             "(no shear, or Dundurs beta = 0)")

    steps = scene.time.steps if scene.time.steps is not None else len(t) - 1
    mem = "none"
    if steps >= 1 and (b1.has_memory or b2.has_memory):
        creeps = [b.creep for b in (b1, b2) if b.has_memory]
        mem = "recursive" if all(isinstance(c, ExponentialCreep) for c in creeps) else "direct"
    return Plan(tangential=tang, coupling=coup, memory=mem,
                time_rule=scene.solver.time_rule, preload=scene.load.preload)
