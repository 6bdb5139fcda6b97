"""A declared key read from a TOML table: its default, its bounds and the line each bad
value gives, the reasons a bound states, a list's elements, names written into files."""

from __future__ import annotations

import dataclasses

import pytest

from antsim.schema.keys import (
    FROM_SETTINGS,
    REQUIRED,
    Key,
    Section,
    duplicate,
    range_text,
    read_key,
    unit_of,
)
from antsim.tomlcheck import Table
from controller.errors import InputError


def table(**data) -> Table:
    return Table(data, "f.toml", "t")


def line(key: Key, name: str, **data) -> str:
    with pytest.raises(InputError) as err:
        read_key(table(**data), name, key)
    return err.value.line()


@pytest.mark.parametrize("key, text", [
    (Key(1.0, "x", min=0.0, max=5.0), "0..5"),
    (Key(1.0, "x", gt=0.0), "> 0"),
    (Key(1.0, "x", gt=0.0, max=1.5), "> 0, <= 1.5"),
    (Key(1.0, "x", min=0.0, lt=24.0), ">= 0, < 24"),
    (Key("a", "x", kind="string", choices=("a", "b")), "one of: a, b"),
    (Key(1.0, "x"), ""),
])
def test_range_text(key, text):
    assert range_text(key) == text


def test_units_come_from_the_name():
    assert [unit_of(n) for n in ("settle_s", "speed_deg_s", "accel_deg_s2", "el_arcsec_per_k",
                                 "duration_h", "flux_jy", "scale")] == \
        ["s", "deg/s", "deg/s^2", "arcsec/K", "h", "Jy", ""]


def test_a_number_in_range_its_default_and_the_lines_beyond():
    key = Key(2.0, "x", min=0.0, max=5.0)
    assert read_key(table(v=3), "v", key) == 3.0
    assert read_key(table(), "v", key) == 2.0
    assert line(key, "v", v=6.0) == "f.toml: t.v = 6.0: must be <= 5"
    assert line(key, "v", v=float("nan")) == "f.toml: t.v = nan: must be finite"
    assert line(key, "v", v="3") == "f.toml: t.v = '3': must be a number"
    assert line(Key(REQUIRED, "x"), "v") == "f.toml: t.v = '<missing>': required key is missing"


def test_a_bound_with_a_reason_states_it_with_the_unit():
    key = Key(1.0, "x", gt=0.0, max=10.0, why="the ephemeris ends there", why_min="never")
    assert line(key, "span_h", span_h=11.0) == \
        "f.toml: t.span_h = 11.0: must be <= 10 h: the ephemeris ends there"
    assert line(key, "span_h", span_h=0.0) == "f.toml: t.span_h = 0.0: must be > 0 h: never"
    # a bound without a reason reads as the plain getter's
    assert line(Key(1.0, "x", gt=0.0, why="big"), "span_h", span_h=0.0) == \
        "f.toml: t.span_h = 0.0: must be > 0"


def test_a_list_s_elements_are_bounded():
    key = Key([], "x", kind="numbers", min=-360.0, max=360.0, element="angles")
    assert read_key(table(a_deg=[1, 2]), "a_deg", key) == [1.0, 2.0]
    assert line(key, "a_deg", a_deg=[0.0, 400.0]) == \
        "f.toml: t.a_deg = [0.0, 400.0]: angles must lie in -360..360 deg"


@pytest.mark.parametrize("value, problem", [
    ("", "must not be empty"),
    ("  ", "must not be empty"),
    ("3C\n84", "holds the control character U+000A"),
    ("3C\u202884", "holds the control character U+2028"),
    ("3C\x0084", "holds the control character U+0000"),
    (" 3C84", "begins or ends with blanks"),
])
def test_a_name_is_one_printable_line(value, problem):
    assert problem in line(Key(REQUIRED, "x", kind="name"), "label", label=value)


def test_a_line_may_be_empty_but_not_two_lines():
    key = Key("", "x", kind="line")
    assert read_key(table(note=""), "note", key) == ""
    assert read_key(table(note="Cas A, 5' shell"), "note", key) == "Cas A, 5' shell"
    assert "U+000D" in line(key, "note", note="a\rb")


def test_duplicate_folds_case_when_asked():
    assert duplicate(["XR", "XL", "xr"]) == (2, "xr")
    assert duplicate(["XR", "XL", "xr"], fold=False) is None
    assert duplicate(["XR", "XL"]) is None


@dataclasses.dataclass(frozen=True)
class _Settings:
    speed_deg_s: float = 1.5
    count: int = 3
    limits: tuple[float, ...] = (1.0, 2.0)


def test_a_section_takes_its_defaults_from_its_settings():
    sec = Section("s", "doc", {"speed_deg_s": Key(doc="x"),
                               "n": Key(doc="y", kind="integer", field="count"),
                               "limits": Key(doc="z", kind="numbers")}, settings=_Settings)
    assert [k.default for k in sec.keys.values()] == [1.5, 3, [1.0, 2.0]]
    assert sec.read_all(table(speed_deg_s=2)) == {"speed_deg_s": 2.0, "count": 3,
                                                  "limits": (1.0, 2.0)}
    with pytest.raises(ValueError, match="no field 'nope'"):
        Section("s", "doc", {"nope": Key(doc="x")}, settings=_Settings)
    with pytest.raises(ValueError, match="needs a settings field"):
        Section("s", "doc", {"free": Key(FROM_SETTINGS, "x")})
