"""The scenario schema against the settings it fills and the reader that reads by it.

* Every field of the world's and the controller's settings that the scenario reader fills is
  a key of the schema, or said to come from elsewhere (:func:`unclaimed_fields` walks the
  dataclasses from :class:`~antsim.scenario.Scenario` down); a field added to a settings
  dataclass without a key fails here.
* A key's default is its settings field's default (converted where the units differ).
* The reader reads exactly the declared keys of every table, in the bundled scenarios and
  plans (a key declared and never read would be refused as unknown; a key read and not
  declared would be missing from the reference page).
"""

from __future__ import annotations

import dataclasses
import re
import types
import typing
from pathlib import Path

import pytest

from antsim import tomlcheck
from antsim.plan.planfile import load_plan
from antsim.scenario import Scenario, load_scenario
from antsim.schema.keys import REQUIRED, Key, Section, unit_of
from antsim.schema.scenario import SCENARIO, section
from antsim.world.effects import EFFECTS

REPO = Path(__file__).resolve().parents[3]
TABLE_KINDS = ("table", "tables", "terms")


def _dataclasses_in(hint) -> list[type]:
    """The dataclasses a field's type names: ``X``, ``X | None``, ``tuple[X, ...]``."""
    if dataclasses.is_dataclass(hint):
        return [hint]
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) in (typing.Union, tuple):
        return [d for arg in typing.get_args(hint) for d in _dataclasses_in(arg)]
    return []


def _sections_of(cls: type, sections: tuple[Section, ...]) -> list[Section]:
    return [s for s in sections if s.settings in (cls, cls.__name__)]


def unclaimed_fields(root: type, sections: tuple[Section, ...]) -> list[str]:
    """``Class.field`` of every settings field reachable from ``root`` through keys that no
    key claims and no section says comes from elsewhere (a settings class no section is
    bound to: ``Class``)."""
    out, todo, seen = [], [root], set()
    while todo:
        cls = todo.pop()
        if cls in seen:
            continue
        seen.add(cls)
        bound = _sections_of(cls, sections)
        if not bound:
            out.append(cls.__name__)
            continue
        claimed = {s.field_of(n) for s in bound for n in s.keys} - {None}
        derived = {f for s in bound for f in s.derived}
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            if f.name in claimed:
                todo.extend(_dataclasses_in(hints[f.name]))
            elif f.name not in derived:
                out.append(f"{cls.__name__}.{f.name}")
    return sorted(out)


def test_every_setting_the_reader_fills_has_a_key():
    assert unclaimed_fields(Scenario, SCENARIO) == []


@dataclasses.dataclass(frozen=True)
class Inner:
    a_s: float = 1.0


@dataclasses.dataclass(frozen=True)
class Outer:
    height_m: float = 0.0
    new_k: float = 2.0
    inner: Inner = Inner()


def test_a_setting_without_a_key_is_found():
    """The check can fail: a settings field added without a key, and a settings class no
    section is bound to, are named."""
    sections = (Section("outer", "a table", {"height_m": Key(doc="h"),
                                             "inner": Key({}, "i", kind="table")},
                        settings=Outer),)
    assert unclaimed_fields(Outer, sections) == ["Inner", "Outer.new_k"]
    sections += (Section("outer.inner", "its table", {"a_s": Key(doc="a")}, settings=Inner),)
    assert unclaimed_fields(Outer, sections) == ["Outer.new_k"]


def test_claimed_and_derived_fields_exist():
    """A key's field and a derived field are fields of the section's settings (a typo in
    the schema would claim nothing)."""
    for s in SCENARIO:
        if not isinstance(s.settings, type):
            continue
        names = {f.name for f in dataclasses.fields(s.settings)}
        for n in s.keys:
            assert s.field_of(n) in names | {None}, f"{s.path}.{n}"
        assert set(s.derived) <= names, s.path


def _field_default(s: Section, field: str):
    if s.defaults is not None:
        return getattr(s.defaults, field)
    f = next(f for f in dataclasses.fields(s.settings) if f.name == field)
    if f.default is not dataclasses.MISSING:
        return f.default
    return f.default_factory() if f.default_factory is not dataclasses.MISSING else REQUIRED


def test_defaults_are_the_settings_defaults():
    checked = 0
    for s in SCENARIO:
        if not isinstance(s.settings, type):
            continue
        for n, key in s.keys.items():
            field = s.field_of(n)
            if field is None or key.kind in TABLE_KINDS or key.required:
                continue
            expected = _field_default(s, field)
            value = key.default
            if key.scale != 1.0:
                value = value * key.scale
            if isinstance(expected, tuple):
                expected = list(expected)
            assert value == expected, f"{s.path}.{n}: {key.default} against {expected}"
            checked += 1
    assert checked > 80


def test_every_number_states_its_unit():
    """Units in the names (or stated, "1" for a pure number): the reference page prints
    them."""
    for s in SCENARIO:
        for n, key in s.keys.items():
            if key.kind in ("number", "numbers"):
                assert key.unit or unit_of(n), f"{s.path}.{n}: no unit"


def test_every_effect_has_its_table():
    paths = {s.path for s in SCENARIO}
    for name, cls in EFFECTS.items():
        sec = section(f'truth.effects[] (effect = "{name}")')
        assert sec.path in paths
        assert set(cls.PARAMS) <= set(sec.keys)
        assert all(k.doc for k in sec.keys.values()), name


@pytest.fixture
def read_keys(monkeypatch):
    """``{(file, table path): keys the reader asked for}`` of what is read while the
    fixture is active (array indices written ``[]``; an effect's table by its name)."""
    seen: dict[tuple[str, str], set[str]] = {}
    finish = tomlcheck.Table.finish

    def recording_finish(self):
        path = re.sub(r"\[\d+\]", "[]", self.prefix)
        if path == "truth.effects[]":
            path = f'truth.effects[] (effect = "{self.data.get("effect")}")'
        seen.setdefault((Path(self.where).name, path), set()).update(self._read)
        return finish(self)

    monkeypatch.setattr(tomlcheck.Table, "finish", recording_finish)
    return seen


def _declared(sections, path: str) -> set[str] | None:
    found = [s for s in sections if s.path == path]
    return set(found[0].keys) if found else None


def test_the_reader_reads_the_declared_keys(read_keys, write_scenario, ghigo_text):
    """Each table of the bundled scenarios is read key by key as the schema declares it:
    no key read that is not declared, none declared that is not read."""
    for path in sorted((REPO / "scenarios").glob("*.toml")):
        load_scenario(path)
    # positions as numbers, a form no bundled scenario uses
    load_scenario(write_scenario(ghigo_text, [('ra = "03h16m29.6s"\ndec = "+41d19m52s"',
                                               "ra_deg = 49.12\ndec_deg = 41.33")]))
    tables = {}
    for (_, path), keys in read_keys.items():
        tables.setdefault(path, set()).update(keys)
    touched = set()
    for path, keys in tables.items():
        declared = _declared(SCENARIO, path)
        if declared is None:  # a table of terms: names, not keys
            assert path in ("truth.terms", "controller.terms", "controller.fit_fixed"), path
            continue
        touched.add(path)
        if path == "sources[]":  # ra or ra_deg, dec or dec_deg: one of each is read
            keys = keys | {"ra", "ra_deg", "dec", "dec_deg"}
        assert keys == declared, f"{path}: read {sorted(keys - declared)}, never read " \
                                 f"{sorted(declared - keys)}"
    untouched = {s.path for s in SCENARIO} - touched
    assert all(p.startswith("truth.effects[]") for p in untouched), untouched


def test_the_plan_reader_reads_the_declared_keys(read_keys):
    from antsim.schema.plan import PLAN

    for path in sorted((REPO / "scenarios" / "plans").glob("*.toml")):
        load_plan(path)
    plans = {p.name for p in (REPO / "scenarios" / "plans").glob("*.toml")}
    tables = {}
    for (file, path), keys in read_keys.items():
        if file in plans:
            tables.setdefault(path, set()).update(keys)
    for path, keys in tables.items():
        declared = _declared(PLAN, path)
        if declared is None:
            assert path == "answers.duration[].targets_arcsec", path
            continue
        assert keys == declared, f"{path}: read {sorted(keys - declared)}, never read " \
                                 f"{sorted(declared - keys)}"
    assert set(tables) >= {s.path for s in PLAN}
