"""Interferometer geometry of one antenna: the delay of non-intersecting axes (BIMA memo 23).

When an alt-az antenna's elevation axis is displaced horizontally by ``D`` from its azimuth
axis (towards the direction the antenna points), the point that stays fixed as the antenna
turns (on the azimuth axis) is not the point that defines the antenna's position in the
array. The elevation axis lies ``D`` from the azimuth axis along the horizontal direction of
the source, so a wavefront from elevation E reaches it earlier by the path ``D cos(E)``: an
extra delay term ``D cos(E) / c`` that depends on elevation alone (Wright 1992 writes it as
D cos(El)), to be removed from the array's geometric delay model.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SPEED_OF_LIGHT_M_S", "axis_offset_delay_s", "axis_offset_path_m"]

SPEED_OF_LIGHT_M_S = 299792458.0


def axis_offset_path_m(offset_m, el_rad) -> np.ndarray:
    """Path (m) by which the wavefront reaches the elevation axis before the azimuth axis,
    ``D cos(E)``, for axis offset ``offset_m`` (m, positive: the elevation axis lies towards
    the pointing direction) at elevation(s) ``el_rad``."""
    return np.asarray(offset_m, dtype=float) * np.cos(np.asarray(el_rad, dtype=float))


def axis_offset_delay_s(offset_m, el_rad) -> np.ndarray:
    """The delay term ``D cos(E) / c`` (s) of :func:`axis_offset_path_m`."""
    return axis_offset_path_m(offset_m, el_rad) / SPEED_OF_LIGHT_M_S
