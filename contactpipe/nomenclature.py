"""One table: every archive variable -> dims, units, long_name, storage type.

The names follow the paper's notation (docs/archive.md lists them). Everything that labels
a result (:mod:`contactpipe.archive`, :mod:`contactpipe.results`, sweeps) reads this
table; nothing else spells a unit or a long name.

Keys of each entry
------------------
dims : tuple of str
    ``FIELD`` (time, x1, x2), ``SERIES`` (time,) or ``MAP`` (x1, x2): a map written once,
    not per instant (the mapped friction coefficient).
units : str
    SI unit (UDUNITS spelling); ``"1"`` for dimensionless numbers and counts.
long_name : str
    Human-readable meaning (CF ``long_name``).
dtype : str
    ``"float"`` (stored as float64 or float32, the archive's precision), or a fixed
    integer type (``"int8"``, ``"int32"``).
required : bool
    In every archive. The others appear only when the scene needs them (frictional
    contact, tangential load).
model : str
    The plan slot whose model writes the variable: ``"tangential"`` for the shear, slip
    and in-plane outputs (present whenever the archive's ``model_tangential`` is not
    ``"none"``), absent for the required ones.
diagnostic : bool
    A solver diagnostic (work spent, passes): written by :func:`contactpipe.simulate`,
    never compared between archives, optional in archives of other origin.
flag_values, flag_meanings
    CF flags, ``status`` only.
"""
from __future__ import annotations

import numpy as np

__all__ = ["FIELD", "SERIES", "MAP", "CYCLE_FIELD", "CYCLE_SERIES", "LOOP_FIELD", "WEAR",
           "HISTORY", "MAPS", "VARIABLES", "COORDINATES", "GLOBAL_ATTRS",
           "REQUIRED_ATTRS", "CONVENTIONS", "TANGENTIAL", "STATUS_SEPARATED", "STATUS_STICK",
           "STATUS_SLIP", "cf_attrs", "variables_for"]

FIELD = ("time", "x1", "x2")
SERIES = ("time",)
MAP = ("x1", "x2")
#: A wear run's history: a map per record (completed cycles), a number per record, and
#: the loop of tractions of a kept cycle (every instant of that cycle).
CYCLE_FIELD = ("cycle", "x1", "x2")
CYCLE_SERIES = ("cycle",)
LOOP_FIELD = ("loop_cycle", "loop_time", "x1", "x2")
#: The ``model`` of the variables a wear run writes.
WEAR = "wear"

CONVENTIONS = "CF-1.10"

STATUS_SEPARATED, STATUS_STICK, STATUS_SLIP = 0, 1, 2
#: The ``model`` of the variables a tangential model writes.
TANGENTIAL = "tangential"


def _v(dims, units, long_name, dtype="float", required=False, **extra):
    return {"dims": dims, "units": units, "long_name": long_name, "dtype": dtype,
            "required": required, **extra}


VARIABLES: dict[str, dict] = {
    # fields over the contact grid
    "p": _v(FIELD, "Pa", "contact pressure", required=True),
    "q1": _v(FIELD, "Pa", "shear traction along x1", model=TANGENTIAL),
    "q2": _v(FIELD, "Pa", "shear traction along x2", model=TANGENTIAL),
    "u1": _v(FIELD, "m", "relative surface displacement along x1", model=TANGENTIAL),
    "u2": _v(FIELD, "m", "relative surface displacement along x2", model=TANGENTIAL),
    "u3": _v(FIELD, "m", "relative normal surface displacement (> 0 opens the gap)",
             required=True),
    "h": _v(FIELD, "m", "gap", required=True),
    "s1": _v(FIELD, "m", "accumulated slip of body 1 relative to body 2 along x1",
             model=TANGENTIAL),
    "s2": _v(FIELD, "m", "accumulated slip of body 1 relative to body 2 along x2",
             model=TANGENTIAL),
    "status": _v(FIELD, "1", "contact status", dtype="int8", required=True,
                 flag_values=(STATUS_SEPARATED, STATUS_STICK, STATUS_SLIP),
                 flag_meanings="separated stick slip"),
    # time series
    "W": _v(SERIES, "N", "normal force", required=True),
    "T1": _v(SERIES, "N", "tangential force along x1", model=TANGENTIAL),
    "T2": _v(SERIES, "N", "tangential force along x2", model=TANGENTIAL),
    "omega1": _v(SERIES, "m", "rigid-body displacement of body 1 relative to body 2 along x1",
                 model=TANGENTIAL),
    "omega2": _v(SERIES, "m", "rigid-body displacement of body 1 relative to body 2 along x2",
                 model=TANGENTIAL),
    "omega3": _v(SERIES, "m", "normal approach of body 1 towards body 2 (> 0 presses)",
                 required=True),
    "M1": _v(SERIES, "N m", "moment of the pressure about x1, sum of p x2 dA",
             required=True),
    "M2": _v(SERIES, "N m", "moment of the pressure, sum of p x1 dA", required=True),
    "M3": _v(SERIES, "N m", "torque of the shear about x3, sum of (q2 x1 - q1 x2) dA",
             required=True),
    "phi1": _v(SERIES, "rad", "rotation of body 1 relative to body 2 about x1 (gap term "
                              "-phi1 x2)", required=True),
    "phi2": _v(SERIES, "rad", "rotation of body 1 relative to body 2 (gap term -phi2 x1)",
               required=True),
    "phi3": _v(SERIES, "rad", "rotation of body 1 relative to body 2 about x3 (moves its "
                              "surface by (-phi3 x2, phi3 x1))", required=True),
    "contact_area": _v(SERIES, "m2", "contact area", required=True),
    "stick_area": _v(SERIES, "m2", "stick area", model=TANGENTIAL),
    "dissipation": _v(SERIES, "J", "frictional energy dissipated so far", model=TANGENTIAL),
    "iterations": _v(SERIES, "1", "solver iterations spent on that step (inner, all loops)",
                     dtype="int32", required=True),
    # solver diagnostics
    "coupling_passes": _v(SERIES, "1", "normal-tangential passes at that step", dtype="int32",
                          model=TANGENTIAL, diagnostic=True),
    "fft_pairs": _v(SERIES, "1", "forward+inverse padded FFT pairs spent on that step",
                    dtype="int32", diagnostic=True),
}

#: A wear run's history over its records (``cycle``) and the loops of tractions it keeps
#: (``loop_cycle``, ``loop_time``): written once at the end of the run, not per instant,
#: so kept apart from :data:`VARIABLES` like the :data:`MAPS`.
HISTORY: dict[str, dict] = {
    # the history of a wear run, over the completed cycles of each record
    "wear_depth": _v(CYCLE_FIELD, "m", "depth removed since the start, both bodies together",
                     model=WEAR),
    "worn_volume": _v(CYCLE_SERIES, "m3", "worn volume, sum of wear_depth dA", model=WEAR),
    "cumulative_dissipation": _v(CYCLE_SERIES, "J", "frictional energy dissipated from the "
                                 "start to the end of that cycle, extrapolated cycles "
                                 "included", model=WEAR),
    "cycle_p_max": _v(CYCLE_SERIES, "Pa", "largest pressure in that cycle", model=WEAR),
    "cycle_stick_area": _v(CYCLE_SERIES, "m2", "smallest stick area in that cycle",
                           model=WEAR),
    # the loops of tractions a wear run keeps (wear.keep_tractions)
    "loop_p": _v(LOOP_FIELD, "Pa", "contact pressure through a kept cycle", model=WEAR),
    "loop_q1": _v(LOOP_FIELD, "Pa", "shear traction along x1 through a kept cycle",
                  model=WEAR),
    "loop_q2": _v(LOOP_FIELD, "Pa", "shear traction along x2 through a kept cycle",
                  model=WEAR),
}

#: Maps over (x1, x2), written once (not per instant) when the scene has them. Kept apart
#: from :data:`VARIABLES`, whose names are the per-instant outputs (a sweep dimension may
#: take a map's name: ``friction.mu`` -> ``mu``).
MAPS: dict[str, dict] = {
    "mu": _v(MAP, "1", "friction coefficient (mapped)"),
    "h0": _v(MAP, "m", "initial gap of a measured or generated rough surface"),
}

COORDINATES: dict[str, dict] = {
    "time": {"units": "s", "long_name": "time"},
    "x1": {"units": "m", "long_name": "cell centre along x1"},
    "x2": {"units": "m", "long_name": "cell centre along x2"},
    "t_norm": {"units": "1", "long_name": "dimensionless time (t - t0)/window"},
    "cycle": {"units": "1", "long_name": "cycles of the load program completed"},
    "loop_cycle": {"units": "1", "long_name": "cycles completed at a kept loop's end"},
    "loop_time": {"units": "s", "long_name": "time since the kept cycle's start"},
}

# Global attributes of every archive (docs/archive.md) and their meaning.
GLOBAL_ATTRS: dict[str, str] = {
    "Conventions": "CF version followed: " + CONVENTIONS,
    "contactpipe_version": "version of contactpipe that wrote the archive",
    "scene": "the validated scene as TOML text, enough to re-run it",
    "models": "the sub-models the scene needed and used",
    "wall_time_s": "wall-clock time of the simulation [s]",
    "complete": "'true' once the archive was fully written",
}
# What a dataset must carry before it is written ("complete" is set by the writer).
REQUIRED_ATTRS = ("Conventions", "contactpipe_version", "scene", "models", "wall_time_s")

_ATTR_KEYS = ("units", "long_name", "flag_values", "flag_meanings")


def variables_for(tangential: bool, diagnostics: bool = True) -> list[str]:
    """The variables of an archive, fields first, in the order of :data:`VARIABLES`
    (the :data:`MAPS`, written once when the scene has them, are not among them).

    Parameters
    ----------
    tangential : bool
        A tangential model ran: its outputs (``model = "tangential"``) are included.
    diagnostics : bool
        Include the solver diagnostics (``coupling_passes`` only with ``tangential``).
    """
    def wanted(entry):
        if entry.get("model") == TANGENTIAL and not tangential:
            return False
        return diagnostics or not entry.get("diagnostic", False)

    names = [n for n, e in VARIABLES.items() if wanted(e)]
    return ([n for n in names if VARIABLES[n]["dims"] == FIELD]
            + [n for n in names if VARIABLES[n]["dims"] == SERIES])


def cf_attrs(name: str) -> dict:
    """The CF attributes (units, long_name, flags) of a variable or coordinate ``name``.

    Ready for netCDF: ``flag_values`` is an array of the variable's own integer type, as
    CF asks.
    """
    entry = VARIABLES.get(name) or MAPS.get(name) or HISTORY.get(name) or COORDINATES[name]
    out = {k: entry[k] for k in _ATTR_KEYS if k in entry}
    if "flag_values" in out:
        out["flag_values"] = np.asarray(out["flag_values"], dtype=entry["dtype"])
    return out
