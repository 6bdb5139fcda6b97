"""Validated reading of TOML tables: every bad value becomes one InputError line.

``Table`` wraps a parsed TOML table with the file name and the dotted key path, so that a
problem anywhere reads ``ghigo1990.toml: telescope.axes.az_speed_deg_s = -1.0: must be > 0``.
Unknown keys are errors too (a misspelt key silently ignored is a wrong simulation).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from controller.errors import InputError, read_text_file

__all__ = ["Table", "load_toml"]

_MISSING = object()


def load_toml(path: str | Path) -> Table:
    """Parse a TOML file into a :class:`Table`; unreadable or invalid files raise InputError."""
    path = Path(path)
    where = str(path)
    text = read_text_file(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InputError(where, "TOML syntax", str(err).split("\n")[0], "not valid TOML") from None
    except RecursionError:  # the reader recurses once per level of nested arrays and tables
        raise InputError(where, "TOML syntax", "arrays or tables nested too deeply",
                         "not valid TOML for antsim: nest a few levels at most") from None
    table = Table(data, where, "")
    table.text = text
    return table


class Table:
    """A TOML table that remembers where it came from and which keys were read."""

    def __init__(self, data: dict[str, Any], where: str, prefix: str):
        self.data = data
        self.where = where
        self.prefix = prefix
        self._read: set[str] = set()
        #: the file's text (the root table of a file only)
        self.text = ""

    # ------------------------------------------------------------------ helpers
    def key(self, name: str) -> str:
        """Dotted path of ``name`` inside the file."""
        return f"{self.prefix}.{name}" if self.prefix else name

    def error(self, name: str, value: Any, problem: str, hint: str = "") -> InputError:
        return InputError(self.where, self.key(name), value, problem, hint)

    def __contains__(self, name: str) -> bool:
        return name in self.data

    def keys(self) -> list[str]:
        return list(self.data)

    def __iter__(self):
        return iter(list(self.data))

    def _get(self, name: str, default: Any) -> Any:
        self._read.add(name)
        if name in self.data:
            return self.data[name]
        if default is _MISSING:
            raise InputError(self.where, self.key(name), "<missing>", "required key is missing")
        return default

    # ------------------------------------------------------------------ typed getters
    def number(self, name: str, default: Any = _MISSING, *, min: float | None = None,
               max: float | None = None, gt: float | None = None, lt: float | None = None,
               allow_none: bool = False) -> float:
        """A finite float (ints accepted) within the given bounds."""
        value = self._get(name, default)
        if value is None and allow_none:
            return None  # type: ignore[return-value]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(name, value, "must be a number")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(name, value, "must be finite")
        if min is not None and value < min:
            raise self.error(name, value, f"must be >= {min:g}")
        if max is not None and value > max:
            raise self.error(name, value, f"must be <= {max:g}")
        if gt is not None and value <= gt:
            raise self.error(name, value, f"must be > {gt:g}")
        if lt is not None and value >= lt:
            raise self.error(name, value, f"must be < {lt:g}")
        return value

    def integer(self, name: str, default: Any = _MISSING, *, min: int | None = None,
                max: int | None = None) -> int:
        value = self._get(name, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(name, value, "must be an integer")
        if min is not None and value < min:
            raise self.error(name, value, f"must be >= {min}")
        if max is not None and value > max:
            raise self.error(name, value, f"must be <= {max}")
        return value

    def string(self, name: str, default: Any = _MISSING, *,
               choices: Sequence[str] | None = None) -> str:
        value = self._get(name, default)
        if value is None and default is None:
            return None  # type: ignore[return-value]
        if not isinstance(value, str):
            raise self.error(name, value, "must be a string")
        if choices is not None and value not in choices:
            raise self.error(name, value, f"must be one of {', '.join(choices)}")
        return value

    def boolean(self, name: str, default: Any = _MISSING) -> bool:
        value = self._get(name, default)
        if not isinstance(value, bool):
            raise self.error(name, value, "must be true or false")
        return value

    def numbers(self, name: str, default: Any = _MISSING, *, length: int | None = None,
                min_length: int = 0) -> list[float]:
        """A list of finite numbers."""
        value = self._get(name, default)
        if not isinstance(value, list):
            raise self.error(name, value, "must be a list of numbers")
        out = []
        for item in value:
            if (isinstance(item, bool) or not isinstance(item, int | float)
                    or not math.isfinite(item)):
                raise self.error(name, value, "must be a list of finite numbers")
            out.append(float(item))
        if length is not None and len(out) != length:
            raise self.error(name, value, f"must have {length} elements")
        if len(out) < min_length:
            raise self.error(name, value, f"must have at least {min_length} elements")
        return out

    def strings(self, name: str, default: Any = _MISSING) -> list[str]:
        value = self._get(name, default)
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.error(name, value, "must be a list of strings")
        return list(value)

    def table(self, name: str, default: Any = _MISSING) -> Table:
        """A sub-table (``default={}`` makes it optional)."""
        value = self._get(name, default)
        if not isinstance(value, dict):
            raise self.error(name, value, "must be a table")
        return Table(value, self.where, self.key(name))

    def tables(self, name: str, default: Any = _MISSING) -> Iterator[Table]:
        """An array of tables (``[[name]]``)."""
        value = self._get(name, default)
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.error(name, value, "must be an array of tables ([[...]])")
        for i, item in enumerate(value):
            yield Table(item, self.where, f"{self.key(name)}[{i}]")

    def raw(self, name: str, default: Any = _MISSING) -> Any:
        return self._get(name, default)

    def finish(self) -> None:
        """Raise for any key that no getter asked for (a typo, or an unsupported setting)."""
        unknown = [k for k in self.data if k not in self._read]
        if unknown:
            name = unknown[0]
            known = sorted(self._read)
            hint = f"known keys here: {', '.join(known)}" if known else ""
            raise self.error(name, self.data[name], "unknown key", hint)
