"""Errors for bad user input: one line naming the file, the field and the value."""

from __future__ import annotations

from typing import Any

__all__ = ["InputError"]


def _short(value: Any, limit: int = 60) -> str:
    text = repr(value)
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


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
        super().__init__(self.line())

    def line(self) -> str:
        text = f"{self.where}: {self.field} = {_short(self.value)}: {self.problem}"
        if self.hint:
            text += f"; {self.hint}"
        return " ".join(text.split())
