"""The sweep stage: :func:`sweep` runs a scene's members on dask (resuming included) and
``contactpipe sweep`` (:mod:`.driver`); the members and their parameters (:mod:`.members`,
:mod:`.parameters`), where they run (:mod:`.execute`), the folder's manifest
(:mod:`.manifest`), the sweep and pipeline files (:mod:`.config`) and :func:`open_sweep`
(:mod:`.combine`)."""
from .driver import (
                     LOCK,
                     MANIFEST,
                     MODES,
                     SYNCHRONOUS,
                     Member,
                     ScriptReimportError,
                     SweepFile,
                     SweepLockedError,
                     SweepResult,
                     add_arguments,
                     archive_state,
                     derived_parameters,
                     load_sweep_file,
                     main,
                     open_member,
                     open_sweep,
                     read_manifest,
                     read_sweep_file,
                     register_parameter,
                     relaxation_time,
                     sweep,
                     tau_ratio,
                     with_window,
)

__all__ = ["sweep", "open_sweep", "open_member", "SweepResult", "Member",
           "SweepLockedError", "ScriptReimportError", "register_parameter",
           "derived_parameters", "relaxation_time", "with_window",
           "tau_ratio", "load_sweep_file", "read_sweep_file", "SweepFile",
           "read_manifest", "archive_state", "add_arguments", "main",
           "MANIFEST", "LOCK", "MODES", "SYNCHRONOUS"]
