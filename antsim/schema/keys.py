"""A declared setting (:class:`Key`) and a table of them (:class:`Section`): what a scenario
or plan key is, and how its value is read.

Every key states its kind (number, integer, text, true/false, list, table...), its unit (by
default the one its name ends in, the project's convention: ``settle_s`` is in seconds), its
range, its default, one line of meaning and, where one gives it, the source document. The
readers (:mod:`antsim.scenario`, :mod:`antsim.plan.planfile`, the effects'
:meth:`~antsim.world.effects.base.Effect.from_table`) read every value through its key
(:meth:`Section.read`), so the ranges the errors state and the reference page
(``docs/scenarios.md``, :mod:`antsim.schema.markdown`) prints are the same numbers. Checks
between keys (a step within the beam, an integration of two samples at least) stay in the
readers; a key's ``note`` says them in words for the reference.

A section bound to a settings dataclass (``settings``) takes a key's default from that
dataclass's field (``default=FROM_SETTINGS``, the default of a key): the dataclass is the
one place a default is written. ``tests/antsim/schema/test_scenario.py`` fails when a field
of the world's or the controller's settings has no key.

This module imports nothing of antsim but :mod:`antsim.tomlcheck`: the world's effects
declare their parameters with it.
"""

from __future__ import annotations

import dataclasses
import math
import unicodedata
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any

from ..tomlcheck import Table
from .utc import utc_time

__all__ = ["FROM_SETTINGS", "KINDS", "REQUIRED", "Key", "Section", "check_bounds",
           "check_elements", "check_line", "check_name", "duplicate", "range_text",
           "read_key", "unit_of"]


class _Marker:
    """A default that is not a value (shown as its text)."""

    def __init__(self, text: str):
        self.text = text

    def __repr__(self) -> str:
        return self.text


#: the key must be given
REQUIRED = _Marker("required")
#: the key's default is its settings dataclass field's default (see :class:`Section`)
FROM_SETTINGS = _Marker("the settings' default")

#: kind -> how the reference page names it
KINDS = {
    "number": "number",
    "integer": "integer",
    "string": "text",
    "line": "line of text",  # written into output files: no control characters
    "name": "name",          # a line of text, not empty, without surrounding blanks
    "boolean": "true/false",
    "numbers": "list of numbers",
    "strings": "list of texts",
    "time": "ISO UTC time",
    "angle": "angle (text)",
    "terms": "table: term = number",
    "table": "table",
    "tables": "array of tables",
}

#: unit by the end of a key's name (first match; the project's "units in the names")
_UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_arcsec_per_k", "arcsec/K"), ("_s_per_day", "s/day"), ("_k_per_jy", "K/Jy"),
    ("_deg_s2", "deg/s^2"), ("_deg_s", "deg/s"), ("_m_s", "m/s"), ("_per_h", "1/h"),
    ("_per_k", "arcsec/K"), ("_arcsec", "arcsec"), ("_arcmin", "arcmin"), ("_deg", "deg"),
    ("_ghz", "GHz"), ("_mhz", "MHz"), ("_hpa", "hPa"), ("_jy", "Jy"), ("_um", "um"),
    ("_days", "d"), ("_h", "h"), ("_s", "s"), ("_k", "K"), ("_c", "C"), ("_m", "m"),
)


def unit_of(name: str) -> str:
    """The unit the end of ``name`` states ("" where it states none)."""
    return next((unit for suffix, unit in _UNIT_SUFFIXES if name.endswith(suffix)), "")


@dataclass(frozen=True)
class Key:
    """One setting: its default, its meaning, its range and its kind.

    ``default``: a value, ``None`` (optional: no value), :data:`REQUIRED` or
    :data:`FROM_SETTINGS`. ``min``/``max`` and ``gt``/``lt`` bound a number (inclusive and
    exclusive; for ``numbers`` every element); ``choices`` the values of a text.
    ``unit``: where the name states none, or states it otherwise ("1" for a pure number).
    ``source``: the document a value or a meaning comes from ("Ghigo 1990, section V").
    ``element``: what a list's elements are, for its errors ("angles must lie in ...").
    ``note``: a rule between this key and others, which the reader checks. ``why`` and
    ``why_min``: the reasons for the upper and the lower bound, which an error beyond
    them states. ``field``: the
    settings field the key fills ("" the key's own name, None none) and ``scale`` the
    factor from the key's unit to the field's (``duration_h`` fills ``duration_s``: 3600).
    """

    default: Any = FROM_SETTINGS
    doc: str = ""
    min: float | None = None
    max: float | None = None
    kind: str = "number"
    choices: tuple[str, ...] | None = None
    gt: float | None = None
    lt: float | None = None
    unit: str = ""
    source: str = ""
    note: str = ""
    field: str | None = ""
    scale: float = 1.0
    min_length: int = 0
    why: str = ""
    why_min: str = ""
    element: str = "values"

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"Key kind {self.kind!r}: not one of {', '.join(KINDS)}")

    @property
    def required(self) -> bool:
        return self.default is REQUIRED


def range_text(key: Key, unit: str = "") -> str:
    """A key's range as the reference page and the errors state it ("" where it has
    none): ``5..90 deg``, ``> 0``, ``> 0, <= 1.5``, ``one of: a, b``."""
    if key.choices:
        return "one of: " + ", ".join(key.choices)
    if key.min is not None and key.max is not None:
        parts = [f"{key.min:g}..{key.max:g}"]
    else:
        lower = [f"{op} {v:g}" for op, v in ((">=", key.min), (">", key.gt)) if v is not None]
        upper = [f"{op} {v:g}" for op, v in (("<=", key.max), ("<", key.lt)) if v is not None]
        parts = lower + upper
    if key.min is not None and key.max is not None:
        parts += [f"{op} {v:g}" for op, v in ((">", key.gt), ("<", key.lt)) if v is not None]
    text = ", ".join(parts)
    return f"{text} {unit}".strip() if text and unit and unit != "1" else text


#: characters a name written into an output file may not hold: control characters and
#: line or paragraph separators (a newline in a source's name splits a recordings row)
_CONTROL_CATEGORIES = ("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp")


def check_line(table: Table, name: str, value: str) -> str:
    """``value`` as one line of text written into output files (a description, a note): no
    control characters (a newline would split a recordings row or a report's line)."""
    if value.isprintable():  # the usual case, in C: no "Other" or "Separator" but spaces
        return value
    bad = next((c for c in value if unicodedata.category(c) in _CONTROL_CATEGORIES), None)
    if bad is not None:
        raise table.error(name, value, f"holds the control character U+{ord(bad):04X}",
                          "it is written into output files: use printable characters on one "
                          "line")
    return value


def check_name(table: Table, name: str, value: str) -> str:
    """``value`` as a name (of a source, a channel, a variant...): not empty, one line of
    printable characters, no leading or trailing blanks."""
    if not value.strip():
        raise table.error(name, value, "must not be empty")
    check_line(table, name, value)
    if value != value.strip():
        raise table.error(name, value, "begins or ends with blanks",
                          "other files and options name it exactly")
    return value


def read_key(table: Table, name: str, key: Key, default: Any = FROM_SETTINGS) -> Any:
    """The value of ``name`` in ``table`` as ``key`` declares it (its default, or
    ``default`` given here), or one InputError line. Tables and arrays of tables are the
    readers' to read."""
    if default is FROM_SETTINGS:
        default = key.default
        if default is FROM_SETTINGS:
            raise ValueError(f"key {table.key(name)}: no default (bind its section to "
                             "settings)")
    kind = key.kind
    if kind == "number" and not (key.why or key.why_min):  # most keys: the getter's bounds
        if default is REQUIRED:
            return table.number(name, min=key.min, max=key.max, gt=key.gt, lt=key.lt)
        return table.number(name, default, min=key.min, max=key.max, gt=key.gt, lt=key.lt,
                            allow_none=default is None)
    missing = () if default is REQUIRED else (default,)
    if kind == "number":
        value = table.number(name, *missing, allow_none=default is None)
        if value is not None:
            check_bounds(table, name, key, value)
        return value
    if kind == "integer":
        if default is None and name not in table:
            table.raw(name, None)
            return None
        return table.integer(name, *missing,
                             min=None if key.min is None else int(key.min),
                             max=None if key.max is None else int(key.max))
    if kind in ("string", "time", "angle", "name", "line"):
        value = table.string(name, *missing, choices=key.choices)
        if value is None:
            return value
        if kind == "name":
            check_name(table, name, value)
        elif kind == "line":
            check_line(table, name, value)
        elif kind == "time":
            utc_time(table, name, value)
        return value
    if kind == "boolean":
        if default is None and name not in table:
            table.raw(name, None)
            return None
        return table.boolean(name, *missing)
    if kind == "numbers":
        values = table.numbers(name, *(None if m is None else list(m) for m in missing),
                               min_length=key.min_length)
        check_elements(table, name, key, values)
        return values
    if kind == "strings":
        if default is None and name not in table:
            table.raw(name, None)
            return None
        return table.strings(name, *(None if m is None else list(m) for m in missing))
    raise ValueError(f"key {table.key(name)}: a {kind} is read by its reader")


def check_bounds(table: Table, name: str, key: Key, value: float) -> None:
    """``value`` within ``key``'s bounds, or one line stating the bound, its unit and the
    key's reason for it (``why``, ``why_min``)."""
    unit = key.unit or unit_of(name)
    unit = "" if unit == "1" else f" {unit}"
    for op, bound, outside, why in ((">=", key.min, lambda b: value < b, key.why_min),
                                    ("<=", key.max, lambda b: value > b, key.why),
                                    (">", key.gt, lambda b: value <= b, key.why_min),
                                    ("<", key.lt, lambda b: value >= b, key.why)):
        if bound is not None and outside(bound):  # without a reason, as Table.number says it
            problem = f"must be {op} {bound:g}{unit}: {why}" if why else f"must be {op} {bound:g}"
            raise table.error(name, value, problem)


def _field_default(settings: type, defaults: Any, name: str) -> Any:
    if defaults is not None:
        return getattr(defaults, name)
    for f in dataclasses.fields(settings):
        if f.name == name:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
            return REQUIRED
    raise ValueError(f"{settings.__name__} has no field {name!r}")


@dataclass(frozen=True)
class Section:
    """A table of a scenario or plan and its keys, in the order the reference lists them.

    ``path``: where the table sits (``mount.az``; ``sources[]`` for an array of tables).
    ``settings``: the dataclass the table fills (None: none; its name where it sits above
    this package, as the scenario's own does), ``defaults`` an instance of it
    holding the defaults where its class has none (the azimuth axis: ``MountConfig().az``).
    ``derived``: the settings fields no key of this table fills, each with where its value
    comes from.
    """

    path: str
    doc: str
    keys: dict[str, Key]
    settings: type | str | None = None
    defaults: Any = None
    derived: dict[str, str] = field(default_factory=dict)
    source: str = ""

    def __post_init__(self) -> None:
        resolved = {}
        for name, key in self.keys.items():
            if key.default is FROM_SETTINGS:
                if not isinstance(self.settings, type) or key.field is None:
                    raise ValueError(f"{self.path}.{name}: FROM_SETTINGS needs a settings "
                                     "field")
                value = _field_default(self.settings, self.defaults, key.field or name)
                if isinstance(value, tuple) and key.kind in ("numbers", "strings"):
                    value = list(value)
                key = replace(key, default=value)
            resolved[name] = key
        object.__setattr__(self, "keys", resolved)

    def __getitem__(self, name: str) -> Key:
        return self.keys[name]

    def field_of(self, name: str) -> str | None:
        """The settings field key ``name`` fills (None: none)."""
        key = self.keys[name]
        return None if key.field is None else key.field or name

    def read(self, table: Table, name: str, default: Any = FROM_SETTINGS) -> Any:
        """The value of key ``name`` (declared here) in ``table``; ``default`` replaces the
        key's where the reader knows better (a default computed from other keys)."""
        return read_key(table, name, self.keys[name], default)

    def read_all(self, table: Table, names: Iterable[str] | None = None) -> dict[str, Any]:
        """``{settings field: value}`` of the plain keys (``names``: these only), each in
        the field's unit: every key is read, then the caller checks the keys together and
        calls ``table.finish()``."""
        out = {}
        for name in (self.keys if names is None else names):
            key = self.keys[name]
            if key.kind in ("table", "tables", "terms"):
                continue
            value = self.read(table, name)
            if key.scale != 1.0 and value is not None:
                value = value * key.scale
            if isinstance(value, list):
                value = tuple(value)
            target = self.field_of(name)
            if target is not None:
                out[target] = value
        return out


def check_elements(table: Table, name: str, key: Key, values: list[float]) -> None:
    """Every element of a list of numbers within ``key``'s bounds, or one line naming
    the list ("angles must lie in -360..360 deg")."""
    for v in values:
        if ((key.min is not None and v < key.min) or (key.max is not None and v > key.max)
                or (key.gt is not None and v <= key.gt)
                or (key.lt is not None and v >= key.lt) or not math.isfinite(v)):
            raise table.error(name, list(values), f"{key.element} must lie in "
                              f"{range_text(key, key.unit or unit_of(name))}")


def duplicate(names: Iterable[str], fold: bool = True) -> tuple[int, str] | None:
    """The first name of ``names`` (index, name) that repeats an earlier one, upper and
    lower case alike when ``fold`` (None: none repeats)."""
    seen = set()
    for i, n in enumerate(names):
        k = n.casefold() if fold else n
        if k in seen:
            return i, n
        seen.add(k)
    return None
