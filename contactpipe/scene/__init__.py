"""The scene: what is simulated (bodies, geometry, friction, load, grid, time mesh,
solver settings), read from TOML and checked before anything runs.

:class:`Scene` and its tables live in :mod:`.model` and :mod:`.parts`; the readers of
its pieces beside them: :mod:`.tables` (the table-driven reader), :mod:`.loading` (load
programs), :mod:`.geometry` (gaps and surfaces), :mod:`.friction_map` and
:mod:`.gridded` (gridded netCDF inputs), :mod:`.fit` (Prony fits of measured tables).
"""
from ..exceptions import SceneError
from .model import (
                    AUTO_MARGIN,
                    AUTO_PUNCH_FACTOR,
                    BodySpec,
                    Fretting,
                    Friction,
                    Geometry,
                    Grid,
                    Load,
                    Output,
                    Scene,
                    Solver,
                    TimeMesh,
                    Wear,
                    auto_grid_size,
                    contact_reach,
                    contact_shifts,
                    hertz_semi_axes,
)

__all__ = ["Scene", "Geometry", "BodySpec", "Friction", "Load", "Fretting", "Grid",
           "TimeMesh", "Solver", "Output", "Wear", "SceneError", "hertz_semi_axes", "contact_reach",
           "contact_shifts", "auto_grid_size", "AUTO_MARGIN", "AUTO_PUNCH_FACTOR"]
