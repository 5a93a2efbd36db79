"""FFTW wisdom kept between processes, so that a grid's plans are measured once per machine.

Only the pyFFTW path uses it (:mod:`.convolution` imports this module where pyFFTW is
installed).

Measuring the pruned DC-FFT plans (:class:`contactpipe.solver.convolution.Convolver`,
``FFTW_MEASURE``) takes a sizeable fraction of a second per grid, in every process: every
run, and every worker of a sweep. FFTW can export what it learnt ("wisdom") and take it
back; with it, the same plans are made in milliseconds (docs/design-choices.md, D8). The
plans are then also the same from one process to the next, and so is
their rounding (without wisdom each process measures afresh and may choose other
algorithms, which moves results by rounding and pair counts by a few pairs).

The wisdom lives in one small text file (FFTW's own format, double precision only):

* ``CONTACTPIPE_FFTW_WISDOM=/some/file``: that file;
* ``CONTACTPIPE_FFTW_WISDOM=off`` (or ``0``, ``no``, ``none``, empty): none kept;
* unset: ``$XDG_CACHE_HOME/contactpipe/`` (``~/.cache/contactpipe/``), one file per
  host, processor architecture and pyFFTW version (wisdom is only good on the machine
  that measured it; the nodes of a cluster that share a home keep one file each); none
  where there is no absolute home or cache folder.

It is a cache and nothing more: a missing, unreadable or foreign file is ignored (FFTW
refuses wisdom it cannot parse), and a file that cannot be written is not written. Writes
go to a temporary file renamed over the old one, so that processes that plan at the same
time never leave a half-written file (:func:`contactpipe._util.files.atomic_path`).
"""
from __future__ import annotations

import os
import platform
import re
from pathlib import Path

import pyfftw  # loaded by .convolution first, without its dask interface

from .._util.files import atomic_path

__all__ = ["ENV", "load", "path", "save"]

#: The environment variable that names the wisdom file, or turns it off.
ENV = "CONTACTPIPE_FFTW_WISDOM"
_OFF = {"", "off", "0", "no", "none", "false"}

_known: dict[Path, bytes] = {}      # what this process loaded or saved, per file


def path() -> Path | None:
    """The wisdom file of this process, or None when it is turned off."""
    value = os.environ.get(ENV)
    if value is not None:
        return None if value.strip().lower() in _OFF else Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME", "")
    if not os.path.isabs(base):       # unset or relative: the XDG default
        base = os.path.join(os.path.expanduser("~"), ".cache")
    if not os.path.isabs(base):       # no home to speak of: keep none rather than guess
        return None
    host = re.sub(r"[^A-Za-z0-9._-]", "_", platform.node() or "host")
    return (Path(base) / "contactpipe" / f"fftw-wisdom-{host}-{platform.machine() or 'cpu'}"
                                         f"-pyfftw-{pyfftw.__version__}.txt")


def load() -> bool:
    """Give FFTW the wisdom of the file (once per process and file); True if it took it."""
    p = path()
    if p is None or p in _known:
        return False
    try:
        data = p.read_bytes()
    except OSError:
        _known[p] = b""
        return False
    _known[p] = data
    return bool(pyfftw.import_wisdom((data, b"", b""))[0])


def save() -> bool:
    """Write FFTW's double-precision wisdom to the file when it holds something new;
    True if written."""
    p = path()
    if p is None:
        return False
    data = pyfftw.export_wisdom()[0]
    if not data or _known.get(p) == data:
        return False
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(p) as tmp:
            tmp.write_bytes(data)
    except OSError:
        return False
    _known[p] = data
    return True
