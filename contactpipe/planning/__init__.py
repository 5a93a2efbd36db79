"""Planning a run before it starts: which sub-models the scene needs (:mod:`.rules`,
a table of rules), what it costs in memory and time (:mod:`.resources`), and the
accuracy presets that set its grid, steps and preload (:mod:`.accuracy`)."""
from .resources import Resources, available_memory, check_resources, check_time, estimate_resources
from .rules import RULES, Plan, Rule, models, pair_couples, plan, q2_reasons

__all__ = ["Plan", "plan", "pair_couples", "q2_reasons", "RULES", "Rule", "models",
           "Resources", "estimate_resources", "available_memory", "check_resources",
           "check_time"]
