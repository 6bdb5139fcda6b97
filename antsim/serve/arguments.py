"""Request arguments of `antsim serve`: parsed with errors that name the argument.

Arguments arrive as bytes (aiokatcp decodes nothing): numbers are read with ``float``, so a
client may send any float text, and a bad one gets a failure reply such as ``argument 1
(SECONDS) 'abc' is not a number``.
"""

from __future__ import annotations

import math

__all__ = ["ArgumentError", "at_most", "integer", "number", "numbers", "quoted", "within"]


class ArgumentError(ValueError):
    """A request argument that cannot be used; the message names it."""


def quoted(arg: bytes) -> str:
    """An argument as it appears in an error message."""
    return repr(arg.decode("utf-8", "replace"))


def number(args: tuple[bytes, ...], i: int, name: str) -> float:
    """Argument ``i`` (called ``name``) as a finite float."""
    try:
        value = float(args[i])
    except IndexError:
        raise ArgumentError(f"argument {i + 1} ({name}) is missing") from None
    except ValueError:
        raise ArgumentError(f"argument {i + 1} ({name}) {quoted(args[i])} is not a "
                            "number") from None
    if not math.isfinite(value):
        raise ArgumentError(f"argument {i + 1} ({name}) {quoted(args[i])} is not a finite "
                            "number")
    return value


def within(args: tuple[bytes, ...], i: int, name: str, low: float, high: float,
           unit: str = "") -> float:
    """Argument ``i`` (called ``name``) as a finite float in ``low..high``."""
    value = number(args, i, name)
    if not low <= value <= high:
        raise ArgumentError(f"argument {i + 1} ({name}) {quoted(args[i])}: must lie within "
                            f"{low:g}..{high:g}{' ' + unit if unit else ''}")
    return value


def integer(args: tuple[bytes, ...], i: int, name: str) -> int:
    """Argument ``i`` (called ``name``) as an integer."""
    try:
        return int(args[i])
    except IndexError:
        raise ArgumentError(f"argument {i + 1} ({name}) is missing") from None
    except ValueError:
        raise ArgumentError(f"argument {i + 1} ({name}) {quoted(args[i])} is not an "
                            "integer") from None


def at_most(args: tuple[bytes, ...], n: int, usage: str) -> None:
    """Refuse more than ``n`` arguments, showing ``usage``."""
    if len(args) > n:
        raise ArgumentError(f"too many arguments ({len(args)}): usage {usage}")


def numbers(args: tuple[bytes, ...]) -> list[float]:
    """Every argument as a float (a program track's table)."""
    values = []
    for i, arg in enumerate(args):
        try:
            values.append(float(arg))
        except ValueError:
            raise ArgumentError(f"argument {i + 1} {quoted(arg)} is not a number") from None
    return values
