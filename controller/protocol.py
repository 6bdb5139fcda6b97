"""The narrow protocol through which the control program drives an antenna.

Commands: track a trajectory (the control program computes where the encoders must point,
pointing model and refraction included), set an offset from it, integrate for N seconds.
Readings: the antenna's clock, commanded and encoder positions, total power per
polarization with the standard deviation of its samples, and weather sensors. Nothing here
exposes the truth of a simulation: a real antenna could implement this interface.

All commands return simpy events; the control program is a simpy process that yields them.
Angles are degrees (encoder frame: azimuth North-based, possibly beyond 0..360 on the cable
wrap); times are seconds on the antenna's clock since the campaign epoch. On an equatorial
mount the encoder frame is (hour angle, declination): "azimuth" and "elevation" below then
read hour angle (positive West) and declination, and cross-axis steps are cross-declination.

Optional capabilities, each its own protocol: :class:`CameraAntenna` (a TV camera boresighted
on the optical axis measures a star's offset directly, as BIMA's optical pointing did),
:class:`FeedAntenna` (a feed box that the controller turns to a feed angle, as the 45-ft's in
Fomalont 1973) and :class:`StructureAntenna` (thermometers on the structure, which the 1990
antenna did not have).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = [
    "Antenna",
    "AntennaError",
    "CameraAntenna",
    "ChannelValues",
    "FeedAntenna",
    "Integration",
    "OffsetReading",
    "StructureAntenna",
    "Trajectory",
    "WeatherReading",
]

#: Encoder trajectory: antenna-clock seconds (array) -> (azimuth deg, elevation deg) arrays,
#: azimuth North-based in [0, 360); the antenna chooses the cable-wrap turn itself.
Trajectory = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


class AntennaError(RuntimeError):
    """A command the antenna cannot carry out (target below the elevation limit, ...)."""


@dataclass(frozen=True)
class WeatherReading:
    """Weather sensors: air temperature (C), pressure (hPa), relative humidity (0..1),
    wind speed (m/s)."""

    temperature_c: float
    pressure_hpa: float
    relative_humidity: float
    wind_speed_m_s: float


class ChannelValues(Mapping):
    """Values per channel (e.g. power or std in K) that an antenna computes or fetches when
    first read: the mapping ``load()`` returns, asked for on every access (``load`` keeps
    what it has). Copies and pickles as that plain dict."""

    __slots__ = ("_load",)

    def __init__(self, load: Callable[[], Mapping[str, float]]):
        self._load = load

    def __getitem__(self, channel: str) -> float:
        return self._load()[channel]

    def __iter__(self):
        return iter(self._load())

    def __len__(self) -> int:
        return len(self._load())

    def __repr__(self) -> str:
        return repr(self._load())

    def __reduce__(self):
        return dict, (dict(self._load()),)


@dataclass(frozen=True)
class Integration:
    """One total-power integration, as the backend reports it.

    ``power_k`` and ``std_k`` map channel name (``"XR"``, ``"XL"``) to the mean total power
    and the standard deviation of the samples within the integration (kelvin); an antenna
    may compute them when they are first read (:class:`ChannelValues`; the simulated one
    does, and so does an antenna over the wire).
    ``enc_az_deg``/``enc_el_deg`` are the mean encoder readings during the integration.
    """

    t_start_s: float
    t_end_s: float
    power_k: Mapping[str, float]
    std_k: Mapping[str, float]
    enc_az_deg: float
    enc_el_deg: float
    weather: WeatherReading
    n_samples: int = 0
    extra: dict[str, float] = field(default_factory=dict)

    @property
    def t_mid_s(self) -> float:
        return 0.5 * (self.t_start_s + self.t_end_s)


@runtime_checkable
class Antenna(Protocol):
    """What the control program may ask of an antenna."""

    #: channel names of the receiver, e.g. ("XR", "XL")
    channels: tuple[str, ...]

    def clock_s(self) -> float:
        """The antenna's clock: seconds since the campaign epoch."""

    def track(self, trajectory: Trajectory, label: str = ""):
        """Slew to and track ``trajectory``; the event fires once on track and settled, its
        value the time the slew and settling took (s).

        The offset is reset to zero. The event fails with :class:`AntennaError` if the
        trajectory is outside the mount's limits at arrival.
        """

    def set_offset(self, d_az_deg: float, d_el_deg: float):
        """Offset the encoder command from the trajectory (degrees of encoder angle);
        the event fires once settled, its value the time the move and settling took (s):
        read it with ``float()`` (an antenna over a network may give it when first read,
        :class:`controller.wire.LaterSeconds`)."""

    def integrate(self, seconds: float):
        """Integrate total power for ``seconds``; the event's value is an :class:`Integration`
        (whose numbers an antenna over a network may give when first read,
        :class:`controller.wire.LaterIntegration`)."""

    def wait(self, seconds: float):
        """Let time pass (the antenna keeps tracking)."""

    def weather(self) -> WeatherReading:
        """Current weather-sensor readings."""

    def encoder_deg(self) -> tuple[float, float]:
        """Current encoder azimuth and elevation (degrees)."""


@dataclass(frozen=True)
class OffsetReading:
    """A camera measurement: the star's offset from the optical axis, averaged over the
    exposure (arcsec; ``xel`` cross-axis, ``el`` along the second axis; positive: the star
    lies at larger azimuth/elevation than the axis, i.e. the correction to apply).
    ``found`` is false when no star was in the field (the offsets are then NaN)."""

    t_start_s: float
    t_end_s: float
    xel_arcsec: float
    el_arcsec: float
    found: bool
    enc_az_deg: float
    enc_el_deg: float
    weather: WeatherReading

    @property
    def t_mid_s(self) -> float:
        return 0.5 * (self.t_start_s + self.t_end_s)


@runtime_checkable
class CameraAntenna(Antenna, Protocol):
    """An antenna with a TV camera on its optical axis (optical pointing)."""

    def measure_offset(self, seconds: float):
        """Expose for ``seconds`` while tracking; the event's value is an
        :class:`OffsetReading` of the brightest star in the field."""


@runtime_checkable
class FeedAntenna(Antenna, Protocol):
    """An antenna whose feed box the controller turns (feed angle, degrees)."""

    def set_feed_angle(self, angle_deg: float):
        """Turn the feed box to ``angle_deg``; the event fires once it is settled."""

    def feed_angle_deg(self) -> float:
        """The feed angle now (degrees)."""


@runtime_checkable
class StructureAntenna(Antenna, Protocol):
    """An antenna with structure temperature sensors (thermometers on the dish, the yoke,
    the pedestal: :data:`controller.pointing.thermal.STRUCTURE_SENSORS`)."""

    #: the sensors' names, in the order the antenna lists them (empty: none)
    structure_sensors: tuple[str, ...]

    def structure_temperatures(self) -> Mapping[str, float]:
        """Every sensor's reading now (C), by name."""
