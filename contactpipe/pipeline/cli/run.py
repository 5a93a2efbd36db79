"""Batch pipeline: sweep -> compare -> plot -> stress, idempotent and safe to run from cron.

``contactpipe pipeline PIPELINE.toml [--scheduler ADDRESS] [--workers N]
[--shared-disk | --no-shared-disk] [--no-progress]``
runs the sweep of the file (on dask, resumable: :mod:`contactpipe.pipeline.sweep`), compares every
member with its closed form or a reference archive (:mod:`contactpipe.pipeline.compare`), draws the
standard figures of every member and an overlay of the sweep
(:mod:`contactpipe.pipeline.figures.plot`), computes the subsurface stress of every member
when the file asks for it (:mod:`contactpipe.pipeline.cli.stress`), and writes a summary.

Pipeline file::

    name = "paper-fig3"
    out = "runs/paper-fig3"        # member archives and products (relative to this file)
    [sweep]
    file = "sweep.toml"            # a sweep file (docs/scene-file.md), relative to this file;
                                   # or inline: base = "scene.toml" (or [sweep.scene]),
                                   # mode = "product", [sweep.axes]
    [compare]                      # optional
    reference = "closed_form"      # default; or an archive path; or "none" (no compare)
    [plot]                         # optional
    figures = ["profiles", "hysteresis", "radii", "sweep"]    # default: all four
    variables = ["contact_area"]   # what the sweep overlay shows (default contact_area;
                                   # a wear run's worn_volume... against cycle)
    [stress]                       # optional: the subsurface stress of every member
    depths = [0.0, 1e-4, 2e-4]     # m, >= 0; or {max = 1e-3, count = 11} (min = 0)
    body = "halfspace"             # or "indenter"
    time = "all"                   # "last" (default), "all", or a list of times [s]
    criterion = "crossland"        # none (default) | amplitude | crossland | dang_van | swt
    torsion_limit = 400e6          # the criterion's constants [Pa] (docs/stress.md)
    bending_limit = 600e6
    cycle = [0.2, 1.0]             # s: the instants the criterion runs over (default all)
    [dask]                         # optional; overrides the sweep file's [dask]
    scheduler = ""                 # address, "synchronous", or "" (a LocalCluster);
    n_workers = 2                  # an address is TRUSTED code (see below)

A scheduler address is trusted code: dask's protocol unpickles what the scheduler sends,
so never point a pipeline at a scheduler you do not control (the sweep's workers need
not share this machine's disk: :mod:`contactpipe.pipeline.sweep.execute`).

``out`` may also be given inside ``[sweep]``; it must be a folder (existing or to be
created): a file, a device or the pipeline file itself is refused before any work. Members
without a closed form are not compared when ``reference = "closed_form"`` (the summary says so);
that is not a failure.

Outputs, in ``out``
-------------------
``<digest>.nc``, ``manifest.json``
    The member archives and the sweep manifest (:func:`contactpipe.pipeline.sweep.sweep`).
``compare/<digest>.nc``
    Per member error table (:func:`contactpipe.pipeline.compare.compare`).
``figures/<digest>-<kind>.png``
    Per member figures (``profiles``, ``hysteresis``, ``radii``, ``maps``, and ``wear``
    for a wear run).
``figures/sweep-<variable>.png``
    The members overlaid (:func:`contactpipe.pipeline.figures.plot.plot_sweep`).
``stress/<digest>.nc``, ``figures/<digest>-stress.png``
    With ``[stress]``: the member's stress field over (time, x3, x1, x2) and, with a
    criterion, the criterion's fields over (x3, x1, x2), in one file
    (:func:`contactpipe.pipeline.cli.stress.write_stress_product`; streamed block by
    block, bounded memory), and its figure (the ``stress`` kind of
    :mod:`contactpipe.pipeline.figures.plot`: the criterion, else von Mises, on the x1-x3 plane
    through the centre and on the surface).
``summary.json``
    What this run did: members (values, digest, status, error), products (path, written
    or up to date), failures, wall times. Rewritten atomically on every run.

Idempotent
----------
A second run with nothing changed does no solver work (every member is skipped: its
archive is complete and valid) and rewrites no product: a comparison or figure is redone
only when missing or older than its archive (or the reference archive); the sweep overlay
when older than any member archive or when the set of members changed; a stress product
when older than its archive or made with other ``[stress]`` settings (the digest of the
settings is stored in the product and compared: a change of depths, body, instants,
criterion, constants, cycle or precision recomputes it), its figure when older than it. Every
product is written to a temporary name and renamed, so an interrupted run leaves no half file.
Figures are drawn by :mod:`contactpipe.pipeline.figures.plot` and written by its
:func:`~contactpipe.pipeline.figures.plot.save_figure`.

Cron-safe
---------
A run holds an exclusive lock on ``out/.pipeline.lock``
(:func:`contactpipe._util.files.exclusive_lock`, non-blocking);
a second run that finds it held exits at once with status 3 and one line on stderr
("another pipeline run holds the lock ..."), doing nothing. The lock dies with its
process, so a killed run never blocks the next one, and the next one resumes where it
stopped. A crontab line (every 30 minutes, no progress bars, one log)::

    */30 * * * * cd /data && contactpipe pipeline paper-fig3.toml --no-progress >> pipeline.log 2>&1

Exit status: 0 all done; 1 a member (or one of its products) failed — the others are
still completed, and the failures are listed; 2 a bad pipeline or sweep file or out
folder; 3 another run holds the lock.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib
import sys
import time as _time

from tqdm.auto import tqdm

from ..._util.files import TEMP_SUFFIX, LockedError, check_output_dir, exclusive_lock, make_folder
from ..._util.files import utc_now as _now
from ..._util.files import write_json as _write_json
from ...exceptions import ArchiveError, ContactpipeError
from ...exceptions import one_line as _one_line
from ..compare import tables as compare_stage
from ..compare.reference import closed_form_for
from ..figures import plot as plot_stage
from ..sweep import SweepLockedError, sweep
from ..sweep.combine import open_sweep
from ..sweep.config import CLOSED_FORM, FIGURES, MEMBER_FIGURES, PipelineSpec, read_pipeline_file
from . import stress as stress_stage

__all__ = ["run_pipeline", "read_pipeline_file", "PipelineSpec", "PipelineResult",
           "PipelineLockedError", "MEMBER_FIGURES", "FIGURES", "LOCK", "SUMMARY",
           "EXIT_LOCKED", "add_arguments", "main"]

LOCK = ".pipeline.lock"
SUMMARY = "summary.json"
EXIT_LOCKED = 3


class PipelineLockedError(LockedError):
    """Another pipeline run (or a sweep) holds the lock of the output folder."""


# ------------------------------------------------------------------- products

@dataclasses.dataclass
class PipelineResult:
    """What :func:`run_pipeline` did.

    Attributes
    ----------
    spec : PipelineSpec
    sweep : SweepResult
    summary : dict
        As written to ``out/summary.json``.
    written, up_to_date : list of pathlib.Path
        Products written by this run, and those left alone because they were current.
    failed : list of dict
        ``{"member", "digest", "stage", "error"}``; stage is simulate, compare, figures,
        stress, stress-figure or sweep-figure.
    """

    spec: PipelineSpec
    sweep: object
    summary: dict
    written: list
    up_to_date: list
    failed: list

    @property
    def ok(self) -> bool:
        return not self.failed

    @property
    def computed(self):
        return self.sweep.computed

    @property
    def skipped(self):
        return self.sweep.skipped


#: The failures of one product that the pipeline records and goes on after: a bad
#: archive or scene (ContactpipeError), a value a stage refuses (ValueError), the disk
#: (OSError). Anything else is a bug and stops the run with its own message.
PRODUCT_ERRORS = (ContactpipeError, ValueError, OSError)


@dataclasses.dataclass
class _Log:
    """The products of a run: written, up to date, failed."""

    written: list = dataclasses.field(default_factory=list)
    up_to_date: list = dataclasses.field(default_factory=list)
    failed: list = dataclasses.field(default_factory=list)

    def fail(self, member: str, digest, stage: str, err) -> dict:
        error = err if isinstance(err, str) else _one_line(err)
        self.failed.append({"member": member, "digest": digest, "stage": stage,
                            "error": error})
        return {"status": "failed", "error": error}


def _mtime(path: pathlib.Path) -> int | None:
    try:
        return path.stat().st_mtime_ns
    except FileNotFoundError:
        return None


def _fresh(product: pathlib.Path, inputs) -> bool:
    """The product exists and is not older than any input."""
    t = _mtime(product)
    if t is None:
        return False
    for p in inputs:
        ti = _mtime(pathlib.Path(p))
        if ti is None or ti > t:
            return False
    return True


def _clean_tmp(folder: pathlib.Path) -> None:
    """Remove temporaries a killed run left (we hold the lock)."""
    if folder.is_dir():
        for p in folder.glob(f".*{TEMP_SUFFIX}*"):
            p.unlink(missing_ok=True)


def _read_previous(out: pathlib.Path) -> dict:
    """The summary of the previous run ({} when there is none or it is not JSON)."""
    try:
        with open(out / SUMMARY, encoding="utf-8") as f:
            prev = json.load(f)
    except FileNotFoundError:
        return {}
    except ValueError:                  # not JSON (a hand edit, a foreign file): start anew
        return {}
    return prev if isinstance(prev, dict) else {}


def _compare_member(archive, reference, product) -> dict:
    """Write the comparison table of one member; returns its record."""
    if reference == CLOSED_FORM:
        form = closed_form_for(archive)
        if form is None:
            return {"status": "no closed form", "path": None}
        compare_stage.compare(archive, None, out=product)
        return {"status": "written", "path": str(product), "closed_form": form}
    compare_stage.compare(archive, reference, out=product)
    return {"status": "written", "path": str(product), "reference": str(reference)}


def _compare_product(spec, m, archive, product, log: _Log) -> dict:
    inputs = [archive] + ([spec.reference] if spec.reference != CLOSED_FORM else [])
    if _fresh(product, inputs):
        log.up_to_date.append(product)
        return {"status": "up to date", "path": str(product)}
    try:
        rec = _compare_member(str(archive), spec.reference, product)
    except PRODUCT_ERRORS as err:
        return log.fail(m.label, m.digest, "compare", err)
    if rec["status"] == "written":
        log.written.append(product)
    return rec


def _member_figures(ds, archive: pathlib.Path, figdir: pathlib.Path, digest: str, kinds):
    """Draw the member figures ``kinds`` that apply and are not current.

    Returns (written, up_to_date, not_applicable) lists; ``plot.plot_<kind>(ds)`` draws
    the figure, :func:`~contactpipe.pipeline.figures.plot.save_figure` writes
    ``figures/<digest>-<kind>.png``.
    """
    written, current, skipped = [], [], []
    for kind in kinds:
        if not plot_stage.figure_applies(kind, ds):
            skipped.append(kind)
            continue
        target = figdir / f"{digest}-{kind}.png"
        if _fresh(target, [archive]):
            current.append(target)
            continue
        draw = getattr(plot_stage, f"plot_{kind}")
        plot_stage.save_figure(draw(ds), target)
        written.append(target)
    return written, current, skipped


def _figure_products(m, archive, figdir, kinds, log: _Log) -> dict:
    try:
        ds, _ = compare_stage.load_dataset(archive)
        with ds:
            w, cur, na = _member_figures(ds, archive, figdir, m.digest, kinds)
    except PRODUCT_ERRORS as err:
        return log.fail(m.label, m.digest, "figures", err)
    log.written.extend(w)
    log.up_to_date.extend(cur)
    return {"status": "written" if w else "up to date", "paths": [str(p) for p in w + cur],
            "not_applicable": na}


def _stress_product(st_spec, m, archive, out, log: _Log) -> dict:
    """The ``[stress]`` product of one member (and its figure), unless current: not
    older than the archive and made with the same settings (their digest)."""
    product = out / "stress" / f"{m.digest}.nc"
    rec = None
    if _fresh(product, [archive]) and stress_stage.stored_digest(product) == st_spec.digest():
        try:
            rec = dict(stress_stage.product_record(product), status="up to date")
            log.up_to_date.append(product)
        except PRODUCT_ERRORS:            # unreadable after all: made anew
            rec = None
    if rec is None:
        try:
            rec = dict(stress_stage.write_stress_product(archive, product, st_spec),
                       status="written")
        except PRODUCT_ERRORS as err:
            return log.fail(m.label, m.digest, "stress", err)
        log.written.append(product)
    if not st_spec.figure:
        return rec
    figure = out / "figures" / f"{m.digest}-stress.png"
    if _fresh(figure, [product]):
        log.up_to_date.append(figure)
    else:
        try:
            plot_stage.save_figure(plot_stage.plot_stress(product), figure)
        except PRODUCT_ERRORS as err:
            rec["figure"] = log.fail(m.label, m.digest, "stress-figure", err)
            return rec
        log.written.append(figure)
    rec["figure"] = str(figure)
    return rec


def _member_products(spec, m, out, log: _Log) -> dict:
    """The comparison, figures and stress product of one member that is done."""
    archive = out / m.file
    rec = {}
    if spec.reference is not None:
        rec["compare"] = _compare_product(spec, m, archive, out / "compare" / f"{m.digest}.nc",
                                          log)
    kinds = [k for k in spec.figures if k in MEMBER_FIGURES]
    if kinds:
        rec["figures"] = _figure_products(m, archive, out / "figures", kinds, log)
    if spec.stress is not None:
        rec["stress"] = _stress_product(spec.stress, m, archive, out, log)
    return rec


def _sweep_figures(spec, out, done: dict, previous: dict, log: _Log) -> dict:
    """The overlays of the sweep (one per variable) that are not current."""
    digests = sorted(done)
    archives = [out / done[d].file for d in digests]
    prev_sweep = previous.get("sweep_figures", {})
    figs, todo = {}, []
    for var in spec.variables:
        target = out / "figures" / f"sweep-{var}.png"
        prev = prev_sweep.get(var, {}) if isinstance(prev_sweep, dict) else {}
        if isinstance(prev, dict) and prev.get("members") == digests \
                and _fresh(target, archives):
            figs[var] = {"status": "up to date", "path": str(target), "members": digests}
            log.up_to_date.append(target)
        else:
            todo.append((var, target))
    if not todo:
        return figs
    try:
        sw = open_sweep(out, allow_missing=True)
    except ArchiveError as err:
        log.fail("(sweep)", None, "sweep-figure", err)
        return figs
    with sw:
        x = "t_norm" if "t_norm" in sw.dims else "time"
        for var, target in todo:
            try:
                plot_stage.save_figure(plot_stage.plot_sweep(sw, variable=var, x=x), target)
            except PRODUCT_ERRORS as err:
                figs[var] = log.fail("(sweep)", None, "sweep-figure", err)
                continue
            figs[var] = {"status": "written", "path": str(target), "members": digests}
            log.written.append(target)
    return figs


# ------------------------------------------------------------------- the run

def run_pipeline(path, *, scheduler=None, progress=True, n_workers=None,
                 client=None, shared_disk=None) -> PipelineResult:
    """Run a pipeline file: sweep -> compare -> plot -> stress -> summary (module docstring).

    Parameters
    ----------
    path : path-like
        The pipeline file (TOML).
    scheduler : str, optional
        Dask scheduler address (or ``"synchronous"``); overrides the file's ``[dask]``.
        Trusted code: dask unpickles what the scheduler sends.
    progress : bool
        Progress bars.
    n_workers : int, optional
        LocalCluster workers; overrides the file.
    client : distributed.Client, optional
        Submit the sweep to it.
    shared_disk : bool, optional
        Whether the sweep's workers write the archives into ``out`` themselves
        (:func:`contactpipe.pipeline.sweep.sweep`).

    Returns
    -------
    PipelineResult
        ``.ok`` False when a member or one of its products failed (the others were
        still completed); ``.failed`` lists them.

    Raises
    ------
    SceneError
        A bad pipeline or sweep file, or a bad member scene (nothing was run).
    OutputPathError
        ``out`` exists and is not a folder, or is the pipeline file (nothing was run).
    PipelineLockedError
        Another run holds ``out/.pipeline.lock`` (or a sweep holds the folder).
    """
    t0 = _time.perf_counter()
    spec = read_pipeline_file(path)
    out = check_output_dir(spec.out, "pipeline out folder", inputs=[spec.path])
    make_folder(out)
    with exclusive_lock(out / LOCK, "pipeline run", error=PipelineLockedError):
        try:
            return _run_locked(spec, scheduler=scheduler, progress=progress,
                               n_workers=n_workers, client=client, shared_disk=shared_disk,
                               t0=t0)
        except SweepLockedError as err:
            raise PipelineLockedError(str(err)) from None


def _summary(spec, res, started, t0, records, sweep_figs, log: _Log) -> dict:
    out = spec.out
    members = []
    for m in res.members:
        entry = m.to_json()
        entry["label"] = m.label
        entry["archive"] = str(out / m.file)
        entry.update(records.get(m.digest, {}))
        members.append(entry)
    return {
        "name": spec.name,
        "pipeline": str(spec.path.resolve()),
        "out": str(out),
        "started": started,
        "finished": _now(),
        "wall_time_s": _time.perf_counter() - t0,
        "ok": not log.failed,
        "counts": {"members": len(res.members), "computed": len(res.computed),
                   "skipped": len(res.skipped), "failed": len(res.failed),
                   "products_written": len(log.written),
                   "products_up_to_date": len(log.up_to_date)},
        "sweep": {"mode": spec.mode, "axes": res.manifest["axes"],
                  "dims": res.manifest["dims"], "manifest": str(out / "manifest.json")},
        "compare": {"reference": None if spec.reference is None else str(spec.reference)},
        "figures": list(spec.figures),
        "stress": None if spec.stress is None else {"settings": spec.stress.settings(),
                                                    "digest": spec.stress.digest()},
        "members": members,
        "sweep_figures": sweep_figs,
        "failed": log.failed,
    }


def _run_locked(spec, *, scheduler, progress, n_workers, client, shared_disk, t0):
    out = spec.out
    started = _now()
    previous = _read_previous(out)
    _clean_tmp(out / "compare")
    _clean_tmp(out / "figures")
    _clean_tmp(out / "stress")
    res = sweep(spec.base, spec.axes, out, mode=spec.mode, client=client,
                scheduler=scheduler or spec.scheduler,
                n_workers=n_workers or spec.n_workers,
                threads_per_worker=spec.threads_per_worker, retries=spec.retries,
                progress=progress, shared_disk=shared_disk)
    log = _Log()
    for m in res.failed:
        log.fail(m.label, m.digest, "simulate", m.error or "failed")
    done = {}
    for m in res.members:
        if m.status == "done":
            done.setdefault(m.digest, m)
    records = {}
    for digest, m in tqdm(done.items(), desc="products", unit="member",
                          disable=not progress or not done):
        records[digest] = _member_products(spec, m, out, log)
    sweep_figs = _sweep_figures(spec, out, done, previous, log) \
        if "sweep" in spec.figures and done else {}
    summary = _summary(spec, res, started, t0, records, sweep_figs, log)
    _write_json(out / SUMMARY, summary)
    return PipelineResult(spec=spec, sweep=res, summary=summary, written=log.written,
                          up_to_date=log.up_to_date, failed=log.failed)


# ------------------------------------------------------------------- command line

def add_arguments(parser) -> None:
    parser.add_argument("pipeline_file", type=pathlib.Path, metavar="PIPELINE.toml",
                        help="pipeline file (see the description)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="dask scheduler address or 'synchronous' (default: the file's "
                             "[dask] scheduler, else a LocalCluster). Trusted: dask "
                             "unpickles what the scheduler sends")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="LocalCluster worker processes")
    parser.add_argument("--shared-disk", action=argparse.BooleanOptionalAction,
                        default=None,
                        help="the sweep's workers write the archives into the out folder "
                             "themselves, or send them back (default: in place on this "
                             "machine, sent back from another cluster)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")


def main(args) -> int:
    try:
        res = run_pipeline(args.pipeline_file, scheduler=args.scheduler,
                           n_workers=args.workers, progress=not args.no_progress,
                           shared_disk=args.shared_disk)
    except PipelineLockedError as err:
        print(f"contactpipe: {' '.join(str(err).split())}; nothing done", file=sys.stderr)
        return EXIT_LOCKED
    c = res.summary["counts"]
    print(f"pipeline {res.spec.name}: {c['members']} members: {c['computed']} computed, "
          f"{c['skipped']} skipped, {c['failed']} failed; products: "
          f"{c['products_written']} written, {c['products_up_to_date']} up to date; "
          f"summary {res.spec.out / SUMMARY}")
    if res.failed:
        for f in res.failed:
            print(f"  failed ({f['stage']}): {f['member']}"
                  + (f" ({f['digest']}.nc)" if f.get("digest") else "")
                  + f": {f['error']}", file=sys.stderr)
        names = sorted({f["member"] for f in res.failed})
        print(f"contactpipe: error: {len(res.failed)} failure(s) in pipeline "
              f"{res.spec.name}: {'; '.join(names)}", file=sys.stderr)
        return 1
    return 0
