"""Batch pipeline: sweep -> compare -> plot, idempotent and safe to run from cron.

``contactpipe pipeline PIPELINE.toml [--scheduler ADDRESS] [--workers N] [--no-progress]``
runs the sweep of the file (on dask, resumable: :mod:`contactpipe.pipeline.sweep`), compares every
member with its closed form or a reference archive (:mod:`contactpipe.pipeline.compare`), draws the
standard figures of every member and an overlay of the sweep (:mod:`contactpipe.pipeline.plot`),
and writes a summary.

Pipeline file::

    name = "paper-fig3"
    out = "runs/paper-fig3"        # member archives and products (relative to this file)
    [sweep]
    file = "sweep.toml"            # a sweep file (CONTRACT §3b), relative to this file;
                                   # or inline: base = "scene.toml" (or [sweep.scene]),
                                   # mode = "product", [sweep.axes]
    [compare]                      # optional
    reference = "closed_form"      # default; or an archive path; or "none" (no compare)
    [plot]                         # optional
    figures = ["profiles", "hysteresis", "radii", "sweep"]    # default: all four
    variables = ["contact_area"]   # what the sweep overlay shows (default contact_area)
    [dask]                         # optional; overrides the sweep file's [dask]
    scheduler = ""                 # address, "synchronous", or "" (a LocalCluster)
    n_workers = 2

``out`` may also be given inside ``[sweep]``. Members without a closed form are not
compared when ``reference = "closed_form"`` (the summary says so); that is not a failure.

Outputs, in ``out``
-------------------
``<digest>.nc``, ``manifest.json``
    The member archives and the sweep manifest (:func:`contactpipe.pipeline.sweep.sweep`).
``compare/<digest>.nc``
    Per member error table (:func:`contactpipe.pipeline.compare.compare`).
``figures/<digest>-<kind>.png``
    Per member figures (``profiles``, ``hysteresis``, ``radii``).
``figures/sweep-<variable>.png``
    The members overlaid (:func:`contactpipe.pipeline.plot.plot_sweep`).
``summary.json``
    What this run did: members (values, digest, status, error), products (path, written
    or up to date), failures, wall times. Rewritten atomically on every run.

Idempotent
----------
A second run with nothing changed does no solver work (every member is skipped: its
archive is complete and valid) and rewrites no product: a comparison or figure is redone
only when missing or older than its archive (or the reference archive); the sweep overlay
when older than any member archive or when the set of members changed. Every product is
written to a temporary name and renamed, so an interrupted run leaves no half file.

Cron-safe
---------
A run holds an exclusive lock on ``out/.pipeline.lock`` (``fcntl.flock``, non-blocking);
a second run that finds it held exits at once with status 3 and one line on stderr
("another pipeline run holds the lock ..."), doing nothing. The lock dies with its
process, so a killed run never blocks the next one, and the next one resumes where it
stopped. A crontab line (every 30 minutes, no progress bars, one log)::

    */30 * * * *  cd /data/study && contactpipe pipeline paper-fig3.toml --no-progress >> pipeline.log 2>&1

Exit status: 0 all done; 1 a member (or one of its products) failed — the others are
still completed, and the failures are listed; 2 a bad pipeline or sweep file; 3 another
run holds the lock.
"""
from __future__ import annotations

import contextlib
import dataclasses
import importlib
import json
import pathlib
import sys
import time as _time

from ..exceptions import ArchiveError, ContactpipeError
from ..exceptions import one_line as _one_line
from ..files import (TEMP_SUFFIX, LockedError, atomic_path, exclusive_lock, utc_now as _now,
                     write_json as _write_json)
from .config import CLOSED_FORM, FIGURES, MEMBER_FIGURES, PipelineSpec, read_pipeline_file
from .sweep import SweepLockedError, sweep

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
        ``{"member", "digest", "stage", "error"}``; stage is simulate, compare, figures
        or sweep-figure.
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


def _mtime(path: pathlib.Path) -> int | None:
    try:
        return path.stat().st_mtime_ns
    except OSError:
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


def _atomic(path: pathlib.Path):
    """:func:`contactpipe.files.atomic_path` keeping the suffix (writers infer the format)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    return atomic_path(path, keep_suffix=True)


def _clean_tmp(folder: pathlib.Path) -> None:
    """Remove temporaries a killed run left (we hold the lock)."""
    if folder.is_dir():
        for p in folder.glob(f".*{TEMP_SUFFIX}*"):
            with contextlib.suppress(OSError):
                p.unlink()


def _read_previous(out: pathlib.Path) -> dict:
    try:
        with open(out / SUMMARY, encoding="utf-8") as f:
            prev = json.load(f)
        return prev if isinstance(prev, dict) else {}
    except (OSError, ValueError):
        return {}


def _compare_member(mod, archive, reference, product):
    """Write the comparison table of one member; returns its record."""
    if reference == CLOSED_FORM:
        form = mod.closed_form_for(archive)
        if form is None:
            return {"status": "no closed form", "path": None}
        with _atomic(product) as tmp:
            mod.compare(archive, None, out=tmp)
        return {"status": "written", "path": str(product), "closed_form": form}
    with _atomic(product) as tmp:
        mod.compare(archive, reference, out=tmp)
    return {"status": "written", "path": str(product), "reference": str(reference)}


def _applies(kind: str, ds) -> bool:
    """Whether a member figure applies: the fretting loop needs a frictional archive with
    a tangential load (as :func:`contactpipe.pipeline.plot.standard_figures` decides)."""
    if kind == "hysteresis":
        import numpy as np
        return all(v in ds for v in ("q1", "T1", "omega1")) and \
            bool(np.any(np.abs(np.asarray(ds["T1"].values)) > 0))
    return True


def _member_figures(mod, ds, archive: pathlib.Path, figdir: pathlib.Path, digest: str,
                    kinds):
    """Draw the member figures ``kinds`` that apply and are not current.

    Returns (written, up_to_date, not_applicable) lists; ``plot.plot_<kind>(ds, path)``
    draws ``figures/<digest>-<kind>.png`` (through a temporary name).
    """
    written, current, skipped = [], [], []
    for kind in kinds:
        if not _applies(kind, ds):
            skipped.append(kind)
            continue
        target = figdir / f"{digest}-{kind}.png"
        if _fresh(target, [archive]):
            current.append(target)
            continue
        fn = getattr(mod, f"plot_{kind}", None)
        if fn is None:
            raise ContactpipeError(f"the plot module has no plot_{kind}()")
        with _atomic(target) as tmp:
            fn(ds, tmp)
        written.append(target)
    return written, current, skipped


# ------------------------------------------------------------------- the run

def run_pipeline(path, *, scheduler=None, progress=True, n_workers=None,
                 client=None) -> PipelineResult:
    """Run a pipeline file: sweep -> compare -> plot -> summary (module docstring).

    Parameters
    ----------
    path : path-like
        The pipeline file (TOML).
    scheduler : str, optional
        Dask scheduler address (or ``"synchronous"``); overrides the file's ``[dask]``.
    progress : bool
        Progress bars.
    n_workers : int, optional
        LocalCluster workers; overrides the file.
    client : distributed.Client, optional
        Submit the sweep to it.

    Returns
    -------
    PipelineResult
        ``.ok`` False when a member or one of its products failed (the others were
        still completed); ``.failed`` lists them.

    Raises
    ------
    SceneError
        A bad pipeline or sweep file, or a bad member scene (nothing was run).
    PipelineLockedError
        Another run holds ``out/.pipeline.lock`` (or a sweep holds the folder).
    """
    t0 = _time.perf_counter()
    spec = read_pipeline_file(path)
    out = spec.out
    out.mkdir(parents=True, exist_ok=True)
    with exclusive_lock(out / LOCK, "pipeline run", error=PipelineLockedError):
        try:
            return _run_locked(spec, scheduler=scheduler, progress=progress,
                               n_workers=n_workers, client=client, t0=t0)
        except SweepLockedError as err:
            raise PipelineLockedError(str(err)) from None


def _run_locked(spec, *, scheduler, progress, n_workers, client, t0):
    out = spec.out
    started = _now()
    previous = _read_previous(out)
    cmpdir, figdir = out / "compare", out / "figures"
    _clean_tmp(cmpdir)
    _clean_tmp(figdir)
    res = sweep(spec.base, spec.axes, out, mode=spec.mode, client=client,
                scheduler=scheduler or spec.scheduler,
                n_workers=n_workers or spec.n_workers,
                threads_per_worker=spec.threads_per_worker, retries=spec.retries,
                progress=progress)
    failed = [{"member": m.label, "digest": m.digest, "stage": "simulate", "error": m.error}
              for m in res.failed]
    written, up_to_date = [], []
    records: dict[str, dict] = {}
    done = {}
    for m in res.members:
        if m.status == "done":
            done.setdefault(m.digest, m)
    kinds = [k for k in spec.figures if k in MEMBER_FIGURES]
    cmp_mod = plot_mod = None
    # importlib, not "from . import compare": the package resolves that name lazily
    if spec.reference is not None and done:
        cmp_mod = importlib.import_module(__package__ + ".compare")
    if (kinds or "sweep" in spec.figures) and done:
        plot_mod = importlib.import_module(__package__ + ".plot")
    from tqdm.auto import tqdm
    for digest, m in tqdm(done.items(), desc="products", unit="member",
                          disable=not progress or not done):
        archive = out / m.file
        rec = {}
        if cmp_mod is not None:
            product = cmpdir / f"{digest}.nc"
            inputs = [archive] + ([spec.reference] if spec.reference != CLOSED_FORM else [])
            if _fresh(product, inputs):
                rec["compare"] = {"status": "up to date", "path": str(product)}
                up_to_date.append(product)
            else:
                try:
                    rec["compare"] = _compare_member(cmp_mod, str(archive), spec.reference,
                                                     product)
                    if rec["compare"]["status"] == "written":
                        written.append(product)
                except Exception as err:        # noqa: BLE001 - keep going, report
                    rec["compare"] = {"status": "failed", "error": _one_line(err)}
                    failed.append({"member": m.label, "digest": digest, "stage": "compare",
                                   "error": _one_line(err)})
        if kinds:
            try:
                from ..archive import open_archive
                ds = open_archive(archive)
                try:
                    w, cur, na = _member_figures(plot_mod, ds, archive, figdir, digest,
                                                 kinds)
                finally:
                    ds.close()
                rec["figures"] = {"status": "written" if w else "up to date",
                                  "paths": [str(p) for p in w + cur],
                                  "not_applicable": na}
                written.extend(w)
                up_to_date.extend(cur)
            except Exception as err:            # noqa: BLE001 - keep going, report
                rec["figures"] = {"status": "failed", "error": _one_line(err)}
                failed.append({"member": m.label, "digest": digest, "stage": "figures",
                               "error": _one_line(err)})
        records[digest] = rec
    sweep_figs = {}
    if "sweep" in spec.figures and done:
        digests = sorted(done)
        archives = [out / done[d].file for d in digests]
        prev_sweep = previous.get("sweep_figures", {}) if isinstance(previous, dict) else {}
        sw = None
        try:
            for var in spec.variables:
                target = figdir / f"sweep-{var}.png"
                prev = prev_sweep.get(var, {}) if isinstance(prev_sweep, dict) else {}
                if prev.get("members") == digests and _fresh(target, archives):
                    sweep_figs[var] = {"status": "up to date", "path": str(target),
                                       "members": digests}
                    up_to_date.append(target)
                    continue
                if sw is None:
                    from .sweep import open_sweep
                    sw = open_sweep(out, allow_missing=True)
                x = "t_norm" if "t_norm" in sw.dims else "time"
                try:
                    with _atomic(target) as tmp:
                        plot_mod.plot_sweep(sw, tmp, variable=var, x=x)
                    sweep_figs[var] = {"status": "written", "path": str(target),
                                       "members": digests}
                    written.append(target)
                except Exception as err:        # noqa: BLE001
                    sweep_figs[var] = {"status": "failed", "error": _one_line(err)}
                    failed.append({"member": "(sweep)", "digest": None,
                                   "stage": "sweep-figure", "error": _one_line(err)})
        except ArchiveError as err:
            failed.append({"member": "(sweep)", "digest": None, "stage": "sweep-figure",
                           "error": _one_line(err)})
        finally:
            if sw is not None:
                sw.close()
    members = []
    for m in res.members:
        entry = m.to_json()
        entry["label"] = m.label
        entry["archive"] = str(out / m.file)
        entry.update(records.get(m.digest, {}))
        members.append(entry)
    summary = {
        "name": spec.name,
        "pipeline": str(spec.path.resolve()),
        "out": str(out),
        "started": started,
        "finished": _now(),
        "wall_time_s": _time.perf_counter() - t0,
        "ok": not failed,
        "counts": {"members": len(res.members), "computed": len(res.computed),
                   "skipped": len(res.skipped), "failed": len(res.failed),
                   "products_written": len(written), "products_up_to_date": len(up_to_date)},
        "sweep": {"mode": spec.mode, "axes": res.manifest["axes"],
                  "dims": res.manifest["dims"], "manifest": str(out / "manifest.json")},
        "compare": {"reference": None if spec.reference is None else str(spec.reference)},
        "figures": list(spec.figures),
        "members": members,
        "sweep_figures": sweep_figs,
        "failed": failed,
    }
    _write_json(out / SUMMARY, summary)
    return PipelineResult(spec=spec, sweep=res, summary=summary, written=written,
                          up_to_date=up_to_date, failed=failed)


# ------------------------------------------------------------------- command line

def add_arguments(parser) -> None:
    parser.add_argument("pipeline_file", type=pathlib.Path, metavar="PIPELINE.toml",
                        help="pipeline file (see the description)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="dask scheduler address or 'synchronous' (default: the file's "
                             "[dask] scheduler, else a LocalCluster)")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="LocalCluster worker processes")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")


def main(args) -> int:
    try:
        res = run_pipeline(args.pipeline_file, scheduler=args.scheduler,
                           n_workers=args.workers, progress=not args.no_progress)
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
