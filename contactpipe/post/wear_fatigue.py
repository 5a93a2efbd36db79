"""Fatigue against wear: a fatigue criterion on each kept loop of a wear run, so that its
largest value can be followed over the cycles.

A wear run keeps the loop of tractions of some recorded cycles (``wear.keep_tractions``):
``loop_p``, ``loop_q1``, ``loop_q2`` over (loop_cycle, loop_time, x1, x2). Each loop is a
whole cycle of the worn contact; its subsurface stress (:func:`contactpipe.subsurface_stress`
at the depths asked) over the loop's instants is the stress history a criterion
(:func:`contactpipe.fatigue`: Crossland, SWT, Dang Van, amplitude) needs. The result is,
over ``cycle`` (the kept cycles), the criterion's largest value and where it is.

    >>> fc = fatigue_over_cycles("wear.nc", x3=[0, 2e-5, 5e-5], criterion="crossland",
    ...                          torsion_limit=300e6, bending_limit=450e6)
    >>> fc.maximum.plot()          # the largest Crossland index against cycles
"""
from __future__ import annotations

import os

import numpy as np
import xarray as xr

from .._version import __version__
from ..archive import open_archive
from ..exceptions import ArchiveError
from .fatigue import fatigue
from .stress import subsurface_stress

__all__ = ["fatigue_over_cycles", "kept_cycles", "loop_tractions", "LOOP_VARIABLES"]

#: The kept loops of tractions and what each becomes in a loop's archive-like Dataset.
LOOP_VARIABLES = {"loop_p": "p", "loop_q1": "q1", "loop_q2": "q2"}


def kept_cycles(ds) -> list[int]:
    """The cycles whose loop of tractions the archive keeps (loop_cycle), [] for none."""
    if "loop_p" not in ds.data_vars or "loop_cycle" not in ds.coords:
        return []
    return [int(c) for c in np.asarray(ds["loop_cycle"].values)]


def _require_loops(ds) -> list[int]:
    kept = kept_cycles(ds)
    if not kept:
        what = ("a wear run that kept no loop of tractions (give wear.keep_tractions > 0)"
                if "cycle" in ds.dims else "not the archive of a wear run (no 'cycle')")
        raise ArchiveError(f"fatigue over cycles needs the kept loops of tractions "
                           f"(loop_p over loop_cycle, loop_time, x1, x2): this archive is "
                           f"{what}")
    return kept


def loop_tractions(ds: xr.Dataset, cycle: int) -> xr.Dataset:
    """The kept loop of ``cycle`` as tractions over (time, x1, x2): ``p``, ``q1``, ``q2``
    of every instant of that cycle (time: since the cycle's start [s]), with the archive's
    attributes (its scene gives the bodies' Poisson ratios).

    Raises
    ------
    ArchiveError
        The archive keeps no loops; ValueError: ``cycle`` is not one of the kept cycles.
    """
    kept = _require_loops(ds)
    if int(cycle) not in kept:
        raise ValueError(f"cycle = {cycle!r}: the archive keeps the loops of cycles "
                         f"{', '.join(map(str, kept))}")
    j = kept.index(int(cycle))
    names = [n for n in LOOP_VARIABLES if n in ds.data_vars]
    out = ds[names].isel(loop_cycle=j, drop=True).rename(
        {**{n: LOOP_VARIABLES[n] for n in names}, "loop_time": "time"})
    out = out.drop_vars([c for c in out.coords if c not in ("time", "x1", "x2")])
    out.attrs = dict(ds.attrs)
    return out


def _history(kept, rows, criterion, field, units, x3, body) -> xr.Dataset:
    cyc = xr.Variable("cycle", np.asarray(kept, np.int64),
                      {"units": "1", "long_name": "cycles completed at the kept loop's end"})
    data = {"maximum": xr.Variable("cycle", [r[0] for r in rows],
                                   {"units": units, "long_name": f"largest {field} of the "
                                    f"kept cycle's loop"})}
    for n, ax in enumerate(("x1", "x2", "x3"), start=1):
        data[f"maximum_{ax}"] = xr.Variable("cycle", [r[n] for r in rows],
                                            {"units": "m", "long_name": f"{ax} of the "
                                             f"largest {field}"})
    out = xr.Dataset(data, coords={"cycle": cyc})
    out.attrs = {"Conventions": "CF-1.10",
                 "title": f"fatigue criterion {criterion} over a wear run's kept cycles",
                 "contactpipe_version": __version__, "criterion": criterion,
                 "criterion_field": field, "body": body,
                 "x3": np.asarray(x3, float)}
    return out


def fatigue_over_cycles(ds, x3, criterion: str = "crossland", *, body: str = "halfspace",
                        poisson=None, fft: str = "auto", **constants) -> xr.Dataset:
    """A fatigue criterion's largest value over each kept loop of a wear run.

    Parameters
    ----------
    ds : xarray.Dataset or path
        The archive of a wear run that kept loops of tractions (opened verified when a
        path).
    x3 : float or sequence of float
        Depths into ``body`` [m] where the criterion is evaluated (the surface, 0, is
        where fretting cracks start; a few depths down to about the contact radius / 2
        catch the subsurface peak).
    criterion : {"crossland", "swt", "dang_van", "amplitude"}
        The criterion of :func:`contactpipe.fatigue`, with its ``**constants``.
    body, poisson, fft
        As for :func:`contactpipe.subsurface_stress`.

    Returns
    -------
    xarray.Dataset
        Over ``cycle`` (the kept cycles): ``maximum`` (the criterion's main field, its
        largest value over the points of that loop) and ``maximum_x1``, ``maximum_x2``,
        ``maximum_x3`` [m] where it is. Attributes: criterion, criterion_field, body.

    Raises
    ------
    ArchiveError
        Not a wear archive, or one without kept loops.
    ValueError
        As :func:`contactpipe.subsurface_stress` and :func:`contactpipe.fatigue`.
    """
    if isinstance(ds, (str, os.PathLike)):
        with open_archive(ds, verify=True) as opened:
            return fatigue_over_cycles(opened.load(), x3, criterion, body=body,
                                       poisson=poisson, fft=fft, **constants)
    kept = _require_loops(ds)
    rows, field, units = [], criterion, "1"
    for cycle in kept:
        loop = loop_tractions(ds, cycle)
        st = subsurface_stress(loop, x3, body, time="all", chunks=False, poisson=poisson,
                               fft=fft)
        fi = fatigue(st, criterion, **constants)
        field = fi.attrs["criterion_field"]
        units = fi["maximum"].attrs.get("units", "1")
        rows.append(tuple(float(fi[v].values) for v in
                          ("maximum", "maximum_x1", "maximum_x2", "maximum_x3")))
    return _history(kept, rows, criterion, field, units, x3, body)
