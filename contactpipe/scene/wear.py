"""The ``[wear]`` table of a scene: fretting wear over many repetitions of the load program
(:class:`Wear`), and the rules it sets on the other tables (:func:`check_wear`): a program
that ends where it starts, friction to wear by, and a memory a cycle jump can advance.

Units: SI; the coefficient k in Pa⁻¹ (m³/(N m) for Archard, m³/J for the energy law).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .tables import Field, Part, Reader, is_integer, is_number, is_sequence, show

__all__ = ["Wear", "WEAR_LAWS", "MAX_WEAR_CYCLES", "MAX_KEPT_LOOPS", "check_wear"]

WEAR_LAWS = ("archard", "energy")
#: Cap on the cycles of a wear run, against absurd sizes (10⁹ cycles of a 1 s program
#: span 30 years of fretting).
MAX_WEAR_CYCLES = 1_000_000_000
#: Cap on the recorded cycles whose loop of tractions is kept (``keep_tractions``).
MAX_KEPT_LOOPS = 1000

_COEFFICIENT = ("a finite number >= 0 [1/Pa] (the half-space wears), or a pair "
                "[k_indenter, k_halfspace] of finite numbers >= 0 [1/Pa] (both wear)")
_JUMP = f"'auto' or an integer from 1 to {MAX_WEAR_CYCLES}"


def _check_coefficient(r: Reader):
    """k: a number, or a pair (k_indenter, k_halfspace), each finite and >= 0."""
    key, v = r.key("coefficient"), r.raw.get("coefficient")
    if v is None:
        r.missing("coefficient", "", _COEFFICIENT)
        return None
    items = list(v) if is_sequence(v) and not isinstance(v, np.ndarray) else \
        (v.tolist() if isinstance(v, np.ndarray) else [v])
    ok = len(items) in (1, 2) and (len(items) == 2 or not is_sequence(v)) and all(
        is_number(x) and math.isfinite(float(x)) and float(x) >= 0 for x in items)
    if not ok:
        r.add(f"{key} must be {_COEFFICIENT}, got {show(v, typed=True)}")
        return None
    vals = tuple(float(x) + 0.0 for x in items)
    if not any(vals):
        r.add(f"{key} = {show(v)}: no body wears; give a coefficient > 0 [1/Pa], or "
              f"remove [wear]")
        return None
    return vals[0] if len(vals) == 1 else vals


def _check_jump(r: Reader):
    """jump: "auto" or an integer >= 1."""
    v = r.raw.get("jump", "auto")
    if v == "auto":
        return "auto"
    if is_integer(v) and 1 <= int(v) <= MAX_WEAR_CYCLES:
        return int(v)
    r.add(f"{r.key('jump')} must be {_JUMP}, got {show(v, typed=not is_integer(v))}")
    return None


@dataclass(frozen=True)
class Wear(Part):
    """Fretting wear over many cycles (``[wear]``; docs/wear.md).

    Parameters
    ----------
    law : {"archard", "energy"}
        Archard: Δh = k p |Δs|; energy (Fouvry): Δh = k |q·Δs|; per cell and step.
    coefficient : float or (float, float)
        k [1/Pa], >= 0: a number wears the half-space only; a pair
        (k_indenter, k_halfspace) wears both bodies, both losses opening the gap.
    cycles : int
        How many times the load program (one cycle) repeats, from 1 to 10⁹.
    jump : "auto" or int
        Cycles each simulated cycle stands for: its wear is extrapolated over ``jump``
        cycles (1 simulates every cycle); "auto" chooses the jump by an error estimate.
    keep_tractions : int
        How many recorded cycles keep their whole loop of tractions (p, q1, q2 at every
        instant of the cycle) in the archive, log-spaced from the first to the last; 0
        keeps none.
    tolerance : float
        Relative error per jump that ``jump = "auto"`` allows on the extrapolated wear.
    """

    law: str = "archard"
    coefficient: float | tuple = 0.0
    cycles: int = 1
    jump: str | int = "auto"
    keep_tractions: int = 0
    tolerance: float = 0.003

    PATH = "wear"
    FIELDS = (
        Field("law", "choice", options=WEAR_LAWS, default="archard"),
        Field("coefficient", ("number", "numbers"), _COEFFICIENT, required=True,
              unit="1/Pa"),
        Field("cycles", "integer", f"an integer from 1 to {MAX_WEAR_CYCLES}",
              ok=lambda n: n >= 1, required=True, cap=MAX_WEAR_CYCLES,
              cap_why="beyond any fretting life"),
        Field("jump", ("integer", "string"), _JUMP, default="auto"),
        Field("keep_tractions", "integer", f"an integer from 0 to {MAX_KEPT_LOOPS}",
              ok=lambda n: n >= 0, default=0, cap=MAX_KEPT_LOOPS,
              cap_why="each kept loop holds every instant of a cycle"),
        Field("tolerance", "number", "a finite number > 0 and < 1 [1]",
              ok=lambda x: 0 < x < 1, default=0.003, unit="1"),
    )

    @classmethod
    def read(cls, raw, path, problems):
        r = Reader(raw, path, problems)
        r.check_keys(cls.FIELDS)
        v = {f.name: r.value(f) for f in cls.FIELDS
             if f.name not in ("coefficient", "jump")}
        v["coefficient"] = _check_coefficient(r)
        v["jump"] = _check_jump(r)
        return cls.make(**v) if r.ok else None

    @property
    def both(self) -> bool:
        """Both bodies wear (a pair of coefficients)."""
        return isinstance(self.coefficient, tuple)

    @property
    def coefficients(self) -> tuple[float, float]:
        """(k_indenter, k_halfspace) [1/Pa]."""
        k = self.coefficient
        if isinstance(k, tuple):
            return float(k[0]), float(k[1])
        return 0.0, float(k)


def _open_rows(load) -> list[str]:
    """The controlled load keys whose value at the last knot differs from the first."""
    prog = load.programs()
    out = []
    for row, key in enumerate(prog.keys):
        for values in (prog.force[row], prog.motion[row]):
            if np.isnan(values).all() or not key:
                continue
            if values[-1] != values[0]:
                out.append(f"load.{key} ({values[0]:g} at the first knot, {values[-1]:g} at "
                           f"the last)")
    return list(dict.fromkeys(out))


def check_wear(p: dict, problems: list) -> None:
    """The rules ``[wear]`` sets on the scene's other tables (parts ``p``)."""
    wear, load, fric = p.get("wear"), p.get("load"), p.get("friction")
    if wear is None:
        return
    if load is not None:
        rows = _open_rows(load)
        if rows:
            problems.append(
                f"wear.cycles repeats the load program, which must end where it starts "
                f"(every controlled value at the last knot equal to the first): "
                f"{'; '.join(rows)} does not; close the program")
    if fric is not None and fric.largest == 0:
        problems.append(
            f"[wear] needs friction: friction.mu = {show(fric.mu)} (absent: 0) makes no "
            f"slip work and no wear; give friction.mu > 0 or remove [wear]")
    if wear.jump != 1:
        for side in ("indenter", "halfspace"):
            spec = p.get(side)
            if spec is not None and getattr(spec, "creep", None) == "tabulated":
                problems.append(
                    f"wear.jump = {show(wear.jump)} with {side}.creep = 'tabulated': a cycle "
                    f"jump advances the creep memory of a sum of exponentials only; give "
                    f"wear.jump = 1, or a creep model (or creep = 'fit')")
