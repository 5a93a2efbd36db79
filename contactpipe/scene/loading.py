"""The load program of the six rigid-body freedoms (paper eqs. 1-4; docs/conventions.md).

Each freedom of body 1 relative to body 2 is force-controlled or displacement-controlled,
as a piecewise-linear program through the knots of ``load.time``. One table
(:data:`ROWS`) says which scene keys control which freedoms; :class:`Programs` holds the
six programs at a set of instants (the knots, or the uniform time mesh): a force where the
freedom is force-controlled (NaN elsewhere), a motion where it is displacement-controlled
(NaN elsewhere).

=========  =====================  ============================  =======================
row        force key [unit]       displacement key [unit]       absent
=========  =====================  ============================  =======================
normal     ``normal_force`` [N]   ``normal_approach`` [m]       one of them is required
tangential ``tangential_force``   ``tangential_displacement``   T = 0 (force-controlled)
           [N], T1 or [T1, T2]    [m], ω1 or [ω1, ω2]
tilt 1     ``moment1`` [N m]      ``rotation1`` [rad]           φ1 held at 0
tilt 2     ``moment2`` [N m]      ``rotation2`` [rad]           φ2 held at 0
twist      ``moment3`` [N m]      ``rotation3`` [rad]           φ3 held at 0
=========  =====================  ============================  =======================

M1 = Δ Σ p x2, M2 = Δ Σ p x1, M3 = Δ Σ (q2 x1 − q1 x2); the gap is
h = hi + u3 − ω3 − φ1 x2 − φ2 x1 and φ3 moves body 1's surface point by (−φ3 x2, φ3 x1).
A moment given as 0 leaves its rotation free; an absent one holds it at 0 (the reaction
moment is reported).

This module also holds :func:`knot_steps`, the least uniform mesh through the knots.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .tables import Field, Reader

__all__ = ["Row", "ROWS", "FREEDOMS", "Programs", "knot_steps", "MAX_STEPS",
           "program_field", "read_program", "per_knot"]

#: Cap on time steps (each step is a full contact solve).
MAX_STEPS = 1_000_000

#: The six freedoms, in the order of :class:`Programs`' arrays: (force, motion) names.
FREEDOMS = (("W", "omega3"), ("T1", "omega1"), ("T2", "omega2"), ("M1", "phi1"),
            ("M2", "phi2"), ("M3", "phi3"))


@dataclass(frozen=True)
class Row:
    """One row of the load table: the keys that control some freedoms."""

    name: str
    force_key: str
    motion_key: str
    force_unit: str
    motion_unit: str
    freedoms: tuple          # indices into FREEDOMS

    def what(self, which: str) -> str:
        """The row's freedoms in words, e.g. 'W | omega3'."""
        names = [FREEDOMS[i][0 if which == "force" else 1] for i in self.freedoms]
        return ", ".join(names)


ROWS = (
    Row("normal", "normal_force", "normal_approach", "N", "m", (0,)),
    Row("tangential", "tangential_force", "tangential_displacement", "N", "m", (1, 2)),
    Row("tilt 1", "moment1", "rotation1", "N m", "rad", (3,)),
    Row("tilt 2", "moment2", "rotation2", "N m", "rad", (4,)),
    Row("twist", "moment3", "rotation3", "N m", "rad", (5,)),
)


@dataclass(frozen=True)
class Programs:
    """The six programs at a set of instants.

    Attributes
    ----------
    t : ndarray (n,)
        The instants [s].
    force : ndarray (6, n)
        W [N], T1, T2 [N], M1, M2, M3 [N m] (:data:`FREEDOMS` order); NaN where the
        freedom is displacement-controlled.
    motion : ndarray (6, n)
        ω3 [m], ω1, ω2 [m], φ1, φ2, φ3 [rad]; NaN where the freedom is force-controlled.
    keys : tuple of str
        The scene key that controls each freedom ("" for a rotation held at 0).
    """

    t: np.ndarray
    force: np.ndarray
    motion: np.ndarray
    keys: tuple

    def is_force(self, i: int) -> bool:
        """Freedom ``i`` is force-controlled."""
        return not np.isnan(self.force[i]).all()

    def at(self, k: int):
        """(force (6,), motion (6,)) at instant ``k``."""
        return self.force[:, k].copy(), self.motion[:, k].copy()

    @functools.cached_property
    def _sizes(self) -> np.ndarray:
        """(12, 1): each freedom's largest |force| then |motion| over the instants, 1 where
        it is 0 or never controlled (the scales of :meth:`continuation`)."""
        size = np.abs(np.nan_to_num(np.concatenate([self.force, self.motion]))).max(axis=1)
        return np.where(size > 0.0, size, 1.0)[:, None]

    def continuation(self, k: int, rtol: float = 1e-9) -> float:
        """c > 0 where the programs' increment into instant ``k`` is c times the one into
        k − 1 (every freedom, each relative to its largest value, within ``rtol`` of the
        increment): the load goes on along a straight path. 0 otherwise: k < 2, a knot's
        turn, a reversal, or a load held (nothing to go on with) [1]."""
        if k < 2:
            return 0.0
        P = np.nan_to_num(np.concatenate([self.force[:, k - 2:k + 1],
                                          self.motion[:, k - 2:k + 1]])) / self._sizes
        d1, d0 = P[:, 2] - P[:, 1], P[:, 1] - P[:, 0]
        dd = float(d0 @ d0)
        if dd == 0.0:
            return 0.0
        c = float(d1 @ d0) / dd
        if c <= 0.0 or np.linalg.norm(d1 - c * d0) > rtol * np.linalg.norm(d1):
            return 0.0
        return c

    def on(self, tm) -> Programs:
        """The programs interpolated linearly onto the instants ``tm`` [s]."""
        tm = np.atleast_1d(np.asarray(tm, dtype=float))

        def interp(a):
            return np.array([np.full(tm.shape, np.nan) if np.isnan(row).all()
                             else np.interp(tm, self.t, row) for row in a])

        return Programs(tm, interp(self.force), interp(self.motion), self.keys)

    @property
    def general(self) -> bool:
        """Anything beyond W and T force-controlled with the rotations held at 0."""
        return not (self.is_force(0) and self.is_force(1)
                    and not any(self.is_force(i) for i in (3, 4, 5))
                    and np.all(self.motion[3:] == 0.0))

    @property
    def moves(self) -> bool:
        """A rotation program is given (not held at 0) or a moment is force-controlled:
        the moment arms are needed."""
        return any(self.is_force(i) for i in (3, 4, 5)) or bool(np.any(self.motion[3:] != 0))


def program_field(key, unit, what, ok=None, pairs=False):
    """A per-knot program key: a scalar (a step at time[0]) or one value per knot (a
    pair per knot for both tangential components)."""
    kinds = ("number", "numbers", "pairs") if pairs else ("number", "numbers")
    per = f"a list of {what} [{unit}] per load.time knot"
    if pairs:
        per += f", or a list of [{what}1, {what}2] pairs"
    return Field(key, kinds, f"{what} [{unit}] (a step at time[0]) or {per}", ok=ok,
                 unit=unit)


def per_knot(values, t):
    """A program's values at the knots (NaN where absent; a scalar is a step)."""
    if values is None:
        return np.full(t.shape, np.nan)
    if isinstance(values, tuple):
        return np.array(values, dtype=float)
    return np.full(t.shape, float(values))


def read_program(r: Reader, f: Field, n):
    """A program key: a scalar step, or one value (pair) per knot (``n`` knots, if known)."""
    if not r.has(f.name):
        return None
    value = r.value(f)
    if isinstance(value, tuple) and n is not None and len(value) != n:
        r.add(f"{r.key(f.name)} has {len(value)} values but load.time has {n} knots: give "
              f"one value per knot, or a scalar (a step at time[0])")
        return None
    return value


def knot_steps(t, limit: int = MAX_STEPS):
    """The least number of uniform steps from ``t[0]`` to ``t[-1]`` whose instants hold
    every knot of ``t``: the least common multiple of the denominators of the knots'
    positions (t_k - t_0) / (t_n - t_0) written as fractions.

    A knot counts as held when it lies within 1e-9 of a step of an instant (plus the
    rounding of its float). Returns 0 for a single knot, 1 for two, and None when no
    such mesh has at most ``limit`` steps (positions incommensurate, or too fine).
    """
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        return 0
    span = float(t[-1] - t[0])
    if not (math.isfinite(span) and span > 0):
        return None
    rounding = 8 * np.finfo(float).eps * max(abs(float(t[0])), abs(float(t[-1]))) / span
    f = (t[1:-1] - t[0]) / span
    held = np.zeros(f.size, dtype=bool)
    m = 1
    while True:
        # every knot at once on the mesh of m steps; the first one off sets a finer mesh
        pos = f * m
        off = np.flatnonzero(~held & (np.abs(pos - np.rint(pos)) > 1e-9 + m * rounding))
        if off.size == 0:
            return m
        q = _least_denominator(float(f[off[0]]), rounding, limit)
        if q is None:
            return None
        if m % q == 0:          # held to 1e-9 of its own step, which m subdivides
            held[off[0]] = True
            continue
        m = m * q // math.gcd(m, q)
        if m > limit:
            return None


def _least_denominator(f: float, rounding: float, limit: int):
    """The least q <= limit with |f q - p| <= 1e-9 + q rounding for an integer p, among
    the continued-fraction convergents p/q of ``f`` (exact on the float); None if none."""
    num, den = float(f).as_integer_ratio()
    p0, q0, p1, q1 = 0, 1, 1, 0
    while den:
        a, rest = divmod(num, den)
        p0, q0, p1, q1 = p1, q1, a * p1 + p0, a * q1 + q0
        if q1 > limit:
            return None
        if abs(f * q1 - p1) <= 1e-9 + q1 * rounding:
            return q1
        num, den = den, rest
    return q1 if q1 <= limit else None


