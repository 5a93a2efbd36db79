"""The old import paths of moved modules: each warns once (DeprecationWarning) and then
is the new module itself (``sys.modules`` holds the new module under the old name), so
that every name is the same object under both paths."""
from __future__ import annotations

import importlib
import sys
import warnings

#: Release that removes the old paths.
REMOVED_IN = "0.2"


_PACKAGE_INIT = __file__.rsplit("_util", 1)[0] + "__init__.py"


def _importer():
    """The stack level of the code that imported the old path, as ``warnings.warn``
    counts it from :func:`alias` (the import system's frames skipped, and
    ``contactpipe.__getattr__``, which imports on behalf of ``cp.<name>``)."""
    frame, level = sys._getframe(2), 2                  # the old path's module
    frame = frame.f_back
    while frame is not None:
        name = frame.f_code.co_filename
        if not ("importlib" in name and "_bootstrap" in name):   # warnings skips those
            level += 1
            if "importlib" not in name and name != _PACKAGE_INIT:
                return level
        frame = frame.f_back
    return level


def alias(old: str, new: str) -> None:
    """Make ``old`` an alias of module ``new``, with a DeprecationWarning that points at
    the importer's line."""
    warnings.warn(f"{old} has moved to {new}; import it from there (the old path goes in "
                  f"{REMOVED_IN})", DeprecationWarning, stacklevel=_importer())
    sys.modules[old] = importlib.import_module(new)
