"""Exceptions raised by contactpipe. Nothing internal is imported here."""


class ContactpipeError(Exception):
    """Base class of every error contactpipe raises on purpose."""


class SceneError(ContactpipeError, ValueError):
    """A scene (or sweep/pipeline file) is invalid.

    The message names the field (dotted path), the value given and what is allowed.
    Several problems are reported together, one per line.
    """

    def __init__(self, problems):
        if isinstance(problems, str):
            problems = [problems]
        self.problems = list(problems)
        super().__init__("; ".join(self.problems) if len(self.problems) < 2
                         else f"{len(self.problems)} problems: " + "; ".join(self.problems))


class ConvergenceError(ContactpipeError, RuntimeError):
    """A solver did not reach its tolerance; the message names the step and residual."""


class GrossSlidingError(ConvergenceError):
    """The tangential force cannot be carried in partial slip (|T| >= mu W)."""


class GridError(ContactpipeError, RuntimeError):
    """The contact reached the edge of the grid: the domain is too small."""


class ArchiveError(ContactpipeError, OSError):
    """An archive is missing, truncated, corrupt or does not follow the schema."""


class OutputPathError(ContactpipeError, ValueError):
    """An output path cannot be written: empty, a directory, a device, or an input file."""


def one_line(err: BaseException, with_type: bool = True) -> str:
    """An exception as one line of text for a message: ``Type: text`` (or just the text).

    Whitespace runs, newlines included, become one space; an empty message gives the
    type's name.
    """
    text = " ".join(str(err).split())
    if not text:
        return type(err).__name__
    return f"{type(err).__name__}: {text}" if with_type else text


class ResumeNotice(UserWarning):
    """Where a resumable run starts: the instant of its checkpoint, or the first one."""
