"""Structure temperature sensors: thermometers on the simulated antenna's structure.

The 1990 antenna had none (its scenario has none); a scenario's ``[structure_sensors]`` table
puts them on (``scenarios/ghigo1990_sensors.toml``). They read the same structure
temperatures that drive the thermal deformation (:class:`~antsim.world.effects.thermal.
ThermalEffect`), never the deformation itself, with a real thermometer's imperfections:

* **placement**: twelve sensors, one on each side of the three parts the thermal model
  bends (:data:`controller.pointing.thermal.STRUCTURE_SENSORS`): the dish's backup
  structure (front and back chords, left and right rims), the yoke (front and back faces,
  left and right arms) and the pedestal (north, east, south and west faces). The model's
  temperatures are averages over each part; a sensor sees one member, which in sunshine
  departs from that average by shadows, paint and wind (``local_k`` rms at full overhead
  Sun, scaled by the insolation, an Ornstein-Uhlenbeck wander with ``local_timescale_s``);
  what they see of a part is T_bulk +- half the part's difference;
* **lag**: ``lag_s``, the first-order response of a sensor clamped to its member under a
  radiation shield;
* **noise**: ``noise_k`` rms per reading, independent (drawn for the time of the reading);
* **resolution**: readings rounded to ``resolution_k``.

Every number is an assumption (``docs/assumptions.md``, Structure temperature sensors).

The dish's differences depend on where the antenna has pointed (the Sun on the dish's face or
side; minutes of time constant): the thermal effect keeps, when sensors read it, the forcing
and the differences at every instant its state advanced to (``dish_log``); the sensors' lag
follows that history exactly under the effect's own assumption (between two instants the
difference relaxes towards the later instant's forcing). A reading first has the antenna
compute its pending integrations, so that the history reaches the time of the reading.

Without a thermal effect the structure is isothermal at the air temperature lagged by the
thermal effect's default bulk time constant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from controller.pointing.thermal import STRUCTURE_SENSORS

from .effects.thermal import (
    GRID_STEP_S,
    ThermalEffect,
    _dish_forcing,
    campaign_grid_s,
    interp_rows,
    ou_series,
    relax,
)

__all__ = ["SensorConfig", "StructureSensors", "thermal_truth"]

#: a sensor's part of the structure and which side of its difference it is on
_SIDES = {
    "dish_front": ("dish_fb", 0.5), "dish_back": ("dish_fb", -0.5),
    "dish_right": ("dish_lr", 0.5), "dish_left": ("dish_lr", -0.5),
    "yoke_front": ("yoke_fb", 0.5), "yoke_back": ("yoke_fb", -0.5),
    "yoke_right": ("yoke_lr", 0.5), "yoke_left": ("yoke_lr", -0.5),
    "pedestal_north": ("pedestal_n", 0.5), "pedestal_south": ("pedestal_n", -0.5),
    "pedestal_east": ("pedestal_e", 0.5), "pedestal_west": ("pedestal_e", -0.5),
}
#: the thermal effect's default bulk time constant (s), for a structure without one
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
    """A thermal effect's coefficients (its parameters ``params``) as the thermal terms of
    :mod:`controller.pointing.thermal` express them (arcsec per kelvin of the sensors'
    difference, indicated minus true): each pair's difference is its part's difference
    (without the sensors' imperfections), so TEDFB and TSDRL are the dish's arcsec per
    kelvin, TEYFB and TSYRL the yoke's, TNPNS, TWPEW and TTILT the pedestal's tilt per
    kelvin."""
    return {"TEDFB": params["dish_arcsec_per_k"],
            "TSDRL": params["dish_arcsec_per_k"] * params.get("dish_xel_factor", 1.0),
            "TEYFB": params["el_arcsec_per_k"], "TSYRL": params["xel_arcsec_per_k"],
            "TNPNS": params["tilt_arcsec_per_k"], "TWPEW": params["tilt_arcsec_per_k"],
            "TTILT": params["tilt_arcsec_per_k"]}


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
            parts = {"yoke_fb": thermal.gradient_fb_k, "yoke_lr": thermal.gradient_lr_k,
                     "pedestal_n": thermal.pedestal_n_k, "pedestal_e": thermal.pedestal_e_k}
            insolation = thermal._insolation
            thermal.dish_log = {}
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
        # the dish's differences through the sensors' lag (front-back, left-right)
        self._dish_state: tuple[float, float, float, float, float] | None = None
        #: a reading's noise is drawn from this key and the time of the reading, so that
        #: who reads when (a second client, a monitor) changes no other reading
        self._noise_key = int(rng.integers(2**63))

    def true_coefficients(self) -> dict[str, float]:
        """The thermal effect's coefficients as the thermal terms express them
        (:func:`thermal_truth`); empty without a thermal effect."""
        return {} if self.thermal is None else thermal_truth(self.thermal.p)

    # ------------------------------------------------------------------ the dish
    def _dish_lagged(self, t_s: float, az_rad: float, el_rad: float) -> tuple[float, float]:
        """The dish's front-back and left-right differences as lagged sensors see them at
        ``t_s`` (the antenna pointing at ``az_rad``, ``el_rad`` since the last instant)."""
        thermal = self.thermal
        if thermal is None or not thermal.dish_log:
            return 0.0, 0.0
        p = thermal.p
        tau_g, tau_s = p["dish_tau_s"], self.config.lag_s
        log = thermal.dish_log
        times = sorted(k for k in log if self._dish_state is None or k > self._dish_state[0])
        state = self._dish_state
        for t_k in times:
            if t_k > t_s:
                break
            f_fb, f_lr, g_fb, g_lr = log[t_k]
            if state is None:  # no past: the sensors start at the member's value
                state = (t_k, g_fb, g_lr, g_fb, g_lr)
                continue
            t0, g0_fb, g0_lr, s_fb, s_lr = state
            dt = t_k - t0
            state = (t_k, g_fb, g_lr, _lagged_step(s_fb, g0_fb, f_fb, dt, tau_g, tau_s),
                     _lagged_step(s_lr, g0_lr, f_lr, dt, tau_g, tau_s))
        self._dish_state = state
        if state is None:
            return 0.0, 0.0
        t0, g0_fb, g0_lr, s_fb, s_lr = state
        if t_s <= t0:
            return s_fb, s_lr
        # since the last instant: the forcing of where the antenna points now
        sun = [float(interp_rows(t_s, thermal.t_grid, row)) for row in thermal._sun_vec]
        flux = p["dish_gradient_k"] * float(interp_rows(t_s, thermal.t_grid,
                                                        thermal._insolation))
        f_fb, f_lr = _dish_forcing(flux, *sun, az_rad, el_rad, math)
        dt = t_s - t0
        return (_lagged_step(s_fb, g0_fb, f_fb, dt, tau_g, tau_s),
                _lagged_step(s_lr, g0_lr, f_lr, dt, tau_g, tau_s))

    # ------------------------------------------------------------------ readings
    def read(self, t_s: float, az_rad: float, el_rad: float) -> dict[str, float]:
        """Every sensor's reading (C) at ``t_s``, the antenna pointing at (``az_rad``,
        ``el_rad``) (true direction, radians): member temperature, lag, noise, resolution."""
        slow = interp_rows(float(t_s), self.t_grid, self._slow)
        dish = dict(zip(("dish_fb", "dish_lr"), self._dish_lagged(float(t_s), az_rad, el_rad),
                        strict=True))
        draws = np.random.default_rng((self._noise_key, round(float(t_s) * 1e6)))
        noise = draws.standard_normal(len(self.names)) * self.config.noise_k
        res = self.config.resolution_k
        out = {}
        for i, name in enumerate(self.names):
            part, side = _SIDES[name]
            value = float(slow[i]) + side * dish.get(part, 0.0) + float(noise[i])
            out[name] = round(round(value / res) * res, 9) if res > 0 else value
        return out
