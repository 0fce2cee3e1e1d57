"""Declaring the environment's flat keyword arguments once, as dataclass field metadata.

Each keyword of ``gym.make("HyperloopSuspension-v0", **kwargs)`` is one field of
:class:`~hyperloop_env.config.EnvConfig` (or of a group it nests: ``SensorConfig``,
``RewardWeights``) declared with :func:`kw`::

    speed_kmh: float | None = field(
        default=None, metadata=kw("speed", unit="km/h", bounds=(MIN_SPEED_KMH, inf), ...)
    )

From these declarations come the keyword list, the validation of a value (its type,
bounds or choices: a ``ValueError`` naming the keyword), the flat keyword arguments of a
configuration (``EnvConfig.to_kwargs``), the override groups and the keyword tables of
the docstrings (:func:`keyword_table`, appended to ``help()`` of the config module and the
environments). Adding a keyword is adding one declared field.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Iterator
from dataclasses import MISSING, Field, dataclass, fields
from typing import Any

import numpy as np

from hyperloop_env.physics.params import is_real

KEYWORD = "keyword"
"""Key of a field's metadata holding its :class:`Keyword`."""

GROUP = "keyword_group"
"""Key of a field's metadata marking a nested dataclass whose fields are keywords."""

TABLE_MARKER = "[keyword table]"
"""Line of a docstring replaced by the generated keyword table (:func:`with_table`)."""

PHYSICAL = "physical"
"""Group of the physical overrides: ``None`` keeps the scenario's value."""

REWARD = "reward"
"""Group of the reward weights: keyword ``<term>_weight``."""


@dataclass(frozen=True)
class Keyword:
    """What one environment keyword is: its description, unit and accepted values.

    ``bounds`` (lo, hi) makes it a real number (stored as ``float``); ``math.inf`` is a
    bound that is not checked, ``lo_open`` makes the lower bound strict, ``infinite``
    accepts ``math.inf`` as a value and says what it means ("math.inf for straight"), and
    ``why`` names the constant of a bound and its reason. ``choices`` makes it one of
    these values (integers or strings); ``parse`` converts and checks a value (raising
    its own ``ValueError``). ``optional``: ``None`` is accepted and keeps what the
    scenario or the model sets. ``shown_default``: the default the tables show, if not
    the field's (e.g. "scenario"). ``name``: the flat keyword, if not the field's name
    (or, in the reward group, ``<field>_weight``). ``aliases``: deprecated names still
    accepted (with a ``DeprecationWarning``). ``dump``: a JSON-friendly value for
    ``to_kwargs``; ``omit``: when ``to_kwargs`` leaves the keyword out."""

    doc: str
    unit: str = ""
    bounds: tuple[float, float] | None = None
    lo_open: bool = False
    infinite: str = ""
    why: str = ""
    choices: tuple[Any, ...] | None = None
    parse: Callable[[Any], Any] | None = None
    optional: bool = False
    shown_default: str = ""
    group: str = ""
    name: str = ""
    aliases: tuple[str, ...] = ()
    dump: Callable[[Any], Any] | None = None
    omit: Callable[[Any], bool] | None = None

    def check(self, name: str, value: Any) -> Any:
        """``value`` validated and normalised (numbers as ``float``, choices as given);
        ``ValueError`` naming ``name`` (the keyword as the user wrote it) otherwise."""
        if value is None and self.optional:
            return None
        if self.bounds is not None:
            return self._number(name, value)
        if self.choices is not None:
            return self._choice(name, value)
        if self.parse is not None:
            return self.parse(value)
        return value

    def __post_init__(self) -> None:
        assert not self.infinite or (self.bounds is not None and self.bounds[0] > 0), (
            "math.inf is accepted only for positive quantities"
        )

    def _number(self, name: str, value: Any) -> float:
        assert self.bounds is not None
        lo, hi = self.bounds
        if not is_real(value) or math.isnan(value):
            raise ValueError(f"{name} must be a number, got {value!r}")
        if math.isinf(value) and not self.infinite:
            raise ValueError(f"{name} must be finite, got {value!r}")
        if math.isinf(value) and value < 0:
            raise ValueError(f"{name} must be > 0 ({self.infinite}), got {value!r}")
        v = float(value)
        unit = f" {self.unit}" if self.unit else ""
        why = f" ({self.why})" if self.why else ""
        if v <= lo if self.lo_open else v < lo:
            op = ">" if self.lo_open else ">="
            raise ValueError(f"{name} must be {op} {number(lo)}{unit}{why}, got {value!r}")
        if v > hi:
            raise ValueError(f"{name} must be <= {number(hi)}{unit}{why}, got {value!r}")
        return v

    def _choice(self, name: str, value: Any) -> Any:
        assert self.choices is not None
        if all(isinstance(c, int) for c in self.choices):  # an integer, not a bool or float
            ok = not isinstance(value, bool) and isinstance(value, int | np.integer)
            value = int(value) if ok else value
        else:
            ok = isinstance(value, str)
        if not ok or value not in self.choices:
            options = " or ".join(repr(c) for c in self.choices)
            unit = f" ({self.unit})" if self.unit else ""
            why = f" ({self.why})" if self.why else ""
            raise ValueError(f"{name} must be {options}{unit}{why}, got {value!r}")
        return value

    def range_text(self) -> str:
        """The accepted values, for the tables (empty if another check owns them)."""
        if self.choices is not None:
            return ", ".join(repr(c) if isinstance(c, str) else str(c) for c in self.choices)
        if self.bounds is None:
            return ""
        lo, hi = self.bounds
        parts = []
        if lo > -math.inf:
            parts.append(f"{'>' if self.lo_open else '>='} {number(lo)}")
        if hi < math.inf:
            parts.append(f"<= {number(hi)}")
        if self.infinite:
            parts.append("math.inf")
        return ", ".join(parts)


def number(x: float) -> str:
    """A bound as the messages write it: ``repr`` (1.0, 1e-06), large ones as ``:g``
    (1000)."""
    return repr(x) if abs(x) < 1000 else f"{x:g}"


def kw(doc: str, **options: Any) -> dict[str, Keyword]:
    """Field metadata declaring an environment keyword (options: :class:`Keyword`)."""
    return {KEYWORD: Keyword(doc, **options)}


def kw_group(doc: str) -> dict[str, str]:
    """Field metadata of a nested dataclass whose fields are keywords."""
    return {GROUP: doc}


@dataclass(frozen=True)
class Declared:
    """One declared keyword: its flat name, the field path and the declaration."""

    name: str
    path: tuple[str, ...]
    keyword: Keyword
    field: Field[Any]

    @property
    def field_path(self) -> str:
        return ".".join(self.path)

    def default(self) -> Any:
        f = self.field
        return f.default_factory() if f.default is MISSING else f.default  # type: ignore[misc]


def flat_name(f: Field[Any], keyword: Keyword) -> str:
    """The flat keyword of field ``f``: ``keyword.name``, else ``<field>_weight`` in the
    reward group, else the field's name."""
    if keyword.name:
        return keyword.name
    return f"{f.name}_weight" if keyword.group == REWARD else f.name


def declared(cls: type, path: tuple[str, ...] = ()) -> Iterator[Declared]:
    """The keywords declared by ``cls``'s fields, in field order (nested groups in
    place)."""
    for f in fields(cls):
        if KEYWORD in f.metadata:
            k: Keyword = f.metadata[KEYWORD]
            yield Declared(flat_name(f, k), (*path, f.name), k, f)
        elif GROUP in f.metadata:
            nested = f.default_factory  # type: ignore[misc]
            assert isinstance(nested, type), f"keyword group {f.name} needs a default_factory"
            yield from declared(nested, (*path, f.name))


def validate_fields(obj: Any) -> None:
    """Validate and normalise (frozen dataclass: ``object.__setattr__``) every keyword
    field of ``obj``; a nested group must be an instance of its class."""
    for f in fields(obj):
        value = getattr(obj, f.name)
        if KEYWORD in f.metadata:
            k: Keyword = f.metadata[KEYWORD]
            object.__setattr__(obj, f.name, k.check(flat_name(f, k), value))
        elif GROUP in f.metadata:
            cls = f.default_factory  # type: ignore[misc]
            if not isinstance(value, cls):  # type: ignore[arg-type]
                raise ValueError(f"{f.name} must be a {cls.__name__}, got {value!r}")  # type: ignore[union-attr]


def _default_text(d: Declared) -> str:
    if d.keyword.shown_default:
        return d.keyword.shown_default
    v = d.default()
    return f'"{v}"' if isinstance(v, str) else f"{v!r}"


def _widths(head: tuple[str, ...], rows: list[tuple[str, ...]]) -> list[int]:
    return [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]


def _table(head: tuple[str, ...], rows: list[tuple[str, ...]]) -> list[str]:
    w = _widths(head, rows)

    def fmt(r: tuple[str, ...]) -> str:
        return "| " + " | ".join(c.ljust(n) for c, n in zip(r, w, strict=True)) + " |"

    return [fmt(head), "|" + "|".join("-" * (n + 2) for n in w) + "|", *map(fmt, rows)]


def keyword_table(cls: type, extra: tuple[tuple[str, str, str], ...] = ()) -> str:
    """The Markdown table (``help()`` and Gymnasium-style docs) of ``cls``'s keywords:
    name, default, unit, accepted values and description; ``extra`` rows (name, default,
    description) follow. Deprecated aliases are listed below it."""
    rows = [
        (
            f"`{d.name}`",
            f"`{_default_text(d)}`",
            d.keyword.unit,
            d.keyword.range_text(),
            d.keyword.doc,
        )
        for d in declared(cls)
    ]
    rows += [(f"`{n}`", f"`{dft}`", "", "", doc) for n, dft, doc in extra]
    out = _table(("Parameter", "Default", "Unit", "Accepted", "Description"), rows)
    aliases = [(a, d.name) for d in declared(cls) for a in d.keyword.aliases]
    if aliases:
        names = ", ".join(f"``{a}`` (now ``{n}``)" for a, n in aliases)
        text = f"Deprecated keyword names, still accepted with a ``DeprecationWarning``: {names}."
        out += ["", *textwrap.wrap(text, 88, break_on_hyphens=False)]
    return "\n".join(out)


def field_table(cls: type) -> str:
    """The reStructuredText table (module docstring) of ``cls``'s keywords: flat name,
    the field it sets, unit and accepted values."""
    rows = [
        (d.name, f"``{d.field_path}``", d.keyword.unit or "-", d.keyword.range_text() or "-")
        for d in declared(cls)
    ]
    head = ("keyword", "field", "unit", "accepted")
    w = _widths(head, rows)
    rule = "  ".join("=" * n for n in w)

    def fmt(r: tuple[str, ...]) -> str:
        return "  ".join(c.ljust(n) for c, n in zip(r, w, strict=True)).rstrip()

    return "\n".join([rule, fmt(head), rule, *(fmt(r) for r in rows), rule])


def with_table(doc: str | None, table: str) -> str | None:
    """``doc`` with its :data:`TABLE_MARKER` line replaced by ``table`` (indented like
    the marker); None stays None (``python -OO``)."""
    if doc is None:
        return None
    lines = doc.split("\n")
    for i, line in enumerate(lines):
        if line.strip() == TABLE_MARKER:
            indent = line[: len(line) - len(line.lstrip())]
            body = [indent + t if t else t for t in table.split("\n")]
            return "\n".join(lines[:i] + body + lines[i + 1 :])
    raise ValueError(f"no {TABLE_MARKER!r} line in the docstring")
