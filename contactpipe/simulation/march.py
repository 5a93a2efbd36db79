"""The outer loop (paper §4): march the coupled contact through the temporal mesh.

At every instant t_k of the uniform mesh (:func:`_step`, from the :class:`State` the
previous instant left):

1. the viscoelastic history of each body (its Boltzmann sum, :mod:`contactpipe.solver.memory`)
   gives a known relative displacement, one spatial convolution per body and step;
2. the instantaneous contact (:func:`contactpipe.solver.coupling.solve_instant`) finds p, q, the
   contact and stick areas and the rigid motions, warm-started from the previous instant;
3. slip, dissipation and status follow; the instant is streamed to the archive (every
   ``output.stride``-th instant and the last one) and committed to the memory.

The normal load is applied first: the first instant holds the state reached under the
load at t0. With ``load.preload = "frictional"`` (the default) friction acts while that
load is applied — for a coupled pair this produces shear and slip during indentation
(Spence's effect), resolved in ``solver.preload_substeps`` proportional sub-steps of the
instantaneous (glassy) response; with ``"frictionless"`` the first instant is the paper's
initial frictionless normal solve (outer loop, step 1).

Before anything is allocated, :func:`simulate` checks the output path
(:func:`contactpipe._util.files.check_output_path`) and the memory the run needs
(:func:`contactpipe.planning.estimate_resources`). A resumable run holds a lock on its
target's resume state (:func:`contactpipe.archive.resume_lock`) and checkpoints beside the
archive writers (:class:`contactpipe.archive.Checkpoint`).
"""
from __future__ import annotations

import time as _time
import warnings

import numpy as np

from .._util.files import LockedError, check_output_path, exclusive_lock, make_folder
from .._util.interrupts import Interrupted, deferred, raise_if_signalled, signals_as_interrupt
from ..archive import ArchiveWriter, Checkpoint, MemoryWriter, open_archive, resume_lock
from ..exceptions import (
    ArchiveError,
    ConvergenceError,
    GridError,
    GrossSlidingError,
    OutputPathError,
    ResumeNotice,
    one_line,
)
from ..nomenclature import STATUS_STICK, variables_for
from ..planning import check_resources, estimate_resources
from ..planning import plan as make_plan
from ..planning.accuracy import resolve_accuracy
from ..solver.coupling import FREEDOMS, Previous, solve_instant
from ..solver.projection import RECOGNISED, on_bound
from ..solver.state import State
from ..solver.warm_start import continued_start, self_similar_start
from ..solver.window import solve_in_window
from . import preload
from .cycles import run_cycles
from .preload import Path
from .problem import Problem, grid_coordinates

__all__ = ["simulate", "grid_coordinates", "State", "ResumeLockedError", "ResumeWarning",
           "ResumeNotice", "Interrupted", "signals_as_interrupt", "raise_if_signalled"]

class ResumeLockedError(LockedError):
    """Another process is running a resumable run of the same target."""


class ResumeWarning(UserWarning):
    """The resume state of a target was damaged or unusable: the run starts afresh."""


# --------------------------------------------------------------------------- one instant

def _step(pb: Problem, st: State, k: int, path: Path) -> dict:
    """Solve instant ``k`` from ``st`` (updated in place); return its record. ``path``
    says how the first instant's preload is solved (:class:`.preload.Path`)."""
    first = k == 0
    op = pb.ops.operator(pb.ops.instant_weights(st.memories))
    pairs0 = pb.ops.conv.pairs
    U = pb.history(st, k)
    T = np.array([pb.T1[k], pb.T2[k]])
    # the normal problem is unchanged from the previous instant: reuse its solution
    same_normal = (not first and pb.plan.coupling == "none" and pb.plan.memory == "none"
                   and _same_normal(pb.program, k) and st.normal is not None
                   and pb.wear is None)         # wear moves the gap at every step
    iterations, passes, f_last = 0, 0, 0.0
    q_before, p_before, c = st.q, st.p, pb.program.continuation(k)
    fractions = pb.fractions(first, _drive(pb.program, k), path.substeps)
    windowed = not first or fractions.size > 1 and pb.similar is not None   # solver.window
    for f in fractions:
        sub = pb.sub_plan(first)
        previous = Previous(st.q, st.u, st.p, st.normal if same_normal else None, st.motion)
        if f_last > 0.0 and pb.similar is not None:     # a preload sub-step: its start
            previous = self_similar_start(previous, f / f_last, pb.similar, pb.limits.tuning)
        elif pb.tang:                                   # a straight load path: its start
            previous = continued_start(previous, st.dq, c, st.dp, pb.limits.tuning)
        f_last = f
        res = (solve_in_window if windowed else solve_instant)(
            op, pb.grid.gap, U, f * pb.W[k], f * T, pb.grid.cell, pb.grid.mu, sub, previous,
            path.limits, controls=pb.controls(k, f))
        iterations += res.iterations
        passes += res.passes
        if not res.converged:
            if np.all(np.isfinite(res.p)):
                # a contact cut by the grid's edge is the cause (a solve may stall on it,
                # e.g. a flat gap over the whole grid): say so rather than the stall
                _check_edges(res.p, k, pb.t[k], pb.scene, stopped=res.failed)
            raise _failure(pb, k, T, res)
        _advance(pb, st, op, sub, U, res)
        _take_motions(pb, st, k, f, res)
    if fractions.size > 1 and not path.scratch:  # the preload's windows of the contact
        op.drop_windows()                           # (solver.window): the march makes its own
    st.dq, st.dp = st.q - q_before, st.p - p_before
    _check_edges(st.p, k, pb.t[k], pb.scene)
    for m in st.memories:
        if m is not None:
            m.commit(np.stack([st.q[0], st.q[1], st.p]))
    st.k = k
    return _record(pb, st, pb.W[k], T, iterations, passes, pb.ops.conv.pairs - pairs0)


def _same_normal(program, k) -> bool:
    """The normal sub-problem's controls (W | ω3, M1 | φ1, M2 | φ2) are those of k − 1."""
    rows = [0, 3, 4]
    return (np.array_equal(program.force[rows, k], program.force[rows, k - 1], equal_nan=True)
            and np.array_equal(program.motion[rows, k], program.motion[rows, k - 1],
                               equal_nan=True))


def _drive(program, k):
    """What drives the shear at instant k: the tangential forces, or (where they are not
    controlled) the tangential motions and the twist (nonzero when anything does)."""
    force, motion = program.at(k)
    if not program.general:
        return force[1:3]
    return np.nan_to_num(np.concatenate([force[[1, 2, 5]], motion[[1, 2, 5]]]))


def _take_motions(pb, st, k, f, res):
    """The rigid motions reached: the normal's (ω3, φ1, φ2), and the imposed value of
    every displacement-controlled freedom."""
    st.omega[2] = res.omega3
    st.phi[:2] = res.phi
    if pb.program.general:
        _, motion = pb.program.at(k)
        reached = st.motion
        imposed = ~np.isnan(motion)
        reached[imposed] = f * motion[imposed]
        st.omega[:] = reached[[1, 2, 0]]
        st.phi[:] = reached[3:]


def _advance(pb, st, op, sub, U, res):
    """Take a solved (sub-)instant into the state: slip, dissipation, rigid motion."""
    contact = res.p > 0
    if sub.tangential == "none" and pb.tang and pb.plan.coupling != "none" and not op.rigid:
        # frictionless preload on a coupled pair: the pressure still moves the surfaces
        # in-plane (K13, K23); record it, or the next step would take it for slip (an
        # instant without compliance, phi(0) = 0 on every body, moves nothing)
        res.u[:2] = U[:2] + op.coupling_to_tangential(res.p)
    if pb.tang:
        du = res.u[:2] - st.u[:2]
        rigid = res.domega[:, None, None]
        if res.dphi3 != 0.0:
            rigid = rigid + res.dphi3 * pb.grid.twist()
        ds = np.where(contact, rigid - du, 0.0)
        stick = contact & ~on_bound(np.hypot(res.q[0], res.q[1]), pb.grid.mu * res.p,
                                    RECOGNISED)
        ds[:, stick] = 0.0
        if pb.plan.tangential == "scalar":
            ds[1] = 0.0
        st.s = st.s + ds
        st.dissipation += float(np.sum(res.q * ds)) * pb.grid.cell
        if pb.wear is not None:         # the worn depth opens the gap (simulation.wear)
            pb.grid.gap = pb.wear.take(res.p, res.q, ds)
        st.omega[:2] += res.domega
        st.phi[2] += res.dphi3
    st.p, st.q, st.u = res.p, res.q, res.u
    st.normal = res.normal


def _failure(pb, k, T, res) -> ConvergenceError:
    """The error of an instant whose solve stopped, naming the sub-problem."""
    tk, W, mu = pb.t[k], pb.W[k], pb.scene.friction.largest
    twist = _twist_failure(pb, k, res)
    if twist is not None:
        return twist
    if res.failed == "sliding":
        return _sliding_failure(pb, k, res)
    if not pb.program.is_force(0):            # approach control: W is the one reached
        W = float(res.p.sum()) * pb.grid.cell
    if res.failed == "tangential" and np.hypot(*T) >= 0.99 * mu * W > 0:
        return GrossSlidingError(
            f"step {k} (t = {tk:.6g} s): the stick zone was lost under "
            f"|T| = {np.hypot(*T):.6g} N against mu * W = {mu * W:.6g} N "
            f"(residual {res.residual:.3g}); the contact slides as a whole, which "
            f"has no static solution under force control. Lower the tangential "
            f"force or refine the grid.")
    hint = ""
    if res.failed == "coupling":
        npass = f"{res.passes} pass" + ("es" if res.passes != 1 else "")
        hint = (f"; the normal-tangential passes did not settle in {npass} (the last one "
                f"left the pressure moving by {res.residual:.3g} of W; the pair couples "
                f"with Dundurs beta = {pb.beta:.2f}, mu = {pb.scene.friction.largest:g})"
                + "; raise solver.max_coupling_passes or take smaller load steps")
    rigid = (pb.ops.first if k == 0 else pb.ops.next).rigid
    if rigid and res.failed == "normal":
        return ConvergenceError(
            f"normal problem at step {k} (t = {tk:.6g} s) has no solution "
            f"({_loads(pb, k)}): this instant has no instantaneous elasticity (phi(0) = 0), "
            f"so an approach or a tilt that closes a gap, or a moment, would need an "
            f"infinite pressure; only a normal force without moments can be applied then: "
            f"start the approach, tilt or moment from 0 at time[0], or apply "
            f"load.normal_force")
    if not np.isfinite(res.residual):
        hint += ("; the computation overflowed float64 (the forces, moduli or lengths of "
                 "the scene are beyond its range)")
    if res.failed == "normal" and pb.program.general:
        keys = [key for i, key in zip((3, 4), pb.program.keys[3:5], strict=True)
                if key.startswith("moment")]
        if keys:
            hint += (f"; a force-controlled {' and '.join('load.' + k_ for k_ in keys)} may "
                     f"have no solution: the pressure centre M/W must lie inside the "
                     f"contact the geometry can make")
    return ConvergenceError(
        f"{res.failed} problem at step {k} (t = {tk:.6g} s) stopped after "
        f"{res.iterations} iterations, residual {res.residual:.3g} > tolerance "
        f"{pb.limits.tol:g} ({_loads(pb, k)}){hint}")


def _sliding_failure(pb, k, res) -> GrossSlidingError:
    """A force-controlled T at or above what the bounds carry (μW, or Σμp Δ with a
    friction map): gross sliding. Under approach control W is an outcome of the step, so
    this is found only here; a scene under force control is refused before the run."""
    W, T, capacity = res.sliding
    mu = pb.scene.friction
    what = (f"mu W = {capacity:.6g} N (mu = {mu.largest:g}, W = {W:.6g} N)"
            if not mu.mapped else f"the sum of mu p = {capacity:.6g} N (W = {W:.6g} N)")
    approach = not pb.program.is_force(0)
    open_ = (": the contact is open at this instant (no cell centre lies within the "
             "approach; a grid too coarse for the contact also leaves it open)") * (W <= 0)
    cause = "; under load.normal_approach W is what the approach gives" + open_
    fix = ("lower load.tangential_force, " + "raise load.normal_approach, " * approach
           + "or impose the motion (load.tangential_displacement)")
    return GrossSlidingError(
        f"at step {k} (t = {pb.t[k]:.6g} s) the tangential force |T| = {T:.6g} N reaches "
        f"{what}: gross sliding under force control has no static solution"
        f"{cause * approach}; {fix}")


def _loads(pb, k) -> str:
    """The instant's controlled values, for messages: 'W = 1000 N, T = (90, 0) N'."""
    force, motion = pb.program.at(k)
    if not pb.program.general:
        return f"W = {force[0]:.6g} N, T = ({force[1]:.6g}, {force[2]:.6g}) N"
    units = ("N", "N", "N", "N m", "N m", "N m")
    parts = []
    for i, (fname, mname) in enumerate(FREEDOMS):
        if not np.isnan(force[i]):
            parts.append(f"{fname} = {force[i]:.6g} {units[i]}")
        elif motion[i] != 0.0:
            parts.append(f"{mname} = {motion[i]:.6g} {'m' if i < 3 else 'rad'}")
    return ", ".join(parts)


def _twist_failure(pb, k, res):
    """A force-controlled torque the contact could not carry: gross slip in torsion."""
    if res.failed != "tangential" or not pb.program.is_force(5):
        return None
    M3 = float(pb.program.force[5, k])
    return GrossSlidingError(
        f"step {k} (t = {pb.t[k]:.6g} s): the stick zone was lost under load.moment3 = "
        f"{M3:.6g} N m ({_loads(pb, k)}; residual {res.residual:.3g}); the contact slides "
        f"as a whole in torsion, which has no static solution under force control. Lower "
        f"the moment, or impose the rotation (load.rotation3).")


def _check_edges(p, k, tk, scene, stopped=""):
    """GridError where the pressure p reaches the grid's edge (``stopped``: the
    sub-problem whose solve stopped with this p, named in the message). A periodic grid
    has no edge: its contact may cross the period's sides."""
    if scene.grid.periodic:
        return
    edge = np.concatenate([p[0], p[-1], p[:, 0], p[:, -1]])
    if np.any(edge > 0):
        load = scene.load
        tilts = [f"load.{key}" for key in ("moment1", "moment2", "rotation1", "rotation2")
                 if getattr(load, key) is not None]
        why = (f" ({' and '.join(tilts)} moves the contact off-centre: it would open at "
               f"the grid's edge)" if tilts else "")
        raise GridError(
            f"step {k} (t = {tk:.6g} s): the contact reached the edge of the grid "
            f"(grid.size = {scene.grid.size}){why}"
            + (f", and the {stopped} problem stopped short of its tolerance there"
               if stopped else "")
            + "; enlarge grid.size or set grid.size = \"auto\"")


def _record(pb, st, W, T, iterations, passes, pairs) -> dict:
    """The outputs of an instant, as the archive stores them."""
    p, q, u, omega, mu, cell = st.p, st.q, st.u, st.omega, pb.grid.mu, pb.grid.cell
    contact = p > 0
    h = np.where(contact, 0.0, np.maximum(pb.grid.gap + u[2] - omega[2], 0.0))
    status = np.zeros(p.shape, dtype=np.int8)
    if pb.tang:
        slip = contact & on_bound(np.hypot(q[0], q[1]), mu * p, RECOGNISED)
        status[contact] = 1
        status[slip] = 2
    else:
        status[contact] = np.where(np.broadcast_to(np.equal(mu, 0), p.shape), 2, 1)[contact]
    rec = {"p": p, "u3": u[2], "h": h, "status": status, "W": float(p.sum() * cell),
           "omega3": omega[2], "contact_area": float(np.count_nonzero(contact) * cell),
           "iterations": int(iterations), "fft_pairs": int(round(pairs))}
    rec.update(_moments(pb, st))
    if pb.tang:
        s = st.s
        rec.update({"q1": q[0], "q2": q[1], "u1": u[0], "u2": u[1], "s1": s[0], "s2": s[1],
                    "T1": float(q[0].sum() * cell), "T2": float(q[1].sum() * cell),
                    "omega1": omega[0], "omega2": omega[1],
                    "stick_area": float(np.count_nonzero(status == STATUS_STICK) * cell),
                    "dissipation": st.dissipation, "coupling_passes": int(passes)})
    return rec


def _moments(pb, st) -> dict:
    """The moments reached (M1 = Δ Σ p x2, M2 = Δ Σ p x1, M3 = Δ Σ (q2 x1 − q1 x2)) [N m]
    and the rotations (φ1, φ2, φ3) [rad], whichever way each is controlled."""
    p, q, cell = st.p, st.q, pb.grid.cell
    M3 = float(np.sum(q[1] * pb.grid.X1 - q[0] * pb.grid.X2)) * cell if pb.tang else 0.0
    return {"M1": float(np.sum(p * pb.grid.X2)) * cell, "M2": float(np.sum(p * pb.grid.X1)) * cell,
            "M3": M3, "phi1": float(st.phi[0]), "phi2": float(st.phi[1]),
            "phi3": float(st.phi[2])}


# --------------------------------------------------------------------------- the march

def _start(pb, path, attrs, ckpt):
    """The writer and the state to march from: fresh, or a checkpoint's (resumable runs).

    A resumable run says where it starts (:class:`ResumeNotice`) when it finds a resume
    state. A damaged resume state (unreadable checkpoint, truncated or inconsistent part
    file) is dropped with a :class:`ResumeWarning`, and the run starts afresh.
    """
    out = pb.scene.output
    names = variables_for(pb.tang)
    kw = {"precision": out.precision, "compress": out.compress}
    maps = pb.maps()
    if maps:
        kw["maps"] = maps
    st = State.initial(pb.grid.shape, pb.ops.new_memories())
    if path is None:
        return MemoryWriter(None, pb.grid.x1, pb.grid.x2, names, attrs,
                            capacity=pb.written(pb.t.size - 1), **kw), st
    if ckpt is not None:
        found = ckpt.found()
        try:
            saved = ckpt.load()
            if saved is not None:
                k, written = int(saved["k"]), int(saved["written"])
                if not (0 <= k < pb.t.size and written == pb.written(k)):
                    raise ValueError(f"instant {k} with {written} written does not fit the "
                                     f"scene's {pb.t.size} instants")
                st.restore(saved, k)
                writer = ArchiveWriter(path, pb.grid.x1, pb.grid.x2, names, attrs, resumable=True,
                                       resume_steps=written, **kw)
                warnings.warn(ResumeNotice(f"{path.name}: resuming from {_instant(pb, k)}, "
                                           f"its checkpoint ({written} instants written)"),
                              stacklevel=5)
                return writer, st
            if found:
                warnings.warn(ResumeNotice(f"{path.name}: no checkpoint of this scene to "
                                           f"resume from; starting from the first instant"),
                              stacklevel=5)
        except (ArchiveError, ValueError, KeyError) as e:
            warnings.warn(ResumeWarning(f"{path}: the resume state is damaged "
                                        f"({one_line(e, with_type=False)}); starting afresh"),
                          stacklevel=5)
            ckpt.discard()
            st = State.initial(pb.grid.shape, pb.ops.new_memories())
    return ArchiveWriter(path, pb.grid.x1, pb.grid.x2, names, attrs, resumable=ckpt is not None,
                         **kw), st


def _instant(pb, k) -> str:
    """``instant 155 of 300 (t = 0.516 s)``: where a resumable run stands."""
    return f"instant {k} of {pb.t.size - 1} (t = {float(pb.t[k]):.6g} s)"


def _checkpoint_on_interrupt(pb, writer, ckpt, st, whole, saved, err):
    """Checkpoint the instant ``whole`` the run completed (None: stopped inside an
    instant, the last checkpoint ``saved`` stands) and tell ``err`` where a resume
    continues."""
    if whole is not None and whole != saved:
        writer.flush()
        ckpt.save(whole, writer.steps, st.arrays())
        saved = whole
    err.resume_from = _instant(pb, saved) if saved is not None else "the first instant"


def _progress(scene, total, initial):
    from tqdm.auto import tqdm  # only with progress=True: tqdm is optional here
    return tqdm(total=total, initial=initial, desc=scene.name, unit="step")


def _march(pb, path, ckpt, accuracy_note, on_step, progress, checkpoint_seconds, wall0):
    """Every instant from the start state to the end; the archive (or Dataset).

    A signal is acted on between two instants (:func:`contactpipe._util.interrupts.deferred`),
    where the state is whole: a resumable run checkpoints the instant it reached, then
    stops; and just before the archive is renamed into place (nothing is published).
    """
    pre = preload.estimate(pb, _step)
    first = Path(pre["substeps"], pb.limits)
    writer, st = _start(pb, path, pb.attrs(accuracy_note, pre), ckpt)
    stride, last = int(pb.scene.output.stride), pb.t.size - 1
    bar = _progress(pb.scene, pb.t.size, st.k + 1) if progress else None
    last_ckpt = _time.perf_counter()
    # whole: the last instant whose state and record are complete (None inside an instant)
    whole = saved = st.k if st.k >= 0 else None
    try:
        with deferred():
            for k in range(st.k + 1, pb.t.size):
                raise_if_signalled()
                whole = None
                record = _step(pb, st, k, first)
                if k % stride == 0 or k == last:
                    writer.append(pb.t[k], record)
                whole = k
                if on_step is not None:
                    on_step(k, float(pb.t[k]), record)
                if bar is not None:
                    bar.update(1)
                if ckpt is not None and _time.perf_counter() - last_ckpt > checkpoint_seconds:
                    writer.flush()
                    ckpt.save(k, writer.steps, st.arrays())
                    saved, last_ckpt = k, _time.perf_counter()
            result = writer.close({"wall_time_s": _time.perf_counter() - wall0})
    except KeyboardInterrupt as err:    # Ctrl-C, SIGTERM, SIGHUP
        if ckpt is not None:            # keep the part file and checkpoint what was reached
            _checkpoint_on_interrupt(pb, writer, ckpt, st, whole, saved, err)
            writer.suspend()
        else:
            writer.abort()
        raise
    except BaseException:
        writer.abort()
        if ckpt is not None:
            ckpt.remove()
        raise
    finally:
        if bar is not None:
            bar.close()
    if ckpt is not None:
        ckpt.remove()
    return result


def _inputs(scene):
    """Files the scene reads, which its archive must not overwrite."""
    return [getattr(part, "file", None) for part in (scene.geometry, scene.indenter,
                                                     scene.halfspace)] + \
        [scene.friction.mu if scene.friction.mapped else None]


def simulate(scene, path=None, *, progress=False, tangential=None, coupling=None, tuning=None,
             fft=None, threads=None, on_step=None, resume=False, checkpoint_seconds=30.0):
    """Run one scene; return its labelled :class:`xarray.Dataset` (docs/archive.md).

    Parameters
    ----------
    scene : Scene
        A validated scene (:class:`contactpipe.Scene`).
    path : str or Path, optional
        Stream the instants into this netCDF archive (atomic: written to a temporary file,
        read back and checked, and renamed on success) and return the archive opened
        lazily. Its folder is created if missing. Without it the result is assembled in
        memory.
    progress : bool
        Show a progress bar over the time steps.
    tangential, coupling : str, optional
        Overrides of the inferred sub-models (:func:`contactpipe.planning.plan`), checked
        against the scene.
    fft, threads, tuning : optional
        Override ``solver.fft``, ``solver.threads`` and the solver's switches (``Tuning``).
    on_step : callable, optional
        Called after every instant as ``on_step(k, t_k, record)`` with the instant's
        outputs (a dict of arrays and numbers, as written to the archive).
    resume : bool
        With ``path``: the run is resumable. Its part file (``.NAME.resumable.part``)
        and a checkpoint (``.NAME.ckpt.npz``, every ``checkpoint_seconds`` and, on Ctrl-C,
        SIGTERM or SIGHUP, of the instant reached) stay beside the target when the run is
        interrupted or killed; the :class:`Interrupted` raised says in ``resume_from``
        where a resume continues. Calling again with ``resume=True`` continues from the
        last checkpoint of the same scene and says so (:class:`ResumeNotice`). Without
        a checkpoint it starts from the beginning (a :class:`ResumeNotice` says so when
        a part file was there), with a damaged one too (a :class:`ResumeWarning`). While
        it runs it holds ``.NAME.resume.lock``.
    checkpoint_seconds : float
        Wall time between checkpoints of a resumable run [s].

    Returns
    -------
    xarray.Dataset

    Raises
    ------
    OutputPathError
        ``path`` is empty, a directory, a device or another special file, or a file the
        scene reads; checked before any work.
    SceneError
        The run would need more memory than is available, or is estimated to take longer
        than ``solver.max_hours`` (1 h when absent; :func:`contactpipe.planning.estimate_resources`,
        checked before any work), or the scene's constants
        overflow the influence coefficients.
    ResumeLockedError
        Another process runs a resumable run of the same target; nothing is touched.
    ConvergenceError
        A solver missed its tolerance: the message names the step, the time, the
        sub-problem and the residual.
    GridError
        The contact reached the edge of the grid.

    Notes
    -----
    A scene with ``[wear]`` repeats its load program ``wear.cycles`` times on the wearing
    surface (:mod:`contactpipe.simulation.cycles`, docs/wear.md): the archive holds the
    last cycle's instants and the wear history over ``cycle``; it is written whole at the
    end, and a resumable one checkpoints at cycle boundaries.

    Ctrl-C, SIGTERM and SIGHUP raise :class:`Interrupted` (a ``KeyboardInterrupt``)
    while the run holds the main thread and no handler of the application is installed
    for them: at the end of the instant in progress (a second signal: at once), or just
    before the archive's rename, when nothing is published.
    """
    out = run_scene(scene, path, progress=progress, tangential=tangential, coupling=coupling,
                    tuning=tuning, fft=fft, threads=threads, on_step=on_step, resume=resume,
                    checkpoint_seconds=checkpoint_seconds)
    return out if path is None else open_archive(out)


def run_scene(scene, path=None, *, progress=False, tangential=None, coupling=None,
              tuning=None, fft=None, threads=None, on_step=None, resume=False,
              checkpoint_seconds=30.0):
    """:func:`simulate`, returning the archive's path (with ``path``) rather than the
    archive opened: for a caller that needs the file, not the data (the command line).
    Opening it lazily imports dask's arrays (0.23 s of a 2.06 s ``contactpipe run``).
    Without ``path``: the Dataset assembled in memory, as :func:`simulate` returns it."""
    wall0 = _time.perf_counter()
    if path is not None:
        path = check_output_path(path, "archive", inputs=_inputs(scene))
    scene, accuracy_note = resolve_accuracy(scene)
    pl = make_plan(scene, tangential=tangential, coupling=coupling)
    check_resources(estimate_resources(scene, pl, in_memory=path is None),
                    max_hours=scene.solver.max_hours)
    opts = (accuracy_note, on_step, progress, checkpoint_seconds, wall0)
    with signals_as_interrupt(only_default=True):
        return _run(Problem(scene, pl, fft, threads, tuning), path, resume, opts)


def _start_record(pb, st) -> dict:
    """The record of the state ``st`` as it stands (a wear cycle's start)."""
    return _record(pb, st, pb.W[0], None, 0, 0, 0)


def _go(pb, path, ckpt, opts):
    """March ``pb``, or repeat its program for a wear run (:mod:`.cycles`, written whole
    at its end)."""
    if pb.wear is not None:
        return run_cycles(pb, path, _step, _start_record, opts, ckpt)
    return _march(pb, path, ckpt, *opts)


def _run(pb, path, resume, opts):
    """March ``pb`` in memory (``path`` None: the Dataset), into a new archive, or
    resumably (the archive's path)."""
    if path is None:
        return _go(pb, None, None, opts)
    try:
        make_folder(path.parent)
    except OSError as e:
        raise OutputPathError(f"archive {path}: cannot create its folder "
                              f"({e.strerror or one_line(e)})") from None
    if not resume:
        return _go(pb, path, None, opts)
    lock = resume_lock(path)
    with exclusive_lock(lock, f"resumable run of {path.name}", error=ResumeLockedError):
        ckpt = Checkpoint(path, pb.scene.digest())
        ckpt.clean()                    # what a run killed while checkpointing left
        try:
            result = _go(pb, path, ckpt, opts)
        finally:
            lock.unlink(missing_ok=True)
    return result

