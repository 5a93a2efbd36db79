"""The outer loop (paper §4): march the coupled contact through the temporal mesh.

At every instant t_k of the uniform mesh:

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
"""
from __future__ import annotations

import time as _time

import numpy as np

from .solver.coupling import solve_instant
from .exceptions import ConvergenceError, GridError, GrossSlidingError
from .files import atomic_path
from .accuracy import resolve_accuracy
from .solver.memory import make_memory
from .solver.operator import (ContactOperator, body_spectra, convolver, history_displacement,
                       history_kernels)
from .planning import plan as make_plan

__all__ = ["simulate", "grid_coordinates"]

FIELDS_NORMAL = ("p", "u3", "h", "status")
FIELDS_TANGENTIAL = ("q1", "q2", "u1", "u2", "s1", "s2")
SERIES_NORMAL = ("W", "omega3", "contact_area", "iterations", "fft_pairs")
SERIES_TANGENTIAL = ("T1", "T2", "omega1", "omega2", "stick_area", "dissipation",
                     "coupling_passes")


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


def simulate(scene, path=None, *, progress=False, tangential=None, coupling=None,
             fft=None, threads=None, on_step=None, resume=False, checkpoint_seconds=30.0):
    """Run one scene; return its labelled :class:`xarray.Dataset` (CONTRACT §3).

    Parameters
    ----------
    scene : Scene
        A validated scene (:class:`contactpipe.Scene`).
    path : str or Path, optional
        Stream the instants into this netCDF archive (atomic: written to a temporary file
        and renamed on success) and return the archive opened lazily. Without it the
        result is assembled in memory.
    progress : bool
        Show a progress bar over the time steps.
    tangential, coupling : str, optional
        Overrides of the inferred sub-models (:func:`contactpipe.planning.plan`), checked
        against the scene.
    fft, threads : optional
        Override ``solver.fft`` and ``solver.threads``.
    on_step : callable, optional
        Called after every instant as ``on_step(k, t_k, record)`` with the instant's
        outputs (a dict of arrays and numbers, as written to the archive).
    resume : bool
        With ``path``: the run is resumable. Its part file (``.NAME.resumable.part``)
        and a checkpoint (``.NAME.ckpt.npz``, every ``checkpoint_seconds``) stay beside the
        target when the run is interrupted (Ctrl-C, a killed process); calling again with
        ``resume=True`` continues from the last checkpoint of the same scene. Without a
        checkpoint it starts from the beginning.
    checkpoint_seconds : float
        Wall time between checkpoints of a resumable run [s].

    Returns
    -------
    xarray.Dataset

    Raises
    ------
    ConvergenceError
        A solver missed its tolerance: the message names the step, the time and the
        residual.
    GridError
        The contact reached the edge of the grid.
    """
    from .archive import ArchiveWriter, MemoryWriter, open_archive

    wall0 = _time.perf_counter()
    scene, accuracy_note = resolve_accuracy(scene)
    pl = make_plan(scene, tangential=tangential, coupling=coupling)
    sv = scene.solver
    x1, x2, d1, d2 = grid_coordinates(scene)
    n1, n2 = len(x1), len(x2)
    cell = d1 * d2
    gap = np.asarray(scene.geometry.gap(x1, x2), dtype=float)
    steps = _n_steps(scene)
    _warn_off_knots(scene, steps)
    t, W, T1, T2 = scene.load.instants(steps)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    W, T1, T2 = (np.broadcast_to(np.asarray(a, dtype=float), t.shape) for a in (W, T1, T2))
    dt = float(t[1] - t[0]) if t.size > 1 else 0.0
    mu = float(scene.friction.mu)

    backend = fft or sv.fft
    nthreads = threads or sv.threads
    b1, b2 = scene.indenter.body(), scene.halfspace.body()
    spec1 = body_spectra(b1, n1, n2, d1, d2, backend, nthreads)
    spec2 = body_spectra(b2, n1, n2, d1, d2, backend, nthreads)
    conv = convolver(n1, n2, backend, int(nthreads))

    # memory: one per viscoelastic body; tractions held as (q1, q2, p)
    mems = [None, None]
    if pl.memory != "none":
        for i, b in enumerate((b1, b2)):
            if b.has_memory:
                mems[i] = make_memory(b.creep, dt, pl.time_rule, (3, n1, n2))

    operators = {}

    def operator():
        """The operator of the next instant: one per distinct tuple of the memories'
        instantaneous weights (a time rule may weight t0, t1 and later steps apart)."""
        w = []
        for i, b in enumerate((b1, b2)):
            if b.rigid:
                w.append(0.0)
            elif mems[i] is None:
                w.append(float(b.creep.phi0) if b.has_memory else 1.0)
            else:
                w.append(float(mems[i].instant_weight))
        w = tuple(w)
        if w not in operators:
            operators[w] = ContactOperator(spec1, spec2, *w, conv)
        return operators[w]

    hist_kernels = history_kernels(spec1 if mems[0] is not None else None,
                                   spec2 if mems[1] is not None else None)

    tang = pl.tangential != "none"
    fields = list(FIELDS_NORMAL) + (list(FIELDS_TANGENTIAL) if tang else [])
    series = list(SERIES_NORMAL) + (list(SERIES_TANGENTIAL) if tang else [])
    attrs = {
        "title": f"contactpipe simulation: {scene.name}",
        "scene": scene.to_toml(),
        "models": pl.describe(),
        "model_normal": pl.normal, "model_tangential": pl.tangential,
        "model_coupling": pl.coupling, "model_memory": pl.memory,
        "time_rule": pl.time_rule, "preload": pl.preload,
        "dundurs_beta": _beta(b1, b2),
        "fft_backend": conv.backend,
        "grid_spacing_m": [d1, d2],
        "grid_points": [n1, n2],
        "time_steps": steps,
    }
    if accuracy_note:
        attrs["accuracy"] = accuracy_note
    out = scene.output
    ckpt = _Checkpoint(path, scene) if (path is not None and resume) else None
    state = ckpt.load() if ckpt is not None else None
    if path is not None:
        writer = ArchiveWriter(path, x1, x2, fields + series, attrs, precision=out.precision,
                               compress=out.compress, resumable=resume,
                               resume_steps=None if state is None else state["written"])
    else:
        writer = MemoryWriter(None, x1, x2, fields + series, attrs, precision=out.precision,
                              compress=out.compress)

    p = np.zeros((n1, n2))
    q = np.zeros((2, n1, n2))
    u = np.zeros((3, n1, n2))
    s = np.zeros((2, n1, n2))
    omega = np.zeros(3)
    dissipation = 0.0
    last_normal = None
    k_start = 0
    if state is not None:
        k_start = int(state["k"]) + 1
        p, q, u, s = state["p"], state["q"], state["u"], state["s"]
        omega, dissipation = np.array(state["omega"]), float(state["dissipation"])
        for i, m in enumerate(mems):
            if m is not None:
                m.load_state({key[len(f"mem{i}_"):]: v for key, v in state.items()
                              if key.startswith(f"mem{i}_")})
    stride = int(out.stride)
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=t.size, initial=k_start, desc=scene.name, unit="step")
    last_ckpt = _time.perf_counter()
    try:
        for k in range(k_start, t.size):
            first = k == 0
            op = operator()
            pairs0 = conv.pairs
            U = np.zeros((3, n1, n2))
            if any(m is not None for m in mems) and not first:
                h = [None if m is None else m.known() for m in mems]
                outputs = (1, 2, 3) if tang else (3,)
                Uh = history_displacement(hist_kernels, h[0], h[1], conv, outputs=outputs)
                U[[o - 1 for o in outputs]] = Uh
            T = np.array([T1[k], T2[k]])
            # the sub-steps of a frictional preload (instantaneous response at t0)
            if first and tang and pl.preload == "frictional" and \
                    (pl.coupling != "none" or np.any(T)):
                fractions = np.linspace(0.0, 1.0, int(sv.preload_substeps) + 1)[1:]
            else:
                fractions = np.array([1.0])
            iterations = 0
            passes = 0
            # the normal problem is unchanged from the previous instant: reuse its solution
            same_normal = (not first and pl.coupling == "none" and pl.memory == "none"
                           and W[k] == W[k - 1] and last_normal is not None)
            for f in fractions:
                if first and tang and pl.preload == "frictionless":
                    # the paper's initial frictionless normal solve, then shear from there
                    sub_plan = _frictionless(pl)
                else:
                    sub_plan = pl
                res = solve_instant(op, gap, U, f * W[k], f * T, cell, mu, q, u, p,
                                    sub_plan, sv.tolerance, sv.max_iterations,
                                    sv.max_coupling_passes,
                                    normal=last_normal if same_normal else None)
                iterations += res.iterations
                passes += res.passes
                if not res.converged and res.failed == "tangential" and \
                        np.hypot(*T) >= 0.99 * mu * W[k] > 0:
                    raise GrossSlidingError(
                        f"step {k} (t = {t[k]:.6g} s): the stick zone was lost under "
                        f"|T| = {np.hypot(*T):.6g} N against mu * W = {mu * W[k]:.6g} N "
                        f"(residual {res.residual:.3g}); the contact slides as a whole, which "
                        f"has no static solution under force control. Lower the tangential "
                        f"force or refine the grid.")
                if not res.converged:
                    hint = ""
                    if res.failed == "coupling":
                        hint = (f"; the normal-tangential passes did not settle in "
                                f"{res.passes} passes (strong coupling: large friction with "
                                f"Dundurs beta = {_beta(b1, b2):.2f}); raise "
                                f"solver.max_coupling_passes or take smaller load steps")
                    raise ConvergenceError(
                        f"{res.failed} problem at step {k} (t = {t[k]:.6g} s) stopped after "
                        f"{res.iterations} iterations, residual {res.residual:.3g} > tolerance "
                        f"{sv.tolerance:g} (W = {W[k]:.6g} N, T = ({T[0]:.6g}, {T[1]:.6g}) N)"
                        f"{hint}")
                contact = res.p > 0
                if sub_plan.tangential == "none" and tang and pl.coupling != "none":
                    # frictionless preload on a coupled pair: the pressure still moves the
                    # surfaces in-plane (K13, K23); record it, or the next step would take
                    # it for slip
                    res.u[:2] = U[:2] + op.coupling_to_tangential(res.p)
                if tang:
                    du = res.u[:2] - u[:2]
                    ds = np.where(contact, res.domega[:, None, None] - du, 0.0)
                    stick = contact & (np.hypot(res.q[0], res.q[1]) < mu * res.p * (1 - 1e-9))
                    ds[:, stick] = 0.0
                    if pl.tangential == "scalar":
                        ds[1] = 0.0
                    s = s + ds
                    dissipation += float(np.sum(res.q * ds)) * cell
                    omega[:2] += res.domega
                p, q, u = res.p, res.q, res.u
                last_normal = res.normal
            omega[2] = res.omega3
            _check_edges(p, k, t[k], scene)
            for i, m in enumerate(mems):
                if m is not None:
                    m.commit(np.stack([q[0], q[1], p]))
            record = _record(scene, pl, gap, p, q, u, s, omega, W[k], T, dissipation,
                             iterations, passes, conv.pairs - pairs0, mu, cell, tang)
            if k % stride == 0 or k == t.size - 1:
                writer.append(t[k], record)
            if on_step is not None:
                on_step(k, float(t[k]), record)
            if bar is not None:
                bar.update(1)
            if ckpt is not None and _time.perf_counter() - last_ckpt > checkpoint_seconds:
                writer.flush()
                ckpt.save(k, writer.steps, p, q, u, s, omega, dissipation, mems)
                last_ckpt = _time.perf_counter()
    except KeyboardInterrupt:
        if ckpt is not None:
            writer.suspend()           # keep the part file and the last checkpoint
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
    final = {"wall_time_s": _time.perf_counter() - wall0}
    result = writer.close(final)
    if ckpt is not None:
        ckpt.remove()
    if path is not None:
        return open_archive(result)
    return result


class _Checkpoint:
    """The state of a resumable run after a completed instant (``.NAME.ckpt.npz``)."""

    def __init__(self, path, scene):
        import pathlib
        self.path = pathlib.Path(path)
        self.file = self.path.with_name(f".{self.path.name}.ckpt.npz")
        self.digest = scene.digest()

    def load(self):
        from .archive import resumable_part
        if not (self.file.exists() and resumable_part(self.path).exists()):
            return None
        with np.load(self.file) as z:
            state = {k: z[k] for k in z.files}
        if str(state.pop("digest")) != self.digest:
            return None                  # another scene: start afresh
        return state

    def save(self, k, written, p, q, u, s, omega, dissipation, mems):
        arrays = {"digest": np.array(self.digest), "k": np.array(k),
                  "written": np.array(written), "p": p, "q": q, "u": u, "s": s,
                  "omega": omega, "dissipation": np.array(dissipation)}
        for i, m in enumerate(mems):
            if m is not None:
                arrays.update({f"mem{i}_{key}": np.asarray(v) for key, v in m.state().items()})
        with atomic_path(self.file) as tmp, open(tmp, "wb") as f:
            np.savez(f, **arrays)

    def remove(self):
        self.file.unlink(missing_ok=True)


def _warn_off_knots(scene, steps):
    """A load knot between mesh instants is cut off (a turning point of a fretting loop
    is never reached): say so, with the step counts that would hold every knot."""
    t = np.asarray(scene.load.knots()[0], dtype=float)
    if t.size < 3 or steps < 1:
        return
    pos = (t[1:-1] - t[0]) / (t[-1] - t[0]) * steps
    off = np.abs(pos - np.round(pos)) > 1e-6
    if off.any():
        import warnings
        from .accuracy import knot_multiple
        m = knot_multiple(scene)
        hint = f"; use a multiple of {m} steps" if m else ""
        warnings.warn(f"time.steps = {steps}: the load knots at t = "
                      f"{', '.join(f'{x:g}' for x in t[1:-1][off])} s fall between instants of "
                      f"the time mesh, so the program is cut there{hint}", stacklevel=3)


def _frictionless(pl):
    from dataclasses import replace
    return replace(pl, tangential="none", coupling="none")


def _beta(b1, b2):
    from .materials import dundurs_beta
    return float(dundurs_beta(b1, b2))


def _check_edges(p, k, tk, scene):
    edge = np.concatenate([p[0], p[-1], p[:, 0], p[:, -1]])
    if np.any(edge > 0):
        raise GridError(
            f"step {k} (t = {tk:.6g} s): the contact reached the edge of the grid "
            f"(grid.size = {scene.grid.size}); enlarge grid.size or set grid.size = \"auto\"")


def _record(scene, pl, gap, p, q, u, s, omega, W, T, dissipation, iterations, passes,
            pairs, mu, cell, tang):
    contact = p > 0
    h = np.where(contact, 0.0, np.maximum(gap + u[2] - omega[2], 0.0))
    status = np.zeros(p.shape, dtype=np.int8)
    if tang:
        slip = contact & (np.hypot(q[0], q[1]) >= mu * p * (1 - 1e-9))
        status[contact] = 1
        status[slip] = 2
    else:
        status[contact] = 2 if mu == 0 else 1
    rec = {"p": p, "u3": u[2], "h": h, "status": status, "W": float(p.sum() * cell),
           "omega3": omega[2], "contact_area": float(np.count_nonzero(contact) * cell),
           "iterations": int(iterations), "fft_pairs": int(round(pairs))}
    if tang:
        rec.update({"q1": q[0], "q2": q[1], "u1": u[0], "u2": u[1], "s1": s[0], "s2": s[1],
                    "T1": float(q[0].sum() * cell), "T2": float(q[1].sum() * cell),
                    "omega1": omega[0], "omega2": omega[1],
                    "stick_area": float(np.count_nonzero(status == 1) * cell),
                    "dissipation": dissipation, "coupling_passes": int(passes)})
    return rec
