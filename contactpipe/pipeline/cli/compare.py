"""``contactpipe compare ARCHIVE.nc [REFERENCE.nc] [-o TABLE.nc|TABLE.csv] [--figure FIG.png]``

Checks an archive against the closed form of its scene, or against a reference archive,
prints the largest value of each error and when it occurs, and writes the error table
(netCDF or CSV) and the profiles figure when asked. The table comes from
:func:`contactpipe.pipeline.compare.compare`, the figure from
:func:`contactpipe.pipeline.figures.plot.plot_profiles` (the closed form dashed or the reference
dotted, on top of the numerical curves); every output path is checked before any work.
"""
from __future__ import annotations

import argparse
import pathlib

from ..._util.files import check_output_dir, check_output_path
from ..compare import tables as compare_stage
from ..figures.plot import plot_profiles, save_figure
from ..inputs import local_reads

__all__ = ["add_arguments", "main"]


DESCRIPTION = """\
Check an archive against the closed form its scene admits (Hertz, Mindlin-Deresiewicz,
Lee-Radok, the general loading's), or against a reference archive; print the largest of
each error and when it occurs, and write the error table and a profiles figure when asked.
Errors are dimensionless (tractions over the closed form's p0, the shear over mu p0, radii
over the closed-form radius, the stick radius in cells). The error variables: the
docstring of contactpipe.pipeline.compare, and docs/fretting.md for the general loading."""

EPILOG = """\
Examples:
  contactpipe compare runs/fig2.nc
  contactpipe compare runs/fig2.nc -o runs/fig2-errors.csv --figure runs/fig2-errors.png
  contactpipe compare runs/fine.nc runs/coarse.nc -o runs/fine-vs-coarse.nc"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = DESCRIPTION      # short help; the module docstrings are for developers
    parser.epilog = EPILOG
    parser.add_argument("archive", type=pathlib.Path, help="archive to check (netCDF)")
    parser.add_argument("reference", type=pathlib.Path, nargs="?", default=None,
                        help="reference archive (default: the scene's closed form)")
    # str, not pathlib.Path: Path("") is "." and an empty -o must be refused, not the cwd
    parser.add_argument("-o", "--output", default=None, metavar="TABLE",
                        help="write the error table (TABLE.nc or TABLE.csv)")
    parser.add_argument("--figure", default=None, metavar="FIG.png",
                        help="write the profiles against the closed form/reference (PNG)")


def _check_outputs(args) -> None:
    inputs = [p for p in (args.archive, args.reference) if p is not None]
    if args.output is not None:
        compare_stage.check_table_path(args.output, inputs=inputs)
    if args.figure is not None:
        others = [] if args.output is None else [("error table (-o)", args.output)]
        fig = check_output_path(args.figure, "figure", inputs=inputs, others=others)
        check_output_dir(fig.parent, "folder of the figure")


def main(args) -> int:
    _check_outputs(args)
    with local_reads():
        return _compare(args)


def _compare(args) -> int:
    table = compare_stage.compare(args.archive, args.reference, out=args.output)
    print(compare_stage.format_table(table))
    if args.output is not None:
        print(f"wrote {args.output}")
    if args.figure is not None:
        fig = plot_profiles(args.archive, closed_form=args.reference is None,
                            reference=args.reference)
        print(f"wrote {save_figure(fig, args.figure)}")
    return 0
