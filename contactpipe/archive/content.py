"""What an archive holds, checked value by value, streaming over time (bounded memory).

:func:`content_problems` reads the data variables in blocks of instants (at most
``budget_bytes`` of fields at a time, at least one instant) and reports, for each variable,
how many instants break a rule and the first of them:

* a float that is NaN or inf;
* a negative pressure ``p`` or gap ``h`` (p >= 0 and h >= 0 by the contact laws);
* a ``status`` outside its ``flag_values``;
* Coulomb's law broken: |q| - mu p > :data:`COULOMB_RTOL` x max(mu p) of that instant
  (mu from the ``scene`` attribute's ``friction.mu``, or the archive's map ``mu``);
* a value that cannot be read back: a netCDF checksum (fletcher32) mismatch or a corrupt
  compressed chunk, located to the instant.

It never builds an array over the whole time axis but the time coordinate itself.
"""
from __future__ import annotations

import numbers

import numpy as np
import xarray as xr

from ..exceptions import one_line
from ..nomenclature import VARIABLES
from .schema import scene_table

__all__ = ["content_problems", "COULOMB_RTOL", "BLOCK_BYTES"]

#: Allowed excess of |q| over mu p, relative to mu times the largest pressure of the
#: instant: float32 storage rounds p and q by 6e-8 each, the solvers project exactly.
COULOMB_RTOL = 1e-6
#: Default bound of the field data held at once by a scan [bytes].
BLOCK_BYTES = 16 * 2**20
#: Variables that must not be negative.
NON_NEGATIVE = {"p": "negative pressure", "h": "negative gap"}


class _Tally:
    """Per (variable, rule): instants found, the first one, and a detail of it."""

    def __init__(self, times):
        self.times = times
        self.found = {}

    def add(self, key, offset, per_step, detail=None):
        """``per_step``: bool per instant of a block starting at ``offset``."""
        per_step = np.asarray(per_step)
        n = int(per_step.sum())
        if not n:
            return
        count, first, info = self.found.get(key, (0, None, None))
        if first is None:
            k = offset + int(np.argmax(per_step))
            first, info = k, (detail(k - offset) if detail else None)
        self.found[key] = (count + n, first, info)

    def where(self, k):
        return f"step {k} (t = {float(self.times[k]):g} s)"

    def problems(self):
        out = []
        for (name, rule), (count, first, info) in self.found.items():
            tail = f": {info}" if info else ""
            if rule == "nonfinite":
                out.append(f"{name} holds NaN or inf at {count} time step(s), first at "
                           f"{self.where(first)}")
            else:
                out.append(f"{name}: {rule} at {count} time step(s), first at "
                           f"{self.where(first)}{tail}")
        return out


def _friction(ds):
    """mu [1] from the scene attribute (a number), or None when it does not say."""
    table = scene_table(ds.attrs) or {}
    fr = table.get("friction", {})
    mu = fr.get("mu", 0.0) if isinstance(fr, dict) else None
    if isinstance(mu, bool) or not isinstance(mu, numbers.Real):
        return None
    return float(mu)


def _read(v, sl):
    """One block of a variable as numpy (raises whatever the storage raises)."""
    return np.asarray(v.isel(time=sl).values)


def _read_or_locate(v, sl, name, tally):
    """The block, or None after recording at which instant it could not be read."""
    try:
        return _read(v, sl)
    except Exception:                      # noqa: BLE001 - HDF/zlib errors: located below
        pass
    for k in range(sl.start, sl.stop):
        try:
            _read(v, slice(k, k + 1))
        except Exception as e:             # noqa: BLE001 - any failure: unreadable
            reason = one_line(e)
            tally.add((name, "unreadable (checksum mismatch or corrupt chunk)"), k,
                      [True], lambda _, reason=reason: reason)
            return None
    return None


def _check_block(name, arr, offset, tally):
    entry = VARIABLES.get(name, {})
    axes = tuple(range(1, arr.ndim))
    if arr.dtype.kind == "f":
        tally.add((name, "nonfinite"), offset, ~np.isfinite(arr).all(axis=axes))
    rule = NON_NEGATIVE.get(name)
    if rule is not None:
        neg = arr < 0
        tally.add((name, rule), offset, neg.any(axis=axes),
                  lambda i: f"min {float(arr[i].min()):.3g} {entry.get('units', '')}")
    flags = entry.get("flag_values")
    if flags is not None and arr.dtype.kind in "iu":
        outside = ~np.isin(arr, flags)
        tally.add((name, f"values outside flag_values {list(flags)}"), offset,
                  outside.any(axis=axes),
                  lambda i: f"values {np.unique(arr[i][outside[i]]).tolist()}")


def _check_coulomb(block, mu, offset, tally):
    p, q1 = block.get("p"), block.get("q1")
    if p is None or q1 is None or mu is None:
        return
    q2 = block.get("q2")
    with np.errstate(invalid="ignore", over="ignore"):   # NaN/inf are reported apart
        q = np.hypot(q1, q2) if q2 is not None else np.abs(q1)
        bound = mu * p.astype(float)
        scale = bound.reshape(p.shape[0], -1).max(axis=1)
        excess = (q - bound).reshape(p.shape[0], -1).max(axis=1)
        over = excess > COULOMB_RTOL * scale
    what = f"mu = {mu:g}" if np.ndim(mu) == 0 else "mu the archive's map"
    tally.add(("q1, q2", f"|q| > mu p ({what}, allowed excess {COULOMB_RTOL:g} max mu "
                         "p)"), offset, over,
              lambda i: f"excess {excess[i] / max(scale[i], 1e-300):.3g} max mu p")


def content_problems(ds: xr.Dataset, budget_bytes: int = BLOCK_BYTES) -> list[str]:
    """Every value of ``ds`` that breaks the archive's rules, streaming over time.

    Parameters
    ----------
    ds : xarray.Dataset
        An archive Dataset, in memory, lazily indexed or dask-backed.
    budget_bytes : int
        Field data held at once [bytes] (at least one instant of the fields checked
        together: p, q1, q2 and one other).

    Returns
    -------
    list of str
        One line per (variable, rule): how many instants break it and the first, e.g.
        ``"p: negative pressure at 2 time step(s), first at step 3 (t = 0.3 s): min
        -1.2e+06 Pa"``. Empty when none.
    """
    if "time" not in ds.dims or ds.sizes["time"] == 0:
        return []
    times = np.asarray(ds["time"].values) if "time" in ds.coords \
        else np.arange(ds.sizes["time"], dtype=float)
    tally = _Tally(times)
    names = [n for n, v in ds.data_vars.items() if v.dtype.kind in "biuf"]
    timed = [n for n in names if "time" in ds[n].dims]
    for n in names:
        if n not in timed:
            arr = np.asarray(ds[n].values)[None]
            _check_block(n, arr, 0, tally)
    cells = max((int(np.prod([ds.sizes[d] for d in ds[n].dims if d != "time"]))
                 for n in timed), default=1)
    step = max(1, int(budget_bytes) // (4 * 8 * max(cells, 1)))
    mu = _friction(ds)
    if "mu" in ds.data_vars and ds["mu"].dims == ("x1", "x2"):
        mu = np.asarray(ds["mu"].values, dtype=float)        # a mapped friction coefficient
    broken = set()
    for start in range(0, len(times), step):
        sl = slice(start, min(start + step, len(times)))
        block = {}
        for n in timed:
            if n in broken:
                continue
            arr = _read_or_locate(ds[n], sl, n, tally)
            if arr is None:
                broken.add(n)
                continue
            _check_block(n, arr, start, tally)
            if n in ("p", "q1", "q2"):
                block[n] = arr
        _check_coulomb(block, mu, start, tally)
    return tally.problems()
