"""The scenarios and plans that come with antsim, addressable by name.

``antsim run ghigo1990`` runs the scenario called ``ghigo1990``: a scenario's name is its file
name without ``.toml``, a plan's likewise (``antsim plan ghigo1990_whatif``). A path to a file
still works, and wins when it exists. Where they live:

* in an installed wheel, ``antsim/scenarios/`` (package data: the build maps the source
  tree's top-level ``scenarios/`` there, ``pyproject.toml``);
* in a source tree (a clone, an editable install), the top-level ``scenarios/`` itself, the
  one place they are edited.

Plans are in ``plans/`` under it. Listing them (:func:`catalogue`) reads only each file's
``name``, ``description`` and telescope, so ``antsim scenarios`` stays quick.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from controller.errors import InputError

__all__ = ["Entry", "catalogue", "find", "names", "scenarios_dir", "shown"]

Kind = Literal["scenario", "plan"]
_HERE = Path(__file__).resolve().parent


def scenarios_dir() -> Path:
    """The directory of the scenarios that come with this antsim (installed or source)."""
    installed = _HERE / "scenarios"
    return installed if installed.is_dir() else _HERE.parent / "scenarios"


def _dir(kind: Kind) -> Path:
    return scenarios_dir() / "plans" if kind == "plan" else scenarios_dir()


def names(kind: Kind = "scenario") -> list[str]:
    """The names of the scenarios (or plans) that come with antsim, sorted."""
    return sorted(p.stem for p in _dir(kind).glob("*.toml"))


def find(spec: str | Path, kind: Kind = "scenario", where: str = "command line",
         field: str | None = None, relative_to: Path | None = None) -> Path:
    """The file ``spec`` names: an existing path (relative to the directory ``relative_to``
    when given, as a plan names its scenario), else the scenario (or plan) of that name.

    Anything else is one :class:`InputError` at ``where``/``field`` (a missing file given on
    the command line: at that file) that lists the valid names (and, for a path whose file
    name is one of them, says to use the name).
    """
    field = field or kind.upper()
    path = Path(spec)
    if relative_to is not None and not path.is_absolute():
        path = relative_to / path
    if path.is_file():
        return path
    path = Path(spec)
    text = str(spec)
    known = names(kind)
    stem = path.name.removesuffix(".toml")
    if path.name == text and stem in known:  # a bare name, with or without .toml
        return _dir(kind) / f"{stem}.toml"
    listing = f"{kind}s that come with antsim: {' '.join(known)}"
    if relative_to is not None:
        listing = f"paths are relative to {relative_to}; {listing}"
    if path.name != text or text.endswith(".toml"):
        hint = (f"the {kind} that comes with antsim is named {stem}" if stem in known
                else listing)
        # the file first: a long path's value is shortened in the line
        raise InputError(text if relative_to is None else where, field, text,
                         f"no such {kind} file", hint)
    other: Kind = "plan" if kind == "scenario" else "scenario"
    if text.removesuffix(".toml") in names(other):  # the other kind's name: say which
        command = "plan" if other == "plan" else "run"
        listing = f"{text} is a {other}: antsim {command} {text.removesuffix('.toml')}"
    raise InputError(where, field, text, f"neither a file nor the name of a {kind}", listing)


def shown(path: Path) -> str:
    """How a command line names ``path``: its name for a file that comes with antsim (in
    which case it is one of :func:`names`), else the path."""
    resolved = path.resolve()
    for kind in ("scenario", "plan"):
        if resolved.parent == _dir(kind).resolve() and resolved.stem in names(kind):
            return resolved.stem
    return str(path)


@dataclass(frozen=True)
class Entry:
    """One line of ``antsim scenarios``: a scenario's or plan's name, telescope and what it
    is (its ``description``)."""

    kind: Kind
    name: str
    telescope: str
    description: str
    path: Path


def catalogue(kind: Kind = "scenario") -> list[Entry]:
    """The scenarios (or plans) that come with antsim, with their one-line descriptions; a
    plan's telescope is its base scenario's."""
    out = []
    for name in names(kind):
        path = _dir(kind) / f"{name}.toml"
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
        if kind == "plan":
            base = find(str(doc.get("scenario", "")), "scenario", str(path), "scenario",
                        relative_to=path.parent)
            telescope = _telescope(tomllib.loads(base.read_text(encoding="utf-8")))
        else:
            telescope = _telescope(doc)
        out.append(Entry(kind, name, telescope, str(doc.get("description", "")), path))
    return out


def _telescope(doc: dict) -> str:
    site = doc.get("site", {})
    return str(site.get("name", "")) if isinstance(site, dict) else ""
