"""Termination signals as interrupts: a run cleans up on SIGTERM and SIGHUP as on Ctrl-C.

:func:`signals_as_interrupt` turns the signals into :class:`Interrupted` (a
``KeyboardInterrupt``) in the main thread; :func:`raise_if_signalled` lets a long loop act
on a signal whose exception was swallowed. Used by :func:`contactpipe.simulate` and the
command line.
"""
from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["Interrupted", "signals_as_interrupt", "raise_if_signalled"]


class Interrupted(KeyboardInterrupt):
    """A termination signal (SIGTERM, SIGHUP) handled as Ctrl-C; ``signum`` says which."""

    def __init__(self, signum: int):
        super().__init__(f"terminated by {signal.Signals(signum).name}")
        self.signum = int(signum)


#: Termination signals received while :func:`signals_as_interrupt` is active.
_RECEIVED: list = []


@contextlib.contextmanager
def signals_as_interrupt(names=("SIGTERM", "SIGHUP"), only_default: bool = False):
    """Inside, the termination signals raise :class:`Interrupted` in the main thread.

    A run then cleans up as on Ctrl-C: temporary files removed, the part file and
    checkpoint of a resumable run kept. A second such signal during the clean-up is
    ignored. The march also checks after every instant (:func:`raise_if_signalled`), so a
    signal whose exception was swallowed (it came while a finalizer ran, where Python only
    prints exceptions) still ends the run. Outside the main thread (dask workers)
    nothing is installed; with ``only_default`` only signals still at their default
    action are taken over (the library's own use, so that an application's handlers win).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        signal.signal(signum, signal.SIG_IGN)      # the clean-up is not interrupted again
        _RECEIVED.append(signum)
        raise Interrupted(signum)

    previous = {}
    for name in names:
        signum = getattr(signal, name, None)      # SIGHUP does not exist on Windows
        if signum is None or (only_default and signal.getsignal(signum) is not signal.SIG_DFL):
            continue
        previous[signum] = signal.signal(signum, handler)
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)
            while signum in _RECEIVED:
                _RECEIVED.remove(signum)


def raise_if_signalled() -> None:
    """Raise :class:`Interrupted` for a termination signal received (and not yet acted on)."""
    if _RECEIVED:
        raise Interrupted(_RECEIVED[0])
