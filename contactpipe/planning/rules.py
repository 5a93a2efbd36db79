"""Which sub-models a scene needs: model only what the scene requires.

One table (:data:`RULES`) states, for each slot, what in the scene requires or forbids a
model; :func:`plan` infers the plan from it and checks user overrides against it. "Nothing
to do" is a named model (``"none"``), so a plan always lists every slot, and the archive
records it (attribute ``models``).

=============  ======================================  ===========================================
slot           model(s)                                 needed when
=============  ======================================  ===========================================
normal         ``polonsky_keer``                        always
tangential     ``scalar`` (Cattaneo-Mindlin, q2 = 0)    μ > 0 and (a tangential load or
                                                        displacement, a twist, or coupling)
               ``vector`` (disk |q| ≤ μp)               the same, and the scene makes q2 ≠ 0
                                                        (:func:`q2_reasons`), or asked for
coupling       ``gauss_seidel`` (normal ↔ tangential)   tangential model and the pair couples
                                                        (Dundurs β ≠ 0 at some instant)
memory         ``recursive`` / ``direct``               a viscoelastic body and > 1 instant
=============  ======================================  ===========================================

``gauss_seidel`` names the coupling sub-model: the normal and tangential problems solved
together at each instant until both hold. Under force control of W and T alone and a
uniform μ, an instant is solved as one problem over (p, q1) (one-component form) or
(p, q1, q2) (vector form) with only the bound μp lagged between passes
(:mod:`contactpipe.solver.joint`); otherwise, and in the vector form where the contact
slides as a whole, by block Gauss-Seidel passes. Both reach the same answer within the
tolerance.

With ``solver.tangential = "auto"`` the one-component form (q2 = 0) runs only where the
scene makes no x2 shear of its own (:func:`q2_reasons` lists what does; any one of them
picks the vector form):

* an x2 load: T2 or ω2 ≠ 0 at some knot; a twist (M3 or φ3 given); a tilt about x1
  (M1 or φ1 ≠ 0 at some knot);
* a scene without the mirror symmetry x2 → −x2: a friction map or a gap surface that
  differs from its mirror image on the grid;
* a coupled pair (β ≠ 0) whose pressure changes while friction holds: a frictional
  preload, a normal load, approach, tilt moment or tilt that varies between knots, a
  viscoelastic body (its pressure and its coupling creep under a constant load). The
  in-plane displacement the pressure change makes is radial (K13, K23), and the stick
  zone resists it with a radial shear, whose x2 part is as large as its x1 part
  (Spence's problem: a rigid sphere pressed on a ν = 0 half-space with μ = 0.2986 reaches
  a peak pressure 12.7 % lower in the one-component form, with 2.3 times the stick
  cells, 45² cells, 35 stages; ``tests/test_spence.py``). A viscoelastic pair does so
  even after a frictionless preload, its contact growing under the held load: on the
  paper's fig. 3 case (rigid sphere on Maxwell, ν = 0.3, fretting along x1, 48², 40
  steps, windows t' and 2 t') the vector form's q2 reaches 48 % of μp0, and the
  one-component form is off by 22 % of μp0 in q1, 2.7-4.1 % of p0 in p, 2.3-3.4 % in
  ω1, with 11-36 % more stick cells.

What is left for the one-component form: T along x1 on a scene mirror-symmetric about
x2 = 0, with β = 0, or with β ≠ 0 and the pressure set without friction (a
``"frictionless"`` preload) and held (elastic bodies, constant W or ω3). By the mirror
symmetry p and q1 are even in x2 and q2 odd, so q2 adds nothing to T2 or M3; it comes
only from the in-plane Poisson term K21 ⊛ q1 (zero where both bodies have ν = 0, or
are rigid) and, on a coupled pair, from the pressure that q1 itself moves (K23 ⊛ Δp,
second order in β). Dropping those is the Cattaneo-Mindlin approximation the closed
forms make: on the paper's fretting loop (48², 20 steps) the dropped q2 reaches 10-11 %
of μp0 locally, and it moves q1 by at most 1.2 % of μp0, p by 0.2 % of p0 and ω1 by
0.14 % (steel on steel; steel on aluminium and rigid on steel after a frictionless
preload). The one-component form is cheaper (the vector form spends 1.7-2.4 times its
FFT pairs, ``contactpipe bench fretting``); ``"vector"`` asks for the full form anywhere.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from functools import cached_property

import numpy as np

from ..exceptions import SceneError
from ..materials import ExponentialCreep

__all__ = ["Plan", "plan", "pair_couples", "q2_reasons", "RULES", "Rule", "models"]

@dataclass(frozen=True)
class Plan:
    """The sub-models a simulation runs (every slot named, "none" when not needed)."""

    normal: str = "polonsky_keer"
    tangential: str = "none"
    coupling: str = "none"
    memory: str = "none"
    time_rule: str = "auto"
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

    The coupling kernels of the pair are κ2 φ2(t) − κ1 φ1(t) with κ = (1 − 2ν)/G (eq. 8;
    φ the coupling compliance's creep function, ``Body.coupling_creep``): they vanish
    identically when both κ are zero (incompressible or rigid bodies) or when the bodies
    are identical (same κ and the same creep function).
    """
    k1, k2 = body1.coupling_compliance, body2.coupling_compliance
    if k1 == 0.0 and k2 == 0.0:
        return False
    if body1.rigid or body2.rigid:
        return True
    return not (np.isclose(k1, k2, rtol=1e-12, atol=0.0)
                and body1.coupling_creep == body2.coupling_creep)


def _row(prog, i):
    """The program that drives freedom ``i``: its force, or its motion (NaN-free)."""
    return prog.force[i] if prog.is_force(i) else prog.motion[i]


def _varies(x) -> bool:
    x = np.asarray(x, dtype=float)
    return x.size > 1 and bool(np.any(x != x[0]))


def _mirror_asymmetric(values) -> bool:
    """A field on the grid (N1, N2) differs from its mirror image x2 -> -x2 (the grid's
    cell centres are symmetric about x2 = 0, so the mirror is the flip of axis 1)."""
    v = np.asarray(values, dtype=float)
    if v.ndim != 2:
        return False
    scale = float(np.max(np.abs(v))) if v.size else 0.0
    return not np.allclose(v, v[:, ::-1], rtol=1e-9, atol=1e-12 * scale)


def _grid_fields_asymmetric(scene) -> list:
    """The friction map and the gap surface that break the mirror symmetry x2 -> -x2;
    a file that cannot be read on the grid here counts as breaking it."""
    out = []
    mapped, surface = scene.friction.mapped, scene.geometry.shape in ("surface", "rough")
    if not (mapped or surface):
        return out
    try:
        x1, x2 = scene.resolved_grid().coordinates()
    except (SceneError, TypeError, ValueError):
        return [f"{key}: its symmetry about x2 = 0 cannot be checked without the grid"
                for key, flag in (("friction.mu (a map)", mapped),
                                  ("geometry (a surface)", surface)) if flag]
    for flag, key, on_grid in ((mapped, "friction.mu (a map)", scene.friction.on_grid),
                               (surface, "geometry (a surface)", scene.geometry.gap)):
        if not flag:
            continue
        try:
            asym = _mirror_asymmetric(on_grid(x1, x2))
        except (SceneError, OSError, ValueError):
            asym = True
        if asym:
            out.append(f"{key} is not symmetric about x2 = 0")
    return out


def q2_reasons(scene) -> list:
    """Why the scene makes an x2 shear (q2 ≠ 0) beyond the Cattaneo-Mindlin
    approximation: one line per cause, empty when none (then ``"auto"`` runs the
    one-component form). See the module's docstring for the argument.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    list of str
    """
    load = scene.load
    prog = load.programs()
    why = []
    tang = _row(prog, 1), _row(prog, 2)
    if np.any(tang[1] != 0):
        why.append("T2 or omega2 != 0 (a load along x2)")
    if load.moment3 is not None or load.rotation3 is not None:
        why.append("a twist (load.moment3 or load.rotation3)")
    if np.any(_row(prog, 3) != 0):
        why.append("a tilt about x1 (load.moment1 or load.rotation1 != 0)")
    why += _grid_fields_asymmetric(scene)
    b1, b2 = scene.indenter.body(), scene.halfspace.body()
    if not pair_couples(b1, b2):
        return why
    # the pair couples: a pressure that changes while friction holds shears radially
    normal = _row(prog, 0)
    if load.preload == "frictional" and normal.size and normal[0] > 0:
        why.append("a frictional preload on a coupled pair (Spence's radial shear)")
    if any(_varies(_row(prog, i)) for i in (0, 3, 4)):
        why.append("the normal load, approach or a tilt varies on a coupled pair")
    steps = scene.time.steps if scene.time.steps is not None else prog.t.size - 1
    if steps >= 1 and (b1.has_memory or b2.has_memory):
        why.append("a viscoelastic body on a coupled pair (the pressure creeps)")
    return why


# --------------------------------------------------------------------------- the rules

class _Facts:
    """What the rules ask of a scene, each computed once and only when a rule asks
    (:func:`q2_reasons` reads the grid fields); ``chosen`` holds the slots decided so far
    (the coupling rules read the tangential model)."""

    def __init__(self, scene):
        self.scene = scene
        self.bodies = scene.indenter.body(), scene.halfspace.body()
        self.mu = scene.friction.largest
        self.load = scene.load
        self.prog = scene.load.programs()
        # the tangential row, force or displacement, and the twist: what moves the shear
        tang = self.prog.force[1:3] if self.prog.is_force(1) else self.prog.motion[1:3]
        self.twist = self.load.moment3 is not None or self.load.rotation3 is not None
        self.has_T = bool(np.any(tang != 0)) or self.twist
        self.has_T2 = bool(np.any(tang[1] != 0)) or self.twist
        self.chosen = {}

    @cached_property
    def couples(self) -> bool:
        try:
            return pair_couples(*self.bodies)
        except (ZeroDivisionError, OverflowError):   # a modulus that rounds to 0 or inf
            scene = self.scene
            moduli = ", ".join(f"{side}.young = {getattr(scene, side).young!r}"
                               for side in ("indenter", "halfspace")
                               if getattr(getattr(scene, side), "young", None) is not None)
            raise SceneError(f"{moduli}: a shear modulus rounds to 0 Pa or overflows; give "
                             "moduli of a material (1e3 to 1e13 Pa)") from None

    @cached_property
    def shear(self) -> bool:
        """Friction acts and something shears the contact: a load, a twist or coupling."""
        return self.mu > 0 and (self.has_T or self.couples)

    @cached_property
    def q2(self) -> bool:
        return bool(q2_reasons(self.scene))

    @cached_property
    def memories(self) -> list:
        """The creep functions of the bodies with a memory, when the run has > 1 instant."""
        scene = self.scene
        steps = scene.time.steps if scene.time.steps is not None else len(self.prog.t) - 1
        return [b.creep for b in self.bodies if b.has_memory] if steps >= 1 else []

    @property
    def sheared(self) -> bool:
        """The tangential model chosen is not "none"."""
        return self.chosen.get("tangential", "none") != "none"

    @property
    def twist_key(self) -> str:
        return "load.moment3" if self.load.moment3 is not None else "load.rotation3"

    @property
    def x2_key(self) -> str:
        return "load.tangential_force" if self.prog.is_force(1) else \
            "load.tangential_displacement"


#: A condition of a rule: a predicate of the scene's facts and the one-line refusal (a
#: function of the facts) given when a user asks for the model against it.
Condition = tuple[Callable[[_Facts], bool], Callable[[_Facts], str]]


@dataclass(frozen=True)
class Rule:
    """One model of one slot (in the manner of pvlib's ModelChain inference).

    ``applies``: when :func:`plan` infers this model (the first rule of its slot that
    applies wins); ``requires``: what the scene must have for the model to be asked for;
    ``excludes``: what in the scene rules it out. An override that breaks a requirement
    or meets an exclusion is refused with that condition's message.
    """

    model: str
    applies: Callable[[_Facts], bool]
    requires: tuple[Condition, ...] = ()
    excludes: tuple[Condition, ...] = ()


def _no_shear(f) -> str:
    return (f"tangential={f.chosen['asked']!r}: this scene has no shear to solve "
            f"(mu = {f.mu}, no tangential load, no normal-tangential coupling)")


def _shear_left(f) -> str:
    return ("tangential='none': the scene carries shear (friction.mu > 0 with a "
            "tangential load or a coupled pair); allowed: 'scalar', 'vector', 'auto'")


def _twisted(f) -> str:
    return (f"tangential='scalar': {f.twist_key} twists the contact; the one-component "
            "form cannot carry a torque. Use 'vector' or 'auto'")


def _along_x2(f) -> str:
    return (f"tangential='scalar': {f.x2_key} has a component along x2; "
            "the one-component form cannot carry it. Use 'vector' or 'auto'")


def _coupled(f) -> str:
    return ("coupling='none': the pair couples (Dundurs beta != 0) and the scene "
            "carries shear; dropping the coupling would drop physics")


def _uncoupled(f) -> str:
    return ("coupling='gauss_seidel': nothing to couple in this scene "
            "(no shear, or Dundurs beta = 0)")


def _shear(f) -> bool:
    return f.shear


def _no_shear_at_all(f) -> bool:
    return not f.shear


def _sheared_pair(f) -> bool:
    return f.sheared and f.couples


def _exponential(f) -> bool:
    return all(isinstance(c, ExponentialCreep) for c in f.memories)


def _always(f) -> bool:
    return True


#: The sub-models of each slot, in the order :func:`plan` tries them.
RULES = {
    "normal": (Rule("polonsky_keer", applies=_always),),
    "tangential": (
        Rule("none", applies=_no_shear_at_all, requires=((_no_shear_at_all, _shear_left),)),
        Rule("scalar", applies=lambda f: not f.q2, requires=((_shear, _no_shear),),
             excludes=(((lambda f: f.twist), _twisted), ((lambda f: f.has_T2), _along_x2))),
        Rule("vector", applies=_always, requires=((_shear, _no_shear),)),
    ),
    "coupling": (
        Rule("none", applies=lambda f: not _sheared_pair(f),
             excludes=((_sheared_pair, _coupled),)),
        Rule("gauss_seidel", applies=_always, requires=((_sheared_pair, _uncoupled),)),
    ),
    "memory": (
        Rule("none", applies=lambda f: not f.memories),
        Rule("recursive", applies=_exponential),
        Rule("direct", applies=_always),
    ),
}


def models(slot) -> tuple:
    """The model names of a slot, in the order of :data:`RULES`."""
    return tuple(r.model for r in RULES[slot])


def _choose(slot, facts, asked=None) -> str:
    """The model of ``slot``: the first rule that applies, or the one ``asked`` for once
    its requirements and exclusions are checked (a :class:`SceneError` otherwise)."""
    if asked is None:
        model = next(r.model for r in RULES[slot] if r.applies(facts))
    else:
        facts.chosen["asked"] = asked
        rule = next(r for r in RULES[slot] if r.model == asked)
        for holds, message in rule.requires:
            if not holds(facts):
                raise SceneError(message(facts))
        for holds, message in rule.excludes:
            if holds(facts):
                raise SceneError(message(facts))
        model = asked
    facts.chosen[slot] = model
    return model


def plan(scene, tangential=None, coupling=None) -> Plan:
    """Infer the plan of a scene from :data:`RULES`; optional overrides are checked
    against the scene (an override the rules refuse raises :class:`SceneError`).

    Parameters
    ----------
    scene : Scene
    tangential : {"scalar", "vector", "none"}, optional
        Override of the tangential form (``scene.solver.tangential`` otherwise).
    coupling : {"gauss_seidel", "none"}, optional
        Override of the coupling loop. Dropping it on a coupled pair is refused.
    """
    facts = _Facts(scene)
    _ = facts.couples                         # a modulus that overflows: refused first
    choice = tangential or scene.solver.tangential
    if choice not in models("tangential") + ("auto",):
        raise SceneError(f"tangential={choice!r}: allowed 'auto', 'scalar', 'vector', 'none'")
    if choice == "auto" or (choice == "none" and not facts.shear):
        choice = None
    tang = _choose("tangential", facts, choice)
    if coupling is not None and coupling not in models("coupling"):
        raise SceneError(f"coupling={coupling!r}: allowed {models('coupling')}")
    coup = _choose("coupling", facts, coupling)
    mem = _choose("memory", facts)
    return Plan(normal=_choose("normal", facts), tangential=tang, coupling=coup,
                memory=mem, time_rule=scene.solver.time_rule, preload=scene.load.preload)
