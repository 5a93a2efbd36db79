"""The sweep stage: :func:`sweep` runs a scene's members on dask (resuming included) and
``contactpipe sweep`` (:mod:`.driver`); the members and their parameters (:mod:`.members`,
:mod:`.parameters`), where they run (:mod:`.execute`), the folder's manifest
(:mod:`.manifest`), the sweep and pipeline files (:mod:`.config`) and :func:`open_sweep`
(:mod:`.combine`).

The names below load their module on first use (module ``__getattr__``): reading a sweep
folder (:func:`open_sweep`, the figures) imports neither the driver nor dask.distributed,
the simulation or the FFTs."""
from __future__ import annotations

from ..._util.lazy import lazy_names

#: Public names and the modules that define them.
_LAZY = {
    "sweep": "driver", "SweepResult": "driver", "SweepLockedError": "driver",
    "ScriptReimportError": "driver", "archive_state": "driver", "add_arguments": "driver",
    "main": "driver", "LOCK": "driver",
    "open_sweep": "combine", "open_member": "combine",
    "load_sweep_file": "config", "read_sweep_file": "config", "SweepFile": "config",
    "SYNCHRONOUS": "execute",
    "read_manifest": "manifest", "MANIFEST": "manifest",
    "Member": "members", "MODES": "members",
    "register_parameter": "parameters", "derived_parameters": "parameters",
    "relaxation_time": "parameters", "tau_ratio": "parameters", "with_window": "parameters",
}

__all__ = ["sweep", "open_sweep", "open_member", "SweepResult", "Member",
           "SweepLockedError", "ScriptReimportError", "register_parameter",
           "derived_parameters", "relaxation_time", "with_window",
           "tau_ratio", "load_sweep_file", "read_sweep_file", "SweepFile",
           "read_manifest", "archive_state", "add_arguments", "main",
           "MANIFEST", "LOCK", "MODES", "SYNCHRONOUS"]


__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
