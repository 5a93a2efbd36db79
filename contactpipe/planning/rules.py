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

import math
import re
from dataclasses import asdict, dataclass, field

import numpy as np

try:
    import resource                      # Unix only
except ImportError:  # pragma: no cover - Windows: no RLIMIT_AS to respect
    resource = None

from .exceptions import SceneError
from .materials import ExponentialCreep
from .nomenclature import FIELD, VARIABLES, variables_for
from .solver.window import LARGEST_SHARE, MARGIN, SIDE_STEP, SMALLEST_GRID

__all__ = ["Plan", "plan", "pair_couples", "q2_reasons", "RULES", "Resources",
           "estimate_resources", "available_memory", "check_resources", "check_time"]

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
    mapped, surface = scene.friction.mapped, scene.geometry.shape == "surface"
    if not (mapped or surface):
        return out
    try:
        x1, x2 = scene.resolved_grid().coordinates()
    except (SceneError, TypeError, ValueError):
        return [f"{key}: its symmetry about x2 = 0 cannot be checked without the grid"
                for key, flag in (("friction.mu (a map)", mapped),
                                  ("geometry.file (a surface)", surface)) if flag]
    for flag, key, on_grid in ((mapped, "friction.mu (a map)", scene.friction.on_grid),
                               (surface, "geometry.file (a surface)", scene.geometry.gap)):
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
    mu = scene.friction.largest
    load = scene.load
    prog = load.programs()
    t = prog.t
    # the tangential row, force or displacement, and the twist row: what moves the shear
    tang = prog.force[1:3] if prog.is_force(1) else prog.motion[1:3]
    twist = load.moment3 is not None or load.rotation3 is not None
    has_T = bool(np.any(tang != 0)) or twist
    has_T2 = bool(np.any(tang[1] != 0)) or twist
    try:
        couples = pair_couples(b1, b2)
    except (ZeroDivisionError, OverflowError):   # a modulus that rounds to 0 or inf
        moduli = ", ".join(f"{side}.young = {getattr(scene, side).young!r}"
                           for side in ("indenter", "halfspace")
                           if getattr(getattr(scene, side), "young", None) is not None)
        raise SceneError(f"{moduli}: a shear modulus rounds to 0 Pa or overflows; give "
                         "moduli of a material (1e3 to 1e13 Pa)") from None
    needs_tangential = mu > 0 and (has_T or couples)
    choice = tangential or scene.solver.tangential

    if choice not in RULES["tangential"] + ("auto",):
        raise SceneError(f"tangential={choice!r}: allowed 'auto', 'scalar', 'vector', 'none'")
    if not needs_tangential:
        if choice not in ("auto", "none"):
            raise SceneError(f"tangential={choice!r}: this scene has no shear to solve "
                             f"(mu = {mu}, no tangential load, no normal-tangential coupling)")
        tang = "none"
    elif choice == "auto":
        tang = "vector" if q2_reasons(scene) else "scalar"
    elif choice == "none":
        raise SceneError("tangential='none': the scene carries shear (friction.mu > 0 with a "
                         "tangential load or a coupled pair); allowed: 'scalar', 'vector', 'auto'")
    elif choice == "scalar" and twist:
        key = "load.moment3" if load.moment3 is not None else "load.rotation3"
        raise SceneError(f"tangential='scalar': {key} twists the contact; the one-component "
                         f"form cannot carry a torque. Use 'vector' or 'auto'")
    elif choice == "scalar" and has_T2:
        key = "load.tangential_force" if prog.is_force(1) else "load.tangential_displacement"
        raise SceneError(f"tangential='scalar': {key} has a component along x2; "
                         "the one-component form cannot carry it. Use 'vector' or 'auto'")
    else:
        tang = choice

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


# --------------------------------------------------------------------------- resources
#
# Memory model of one run on an N1 x N2 grid (N = N1 N2 cells), in bytes, with the DC-FFT
# padded grid of 4N reals (R = 32 N bytes) and its half spectrum of 2 N1 (N2 + 1) complex
# values (S ~ 32 N bytes):
#   kernel spectra     9 S per compliant body and kernel part (cached)
#   kernel set-up      9 R of padded kernels + their quadrant, while the spectra are made
#   operators          9 S for the first instant's operator, 9 S for the others', 9 S per
#                      body with a history (signed kernels)
#   FFT buffers        2 R + 3 S (pyFFTW in/out, scratch) + 4 S inside a matrix product
#   memory fields      per viscoelastic body: (2 + n_tau) 3N floats (recursion) plus 3 x 3N
#                      of temporaries, or (steps + 2) 3N floats (direct sum of increments)
#   per-step arrays    WORKING[tangential] N floats: the state (p, q, u, s), the solvers'
#                      vectors and the record of the instant
#   output             streamed: one chunk per variable and the read-back check's block;
#                      in memory: every instant kept, then stacked (twice)
# The set-up's padded kernels are freed before the operators are formed, so the peak is
# the spectra plus the larger of the set-up and everything else. WORKING and BASE_BYTES
# were calibrated on the peak resident memory of real runs (see estimate_resources).

#: Floats per cell of the per-step working arrays, by tangential model.
WORKING = {"none": 25, "scalar": 45, "vector": 70}
#: Fixed allowance for the allocator, FFTW plans and library buffers [bytes].
BASE_BYTES = 16 * 2**20
#: Field data the archive's read-back check holds at once [bytes]
#: (:data:`contactpipe.archive.content.BLOCK_BYTES`).
CHECK_BYTES = 16 * 2**20
#: Lower bound of the time of one FFT pair, per padded point and log2 of the points [s]
#: (pyFFTW, one thread: 0.44 ms at 128², 1.6 ms at 256², 10.6 ms at 512² on the 2-core
#: machine of the README's speed table; the least of the three, 3.4e-10, is the floor).
FFT_FLOOR_S = 3.4e-10
#: FFT pairs of one instant, per fourth root of N, by model, fitted where the pairs grow
#: least, so that ``seconds`` stays near a lower bound: a cold normal solve 20 / 21 / 23 /
#: 28 pairs at 64² ... 512² (28 / 22.6 = 1.2 N^(1/4) at 512²), a one-component fretting
#: step 10.4 / 12.2 at 64² / 128² (steel on steel), the vector form's 24.9 / 28.7 (2.5-3.1
#: N^(1/4); `contactpipe bench fretting`, docs/design-choices.md D3).
PAIRS_PER_ROOT = {"none": 1.2, "scalar": 1.2, "vector": 2.2}
#: A preload sub-step on a window of its contact against an instant on the whole grid,
#: at least (its window's share of the grid: 16.8 / 66 pairs per sub-step on paper fig. 3,
#: 128², 36 / 67 steel on aluminium).
WINDOWED_SUBSTEP = 0.2
#: A coupled instant (β ≠ 0) against an uncoupled one, by tangential form: the scalar
#: joint solve 42.6 / 46.5 against 10.4 / 12.2 pairs at 64² / 128² (steel on aluminium
#: against steel on steel), the vector form 74.0 / 87.3 against 24.9 / 28.7 (3.0); both
#: kept at 2.8 so that the coupled estimate stays below the pairs spent (vector/scalar
#: 1.84 against 1.74-1.88 measured).
COUPLING_FACTOR = {"none": 1.0, "scalar": 2.8, "vector": 2.8}
#: What an FFT pair costs beyond its transforms (the solvers' element-wise work and the
#: Python around it), for the estimate of the wall time [s]: 0.25 ms measured (64²
#: fretting, 3.4 ms for 10.4 pairs a step; 16²-24² tiny scenes, 0.26-0.28 ms a pair).
PAIR_COST_S = 2.5e-4
#: A floor of one term of the direct history sum (a tabulated creep function: step k adds
#: its k past increments, each a 3 N array): per term [s] and per float of it [s]
#: (measured 2.3 µs at 16², 3-6 ns a float at 64² and 128²).
DIRECT_TERM_S = 1.0e-6
DIRECT_FLOAT_S = 1.0e-9
#: The run time a scene may be estimated to take without ``solver.max_hours`` [h].
DEFAULT_MAX_HOURS = 1.0
#: Pairs a run spends against the floor count of :data:`PAIRS_PER_ROOT`, for the estimate
#: (measured 1.6-2.8: 2.8 paper-maxwell 64², 2.4 tiny-fretting 24², 2.6 tiny-creep 64²,
#: 1.6 the elastic paper loop 128², 40 steps each).
TYPICAL_PAIRS = 2.5


@dataclass(frozen=True)
class Resources:
    """What a run is estimated to need, before anything is allocated.

    Attributes
    ----------
    memory_bytes : int
        Peak memory beyond what the process holds before the run [bytes].
    parts : dict
        The same, by item (kernel spectra, operators, FFT buffers, memory fields,
        per-step arrays, output) [bytes].
    fft_pairs : float
        Estimated FFT pairs of the whole run (an order of magnitude).
    seconds : float
        ``fft_pairs`` times the floor time of one FFT pair on the padded grid, plus a
        floor of the direct history sum [s]: a lower bound of the wall time.
    estimated_seconds : float
        The wall time to expect [s]: :data:`TYPICAL_PAIRS` times the pairs, each costing
        its transforms' floor and :data:`PAIR_COST_S`, plus the direct history sum's
        floor; the set-up (kernels, FFT plans) is left out.
    grid : tuple of int
        (N1, N2) the estimate is for.
    instants : int
        Instants the run computes.
    history_terms : float
        Terms of the direct history sum over the run (0 for creep laws of exponentials).
    """

    memory_bytes: int
    parts: dict = field(default_factory=dict)
    fft_pairs: float = 0.0
    seconds: float = 0.0
    grid: tuple = (0, 0)
    instants: int = 0
    estimated_seconds: float = 0.0
    history_terms: float = 0.0

    def describe(self) -> str:
        """One line: the total and its three largest items."""
        top = sorted(self.parts.items(), key=lambda kv: -kv[1])[:3]
        items = ", ".join(f"{k} {_fmt_bytes(v)}" for k, v in top)
        return (f"{_fmt_bytes(self.memory_bytes)} ({items}) and at least "
                f"{_fmt_seconds(self.seconds)} for {self.instants} instants on "
                f"{self.grid[0]}x{self.grid[1]} cells")

    def describe_time(self) -> str:
        """One line: the time to expect, its floor and what it is made of."""
        history = (f", a direct history sum of {self.history_terms:.3g} array terms"
                   if self.history_terms else "")
        return (f"about {_fmt_seconds(self.estimated_seconds)} (at least "
                f"{_fmt_seconds(self.seconds)}: {self.instants} instants on "
                f"{self.grid[0]}x{self.grid[1]} cells, {self.fft_pairs:.3g} FFT pairs"
                f"{history})")


def _fmt_bytes(n) -> str:
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} TiB"


def _fmt_seconds(s) -> str:
    if s < 120:
        return f"{s:.2g} s"
    if s < 7200:
        return f"{s / 60:.3g} min"
    if s < 172800:
        return f"{s / 3600:.3g} h"
    return f"{s / 86400:.3g} days"


def _instants(scene) -> int:
    steps = scene.time.steps if scene.time.steps is not None else \
        len(scene.load.knots()[0]) - 1
    return int(steps) + 1


def _direct_terms(bodies, memory, instants) -> float:
    """Terms of the direct history sums over the run: step k sums its k past increments,
    once per kernel part whose creep function is not of exponentials."""
    if memory == "none":
        return 0.0
    parts = sum(1 for b in bodies if b.has_memory for c in b.part_creeps
                if not isinstance(c, ExponentialCreep))
    steps = float(instants - 1)
    return parts * steps * (steps + 1.0) / 2.0


def _memory_fields(bodies, memory, instants, n) -> int:
    """Bytes of the viscoelastic memories."""
    if memory == "none":
        return 0
    total = 0
    for b in bodies:
        if not b.has_memory:
            continue
        for creep in b.part_creeps:          # one recursion per kernel part
            if isinstance(creep, ExponentialCreep):
                total += (2 + len(creep.tau) + 3) * 3 * n * 8
            else:
                total += (instants + 2) * 3 * n * 8
    return total


#: The sub-steps "auto" is counted with in the time estimate (it took 16 for 1 % and
#: 64-128 for 0.2 % on a rigid sphere on nu = 0.3, 32^2 and 64^2).
AUTO_PRELOAD_GUESS = 32


def _preload_substeps(setting) -> int:
    """Sub-step solves of a frictional preload: its n, and the coarser paths of its error
    estimate (n/4 and n/2; 2, 4, ..., n/2 for "auto";
    :func:`contactpipe.accuracy.choose_preload`)."""
    if setting == "auto":
        return 2 * AUTO_PRELOAD_GUESS
    n = int(setting)
    return n + (n // 4 + n // 2 if n >= 4 else 0)


def _windows_apply(scene, pl, n1, n2) -> bool:
    """A frictional preload whose sub-steps run on windows of their contact
    (:mod:`contactpipe.solver.window`): a coupled pair, a sphere or an ellipsoid."""
    return (pl.tangential != "none" and pl.coupling != "none" and pl.preload == "frictional"
            and scene.geometry.shape in ("sphere", "ellipsoid")
            and min(n1, n2) >= SMALLEST_GRID)


def _window_bytes(n1, n2, R, S) -> int:
    """Bytes the windows of the contact (:mod:`contactpipe.solver.window`) hold while
    they serve: the grid's nine kernels in real space, and one window's kernel spectra
    and FFT buffers (at most :data:`LARGEST_SHARE` of the grid's)."""
    if min(n1, n2) < SMALLEST_GRID:
        return 0
    return int(9 * R + LARGEST_SHARE * (9 * S + 2 * R + 7 * S))


def _step_share(scene, n1, n2) -> float:
    """A floor of a step's FFT pairs on a window of its contact against the whole grid:
    the share of the grid's cells in the window around the Hertz contact under the
    instantaneous (glassy) moduli, the smallest of a creeping contact (its extent,
    :data:`MARGIN` on each side, sides rounded up to :data:`SIDE_STEP`); 1 where no window
    serves: a grid under :data:`SMALLEST_GRID`, a contact without an estimate or whose
    window would exceed :data:`LARGEST_SHARE`."""
    if min(n1, n2) < SMALLEST_GRID:
        return 1.0
    axes, size = scene.hertz_semi_axes("instantaneous"), scene.resolved_grid_size()
    if axes is None or size is None:
        return 1.0
    share = 1.0
    for a, length, n in zip(axes, size, (n1, n2), strict=True):
        cells = 2.0 * float(a) / float(length) * n             # the contact's extent
        c = SIDE_STEP * math.ceil((cells + 2 * max(2.0, MARGIN * cells)) / SIDE_STEP)
        share *= min(n, c) / n
    return share if np.isfinite(share) and 0.0 < share <= LARGEST_SHARE else 1.0


def _output_bytes(scene, tangential, instants, n, in_memory) -> int:
    """Bytes of the output: the instants kept in memory (twice: kept, then stacked), or
    one chunk per variable and the read-back check's blocks of a streamed archive."""
    names = variables_for(tangential)
    fields = [v for v in names if VARIABLES[v]["dims"] == FIELD]
    size = np.dtype(scene.output.precision).itemsize
    per_instant = sum(n * (1 if VARIABLES[v]["dtype"] == "int8" else size) for v in fields)
    stride = int(scene.output.stride)
    kept = (instants - 1) // stride + 1 + (1 if (instants - 1) % stride else 0)
    check = 2 * min(CHECK_BYTES, kept * 4 * 8 * n)       # blocks and temporaries
    if in_memory:
        return 2 * kept * per_instant + check
    return per_instant + check


def estimate_resources(scene, plan_=None, in_memory=False) -> Resources:
    """Memory and time a run of ``scene`` needs, computed from the grid, the plan and the
    instants alone (nothing is allocated).

    Parameters
    ----------
    scene : Scene
        With its grid and steps resolved (after :func:`contactpipe.accuracy.resolve_accuracy`).
    plan_ : Plan, optional
        The plan (:func:`plan` of the scene otherwise).
    in_memory : bool
        The result is kept in memory (no archive path): every instant counts.

    Returns
    -------
    Resources

    Notes
    -----
    The memory model (comments above :data:`WORKING`) was calibrated on the peak
    resident memory of real runs: ``resource.getrusage(RUSAGE_SELF).ru_maxrss`` after
    the run minus the resident memory before it, one fresh process per run, pyFFTW, one
    thread (measured [MiB] / estimated [MiB]):

    ======================================================  =========  =========
    scene (steps; the archive streamed unless "in memory")  128²       256²
    ======================================================  =========  =========
    rigid sphere on Maxwell, frictionless (10)              36 / 55    122 / 160
    the same, 40 steps kept in memory                       60 / 108   242 / 287
    rigid on Maxwell, fretting, coupled, one-component (8)  46 / 56    163 / 173
    elastic pair, beta = 0, one-component (8)               40 / 54    136 / 165
    steel on aluminium, vector, coupled (4; 2 at 256²)      42 / 54    132 / 158
    ======================================================  =========  =========

    and 415 / 495 MiB for the frictionless Maxwell run at 512² (4 steps); before each
    run ru_maxrss equalled the resident memory (no earlier peak). Since then the instants
    run on windows of their contact, and the estimate counts what the windows hold
    ("contact windows": the nine kernels in real space and one window's spectra and
    buffers at most: +12 MiB at 128², +47 MiB at 256²), which the estimates above leave
    out (128², rigid on Maxwell, fretting, 5 steps: measured 47.7 MiB before the windows,
    54.5 MiB with them, estimated 53.3 then 65.1 MiB). The estimate
    stays above every measurement, by 6 % to 80 % (the most on small grids, where the fixed
    allowances dominate); it grows as N1 x N2 (for a viscoelastic half-space 1.7 kB per cell
    measured at 512², 1.9 kB estimated: four sets of nine kernel spectra). The time is a floor,
    not a forecast: the FFT pairs of the speed table times the least time of one pair.
    """
    pl = plan_ if plan_ is not None else plan(scene)
    n1, n2 = (int(v) for v in scene.grid.points)
    n = n1 * n2
    R = 4 * n * 8
    S = 2 * n1 * (n2 + 1) * 16
    bodies = (scene.indenter.body(), scene.halfspace.body())
    compliant = sum(len(b.part_creeps) for b in bodies if not b.rigid)   # kernel sets
    histories = sum(b.has_memory for b in bodies) if pl.memory != "none" else 0
    instants = _instants(scene)
    tangential = pl.tangential != "none"
    parts = {
        "kernel spectra": 9 * S * compliant,
        "kernel set-up": 9 * R + 2 * 9 * n * 8,
        "operators": 9 * S * ((2 if instants > 1 else 1) + histories),
        "FFT buffers": 2 * R + 7 * S,
        "memory fields": _memory_fields(bodies, pl.memory, instants, n),
        "per-step arrays": WORKING[pl.tangential] * n * 8,
        "output": _output_bytes(scene, tangential, instants, n, in_memory),
        "contact windows": _window_bytes(n1, n2, R, S),
        "base": BASE_BYTES,
    }
    per_instant = PAIRS_PER_ROOT[pl.tangential] * n ** 0.25 * \
        (COUPLING_FACTOR[pl.tangential] if pl.coupling != "none" else 1.0)
    # the frictional preload's sub-steps run where the pair couples (β = 0: the load at t0
    # alone makes no shear, unless T is already there, which this estimate leaves out)
    substeps = _preload_substeps(scene.solver.preload_substeps) \
        if tangential and pl.coupling != "none" else 1
    if substeps > 1 and _windows_apply(scene, pl, n1, n2):
        substeps *= WINDOWED_SUBSTEP
    pairs = per_instant * ((instants - 1) * _step_share(scene, n1, n2) + substeps)
    m = 4 * n
    # the padded kernels of the set-up are freed before the operators are formed
    peak = parts["kernel spectra"] + parts["base"] + max(
        parts["kernel set-up"], sum(v for k, v in parts.items()
                                    if k not in ("kernel spectra", "kernel set-up", "base")))
    terms = _direct_terms(bodies, pl.memory, instants)
    history = terms * (DIRECT_TERM_S + 3 * n * DIRECT_FLOAT_S)
    fft = pairs * FFT_FLOOR_S * m * math.log2(max(m, 2))
    return Resources(memory_bytes=int(peak), parts=parts, fft_pairs=pairs,
                     seconds=fft + history, grid=(n1, n2), instants=instants,
                     estimated_seconds=TYPICAL_PAIRS * (fft + pairs * PAIR_COST_S) + history,
                     history_terms=terms)


def _meminfo_available() -> int | None:
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _address_space_left() -> int | None:
    """RLIMIT_AS minus the address space the process already maps (Unix)."""
    if resource is None:
        return None
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return None
    used = 0
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            m = re.search(r"^VmSize:\s+(\d+) kB", f.read(), re.M)
            used = int(m.group(1)) * 1024 if m else 0
    except OSError:
        pass
    return max(soft - used, 0)


def _cgroup_left() -> int | None:
    """The container's memory limit minus its usage (cgroup v2, then v1)."""
    for limit, usage in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                         ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                          "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        try:
            with open(limit, encoding="ascii") as f:
                text = f.read().strip()
            if text == "max":
                return None
            with open(usage, encoding="ascii") as f:
                used = int(f.read().strip())
            lim = int(text)
            return None if lim >= 2**60 else max(lim - used, 0)
        except (OSError, ValueError):
            continue
    return None


def available_memory() -> tuple[int | None, str]:
    """(bytes, source): the least of the free RAM (MemAvailable), the address space left
    under RLIMIT_AS and the container's memory left (cgroup); (None, "") when none of
    them can be read (then nothing is refused)."""
    found = [(v, what) for v, what in ((_meminfo_available(), "available RAM"),
                                       (_address_space_left(), "address space left under "
                                                               "RLIMIT_AS"),
                                       (_cgroup_left(), "memory left to the container"))
             if v is not None]
    if not found:
        return None, ""
    return min(found)


def check_resources(res: Resources, available: int | None = None,
                    max_hours: float | None = None) -> Resources:
    """Refuse a run whose memory estimate exceeds the memory available, or whose time
    estimate exceeds the cap.

    Parameters
    ----------
    res : Resources
        From :func:`estimate_resources`.
    available : int, optional
        Bytes available; :func:`available_memory` when not given.
    max_hours : float, optional
        The cap on :attr:`Resources.estimated_seconds` [h] (the scene's
        ``solver.max_hours``); :data:`DEFAULT_MAX_HOURS` when not given.

    Raises
    ------
    SceneError
        One line naming the estimate, the limit and what to change.
    """
    source = "given limit"
    if available is None:
        available, source = available_memory()
    if available is None or res.memory_bytes <= available:
        return check_time(res, max_hours)
    fix = ["fewer grid.points (memory grows with N1 x N2)"]
    if res.parts.get("output", 0) > res.memory_bytes / 3:
        fix.insert(0, "write the result to a file, a larger output.stride or "
                      "output.precision = 'float32'")
    if res.parts.get("memory fields", 0) > res.memory_bytes / 3:
        fix.append("a creep law of exponentials (its memory does not grow with the steps)")
    raise SceneError(f"the run needs about {res.describe()}, but only "
                     f"{_fmt_bytes(available)} is available ({source}); use "
                     + " or ".join(fix))


def check_time(res: Resources, max_hours: float | None = None) -> Resources:
    """Refuse a run estimated to take longer than ``max_hours`` (the scene's
    ``solver.max_hours``; :data:`DEFAULT_MAX_HOURS` when None) with one SceneError line
    naming the estimate and the ``max_hours`` that would let it start."""
    cap = DEFAULT_MAX_HOURS if max_hours is None else float(max_hours)
    if res.estimated_seconds > cap * 3600.0:
        lift = max(1, math.ceil(2.0 * res.estimated_seconds / 3600.0))
        fix = "fewer time.steps or grid.points"
        if res.history_terms:
            fix += " or a creep law of exponentials (its time per step does not grow)"
        raise SceneError(f"the run is estimated to take {res.describe_time()}, above the "
                         f"cap solver.max_hours = {cap:g} h; set solver.max_hours = {lift} "
                         f"(or more) to run it anyway, or use {fix}")
    return res
