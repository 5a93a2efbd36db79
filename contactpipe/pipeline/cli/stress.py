"""Subsurface stress of an archive: ``contactpipe stress ARCHIVE.nc -o STRESS.nc --x3 ...``.

    contactpipe stress run.nc -o stress.nc --x3 0,1e-4,2e-4 [--body halfspace|indenter]
                           [--time T|all] [--figure FIG.png] [--precision float32]
    contactpipe stress wear.nc -o crossland.nc --x3 0,2e-5 --over-cycles crossland \
                           --constant torsion_limit=300e6 --constant bending_limit=450e6

Reads the archive's tractions (p, q1, q2) and its scene (for the body's Poisson ratio) and
writes a netCDF file over (time, x3, x1, x2) with s11 s22 s33 s12 s13 s23 and von_mises
[Pa], tension > 0, x3 the depth into the chosen body (docs/stress.md). Default instant: the
last; ``--time all`` every instant. The archive is read lazily and the stress is streamed
to the file block by block (instants x depths), so archives larger than memory work.
The file is written atomically (nothing is left on failure).

``--over-cycles CRITERION`` (the archive of a wear run that kept loops of tractions,
``wear.keep_tractions``): the criterion of :func:`contactpipe.fatigue` (constants by
``--constant NAME=VALUE``) on the stress history of every kept loop, and the file written
holds its largest value and where it is against the kept cycles
(:func:`contactpipe.post.wear_fatigue.fatigue_over_cycles`).

Exit status: 0 on success; 2 on bad input (arguments, an output that is an input or the
other output, an unreadable, foreign or damaged archive, an unknown body, a depth below
0 or deeper than 1000 times the grid's larger side, a time not in the archive), with one
line on stderr; 1 when the computation or the write fails (a read-only or full disk
included). No stress file holding NaN or inf is ever written.

The pipeline's ``[stress]`` product (:mod:`contactpipe.pipeline.cli.run`) is written here too:
:func:`write_stress_product` puts the stress and, when the pipeline file asks for a
fatigue criterion, the criterion's fields in one file, with the settings that made it
(their digest decides whether a later run recomputes it).
"""
from __future__ import annotations

import argparse
import contextlib
import json
import pathlib
import sys

import netCDF4
import numpy as np
import xarray as xr

from ..._util.files import atomic_path, check_output_path, make_folder
from ...archive import open_archive
from ...archive.schema import scene_table
from ...exceptions import ArchiveError, ContactpipeError, one_line
from ...post.fatigue import CRITERIA, fatigue
from ...post.stress import BODIES, check_request, open_stress, save_stress, subsurface_stress
from ...post.wear_fatigue import fatigue_over_cycles
from ..figures.plot import plot_stress, save_figure
from ..inputs import local_reads
from ..sweep.config import StressSpec

__all__ = ["add_arguments", "main", "parse_depths", "parse_time", "parse_constants",
           "write_stress_product",
           "product_record", "stored_digest", "SETTINGS_ATTR", "DIGEST_ATTR"]

#: Attributes of a pipeline product: its settings (JSON) and their digest.
SETTINGS_ATTR = "stress_settings"
DIGEST_ATTR = "stress_settings_digest"
#: Attributes of the largest von Mises stress of a product and where it is.
PEAK_ATTRS = ("von_mises_max", "von_mises_max_time", "von_mises_max_x3",
              "von_mises_max_x1", "von_mises_max_x2")
#: HDF5 chunk cache per variable of the files the product opens [bytes]: every chunk is
#: read once, so a small cache loses nothing (the default, up to 64 MiB per variable,
#: would add up to 7 x 64 MiB reading a stress file back).
CHUNK_CACHE_BYTES = 4 * 2 ** 20


def parse_depths(text: str) -> list[float]:
    """Depths [m] from ``"z1,z2,..."``; ValueError naming the bad item."""
    out = []
    for item in str(text).split(","):
        item = item.strip()
        if not item:
            continue
        try:
            out.append(float(item))
        except ValueError:
            raise ValueError(f"--x3 {text!r}: {item!r} is not a number (give depths [m] "
                             "separated by commas, e.g. 0,1e-4,2e-4)") from None
    if not out:
        raise ValueError(f"--x3 {text!r}: give at least one depth [m]")
    return out


def parse_time(text):
    """``None`` (the last instant), ``"all"``, or a time [s]."""
    if text is None or text == "all":
        return text
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"--time {text!r}: give a time [s] or 'all'") from None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("archive", type=pathlib.Path, help="archive to read (netCDF)")
    parser.add_argument("-o", "--output", type=pathlib.Path, required=True,
                        help="stress file to write (netCDF, atomically)")
    parser.add_argument("--x3", required=True, metavar="Z1,Z2,...",
                        help="depths into the body [m], comma-separated (>= 0)")
    parser.add_argument("--body", default="halfspace", metavar="|".join(BODIES),
                        help="the body whose stress is wanted (default: halfspace)")
    parser.add_argument("--time", default=None, metavar="T|all",
                        help="instant [s] of the archive, or 'all' (default: the last)")
    parser.add_argument("--figure", type=pathlib.Path, default=None,
                        help="also write the von Mises map (x1-x3 section and surface, PNG)")
    parser.add_argument("--precision", choices=("float64", "float32"), default="float64",
                        help="storage type of the stresses (default float64)")
    parser.add_argument("--fft", choices=("auto", "pyfftw", "scipy"), default="auto")
    parser.add_argument("--threads", type=int, default=1, help="FFT threads")
    parser.add_argument("--over-cycles", choices=tuple(CRITERIA), default=None,
                        metavar="CRITERION",
                        help="a wear run with kept loops: write this fatigue criterion's "
                             "largest value against the kept cycles (" +
                             ", ".join(CRITERIA) + ") instead of the stress")
    parser.add_argument("--constant", action="append", default=[], metavar="NAME=VALUE",
                        help="a constant of the --over-cycles criterion, e.g. "
                             "torsion_limit=300e6 (repeat for each)")


def parse_constants(items) -> dict:
    """``["name=value", ...]`` as keyword arguments (numbers where they parse)."""
    out = {}
    for item in items:
        name, sep, value = str(item).partition("=")
        if not sep or not name.strip() or not value.strip():
            raise ValueError(f"--constant {item!r}: give NAME=VALUE, e.g. "
                             "torsion_limit=300e6")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            out[name.strip()] = value.strip()
    return out


def _over_cycles(args, ds, depths) -> int:
    """``--over-cycles``: the criterion over the kept loops, written atomically."""
    constants = parse_constants(args.constant)
    try:
        fc = fatigue_over_cycles(ds, depths, args.over_cycles, body=args.body,
                                 fft=args.fft, **constants)
    except (ValueError, ArchiveError) as err:       # constants, loops: bad input
        if getattr(args, "debug", False):
            raise
        print(f"contactpipe: error: {one_line(err, with_type=False)}", file=sys.stderr)
        return 2
    make_folder(args.output.parent)
    with atomic_path(args.output) as tmp:
        fc.to_netcdf(tmp)
    k = int(np.argmax(fc["maximum"].values))
    print(f"wrote {args.output} ({fc.sizes['cycle']} kept cycle(s); largest "
          f"{fc.attrs['criterion_field']} {float(fc['maximum'][k]):.4g} at cycle "
          f"{int(fc['cycle'][k])}, x3 = {float(fc['maximum_x3'][k]):.4g} m)")
    return 0


def _scene_files(ds) -> list:
    """The files the archive's scene read (a surface, a fitted material table, a friction
    map), as its ``scene`` attribute names them."""
    table = scene_table(ds.attrs) or {}
    files = []
    for part, key in (("geometry", "file"), ("indenter", "file"), ("halfspace", "file"),
                      ("friction", "mu")):
        value = table.get(part)
        value = value.get(key) if isinstance(value, dict) else None
        if isinstance(value, str) and value:
            files.append(value)
    return files


def _check_outputs(args, inputs) -> None:
    """Neither output may be an input nor the other output (resolved real paths)."""
    out = check_output_path(args.output, "stress output (-o)", inputs=inputs)
    if args.figure is not None:
        check_output_path(args.figure, "figure (--figure)", inputs=inputs,
                          others=[("stress output (-o)", out)])


def _bad_input(args):
    """Every check that needs no computation; returns the opened archive, verified (a
    damaged archive, e.g. one with a negative pressure, is refused as compare and plot
    refuse it)."""
    _check_outputs(args, [args.archive])
    depths = parse_depths(args.x3)
    time = parse_time(args.time)
    if args.threads < 1:
        raise ValueError(f"--threads {args.threads}: must be >= 1")
    ds = open_archive(args.archive, verify=True)
    try:
        _check_outputs(args, [args.archive, *_scene_files(ds)])
        check_request(ds, depths, args.body, time)
    except BaseException:
        ds.close()
        raise
    return ds, depths, time


def main(args) -> int:
    try:
        ds, depths, time = _bad_input(args)
    except (ValueError, ContactpipeError, OSError) as err:
        if getattr(args, "debug", False):
            raise
        print(f"contactpipe: error: {one_line(err, with_type=False)}", file=sys.stderr)
        return 2
    with local_reads():
        if args.over_cycles is not None:
            try:
                return _over_cycles(args, ds, depths)
            finally:
                ds.close()
        return _compute(args, ds, depths, time)


def _compute(args, ds, depths, time) -> int:
    try:
        st = subsurface_stress(ds, depths, body=args.body, time=time, fft=args.fft,
                               threads=args.threads)
        make_folder(args.output.parent)
        save_stress(st, args.output, precision=args.precision)
    except (ArchiveError, OSError) as err:   # could not be computed or written: a failed run
        if getattr(args, "debug", False):
            raise
        print(f"contactpipe: error: {one_line(err, with_type=False)}", file=sys.stderr)
        return 1
    finally:
        ds.close()
    summary = _summary(args.output)
    print(f"wrote {args.output} ({summary})")
    if args.figure is not None:
        with open_stress(args.output) as st:
            save_figure(plot_stress(st), args.figure)
        print(f"wrote {args.figure}")
    return 0


def _summary(path) -> str:
    try:
        with open_stress(path) as st:
            vm = st["von_mises"]
            flat = vm.data.argmax()                  # dask: read block by block
            flat = int(flat.compute() if hasattr(flat, "compute") else flat)
            k = np.unravel_index(flat, vm.shape)
            at = {d: float(st[d].values[i]) for d, i in zip(vm.dims, k, strict=True)}
            peak = float(vm[tuple(int(i) for i in k)].values)
            return (f"{st.sizes['time']} instant(s) x {st.sizes['x3']} depth(s) on "
                    f"{st.sizes['x1']}x{st.sizes['x2']} cells, {st.attrs.get('body')}; "
                    f"largest von Mises {peak:.4g} Pa at x1 = {at['x1']:.4g} "
                    f"m, x2 = {at['x2']:.4g} m, x3 = {at['x3']:.4g} m, t = {at['time']:.4g} s")
    except (ArchiveError, OSError) as err:          # pragma: no cover - just written
        return f"summary unavailable: {one_line(err)}"


# --------------------------------------------------------------------------- the pipeline's product

@contextlib.contextmanager
def _small_chunk_cache():
    """netCDF's default chunk cache, for the files opened meanwhile, set to
    :data:`CHUNK_CACHE_BYTES` per variable (a process-wide setting, put back after)."""
    size, nelems, preemption = netCDF4.get_chunk_cache()
    netCDF4.set_chunk_cache(CHUNK_CACHE_BYTES, nelems, preemption)
    try:
        yield
    finally:
        netCDF4.set_chunk_cache(size, nelems, preemption)


def _peak(st) -> dict:
    """The largest von Mises stress [Pa] of a stress file and where it is (time [s],
    x3, x1, x2 [m]), read block by block."""
    vm = st["von_mises"]
    flat = vm.data.argmax()                          # dask: one block at a time
    k = np.unravel_index(int(flat.compute() if hasattr(flat, "compute") else flat), vm.shape)
    at = {d: float(st[d].values[i]) for d, i in zip(vm.dims, k, strict=True)}
    return {"von_mises_max": float(vm[tuple(int(i) for i in k)].values),
            "von_mises_max_time": at["time"], "von_mises_max_x3": at["x3"],
            "von_mises_max_x1": at["x1"], "von_mises_max_x2": at["x2"]}


def _cycle(st, cycle):
    """The instants of ``st`` within ``cycle`` = (t_start, t_end) [s] (all when None);
    ValueError when fewer than 2."""
    t = np.asarray(st["time"].values, float)
    if cycle is not None:
        tol = 1e-9 * max(float(np.ptp(t)), abs(float(t[-1])), 1e-300)
        st = st.isel(time=np.flatnonzero((t >= cycle[0] - tol) & (t <= cycle[1] + tol)))
    n = st.sizes["time"]
    if n < 2:
        where = "" if cycle is None else \
            f"the cycle [{cycle[0]:g} s, {cycle[1]:g} s] holds "
        raise ValueError(f"{where}{n} of the {t.size} instant(s) computed ({t[0]:g} s to "
                         f"{t[-1]:g} s): a fatigue criterion needs at least 2 instants of "
                         "the cycle")
    return st


def _finish(tmp: pathlib.Path, spec: StressSpec, cycle) -> None:
    """Add to the stress file ``tmp`` its von Mises peak and, with a criterion, the
    criterion's fields over (x3, x1, x2) over the instants of ``cycle`` (t_start, t_end)
    [s] (None: all), read back one depth at a time."""
    with open_stress(tmp, chunks={"time": -1, "x3": 1}) as st:
        attrs = _peak(st)
        fields = None
        if spec.criterion is not None:
            fi = fatigue(_cycle(st, cycle), spec.criterion, **dict(spec.constants))
            attrs.update({k: fi.attrs[k] for k in ("criterion", "criterion_field",
                                                   "constants", "cycle")})
            fields = fi.drop_vars(list(fi.coords))
    if fields is None:
        fields = xr.Dataset()
    fields.attrs = attrs
    enc = {v: {"zlib": True, "complevel": 1, "_FillValue": None}
           for v in fields.data_vars if fields[v].ndim}
    fields.to_netcdf(tmp, mode="a", engine="netcdf4", encoding=enc)


def write_stress_product(archive, target, spec: StressSpec) -> dict:
    """Compute the ``[stress]`` product of one archive and write it to ``target``.

    The stress over (time, x3, x1, x2) (:func:`contactpipe.subsurface_stress`, streamed
    block by block from the lazily opened archive: bounded memory) and, when ``spec``
    names a criterion, its fields over (x3, x1, x2) (:func:`contactpipe.fatigue` over the
    instants of ``spec.cycle`` or ``spec.cycle_norm``, read back one depth at a time) in
    one netCDF file,
    written atomically, with the attributes :data:`SETTINGS_ATTR` (the settings as
    JSON), :data:`DIGEST_ATTR` (their digest) and the largest von Mises stress and where
    it is. The work runs on dask's synchronous scheduler (one block in memory at a time,
    and never on a distributed client the process may hold), with small HDF5 chunk caches
    (:data:`CHUNK_CACHE_BYTES`): the memory is about one block of
    :data:`contactpipe.post.stress.BLOCK_BYTES` and one depth of the criterion's history,
    whatever the size of the archive.

    Returns
    -------
    dict
        :func:`product_record` of the file written.

    Raises
    ------
    ValueError
        A time not in the archive, a rigid body, a cycle holding fewer than 2 instants.
    ArchiveError
        Not an archive, tractions holding NaN, the write failed. Nothing is left at
        ``target`` but what was there before.
    """
    target = pathlib.Path(target)
    time = {"last": None, "all": "all"}[spec.time] if isinstance(spec.time, str) else \
        list(spec.time)
    make_folder(target.parent)
    with local_reads(synchronous=True), _small_chunk_cache(), \
            open_archive(archive, verify=True) as ds:
        st = subsurface_stress(ds, list(spec.depths), body=spec.body, time=time)
        st.attrs[SETTINGS_ATTR] = json.dumps(spec.settings(), sort_keys=True)
        st.attrs[DIGEST_ATTR] = spec.digest()
        cycle = spec.cycle
        if spec.cycle_norm is not None:            # t_norm of the archive -> seconds
            t = np.asarray(ds["time"].values, float)
            cycle = tuple(float(t[0] + f * (t[-1] - t[0])) for f in spec.cycle_norm)
        with atomic_path(target) as tmp:
            save_stress(st, tmp, precision=spec.precision)
            _finish(tmp, spec, cycle)
    return product_record(target)


def product_record(path) -> dict:
    """What the summary says of a ``[stress]`` product: its path, settings digest,
    sizes, largest von Mises stress and where, and the criterion's maximum and where.

    Raises
    ------
    ArchiveError
        Not a complete stress file.
    """
    with open_stress(path) as st:
        a = st.attrs
        rec = {"path": str(path), "settings_digest": a.get(DIGEST_ATTR),
               "body": a.get("body"), "instants": st.sizes["time"], "depths": st.sizes["x3"]}
        rec.update({k: float(a[k]) for k in PEAK_ATTRS if k in a})
        if "criterion" in a and "maximum" in st:
            rec["criterion"] = a["criterion"]
            rec["criterion_field"] = a.get("criterion_field")
            rec.update({f"criterion_{k}": float(st[k].values)
                        for k in ("maximum", "maximum_x3", "maximum_x1", "maximum_x2")})
    return rec


def stored_digest(path) -> str | None:
    """The settings digest a ``[stress]`` product was made with (None: no product, or not
    a complete stress file)."""
    try:
        with open_stress(path) as st:
            return st.attrs.get(DIGEST_ATTR)
    except (ArchiveError, OSError):
        return None
