"""The sensors of `antsim serve`: what the simulated antenna reports, with KATCP's sampling
strategies (the table in docs/katcp.md). Timestamps are the simulated UTC (Unix seconds).

Structure temperature sensors are ``structure.NAME`` (degC), where the scenario has them
(``[structure_sensors]``): each holds the latest reading, taken when a client asks for the
temperatures (``?structure-temperatures``), as a logger the control system polls; updating
them reads no thermometer (:func:`set_structure`).
"""

from __future__ import annotations

import enum

import aiokatcp

__all__ = ["MountMode", "add_sensors", "set_structure", "update_sensors"]


class MountMode(enum.Enum):
    """What the mount is doing (the ``mount.mode`` sensor)."""

    PARKED = 0
    SLEWING = 1
    MOVING = 2  # to a new offset or feed angle, and settling
    TRACKING = 3


def add_sensors(sensors: aiokatcp.SensorSet, altaz: bool,
                structure: tuple[str, ...] = ()) -> None:
    """The antenna's sensors (values set by :func:`update_sensors`), and one per structure
    temperature sensor (set by :func:`set_structure`)."""
    first, second = (("azimuth (North = 0, East = 90)", "elevation") if altaz
                     else ("hour angle (positive West)", "declination"))
    S = aiokatcp.Sensor
    for sensor in (
        S(float, "clock.seconds", "antenna clock: seconds since the scenario epoch", "s"),
        S(str, "clock.utc", "antenna clock as UTC (ISO 8601)"),
        S(float, "encoder.az", f"encoder of the first axis: {first}", "deg"),
        S(float, "encoder.el", f"encoder of the second axis: {second}", "deg"),
        S(float, "offset.az", "offset of the first axis from the program track", "deg"),
        S(float, "offset.el", "offset of the second axis from the program track", "deg"),
        S(MountMode, "mount.mode", "parked, slewing, moving (to an offset or feed angle, "
          "and settling) or tracking"),
        S(bool, "mount.on-target", "tracking the program track, settled, within the "
          "mount's limits"),
        S(float, "feed.angle", "feed box angle", "deg"),
        S(float, "weather.air-temperature", "air temperature", "degC"),
        S(float, "weather.pressure", "air pressure", "hPa"),
        S(float, "weather.relative-humidity", "relative humidity (0..1)"),
        S(float, "weather.wind-speed", "wind speed", "m/s"),
        S(str, "control.client", "address of the client that controls the antenna "
          "(empty: none)"),
        *(S(float, f"structure.{name}", f"structure temperature {name} (latest reading)",
            "degC") for name in structure),
    ):
        sensors.add(sensor)


def set_structure(sensors: aiokatcp.SensorSet, reading: dict[str, float], stamp: float) -> None:
    """The ``structure.NAME`` sensors to a reading of the structure temperatures (C) taken
    at ``stamp`` (simulated UTC, Unix seconds)."""
    for name, value in reading.items():
        sensors[f"structure.{name}"].set_value(float(value), timestamp=stamp)


def update_sensors(sensors: aiokatcp.SensorSet, world, busy: str | None, controller: str,
                   utc: str, stamp: float) -> None:
    """Set the sensors to ``world``'s present state; ``busy`` is the command in progress
    (``track``: slewing; ``offset``, ``feed-angle``: moving), ``controller`` the
    controlling client's address, ``utc`` and ``stamp`` the antenna clock's reading."""
    antenna, mount = world.antenna, world.mount
    az, el = antenna.encoder_deg()
    w = antenna.weather()
    if busy == "track":
        mode = MountMode.SLEWING
    elif busy in ("offset", "feed-angle"):
        mode = MountMode.MOVING
    elif mount.on_track:
        mode = MountMode.TRACKING
    else:
        mode = MountMode.PARKED
    limits = world.scenario.mount
    # a track that leaves the limits (a table that sets below them) is not on target
    inside = (limits.az.min_deg <= az <= limits.az.max_deg
              and limits.el.min_deg <= el <= limits.el.max_deg)
    values = {
        "clock.seconds": float(antenna.clock_s()), "clock.utc": utc,
        "encoder.az": az, "encoder.el": el,
        "offset.az": mount.offset_deg[0], "offset.el": mount.offset_deg[1],
        "mount.mode": mode, "mount.on-target": mode is MountMode.TRACKING and inside,
        "feed.angle": antenna.feed_angle_deg(),
        "weather.air-temperature": w.temperature_c, "weather.pressure": w.pressure_hpa,
        "weather.relative-humidity": w.relative_humidity,
        "weather.wind-speed": w.wind_speed_m_s,
        "control.client": controller,
    }
    for name, value in values.items():
        sensors[name].set_value(value, timestamp=stamp)
