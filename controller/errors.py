"""Errors for bad user input: one line naming the file, the field and the value."""

from __future__ import annotations

from os import PathLike, fspath
from typing import Any

__all__ = ["InputError", "Note", "read_text_file"]


def _short(value: Any, limit: int = 60) -> str:
    if type(value).__module__ == "numpy" and hasattr(value, "item"):
        value = value.item()  # 3, not np.int64(3)
    text = repr(value)
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


class Note(UserWarning):
    """Something the user should know that is not an error (a damaged cache rebuilt, ...):
    a warning the command line prints as one line, ``antsim COMMAND: note: ...``."""


class InputError(ValueError):
    """Bad input from a file or the command line.

    ``str(err)`` is a single line ``"<where>: <field> = <value>: <problem>[; <hint>]"``
    that the command line prints before exiting with status 2.
    """

    def __init__(self, where: str, field: str, value: Any, problem: str, hint: str = ""):
        self.where = str(where)
        self.field = str(field)
        self.value = value
        self.problem = problem
        self.hint = hint
        # the parts, not the line, are the args: simpy and process pools rebuild an
        # exception as type(err)(*err.args)
        super().__init__(where, field, value, problem, hint)

    def __str__(self) -> str:
        return self.line()

    def line(self) -> str:
        text = f"{self.where}: {self.field} = {_short(self.value)}: {self.problem}"
        if self.hint:
            text += f"; {self.hint}"
        return " ".join(text.split())


def read_text_file(path: str | PathLike[str], what: str = "file") -> str:
    """The text of a UTF-8 file (a leading byte-order mark dropped), or one InputError line
    for a missing, unreadable or binary file."""
    name = fspath(path)
    try:
        with open(name, "rb") as fh:
            data = fh.read()
    except FileNotFoundError:
        raise InputError(name, what, name, "no such file") from None
    except IsADirectoryError:
        raise InputError(name, what, name, "is a directory, not a file") from None
    except OSError as err:
        raise InputError(name, what, name, f"cannot be read ({err.strerror or err})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        raise InputError(f"{name}:{line}", what, data[err.start:err.start + 8],
                         f"is not UTF-8 text ({err.reason} at byte {err.start})") from None
    if "\x00" in text:
        line = text.count("\n", 0, text.index("\x00")) + 1
        raise InputError(f"{name}:{line}", what, "\\x00", "is not text: it holds a NUL byte")
    return text.removeprefix("\ufeff")
