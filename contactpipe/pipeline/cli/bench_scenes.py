"""The scenes and clocks of ``contactpipe bench``'s cases, shared by :mod:`.bench`,
:mod:`.bench_phases` and :mod:`.bench_wear`: the bodies (a steel sphere, R = 18 mm, on
steel or aluminium, W = 1 kN; μ = 0.1 but in ``wear``), the fretting and paper-fig3
scenes, the time of one FFT pair (the floor's unit), the load average and a run timed
step by step.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

from ...scene import Scene

__all__ = ["ALUMINIUM", "A_HERTZ", "E_STEEL", "MU", "NU", "R", "STEEL", "W", "floor_ms",
           "fretting_scene", "load_average", "make_scene", "pair_ms_around",
           "paper_fig3_scene", "timed_run"]

E_STEEL, NU, R, W, MU = 210e9, 0.3, 0.018, 1000.0, 0.1
A_HERTZ = (3 * W * R / (4 / (2 * (1 - NU ** 2) / E_STEEL))) ** (1 / 3)
STEEL = {"material": "elastic", "young": E_STEEL, "poisson": NU}
ALUMINIUM = {"material": "elastic", "young": 70e9, "poisson": 0.33}


def make_scene(**kw):
    """A scene of the bench: a steel sphere (R = 18 mm) on a steel half-space, the
    tables ``kw`` added or put in their place."""
    d = {"name": "bench", "geometry": {"shape": "sphere", "radius": R},
         "indenter": dict(STEEL), "halfspace": dict(STEEL)}
    d.update(kw)
    return Scene(**d)


def _fretting_load():
    """The loop T: 0 → .9μW → −.9μW → .9μW under W, over a second."""
    Ts = 0.9 * MU * W
    return {"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W,
            "tangential_force": [0.0, Ts, -Ts, Ts]}


def fretting_scene(half, n, steps, backend, threads):
    """The ``fretting`` case's scene: the steel sphere on the half-space ``half`` (a
    material table), the loop of :func:`_fretting_load` over ``steps`` steps, n x n cells
    over 3a."""
    return make_scene(halfspace=dict(half), friction={"mu": MU}, load=_fretting_load(),
                      grid={"points": [n, n], "size": [3 * A_HERTZ] * 2},
                      time={"steps": steps}, solver={"fft": backend, "threads": threads})


def paper_fig3_scene(n, steps, backend, threads):
    """The ``paper-fig3`` case's scene: a rigid sphere on a Maxwell half-space (glassy
    E = 105 GPa, ν = 0.3), the same loop over τ = t′, n x n cells sized from Hertz."""
    return make_scene(indenter={"material": "rigid"},
                      halfspace={"material": "viscoelastic", "young": 105e9, "poisson": NU,
                                 "creep": "maxwell", "relaxation_time": 1.0},
                      friction={"mu": MU}, load=_fretting_load(),
                      grid={"points": [n, n], "size": "auto"}, time={"steps": steps},
                      solver={"fft": backend, "threads": threads})


def floor_ms(n, backend, threads, blocks=3):
    """(milliseconds of one FFT pair of the padded n x n grid, plan time [s]).

    One pair as the solver's engine spends it (:meth:`Convolver.convolve`: forward
    transform, product with a kernel spectrum, inverse transform), on an engine made as the
    solver makes its own (same backend, threads and planner; with FFTW's wisdom, the same
    plans); the least of ``blocks`` timed blocks, so that a busy moment does not count.
    """
    from ...solver.convolution import Convolver  # pyfftw: only when a case runs
    conv = Convolver(n, n, backend=backend, threads=threads)
    k = conv.kernel_spectrum(np.ones((2 * n, 2 * n)))
    x = np.random.default_rng(0).normal(size=(n, n))
    reps = max(5, min(2000, int(2e6 / (n * n))))
    conv.convolve(k, x)
    best = math.inf
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(reps):
            conv.convolve(k, x)
        best = min(best, (time.perf_counter() - t0) / reps)
    return best * 1e3, conv.plan_time_s


def pair_ms_around(n, backend, threads, run, *args):
    """(``run(*args)``, the time of one FFT pair [ms] measured just before and just
    after it by :func:`floor_ms`, the lesser kept): a busy moment on either side of the
    run does not raise the floor the run is judged against."""
    before = floor_ms(n, backend, threads)[0]
    out = run(*args)
    return out, min(before, floor_ms(n, backend, threads)[0])


def load_average() -> float:
    """The one-minute load average, NaN where the system does not tell."""
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan


def timed_run(scene, form=None, tuning=None):
    """Run ``scene`` in memory: (dataset, the run's wall time [s], the wall time of a step
    after the first instant [ms], the one-minute load average, the higher of before and
    after).

    A step's time is that from the end of the first instant to the end of the last step,
    over the steps between: the setup (FFT plans, kernel spectra) and the first instant
    (its frictional preload, its error estimate) are left out, as the per-step pairs
    leave them out. NaN for a run of one instant. ``tuning``: the solver core's switches
    (:class:`contactpipe.solver.options.Tuning`; None: the defaults).
    """
    from ...simulation import simulate  # the solver and the FFTs: only when a case runs
    stamps = []
    load = load_average()
    kw = {} if form is None else {"tangential": form}
    if tuning is not None:
        kw["tuning"] = tuning
    t0 = time.perf_counter()
    ds = simulate(scene, on_step=lambda k, t, rec: stamps.append(time.perf_counter()), **kw)
    run_s = time.perf_counter() - t0
    steps = len(stamps) - 1
    ms = (stamps[-1] - stamps[0]) / steps * 1e3 if steps > 0 else math.nan
    return ds, run_s, ms, max(load, load_average())
