"""One helper for each file chore: atomic writes, locks, TOML reading, output-path checks.

Every writer and reader of contactpipe goes through these, so the policy is stated once:

* :func:`atomic_path` - write to a hidden temporary file beside the target
  (``.NAME.<pid>-<token>.part``), then fsync it, ``os.replace`` it onto the target and
  fsync the folder. On any exception (Ctrl-C included) the temporary file is removed and
  the target is untouched: a reader sees the old file or the new one, never half of one.
* :func:`exclusive_lock` - a non-blocking exclusive lock on a file (``filelock``:
  ``flock`` on Unix, ``msvcrt`` on Windows); a second holder gets an error at once,
  naming who holds it.
* :func:`read_toml` / :func:`loads_toml` - TOML as a dict (``tomllib``, or ``tomli`` on
  Python 3.10), with an error naming the file.
* :func:`check_output_path` - refuse, before any work, an output path that is empty, a
  directory, a device or other special file, or one of the inputs;
  :func:`check_output_dir` the same for an output folder.
"""
from __future__ import annotations

import contextlib
import datetime
import glob
import json
import os
import pathlib
import secrets
import signal
import stat
import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    import tomli as tomllib

from ..exceptions import ContactpipeError, OutputPathError, SceneError

__all__ = ["atomic_path", "write_text", "write_json", "exclusive_lock", "LockedError",
           "read_toml", "loads_toml", "TOMLDecodeError", "check_output_path",
           "check_output_dir", "same_file", "temp_name",
           "temporaries", "publish", "utc_now", "make_folder"]

TOMLDecodeError = tomllib.TOMLDecodeError
#: Suffix of every temporary file of an atomic write (a killed process may leave one).
TEMP_SUFFIX = ".part"


class LockedError(ContactpipeError, BlockingIOError):
    """Another process holds the lock of a folder or a file."""


def utc_now() -> str:
    """The current UTC time, ISO 8601 to the second."""
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


# ----------------------------------------------------------------------------- writing

def temp_name(target, keep_suffix: bool = False) -> pathlib.Path:
    """A fresh hidden temporary name beside ``target``: ``.NAME.<pid>-<token>.part``
    (``.NAME.<pid>-<token>.part.SUFFIX`` with ``keep_suffix``, for writers that infer the
    format from the suffix). Every such name matches ``.NAME.*.part*``."""
    target = pathlib.Path(target)
    tail = target.suffix if keep_suffix else ""
    return target.with_name(f".{target.name}.{os.getpid()}-{secrets.token_hex(4)}"
                            f"{TEMP_SUFFIX}{tail}")


def temporaries(target) -> list:
    """Temporary files that interrupted atomic writes of ``target`` left behind."""
    target = pathlib.Path(target)
    if not target.parent.is_dir():
        return []
    return sorted(target.parent.glob(f".{glob.escape(target.name)}.*{TEMP_SUFFIX}*"))


def fsync_file(path) -> None:
    """Flush a written file's data to the disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_dir(folder) -> None:
    """Make a rename in ``folder`` durable (not possible on every platform: ignored there)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


#: Signals held back from this thread between the last check and the rename of
#: :func:`publish` (Unix).
_HELD = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


@contextlib.contextmanager
def _signals_held():
    """Hold back the interrupting signals from this thread (where it can): one that comes
    meanwhile is delivered on leaving."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _HELD)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def publish(tmp, target, check=None) -> None:
    """fsync a finished temporary file and rename it onto ``target`` (atomic).

    ``check``, when given, is called last before the rename, with the interrupting
    signals held back from this thread until the rename is done: a caller's
    ``check`` that raises for a signal received (a deferred Ctrl-C) stops the
    publication, and a signal that comes later finds the file published.
    """
    tmp, target = pathlib.Path(tmp), pathlib.Path(target)
    fsync_file(tmp)
    with _signals_held():
        if check is not None:
            check()
        os.replace(tmp, target)
    fsync_dir(target.parent)


@contextlib.contextmanager
def atomic_path(target, keep_suffix: bool = False):
    """Yield a temporary path to write; on success it replaces ``target`` atomically.

    >>> with atomic_path("table.csv") as tmp:
    ...     frame.to_csv(tmp)

    The folder of ``target`` must exist. On any exception the temporary file is removed
    and ``target`` is left as it was; when the block wrote nothing, ``OSError``.
    ``keep_suffix``: the temporary name ends with the target's suffix (see
    :func:`temp_name`).
    """
    target = pathlib.Path(target)
    tmp = temp_name(target, keep_suffix)
    try:
        yield tmp
        if not tmp.exists():
            raise FileNotFoundError(f"{target}: nothing was written")
        publish(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def make_folder(folder) -> pathlib.Path:
    """Create ``folder`` and its missing parents (``mkdir -p``) one level at a time, so
    that no depth of missing folders makes a RecursionError (pathlib's and os's
    ``parents=True`` recurse once per level)."""
    folder = pathlib.Path(folder)
    missing = []
    probe = folder
    while not probe.is_dir():
        missing.append(probe)
        if probe.parent == probe:
            break
        probe = probe.parent
    for level in reversed(missing):
        try:
            os.mkdir(level)
        except FileExistsError:
            if not level.is_dir():
                raise
    return folder


def write_text(target, text: str) -> pathlib.Path:
    """Write ``text`` (UTF-8) to ``target`` atomically."""
    with atomic_path(target) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return pathlib.Path(target)


def write_json(target, data) -> pathlib.Path:
    """Write ``data`` as JSON (no NaN, one item per line) to ``target`` atomically."""
    return write_text(target, json.dumps(data, indent=1, allow_nan=False) + "\n")


# ----------------------------------------------------------------------------- locks

def _holder(path: pathlib.Path) -> str:
    """Who holds the lock, as its holder wrote into the lock file ("" if unknown)."""
    try:
        with open(path, "rb") as f:
            return f.read(200).decode("utf-8", "replace").strip()
    except OSError:
        return ""


@contextlib.contextmanager
def exclusive_lock(path, what: str, error=LockedError):
    """Hold an exclusive, non-blocking lock on ``path`` (created if needed) while inside.

    Parameters
    ----------
    path : path-like
        The lock file. It stays after release; the lock dies with its process.
    what : str
        What holds the lock, for the message ("sweep", "pipeline run", "resumable run").
    error : type
        Raised when another process (or another lock object) holds it, with a message
        naming the lock file and its holder.
    """
    import filelock  # only where a lock is taken: not to validate
    path = pathlib.Path(path)
    lock = filelock.FileLock(str(path), blocking=False)
    try:
        lock.acquire()
    except filelock.Timeout:
        holder = _holder(path)
        who = f" ({holder})" if holder else ""
        raise error(f"another {what} holds the lock {path}{who}: wait for it to finish or "
                    f"use another folder") from None
    try:
        with contextlib.suppress(OSError):     # the holder, for a contender's message
            with open(path, "r+b") as f:
                f.truncate(0)
                f.write(f"pid {os.getpid()} since {utc_now()}\n".encode())
        yield
    finally:
        lock.release()


# ----------------------------------------------------------------------------- reading

#: Why a TOML text nested deeper than the parser's recursion can go is refused.
_TOO_DEEP = ("arrays or tables nested too deep to read (hundreds of levels); a scene, "
             "sweep or pipeline file needs a few")


def _too_long(err: ValueError) -> str:
    """Why Python refused to read a value (an integer longer than its digit limit)."""
    text = " ".join(str(err).split(";")[0].split())
    return (f"a value cannot be read ({text}); a scene, sweep or pipeline file needs "
            "numbers of a few digits")


def loads_toml(text: str, source: str = "the text") -> dict:
    """TOML text as a dict; :class:`SceneError` naming ``source`` if it is not TOML
    (a value nested too deep for the parser included: one line, not a RecursionError)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"{source} is not valid TOML: {err}") from None
    except RecursionError:
        raise SceneError(f"{source} is not valid TOML: {_TOO_DEEP}") from None
    except ValueError as err:            # an integer of thousands of digits
        raise SceneError(f"{source} is not valid TOML: {_too_long(err)}") from None


def read_toml(path, what: str = "") -> dict:
    """A TOML file as a dict.

    Raises
    ------
    FileNotFoundError
        No such file.
    SceneError
        The file is not UTF-8 TOML (or nests values too deep to parse); the message
        names the file and ``what`` it should be ("scene", "sweep", "pipeline").
    """
    path = pathlib.Path(path)
    with open(path, "rb") as f:
        raw = f.read()
    kind = f" {what}" if what else ""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise SceneError(f"{path} is not a valid TOML{kind} file: not UTF-8 text "
                         f"({err})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SceneError(f"{path} is not a valid TOML{kind} file: {err}") from None
    except RecursionError:
        raise SceneError(f"{path} is not a valid TOML{kind} file: {_TOO_DEEP}") from None
    except ValueError as err:            # an integer of thousands of digits
        raise SceneError(f"{path} is not a valid TOML{kind} file: {_too_long(err)}") \
            from None


# ----------------------------------------------------------------------------- checks

def same_file(a, b) -> bool:
    """``a`` and ``b`` name one file: the same resolved real path (symbolic links and
    ``..`` followed, whether the file exists yet or not), or the same existing file
    (a hard link)."""
    if a is None or b is None:
        return False
    try:
        if os.path.realpath(os.fspath(a)) == os.path.realpath(os.fspath(b)):
            return True
    except (OSError, ValueError, RuntimeError):     # a link loop: compared below
        pass
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def check_output_path(path, what: str = "output", inputs=(), others=()) -> pathlib.Path:
    """Refuse an output path before any work is done; return it as a Path.

    Refused: an empty path; an existing directory; anything that is not a regular file
    (a device such as ``/dev/null``, a FIFO, a socket); one of ``inputs`` (the file would
    overwrite what it is computed from); one of ``others``, the ``(what, path)`` pairs
    of the other outputs of the same command; a path whose folder exists as a file.
    Files are compared by their resolved real paths (and, existing, by identity).

    Raises
    ------
    OutputPathError
        One line naming the path, the problem and what is allowed.
    """
    if path is None or not os.fspath(path):
        raise OutputPathError(f"{what} path is empty: give a file name such as run.nc")
    path = pathlib.Path(os.fspath(path)).expanduser()
    for inp in inputs:
        if same_file(path, pathlib.Path(os.fspath(inp)).expanduser() if inp else None):
            raise OutputPathError(f"{what} {path} is the input file {inp}: writing "
                                  f"it would destroy the input; give another name")
    for other_what, other in others:
        if same_file(path, pathlib.Path(os.fspath(other)).expanduser() if other else None):
            raise OutputPathError(f"{what} {path} is also the {other_what}: each output "
                                  f"needs its own file; give another name")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        st = None
    except OSError as err:
        raise OutputPathError(f"{what} {path}: cannot be checked ({err.strerror})") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise OutputPathError(f"{what} {path} is an existing directory: give a file "
                                  f"name inside it, e.g. {path / 'run.nc'}")
        if not stat.S_ISREG(st.st_mode):
            raise OutputPathError(f"{what} {path} is not a regular file (a device, FIFO or "
                                  f"socket): contactpipe writes a file atomically and would "
                                  f"replace it; give a file name")
    parent = path.parent if str(path.parent) else pathlib.Path(".")
    if parent.exists() and not parent.is_dir():
        raise OutputPathError(f"{what} {path}: its folder {parent} is a file, not a "
                              f"directory")
    return path


def check_output_dir(path, what: str = "output folder", inputs=()) -> pathlib.Path:
    """Refuse an output folder before any work is done; return it as a Path.

    Refused: an empty path; anything that exists and is not a directory (a file, one of
    ``inputs``, a device such as ``/dev/null``, a FIFO, a socket); a folder to be created
    under an existing path that is not a directory. A missing folder is fine (the writer
    creates it).

    Raises
    ------
    OutputPathError
        One line naming the path, the problem and what is allowed.
    """
    if path is None or not os.fspath(path):
        raise OutputPathError(f"{what} path is empty: give a folder name such as runs/")
    path = pathlib.Path(os.fspath(path)).expanduser()
    probe = path
    while True:
        try:
            st = os.stat(probe)
        except (FileNotFoundError, NotADirectoryError):   # a file on the way: found above
            if probe.parent == probe:
                return path
            probe = probe.parent
            continue
        except OSError as err:
            raise OutputPathError(f"{what} {path}: cannot be checked "
                                  f"({err.strerror})") from None
        break
    if stat.S_ISDIR(st.st_mode):
        return path
    is_input = any(inp is not None and os.path.exists(inp) and os.path.samefile(probe, inp)
                   for inp in inputs)
    kind = ("the input file" if is_input else "a file" if stat.S_ISREG(st.st_mode)
            else "a device, FIFO or socket")
    where = f"{path} is" if probe == path else f"{path}: its parent {probe} is"
    raise OutputPathError(f"{what} {where} {kind}, not a folder: give the path of a "
                          f"folder (existing or to be created)")
