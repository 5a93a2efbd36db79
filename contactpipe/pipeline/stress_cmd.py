"""Subsurface stress of an archive: ``contactpipe stress ARCHIVE.nc -o STRESS.nc --x3 ...``.

    contactpipe stress run.nc -o stress.nc --x3 0,1e-4,2e-4 [--body halfspace|indenter]
                           [--time T|all] [--figure FIG.png] [--precision float32]

Reads the archive's tractions (p, q1, q2) and its scene (for the body's Poisson ratio) and
writes a netCDF file over (time, x3, x1, x2) with s11 s22 s33 s12 s13 s23 and von_mises
[Pa], tension > 0, x3 the depth into the chosen body (CONTRACT §5). Default instant: the
last; ``--time all`` every instant. The archive is read lazily and the stress is streamed
to the file block by block (instants x depths), so archives larger than memory work.
The file is written atomically (nothing is left on failure).

Exit status: 0 on success; 2 on bad input (arguments, an unreadable or foreign archive,
an unknown body, a negative depth, a time not in the archive), with one line on stderr;
1 when the computation or the write fails.
"""
from __future__ import annotations

import argparse
import pathlib
import sys

import numpy as np

from ..archive import open_archive
from ..exceptions import ArchiveError, ContactpipeError, one_line
from ..files import check_output_path
from ..stress import BODIES, check_request, open_stress, save_stress, subsurface_stress
from .plot import plot_stress, save_figure

__all__ = ["add_arguments", "main", "parse_depths", "parse_time"]


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


def _bad_input(args):
    """Every check that needs no computation; returns the opened archive."""
    inputs = [args.archive]
    out = check_output_path(args.output, "stress output", inputs=inputs)
    if args.figure is not None:
        check_output_path(args.figure, "figure", inputs=inputs + [out])
    depths = parse_depths(args.x3)
    time = parse_time(args.time)
    if args.threads < 1:
        raise ValueError(f"--threads {args.threads}: must be >= 1")
    ds = open_archive(args.archive)
    try:
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
    try:
        st = subsurface_stress(ds, depths, body=args.body, time=time, fft=args.fft,
                               threads=args.threads)
        args.output.parent.mkdir(parents=True, exist_ok=True)
        save_stress(st, args.output, precision=args.precision)
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
            at = {d: float(st[d].values[i]) for d, i in zip(vm.dims, k)}
            peak = float(vm[tuple(int(i) for i in k)].values)
            return (f"{st.sizes['time']} instant(s) x {st.sizes['x3']} depth(s) on "
                    f"{st.sizes['x1']}x{st.sizes['x2']} cells, {st.attrs.get('body')}; "
                    f"largest von Mises {peak:.4g} Pa at x1 = {at['x1']:.4g} "
                    f"m, x2 = {at['x2']:.4g} m, x3 = {at['x3']:.4g} m, t = {at['time']:.4g} s")
    except (ArchiveError, OSError) as err:          # pragma: no cover - just written
        return f"summary unavailable: {one_line(err)}"
