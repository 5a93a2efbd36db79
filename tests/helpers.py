"""Shared test helpers: the paper's elastic constants and small scene builders.

Imported by the test modules as ``from helpers import ...`` (``tests/`` is on the path
through ``pythonpath`` in pyproject's ``[tool.pytest.ini_options]``); fixtures stay in
``conftest.py``. No test depends on ../shared.
"""
import numpy as np

import contactpipe as cp

__all__ = ["STEEL", "R", "W", "MU", "E_STAR_STEEL", "A_HERTZ", "P0_HERTZ", "make_scene",
           "fretting_scene"]

# the paper's elastic case: steel on steel, R = 18 mm, W = 1 kN (Hertz: p0 = 1.996 GPa, a = 0.489 mm)
STEEL = {"material": "elastic", "young": 210e9, "poisson": 0.3}
R, W, MU = 0.018, 1000.0, 0.1
E_STAR_STEEL = 1.0 / (2 * (1 - 0.3 ** 2) / 210e9)
A_HERTZ = (3 * W * R / (4 * E_STAR_STEEL)) ** (1 / 3)
P0_HERTZ = 3 * W / (2 * np.pi * A_HERTZ ** 2)


def make_scene(**over):
    """A scene with sensible defaults; keyword tables replace or extend the defaults.

    ``geometry``, ``indenter``, ``halfspace`` and ``load`` are replaced as a whole, the
    other tables (``grid``, ``time``, ...) are merged into the defaults; ``None`` removes
    a table.
    """
    d = {
        "name": "test",
        "geometry": {"shape": "sphere", "radius": R},
        "indenter": dict(STEEL),
        "halfspace": dict(STEEL),
        "load": {"time": [0.0, 1.0], "normal_force": W},
        "grid": {"points": [64, 64], "size": [4 * A_HERTZ, 4 * A_HERTZ]},
        "time": {"steps": 1},
    }
    for k, v in over.items():
        if v is None:
            d.pop(k, None)
        elif isinstance(v, dict) and isinstance(d.get(k), dict) and k not in ("indenter", "halfspace", "load", "geometry"):
            d[k] = {**d[k], **v}
        else:
            d[k] = v
    return cp.Scene(**d)


def fretting_scene(n=128, steps=40, size=3.0, mu=MU, amplitude=0.9, **over):
    """The paper's elastic fretting loop: T: 0 -> +T* -> -T* -> +T* with T* = 0.9 mu W."""
    Ts = amplitude * mu * W
    return make_scene(friction={"mu": mu},
                      load={"time": [0.0, 0.2, 0.6, 1.0], "normal_force": W,
                            "tangential_force": [0.0, Ts, -Ts, Ts]},
                      grid={"points": [n, n], "size": [size * A_HERTZ, size * A_HERTZ]},
                      time={"steps": steps}, **over)
