"""Validated numbers and the array conventions every astro module shares."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["finite_fields", "require_finite", "scalar", "seconds_value"]


def require_finite(value: Any, name: str) -> None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is not a number; give a plain number.") from None
    if not math.isfinite(number):
        raise ValueError(f"{name} = {value!r} is not finite; give a finite number.")


def finite_fields(instance: Any, label: str, *names: str) -> None:
    """Check that the named dataclass fields are finite numbers and store them as floats."""
    for name in names:
        value = getattr(instance, name)
        require_finite(value, f"{label} {name}")
        object.__setattr__(instance, name, float(value))


def seconds_value(value: Any, name: str) -> float:
    """A duration in seconds from a number or an astropy Quantity of time."""
    if hasattr(value, "unit"):
        try:
            value = value.to_value("s")
        except Exception:
            raise ValueError(f"{name} = {value} is not a time; give seconds.") from None
    require_finite(value, name)
    return float(value)


def scalar(array: np.ndarray):
    """0-d arrays become numpy scalars; other arrays pass through."""
    return array[()] if np.ndim(array) == 0 else array
