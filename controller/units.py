"""Angle conversion constants and Quantity helpers for the public API boundary.

Inside the package angles are plain floats with the unit in the name (``az_rad``,
``offset_arcmin``); astropy Quantity is accepted and returned only at public boundaries.
"""

from __future__ import annotations

import math

import numpy as np
from astropy import units as u

__all__ = [
    "ARCMIN_PER_RAD",
    "ARCSEC_PER_RAD",
    "DEG_PER_RAD",
    "RAD_PER_ARCMIN",
    "RAD_PER_ARCSEC",
    "RAD_PER_DEG",
    "to_value",
    "wrap_pi",
]

RAD_PER_DEG = math.pi / 180.0
DEG_PER_RAD = 180.0 / math.pi
RAD_PER_ARCMIN = RAD_PER_DEG / 60.0
ARCMIN_PER_RAD = DEG_PER_RAD * 60.0
RAD_PER_ARCSEC = RAD_PER_DEG / 3600.0
ARCSEC_PER_RAD = DEG_PER_RAD * 3600.0


def to_value(quantity, unit: str, name: str) -> np.ndarray | float:
    """Return ``quantity`` in ``unit`` as plain float(s); refuse bare numbers.

    Units are never guessed from the type: a bare number raises ``TypeError`` that says
    which unit to attach.
    """
    if not isinstance(quantity, u.Quantity):
        raise TypeError(
            f"{name} must be an astropy Quantity (e.g. {name} * u.{unit}); "
            f"got {type(quantity).__name__}"
        )
    value = quantity.to_value(unit)
    return float(value) if np.ndim(value) == 0 else np.asarray(value, dtype=float)


def wrap_pi(angle_rad):
    """Wrap angle(s) to [-pi, pi)."""
    return (np.asarray(angle_rad) + math.pi) % (2.0 * math.pi) - math.pi
