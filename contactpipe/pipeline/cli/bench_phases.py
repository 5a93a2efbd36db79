"""The ``phases`` case of ``contactpipe bench``: where a step's wall time goes, against its
FFT floor.

The floor of a step (pairs x the time of one FFT pair, :func:`.bench_scenes.floor_ms`) counts one
kernel product per pair. A step also spends spectral work the floor does not count in
full: the block operators' extra products (a 2 x 2 block has four products for two pairs),
the Parseval inners that give tᵀA t from spectra, the preconditioner's filters (counted a
quarter of a pair per field), and the copies into and out of the transforms' buffers. This
case times that work where the solver does it, on the five cases the solver's speed is
judged on (``fretting`` steel on aluminium, scalar at 128² and 256², vector at 128²; steel
on steel, vector, 128²; ``paper-fig3``, scalar), and splits each step into

``transforms``  the padded grids' forward and inverse transforms (pyFFTW's plans);
``filters``     the preconditioners' filters on the unpadded grids (their transforms and
                symbol products);
``products``    the kernel products and the buffers' copies of the convolution engine and
                of the block operators;
``inners``      the block operators' Parseval inners;
``rest``        everything else: the CG's element-wise work (gradients, working sets,
                projections, conjugation), the passes' bookkeeping, the history, Python.

``spectral`` is the sum of the first four; ``spectral_over_floor`` is the least wall/floor
any implementation of the other work could reach with these transforms and products.

How it is measured: each scene runs twice after a warm-up run (plans, spectra). The first
run, plain, gives the wall time a step (as :func:`.bench_scenes.timed_run`); the second runs under
:mod:`cProfile`, switched on once the first instant is done and blind to C calls
(``builtins=False``), and gives the spectral functions' time a step: each such call takes
60-600 µs at 128², and their sums agree, within the runs' spread of about 10 %, with a
timer wrapped round each of them. ``rest`` = wall − spectral. Per step after the first
instant, as the other cases; pyFFTW only (the transforms are timed in its plans'
``execute``).
"""
from __future__ import annotations

import cProfile
import pstats

from ...exceptions import SceneError
from .bench_scenes import (
    ALUMINIUM,
    STEEL,
    fretting_scene,
    load_average,
    pair_ms_around,
    paper_fig3_scene,
    timed_run,
)

__all__ = ["bench_phases", "PHASE_COLUMNS", "QUICK_PHASES", "spectral_functions"]

#: The columns of bench-phases.csv: what was run, the figures [ms a step, or ratios], where
#: and when.
PHASE_COLUMNS = ("case", "pair", "grid", "steps", "form", "pairs_per_step", "ms_per_step",
                 "pair_ms", "floor_ms_per_step", "spectral_ms_per_step",
                 "transforms_ms_per_step", "filters_ms_per_step", "products_ms_per_step",
                 "inners_ms_per_step", "rest_ms_per_step", "wall_over_floor",
                 "spectral_over_floor", "wall_over_spectral", "date", "commit", "cpus",
                 "load_average")
#: ``--quick``: the cases at 16², 5 steps (a smoke run of seconds).
QUICK_PHASES = dict(grids=(16, 16), steps=5)


def spectral_functions():
    """{phase: the functions whose time is that phase's}: the entry points of the spectral
    work (none calls another on pyFFTW's path, so their times add up), and the transforms
    inside them (their ``execute`` calls), whose time ``products`` leaves out."""
    from ...solver.blocks import BlockOperator
    from ...solver.convolution import Convolver
    c = Convolver
    return {"entry": (c.forward, c.inverse, c.forward_slot, c.inverse_add, c.convolve,
                      c.convolve_matrix, BlockOperator.product),
            "transforms": (c._execute_forward, c._execute_inverse),
            "filters": (c.periodic_filter,),
            "inners": (BlockOperator.inner,)}


def _seconds(stats, functions) -> float:
    """The functions' cumulative time in a :class:`pstats.Stats` [s]."""
    keys = {(f.__code__.co_filename, f.__code__.co_firstlineno, f.__code__.co_name)
            for f in functions}
    return sum(v[3] for k, v in stats.stats.items() if k in keys)


def _profiled(scene, form, tuning):
    """{phase: spectral seconds a step} of ``scene`` run under cProfile from the end of its
    first instant."""
    from ...simulation import simulate
    prof, marks = cProfile.Profile(builtins=False), []
    try:                                # Python 3.12+: one profiler at a time
        prof.enable()
        prof.disable()
    except ValueError as e:
        raise SceneError(f"bench phases: cProfile cannot run here ({e}); run it without "
                         "another profiler") from None

    def on_step(k, t, record):
        if not marks:
            prof.enable()
        marks.append(k)
    try:
        kw = {} if tuning is None else {"tuning": tuning}
        simulate(scene, tangential=form, on_step=on_step, **kw)
    finally:
        prof.disable()
    stats = pstats.Stats(prof)
    f = spectral_functions()
    entry, transforms = _seconds(stats, f["entry"]), _seconds(stats, f["transforms"])
    steps = max(len(marks) - 1, 1)
    return {"transforms": transforms / steps, "filters": _seconds(stats, f["filters"]) / steps,
            "products": (entry - transforms) / steps,
            "inners": _seconds(stats, f["inners"]) / steps}


def _both(scene, form, tuning):
    """(:func:`.bench_scenes.timed_run`'s plain run, :func:`_profiled`'s split [ms a
    step]) of ``scene``."""
    plain = timed_run(scene, form, tuning)
    return plain, {k: v * 1e3 for k, v in _profiled(scene, form, tuning).items()}


def _cases(grids, steps):
    """(label, bodies, form, grid, scene maker) of the five cases."""
    small, large = grids
    fig3_steps = 200 if steps is None else steps
    steps = 40 if steps is None else steps
    return [("fretting", "steel/Al", "scalar", small,
             lambda b, t: fretting_scene(ALUMINIUM, small, steps, b, t)),
            ("fretting", "steel/Al", "scalar", large,
             lambda b, t: fretting_scene(ALUMINIUM, large, steps, b, t)),
            ("fretting", "steel/Al", "vector", small,
             lambda b, t: fretting_scene(ALUMINIUM, small, steps, b, t)),
            ("fretting", "steel/steel", "vector", small,
             lambda b, t: fretting_scene(STEEL, small, steps, b, t)),
            ("paper-fig3", "rigid/Maxwell", "scalar", small,
             lambda b, t: paper_fig3_scene(small, fig3_steps, b, t))]


def bench_phases(backend, threads, grids=(128, 256), steps=None, tuning=None):
    """Print and return the phase split of a step (module doc) for the five cases,
    ``grids`` = (the 128² cases' grid, the 256² case's grid); ``steps`` None: 40 for
    fretting, 200 for paper-fig3; ``tuning``: the solver core's switches
    (:class:`contactpipe.solver.options.Tuning`; None: the defaults)."""
    from ...solver.convolution import HAVE_PYFFTW
    if backend == "scipy" or not HAVE_PYFFTW:
        raise SceneError(f"bench phases --fft {backend}: the transforms are timed in "
                         "pyFFTW's plans; allowed auto or pyfftw, with pyFFTW installed")
    print("where a step's time goes: spectral work timed in situ (cProfile, from the end "
          "of the first instant), the rest = wall − spectral; ms a step")
    print(f"{'case':>10} {'pair':>13} {'form':>6} {'grid':>5} {'pairs':>6} {'wall':>7} "
          f"{'floor':>6} {'transf':>6} {'filter':>6} {'prod':>6} {'inner':>6} {'rest':>6} "
          f"{'wall/fl':>7} {'spec/fl':>7}")
    rows = []
    for case, pair, form, n, make in _cases(grids, steps):
        scene = make(backend, threads)
        timed_run(scene, form, tuning)              # plans, spectra, wisdom
        ((ds, _, ms, load), split), pair_ms = pair_ms_around(
            n, backend, threads, _both, scene, form, tuning)
        pairs = float(ds.fft_pairs.values[1:].mean())
        floor, spectral = pairs * pair_ms, sum(split.values())
        r = dict(table="phases", case=case, pair=pair, grid=n, steps=ds.sizes["time"] - 1,
                 form=form,
                 pairs_per_step=pairs, ms_per_step=ms, pair_ms=pair_ms,
                 floor_ms_per_step=floor, spectral_ms_per_step=spectral,
                 **{f"{k}_ms_per_step": v for k, v in split.items()},
                 rest_ms_per_step=ms - spectral, wall_over_floor=ms / floor,
                 spectral_over_floor=spectral / floor, wall_over_spectral=ms / spectral,
                 load_average=max(load, load_average()))
        print(f"{case:>10} {pair:>13} {form:>6} {n:>5} {pairs:>6.1f} {ms:>7.2f} {floor:>6.2f} "
              f"{split['transforms']:>6.2f} {split['filters']:>6.2f} {split['products']:>6.2f} "
              f"{split['inners']:>6.2f} {ms - spectral:>6.2f} {ms / floor:>6.2f}x "
              f"{spectral / floor:>6.2f}x")
        rows.append(r)
    return rows

