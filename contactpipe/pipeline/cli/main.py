"""Command line: ``contactpipe run | sweep | compare | plot | pipeline | bench``.

Exit status 0 on success; otherwise one line on stderr (no traceback; ``--debug`` shows
it) and:

* 2 - bad input: a scene, sweep or pipeline file, an argument, an output path (empty, a
  directory, a device, an input file or a file the scene reads, another output of the
  same command), an input archive or stress file that is missing, unreadable or damaged
  (:class:`~contactpipe.exceptions.ArchiveError`), a run that would not fit in the memory
  available; nothing is written;
* 1 - a run that failed: no convergence, contact off the grid, out of memory, an output
  that could not be written (a read-only folder, a full disk: every command alike), a
  member that failed;
* 3 - another process holds the lock (a resumable run of the same target, a sweep or a
  pipeline run on the same folder); nothing is touched;
* 130 - interrupted by Ctrl-C (SIGINT); 143 - terminated by SIGTERM; 129 - by SIGHUP
  (128 + the signal number). Both termination signals are handled like Ctrl-C: temporary
  files are removed, a resumable run keeps its part file and checkpoint;
* 141 - the reader of the output went away (SIGPIPE, ``contactpipe compare ... | head``):
  no message, no traceback.

Warnings are printed as one line each (``contactpipe: warning: ...``).

Each stage module provides ``add_arguments(parser)`` and ``main(args) -> int``; this file
only wires them together, importing only the stage that runs: ``run`` of a refused scene
loads numpy, tomllib and the scene modules, not xarray, dask, matplotlib nor the FFTs.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import pathlib
import signal
import sys
import warnings

from ..._util.files import LockedError, check_output_path, make_folder
from ..._util.interrupts import deferred, pending, raise_if_signalled, signals_as_interrupt
from ..._version import __version__
from ...exceptions import (
    ArchiveError,
    ContactpipeError,
    OutputPathError,
    ResumeNotice,
    SceneError,
    one_line,
)

__all__ = ["main", "build_parser"]

STAGES = {
    # name: (module, one-line help)
    "sweep": ("contactpipe.pipeline.sweep.driver", "run a parameter sweep on dask (resumable)"),
    "compare": ("contactpipe.pipeline.cli.compare",
                "compare archives with closed forms or each other"),
    "plot": ("contactpipe.pipeline.figures.plot",
             "figures of an archive, a stress file or a sweep folder"),
    "pipeline": ("contactpipe.pipeline.cli.run",
                 "sweep -> compare -> plot (-> stress), idempotent, cron-safe"),
    "bench": ("contactpipe.pipeline.cli.bench",
              "print solver speed figures (FFT pairs, iterations, time)"),
    "stress": ("contactpipe.pipeline.cli.stress",
               "subsurface stress field of an archive (DC-FFT per depth)"),
}


def _add_run(sub):
    p = sub.add_parser("run", help="one simulation -> one archive",
                       description="Run one scene file and write its netCDF archive.")
    p.add_argument("scene", type=pathlib.Path, help="scene file (TOML)")
    p.add_argument("-o", "--output", required=True,
                   help="archive to write (netCDF, written atomically)")
    p.add_argument("--figure", default=None,
                   help="also write the standard traction-profile figure (PNG)")
    p.add_argument("--tangential", choices=("auto", "scalar", "vector"), default=None,
                   help="override the tangential form")
    p.add_argument("--fft", choices=("auto", "pyfftw", "scipy"), default=None)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--resume", action="store_true",
                   help="resumable run: an interrupted run (Ctrl-C, SIGTERM, killed) keeps "
                        "its part file and checkpoint beside OUT, and the same command "
                        "continues it; a second resumable run of OUT meanwhile exits with 3")
    p.set_defaults(func=_run, deferred=True)


def _run(args) -> int:
    from ...scene import Scene  # light: numpy, tomllib and the scene modules
    scene = Scene.from_toml(args.scene)
    inputs = [args.scene, *scene.input_files()]
    output = check_output_path(args.output, "archive (-o)", inputs=inputs)
    figure = None
    if args.figure is not None:
        figure = check_output_path(args.figure, "figure (--figure)", inputs=inputs,
                                   others=[("archive (-o)", output)])
    tangential = None if args.tangential in (None, "auto") else args.tangential
    from ...simulation import run_scene  # heavy (xarray, FFT): after the checks
    try:
        run_scene(scene, output, progress=not args.no_progress, tangential=tangential,
                  fft=args.fft, threads=args.threads, resume=args.resume)
    except ArchiveError as err:          # the archive could not be written: a failed run
        if args.debug:
            raise
        print(f"contactpipe: error: {one_line(err, with_type=False)}", file=sys.stderr)
        return 1
    print(f"wrote {output} ({_summary(output)})")
    if figure is not None:
        raise_if_signalled()             # a signal came after the archive: no figure
        # matplotlib and dask's arrays: only when a figure is asked
        from ...archive import open_archive
        from ..figures.plot import plot_profiles, save_figure
        make_folder(figure.parent)
        save_figure(plot_profiles(open_archive(output)), figure)
        print(f"wrote {figure}")
    return 0


def _summary(path) -> str:
    """The instants, models and wall time of the archive just written, from its header:
    netCDF4 reads them in milliseconds, where the archive opened lazily imports dask's
    arrays (0.23 s)."""
    import netCDF4
    with netCDF4.Dataset(path, mode="r") as nc:
        return (f"{nc.dimensions['time'].size} instants, {nc.getncattr('models')}, "
                f"{float(nc.getncattr('wall_time_s')):.2f} s")


def _command(argv) -> str | None:
    """The sub-command named in ``argv`` (its first word that is not an option)."""
    for word in argv:
        if not word.startswith("-"):
            return word
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole command line; with ``command``, only that stage's module is imported
    (the others get their one-line help; ``""``: none is): each stage module imports what
    it draws or computes with (xarray, dask, matplotlib), which a refused scene or the
    top-level help never needs."""
    parser = argparse.ArgumentParser(
        prog="contactpipe",
        description="Frictional stick-slip contact of elastic and viscoelastic bodies.")
    parser.add_argument("--version", action="version", version=f"contactpipe {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_run(sub)
    for name, (module, helptext) in STAGES.items():
        if command is not None and name != command:
            sub.add_parser(name, help=helptext, description=helptext)
            continue
        try:
            mod = importlib.import_module(module)
        except ImportError:
            continue
        p = sub.add_parser(name, help=helptext, description=(mod.__doc__ or helptext).strip(),
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        mod.add_arguments(p)
        p.set_defaults(func=mod.main)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None):
    kind = "" if issubclass(category, ResumeNotice) else "warning: "
    print(f"contactpipe: {kind}{one_line(message, with_type=False)}",
          file=file or sys.stderr)


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the flush at exit does not raise again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):   # no real file descriptor (captured)
        pass


def _error(err, code: int, with_type: bool = False) -> int:
    print(f"contactpipe: error: {one_line(err, with_type=with_type)}", file=sys.stderr)
    return code


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    # no sub-command named (``contactpipe --help``): no stage module is imported at all
    parser = build_parser(_command(argv) or "")
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help(sys.stderr)
        return 2
    # `run` acts on a signal at its safe points (between instants, before a rename): a
    # signal either stops it before its archive is renamed into place (128 + the number),
    # or came after the rename, when the run is complete (0, and one line says so)
    defer = deferred if getattr(args, "deferred", False) else contextlib.nullcontext
    try:
        with signals_as_interrupt(), warnings.catch_warnings(), defer():
            warnings.showwarning = _show_warning
            code = int(args.func(args) or 0)
            sys.stdout.flush()           # a closed pipe shows here, not at exit
            late = pending()
            if late is not None and code == 0:
                print(f"contactpipe: {signal.Signals(late).name} came after the output was "
                      f"published: the run is complete", file=sys.stderr)
            return code
    except BrokenPipeError:              # the reader left (``| head``): stop quietly
        _silence_stdout()
        return 128 + signal.SIGPIPE
    except KeyboardInterrupt as err:     # Ctrl-C, SIGTERM, SIGHUP (Interrupted)
        signum = getattr(err, "signum", signal.SIGINT)
        where = getattr(err, "resume_from", None)
        resume = f"; --resume continues from {where}" if where else ""
        print(f"contactpipe: interrupted ({signal.Signals(signum).name}){resume}",
              file=sys.stderr)
        return 128 + signum
    except Exception as err:             # noqa: BLE001 - mapped to one line and a status
        if args.debug:
            raise
        if isinstance(err, LockedError):
            return _error(err, 3)
        if isinstance(err, (SceneError, OutputPathError, ArchiveError, FileNotFoundError,
                            IsADirectoryError)):
            return _error(err, 2)        # bad input: a file, an argument, an input archive
        if isinstance(err, MemoryError):
            return _error(f"out of memory ({one_line(err)}); reduce grid.points or the "
                          "output kept in memory", 1)
        if isinstance(err, (ContactpipeError, ValueError, OSError)):
            return _error(err, 1, with_type=True)
        raise


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
