"""The old import paths of moved modules: each warns once (DeprecationWarning) and then
is the new module itself (``sys.modules`` holds the new module under the old name), so
that every name is the same object under both paths."""
from __future__ import annotations

import importlib
import sys
import warnings

#: Release that removes the old paths.
REMOVED_IN = "0.2"
#: Modules of the package still importing an old path, pending their own refactor: no
#: warning for them (a user cannot act on it).
PENDING = {"contactpipe.solver.wisdom"}


def _importer(depth):
    """The module name of the code that imported the old path (import machinery skipped)."""
    frame = sys._getframe(depth)
    while frame is not None and "importlib" in frame.f_code.co_filename:
        frame = frame.f_back
    return frame.f_globals.get("__name__", "") if frame is not None else ""


def alias(old: str, new: str) -> None:
    """Make ``old`` an alias of module ``new``, with a DeprecationWarning that points at
    the importer's line."""
    if _importer(3) not in PENDING:
        warnings.warn(f"{old} has moved to {new}; import it from there (the old path "
                      f"goes in {REMOVED_IN})", DeprecationWarning, stacklevel=3)
    sys.modules[old] = importlib.import_module(new)
