"""Thermal pointing terms: linear in structure temperatures, or in proxies for them.

An antenna's structure bends as the Sun warms one side of it more than the other: the
pointing error is, to first order, linear in temperature differences across the structure
(the JCMT corrects 6.5" per kelvin of front-to-back difference of its legs; the GBT,
Effelsberg and the IRAM 30-m fit linear models of structure temperature sensors). These
terms multiply one of the basic shapes of the 1990 report's model by a recorded temperature
difference, per axis:

| shape | error (indicated minus true) | like |
|---|---|---|
| E | dE = c dT | W1 (elevation offset) |
| S | dA cos E = c dT | W10 (collimation: constant on the sky) |
| P | dA cos E = c dT sin E | W9 (the axes' non-perpendicularity: a rolled elevation axis) |
| N | dE = c dT cos A, dA cos E = c dT sin A sin E | W2 = W8: the azimuth axis tilted north |
| W | dE = -c dT sin A, dA cos E = c dT cos A sin E | W3 = -W7: the azimuth axis tilted west |

in the report's sign (indicated minus true), so that a coefficient is the error per kelvin
(arcsec/K) that the structure's bending adds. Names: ``T`` + shape + the sensor pair
(:data:`SENSOR_PAIRS`), e.g. ``TEDFB``: elevation error per kelvin of the dish's
front-minus-back difference. Each axis' rows read the temperatures recorded during that
axis' half of the cross scan (:func:`structure_column`), corrected for the sensors' response
time where it is known (:func:`sensor_aux`).

The sensors (:data:`STRUCTURE_SENSORS`) are those of antsim's simulated 45-ft
(``antsim.world.sensors``; where and why, ``docs/assumptions.md`` and ``docs/physics.md``):
pairs on the feed legs (the upper and lower leg, named front and back as the JCMT names its
leg pairs; the right and left leg), across the yoke (the arms' front and back faces, the
right and left arm) and around the pedestal (north, east, south, west faces).

Without sensors, proxies that every recording allows (:mod:`controller.pointing.proxies`:
the Sun's height and its direction relative to the dish, lagged by a structure time
constant, and the air temperature) multiply the same shapes: ``TESUN``, ``TEFACE``,
``TSSIDE``, ``TNSUN``, ``TWSUN``, ``TEAIR`` (:data:`PROXY_TERMS`; coefficients in arcsec per
unit of the proxy).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .terms import COS_AN, SIN_AN, TAN_E, Regressor, Term, register_terms

__all__ = ["PROXY_TERMS", "SENSOR_FAMILY", "SENSOR_PAIRS", "SENSOR_TERMS", "STRUCTURE_SENSORS",
           "THERMAL_TERMS", "sensor_aux", "structure_column", "structure_sensor_names",
           "structure_time_column", "thermal_regressors"]

#: where each structure temperature sensor sits (antsim's 45-ft; docs/assumptions.md)
STRUCTURE_SENSORS: dict[str, str] = {
    "dish_front": "feed leg above the feed (with the dish at the horizon)",
    "dish_back": "feed leg below the feed",
    "dish_left": "feed leg on the left (looking out along the beam)",
    "dish_right": "feed leg on the right (towards increasing azimuth)",
    "yoke_front": "yoke arms, front faces (facing where the antenna points)",
    "yoke_back": "yoke arms, back faces",
    "yoke_left": "left yoke arm",
    "yoke_right": "right yoke arm",
    "pedestal_north": "pedestal, north face",
    "pedestal_east": "pedestal, east face",
    "pedestal_south": "pedestal, south face",
    "pedestal_west": "pedestal, west face",
}

#: the temperature differences the terms use: code -> (plus, minus)
SENSOR_PAIRS: dict[str, tuple[str, str]] = {
    "DFB": ("dish_front", "dish_back"),
    "DRL": ("dish_right", "dish_left"),
    "YFB": ("yoke_front", "yoke_back"),
    "YRL": ("yoke_right", "yoke_left"),
    "PNS": ("pedestal_north", "pedestal_south"),
    "PEW": ("pedestal_east", "pedestal_west"),
}

_SHAPES = {
    # shape: (TPOINT-sign components without the regressor factor, words)
    "E": ((("E", -1.0, ()),), "dE = c dT"),
    "S": ((("S", -1.0, ()),), "dA cos E = c dT"),
    "N": ((("E", -1.0, (COS_AN,)), ("A", -1.0, (SIN_AN, TAN_E))),
          "azimuth axis tilted north by c dT: dE = c dT cos A, dA cos E = c dT sin A sin E"),
    "W": ((("E", 1.0, (SIN_AN,)), ("A", -1.0, (COS_AN, TAN_E))),
          "azimuth axis tilted west by c dT: dE = -c dT sin A, dA cos E = c dT cos A sin E"),
    "P": ((("A", -1.0, (TAN_E,)),), "elevation axis rolled by c dT: dA cos E = c dT sin E"),
}


def _thermal(name: str, shape: str, regressor: Regressor, what: str) -> Term:
    components, words = _SHAPES[shape]
    factor = ("lin", regressor, 1)
    return Term(name, f"{words}; dT = {what} (c per unit of dT)",
                tuple((axis, sign, (*factors, factor)) for axis, sign, factors in components),
                kind="thermal")


def _sensor_terms() -> dict[str, Term]:
    spec = (("TEDFB", "E", "DFB"), ("TSDRL", "S", "DRL"), ("TEYFB", "E", "YFB"),
            ("TPYRL", "P", "YRL"), ("TNPNS", "N", "PNS"), ("TWPEW", "W", "PEW"))
    out = {}
    for name, shape, pair in spec:
        plus, minus = SENSOR_PAIRS[pair]
        out[name] = _thermal(name, shape, Regressor(plus, minus), f"{plus} - {minus} (K)")
    # an axisymmetric pedestal bends away from its warmer side by the same angle per kelvin
    # whichever way its difference lies: the axis tilts towards the cooler side, north by c
    # per kelvin of south minus north (TNPNS = -c) and west by c per kelvin of east minus
    # west (TWPEW = c)
    north, west = out["TNPNS"], out["TWPEW"]
    south = tuple((axis, -sign, factors) for axis, sign, factors in north.components)
    out["TTILT"] = Term("TTILT", "azimuth axis tilted towards the cooler side of the pedestal "
                        "by c per kelvin: TWPEW = c and TNPNS = -c with one coefficient",
                        south + west.components, kind="thermal")
    return out


def _proxy_terms() -> dict[str, Term]:
    spec = (("TESUN", "E", "sun_lag", "the Sun's insolation lagged by the structure"),
            ("TEFACE", "E", "sun_face", "the insolation on the dish's face (Sun in front "
                                        "of the dish: +, behind it: -)"),
            ("TSSIDE", "S", "sun_side", "the insolation on the dish's right side"),
            ("TNSUN", "N", "sun_north_lag", "the insolation from the north, lagged"),
            ("TWSUN", "W", "sun_east_lag", "the insolation from the east, lagged"),
            ("TEAIR", "E", "air_lag", "the air temperature lagged by the structure (K)"))
    return {name: _thermal(name, shape, Regressor(key), what)
            for name, shape, key, what in spec}


#: terms in structure temperature differences (arcsec per kelvin)
SENSOR_TERMS: dict[str, Term] = _sensor_terms()
#: the six pair terms: one term per sensor pair (TTILT is TNPNS and TWPEW with one
#: coefficient); fit T and diagnose test them as one family
SENSOR_FAMILY: tuple[str, ...] = ("TEDFB", "TSDRL", "TEYFB", "TPYRL", "TNPNS", "TWPEW")
#: terms in proxies (arcsec per unit of the proxy; :mod:`controller.pointing.proxies`)
PROXY_TERMS: dict[str, Term] = _proxy_terms()
THERMAL_TERMS: dict[str, Term] = {**SENSOR_TERMS, **PROXY_TERMS}
register_terms(THERMAL_TERMS)  # get_term knows them by name (the package imports this first)

AXES_RECORDED = ("xel", "el")


def structure_column(sensor: str, axis: str) -> str:
    """The recordings' column of ``sensor`` read during the ``axis`` ("xel": azimuth scan,
    "el": elevation scan) half of a cross scan (C)."""
    return f"temp_{sensor}_{axis}_c"


def structure_time_column(axis: str) -> str:
    """The recordings' column of the antenna clock (s) when the structure temperatures were
    read during the ``axis`` half of a cross scan."""
    return f"temp_{axis}_t_s"


def structure_sensor_names(column_names: Sequence[str]) -> tuple[str, ...]:
    """The sensors whose two columns (both halves) are among ``column_names``, or their one
    column ``temp_<sensor>_c`` (one reading per row, e.g. from a CSV file)."""
    names = set(column_names)
    return tuple(s for s in STRUCTURE_SENSORS
                 if all(structure_column(s, a) in names for a in AXES_RECORDED)
                 or f"temp_{s}_c" in names)


def sensor_aux(columns: Mapping[str, np.ndarray], sensors: Sequence[str],
               lag_s: float = 0.0) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The ``aux`` of :class:`~controller.pointing.data.PointingData` from recording
    columns: sensor -> (reading during the azimuth scan, during the elevation scan) (C).

    ``lag_s``: the sensors' response time (their datasheet's first-order time constant).
    A first-order sensor reads T_read with T_member = T_read + lag dT_read/dt; the slope is
    taken from the scan's two readings (columns :func:`structure_time_column`), so each
    reading becomes the member's temperature then. Without it, a sensor a minute slow reads
    the dish's difference late after every slew, which biases the terms that share its
    pointing pattern (``benchmarks/recovery.py``)."""
    out = {}
    times = [structure_time_column(a) for a in AXES_RECORDED]
    compensate = lag_s > 0.0 and all(c in columns for c in times)
    if compensate:
        gap = np.asarray(columns[times[1]], dtype=float) - np.asarray(columns[times[0]],
                                                                      dtype=float)
        gap = np.where(gap > 0.0, gap, np.nan)
    for s in sensors:
        halves = [structure_column(s, a) for a in AXES_RECORDED]
        if not all(c in columns for c in halves):  # one reading per row: for both axes
            halves = [f"temp_{s}_c"] * 2
        xel, el = (np.asarray(columns[c], dtype=float) for c in halves)
        if compensate:
            ahead = lag_s * (el - xel) / gap
            xel, el = xel + ahead, el + ahead
        out[s] = (xel, el)
    return out


def thermal_regressors(terms: Sequence[Term]) -> set[str]:
    """The recorded names the thermal factors of ``terms`` read."""
    names: set[str] = set()
    for term in terms:
        for _, _, factors in term.components:
            for _, arg, _ in factors:
                if isinstance(arg, Regressor):
                    names.update(arg.names)
    return names
