"""Running a scene: :func:`simulate` marches the contact through the time mesh
(:mod:`.march`) on a problem set up once (:mod:`.problem`: the grid, the operators and the
frictional preload's estimate)."""
from .march import (
                    Interrupted,
                    ResumeLockedError,
                    ResumeNotice,
                    ResumeWarning,
                    State,
                    grid_coordinates,
                    raise_if_signalled,
                    run_scene,
                    signals_as_interrupt,
                    simulate,
)

__all__ = ["simulate", "run_scene", "grid_coordinates", "State", "ResumeLockedError",
           "ResumeWarning", "ResumeNotice", "Interrupted", "signals_as_interrupt",
           "raise_if_signalled"]
