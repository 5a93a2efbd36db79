"""A synthetic archive of a wear run, shaped as the archive's documented wear schema
(docs/wear.md): the last simulated cycle's fields over (time, x1, x2) and the wear history
over ``cycle``, made from the closed-form limiting state so that its figures mean
something. For the tests of the stages built on wear archives (figures, fatigue)."""
import numpy as np
import xarray as xr

from contactpipe import analytic as an

E_STAR = 210e9 / (2 * (1 - 0.3 ** 2))
R, W, MU = 0.018, 1000.0, 0.3
T_STAR = 0.875 * MU * W


def _da(dims, values, units):
    return (dims, np.asarray(values), {"units": units})


def wear_dataset(n=24, steps=8, cycles=(1, 3, 10, 30, 100, 300, 1000), simulated=7,
                 kept=None):
    """A contract-shaped wear archive (float64) over an n x n grid of side 3a.

    The wear depth grows as (1 - exp(-N/300)) times the limiting wear depth; worn volume
    is its sum times the cell area, and the dissipation is worn_volume mu / k (Archard's
    identity) with k = 1e-14 1/Pa. ``kept``: cycles whose loop of tractions (Hertz p,
    Cattaneo q1 of the instant's force) is kept as loop_p, loop_q1, loop_q2 over
    (loop_cycle, loop_time, x1, x2), scaled by 1 + cycle / last kept cycle.
    """
    lim = an.fretting_wear_limit(W, T_STAR, MU, R, E_STAR)
    hz = an.hertz_sphere(W, R, E_STAR)
    a = hz.contact_radius
    d = 3 * a / n
    x = -1.5 * a + (np.arange(n) + 0.5) * d
    r = np.hypot(x[:, None], x[None, :])
    t = np.linspace(0.0, 1.0, steps + 1)[1:]
    T = T_STAR * np.sin(2 * np.pi * t)
    p = np.broadcast_to(hz.pressure(r), (steps, n, n)).copy()
    q1 = np.stack([an.cattaneo_mindlin(f, MU, W, a, hz.max_pressure).traction(r)
                   for f in T])
    cyc = np.asarray(cycles, np.int64)
    grow = 1.0 - np.exp(-cyc / 300.0)
    depth = grow[:, None, None] * lim.wear_depth(r)[None]
    volume = depth.sum(axis=(1, 2)) * d * d
    k = 1e-14
    status = np.where(p > 0, np.where(np.abs(q1) < MU * p * (1 - 1e-9), 1, 2), 0)
    ds = xr.Dataset(
        {"p": _da(("time", "x1", "x2"), p, "Pa"),
         "q1": _da(("time", "x1", "x2"), q1, "Pa"),
         "q2": _da(("time", "x1", "x2"), np.zeros_like(p), "Pa"),
         "status": (("time", "x1", "x2"), status.astype(np.int8), {"units": "1"}),
         "T1": _da(("time",), T, "N"),
         "omega1": _da(("time",), T / 1e8, "m"),
         "wear_depth": _da(("cycle", "x1", "x2"), depth, "m"),
         "worn_volume": _da(("cycle",), volume, "m3"),
         "cumulative_dissipation": _da(("cycle",), volume * MU / k, "J"),
         "cycle_p_max": _da(("cycle",), hz.max_pressure * (1 + grow), "Pa"),
         "cycle_stick_area": _da(("cycle",), np.pi * lim.stick_radius ** 2 * np.ones(len(cyc)),
                                 "m2")},
        coords={"time": _da(("time",), t, "s"), "x1": _da(("x1",), x, "m"),
                "x2": _da(("x2",), x, "m"), "cycle": ("cycle", cyc, {"units": "1"})},
        attrs={"title": "synthetic-wear", "wear_law": "archard",
               "cycles_simulated": int(simulated)})
    if kept:
        kc = np.asarray(kept, np.int64)
        scale = 1.0 + (kc / kc.max())[:, None, None, None]
        loop = ("loop_cycle", "loop_time", "x1", "x2")
        ds["loop_p"] = (loop, p[None] * scale, {"units": "Pa"})
        ds["loop_q1"] = (loop, q1[None] * scale, {"units": "Pa"})
        ds["loop_q2"] = (loop, np.zeros((len(kc),) + p.shape), {"units": "Pa"})
        ds = ds.assign_coords(loop_cycle=("loop_cycle", kc, {"units": "1"}),
                               loop_time=("loop_time", t, {"units": "s"}))
    return ds


def wear_run(path, n=16, cycles=10, keep=2, k=1e-11):
    """A real wear run written to ``path``: steel on steel, W = 1 kN, mu = 0.3, T = 0 ->
    T* -> 0 -> -T* -> 0 with T* = 0.875 mu W, 8 steps a cycle, Archard, jump auto, the
    loops of ``keep`` cycles kept. Returns the path."""
    import contactpipe as cp
    steel = {"material": "elastic", "young": 210e9, "poisson": 0.3}
    a = an.hertz_sphere(W, R, E_STAR).contact_radius
    scene = cp.Scene(
        name="wear-run", geometry={"shape": "sphere", "radius": R},
        indenter=dict(steel), halfspace=dict(steel), friction={"mu": MU},
        load={"time": [0, 0.25, 0.5, 0.75, 1.0], "normal_force": W,
              "tangential_force": [0, T_STAR, 0, -T_STAR, 0]},
        grid={"points": [n, n], "size": [3.5 * a, 3.5 * a]}, time={"steps": 8},
        wear={"law": "archard", "coefficient": k, "cycles": cycles, "jump": "auto",
              "keep_tractions": keep})
    cp.simulate(scene, path).close()
    return path
