"""Stick and slip clusters of an archive: the connected patches of each contact status at
each instant, counted as the run reported them (the ``status`` field), for rough contacts
whose contact breaks into islands.

Two cells belong to one cluster when they share an edge (4-connectivity: cells touching
at a corner only are apart, as two asperities meeting at a point carry no shared
traction) and have the same status: stick, slip, or in contact (stick or slip).
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from ..nomenclature import STATUS_SEPARATED, STATUS_SLIP, STATUS_STICK

__all__ = ["count_clusters", "contact_clusters"]


def count_clusters(mask) -> int:
    """Edge-connected clusters of the True cells of a 2-D ``mask``."""
    from scipy.ndimage import label

    return int(label(np.asarray(mask, dtype=bool))[1])


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
    status = np.asarray(ds["status"].values)
    out = {name: np.array([count_clusters(test(s)) for s in status], dtype=np.int32)
           for name, test in (("contact_clusters", lambda s: s != STATUS_SEPARATED),
                              ("stick_clusters", lambda s: s == STATUS_STICK),
                              ("slip_clusters", lambda s: s == STATUS_SLIP))}
    attrs = {"units": "1", "long_name": "edge-connected clusters of cells"}
    return xr.Dataset({k: ("time", v, attrs) for k, v in out.items()},
                      coords={"time": ds["time"].values})
