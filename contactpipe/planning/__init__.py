"""Planning a run before it starts: which sub-models the scene needs (:mod:`.rules`,
a table of rules), what it costs in memory and time (:mod:`.resources`), and the
accuracy presets that set its grid, steps and preload (:mod:`.accuracy`).

The names below load their module on first use (module ``__getattr__``): the rules
(:func:`pair_couples`, the closed forms' choice) do not import the solver, whose window
sizes :mod:`.resources` reads."""
from __future__ import annotations

from .._util.lazy import lazy_names

#: Public names and the modules that define them.
_LAZY = {
    **dict.fromkeys(("Resources", "available_memory", "check_resources", "check_time",
                     "estimate_resources"), "resources"),
    **dict.fromkeys(("RULES", "Plan", "Rule", "models", "pair_couples", "plan",
                     "q2_reasons"), "rules"),
}

__all__ = ["Plan", "plan", "pair_couples", "q2_reasons", "RULES", "Rule", "models",
           "Resources", "estimate_resources", "available_memory", "check_resources",
           "check_time"]


__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
