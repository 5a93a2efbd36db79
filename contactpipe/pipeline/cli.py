"""Command line: ``contactpipe run | sweep | compare | plot | pipeline | bench``.

Exit status 0 on success; on bad input or a failed run, non-zero with a one-line reason on
stderr (no traceback; ``--debug`` shows it): 2 for bad input (scene, sweep or pipeline
file, arguments), 1 for a run that failed (no convergence, contact off the grid, a member
that failed), 130 when interrupted.

Each stage module provides ``add_arguments(parser)`` and ``main(args) -> int``; this file
only wires them together.
"""
from __future__ import annotations

import argparse
import importlib
import pathlib
import sys

from .._version import __version__
from ..exceptions import ArchiveError, ContactpipeError, SceneError, one_line

__all__ = ["main", "build_parser"]

STAGES = {
    # name: (module, one-line help)
    "sweep": ("contactpipe.pipeline.sweep", "run a parameter sweep on dask (resumable)"),
    "compare": ("contactpipe.pipeline.compare", "compare archives with closed forms or each other"),
    "plot": ("contactpipe.pipeline.plot", "standard figures of an archive or a sweep"),
    "pipeline": ("contactpipe.pipeline.run", "sweep -> compare -> plot, idempotent, cron-safe"),
    "bench": ("contactpipe.pipeline.bench", "print solver speed figures (FFT pairs, iterations, time)"),
    "stress": ("contactpipe.pipeline.stress_cmd", "subsurface stress field of an archive (DC-FFT per depth)"),
}


def _add_run(sub):
    p = sub.add_parser("run", help="one simulation -> one archive",
                       description="Run one scene file and write its netCDF archive.")
    p.add_argument("scene", type=pathlib.Path, help="scene file (TOML)")
    p.add_argument("-o", "--output", type=pathlib.Path, required=True,
                   help="archive to write (netCDF, written atomically)")
    p.add_argument("--figure", type=pathlib.Path, default=None,
                   help="also write the standard traction-profile figure (PNG)")
    p.add_argument("--tangential", choices=("auto", "scalar", "vector"), default=None,
                   help="override the tangential form")
    p.add_argument("--fft", choices=("auto", "pyfftw", "scipy"), default=None)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--resume", action="store_true",
                   help="resumable run: an interrupted run (Ctrl-C, killed) keeps its part "
                        "file and checkpoint beside OUT, and the same command continues it")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..scene import Scene
    from ..simulation import simulate
    scene = Scene.from_toml(args.scene)
    tangential = None if args.tangential in (None, "auto") else args.tangential
    args.output.parent.mkdir(parents=True, exist_ok=True)
    ds = simulate(scene, args.output, progress=not args.no_progress, tangential=tangential,
                  fft=args.fft, threads=args.threads, resume=args.resume)
    print(f"wrote {args.output} ({ds.sizes['time']} instants, {ds.attrs['models']}, "
          f"{float(ds.attrs['wall_time_s']):.2f} s)")
    if args.figure is not None:
        from .plot import plot_profiles
        args.figure.parent.mkdir(parents=True, exist_ok=True)
        plot_profiles(ds, args.figure)
        print(f"wrote {args.figure}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="contactpipe",
        description="Frictional stick-slip contact of elastic and viscoelastic bodies.")
    parser.add_argument("--version", action="version", version=f"contactpipe {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_run(sub)
    for name, (module, helptext) in STAGES.items():
        try:
            mod = importlib.import_module(module)
        except ImportError:
            continue
        p = sub.add_parser(name, help=helptext, description=(mod.__doc__ or helptext).strip(),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        mod.add_arguments(p)
        p.set_defaults(func=mod.main)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("contactpipe: interrupted", file=sys.stderr)
        return 130
    except (SceneError, FileNotFoundError, IsADirectoryError) as err:
        if args.debug:
            raise
        print(f"contactpipe: error: {one_line(err, with_type=False)}", file=sys.stderr)
        return 2
    except (ContactpipeError, ArchiveError, ValueError, OSError) as err:
        if args.debug:
            raise
        print(f"contactpipe: error: {one_line(err)}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
