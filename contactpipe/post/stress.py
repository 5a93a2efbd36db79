"""Subsurface stress: the stress field inside either body from an archive's tractions.

    >>> st = cp.subsurface_stress(ds, x3=[0.0, 1e-4, 2e-4], body="halfspace")
    >>> st.von_mises.max()

Reads any archive (docs/archive.md): its tractions ``p``, ``q1``, ``q2`` and its ``scene``
attribute for the Poisson ratio of the chosen body. Returns a Dataset over
(``time``, ``x3``, ``x1``, ``x2``) with ``s11 s22 s33 s12 s13 s23`` and ``von_mises`` [Pa],
tension > 0, in the frame x1, x2, x3 with x3 pointing **into the chosen body** (x3 >= 0 is
the depth below its surface).

Method: the closed-form stresses of uniform tractions on a rectangular cell (Love 1929
for the pressure, the Cerruti counterparts for the shear; Johnson 1985 ch. 3), convolved
with the cell tractions by DC-FFT, depth by depth
(:mod:`contactpipe.solver.subsurface`). At x3 = 0 the values are those at cell centres:
the surface stresses jump at cell edges.

Bodies and signs (docs/conventions.md). The archive's tractions are those exerted by body
1 (the indenter) on body 2 (the half-space): p > 0 presses body 2 and q has the sign of T.

- ``body="halfspace"``: body 2 carries (q1, q2, p) in the global frame, whose x3 already
  points into it.
- ``body="indenter"``: body 1 carries the reaction -(q1, q2, p) (global components).
  Described in its mirrored frame (x1, x2, x3' = -x3), with x3' pointing into it, that
  traction is (-q1, -q2, +p): it presses body 1 and shears it against T. Isotropic
  elasticity is unchanged by the reflection, so the same kernels apply. The components
  returned are those of the mirrored frame; in the global frame s13 and s23 change sign,
  the others are the same. At the interface (x3 = 0) the traction vectors of the two
  bodies then agree: (s13, s23, s33) = (-q1, -q2, -p) in global components.

Viscoelastic bodies: with a constant Poisson ratio the stress field due to given surface
tractions is the elastic one at every instant (the correspondence principle leaves the
stress of a traction boundary-value problem independent of the creep function), so the
archive's tractions are all that is needed; the modulus and the history do not enter.

Equilibrium (the sign convention of the tests): on every depth plane the material above
pulls the material below with the force ``-∫ (s13, s23, s33) dA = (T1, T2, W)`` for the
half-space.

Memory: the work is done per block of instants and depths; the kernel spectra are cached
per (grid, nu, depth). When the archive is lazily opened (:func:`contactpipe.open_archive`)
or ``chunks`` is given, the result is lazy (dask): a block is computed when it is needed,
e.g. while :func:`save_stress` streams it to a file, so archives larger than memory work.
"""
from __future__ import annotations

import os
import pathlib
import warnings
from typing import TYPE_CHECKING

import netCDF4
import numpy as np
import xarray as xr

from .._util.files import atomic_path, loads_toml, make_folder
from .._version import __version__
from ..archive import open_archive
from ..archive.content import content_problems
from ..archive.schema import join_problems
from ..exceptions import ArchiveError

if TYPE_CHECKING:
    from ..solver.subsurface import SubsurfaceOperator

__all__ = ["subsurface_stress", "save_stress", "open_stress", "verify_stress",
           "is_stress_file", "body_poisson", "BODIES", "STRESS_VARIABLES", "check_request",
           "MAX_DEPTH_SIDES"]

BODIES = ("halfspace", "indenter")
#: Variables of a stress dataset: long names (all in Pa).
STRESS_VARIABLES = {
    "s11": "normal stress along x1",
    "s22": "normal stress along x2",
    "s33": "normal stress along x3 (x3 into the body)",
    "s12": "shear stress s12",
    "s13": "shear stress s13",
    "s23": "shear stress s23",
    "von_mises": "von Mises equivalent stress",
}
#: The six components (the solver's order), then von Mises: the variables computed.
COMPUTED = tuple(STRESS_VARIABLES)
FIELD_DIMS = ("time", "x3", "x1", "x2")
#: Default bound of the memory of one output block [bytes] (7 variables, float64).
BLOCK_BYTES = 64 * 2 ** 20
#: Deepest depth allowed, in units of the grid's larger side L: at 1000 L the field is
#: that of a point load to within the storage's rounding (it falls as 1/x3^2 from the
#: contact's scale on), and far beyond, the kernels overflow into NaN.
MAX_DEPTH_SIDES = 1000


# --------------------------------------------------------------------------- checks

def body_poisson(ds: xr.Dataset, body: str = "halfspace") -> float:
    """Poisson ratio [1] of ``body`` from the archive's ``scene`` attribute.

    Raises
    ------
    ArchiveError
        No ``scene`` attribute, or one that does not give the body's material.
    ValueError
        ``body`` is not one of :data:`BODIES`, that body is rigid, or its Poisson ratio
        varies in time (``bulk = "elastic"``).
    """
    if body not in BODIES:
        raise ValueError(f"body = {body!r}: allowed {', '.join(map(repr, BODIES))}")
    text = ds.attrs.get("scene")
    if not isinstance(text, str):
        raise ArchiveError("the dataset has no 'scene' attribute (the scene as TOML text), "
                           "so the Poisson ratio of the body is unknown: pass poisson=")
    try:
        table = loads_toml(text, "the archive's scene attribute").get(body, {})
    except Exception as err:              # noqa: BLE001 - any parse failure is one message
        raise ArchiveError(f"the archive's 'scene' attribute is not valid TOML: "
                           f"{' '.join(str(err).split())}") from None
    material = table.get("material")
    if material == "rigid":
        raise ValueError(f"body = {body!r} is rigid in the archive's scene: a rigid body "
                         "has no elastic stress field; choose the other body")
    if table.get("bulk") == "elastic":
        raise ValueError(f"body = {body!r} has bulk = 'elastic' in the archive's scene: its "
                         "Poisson ratio varies in time, so the stress from its tractions "
                         "carries a memory this stage does not model; pass poisson= to "
                         "evaluate the elastic field of one fixed ratio")
    nu = table.get("poisson")
    if material not in ("elastic", "viscoelastic") or not isinstance(nu, (int, float)):
        raise ArchiveError(f"the archive's scene gives no material and poisson for "
                           f"[{body}] (material = {material!r}, poisson = {nu!r})")
    return float(nu)


def _depths(x3) -> np.ndarray:
    try:
        z = np.atleast_1d(np.asarray(x3, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"x3 = {x3!r}: give depths [m] as numbers >= 0") from None
    if z.ndim != 1 or z.size == 0:
        raise ValueError(f"x3 = {x3!r}: give a list of depths [m], at least one")
    bad = z[~np.isfinite(z) | (z < 0)]
    if bad.size:
        raise ValueError(f"x3 = {float(bad[0]):g} m: depths must be finite and >= 0 (x3 is the "
                         f"depth into the body)")
    return np.unique(z)


def _time_index(ds, time) -> np.ndarray:
    """Indices of the requested instants: None the last, "all" every one, or values [s]."""
    n = ds.sizes["time"]
    if n == 0:
        raise ArchiveError("the archive holds no instant")
    t = np.asarray(ds["time"].values, dtype=float)
    if time is None:
        return np.array([n - 1])
    if isinstance(time, str):
        if time == "all":
            return np.arange(n)
        try:
            time = float(time)
        except ValueError:
            raise ValueError(f"time = {time!r}: give a time [s], 'all' or None (the last "
                             "instant)") from None
    want = np.atleast_1d(np.asarray(time, dtype=float))
    span = float(t.max() - t.min()) if n > 1 else max(abs(float(t[0])), 1.0)
    idx = []
    for w in want:
        hit = np.flatnonzero(np.abs(t - w) <= 1e-9 * span)
        if hit.size == 0:
            raise ValueError(f"time = {w:g} s is not an instant of the archive ({n} instants "
                             f"from {t[0]:g} s to {t[-1]:g} s); give one of them, 'all' or "
                             "None (the last)")
        idx.append(int(hit[0]))
    return np.unique(idx)


def _grid(ds):
    """(n1, n2, d1, d2) of a uniform grid of cell centres."""
    out = []
    for ax in ("x1", "x2"):
        if ax not in ds.coords:
            raise ArchiveError(f"the archive has no coordinate {ax!r}")
        x = np.asarray(ds[ax].values, dtype=float)
        if x.size < 2:
            raise ArchiveError(f"the archive has {x.size} cell along {ax}: at least 2 needed")
        d = np.diff(x)
        if not (np.all(d > 0) and np.ptp(d) <= 1e-6 * d.mean()):
            raise ArchiveError(f"the cell centres along {ax} are not uniform and ascending")
        out.append((x.size, float((x[-1] - x[0]) / (x.size - 1))))
    return out[0][0], out[1][0], out[0][1], out[1][1]


def _periodic(ds) -> bool:
    """The archive's scene is one period of an infinite surface
    (``grid.boundary = "periodic"``): its stresses come from the periodic kernels."""
    text = ds.attrs.get("scene")
    if not isinstance(text, str):
        return False
    try:
        grid = loads_toml(text, "the archive's scene attribute").get("grid", {})
    except Exception:                     # noqa: BLE001 - reported by body_poisson
        return False
    return isinstance(grid, dict) and grid.get("boundary") == "periodic"


def check_request(ds, x3, body="halfspace", time=None, poisson=None):
    """Check a request before any work: (time indices, depths, nu, grid).

    Raises one-line ``ValueError`` (unknown body, negative depth, a time not in the
    archive) or ``ArchiveError`` (no ``p``, no scene, not on a uniform grid).
    """
    if body not in BODIES:
        raise ValueError(f"body = {body!r}: allowed {', '.join(map(repr, BODIES))}")
    depths = _depths(x3)
    if not isinstance(ds, xr.Dataset):
        raise ArchiveError(f"expected an archive path or an xarray.Dataset, got "
                           f"{type(ds).__name__}")
    if "p" not in ds.data_vars:
        raise ArchiveError("the archive has no contact pressure 'p': not a contactpipe "
                           "archive")
    for name in ("p", "q1", "q2"):
        if name in ds.data_vars and tuple(ds[name].dims) != ("time", "x1", "x2"):
            raise ArchiveError(f"'{name}' has dims {ds[name].dims}, expected "
                               "('time', 'x1', 'x2')")
    grid = _grid(ds)
    side = max(grid[0] * grid[2], grid[1] * grid[3])
    deepest = MAX_DEPTH_SIDES * side
    if depths[-1] > deepest:
        raise ValueError(f"x3 = {float(depths[-1]):g} m is too deep: depths must be from 0 to "
                         f"{deepest:g} m ({MAX_DEPTH_SIDES} times the grid's larger side, "
                         f"{side:g} m); below that the field is a point load's")
    idx = _time_index(ds, time)
    if poisson is None:
        nu = body_poisson(ds, body)
    else:
        nu = float(poisson)
    if not 0.0 <= nu <= 0.5:
        raise ValueError(f"poisson = {nu!r}: allowed 0 <= nu <= 0.5")
    return idx, depths, nu, grid


# --------------------------------------------------------------------------- blocks

def _block(arrays, names, depths, op: SubsurfaceOperator, sign_q: float):
    """Stress of a block of instants (arrays: (nt, n1, n2) each) at ``depths``.

    Returns (7, nt, nz, n1, n2) [Pa]: the components of COMPONENTS, then von Mises.
    Depth-outer loop: each depth's spectra serve every instant of the block.
    """
    from ..solver.subsurface import COMPONENTS, von_mises  # the FFTs: only when computing
    fields = dict(zip(names, (np.asarray(a, dtype=float) for a in arrays), strict=True))
    nt = fields["p"].shape[0]
    for name, f in fields.items():
        if not np.all(np.isfinite(f)):
            raise ArchiveError(f"the archive's '{name}' holds NaN or inf: no stress computed")
    specs = []
    for k in range(nt):
        tr = {"p": fields["p"][k]}
        for q in ("q1", "q2"):
            if q in fields:
                tr[q] = sign_q * fields[q][k]
        specs.append(op.traction_spectra(tr))
    out = np.empty((len(COMPONENTS) + 1, nt, len(depths), op.n1, op.n2))
    buf = np.empty((len(COMPONENTS), op.n1, op.n2))
    for j, z in enumerate(np.asarray(depths, dtype=float).ravel()):
        for k in range(nt):
            op.stress(specs[k], z, out=buf)
            out[:len(COMPONENTS), k, j] = buf
            out[-1, k, j] = von_mises(*buf)
    if not np.all(np.isfinite(out)):
        raise ArchiveError(f"the stress at x3 = {float(np.max(depths)):g} m overflows to NaN "
                           "or inf: nothing written (give depths of the contact's scale)")
    return out


def _chunk_sizes(nt, nz, n1, n2, chunks, cache_bytes):
    spec_bytes = 15 * (2 * n1) * (n2 + 1) * 8          # distinct kernel spectra per depth
    zc = max(1, min(nz, int(cache_bytes // (2 * spec_bytes))))
    tc = max(1, min(nt, int(BLOCK_BYTES // (7 * zc * n1 * n2 * 8))))
    if isinstance(chunks, dict):
        unknown = set(chunks) - {"time", "x3"}
        if unknown:
            raise ValueError(f"chunks keys {sorted(unknown)}: allowed 'time' and 'x3'")
        tc = int(chunks.get("time", tc) or tc)
        zc = int(chunks.get("x3", zc) or zc)
        if tc < 1 or zc < 1:
            raise ValueError(f"chunks = {chunks!r}: sizes must be >= 1")
    return min(tc, nt), min(zc, nz)


def _lazy(fields, names, depths, op, sign_q, tc, zc):
    import dask.array as da  # heavy: only for lazy results
    arrays = []
    for name in names:
        a = fields[name].data
        a = a.rechunk((tc, -1, -1)) if isinstance(a, da.Array) else \
            da.from_array(np.asarray(a), chunks=(tc, -1, -1))
        arrays.append(a)
    zarr = da.from_array(depths, chunks=zc)

    def fn(*blocks):
        *trac, z = blocks
        return _block(trac, names, z, op, sign_q)

    args = []
    for a in arrays:
        args += [a, "tij"]
    args += [zarr, "z"]
    with warnings.catch_warnings():
        # one block per (instants, depths) pair is the point: more blocks than inputs
        warnings.filterwarnings("ignore", message="Increasing number of chunks")
        out = da.blockwise(fn, "ctzij", *args, new_axes={"c": len(COMPUTED)},
                           dtype=float, concatenate=True,
                           meta=np.empty((0, 0, 0, 0, 0), dtype=float))
    return [out[i] for i in range(len(COMPUTED))]


def _eager(fields, names, depths, op, sign_q, tc, zc):
    nt = fields["p"].shape[0]
    n1, n2 = op.n1, op.n2
    res = [np.empty((nt, len(depths), n1, n2)) for _ in COMPUTED]
    for t0 in range(0, nt, tc):
        block = [np.asarray(fields[n][t0:t0 + tc].values) for n in names]
        for z0 in range(0, len(depths), zc):
            out = _block(block, names, depths[z0:z0 + zc], op, sign_q)
            for i, r in enumerate(res):
                r[t0:t0 + tc, z0:z0 + zc] = out[i]
    return res


# --------------------------------------------------------------------------- API

def subsurface_stress(ds, x3, body: str = "halfspace", time=None, *, chunks=None,
                      poisson=None, fft: str = "auto", threads: int = 1) -> xr.Dataset:
    """Stress field inside a body from an archive's tractions (DC-FFT, depth by depth).

    Parameters
    ----------
    ds : xarray.Dataset or path
        An archive (docs/archive.md), in memory or a file (then opened lazily).
    x3 : float or sequence of float
        Depths into the chosen body [m], >= 0; sorted, duplicates dropped. At x3 = 0 the
        stress is that at cell centres (it jumps at cell edges).
    body : {"halfspace", "indenter"}
        The body whose stress is wanted (module docstring: frames and signs).
    time : None, float, sequence of float or "all"
        Instants [s] of the archive; None: the last instant.
    chunks : None, False or dict
        ``{"time": n, "x3": m}``: a lazy (dask) result with blocks of n instants and m
        depths. None: lazy when the archive's tractions are dask arrays (a lazily opened
        archive), computed now otherwise; block sizes chosen from the memory bounds
        (:data:`BLOCK_BYTES` per output block, half the spectra cache for one block's
        depths). False: computed now.
    poisson : float, optional
        Poisson ratio [1] to use instead of the one the archive's scene gives.
    fft : {"auto", "pyfftw", "scipy"}
        FFT library of the DC-FFT engine.
    threads : int
        FFT threads per engine.

    Returns
    -------
    xarray.Dataset
        Over (time, x3, x1, x2): ``s11 s22 s33 s12 s13 s23`` and ``von_mises`` [Pa],
        tension > 0, in the frame of the chosen body (x3 into it). Attributes say the
        body, its Poisson ratio and the method; ``scene`` is the archive's.

    Raises
    ------
    ValueError
        Unknown body, a negative or non-finite depth, a time not in the archive, a
        rigid body, bad chunks.
    ArchiveError
        Not an archive (no ``p``, no scene for nu, not a uniform grid), or tractions
        holding NaN.

    Notes
    -----
    A viscoelastic body with a constant Poisson ratio needs nothing more than its
    tractions: the stress due to given surface tractions is the elastic one.
    """
    source = None
    if isinstance(ds, (str, os.PathLike)):
        source = str(ds)
        ds = open_archive(ds)
    idx, depths, nu, (n1, n2, d1, d2) = check_request(ds, x3, body, time, poisson)
    from ..solver.subsurface import SPECTRA_CACHE_BYTES, SubsurfaceOperator  # the FFTs
    names = ["p"] + [q for q in ("q1", "q2") if q in ds.data_vars]
    sel = ds[names].isel(time=idx)
    op = SubsurfaceOperator(n1, n2, d1, d2, nu, backend=fft, threads=threads,
                            periodic=_periodic(ds))
    sign_q = -1.0 if body == "indenter" else 1.0
    tc, zc = _chunk_sizes(len(idx), len(depths), n1, n2, chunks, SPECTRA_CACHE_BYTES)
    lazy = isinstance(chunks, dict) or (chunks is None and sel["p"].chunks is not None)
    fields = {n: sel[n] for n in names}
    compute = _lazy if lazy else _eager
    data = compute(fields, names, depths, op, sign_q, tc, zc)
    return _dataset(sel, depths, data, body, nu, ds.attrs, source)


def _dataset(sel, depths, data, body, nu, attrs, source) -> xr.Dataset:
    coords = {"time": sel["time"].variable, "x1": sel["x1"].variable,
              "x2": sel["x2"].variable,
              "x3": xr.Variable("x3", depths, {
                  "units": "m", "long_name": f"depth into the {body}",
                  "positive": "down" if body == "halfspace" else "up",
                  "axis": "Z"})}
    frame = ("global frame (x3 into the half-space)" if body == "halfspace" else
             "mirrored frame (x1, x2, -x3): x3 into the indenter; in the global frame "
             "s13 and s23 change sign")
    variables = {}
    for name, arr in zip(COMPUTED, data, strict=True):
        variables[name] = xr.Variable(FIELD_DIMS, arr, {
            "units": "Pa", "long_name": f"{STRESS_VARIABLES[name]} in the {body}",
            "comment": "tension > 0; " + frame})
    out = xr.Dataset(variables, coords=coords)
    out.attrs = {
        "Conventions": "CF-1.10",
        "title": f"subsurface stress in the {body}",
        "contactpipe_version": __version__,
        "source": "contactpipe.subsurface_stress: closed-form stresses of uniform tractions "
                  "on rectangular cells (Love 1929; Cerruti; Johnson 1985 ch. 3) by DC-FFT "
                  "per depth; cell-centre values",
        "body": body,
        "poisson": nu,
        "scene": attrs.get("scene", ""),
    }
    if source is not None:
        out.attrs["source_archive"] = source
    return out


def _refuse_nonfinite(st, fields) -> None:
    """ArchiveError when a field of ``st`` (in memory) holds NaN or inf: never written."""
    for v in fields:
        values = np.asarray(st[v].values)
        if not np.all(np.isfinite(values)):
            bad = np.argwhere(~np.isfinite(values))[0]
            at = ", ".join(f"{d} = {float(st[d].values[i]):g}"
                           for d, i in zip(st[v].dims, bad, strict=True))
            raise ArchiveError(f"{v} holds NaN or inf (first at {at}): a stress file is "
                               "never written with them")


def _write_streamed(st: xr.Dataset, tmp, encoding) -> None:
    """Write a lazy stress dataset block by block: the coordinates and attributes first
    (xarray), then the fields one (instants x depths) block at a time, its seven
    variables computed together (one computation of the block) and written before the
    next block is computed, so that one block is in memory at a time whatever order a
    dask scheduler would choose."""
    fields = list(STRESS_VARIABLES)
    st.drop_vars(fields).to_netcdf(tmp, mode="w", format="NETCDF4", engine="netcdf4")
    tchunks, zchunks = st["s11"].chunks[:2]
    with netCDF4.Dataset(tmp, mode="a") as nc:
        for v in fields:
            e = encoding[v]
            var = nc.createVariable(v, e["dtype"], FIELD_DIMS, zlib=e["zlib"],
                                    complevel=e.get("complevel", 4),
                                    shuffle=e.get("shuffle", False),
                                    fletcher32=e.get("fletcher32", False),
                                    chunksizes=e["chunksizes"], fill_value=False)
            var.setncatts(st[v].attrs)
            # whole chunks are written once: a cache of one chunk, not HDF5's default of
            # up to 64 MiB per variable, which would grow with the file to 7 x 64 MiB
            var.set_var_chunk_cache(size=int(np.prod(e["chunksizes"])) * var.dtype.itemsize,
                                    nelems=1, preemption=1.0)
        t0 = 0
        for nt in tchunks:
            z0 = 0
            for nz in zchunks:
                block = st[fields].isel(time=slice(t0, t0 + nt), x3=slice(z0, z0 + nz))
                block = block.compute()
                _refuse_nonfinite(block, fields)
                for v in fields:
                    nc[v][t0:t0 + nt, z0:z0 + nz] = block[v].values
                del block
                z0 += nz
            t0 += nt


def save_stress(st: xr.Dataset, path, precision: str = "float64",
                compress: bool = True) -> pathlib.Path:
    """Write a stress dataset to netCDF atomically (a lazy one is streamed block by block).

    Parameters
    ----------
    st : xarray.Dataset
        From :func:`subsurface_stress`.
    path : path-like
        Target file; replaced only when the new file is complete.
    precision : {"float64", "float32"}
        Storage type of the stresses.
    compress : bool
        zlib level 1 with shuffle.

    Raises
    ------
    ArchiveError
        The dataset is not a stress dataset; or writing failed (nothing is left at
        ``path`` but what was there before). Errors raised while a lazy block is
        computed (tractions holding NaN) propagate the same way.
    """
    path = pathlib.Path(path)
    missing = [v for v in STRESS_VARIABLES if v not in st.data_vars]
    if missing:
        raise ArchiveError(f"{path}: not saved: not a stress dataset (missing "
                           f"{', '.join(missing)})")
    if tuple(st["s11"].dims) != FIELD_DIMS:
        raise ArchiveError(f"{path}: not saved: stress dims {st['s11'].dims}, expected "
                           f"{FIELD_DIMS}")
    if precision not in ("float64", "float32"):
        raise ValueError(f"precision = {precision!r}: allowed 'float64', 'float32'")
    # a fletcher32 checksum per chunk, as archives have: open_stress(verify=True) and the
    # figures find a damaged chunk instead of drawing it
    enc = {"zlib": bool(compress), "_FillValue": None, "dtype": precision,
           "fletcher32": True}
    if compress:
        enc.update(complevel=1, shuffle=True)
    n1, n2 = st.sizes["x1"], st.sizes["x2"]
    encoding = {v: dict(enc, chunksizes=(1, 1, n1, n2)) for v in STRESS_VARIABLES}
    st = st.copy()
    st.attrs = dict(st.attrs, complete="true")
    make_folder(path.parent)
    try:
        with atomic_path(path) as tmp:
            if st["s11"].chunks is None:
                _refuse_nonfinite(st, STRESS_VARIABLES)
                st.to_netcdf(tmp, mode="w", format="NETCDF4", engine="netcdf4",
                             encoding=encoding)
            else:
                _write_streamed(st, tmp, encoding)
    except (ArchiveError, ValueError):
        raise
    except Exception as err:               # noqa: BLE001 - HDF/netCDF errors of every kind
        raise ArchiveError(f"{path}: writing failed, nothing written "
                           f"({type(err).__name__}: {' '.join(str(err).split())})") from err
    return path


def verify_stress(path) -> None:
    """Read every value of the stress file at ``path`` once, block by block, as archives
    are verified (:func:`contactpipe.archive.content_problems`: NaN or inf, a checksum
    mismatch or a corrupt chunk, located to the instant).

    Raises
    ------
    ArchiveError
        Not a complete stress file, or one naming each damaged variable.
    """
    with open_stress(path, chunks=False) as st:
        problems = content_problems(st)
    if problems:
        raise ArchiveError(f"{path}: damaged stress file: {join_problems(problems)}")


def open_stress(path, chunks=None, *, verify: bool = False) -> xr.Dataset:
    """Open a stress file written by :func:`save_stress` (lazily, dask-backed; ``chunks``
    False: lazily indexed, without dask).

    ``verify``: read every value once first (:func:`verify_stress`); the figures do.

    Raises
    ------
    ArchiveError
        Missing, unreadable, incomplete, or not a stress dataset; with ``verify``, a
        value that is NaN or inf or cannot be read back.
    """
    path = pathlib.Path(path)
    if verify:
        verify_stress(path)
    if not path.exists():
        raise ArchiveError(f"{path}: no such stress file")
    try:
        kwargs = {} if chunks is False else {"chunks": {} if chunks is None else chunks}
        st = xr.open_dataset(path, engine="netcdf4", **kwargs)
    except Exception as err:              # noqa: BLE001
        raise ArchiveError(f"{path}: not a readable netCDF file: "
                           f"{' '.join(str(err).split())}") from None
    missing = [v for v in STRESS_VARIABLES if v not in st.data_vars]
    if st.attrs.get("complete") != "true" or missing:
        st.close()
        raise ArchiveError(f"{path}: not a complete stress file"
                           + (f" (missing {', '.join(missing)})" if missing else ""))
    return st


def is_stress_file(path) -> bool:
    """True when ``path`` is a netCDF file holding a stress field (the variables of
    :data:`STRESS_VARIABLES` and a dimension ``x3``), as :func:`save_stress` writes.

    Reads the metadata only and never raises: a missing, unreadable or foreign file is
    not a stress file (opening it says why).
    """
    try:
        nc = netCDF4.Dataset(path, mode="r")
    except Exception:                     # noqa: BLE001 - not netCDF, missing: not stress
        return False
    try:
        return "x3" in nc.dimensions and all(v in nc.variables for v in STRESS_VARIABLES)
    finally:
        nc.close()
