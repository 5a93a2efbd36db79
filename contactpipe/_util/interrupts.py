"""Ctrl-C and the termination signals as interrupts, acted on where the state is whole.

:func:`signals_as_interrupt` turns SIGINT, SIGTERM and SIGHUP into :class:`Interrupted`
(a ``KeyboardInterrupt``) in the main thread. Inside :func:`deferred` a first signal is
only recorded: the code acts on it at its next safe point (:func:`raise_if_signalled`:
between two instants of a run, and just before an archive is renamed into place), so a
run can checkpoint the instant it reached and the signal is never lost inside a
finalizer (where Python only prints exceptions). A second signal while the first waits
is acted on at once. Used by :func:`contactpipe.simulate` and the command line.
"""
from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["Interrupted", "signals_as_interrupt", "deferred", "raise_if_signalled",
           "pending"]


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or a termination signal (SIGTERM, SIGHUP); ``signum`` says which.

    ``resume_from`` is set by a resumable run that checkpointed before stopping: a short
    text saying where ``--resume`` continues (None otherwise).
    """

    def __init__(self, signum: int):
        name = signal.Signals(signum).name
        super().__init__(f"interrupted by {name}" if signum == signal.SIGINT
                         else f"terminated by {name}")
        self.signum = int(signum)
        self.resume_from: str | None = None


#: Signals received while :func:`signals_as_interrupt` is active and not yet acted on.
_RECEIVED: list = []
#: [depth of the :func:`deferred` blocks entered, 1 once a signal was raised (the
#: clean-up that follows is not interrupted again)].
_STATE = [0, 0]


def _handler(signum, frame):
    _RECEIVED.append(signum)
    if _STATE[1]:                       # the clean-up of an interrupt is under way
        return
    if _STATE[0] and len(_RECEIVED) == 1:
        return                          # deferred: acted on at the next safe point
    _STATE[1] = 1
    raise Interrupted(signum)


def _is_default(signum) -> bool:
    current = signal.getsignal(signum)
    return current is signal.SIG_DFL or (signum == signal.SIGINT
                                         and current is signal.default_int_handler)


@contextlib.contextmanager
def signals_as_interrupt(names=("SIGINT", "SIGTERM", "SIGHUP"), only_default: bool = False):
    """Inside, the signals ``names`` raise :class:`Interrupted` in the main thread.

    A run then cleans up alike whichever came: temporary files removed, the part file
    and checkpoint of a resumable run kept. Inside :func:`deferred` the first signal
    waits for the next safe point; a signal that comes during the clean-up is ignored.
    Outside the main thread (dask workers) nothing is installed; with ``only_default``
    only signals still at their default action (for SIGINT: Python's
    ``KeyboardInterrupt``) are taken over (the library's own use, so that an
    application's handlers win).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    for name in names:
        signum = getattr(signal, name, None)      # SIGHUP does not exist on Windows
        if signum is None or (only_default and not _is_default(signum)):
            continue
        previous[signum] = signal.signal(signum, _handler)
    outermost = not any(h is _handler for h in previous.values())
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)
            while signum in _RECEIVED:
                _RECEIVED.remove(signum)
        if outermost and previous:
            _STATE[1] = 0


@contextlib.contextmanager
def deferred():
    """Inside, a first signal is recorded, not raised: the code acts on it at its safe
    points (:func:`raise_if_signalled`). On leaving, a signal still waiting is left
    recorded (:func:`pending`) for the caller to act on."""
    _STATE[0] += 1
    try:
        yield
    finally:
        _STATE[0] -= 1


def pending() -> int | None:
    """The signal received and not yet acted on, or None."""
    return _RECEIVED[0] if _RECEIVED else None


def raise_if_signalled() -> None:
    """Raise :class:`Interrupted` for a signal received (and not yet acted on)."""
    if _RECEIVED:
        _STATE[1] = 1
        raise Interrupted(_RECEIVED[0])
