"""What does not change during a run, set up once before the march (:mod:`.march`).

Three parts, each built from the scene and the plan:

* :class:`Grid`: the surface grid, the gap and the friction coefficient on it;
* :class:`Operators`: the bodies' influence spectra, the contact operators of the
  instants (one per tuple of creep weights) and the bodies' fresh memories;
* the frictional preload's estimate (:mod:`.preload`: how many sub-steps, what error).

:class:`Problem` holds them with the load program and the solver's limits, and checks
that float64 can hold the scene's scales before anything runs.
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from ..exceptions import SceneError
from ..materials import FIT_TOLERANCE, dundurs_beta
from ..planning.accuracy import knot_multiple, preload_fractions
from ..solver.coupling import Controls, Tolerances
from ..solver.memory import BodyMemory, make_memory, resolve_body_rule
from ..solver.operator import (
    ContactOperator,
    body_spectra_parts,
    convolver,
    history_displacement,
    history_kernels,
)
from .wear import WearTracker

__all__ = ["Grid", "Operators", "Problem", "grid_coordinates"]

#: Knots listed by the off-mesh warning; the others are counted.
KNOTS_LISTED = 5
#: Pressures [Pa] and displacements [m] a run may reach: their squares, summed over a
#: grid, stay within float64 (about 1e-308 .. 1e308).
SCALE_RANGE = (1e-150, 1e150)


def grid_coordinates(scene):
    """Cell-centre coordinates x1, x2 [m] and spacings d1, d2 [m] of the scene's grid."""
    n1, n2 = scene.grid.points
    size = scene.grid.size
    if isinstance(size, str):
        size = scene.resolved_grid_size()
    L1, L2 = float(size[0]), float(size[1])
    d1, d2 = L1 / n1, L2 / n2
    x1 = -L1 / 2 + (np.arange(n1) + 0.5) * d1
    x2 = -L2 / 2 + (np.arange(n2) + 0.5) * d2
    return x1, x2, d1, d2


def _n_steps(scene):
    if scene.time.steps is not None:
        return int(scene.time.steps)
    return len(scene.load.knots()[0]) - 1


class Grid:
    """The N1 x N2 surface grid: cell centres x1, x2 [m] (and their mesh X1, X2),
    spacings d1, d2 [m], the cell's area [m²], the gap [m] and mu (a float or a map)."""

    def __init__(self, scene):
        self.x1, self.x2, self.d1, self.d2 = grid_coordinates(scene)
        self.shape = (len(self.x1), len(self.x2))
        self.cell = self.d1 * self.d2
        self.gap = np.asarray(scene.geometry.gap(self.x1, self.x2), dtype=float)
        self.mu = scene.friction.on_grid(self.x1, self.x2)      # a float, or a map
        #: one period of an infinite surface (grid.boundary = "periodic")
        self.periodic = bool(getattr(scene.grid, "periodic", False))
        self.X1, self.X2 = np.meshgrid(self.x1, self.x2, indexing="ij")

    def twist(self):
        """The in-plane motion (2, N1, N2) of body 1's surface per unit rotation φ3 [m]."""
        return np.stack([-self.X2, self.X1])


class Operators:
    """The bodies' influence operators on a grid: spectra of their kernels, the contact
    operator of the first instant and of the others, the history kernels, and a fresh
    memory per viscoelastic body (:meth:`new_memories`)."""

    def __init__(self, bodies, grid: Grid, plan, dt, instants, backend, nthreads):
        self.bodies, self.plan, self.dt, self.shape = bodies, plan, dt, grid.shape
        n1, n2 = grid.shape
        per = grid.periodic
        # extreme constants may overflow the kernels: harmless here, refused by Problem
        with np.errstate(over="ignore", invalid="ignore"):
            spectra = [body_spectra_parts(b, n1, n2, grid.d1, grid.d2, backend, nthreads,
                                          periodic=per) for b in bodies]
            self.conv = convolver(n1, n2, backend, int(nthreads), periodic=per)
            fresh = self.new_memories()
            self.spectra = spectra
            self._operators = {}
            self.first = self.operator(self._weights(fresh, True))
            self.history_kernels = history_kernels(*(s if m is not None else None
                                                     for s, m in zip(spectra, fresh, strict=True)))
            self.next = self.operator(self._weights(fresh, False)) \
                if instants > 1 else self.first
            #: the time rule each body's memory applies ("auto" resolved), None without one
            self.rules = [None if m is None else m.rule for m in fresh]

    def operator(self, weights) -> ContactOperator:
        """The operator of an instant whose traction has the creep weights ``weights``
        (one per body: a float, or a tuple with one per kernel part of a body whose
        Poisson ratio varies), made once per distinct tuple: a time rule may weight t0,
        its start steps and the later steps apart."""
        key = tuple(float(w) if np.ndim(w) == 0 else tuple(float(x) for x in w)
                    for w in weights)
        if key not in self._operators:
            self._operators[key] = ContactOperator(*self.spectra, *key, self.conv)
        return self._operators[key]

    def instant_weights(self, mems) -> list:
        """The creep weights of the next instant's traction, one per body [1]."""
        return [self._body_weight(b, m, None if m is None else m.instant_weight)
                for b, m in zip(self.bodies, mems, strict=True)]

    def new_memories(self) -> list:
        """A fresh memory per viscoelastic body (None for the others): one recursion per
        kernel part, all with the rule the body's compliances call for."""
        if self.plan.memory == "none":
            return [None, None]
        out = []
        for b in self.bodies:
            if not b.has_memory:
                out.append(None)
                continue
            rule = resolve_body_rule(b.rule_creeps, self.dt, self.plan.time_rule)
            parts = [make_memory(c, self.dt, rule, (3,) + self.shape) for c in b.part_creeps]
            out.append(parts[0] if len(parts) == 1 else BodyMemory(parts))
        return out

    @staticmethod
    def _body_weight(b, m, weight):
        """A body's creep weight(s): 0 when rigid, the memory's, or phi(0) of each part
        without a memory (1 for an elastic body)."""
        if b.rigid:
            return 0.0
        if m is not None:
            return weight
        w = tuple(float(c.phi0) for c in b.part_creeps) if b.has_memory else (1.0,)
        return w[0] if len(w) == 1 else w

    def _weights(self, mems, first):
        return [self._body_weight(b, m, None if m is None else
                                  (m.weight0 if first else m.weight))
                for b, m in zip(self.bodies, mems, strict=True)]

    def kernels(self) -> list:
        """Every kernel the run convolves with (the compliant operators' and the history's)."""
        out = [op.k for op in (self.first, self.next) if not op.rigid]
        return out + [p for k in self.history_kernels if k is not None
                      for p in (k if isinstance(k, list) else [k])]


class Problem:
    """One run's fixed parts: the :class:`Grid`, the load program, the :class:`Operators`
    and the solver's limits, for a scene and its plan."""

    def __init__(self, scene, pl, fft=None, threads=None, tuning=None):
        self.scene, self.plan, sv = scene, pl, scene.solver
        self.grid = Grid(scene)
        self.steps = _n_steps(scene)
        _warn_off_knots(scene, self.steps)
        self.program = scene.load.programs(self.steps)
        self.t = self.program.t
        # the force programs (NaN where the freedom is displacement-controlled)
        self.W, self.T1, self.T2 = self.program.force[:3]
        self.dt = float(self.t[1] - self.t[0]) if self.t.size > 1 else 0.0
        #: the contact's growth exponent under load, where self-similar (solver.warm_start)
        self.similar = {"sphere": 1 / 3, "ellipsoid": 1 / 3}.get(scene.geometry.shape)
        self.limits = Tolerances(sv.tolerance, sv.max_iterations, sv.max_coupling_passes,
                                 tuning)
        self.tang = pl.tangential != "none"
        bodies = (scene.indenter.body(), scene.halfspace.body())
        self.beta = float(dundurs_beta(*bodies))
        self.ops = Operators(bodies, self.grid, pl, self.dt, self.t.size,
                             fft or sv.fft, threads or sv.threads)
        self._check_finite()
        #: the worn surface of a wear run (:mod:`.wear`), None without ``[wear]``
        self.wear = None if getattr(scene, "wear", None) is None else \
            WearTracker(scene.wear, self.grid.gap)

    def maps(self) -> dict:
        """The archive's maps over (x1, x2): a mapped friction ``mu``, and for a measured or
        generated surface the initial gap ``h0`` the run starts from (unworn in a wear
        run, whose gap opens as it goes)."""
        maps = {"mu": self.grid.mu} if np.ndim(self.grid.mu) else {}
        if self.scene.geometry.shape in ("surface", "rough"):
            maps["h0"] = self.grid.gap if self.wear is None else self.wear.hi
        return maps

    def _check_finite(self):
        """Refuse constants whose influence coefficients float64 cannot hold, or whose
        pressures and displacements it cannot square (the solvers' inner products)."""
        ops, g, sc = self.ops, self.grid, self.scene
        where = (f"indenter: {sc.indenter.material}{_young(sc.indenter)}, halfspace: "
                 f"{sc.halfspace.material}{_young(sc.halfspace)}, cells {g.d1:.3g} x "
                 f"{g.d2:.3g} m, creep weights {_show_weight(ops.next.w1)}, "
                 f"{_show_weight(ops.next.w2)} with steps of "
                 f"{self.dt:.3g} s")
        if not all(np.isfinite(v).all() for k in ops.kernels() for v in k.values()):
            raise SceneError(
                f"the influence coefficients overflow float64 ({where}): the moduli, "
                f"relaxation times or time span are beyond what a computation can hold")
        p_star = self._pressure_scale()
        if p_star == 0.0:
            return
        for op in (ops.first, ops.next):
            if op.rigid:
                continue
            u_star = abs(op.self_influence("33")) * p_star
            if not (SCALE_RANGE[0] <= p_star <= SCALE_RANGE[1]
                    and SCALE_RANGE[0] <= u_star <= SCALE_RANGE[1]):
                raise SceneError(
                    f"the scene's scales are beyond float64: the normal force on one cell, "
                    f"{p_star:.3g} Pa, moves it by {u_star:.3g} m ({where}); the solvers "
                    f"square pressures and displacements, so both must lie within "
                    f"{SCALE_RANGE[0]:g} .. {SCALE_RANGE[1]:g}: check the moduli, the "
                    f"relaxation times, load.normal_force and the grid")

    def _pressure_scale(self) -> float:
        """The largest normal force on one cell [Pa]; under approach control the pressure
        that moves one cell by the largest approach (an upper bound)."""
        if self.program.is_force(0):
            return float(np.max(np.abs(self.W))) / self.grid.cell
        op = self.ops.first if not self.ops.first.rigid else self.ops.next
        if op.rigid:
            return 0.0
        approach = float(np.nanmax(np.abs(self.program.motion[0])))
        return approach / max(abs(op.self_influence("33")), 1e-300)

    def controls(self, k, f=1.0):
        """The six freedoms at instant ``k`` for the solver (a fraction ``f`` of them in a
        preload sub-step), or None where W and T are force-controlled and the rotations
        held at zero (the solver's own default)."""
        if not self.program.general:
            return None
        force, motion = self.program.at(k)
        return Controls(f * force, f * motion, self.grid.x1, self.grid.x2)

    def preload_active(self) -> bool:
        """A frictional preload at t0: shear is solved while the first load is applied."""
        pl = self.plan
        return bool(self.tang and pl.preload == "frictional" and self.t.size > 0 and
                    (pl.coupling != "none" or self.T1[0] != 0 or self.T2[0] != 0))

    def fractions(self, first, T, substeps):
        """The sub-steps of an instant: the ``substeps`` of a frictional preload at t0
        (:func:`preload_fractions`), else one."""
        pl = self.plan
        if first and self.tang and pl.preload == "frictional" and \
                (pl.coupling != "none" or np.any(T)):
            return preload_fractions(substeps)
        return np.array([1.0])

    def sub_plan(self, first):
        """The paper's initial frictionless normal solve at t0, then shear from there."""
        if first and self.tang and self.plan.preload == "frictionless":
            return replace(self.plan, tangential="none", coupling="none")
        return self.plan

    def history(self, st, k):
        """The known displacement U [m] at instant ``k`` from the bodies' history tractions.

        Raises
        ------
        SceneError
            The history tractions overflow float64 (a creep function grown beyond any
            representable traction over an absurd time span).
        """
        U = np.zeros((3,) + self.grid.shape)
        if any(m is not None for m in st.memories) and k > 0:
            outputs = (1, 2, 3) if self.tang else (3,)
            # an overflow here is harmless: it is refused just below, before any use
            with np.errstate(over="ignore", invalid="ignore"):
                h = [None if m is None else m.known() for m in st.memories]
                Uh = history_displacement(self.ops.history_kernels, h[0], h[1],
                                          self.ops.conv, outputs=outputs)
            if not np.isfinite(Uh).all():
                raise SceneError(
                    f"step {k} (t = {self.t[k]:.6g} s): the viscoelastic history overflows "
                    f"float64 (the creep of a body over load.time up to {self.t[-1]:.3g} s "
                    f"grows beyond any representable displacement); shorten load.time or "
                    f"check the relaxation times")
            U[[o - 1 for o in outputs]] = Uh
        return U

    def attrs(self, accuracy_note: str, preload: dict) -> dict:
        """The archive's global attributes; ``preload`` is the frictional preload's
        estimate (:func:`contactpipe.simulation.preload.estimate`)."""
        pl, scene = self.plan, self.scene
        out = {
            "title": f"contactpipe simulation: {scene.name}",
            "scene": scene.to_toml(),
            "models": pl.describe(),
            "model_normal": pl.normal, "model_tangential": pl.tangential,
            "model_coupling": pl.coupling, "model_memory": pl.memory,
            "time_rule": pl.time_rule, "preload": pl.preload,
            "dundurs_beta": self.beta,
            "fft_backend": self.ops.conv.backend,
            "grid_spacing_m": [self.grid.d1, self.grid.d2],
            "grid_points": list(self.grid.shape),
            "time_steps": self.steps,
        }
        if accuracy_note:
            out["accuracy"] = accuracy_note
        out.update(self._material_attrs())
        if preload["substeps"]:
            out["preload_substeps"] = preload["substeps"]
            out["preload_estimate_fft_pairs"] = preload["pairs"]
            if preload["error"] is not None:
                out["preload_error_estimate"] = preload["error"]
        return out

    def _material_attrs(self) -> dict:
        """What the bodies' memories used: the time rule each resolved to, the Poisson
        model, and the fit of a creep function from a table."""
        out = {}
        sides = ("indenter", "halfspace")
        used = [f"{side}: {rule}" for side, rule in zip(sides, self.ops.rules, strict=True)
                if rule]
        if used:
            out["time_rule_resolved"] = ", ".join(used)
        for side, b in zip(sides, self.ops.bodies, strict=True):
            if b.split:
                out[f"{side}_poisson_model"] = ("elastic bulk: the Poisson ratio varies "
                                                "from its value where phi = 1")
            spec = getattr(self.scene, side)
            fit = spec.fit()
            if fit is not None:
                out[f"{side}_fit_rms_error"] = fit.rms_error
                out[f"{side}_fit_max_error"] = fit.max_error
                out[f"{side}_fit_terms"] = len(fit.creep.tau)
                out[f"{side}_fit_compliance_error"] = fit.compliance_error
                out[f"{side}_fit_tolerance"] = spec.fit_tolerance or FIT_TOLERANCE
        return out

    def written(self, k) -> int:
        """Instants in the archive once instant ``k`` is done."""
        stride, last = int(self.scene.output.stride), self.t.size - 1
        return k // stride + 1 + (1 if k == last and k % stride else 0)


def _show_weight(w) -> str:
    return f"{w:.3g}" if np.ndim(w) == 0 else "(" + ", ".join(f"{x:.3g}" for x in w) + ")"


def _young(part) -> str:
    young = getattr(part, "young", None)
    return f" young = {young:g} Pa" if young is not None else ""



def _warn_off_knots(scene, steps):
    """A load knot between mesh instants is cut off (a turning point of a fretting loop
    is never reached): say so, with the step counts that would hold every knot."""
    t = np.asarray(scene.load.knots()[0], dtype=float)
    if t.size < 3 or steps < 1:
        return
    pos = (t[1:-1] - t[0]) / (t[-1] - t[0]) * steps
    off = np.abs(pos - np.round(pos)) > 1e-6
    if off.any():
        m = knot_multiple(scene)
        hint = f"; use a multiple of {m} steps" if m else ""
        cut = t[1:-1][off]
        listed = ", ".join(f"{x:g}" for x in cut[:KNOTS_LISTED])
        more = f" and {cut.size - KNOTS_LISTED} more" if cut.size > KNOTS_LISTED else ""
        warnings.warn(f"time.steps = {steps}: the load knots at t = {listed}{more} s fall "
                      f"between instants of the time mesh, so the program is cut there{hint}",
                      stacklevel=4)
