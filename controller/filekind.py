"""What kind of file a user gave: the one place that decides it, from the name and the text.

Every command that reads a user's file asks here first: pointing data for ``antsim fit`` and
``antsim diagnose`` (:mod:`controller.program.inputs`, which then reads it) and a model for
``--model`` (:mod:`controller.pointing.modelio`). The kinds:

* ``"ecsv"``: antsim's recordings, the text starts with ``# %ECSV``;
* ``"csv"``: measurements as CSV (:mod:`controller.program.csvdata`): a ``.csv`` name, or a
  first line (after ``#`` lines) of at least four comma-separated names one an azimuth;
* ``"json"``: a model as JSON (a ``fit.json``), the text starts with ``{`` or ``[``;
* ``"tpoint"``: TPOINT pointing data: after the caption, an option (``:``) or a
  run-parameters record of numbers;
* ``"mod"``: a TPOINT model: after the caption, a word and numbers (the parameters record)
  or a term line.

Anything else is one :class:`~controller.errors.InputError` line. This module reads text
only: it imports nothing of the program but its errors.
"""

from __future__ import annotations

import re
from os import PathLike
from typing import Literal

from controller.errors import InputError

__all__ = ["KIND_NAMES", "FileKind", "file_kind", "looks_like_csv", "tpoint_or_mod"]

FileKind = Literal["ecsv", "csv", "json", "tpoint", "mod"]

#: each kind in words, for a line that says what a file is and should not be
KIND_NAMES: dict[str, str] = {
    "ecsv": "ECSV recordings",
    "csv": "CSV measurements",
    "json": "JSON (a model such as a fit.json)",
    "tpoint": "TPOINT pointing data",
    "mod": "a TPOINT model (.mod)",
}

_NUMBER = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")


def file_kind(path: str | PathLike[str], text: str) -> FileKind:
    """The kind of the file at ``path`` whose text is ``text`` (see the module)."""
    if text.startswith("# %ECSV"):
        return "ecsv"
    if looks_like_csv(path, text):
        return "csv"
    if text.lstrip()[:1] in ("{", "["):
        return "json"
    return tpoint_or_mod(path, text)


def looks_like_csv(path: str | PathLike[str], text: str) -> bool:
    """Whether a file is CSV pointing data: a ``.csv`` name, or a first line (after ``#``
    lines) of comma-separated names that include an azimuth column."""
    if str(path).lower().endswith(".csv"):
        return True
    for line in text.splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        names = [n.strip().lower() for n in line.split(",")]
        return len(names) >= 4 and any(n == "az" or n.startswith("az_") for n in names)
    return False


def tpoint_or_mod(path: str | PathLike[str], text: str) -> Literal["tpoint", "mod"]:
    """TPOINT pointing data or a TPOINT model, by the record after the caption: an option
    (``:``) or a run-parameters record of numbers means data; a word followed by numbers (the
    model parameters record) or a term line means a model."""
    caption_seen = False
    second: str | None = None
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("!"):
            continue
        if not caption_seen:
            caption_seen = True
            continue
        second = stripped.split("!", 1)[0].strip()
        if second:
            break
    where = str(path)
    if not second:
        raise InputError(where, "file", where,
                         "is too short to be TPOINT data, a .mod model or ECSV recordings")
    tokens = second.split()
    if second.startswith(":") or all(_NUMBER.match(t) for t in tokens):
        return "tpoint"
    if re.fullmatch(r"[A-Za-z&=]\S*", tokens[0]):
        return "mod"
    raise InputError(where, "file", where,
                     "is neither TPOINT pointing data, a TPOINT .mod model nor ECSV recordings")
