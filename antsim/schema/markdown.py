"""The reference page of scenario and plan files, ``docs/scenarios.md``, written from the
declared schema (:mod:`antsim.schema.scenario`, :mod:`antsim.schema.plan`): every table,
every key with its kind, unit, default, range, meaning and source.

``python -m antsim.schema --markdown > docs/scenarios.md`` writes it; a test fails when the
page in ``docs/`` is not what this module writes now.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from .keys import KINDS, REQUIRED, Key, Section, range_text, unit_of
from .plan import PLAN
from .scenario import SCENARIO

__all__ = ["reference_page", "section_markdown"]

_HEAD = """\
# Scenario and plan files: every key

<!-- Generated from antsim/schema/ by `python -m antsim.schema --markdown > docs/scenarios.md`;
tests/antsim/schema/test_markdown.py fails when this page differs. Do not edit it by hand. -->

Scenarios and plans are TOML files (`scenarios/ghigo1990.toml` is a commented example, and
`scenarios/plans/ghigo1990_whatif.toml` a plan). Every key a file may give is listed here,
table by table, as the readers check it: a value outside its range, of the wrong type, or a
key not listed (a typo) is one line naming the file, the key and the value, and exit status
2. Rules between keys (a step within the beam) are the "rule" of a key's meaning.

Columns: **type** (number: an integer or a decimal; text: a TOML string; name: a text
written into output files, without control characters); **unit** (the one the key's name
ends in, the project's convention); **default** (*required*: must be given; *-*: not given
unless the file gives it); **range** (`a..b` inclusive, `> a` exclusive; a list's range is
its elements'); **source**: the document a value or a meaning comes from, where one does
(`docs/assumptions.md` for the project's assumptions).
"""


def _value(value: Any) -> str:
    """A default as TOML would write it."""
    if value is REQUIRED:
        return "*required*"
    if value is None or value == {}:
        return "-"
    if isinstance(value, bool):
        return f"`{str(value).lower()}`"
    if isinstance(value, float):
        return f"`{value:g}`"
    if isinstance(value, str):
        return f'`"{value}"`'
    if isinstance(value, list | tuple):
        if value and dataclasses.is_dataclass(value[0]):
            return "; ".join(_value(v) for v in value)
        return "`[" + ", ".join(_value(v).strip("`") for v in value) + "]`"
    if dataclasses.is_dataclass(value):
        parts = [f"{f.name} = {_value(getattr(value, f.name)).strip('`')}"
                 for f in dataclasses.fields(value) if getattr(value, f.name) is not None]
        return "`{" + ", ".join(parts) + "}`"
    return f"`{value}`"


def _heading(path: str) -> str:
    if not path:
        return "the top level"
    if "[] (" in path:  # truth.effects[] (effect = "thermal")
        table, _, rest = path.partition("[] (")
        return f"`[[{table}]]` {rest.rstrip(')')}"
    if path.endswith("[]"):
        return f"`[[{path[:-2]}]]`"
    return f"`[{path}]`"


def _cell(text: str) -> str:
    return " ".join(text.replace("|", "\\|").split())


def _row(name: str, key: Key) -> str:
    unit = key.unit or unit_of(name)
    unit = "" if unit == "1" else unit
    meaning = key.doc
    if key.note:
        meaning += f"; rule: {key.note}"
    for reason in (key.why_min, key.why):
        if reason:
            meaning += f"; bound: {reason}"
    cells = (f"`{name}`", KINDS[key.kind], unit, _value(key.default), range_text(key),
             meaning, key.source)
    return "| " + " | ".join(_cell(c) for c in cells) + " |"


def section_markdown(section: Section) -> str:
    """One table's part of the page: its heading, meaning and keys."""
    lines = [f"### {_heading(section.path)}", "", section.doc]
    if section.source:
        lines[-1] += f" Source: {section.source}."
    lines += ["", "| key | type | unit | default | range | meaning | source |",
              "|---|---|---|---|---|---|---|"]
    lines += [_row(name, key) for name, key in section.keys.items()]
    return "\n".join(lines) + "\n"


def reference_page() -> str:
    """``docs/scenarios.md``."""
    parts = [_HEAD, "## Scenarios\n"]
    parts += [section_markdown(s) for s in SCENARIO]
    parts += ["## Plans\n", "A plan's variants change the base scenario's keys of the same "
              "name; their ranges are the scenario's.\n"]
    parts += [section_markdown(s) for s in PLAN]
    return "\n".join(parts)
