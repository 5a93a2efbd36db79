"""What the stages read from an archive besides its variables: its cell grid, its scene,
the rows through its centre, and the radius of an area; and the dask scheduler they read
with (:func:`local_reads`).

The lowest module of :mod:`contactpipe.pipeline`: the comparison, the figures and the
sweeps all use these, so each is written once.
"""
from __future__ import annotations

import math
import os

import numpy as np
import xarray as xr

from ..archive import open_archive
from ..exceptions import ArchiveError, SceneError
from ..scene import Scene

__all__ = ["grid_of", "centre_rows", "radius_of_area", "scene_of", "scene_digest",
           "local_reads"]


def local_reads(synchronous: bool = False):
    """A dask configuration (a context manager) that computes the lazy arrays of an
    archive on this process's threads, or with ``synchronous`` on the calling thread
    alone: the schedulers dask would choose for them. Named outright, the scheduler
    spares the import of dask.distributed (0.1-0.2 s) that dask makes to look for a
    client when left to choose, so that ``contactpipe plot``, ``compare`` and ``stress``
    import no more than they use."""
    import dask
    import dask.local
    import dask.threaded
    return dask.config.set(scheduler=dask.local.get_sync if synchronous else dask.threaded.get)


def scene_of(ds) -> Scene:
    """The :class:`~contactpipe.Scene` of an archive.

    Parameters
    ----------
    ds : xarray.Dataset, Scene or path
        An archive (its ``scene`` attribute, the scene as TOML text, is read), a scene
        (returned as it is), or the path of an archive (opened for its attribute only,
        then closed).

    Raises
    ------
    ArchiveError
        No ``scene`` attribute, or one that is not a valid scene; a path that is not an
        archive.
    """
    if isinstance(ds, Scene):
        return ds
    if isinstance(ds, (str, os.PathLike)):
        with open_archive(ds) as opened:
            return scene_of(opened)
    text = ds.attrs.get("scene") if isinstance(ds, xr.Dataset) else None
    if not isinstance(text, str):
        raise ArchiveError("the dataset has no 'scene' attribute (the scene as TOML text): "
                           "not a contactpipe archive")
    try:
        return Scene.from_toml_text(text)
    except SceneError as err:
        raise ArchiveError(f"the archive's 'scene' attribute is not a valid scene: {err}") \
            from None


def scene_digest(ds) -> str:
    """:meth:`Scene.digest` of an archive's ``scene`` attribute (what a sweep names the
    archive by); ArchiveError as :func:`scene_of`."""
    return scene_of(ds).digest()


def grid_of(ds) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(x1 [m], x2 [m], d1 [m], d2 [m]): the cell centres and spacings of an archive.

    The spacings come from the coordinates when there are two cells or more along each
    axis, else from the ``grid_spacing_m`` attribute, else from the archive's scene.
    """
    x1 = np.asarray(ds["x1"].values, float)
    x2 = np.asarray(ds["x2"].values, float)
    sp = ds.attrs.get("grid_spacing_m")
    if x1.size > 1 and x2.size > 1:
        d1, d2 = float(x1[1] - x1[0]), float(x2[1] - x2[0])
    elif sp is not None and np.size(sp) == 2:
        d1, d2 = (float(v) for v in np.asarray(sp).ravel())
    else:
        d1, d2 = scene_of(ds).resolved_grid().spacing()
    return x1, x2, d1, d2


def centre_rows(x2) -> np.ndarray:
    """Indices of the row(s) through the centre of a grid: the one with x2 = 0, or for an
    even grid the two middle rows (x2 nearest 0), which the figures average."""
    ax = np.abs(np.asarray(x2, float))
    return np.flatnonzero(ax <= ax.min() * (1 + 1e-9) + 1e-15)


def radius_of_area(area) -> float:
    """Radius [m] of the circle of area ``area`` [m²] (0 for a negative area)."""
    return math.sqrt(max(float(area), 0.0) / math.pi)
