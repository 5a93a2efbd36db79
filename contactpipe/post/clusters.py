"""Stick and slip clusters of an archive: the connected patches of each contact status at
each instant, counted as the run reported them (the ``status`` field), for rough contacts
whose contact breaks into islands.

Two cells belong to one cluster when they share an edge (4-connectivity: cells touching
at a corner only are apart, as two asperities meeting at a point carry no shared
traction) and have the same status: stick, slip, or in contact (stick or slip). On a
periodic grid (``grid.boundary = "periodic"``) the first and last rows and columns are
neighbours too, so a cluster that crosses the period's edge counts once.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from ..nomenclature import STATUS_SEPARATED, STATUS_SLIP, STATUS_STICK

__all__ = ["count_clusters", "contact_clusters", "is_periodic"]


def count_clusters(mask, periodic: bool = False) -> int:
    """Edge-connected clusters of the True cells of a 2-D ``mask``; with ``periodic`` the
    grid wraps round in both directions (one period of an infinite surface)."""
    from scipy.ndimage import label

    labels, n = label(np.asarray(mask, dtype=bool))
    if not periodic or n < 2:
        return int(n)
    root = np.arange(n + 1)

    def find(i):
        while root[i] != i:
            root[i] = root[root[i]]
            i = root[i]
        return i

    # cells facing each other across the period's edges: the last row and the first, the
    # last column and the first
    for a, b in ((labels[-1, :], labels[0, :]), (labels[:, -1], labels[:, 0])):
        for i, j in {(int(i), int(j)) for i, j in zip(a, b, strict=True) if i and j}:
            ri, rj = find(i), find(j)
            if ri != rj:
                root[max(ri, rj)] = min(ri, rj)
    return len({find(i) for i in range(1, n + 1)})


def is_periodic(ds: xr.Dataset) -> bool:
    """Whether an archive's scene is one period of a surface (``grid.boundary``)."""
    from .._util.files import loads_toml
    from ..exceptions import SceneError

    try:
        scene = loads_toml(str(ds.attrs.get("scene", "")))
    except SceneError:                          # no scene, or not TOML: a free grid
        return False
    return scene.get("grid", {}).get("boundary") == "periodic"


def contact_clusters(ds: xr.Dataset) -> xr.Dataset:
    """Counts of the contact, stick and slip clusters at each instant of an archive.

    Parameters
    ----------
    ds : xarray.Dataset
        An archive with ``status`` over (time, x1, x2).

    Returns
    -------
    xarray.Dataset
        ``contact_clusters``, ``stick_clusters``, ``slip_clusters`` over ``time`` (int32).
    """
    status, periodic = np.asarray(ds["status"].values), is_periodic(ds)
    out = {name: np.array([count_clusters(test(s), periodic) for s in status],
                          dtype=np.int32)
           for name, test in (("contact_clusters", lambda s: s != STATUS_SEPARATED),
                              ("stick_clusters", lambda s: s == STATUS_STICK),
                              ("slip_clusters", lambda s: s == STATUS_SLIP))}
    attrs = {"units": "1", "long_name": "edge-connected clusters of cells"}
    return xr.Dataset({k: ("time", v, attrs) for k, v in out.items()},
                      coords={"time": ds["time"].values})
