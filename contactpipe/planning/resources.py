"""What a run costs before it starts: memory and time estimates, checked against the
machine (:func:`estimate_resources`, :func:`check_resources`, :func:`check_time`).

The estimate follows the plan of the scene (:func:`contactpipe.planning.plan`): the
tangential form, the coupling and the bodies' memory set the working arrays and the FFT
pairs of each instant.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

try:
    import resource  # Unix only
except ImportError:  # pragma: no cover - Windows: no RLIMIT_AS to respect
    resource = None

from ..exceptions import SceneError
from ..materials import ExponentialCreep
from ..nomenclature import FIELD, VARIABLES, variables_for
from ..solver.window import LARGEST_SHARE, MARGIN, SIDE_STEP, SMALLEST_GRID
from .rules import plan

__all__ = ["Resources", "estimate_resources", "available_memory", "check_resources",
           "check_time"]

# --------------------------------------------------------------------------- resources
#
# Memory model of one run on an N1 x N2 grid (N = N1 N2 cells), in bytes, with the DC-FFT
# padded grid of 4N reals (R = 32 N bytes) and its half spectrum of 2 N1 (N2 + 1) complex
# values (S ~ 32 N bytes); a periodic grid (grid.boundary = "periodic") is transformed
# unpadded: N reals (R = 8 N) and N1 (N2/2 + 1) complex values (S ~ 8 N), 4x less per
# transform, and its kernel spectra are built in Fourier space (no padded kernels):
#   kernel spectra     9 S per compliant body and kernel part (cached)
#   kernel set-up      9 R of padded kernels + their quadrant, while the spectra are made
#   operators          9 S for the first instant's operator, 9 S for the others', 9 S per
#                      body with a history (signed kernels)
#   FFT buffers        2 R + 3 S (pyFFTW in/out, scratch) + 4 S inside a matrix product
#   memory fields      per viscoelastic body: (2 + n_tau) 3N floats (recursion) plus 3 x 3N
#                      of temporaries, or (steps + 2) 3N floats (direct sum of increments)
#   per-step arrays    WORKING[tangential] N floats: the state (p, q, u, s), the solvers'
#                      vectors and the record of the instant
#   output             streamed: the instants the archive's writer thread holds (its
#                      queue's two and the one being handed over) and the read-back
#                      check's block;
#                      in memory: every instant kept, then stacked (twice)
#   surface            a rough or measured surface: its initial gap h0, a map the archive
#                      keeps (N floats, twice in memory); while the gap is made, before
#                      the kernels, SURFACE_SETUP bytes per cell of the grid and of the
#                      height file (read, filled, resampled; a generated one: its spectra)
# The set-up's padded kernels are freed before the operators are formed, so the peak is
# the spectra plus the larger of the set-up and everything else. WORKING and BASE_BYTES
# were calibrated on the peak resident memory of real runs (see estimate_resources).

#: Floats per cell of the per-step working arrays, by tangential model.
WORKING = {"none": 25, "scalar": 45, "vector": 70}
#: Bytes per cell held while a surface's gap is made (freed before the kernels): a height
#: file's heights, their mask, the nearest-point indices of a fill and the resampling
#: points per file point and per grid cell; a generated surface's noise, spectra and
#: phases per grid cell.
SURFACE_SETUP = {"file": 48, "grid": 48, "rough": 112}
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

    @property
    def bytes_per_cell(self) -> float:
        """The estimate per cell of the grid [bytes]."""
        return self.memory_bytes / max(1, self.grid[0] * self.grid[1])

    def describe(self) -> str:
        """One line: the total, per cell, and its three largest items."""
        top = sorted(self.parts.items(), key=lambda kv: -kv[1])[:3]
        items = ", ".join(f"{k} {_fmt_bytes(v)}" for k, v in top)
        return (f"{_fmt_bytes(self.memory_bytes)} ({_fmt_bytes(self.bytes_per_cell)} per "
                f"cell; {items}) and at least "
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
    :func:`contactpipe.planning.accuracy.choose_preload`)."""
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


#: Instants a streamed archive's writer holds at most: the two its thread's queue keeps
#: (:data:`contactpipe.archive.background.DEPTH`) and the one being handed over.
WRITER_INSTANTS = 3


def _output_bytes(scene, tangential, instants, n, in_memory) -> int:
    """Bytes of the output: the instants kept in memory (twice: kept, then stacked), or
    the instants the writer's thread holds and the read-back check's blocks of a
    streamed archive."""
    names = variables_for(tangential)
    fields = [v for v in names if VARIABLES[v]["dims"] == FIELD]
    size = np.dtype(scene.output.precision).itemsize
    per_instant = sum(n * (1 if VARIABLES[v]["dtype"] == "int8" else size) for v in fields)
    stride = int(scene.output.stride)
    kept = (instants - 1) // stride + 1 + (1 if (instants - 1) % stride else 0)
    check = 2 * min(CHECK_BYTES, kept * 4 * 8 * n)       # blocks and temporaries
    if in_memory:
        return 2 * kept * per_instant + check
    return WRITER_INSTANTS * per_instant + check


def _surface_bytes(scene, n, in_memory) -> tuple[int, int]:
    """(bytes held through the run, bytes while the gap is made) of a rough or measured
    surface; (0, 0) for the analytical shapes."""
    geo = scene.geometry
    if geo.shape not in ("surface", "rough"):
        return 0, 0
    held = n * np.dtype(scene.output.precision).itemsize * (2 if in_memory else 1)
    if geo.shape == "rough":
        return held, SURFACE_SETUP["rough"] * n
    points = n
    try:
        from ..scene.geometry import is_gap_file
        from ..scene.topography import read_heights

        if not is_gap_file(geo.file):
            points = int(np.prod(read_heights(geo.file).shape))   # cached: read once
    except (SceneError, OSError):
        pass
    return held, SURFACE_SETUP["file"] * points + SURFACE_SETUP["grid"] * n


def _add_surface(parts, scene, n, in_memory, R, S) -> None:
    """A rough or measured surface's items in ``parts`` (:func:`_surface_bytes`), and a
    second contact window: a contact of islands retries its window, holding a second
    window's spectra and buffers (rough sphere on Maxwell, vector, coupled, 512^2: +93 MiB
    measured against a smooth sphere, 115 MiB counted; benchmarks/bench_rough.py)."""
    parts["surface"], parts["surface set-up"] = _surface_bytes(scene, n, in_memory)
    if parts["surface"] and parts["contact windows"]:
        parts["contact windows"] += int(LARGEST_SHARE * (9 * S + 2 * R + 7 * S))


def _peak(parts) -> int:
    """The peak of the items: the padded kernels of the set-up are freed before the
    operators are formed, and a surface's set-up before the kernels."""
    setup = ("kernel spectra", "kernel set-up", "surface set-up", "base")
    peak = parts["kernel spectra"] + parts["base"] + max(
        parts["kernel set-up"], sum(v for k, v in parts.items() if k not in setup))
    return max(peak, parts["surface set-up"] + parts["surface"] + parts["base"])


def _fft_pairs(scene, pl, n1, n2, instants) -> float:
    """The FFT pairs of a run: per instant, by the plan's forms, times the instants (the
    later ones by their share of a whole-grid step, the first by its preload's)."""
    per_instant = PAIRS_PER_ROOT[pl.tangential] * (n1 * n2) ** 0.25 * \
        (COUPLING_FACTOR[pl.tangential] if pl.coupling != "none" else 1.0)
    # the frictional preload's sub-steps run where the pair couples (β = 0: the load at t0
    # alone makes no shear, unless T is already there, which this estimate leaves out)
    substeps = _preload_substeps(scene.solver.preload_substeps) \
        if pl.tangential != "none" and pl.coupling != "none" else 1
    if substeps > 1 and _windows_apply(scene, pl, n1, n2):
        substeps *= WINDOWED_SUBSTEP
    return per_instant * ((instants - 1) * _step_share(scene, n1, n2) + substeps)


def _transform_bytes(scene, n1, n2):
    """(periodic, points per cell of a transform, bytes R of its real field, bytes S of its
    half spectrum): a periodic grid is transformed unpadded (R = 8 N, S ~ 8 N), the
    DC-FFT grid padded to 2 N1 x 2 N2 (R = 32 N, S ~ 32 N)."""
    periodic = bool(getattr(scene.grid, "periodic", False))
    pad = 1 if periodic else 4
    spectrum = n1 * (n2 // 2 + 1) if periodic else 2 * n1 * (n2 + 1)
    return periodic, pad, pad * n1 * n2 * 8, spectrum * 16


def estimate_resources(scene, plan_=None, in_memory=False) -> Resources:
    """Memory and time a run of ``scene`` needs, computed from the grid, the plan and the
    instants alone (nothing is allocated).

    Parameters
    ----------
    scene : Scene
        With its grid and steps resolved (after
        :func:`contactpipe.planning.accuracy.resolve_accuracy`).
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
    measured at 512², 1.9 kB estimated: four sets of nine kernel spectra). The time is a
    floor, not a forecast: the FFT pairs of the speed table times the least time of one pair.
    """
    pl = plan_ if plan_ is not None else plan(scene)
    n1, n2 = (int(v) for v in scene.grid.points)
    n = n1 * n2
    periodic, pad, R, S = _transform_bytes(scene, n1, n2)
    bodies = (scene.indenter.body(), scene.halfspace.body())
    compliant = sum(len(b.part_creeps) for b in bodies if not b.rigid)   # kernel sets
    histories = sum(b.has_memory for b in bodies) if pl.memory != "none" else 0
    instants = _instants(scene)
    tangential = pl.tangential != "none"
    parts = {
        "kernel spectra": 9 * S * compliant,
        # periodic: the spectra are built in Fourier space (six basis symbols, two parts)
        "kernel set-up": 2 * 9 * S + 6 * 4 * n if periodic else 9 * R + 2 * 9 * n * 8,
        "operators": 9 * S * ((2 if instants > 1 else 1) + histories),
        "FFT buffers": 2 * R + 7 * S,
        "memory fields": _memory_fields(bodies, pl.memory, instants, n),
        "per-step arrays": WORKING[pl.tangential] * n * 8,
        "output": _output_bytes(scene, tangential, instants, n, in_memory),
        "contact windows": _window_bytes(n1, n2, R, S),
        "base": BASE_BYTES,
    }
    _add_surface(parts, scene, n, in_memory, R, S)
    pairs, m, peak = _fft_pairs(scene, pl, n1, n2, instants), pad * n, _peak(parts)
    terms = _direct_terms(bodies, pl.memory, instants)
    history, fft = terms * (DIRECT_TERM_S + 3 * n * DIRECT_FLOAT_S), \
        pairs * FFT_FLOOR_S * m * math.log2(max(m, 2))
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
