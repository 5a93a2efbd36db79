"""The ``[load]`` table of a scene: the load program through its knots (six freedoms,
force or motion controlled) and the fretting preset that writes one
(:class:`Load`, :class:`Fretting`; the programs themselves: :mod:`.loading`)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .loading import MAX_STEPS, ROWS, Programs, knot_steps, per_knot, program_field, read_program
from .tables import Field, Part, Reader, is_sequence, show

__all__ = ["Load", "Fretting", "PRELOADS", "MAX_CYCLES"]

PRELOADS = ("frictional", "frictionless")
#: Cap on fretting cycles, against absurd sizes (far beyond a practical simulation).
MAX_CYCLES = 100_000


def _positive(x) -> bool:
    return x > 0


# ----------------------------------------------------------------------------- load

@dataclass(frozen=True)
class Fretting(Part):
    """Fretting-loop preset of the load (``[load.fretting]``).

    The tangential force goes 0 -> +T* -> -T* -> +T* ... at a constant rate under a
    normal force applied as a step at t = 0. Rising to +T* takes one time unit and each
    half cycle two, so ``cycles`` = n takes 1 + 4 n units over ``window``: knots at units
    0, 1, 3, 5, ..., 1 + 4 n. One cycle gives time = [0, tau/5, 3 tau/5, tau] and
    T = [0, T*, -T*, T*]; the default time mesh then has 1 + 4 n steps.

    Parameters
    ----------
    amplitude : float
        T* [N], > 0.
    window : float
        tau, the total duration [s], > 0.
    cycles : int
        Number of full cycles (-T* and back to +T*), from 1 to 100 000.
    direction : float
        Angle of the tangential force from x1 [deg]; T1 = T cos, T2 = T sin.
    """

    amplitude: float
    window: float
    cycles: int = 1
    direction: float = 0.0

    PATH = "load.fretting"
    FIELDS = (
        Field("amplitude", "number", "T*, a finite number > 0 [N]", ok=_positive,
              required=True, unit="N"),
        Field("window", "number", "tau, the total duration, a finite number > 0 [s]",
              ok=_positive, required=True, unit="s"),
        Field("cycles", "integer", f"an integer from 1 to {MAX_CYCLES}",
              ok=lambda n: 1 <= n <= MAX_CYCLES, default=1),
        Field("direction", "number", "the angle of T from x1, a finite number [deg]",
              default=0.0, unit="deg"),
    )

    def knots(self):
        """(time [s], T [N]) at the knots, T signed along ``direction``."""
        units = 1 + 4 * self.cycles
        u = np.array([0] + [1 + 2 * k for k in range(2 * self.cycles + 1)], dtype=float)
        t = u * self.window / units
        T = np.array([0.0] + [self.amplitude * (-1.0) ** k
                              for k in range(2 * self.cycles + 1)])
        return t, T

    def unit_vector(self):
        """(cos, sin) of ``direction``, exact on the axes."""
        a = math.radians(self.direction)
        c, s = math.cos(a), math.sin(a)
        c = 0.0 if abs(c) < 1e-15 else c
        s = 0.0 if abs(s) < 1e-15 else s
        return c, s


def _check_times(t, key):
    bad = [i for i in range(1, len(t)) if t[i] <= t[i - 1]]
    if bad:
        i = bad[0]
        return (f"{key} must be strictly increasing, got {show(list(t))} (time[{i}] = "
                f"{t[i]:g} s <= time[{i - 1}] = {t[i - 1]:g} s)")
    if not math.isfinite(t[-1] - t[0]):
        return (f"{key} spans {t[0]:g} to {t[-1]:g} s, a duration beyond the range of a "
                f"float; give times of a finite span")
    return None


_NORMAL_WHAT = ("a force >= 0 [N] (a step at time[0]) or a list with one force >= 0 [N] "
                "per load.time knot (or give load.normal_approach instead)")


@dataclass(frozen=True)
class Load(Part):
    """The load program, piecewise linear through knots (:mod:`contactpipe.scene.loading`).

    Each of the six rigid-body freedoms of body 1 relative to body 2 is force-controlled
    or displacement-controlled (at most one key per row of :data:`loading.ROWS`): a
    scalar is a step applied at time[0], a list gives one value per knot.

    Parameters
    ----------
    time : tuple of float
        Knot times [s], strictly increasing (at least one). Absent (None) with
        ``fretting``: read the program through :meth:`knots` / :meth:`programs`, which
        serve both forms.
    normal_force : float or tuple of float
        W [N]; required unless ``normal_approach`` is given.
    tangential_force : tuple, optional
        T [N] per knot: floats along x1 (T2 = 0), or (T1, T2) pairs. Absent (and no
        ``tangential_displacement``): T = 0.
    preload : {"frictional", "frictionless"}
        Whether friction acts during the normal preload.
    fretting : Fretting, optional
        A fretting-loop preset instead of ``time`` and ``tangential_force``.
    normal_approach : float or tuple of float, optional
        ω3 [m] (> 0 presses the bodies together; the contact may open, W = 0).
    tangential_displacement : float or tuple, optional
        ω1 [m], or (ω1, ω2) pairs: rigid displacement of body 1 relative to body 2; the
        contact may slide as a whole.
    moment1, moment2, moment3 : float or tuple of float, optional
        M1 = Δ Σ p x2, M2 = Δ Σ p x1, M3 = Δ Σ (q2 x1 − q1 x2) [N m]; 0 leaves the
        rotation free.
    rotation1, rotation2, rotation3 : float or tuple of float, optional
        φ1, φ2, φ3 [rad]. A rotation whose row is absent is held at 0.
    """

    time: tuple | None = None
    normal_force: float | tuple | None = None
    tangential_force: tuple | None = None
    preload: str = "frictional"
    fretting: Fretting | None = None
    normal_approach: float | tuple | None = None
    tangential_displacement: float | tuple | None = None
    moment1: float | tuple | None = None
    moment2: float | tuple | None = None
    moment3: float | tuple | None = None
    rotation1: float | tuple | None = None
    rotation2: float | tuple | None = None
    rotation3: float | tuple | None = None

    PATH = "load"
    FIELDS = (
        Field("time", "numbers", "a list of at least 1 strictly increasing times [s]",
              min_length=1, check=_check_times, unit="s"),
        Field("normal_force", ("number", "numbers"), _NORMAL_WHAT, ok=lambda x: x >= 0,
              required=True, unit="N"),
        Field("tangential_force", ("numbers", "pairs"),
              "a list of forces [N] along x1 or a list of [T1, T2] pairs [N], one per "
              "load.time knot", min_length=1, unit="N"),
        Field("preload", "choice", options=PRELOADS, default="frictional"),
        Field("fretting", "table", "amplitude [N], window [s], cycles, direction [deg]",
              part=Fretting),
        program_field("normal_approach", "m", "an approach omega3"),
        program_field("tangential_displacement", "m", "a displacement omega", pairs=True),
        program_field("moment1", "N m", "a moment M1"),
        program_field("moment2", "N m", "a moment M2"),
        program_field("moment3", "N m", "a moment M3"),
        program_field("rotation1", "rad", "a rotation phi1"),
        program_field("rotation2", "rad", "a rotation phi2"),
        program_field("rotation3", "rad", "a rotation phi3"),
    )
    #: The keys read by :func:`loading.read_program` (one value, or one per knot).
    PROGRAM_KEYS = ("normal_approach", "tangential_displacement", "moment1", "moment2",
                    "moment3", "rotation1", "rotation2", "rotation3")

    @classmethod
    def read(cls, raw, path, problems):
        r = Reader(raw, path, problems)
        r.check_keys(cls.FIELDS)
        v = {"preload": r.value(cls.field("preload")), "time": None, "fretting": None,
             "tangential_force": None}
        n = None  # number of knots, when known
        if r.has("fretting"):
            v["fretting"] = r.value(cls.field("fretting"))
            if v["fretting"] is not None:
                n = 2 * v["fretting"].cycles + 2
            for k in ("time", "tangential_force", "tangential_displacement"):
                if r.has(k):
                    r.add(f"{r.key(k)} = {show(r.raw[k])} cannot be given with {path}."
                          f"fretting: the preset makes the time program and the tangential "
                          f"force; remove one of them")
        else:
            v["time"] = r.value(cls.field("time"), need=" (or a [load.fretting] preset)",
                                required=True)
            n = None if v["time"] is None else len(v["time"])
        for row in ROWS:
            if r.has(row.force_key) and r.has(row.motion_key):
                r.add(f"{r.key(row.force_key)} and {r.key(row.motion_key)} both control the "
                      f"{row.name} freedom ({row.what('force')} | {row.what('motion')}): "
                      f"give one of them")
        approach = r.has("normal_approach") and not r.has("normal_force")
        v["normal_force"] = None if approach else \
            _read_normal_force(r, cls.field("normal_force"), n)
        if r.has("tangential_force") and not r.has("fretting"):
            tf = r.value(cls.field("tangential_force"))
            if tf is not None and n is not None and len(tf) != n:
                r.add(f"{r.key('tangential_force')} has {len(tf)} values but load.time has "
                      f"{n} knots: give one value per knot")
                tf = None
            v["tangential_force"] = tf
        for key in cls.PROGRAM_KEYS:
            v[key] = read_program(r, cls.field(key), n)
        if v["normal_approach"] is not None and \
                max(np.atleast_1d(v["normal_approach"])) <= 0:
            r.add(f"{r.key('normal_approach')} = {show(r.raw['normal_approach'])} is <= 0 "
                  f"at every knot: nothing is in contact; give an approach > 0 [m] at some "
                  f"knot")
        return cls.make(**v) if r.ok else None

    @property
    def step_load(self) -> bool:
        """True when the normal row (force or approach) is a scalar step at time[0]."""
        normal = self.normal_force if self.normal_approach is None else self.normal_approach
        return not isinstance(normal, tuple)

    def _times(self):
        if self.fretting is not None:
            return self.fretting.knots()[0]
        return np.array(self.time, dtype=float)

    def _tangential(self, values, t):
        """(first, second) components of a tangential program per knot."""
        if values is None:
            return np.zeros_like(t), np.zeros_like(t)
        if not isinstance(values, tuple):
            return np.full(t.shape, float(values)), np.zeros_like(t)
        if isinstance(values[0], tuple):
            return (np.array([p[0] for p in values], dtype=float),
                    np.array([p[1] for p in values], dtype=float))
        return np.array(values, dtype=float), np.zeros_like(t)

    def knots(self):
        """The force program at its knots: (time [s], W [N], T1 [N], T2 [N]) float
        arrays; NaN in place of a force that is displacement-controlled
        (``normal_approach``, ``tangential_displacement``: see :meth:`programs`)."""
        t = self._times()
        if self.fretting is not None:
            _, T = self.fretting.knots()
            c, s = self.fretting.unit_vector()
            T1, T2 = T * c, T * s
        elif self.tangential_displacement is not None:
            T1 = T2 = np.full(t.shape, np.nan)
        else:
            T1, T2 = self._tangential(self.tangential_force, t)
        if self.normal_force is None:
            W = np.full(t.shape, np.nan)
        elif self.step_load:
            W = np.full(t.shape, self.normal_force, dtype=float)
        else:
            W = np.array(self.normal_force, dtype=float)
        return t, W, T1, T2

    def programs(self, steps: int | None = None) -> Programs:
        """The six programs (:class:`contactpipe.scene.loading.Programs`): at the knots, or on
        the uniform mesh of ``steps`` + 1 instants from time[0] to time[-1]."""
        t, W, T1, T2 = self.knots()
        nan = np.full(t.shape, np.nan)
        om1, om2 = (self._tangential(self.tangential_displacement, t)
                    if self.tangential_displacement is not None else (nan, nan))
        force = [W, T1, T2]
        motion = [per_knot(self.normal_approach, t), om1, om2]
        keys = ["normal_force" if self.normal_approach is None else "normal_approach",
                "tangential_force" if self.tangential_displacement is None
                else "tangential_displacement"]
        keys.append(keys[-1])
        for i in (1, 2, 3):
            m, rot = getattr(self, f"moment{i}"), getattr(self, f"rotation{i}")
            force.append(per_knot(m, t))
            motion.append(nan if m is not None else
                          (np.zeros_like(t) if rot is None else per_knot(rot, t)))
            keys.append(f"moment{i}" if m is not None else (f"rotation{i}" if rot is not None
                                                            else ""))
        out = Programs(t, np.array(force), np.array(motion), tuple(keys))
        if steps is None:
            return out
        return out.on(np.linspace(t[0], t[-1], int(steps) + 1))

    def instants(self, steps: int):
        """The force program on the uniform mesh of ``steps`` + 1 instants from time[0] to
        time[-1], interpolated linearly between knots: (t [s], W [N], T1 [N], T2 [N])
        (NaN where displacement-controlled; :meth:`programs` gives all six)."""
        p = self.programs(steps)
        return p.t, p.force[0], p.force[1], p.force[2]

    @property
    def window(self) -> float:
        """Duration of the program, time[-1] - time[0] [s]."""
        t = self.knots()[0]
        return float(t[-1] - t[0])

    def default_steps(self):
        """The default number of time steps: the least whose uniform mesh holds every
        knot (:func:`knot_steps`; 1 + 4 n for a fretting preset of n cycles, one per
        interval for equally spaced knots), or None when that needs more than
        :data:`MAX_STEPS` steps."""
        return knot_steps(self.knots()[0], MAX_STEPS)


def _read_normal_force(r: Reader, f: Field, n):
    """The normal force: a scalar step, or one value per knot (``n`` knots, if known)."""
    v = r.raw.get(f.name)
    key = r.key(f.name)
    if is_sequence(v) and r.has("fretting"):
        r.add(f"{key} must be a scalar (a step at t = 0) with {r.path}.fretting, got {show(v)}")
        return None
    normal = r.value(f, need="")
    if normal is None:
        return None
    if not isinstance(normal, tuple):
        if normal == 0:
            r.add(f"{key} = {show(v)}: zero normal force leaves nothing in contact; give a "
                  f"force > 0 [N]")
            return None
        return normal
    if n is not None and len(normal) != n:
        r.add(f"{key} has {len(normal)} values but load.time has {n} knots: give one value "
              f"per knot, or a scalar (a step at time[0])")
        return None
    if not any(x > 0 for x in normal):
        r.add(f"{key} is zero at every knot, got {show(v)}: nothing is in contact; give a "
              f"force > 0 [N]")
        return None
    return normal
