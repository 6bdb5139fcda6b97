"""Structure temperature sensors: thermometers on the simulated antenna's structure.

The 1990 antenna had none (its scenario has none); a scenario's ``[structure_sensors]`` table
puts them on (``scenarios/ghigo1990_sensors.toml``). They read the temperatures of the same
members whose differences bend the structure (:class:`~antsim.world.effects.heating.
ThermalEffect`), never the deformation itself, with a real thermometer's imperfections:

* **placement**: twelve sensors, a pair on each of the six differences the thermal model
  bends with (:data:`controller.pointing.thermal.STRUCTURE_SENSORS`): the feed legs
  (``dish_front`` and ``dish_back`` on the upper and lower leg, ``dish_right`` and
  ``dish_left`` on the right and left one), the yoke arms (``yoke_front`` and ``yoke_back``
  on their front and back faces, ``yoke_right`` and ``yoke_left`` on the two arms) and the
  pedestal (north, east, south and west faces). A pair reads its part's mean temperature
  +- half the part's difference; a sensor sees one spot of its member, which in sunshine
  departs from the member's mean by shadows, paint and wind (``local_k`` rms at full overhead
  Sun, scaled by the insolation, an Ornstein-Uhlenbeck wander with ``local_timescale_s``);
* **lag**: ``lag_s``, the first-order response of a sensor clamped to its member under a
  radiation shield;
* **noise**: ``noise_k`` rms per reading, independent (drawn for the time of the reading);
* **resolution**: readings rounded to ``resolution_k``.

Every number is an assumption (``docs/assumptions.md``, Structure temperature sensors).

The legs' and the yoke's differences depend on where the antenna has pointed: the thermal
effect keeps, when sensors read it, the forcing, the differences and the time constants at
every instant its state advanced to (``parts_log``); the sensors' lag follows that history
exactly under the effect's own assumption (between two instants a difference relaxes towards
the later instant's forcing). A reading first has the antenna compute its pending
integrations, so that the history reaches the time of the reading.

Without a thermal effect the structure is isothermal at the air temperature lagged by
:data:`BULK_TAU_S`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from controller.pointing.thermal import STRUCTURE_SENSORS

from .effects.heating import PARTS, ThermalEffect
from .effects.thermal import GRID_STEP_S, campaign_grid_s, interp_rows, ou_series, relax

__all__ = ["SensorConfig", "StructureSensors", "thermal_truth"]

#: a sensor's part of the structure and which side of its difference it is on (the parts of
#: the feed legs and the yoke are the thermal effect's pointing-dependent differences)
_SIDES = {
    "dish_front": ("dish_fb", 0.5), "dish_back": ("dish_fb", -0.5),
    "dish_right": ("dish_lr", 0.5), "dish_left": ("dish_lr", -0.5),
    "yoke_front": ("yoke_fb", 0.5), "yoke_back": ("yoke_fb", -0.5),
    "yoke_right": ("yoke_lr", 0.5), "yoke_left": ("yoke_lr", -0.5),
    "pedestal_north": ("pedestal_n", 0.5), "pedestal_south": ("pedestal_n", -0.5),
    "pedestal_east": ("pedestal_e", 0.5), "pedestal_west": ("pedestal_e", -0.5),
}
#: the parts that follow where the antenna points: sensor part -> index in the thermal
#: effect's state (:data:`antsim.world.effects.heating.PARTS`)
POINTED = {"dish_fb": PARTS.index("legs_ul"), "dish_lr": PARTS.index("legs_rl"),
           "yoke_fb": PARTS.index("yoke_fb"), "yoke_lr": PARTS.index("yoke_rl")}
#: the time constant of an isothermal structure's bulk temperature (s), without a thermal
#: effect: a steel wall 20 mm thick losing 10 W/(m^2 K) (antsim.world.heat.time_constant_s)
BULK_TAU_S = 7200.0


@dataclass(frozen=True)
class SensorConfig:
    """A scenario's structure temperature sensors (``[structure_sensors]``; units in the
    names; every default an assumption of ``docs/assumptions.md``)."""

    names: tuple[str, ...] = tuple(STRUCTURE_SENSORS)
    noise_k: float = 0.05
    resolution_k: float = 0.1
    lag_s: float = 60.0
    local_k: float = 0.3
    local_timescale_s: float = 1800.0
    notes: tuple[str, ...] = field(default=(), compare=False)


def thermal_truth(params: dict[str, float]) -> dict[str, float]:
    """A thermal effect's coefficients (its parameters ``params``, the effect's defaults for
    those not given) as the thermal terms of :mod:`controller.pointing.thermal` express them
    (arcsec per kelvin of the sensors' difference, indicated minus true): each pair's
    difference is its part's difference (without the sensors' imperfections), so TEDFB and
    TSDRL are the feed legs' arcsec per kelvin, TEYFB the yoke's bow and TPYRL its roll,
    TNPNS, TWPEW and TTILT the pedestal's tilt per kelvin (the geometry's,
    :class:`antsim.world.structure.Structure`), towards the cooler side: TNPNS (north by c
    per kelvin of north minus south) its negative, TWPEW (west by c per kelvin of east minus
    west) and TTILT (towards the cooler side) the tilt itself."""
    full = {k: spec.default for k, spec in ThermalEffect.PARAMS.items()}
    k = ThermalEffect(**{**full, **params}).coefficients()
    return {"TEDFB": k["legs_el"], "TSDRL": k["legs_xel"], "TEYFB": k["yoke_bow"],
            "TPYRL": k["yoke_roll"], "TNPNS": -k["pedestal_tilt"],
            "TWPEW": k["pedestal_tilt"], "TTILT": k["pedestal_tilt"]}


def _lagged_step(s0: float, g0: float, f: float, dt: float, tau_g: float,
                 tau_s: float) -> float:
    """A first-order sensor (time constant ``tau_s``) reading a member whose temperature
    relaxes from ``g0`` towards ``f`` with ``tau_g``, ``dt`` after both were at (``s0``,
    ``g0``): the exact solution."""
    if tau_s <= 0.0:
        return f + (g0 - f) * math.exp(-dt / tau_g)
    e_s = math.exp(-dt / tau_s)
    if abs(tau_g - tau_s) < 1e-9 * tau_s:
        member = (g0 - f) * (dt / tau_s) * e_s
    else:
        member = (g0 - f) * tau_g / (tau_g - tau_s) * (math.exp(-dt / tau_g) - e_s)
    return f + (s0 - f) * e_s + member


class StructureSensors:
    """The sensors of one world (see the module docstring)."""

    def __init__(self, config: SensorConfig, world, rng: np.random.Generator):
        self.config = config
        self.names = tuple(config.names)
        thermal = next((e for e in world.effects if isinstance(e, ThermalEffect)), None)
        self.thermal = thermal
        if thermal is not None:
            t = thermal.t_grid
            bulk = thermal.structure_c
            parts = {"pedestal_n": thermal.pedestal_n_k, "pedestal_e": thermal.pedestal_e_k}
            insolation = thermal._insolation
            thermal.parts_log = {}
        else:
            t = campaign_grid_s(world.duration_s)
            air = world.air_temperature_c(t)
            bulk = relax(air, GRID_STEP_S, BULK_TAU_S, float(air[0]))
            parts = {}
            insolation = np.zeros_like(t)
        self.t_grid = t
        # every sensor's own wander, drawn in the order of the scenario's list
        series = []
        for name in self.names:
            part, side = _SIDES[name]
            local = ou_series(rng, t.size, GRID_STEP_S, config.local_timescale_s,
                              config.local_k) * insolation
            member = bulk + local
            if part in parts:
                member = member + side * parts[part]
            series.append(relax(member, GRID_STEP_S, config.lag_s, float(member[0]))
                          if config.lag_s > 0 else member)
        self._slow = np.array(series)
        # the pointing-dependent differences through the sensors' lag: (time, the members'
        # differences, the sensors' readings of them), each (4,)
        self._pointed_state: tuple[float, list[float], list[float]] | None = None
        #: a reading's noise is drawn from this key and the time of the reading, so that
        #: who reads when (a second client, a monitor) changes no other reading
        self._noise_key = int(rng.integers(2**63))

    def true_coefficients(self) -> dict[str, float]:
        """The thermal effect's coefficients as the thermal terms express them
        (:func:`thermal_truth`); empty without a thermal effect."""
        return {} if self.thermal is None else thermal_truth(self.thermal.p)

    # ------------------------------------------------------------------ legs and yoke
    def _pointed_lagged(self, t_s: float, az_rad: float, el_rad: float) -> list[float]:
        """The pointing-dependent differences (:data:`POINTED`'s order: legs upper-lower and
        right-left, yoke front-back and right-left) as lagged sensors see them at ``t_s``
        (the antenna pointing at ``az_rad``, ``el_rad`` since the last instant)."""
        thermal = self.thermal
        if thermal is None or not thermal.parts_log:
            return [0.0] * 4
        tau_s = self.config.lag_s
        log = thermal.parts_log
        state = self._pointed_state
        times = sorted(k for k in log if state is None or k > state[0])
        for t_k in times:
            if t_k > t_s:
                break
            forcing, values, tau_leg, tau_yoke = log[t_k]
            if state is None:  # no past: the sensors start at the members' values
                state = (t_k, list(values), list(values))
                continue
            t0, g0, s0 = state
            dt = t_k - t0
            taus = (tau_leg, tau_leg, tau_yoke, tau_yoke)
            state = (t_k, list(values), [_lagged_step(s0[i], g0[i], forcing[i], dt, taus[i],
                                                      tau_s) for i in range(4)])
        self._pointed_state = state
        if state is None:
            return [0.0] * 4
        t0, g0, s0 = state
        if t_s <= t0:
            return s0
        # since the last instant: the forcing of where the antenna points now
        forcing = thermal.forcings_k(t_s, az_rad, el_rad).tolist()
        series = thermal.series_at(t_s)
        taus = (series[6], series[6], series[7], series[7])
        dt = t_s - t0
        return [_lagged_step(s0[i], g0[i], forcing[i], dt, taus[i], tau_s) for i in range(4)]

    # ------------------------------------------------------------------ readings
    def read(self, t_s: float, az_rad: float, el_rad: float) -> dict[str, float]:
        """Every sensor's reading (C) at ``t_s``, the antenna pointing at (``az_rad``,
        ``el_rad``) (true direction, radians): member temperature, lag, noise, resolution."""
        slow = interp_rows(float(t_s), self.t_grid, self._slow)
        lagged = self._pointed_lagged(float(t_s), az_rad, el_rad)
        pointed = {part: lagged[i] for part, i in POINTED.items()}
        draws = np.random.default_rng((self._noise_key, round(float(t_s) * 1e6)))
        noise = draws.standard_normal(len(self.names)) * self.config.noise_k
        res = self.config.resolution_k
        out = {}
        for i, name in enumerate(self.names):
            part, side = _SIDES[name]
            value = float(slow[i]) + side * pointed.get(part, 0.0) + float(noise[i])
            out[name] = round(round(value / res) * res, 9) if res > 0 else value
        return out
