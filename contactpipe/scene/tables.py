"""Table-driven reading of TOML tables: the scene's parts, the sweep, pipeline and dask tables.

A table is described by data: a tuple of :class:`Field`, one per key, giving the key's
name, its kind (number, integer, choice, bool, string, path, numbers, integers, pairs,
table), what is allowed in words, a predicate, a cap, a default and whether it is
required. One loop (:meth:`Reader.read`) reads a table against its description and
collects every problem, each naming the dotted field, the value given and what is
allowed::

    FIELDS = (Field("mu", "number", "a finite number >= 0", ok=lambda x: x >= 0,
                    default=0.0),)
    problems = []
    r = Reader({"mu": -1}, "friction", problems)
    r.check_keys(FIELDS)           # unknown keys, with "did you mean"
    values = r.read(FIELDS)        # {"mu": None}; problems gets
    # "friction.mu must be a finite number >= 0, got -1"

Rules that tie keys together (a shape's required keys, a creep model's keys, a load
program's lengths) are written as plain functions by the callers, on top of
:meth:`Reader.value`, :meth:`Reader.forbid` and :meth:`Reader.add`.

``None`` given for a key means "absent" (TOML has no null).
"""
from __future__ import annotations

import dataclasses
import difflib
import math
import os
import reprlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..exceptions import SceneError

__all__ = ["Field", "Reader", "show", "is_number", "is_integer", "is_sequence", "as_list",
           "to_float", "did_you_mean", "nesting_depth", "MISSING", "KINDS", "Part"]

#: The kinds a field may have; a tuple of kinds is chosen by the shape of the value.
KINDS = ("number", "integer", "choice", "bool", "string", "path", "numbers", "integers",
         "strings", "pairs", "table")

MISSING = object()


# ----------------------------------------------------------------------------- values

class _ShortRepr(reprlib.Repr):
    """repr() that stops at a depth and a length, so a value nested thousands of levels
    deep or a huge list prints as one short line (never a RecursionError)."""

    def __init__(self):
        super().__init__()
        self.maxlevel = 6
        self.maxlist = self.maxtuple = self.maxdict = self.maxset = 24
        self.maxfrozenset = self.maxdeque = self.maxarray = 24
        self.maxstring = self.maxother = 120
        self.maxlong = 60


_REPR = _ShortRepr()


def show(v, typed: bool = False) -> str:
    """A value as given, at most 80 characters, for an error message.

    ``typed`` points out a string or a boolean given where a number is needed.
    """
    if isinstance(v, np.ndarray):
        v = v.tolist() if v.size <= 64 else f"<array of shape {v.shape}, {v.dtype}>"
    if typed and isinstance(v, (bool, np.bool_)):
        return f"{v!r} (a boolean)"
    if typed and isinstance(v, str):
        return f"{_REPR.repr(v)} (a string)"
    s = _REPR.repr(v)
    return s if len(s) <= 80 else s[:77] + "..."


def is_number(v) -> bool:
    """A real number (int or float, numpy's included), not a boolean."""
    return (isinstance(v, (int, float, np.integer, np.floating))
            and not isinstance(v, (bool, np.bool_)))


def is_integer(v) -> bool:
    """An integer (numpy's included), not a boolean."""
    return isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))


def to_float(v) -> float:
    """float(v) for a number (-0.0 read as 0.0), inf when too large for a float."""
    try:
        return float(v) + 0.0
    except OverflowError:
        return math.inf


def is_sequence(v) -> bool:
    """A list, a tuple or a numpy array of at least one dimension."""
    return isinstance(v, (list, tuple)) or (isinstance(v, np.ndarray) and v.ndim >= 1)


def as_list(v) -> list:
    return v.tolist() if isinstance(v, np.ndarray) else list(v)


def did_you_mean(key, allowed) -> str:
    """`` (did you mean 'x'?)`` for the allowed name closest to ``key``, or ""."""
    close = difflib.get_close_matches(str(key), [str(a) for a in allowed], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def nesting_depth(v, limit: int = 64) -> int:
    """How deep lists, tuples and dicts nest in ``v`` (a scalar: 0, ``[1]``: 1), counted
    level by level without recursion, up to ``limit`` + 1."""
    depth, level = 0, [v]
    while depth <= limit:
        containers = [x for x in level if isinstance(x, (Mapping, list, tuple))]
        if not containers:
            break
        depth += 1
        level = [y for x in containers for y in (x.values() if isinstance(x, Mapping) else x)]
    return depth


# ----------------------------------------------------------------------------- fields

@dataclass(frozen=True)
class Field:
    """One key of a table.

    Parameters
    ----------
    name : str
        The key.
    kind : str or tuple of str
        One of :data:`KINDS`; a tuple accepts several, chosen by the shape of the value
        (a scalar, a list of scalars, a list of lists).
    what : str
        What is allowed, in words, with the unit: "a finite number > 0 [m]". For a
        choice, default "one of 'a', 'b'"; for a table, what it holds.
    ok : callable, optional
        Predicate on the value read (on each item of a list; on each pair).
    default : object
        The value when the key is absent.
    required : bool
        Absent is an error.
    options : tuple
        A choice's options; for numbers and integers, words also accepted in place of
        the value (``"auto"``).
    length : int, optional
        Lists: the exact number of items.
    min_length : int
        Lists: the least number of items.
    cap : int or float, optional
        The largest value allowed, refused with its own message naming the cap and
        ``cap_why`` (a bound on absurd sizes rather than on meaning).
    cap_why : str
        Why there is a cap.
    check : callable, optional
        ``check(value, key)`` after the kind and range checks: a message (or a list of
        them) for each further problem, or None.
    part : type, optional
        A table's class, with a ``read(raw, path, problems)`` classmethod; an instance
        of it is accepted in place of the table.
    unit : str
        The unit of the value ("m", "Pa", "s", "N", "1"; "" when none).
    """

    name: str
    kind: str | tuple
    what: str = ""
    ok: Callable | None = None
    default: object = None
    required: bool = False
    options: tuple = ()
    length: int | None = None
    min_length: int = 0
    cap: float | None = None
    cap_why: str = ""
    check: Callable | None = None
    part: type[Part] | None = None
    unit: str = ""

    @property
    def wording(self) -> str:
        """What is allowed, in words."""
        if self.what:
            return self.what
        if "choice" in self.kinds:
            return "one of " + ", ".join(repr(o) for o in self.options)
        if "bool" in self.kinds:
            return "true or false"
        return self.name

    @property
    def kinds(self) -> tuple:
        return self.kind if isinstance(self.kind, tuple) else (self.kind,)


def _shape_of(v) -> str:
    """'scalar', 'list' (of scalars) or 'rows' (a list whose first item is a list)."""
    if not is_sequence(v):
        return "scalar"
    items = as_list(v)
    return "rows" if items and is_sequence(items[0]) else "list"


_SHAPES = {"numbers": "list", "integers": "list", "strings": "list", "pairs": "rows"}


def _pick(kinds: tuple, v) -> str:
    """The kind that reads ``v``: the first whose shape matches, else the first."""
    shape = _shape_of(v)
    for k in kinds:
        if _SHAPES.get(k, "scalar") == shape:
            return k
    return kinds[0]


def _ok(f: Field, x) -> bool:
    return f.ok is None or bool(f.ok(x))


def _length_ok(f: Field, items) -> bool:
    return (f.length is None or len(items) == f.length) and len(items) >= f.min_length


def _number(f, v):
    x = to_float(v) if is_number(v) else None
    return x if x is not None and math.isfinite(x) and _ok(f, x) else MISSING


def _integer(f, v):
    if isinstance(v, str) and v in f.options:    # a word accepted in place of the number
        return v
    return int(v) if is_integer(v) and _ok(f, int(v)) else MISSING


def _choice(f, v):
    return v if isinstance(v, str) and v in f.options else MISSING


def _bool(f, v):
    return bool(v) if isinstance(v, (bool, np.bool_)) else MISSING


def _string(f, v):
    return v if isinstance(v, str) and _ok(f, v) else MISSING


def _strings(f, v):
    if not is_sequence(v) or isinstance(v, np.ndarray):
        return MISSING
    items = as_list(v)
    if not all(isinstance(x, str) and _ok(f, x) for x in items):
        return MISSING
    return tuple(items) if _length_ok(f, items) else MISSING


def _path(f, v):
    if isinstance(v, (str, os.PathLike)) and os.fspath(v):
        return os.fspath(v)
    return MISSING


def _numbers(f, v):
    if isinstance(v, str) and v in f.options:
        return v
    if not is_sequence(v):
        return MISSING
    items = as_list(v)
    vals = [to_float(x) if is_number(x) else None for x in items]
    if any(x is None or not math.isfinite(x) or not _ok(f, x) for x in vals):
        return MISSING
    return tuple(vals) if _length_ok(f, vals) else MISSING


def _integers(f, v):
    if not is_sequence(v):
        return MISSING
    items = as_list(v)
    if not all(is_integer(x) and _ok(f, int(x)) for x in items):
        return MISSING
    return tuple(int(x) for x in items) if _length_ok(f, items) else MISSING


def _pairs(f, v):
    rows = as_list(v) if is_sequence(v) else None
    if not rows:
        return MISSING
    out = []
    for row in rows:
        if not (is_sequence(row) and len(as_list(row)) == 2
                and all(is_number(x) for x in as_list(row))):
            return MISSING
        a, b = (to_float(x) for x in as_list(row))
        if not (math.isfinite(a) and math.isfinite(b) and _ok(f, (a, b))):
            return MISSING
        out.append((a, b))
    return tuple(out) if _length_ok(f, out) else MISSING


_READERS = {"number": _number, "integer": _integer, "choice": _choice, "bool": _bool,
            "string": _string, "strings": _strings, "path": _path, "numbers": _numbers,
            "integers": _integers, "pairs": _pairs}
#: Kinds whose "got" points out a string or a boolean given in place of a number.
_TYPED = {"number", "integer", "numbers", "integers", "pairs"}


# ----------------------------------------------------------------------------- reader

class Reader:
    """Reads one table, appending a message per problem to ``problems``.

    Parameters
    ----------
    raw : mapping
        The table as given; ``None`` values are taken as absent.
    path : str
        Its dotted path ("geometry", "load.fretting"; "" for the top level).
    problems : list of str
        Where the messages go.
    title : str
        What the top level is, for unknown keys there ("the scene", "the sweep file").
    """

    def __init__(self, raw, path: str, problems: list, title: str = ""):
        self.raw = {k: v for k, v in raw.items() if v is not None}
        self.path = path
        self.problems = problems
        self.title = title
        self.ok = True

    def key(self, k) -> str:
        """The dotted name of key ``k``."""
        return f"{self.path}.{k}" if self.path else str(k)

    def add(self, message) -> None:
        """Record a problem (a message or a list of them)."""
        if isinstance(message, str):
            message = [message]
        if message:
            self.problems.extend(message)
            self.ok = False

    def has(self, k) -> bool:
        return k in self.raw

    def check_keys(self, fields) -> None:
        """An "unknown key" problem, with "did you mean", for each key not in ``fields``
        (Field objects or names)."""
        allowed = [f.name if isinstance(f, Field) else f for f in fields]
        for k in self.raw:
            if k in allowed:
                continue
            hint = did_you_mean(k, allowed)
            if self.path:
                self.add(f"unknown key {self.key(k)!r}{hint}; allowed keys in "
                         f"[{self.path}]: {', '.join(allowed)}")
            else:
                where = f" of {self.title}" if self.title else ""
                self.add(f"unknown key {show(k)}{hint} at the top level{where}; allowed "
                         f"keys: {', '.join(allowed)}")

    def missing(self, k, need: str, what: str) -> None:
        self.add(f"{self.key(k)} is required{need}: {what}")

    def forbid(self, k, why: str) -> None:
        """A problem if ``k`` is given: it is not used ``why``."""
        if k in self.raw:
            self.add(f"{self.key(k)} = {show(self.raw[k])} is not used {why}; remove it")

    def value(self, f: Field, need: str | None = None, required: bool | None = None):
        """Read one field: its value, its default when absent, or None on a problem.

        ``required`` overrides the field's; ``need`` is the context of a required key
        (" for shape = 'sphere'").
        """
        v = self.raw.get(f.name, MISSING)
        key = self.key(f.name)
        if v is MISSING:
            if f.required if required is None else required:
                if "table" in f.kinds:
                    self.add(f"{key} is required{need or ''}: a table [{key}] with {f.what}")
                else:
                    self.missing(f.name, need or "", f.wording)
            return f.default
        kind = _pick(f.kinds, v)
        if kind == "table":
            return self._table(f, v, key)
        x = _READERS[kind](f, v)
        if x is MISSING:
            self.add(f"{key} must be {f.wording}, got {show(v, typed=kind in _TYPED)}")
            return None
        if f.cap is not None and is_number(x) and x > f.cap:
            why = f": {f.cap_why}" if f.cap_why else ""
            cap = int(f.cap) if float(f.cap).is_integer() else f.cap
            self.add(f"{key} = {show(v)} is above the cap of {cap}{why}")
            return None
        if f.check is not None:
            before = len(self.problems)
            self.add(f.check(x, key) or [])
            if len(self.problems) > before:
                return None
        return x

    def _table(self, f: Field, v, key):
        if f.part is not None and isinstance(v, f.part):
            v = v.to_fields()
        if not isinstance(v, Mapping):
            self.add(f"{key} must be a table (dict) with {f.what}, got {show(v)}")
            return None
        if f.part is None:
            return dict(v)
        out = f.part.read(dict(v), key, self.problems)
        if out is None:
            self.ok = False
        return out

    def read(self, fields, need: str | None = None, require=None) -> dict:
        """Read every field of ``fields``: {name: value, default or None}.

        ``require``: names that are required here (with the context ``need``), in
        place of each field's own ``required``.
        """
        out = {}
        for f in fields:
            req = None if require is None else f.name in require
            out[f.name] = self.value(f, need=need, required=req)
        return out


# ------------------------------------------------------------- parts backed by a table

def _plain(v):
    """Tuples -> lists, recursively (TOML and JSON want lists)."""
    if isinstance(v, (tuple, list)):
        return [_plain(x) for x in v]
    return v


class Part:
    """Base of the scene's parts: a frozen dataclass read from its table by :meth:`read`
    (validated on construction too) and written back by :meth:`to_dict`.

    A subclass sets ``PATH`` (its dotted name when constructed alone, for messages) and
    ``FIELDS`` (one :class:`~contactpipe.scene.tables.Field` per dataclass field, in file
    order); it overrides :meth:`read` only to add rules that tie keys together.
    """

    PATH = ""
    FIELDS: tuple = ()

    def __post_init__(self):
        problems: list[str] = []
        new = type(self).read(self.to_fields(), self.PATH, problems)
        if problems or new is None:
            raise SceneError(problems or [f"{self.PATH}: invalid"])
        for f in self._fields():
            object.__setattr__(self, f.name, getattr(new, f.name))

    @classmethod
    def _fields(cls) -> tuple[dataclasses.Field, ...]:
        """The dataclass fields of the concrete part."""
        # every concrete part is a @dataclass; Part itself is not, which mypy cannot see
        return dataclasses.fields(cls)  # type: ignore[arg-type]

    @classmethod
    def field(cls, name: str) -> Field:
        """The description of key ``name``."""
        return next(f for f in cls.FIELDS if f.name == name)

    @classmethod
    def read(cls, raw, path: str, problems: list):
        """The part from its table (a dict), or None with a message per problem appended
        to ``problems``. The default reads every field with no rule across keys."""
        r = Reader(raw, path, problems)
        r.check_keys(cls.FIELDS)
        values = r.read(cls.FIELDS)
        return cls.make(**values) if r.ok else None

    @classmethod
    def make(cls, **values):
        """An instance from already validated values (no check)."""
        obj = object.__new__(cls)
        for f in cls._fields():
            object.__setattr__(obj, f.name, values.get(f.name))
        return obj

    def to_fields(self) -> dict:
        """The fields as they are held (tuples, parts, None for absent)."""
        return {f.name: getattr(self, f.name) for f in self._fields()}

    def to_dict(self) -> dict:
        """The part as a plain dict (lists, floats, ints, str, bool) without its None
        values (TOML has no null)."""
        out = {}
        for k, v in self.to_fields().items():
            if v is not None:
                out[k] = v.to_dict() if isinstance(v, Part) else _plain(v)
        return out
