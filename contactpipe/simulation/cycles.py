"""A wear run: the load program repeated ``wear.cycles`` times on the wearing surface, with
cycle jumps (docs/wear.md).

The program is one cycle that ends where it starts. The first cycle runs every instant
from t0 (the normal preload included); each later one runs instants 1 .. steps again from
the state the last one left: the stick/slip state, the slip, the creep memory and the
rigid motions carry over, nothing restarts. The worn depth (:mod:`.wear`) opens the gap
after every step.

A simulated cycle stands for ``J`` cycles (the jump): its wear increment, its dissipation
and its slip are extrapolated over the ``J − 1`` cycles that follow, and the creep memory
is advanced as the same periodic load would leave it (:func:`.wear.advance_memories`).
The last cycle is always simulated. ``jump = "auto"`` chooses J from the change of the
wear increment between the last two simulated cycles (:class:`Jumps`).

The archive holds the instants of the last cycle (over ``time``, absolute from t0) and the
history at the records (over ``cycle``): every simulated cycle a jump is taken from, and
about :data:`RECORDS` log-spaced cycles (the first and the last among them).
"""
from __future__ import annotations

import math
import time as _time
import warnings
import zipfile

import numpy as np
import xarray as xr

from .._util.interrupts import deferred, raise_if_signalled
from ..archive import MemoryWriter, save, validate
from ..exceptions import ArchiveError, ResumeNotice, one_line
from ..nomenclature import (
    CYCLE_FIELD,
    CYCLE_SERIES,
    LOOP_FIELD,
    cf_attrs,
    variables_for,
)
from . import preload
from .preload import Path
from .wear import advance_memories, memory_snapshot

__all__ = ["run_cycles", "Jumps", "record_cycles", "RECORDS"]

#: Records of a run that simulates every cycle: about this many, log-spaced.
RECORDS = 100


class Jumps:
    """The jump J (cycles per simulated cycle): fixed, or chosen from an error estimate.

    With ``jump = "auto"``, r is the wear increment per cycle (a field) of a simulated
    cycle and D the depth worn over the n cycles completed. ρ = (r − r_prev)/G is the
    change of r per cycle between the last two simulated cycles, G cycles apart; holding
    r over the next J cycles errs by about |ρ| J²/2 (largest over the cells). That error
    is allowed ``tolerance`` × J × max(|r|, |D|/n) (largest over the cells):
    ``tolerance`` of the wear the jump adds, or of the life's mean wear per cycle once
    the wear slows down (a contact nearing a state where nothing wears, r → 0), so that
    summed over the life the error stays of the order of ``tolerance`` × D. J is the
    largest jump within that, at most twice the last; 1 until two cycles are known.
    """

    def __init__(self, jump, tolerance: float):
        self.fixed = None if jump == "auto" else int(jump)
        self.tol = float(tolerance)
        self.size = 1
        self._rate: np.ndarray | None = None

    def choose(self, rate: np.ndarray, depth: np.ndarray, cycles: int) -> int:
        """The next jump, after a simulated cycle whose wear increment is ``rate`` [m],
        with ``depth`` [m] worn over the ``cycles`` completed so far."""
        if self.fixed is not None:
            return self.fixed
        prev, self._rate = self._rate, np.array(rate, copy=True)
        if prev is None:
            return 1
        scale = max(float(np.linalg.norm(rate)),
                    float(np.linalg.norm(depth)) / max(int(cycles), 1))
        change = float(np.linalg.norm(self._rate - prev)) / self.size
        if scale == 0.0 or change == 0.0:
            size = 2 * self.size
        else:
            size = min(2 * self.size, int(2.0 * self.tol * scale / change))
        self.size = max(1, size)
        return self.size

    def state(self) -> dict:
        """The controller's state, for a checkpoint."""
        out = {"jump_size": np.array(self.size)}
        if self._rate is not None:
            out["jump_rate"] = self._rate.copy()
        return out

    def load_state(self, saved) -> None:
        """Take the state of a checkpoint (:meth:`state`)."""
        self.size = int(saved["jump_size"])
        self._rate = saved.get("jump_rate")


def record_cycles(total: int) -> set:
    """The cycles recorded besides those a jump is taken from: about :data:`RECORDS`
    log-spaced, the first and the last included (every cycle up to :data:`RECORDS`)."""
    if total <= RECORDS:
        return set(range(1, total + 1))
    marks = np.round(np.logspace(0.0, math.log10(total), RECORDS))
    return {int(c) for c in marks} | {1, total}


def _kept_loops(total: int, count: int) -> list:
    """The cycles whose loop of tractions is kept: ``count`` log-spaced targets."""
    if count <= 0:
        return []
    marks = np.round(np.logspace(0.0, math.log10(total), count)).astype(int)
    return sorted({int(c) for c in marks} | {total})


class _History:
    """The records over ``cycle`` and the kept loops over ``loop_cycle``."""

    def __init__(self, pb, targets):
        self.cell = pb.grid.cell
        self.rows: dict[str, list] = {k: [] for k in (
            "cycle", "wear_depth", "worn_volume", "cumulative_dissipation", "cycle_p_max",
            "cycle_stick_area")}
        self.targets = list(targets)
        self.loops: dict[str, list] = {"loop_cycle": [], "loop_p": [], "loop_q1": [],
                                       "loop_q2": []}

    def keeps(self, cycle: int) -> bool:
        """Keep this cycle's loop: it reaches the next target (the last cycle always)."""
        return bool(self.targets) and cycle >= self.targets[0]

    def keep(self, cycle, loop):
        while self.targets and self.targets[0] <= cycle:
            self.targets.pop(0)
        self.loops["loop_cycle"].append(cycle)
        for name in ("p", "q1", "q2"):
            self.loops["loop_" + name].append(np.stack([rec[name] for rec in loop]))

    def lengths(self) -> tuple:
        return len(self.rows["cycle"]), len(self.loops["loop_cycle"])

    def arrays(self, lengths) -> dict:
        """The records and loops up to ``lengths`` as arrays (for a checkpoint)."""
        n_rows, n_loops = lengths
        out = {f"h_{k}": np.array(v[:n_rows], dtype=float) for k, v in self.rows.items()}
        if n_loops:
            out.update({f"l_{k}": np.array(v[:n_loops], dtype=float)
                        for k, v in self.loops.items()})
        return out

    def restore(self, saved):
        """Take the records and loops of a checkpoint."""
        for k in self.rows:
            self.rows[k] = [int(v) if k == "cycle" else v for v in saved[f"h_{k}"]]
        if "l_loop_cycle" in saved:
            for k in self.loops:
                self.loops[k] = [int(v) if k == "loop_cycle" else v
                                 for v in saved[f"l_{k}"]]
            kept = max(self.loops["loop_cycle"])
            self.targets = [t for t in self.targets if t > kept]

    def add(self, cycle, depth, dissipation, p_max, stick_min):
        depth = np.maximum(depth, 0.0)
        for key, v in (("cycle", cycle), ("wear_depth", depth.copy()),
                       ("worn_volume", float(depth.sum()) * self.cell),
                       ("cumulative_dissipation", dissipation), ("cycle_p_max", p_max),
                       ("cycle_stick_area", stick_min)):
            self.rows[key].append(v)

    def variables(self, loop_time) -> dict:
        """The history as labelled variables, and the kept loops with their coordinates."""
        out = {"cycle": xr.Variable(("cycle",), np.array(self.rows["cycle"], dtype=np.int64),
                                    attrs=cf_attrs("cycle"))}
        for name, rows in self.rows.items():
            if name != "cycle":
                dims = CYCLE_FIELD if np.ndim(rows[0]) == 2 else CYCLE_SERIES
                out[name] = xr.Variable(dims, np.array(rows, dtype=float),
                                        attrs=cf_attrs(name))
        if self.loops["loop_cycle"]:
            out["loop_cycle"] = xr.Variable(("loop_cycle",), np.array(
                self.loops["loop_cycle"], dtype=np.int64), attrs=cf_attrs("loop_cycle"))
            out["loop_time"] = xr.Variable(("loop_time",), np.asarray(loop_time, dtype=float),
                                           attrs=cf_attrs("loop_time"))
            for name in ("loop_p", "loop_q1", "loop_q2"):
                out[name] = xr.Variable(LOOP_FIELD, np.array(self.loops[name], dtype=float),
                                        attrs=cf_attrs(name))
        return out


def _cycle(pb, st, step, record_of, cycle, first, *, keep, on_step):
    """Simulate cycle ``cycle`` (1-based) from ``st``: its largest pressure, its least
    stick area, and (``keep``) the records of its instants, its start included."""
    period = float(pb.t[-1] - pb.t[0])
    shift = (cycle - 1) * period
    if cycle == 1:
        ks, records = range(0, pb.t.size), []
    else:
        ks = range(1, pb.t.size)
        start = {key: np.array(v, copy=True) if isinstance(v, np.ndarray) else v
                 for key, v in record_of(pb, st).items()}
        records = [start] if keep else []
    p_max, stick_min = 0.0, math.inf
    for k in ks:
        raise_if_signalled()             # a signal acts between two instants
        rec = step(pb, st, k, first)
        p_max = max(p_max, float(np.max(rec["p"])))
        stick_min = min(stick_min, float(rec.get("stick_area", 0.0)))
        if keep:                  # the solver may reuse the state's arrays: copies
            records.append({key: np.array(v, copy=True) if isinstance(v, np.ndarray) else v
                            for key, v in rec.items()})
        if on_step is not None:
            on_step(k, float(pb.t[k]) + shift, rec)
    if cycle > 1:
        p_max = max(p_max, float(np.max(start["p"])))
        stick_min = min(stick_min, float(start.get("stick_area", 0.0)))
    return p_max, stick_min, records


def _extrapolate(pb, st, before, more):
    """Carry the simulated cycle (from the state ``before``) over ``more`` cycles: its
    wear, dissipation and slip increments added ``more`` times, the memory advanced."""
    if more <= 0:
        return
    wear = pb.wear
    wear.depth = wear.depth + more * (wear.depth - before["depth"])
    st.dissipation += more * (st.dissipation - before["dissipation"])
    st.s = st.s + more * (st.s - before["s"])
    advance_memories(st.memories, before["memories"], more, float(pb.t[-1] - pb.t[0]))
    pb.grid.gap = wear.gap()


def _progress(pb, total):
    from tqdm.auto import tqdm  # only with progress=True: tqdm is optional here
    return tqdm(total=total, desc=pb.scene.name, unit="cycle")


class _Boundary:
    """The run at its last cycle boundary (the state a next cycle starts from), held in
    memory so that an interrupt inside a cycle checkpoints a whole state."""

    def __init__(self):
        self.arrays: dict | None = None
        self.saved_at = _time.perf_counter()

    def take(self, pb, st, n, simulated, jumps, hist):
        arrays = {f"st_{k}": np.array(v, copy=True) for k, v in st.arrays().items()}
        arrays.update({"wear_depth": pb.wear.depth.copy(), "simulated": np.array(simulated),
                       **jumps.state()})
        self.n, self.arrays, self.lengths, self.hist = n, arrays, hist.lengths(), hist

    def save(self, ckpt):
        if ckpt is None or self.arrays is None:
            return
        ckpt.save(self.n, 0, {**self.arrays, **self.hist.arrays(self.lengths)})
        self.saved_at = _time.perf_counter()


def _resume(pb, st, ckpt, jumps, hist):
    """(cycles completed, cycles simulated) of the checkpoint of ``ckpt`` taken into
    ``st``, ``pb.wear``, ``jumps`` and ``hist``; (0, 0) without one (a damaged one is
    dropped, and the run starts afresh)."""
    if ckpt is None or not ckpt.found() or not ckpt.file.exists():
        return 0, 0
    name = ckpt.path.name
    try:
        with np.load(ckpt.file, allow_pickle=False) as z:
            saved = {k: z[k] for k in z.files}
        if str(saved.pop("digest")) != ckpt.digest:
            raise ValueError("the checkpoint is of another scene")
        n = int(saved["k"])
        st.restore({k[3:]: v for k, v in saved.items() if k.startswith("st_")}, 0)
        pb.wear.load_state({"depth": saved["wear_depth"]})
        pb.grid.gap = pb.wear.gap()
        jumps.load_state(saved)
        hist.restore(saved)
        simulated = int(saved["simulated"])
    except (OSError, ValueError, KeyError, EOFError, TypeError, zipfile.BadZipFile) as e:
        warnings.warn(ResumeNotice(f"{name}: the wear run's checkpoint is unusable "
                                   f"({one_line(e, with_type=False)}); starting afresh"),
                      stacklevel=6)
        ckpt.remove()
        return -1, 0
    warnings.warn(ResumeNotice(f"{name}: resuming the wear run after cycle {n} of "
                               f"{pb.scene.wear.cycles}, its checkpoint ({simulated} "
                               f"simulated)"), stacklevel=6)
    return n, simulated


def _loop(pb, st, step, record_of, first, on_step, bar, ckpt, every):
    """Every cycle, simulated or jumped, from the checkpoint's (``ckpt``) or the first;
    returns the history, the last cycle's records and the count of simulated cycles."""
    spec = pb.scene.wear
    total, jumps = spec.cycles, Jumps(spec.jump, spec.tolerance)
    hist = _History(pb, _kept_loops(total, spec.keep_tractions))
    n, simulated = _resume(pb, st, ckpt, jumps, hist)
    if n < 0:                                        # a damaged checkpoint: afresh
        return None
    if bar is not None:
        bar.update(n)
    boundary = _Boundary()
    try:
        with deferred():
            hist, last, simulated = _cycles(pb, st, step, record_of, first, on_step, bar,
                                            ckpt, every, (n, simulated, jumps, hist,
                                                          boundary))
    except KeyboardInterrupt as err:
        boundary.save(ckpt)
        if ckpt is not None:
            err.resume_from = f"cycle {boundary.n + 1} of {total}"  # type: ignore[attr-defined]
        raise
    if bar is not None:
        bar.update(1)
    return hist, last, simulated


def _cycles(pb, st, step, record_of, first, on_step, bar, ckpt, every, start):
    """The cycles from ``start`` = (completed, simulated, jumps, history, boundary)."""
    n, simulated, jumps, hist, boundary = start
    spec = pb.scene.wear
    total, last = spec.cycles, []
    marks = record_cycles(total)
    while n < total:
        boundary.take(pb, st, n, simulated, jumps, hist)
        if ckpt is not None and _time.perf_counter() - boundary.saved_at > every:
            boundary.save(ckpt)
        cycle = n + 1
        before = {"depth": pb.wear.depth.copy(), "dissipation": st.dissipation,
                  "s": st.s.copy(), "memories": memory_snapshot(st.memories)}
        loop = hist.keeps(cycle)
        p_max, stick_min, records = _cycle(pb, st, step, record_of, cycle, first,
                                           keep=loop or cycle == total, on_step=on_step)
        n, simulated = cycle, simulated + 1
        if loop:
            hist.keep(cycle, records)
        if cycle == total:
            size = 1
        else:
            depth = pb.wear.depth.sum(axis=0)       # both bodies' depths, summed once
            size = jumps.choose(depth - before["depth"].sum(axis=0), depth, cycle)
        size = 1 if cycle == 1 else min(size, total - cycle)   # the first: a start-up
        if cycle in marks or size > 1 or cycle == total:
            hist.add(cycle, pb.wear.total, st.dissipation, p_max, stick_min)
        if cycle == total:
            last = records
            break
        _extrapolate(pb, st, before, size - 1)
        n += size - 1
        if bar is not None:
            bar.set_postfix(jump=size, refresh=False)
            bar.update(size)
    return hist, last, simulated


def _simulate_all(pb, step, record_of, first, opts, ckpt):
    """The cycles, from a checkpoint when there is a usable one."""
    from ..solver.state import State
    _, on_step, progress, every, _ = opts
    for _attempt in range(2):
        st = State.initial(pb.grid.shape, pb.ops.new_memories())
        pb.wear.load_state({"depth": np.zeros_like(pb.wear.depth)})
        pb.grid.gap = pb.wear.gap()
        bar = _progress(pb, pb.scene.wear.cycles) if progress else None
        try:
            out = _loop(pb, st, step, record_of, first, on_step, bar, ckpt, every)
        finally:
            if bar is not None:
                bar.close()
        if out is not None:
            return out
    raise ArchiveError(f"{ckpt.path}: the wear run's checkpoint cannot be dropped")


def run_cycles(pb, path, step, record_of, opts, ckpt=None):
    """Run the wear cycles of problem ``pb``; ``step(pb, st, k, path)`` solves an instant
    and ``record_of(pb, st)`` gives the record of a state. Returns the Dataset, or the
    path of the archive written (atomic: nothing is written on an error or an interrupt).
    With a :class:`~contactpipe.archive.Checkpoint` ``ckpt`` (a resumable run), the run
    continues from its checkpoint, checkpoints at cycle boundaries every
    ``checkpoint_seconds`` and on an interrupt, and drops it once the archive is written."""
    accuracy_note, _, _, _, wall0 = opts
    wear, pb.wear = pb.wear, None         # the preload's estimate runs unworn, on scratch
    try:
        pre = preload.estimate(pb, step)
    finally:
        pb.wear, pb.grid.gap = wear, wear.gap()
    first = Path(pre["substeps"], pb.limits)
    hist, last, simulated = _simulate_all(pb, step, record_of, first, opts, ckpt)
    attrs = pb.attrs(accuracy_note, pre)
    attrs["models"] = f"{attrs['models']}, wear={pb.scene.wear.law}"
    ds = _dataset(pb, attrs, last, hist)
    ds.attrs.update({"wear_law": pb.scene.wear.law, "cycles_simulated": simulated,
                     "wall_time_s": _time.perf_counter() - wall0})
    problems = validate(ds)
    if problems:
        raise ArchiveError("wear run: the archive breaks its rules: " + "; ".join(problems))
    if path is None:
        return ds
    out = pb.scene.output
    save(ds, path, precision=out.precision, compress=out.compress)
    if ckpt is not None:
        ckpt.remove()
    return path


def _dataset(pb, attrs, last, hist) -> xr.Dataset:
    """The last cycle's instants (every ``output.stride``-th and the last) and the
    history, as one Dataset."""
    out = pb.scene.output
    names = variables_for(pb.tang)
    maps = pb.maps()
    kw = {"maps": maps} if maps else {}
    writer = MemoryWriter(None, pb.grid.x1, pb.grid.x2, names, attrs,
                          precision=out.precision, capacity=len(last), **kw)
    shift = (pb.scene.wear.cycles - 1) * float(pb.t[-1] - pb.t[0])
    stride, end = int(out.stride), len(last) - 1
    for k, rec in enumerate(last):
        if k % stride == 0 or k == end:
            writer.append(float(pb.t[k]) + shift, rec)
    ds = writer.close()
    history = hist.variables(pb.t - pb.t[0])
    coords = {k: v for k, v in history.items() if k in ("cycle", "loop_cycle", "loop_time")}
    return ds.assign_coords(coords).assign(
        {k: v for k, v in history.items() if k not in coords})

