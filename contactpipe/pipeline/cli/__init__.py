"""The command line: ``contactpipe`` and its sub-commands (:mod:`.main`), the batch
pipeline (:mod:`.run`), the speed figures (:mod:`.bench`), and the ``stress`` and
``compare`` commands (:mod:`.stress`, :mod:`.compare`)."""
from .main import build_parser, main

__all__ = ["main", "build_parser"]
