"""contactpipe: frictional stick-slip contact of elastic and linear viscoelastic bodies.

Semi-analytical method (SAM) after Spinu et al., "A numerical solution to the
Cattaneo-Mindlin problem for viscoelastic materials": only the contact surface is meshed,
tractions are piecewise constant on an N1 x N2 grid, displacements come from influence
coefficients by DC-FFT. Every simulation returns a labelled :class:`xarray.Dataset`
(dimensions ``time``, ``x1``, ``x2``); archives are netCDF files written atomically.

    >>> import contactpipe as cp
    >>> scene = cp.Scene.from_toml("scene.toml")
    >>> ds = cp.simulate(scene)
    >>> cp.save(ds, "run.nc")

All quantities are SI (m, s, N, Pa, J); see docs/conventions.md for signs.
"""
from __future__ import annotations

import importlib
import sys
import types

from ._version import __version__
from .exceptions import (
    ArchiveError,
    ContactpipeError,
    ConvergenceError,
    GridError,
    GrossSlidingError,
    SceneError,
)

#: Public names and the modules that define them, imported on first use (module
#: ``__getattr__``): ``import contactpipe`` stays light (no xarray, dask, scipy, pyfftw),
#: so that the command line refuses a bad scene in a fraction of a second.
_LAZY = {
    "Scene": "scene", "Plan": "planning", "plan": "planning", "simulate": "simulation",
    "open_archive": "archive", "save": "archive", "subsurface_stress": "post.stress",
    "fatigue": "post.fatigue", "compare": "pipeline.compare", "open_sweep": "pipeline.sweep",
    "sweep": "pipeline.sweep", "fatigue_over_cycles": "post.wear_fatigue",
}

__all__ = [
    "__version__", "Scene", "simulate", "save", "open_archive", "plan", "Plan",
    "SceneError", "ConvergenceError", "GrossSlidingError", "GridError", "ArchiveError",
    "ContactpipeError", "sweep", "open_sweep", "compare", "subsurface_stress", "fatigue",
    "fatigue_over_cycles",
]


def __getattr__(name):
    module = _LAZY.get(name)
    if module is not None:
        value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    else:
        try:                             # a subpackage or module: cp.analytic, cp.post
            value = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as err:
            if err.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


class _Package(types.ModuleType):
    """The package: ``contactpipe.fatigue`` stays the function :func:`fatigue` when the
    module of the same name is imported (the import system binds a submodule to its
    parent's attribute; here that binding is kept off the public name)."""

    def __setattr__(self, name, value):
        if name in _LAZY and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
