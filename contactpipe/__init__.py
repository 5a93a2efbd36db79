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
from ._version import __version__

from .exceptions import (ArchiveError, ContactpipeError, ConvergenceError, GridError,
                         GrossSlidingError, SceneError)
from .scene import Scene
from .planning import Plan, plan
from .simulation import simulate
from .archive import open_archive, save
from .stress import subsurface_stress
from .fatigue import fatigue
# the pipeline stages: bound after their modules so the names are the functions
from .pipeline.compare import compare
from .pipeline.sweep import open_sweep, sweep

__all__ = [
    "__version__", "Scene", "simulate", "save", "open_archive", "plan", "Plan",
    "SceneError", "ConvergenceError", "GrossSlidingError", "GridError", "ArchiveError",
    "ContactpipeError", "sweep", "open_sweep", "compare", "subsurface_stress", "fatigue",
]
