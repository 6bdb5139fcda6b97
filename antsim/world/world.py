"""The simulated world: sky, weather, mount, effects, beam, receiver, in one simpy environment.

:class:`World` assembles the parts of a scenario and :class:`SimulatedAntenna` implements the
control protocol (:mod:`controller.protocol`) on top of them. The controller sees only what
the protocol returns: clock, encoder positions, total powers, weather sensors.

How an integration is computed (all vectorized over the samples of the integration):

1. encoder command at the antenna's clock time (trajectory + offset on the cable-wrap turn);
2. the slowly varying pointing errors (geometry, thermal, ...) at the integration's middle:
   the true beam direction ``B`` solves ``B + d(B) = encoder`` (fixed-point steps from the
   previous solution until they change nothing above 1e-5"; the error changes by far less
   than an arcsec per arcmin, so a few steps do);
3. per-sample errors (wind and servo jitter) on top;
4. each source near the beam at its true, refracted position; the beam's response per
   channel (squint included) times flux, gain, elevation efficiency and transmission;
5. the receiver adds system and sky temperature, gain fluctuations and radiometer noise.

Steps 2-5 wait until the integration's powers are first read (the control program reads a
scan's ten at its end): then every integration not yet computed is, those of one track
together, vectorized over their samples and over the integrations
(:meth:`World.sample_blocks`), with each component's random numbers drawn in the order
one-by-one integrations would draw them. When the reads come changes no value.

Other mounts and instruments: on an equatorial mount (``scenario.mount.kind``) the encoders,
the pointing errors and the per-sample jitter live in (hour angle, declination); the beam's
true direction is converted to azimuth and elevation before step 4 (sources, atmosphere and
the sky are always alt-az). ``beam.gain_harmonics`` makes the gain a function of hour angle
and declination (Crane 1981's Y00, Y10, Y11e, Y11o). A feed box turned by the controller
(:meth:`SimulatedAntenna.set_feed_angle`) sets :class:`PointingState` ``feed_angle_rad``. A
camera (:mod:`antsim.world.camera`) answers :meth:`SimulatedAntenna.measure_offset`.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable
from dataclasses import replace
from functools import lru_cache, partial
from typing import TYPE_CHECKING

import numpy as np
from astropy import units as u
from astropy.time import Time

from controller.astro.ephemeris import Ephemeris
from controller.astro.frames import ALTAZ, MountFrame, altaz_to_hadec
from controller.astro.sources import FixedSource
from controller.pointing.legacy import w_terms_marker
from controller.pointing.signs import sign_convention
from controller.protocol import (
    AntennaError,
    ChannelValues,
    Integration,
    OffsetReading,
    Trajectory,
    WeatherReading,
)
from controller.scans.gaincurve import HARMONIC_NAMES, harmonic_basis
from controller.units import ARCMIN_PER_RAD, RAD_PER_DEG

from .atmosphere import Atmosphere
from .beam import Beam, tangent_offsets
from .camera import Camera
from .effects import EFFECTS, GeometricEffect, PointingState
from .effects.base import BLOCK_FIELDS
from .mount import Mount
from .receiver import Receiver
from .sensors import StructureSensors
from .sky import Sky
from .weather import WeatherModel

if TYPE_CHECKING:
    from antsim.scenario import Scenario

__all__ = ["SimulatedAntenna", "World", "component_rng", "weather_model"]

#: the ephemeris extends this far beyond the campaign, for scans still running at its end (s)
EPHEMERIS_MARGIN_S = 3600.0
#: the fixed point of a block of integrations stops when no error changes by more (rad,
#: 1e-5 arcsec), or after this many steps
SOLVE_TOL_RAD = 5e-11
SOLVE_MAX_STEPS = 12
#: true source paths are tabulated per track at this step over this span (s)
TABLE_STEP_S = 2.0
TABLE_SPAN_S = 900.0


def component_rng(seed: int, component: str) -> np.random.Generator:
    """The run's generator for one component, derived from the seed and the component's
    name, so adding a component never changes another's random numbers."""
    key = zlib.crc32(component.encode("utf-8"))
    return np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(key,)))


def weather_model(scenario: Scenario, rng: np.random.Generator) -> WeatherModel:
    """The weather of a campaign of ``scenario`` with its random wander drawn from ``rng``."""
    return WeatherModel(scenario.weather, _epoch_hours(scenario.epoch_utc),
                        scenario.site.longitude_deg, scenario.duration_s + EPHEMERIS_MARGIN_S,
                        rng)


@lru_cache(maxsize=16)
def _epoch_hours(epoch_utc: str) -> float:
    """UTC hour of day of the epoch."""
    return (Time(epoch_utc, scale="utc").mjd % 1.0) * 24.0


class World:
    """Everything that is true in a simulation, built from a :class:`Scenario`."""

    #: the frame of the mount's axes (class default: alt-az, for partial worlds such as
    #: antsim.plan's member worlds, which are not built by ``__init__``)
    frame: MountFrame = ALTAZ
    camera = None
    sensors = None  # structure temperature sensors (antsim.world.sensors), where there are

    def __init__(self, scenario: Scenario, env, seed: int | None = None):
        self.scenario = scenario
        self.env = env
        self.seed = scenario.seed if seed is None else seed
        self.duration_s = scenario.duration_s
        site = scenario.site
        epoch = Time(scenario.epoch_utc, scale="utc")
        fixed = tuple(FixedSource(s.name, s.ra_deg, s.dec_deg, s.frame) for s in scenario.sources)
        self.ephemeris = Ephemeris(site, epoch, self.duration_s + EPHEMERIS_MARGIN_S, fixed)
        # the Sun from a day before the epoch: thermal lags need a day of spin-up
        self._sun = Ephemeris(site, epoch - 1.0 * _day(), self.duration_s + 86400.0
                              + EPHEMERIS_MARGIN_S, ())
        self.weather = weather_model(scenario, component_rng(self.seed, "weather"))
        self.frame = MountFrame(scenario.mount.kind, site.latitude_deg)
        camera = getattr(scenario, "camera", None)
        self.sky = Sky(self.ephemeris, scenario.sources, self.weather,
                       camera.frequency_ghz if camera is not None
                       else scenario.receiver.frequency_ghz)
        self.beam = Beam(scenario.beam)
        self.atmosphere = Atmosphere(scenario.atmosphere)
        self.receiver = Receiver(scenario.receiver, component_rng(self.seed, "receiver"))
        if self.frame.is_altaz:
            self.mount = Mount(env, scenario.mount)
        else:  # an equatorial mount parks at the zenith: hour angle 0, dec = latitude
            self.mount = Mount(env, scenario.mount, 0.0, site.latitude_deg)
        self.camera = None
        if camera is not None:
            self.camera = Camera(camera, component_rng(self.seed, "camera"))
        self._clock_error = None
        self.geometry = GeometricEffect(scenario.truth_model)
        self.effects = [self.geometry]
        for spec in scenario.effects:
            self.effects.append(EFFECTS[spec.name](**spec.params))
        for i, effect in enumerate(self.effects):
            effect.start(self, component_rng(self.seed, f"effect:{i}:{effect.name}"))
        self.slow_effects = [e for e in self.effects if not e.per_sample]
        self.fast_effects = [e for e in self.effects if e.per_sample]
        config = getattr(scenario, "structure_sensors", None)
        if config is not None:
            self.sensors = StructureSensors(config, self, component_rng(self.seed, "sensors"))
        self.antenna = SimulatedAntenna(self)

    # ------------------------------------------------------------------ services for effects
    def sun_el_rad(self, t_s) -> np.ndarray:
        """Elevation of the Sun (radians) at campaign time(s), valid from a day before."""
        return self._sun.sun_altaz_rad(np.asarray(t_s, dtype=float) + 86400.0)[1]

    sun_el_rad_periodic = sun_el_rad

    def sun_az_rad(self, t_s) -> np.ndarray:
        """Azimuth of the Sun (radians, N = 0) at campaign time(s), valid from a day before."""
        return self._sun.sun_altaz_rad(np.asarray(t_s, dtype=float) + 86400.0)[0]

    def air_temperature_c(self, t_s) -> np.ndarray:
        return self.weather.air_temperature_c(t_s)

    def set_clock_error(self, error_s) -> None:
        """Make the antenna's clock read ``t + error_s(t)``."""
        self._clock_error = error_s
        self.mount._clock = lambda t: t + error_s(t)

    # ------------------------------------------------------------------ truth for reports
    def truth(self) -> dict:
        """The injected truth in the ``truth.json`` schema of docs/contract.md."""
        model = self.scenario.truth_model
        truth = {
            "seed": int(self.seed),
            "model": model.name,
            **w_terms_marker(model.names),
            "sign_convention": sign_convention(model.names),
            "terms": {n: {"value_arcsec": float(v)} for n, v in model.as_dict().items()},
            "effects": [e.truth() for e in self.effects[1:]],
        }
        if self.scenario.mount.kind != "altaz":
            truth["mount"] = self.scenario.mount.kind
        harmonics = getattr(self.beam.config, "gain_harmonics", None)
        if harmonics is not None:  # the gain curve in K/Jy (controller.scans.gaincurve's form)
            base = self.beam.config.gain_k_per_jy
            relative = channel_gains(self.scenario)
            per_channel = {ch: base * relative.get(ch, 1.0)
                           for ch in self.receiver.names}

            def curve(gain: float) -> dict[str, float]:
                return {n: gain * float(c) for n, c in zip(HARMONIC_NAMES, harmonics,
                                                           strict=True)}

            # the recordings' AVG rows average the channels: their gain is the mean
            truth["gain_curve"] = {
                "form": "harmonics",
                "coefficients_k_per_jy": curve(float(np.mean(list(per_channel.values())))),
                "per_channel": {ch: curve(g) for ch, g in per_channel.items()}}
        if self.scenario.controller.tipping is not None:
            truth["zenith_opacity"] = float(self.atmosphere.tau0)
        if self.sensors is not None:
            truth["thermal_terms"] = self.sensors.true_coefficients()
        return truth

    def pointing_error_rad(self, state: PointingState) -> tuple[float, float]:
        """Sum of the slowly varying effects' errors (indicated - true) at ``state``."""
        d_az = d_el = 0.0
        for effect in self.slow_effects:
            a, e = effect.pointing_error(state)
            d_az += a
            d_el += e
        return d_az, d_el

    def solve_pointing(self, enc_az_rad, enc_el_rad, state: PointingState,
                       error_prev) -> tuple:
        """The slowly varying errors (d_az, d_el) at encoder position ``enc_*_rad``: solve
        B + d(B) = encoder by two fixed-point steps from ``error_prev``; ``state``'s
        ``az_rad``/``el_rad`` are left at the true beam direction B."""
        d_az, d_el = error_prev
        for _ in range(2):
            state.az_rad = enc_az_rad - d_az
            state.el_rad = enc_el_rad - d_el
            d_az, d_el = self.pointing_error_rad(state)
        state.az_rad = enc_az_rad - d_az
        state.el_rad = enc_el_rad - d_el
        return d_az, d_el

    def beam_direction(self, t, enc_a, enc_b, state: PointingState, error_prev) -> tuple:
        """The beam's true direction per sample on the mount's two axes (rad), from the
        encoder command per sample ``enc_a``/``enc_b``: the slow errors solved at the middle
        sample (``state`` is left there, see :meth:`solve_pointing`) and the fast ones per
        sample. Returns (beam_a, beam_b, slow errors)."""
        mid = t.size // 2
        d_a, d_b = self.solve_pointing(enc_a[mid], enc_b[mid], state, error_prev)
        beam_a = enc_a - d_a
        beam_b = enc_b - d_b
        for effect in self.fast_effects:
            j_a, j_b = effect.sample_error(t, state.el_rad)
            beam_a = beam_a - j_a
            beam_b = beam_b - j_b
        return beam_a, beam_b, (d_a, d_b)

    def sample_blocks(self, t, enc_az, enc_el, states: list[PointingState], paths,
                      error_prev, channels) -> tuple[np.ndarray, tuple]:
        """Total-power samples (K) of K equally long integrations, in time order: steps 2-5
        of the module docstring. ``t`` (K, n) sample times (s), ``enc_az``/``enc_el`` (K, n)
        the encoder command per sample (rad), one state per integration (at its middle),
        ``paths`` ``(source index, az, el)`` true paths (K, n) per source (rad),
        ``error_prev`` the previous integration's slow errors (the fixed point's start).
        Returns samples (K, n, channels) and the last integration's slow errors.
        The slow errors are solved for the K middles together (:meth:`solve_pointing_block`,
        converged where one call's two steps stop short), everything after that (the fast
        effects, the beam, the receiver) once for the K, with the random numbers of K calls
        in the same order: the values of K calls, with numpy's per-call cost paid once.
        With a member axis (``antsim.plan``): ``enc_*`` and the paths (K, n, 1), effects and
        receiver with member-stacked realisations, ``error_prev`` (members,) arrays; samples
        are then (K, n, members, channels) and the slow errors (members,) arrays."""
        mid = t.shape[1] // 2
        enc_az_mid, enc_el_mid = enc_az[:, mid], enc_el[:, mid]  # (K,), or (K, 1): members
        block = PointingState(**{f: np.array([getattr(s, f) for s in states]
                                             ).reshape(enc_az_mid.shape)
                                 for f in BLOCK_FIELDS})
        d_az, d_el = self.solve_pointing_block(enc_az_mid, enc_el_mid, block, error_prev)
        beam_az = enc_az - d_az[:, None]
        beam_el = enc_el - d_el[:, None]
        for f in BLOCK_FIELDS:  # one value per integration, against (K, n) samples
            setattr(block, f, getattr(block, f)[:, None])
        for effect in self.fast_effects:
            j_a, j_b = effect.sample_error(t, block.el_rad)
            beam_az = beam_az - j_a
            beam_el = beam_el - j_b
        last = (d_az[-1], d_el[-1]) if d_az.ndim > 1 else (float(d_az[-1]), float(d_el[-1]))
        return self._received(t, beam_az, beam_el, block, paths, channels), last

    def solve_pointing_block(self, enc_az_rad, enc_el_rad, state: PointingState,
                             error_prev) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`solve_pointing` at K instants (arrays (K,)), all from ``error_prev``:
        fixed-point steps until no error changes by more than ``SOLVE_TOL_RAD`` (the
        error left is smaller still: each step shrinks it by the errors' slope, a few
        hundredths at most). ``state`` is left at the true directions B. Returns the
        errors (d_az, d_el), each (K,); with ``enc_*`` (K, 1) and ``error_prev`` (members,)
        arrays, each (K, members)."""
        shape = np.broadcast_shapes(enc_az_rad.shape, np.shape(error_prev[0]))
        d_az = np.broadcast_to(np.asarray(error_prev[0], dtype=float), shape)
        d_el = np.broadcast_to(np.asarray(error_prev[1], dtype=float), shape)
        for _ in range(SOLVE_MAX_STEPS):
            state.az_rad = enc_az_rad - d_az
            state.el_rad = enc_el_rad - d_el
            new_az = new_el = 0.0
            for effect in self.slow_effects:
                a, e = effect.block_error(state)
                new_az = new_az + a
                new_el = new_el + e
            change = max(float(np.max(np.abs(new_az - d_az))),
                         float(np.max(np.abs(new_el - d_el))))
            d_az = np.broadcast_to(new_az, shape)
            d_el = np.broadcast_to(new_el, shape)
            if change < SOLVE_TOL_RAD:
                break
        state.az_rad = enc_az_rad - d_az
        state.el_rad = enc_el_rad - d_el
        return d_az, d_el

    def _received(self, t, beam_az, beam_el, state: PointingState, paths,
                  channels) -> np.ndarray:
        """Steps 4-5 of the module docstring: samples (..., channels) of the receiver for
        the beam's true direction per sample on the mount's axes (rad)."""
        if not self.frame.is_altaz:  # (HA, Dec) of the beam -> azimuth and elevation
            beam_az, beam_el = self.frame.to_altaz(beam_az, beam_el)

        t_src = np.zeros((*np.shape(beam_el), len(channels)))
        sky = self.sky
        relative = channel_gains(self.scenario)
        for i, src_az, src_el in paths:
            if self.frame.is_altaz:
                d_xel = ((src_az - beam_az + math.pi) % (2 * math.pi) - math.pi) * np.cos(src_el)
                d_el_src = src_el - beam_el
            else:  # both scans cross azimuth and elevation: exact offsets (tangent_offsets)
                d_xel, d_el_src = tangent_offsets(src_az, src_el, beam_az, beam_el)
            scale = (sky.flux_jy[i] * self.beam.config.gain_k_per_jy
                     * self.efficiency(src_az, src_el) * self.atmosphere.transmission(src_el))
            for c, channel in enumerate(channels):
                channel_scale = scale * relative.get(channel, 1.0)
                off_x = off_e = 0.0
                for effect in self.slow_effects:
                    ox, oe = effect.beam_offset(channel, state)
                    off_x += ox
                    off_e += oe
                t_src[..., c] += channel_scale * self.beam.response(
                    (d_xel - off_x) * ARCMIN_PER_RAD, (d_el_src - off_e) * ARCMIN_PER_RAD,
                    float(sky.size_arcmin[i]))
        t_in = t_src + self.atmosphere.emission_k(beam_el)[..., None]
        return self.receiver.sample(t, t_in)

    def efficiency(self, az_rad, el_rad) -> np.ndarray:
        """Relative gain towards (az, el) (rad): the beam's elevation curve, or with
        ``beam.gain_harmonics`` the harmonic gain of hour angle and declination."""
        harmonics = getattr(self.beam.config, "gain_harmonics", None)
        if harmonics is None:
            return self.beam.efficiency(el_rad)
        ha, dec = altaz_to_hadec(az_rad, el_rad, self.frame.latitude_rad)
        return harmonic_basis(ha, dec) @ np.asarray(harmonics, dtype=float)


def channel_gains(scenario) -> dict[str, float]:
    """Each channel's own peak gain relative to the beam's, for the channels that set one."""
    return {c.name: c.gain_k_per_jy / scenario.beam.gain_k_per_jy
            for c in scenario.receiver.channels if c.gain_k_per_jy is not None}


def _day():
    return u.day


class SimulatedAntenna:
    """The protocol of :mod:`controller.protocol`, implemented by the simulated world."""

    def __init__(self, world: World):
        self.world = world
        self.env = world.env
        self.mount = world.mount
        self.channels = world.receiver.names
        self._targets: list[int] = []
        self._tables: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._error_prev = (0.0, 0.0)
        self._pending: list[_Pending] = []
        self._feed_angle_deg = 0.0
        self.slews = 0
        #: called with each integration's deterministic inputs (see :meth:`_integrate`)
        self.recorder: Callable[..., None] | None = None

    # ------------------------------------------------------------------ readings
    def clock_s(self) -> float:
        return self.mount.clock()

    def weather(self) -> WeatherReading:
        return self.world.weather.reading(self.env.now)

    def encoder_deg(self) -> tuple[float, float]:
        return self.mount.current_deg()

    @property
    def structure_sensors(self) -> tuple[str, ...]:
        """The structure temperature sensors' names (empty: none)."""
        sensors = self.world.sensors
        return () if sensors is None else sensors.names

    def structure_temperatures(self) -> dict[str, float]:
        """Every structure temperature sensor's reading now (C): the integrations not yet
        computed are computed first (the dish's temperatures follow where it pointed)."""
        sensors = self.world.sensors
        if sensors is None:
            raise AntennaError("this antenna has no structure temperature sensors (the "
                               "scenario has no [structure_sensors] table)")
        self.flush()
        az_deg, el_deg = self.world.frame.to_altaz_deg(*self.mount.current_deg())
        return sensors.read(float(self.env.now), az_deg * RAD_PER_DEG, el_deg * RAD_PER_DEG)

    # ------------------------------------------------------------------ commands
    def track(self, trajectory: Trajectory, label: str = ""):
        return self.env.process(self._track(trajectory))

    def _track(self, trajectory: Trajectory):
        duration = yield self.env.process(self.mount.track(trajectory))
        self.slews += 1
        az_deg, el_deg = self.world.frame.to_altaz_deg(*self.mount.current_deg())
        self._targets = self.world.sky.nearby(az_deg * RAD_PER_DEG, el_deg * RAD_PER_DEG,
                                              self.env.now)
        self._tables = {}
        return duration

    def _source_path(self, index: int, t: np.ndarray,
                     tables: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
        """True observed position of source ``index`` at sample times ``t``, from the
        path ``tables`` of a track (default: the current one's).

        Tabulated every ``TABLE_STEP_S`` over ``TABLE_SPAN_S`` from first use (one
        vectorized ephemeris call per track; linear interpolation error < 0.01" below 85 deg
        elevation), with the refraction of the weather at tabulation time (it changes by
        far less than 0.01" in minutes).
        """
        if tables is None:
            tables = self._tables
        table = tables.get(index)
        if table is None or t[0] < table[0][0] or t[-1] > table[0][-1]:
            limit = self.world.duration_s + EPHEMERIS_MARGIN_S
            grid = np.arange(t[0], min(t[0] + TABLE_SPAN_S, limit), TABLE_STEP_S)
            if grid.size < 2 or grid[-1] < t[-1]:
                grid = np.linspace(t[0], t[-1] + TABLE_STEP_S, 4)
            az, el = self.world.sky.observed_altaz_rad(index, grid, t_weather_s=float(t[0]))
            table = (grid, np.unwrap(az), el)
            tables[index] = table
        grid, az, el = table
        return np.interp(t, grid, az), np.interp(t, grid, el)

    def set_offset(self, d_az_deg: float, d_el_deg: float):
        if not self.mount.on_track:
            raise AntennaError("set_offset needs a trajectory: call track() first")
        return self.env.process(self.mount.set_offset(d_az_deg, d_el_deg))

    def wait(self, seconds: float):
        return self.env.timeout(seconds)

    def set_feed_angle(self, angle_deg: float):
        """Turn the feed box to ``angle_deg`` (the mount's ``feed_speed_deg_s``, then its
        settle time); the pointing effects see it as ``PointingState.feed_angle_rad``."""
        angle = float(angle_deg)
        if not math.isfinite(angle):
            raise AntennaError(f"feed angle must be a finite number of degrees, not {angle_deg!r}")
        return self.env.process(self._turn_feed(angle))

    def feed_turn_s(self, angle_deg: float) -> float:
        """Time to turn the feed box to ``angle_deg`` and settle (s), without turning."""
        cfg = self.world.scenario.mount
        speed = getattr(cfg, "feed_speed_deg_s", 2.0)
        return abs(angle_deg - self._feed_angle_deg) / speed + cfg.settle_s

    def _turn_feed(self, angle_deg: float):
        duration = self.feed_turn_s(angle_deg)
        yield self.env.timeout(duration)
        self._feed_angle_deg = angle_deg
        return duration

    def feed_angle_deg(self) -> float:
        return self._feed_angle_deg

    def measure_offset(self, seconds: float):
        """Expose the camera for ``seconds`` while tracking: an :class:`OffsetReading`."""
        if self.world.camera is None:
            raise AntennaError("this antenna has no camera (scenario has no [camera] table)")
        if not seconds > 0:
            raise AntennaError(f"exposure time must be positive, got {seconds!r} s")
        if not self.mount.on_track:
            raise AntennaError("measure_offset needs a trajectory: call track() first")
        return self.env.process(self._measure(float(seconds)))

    def _commanded_samples(self, t_start: float, seconds: float):
        """Sample times of an exposure starting at ``t_start`` (s), the control clock's
        reading of them, and the mount's commanded axis angles at those readings (deg)."""
        t = self.world.receiver.sample_times(t_start, seconds)
        t_clock = t + self.world._clock_error(t) if self.world._clock_error else t
        return (t, t_clock, *self.mount.commanded_deg(t_clock))

    def _measure(self, seconds: float):
        world = self.world
        t_start = self.env.now
        yield self.env.timeout(seconds)
        self.flush()  # the integrations before it carry the slow errors' fixed point
        t, t_clock, enc_lon_deg, enc_lat_deg = self._commanded_samples(t_start, seconds)
        enc_lon = enc_lon_deg * RAD_PER_DEG
        enc_lat = enc_lat_deg * RAD_PER_DEG
        mid = t.size // 2
        state = PointingState(t_s=float(t[mid]), az_rad=0.0, el_rad=0.0,
                              approach_az=self.mount.approach[0],
                              approach_el=self.mount.approach[1],
                              feed_angle_rad=math.radians(self._feed_angle_deg))
        paths = [(i, *self._source_path(i, t)) for i in self._targets]
        (xel, el, found), self._error_prev = world.camera.measure(
            world.beam_direction, world.frame, t, enc_lon, enc_lat, state, paths,
            self._error_prev)
        return OffsetReading(
            t_start_s=float(t_start + (t_clock[0] - t[0])),
            t_end_s=float(t_start + seconds + (t_clock[-1] - t[-1])),
            xel_arcsec=xel, el_arcsec=el, found=found,
            enc_az_deg=float(np.mean(enc_lon_deg)), enc_el_deg=float(np.mean(enc_lat_deg)),
            weather=world.weather.reading(float(t[mid])),
        )

    def integrate(self, seconds: float):
        if not seconds > 0:
            raise AntennaError(f"integration time must be positive, got {seconds!r} s")
        return self.env.process(self._integrate(float(seconds)))

    # ------------------------------------------------------------------ the physics
    def _integrate(self, seconds: float):
        world = self.world
        t_start = self.env.now
        yield self.env.timeout(seconds)
        t, t_clock, enc_az_deg, enc_el_deg = self._commanded_samples(t_start, seconds)
        limits = world.scenario.mount.el
        enc_el_deg = np.clip(enc_el_deg, limits.min_deg, limits.max_deg)
        enc_az = enc_az_deg * RAD_PER_DEG
        enc_el = enc_el_deg * RAD_PER_DEG
        mid = t.size // 2
        if t.size > 1:
            span = t[-1] - t[0]
            rates = ((enc_az[-1] - enc_az[0]) / span, (enc_el[-1] - enc_el[0]) / span)
        else:  # one sample: the command's rate over that sample (not zero while tracking)
            half = 0.5 * seconds
            a_deg, e_deg = self.mount.commanded_deg(t_clock[0] + np.array([-half, half]))
            rates = ((a_deg[1] - a_deg[0]) * RAD_PER_DEG / seconds,
                     (e_deg[1] - e_deg[0]) * RAD_PER_DEG / seconds)

        state = PointingState(t_s=float(t[mid]), az_rad=0.0, el_rad=0.0,
                              az_rate_rad_s=rates[0], el_rate_rad_s=rates[1],
                              approach_az=self.mount.approach[0],
                              approach_el=self.mount.approach[1],
                              feed_angle_rad=math.radians(self._feed_angle_deg))
        pending = _Pending(self, t, enc_az, enc_el, state, self._targets, self._tables)
        if self.recorder is not None:  # the shared schedule of antsim.plan's ensembles
            pending.paths = [(i, *self._source_path(i, t)) for i in self._targets]
            self.recorder(t=t, enc_az=enc_az, enc_el=enc_el, state=replace(state),
                          paths=pending.paths, seconds=seconds)
        self._pending.append(pending)
        return Integration(
            t_start_s=float(t_start + (t_clock[0] - t[0])),
            t_end_s=float(t_start + seconds + (t_clock[-1] - t[-1])),
            power_k=ChannelValues(partial(pending.read, 0)),
            std_k=ChannelValues(partial(pending.read, 1)),
            enc_az_deg=math.fsum(enc_az_deg.tolist()) / t.size,
            enc_el_deg=math.fsum(enc_el_deg.tolist()) / t.size,
            weather=world.weather.reading(float(t[mid])),
            n_samples=int(t.size),
        )

    def flush(self) -> None:
        """Compute the powers of every integration not yet read, oldest first.

        An integration's samples are computed when its powers are first read (the control
        program reads a scan's ten at its end), so that consecutive integrations of one
        track and one length are computed together (:meth:`World.sample_blocks`); the
        values do not depend on when that happens."""
        pending, self._pending = self._pending, []
        start = 0
        while start < len(pending):
            first = pending[start]
            stop = start + 1
            while (stop < len(pending) and pending[stop].t.size == first.t.size
                   and pending[stop].tables is first.tables):
                stop += 1
            self._compute(pending[start:stop])
            start = stop

    def _compute(self, block: list[_Pending]) -> None:
        """The samples of ``block``: integrations of one track, equally long, in order."""
        t = np.stack([p.t for p in block])
        paths = self._block_paths(block, t)
        samples, self._error_prev = self.world.sample_blocks(
            t, np.stack([p.enc_az for p in block]), np.stack([p.enc_el for p in block]),
            [p.state for p in block], paths, self._error_prev, self.channels)
        power = samples.mean(axis=1)
        std = samples.std(axis=1, ddof=1) if t.shape[1] > 1 else np.zeros_like(power)
        for k, p in enumerate(block):
            p.values = ({ch: float(power[k, c]) for c, ch in enumerate(self.channels)},
                        {ch: float(std[k, c]) for c, ch in enumerate(self.channels)})

    def _block_paths(self, block: list[_Pending], t: np.ndarray) -> list:
        """The sources' true paths (K, n) at the block's sample times ``t`` (K, n): the
        recorded ones, else from the track's tables (one lookup for the block where the
        table covers it; else integration by integration, as when each came)."""
        if block[0].paths is not None:
            return [(i, np.stack([p.paths[j][1] for p in block]),
                     np.stack([p.paths[j][2] for p in block]))
                    for j, (i, _, _) in enumerate(block[0].paths)]
        tables = block[0].tables
        out = []
        for i in block[0].targets:
            first = self._source_path(i, t[0], tables)  # builds the table as it would
            grid, az, el = tables[i]
            if grid[0] <= t[0, 0] and t[-1, -1] <= grid[-1]:
                out.append((i, np.interp(t, grid, az), np.interp(t, grid, el)))
            else:
                rows = [first, *(self._source_path(i, row, tables) for row in t[1:])]
                out.append((i, np.stack([r[0] for r in rows]), np.stack([r[1] for r in rows])))
        return out


class _Pending:
    """An integration whose samples are not computed yet: what they depend on, fixed when
    it ended (sample times, encoder command, state, the sources near the beam and the
    track's path tables), and its (power, std) per channel once computed."""

    __slots__ = ("antenna", "enc_az", "enc_el", "paths", "state", "t", "tables", "targets",
                 "values")

    def __init__(self, antenna: SimulatedAntenna, t, enc_az, enc_el, state, targets, tables):
        self.antenna = antenna
        self.t = t
        self.enc_az = enc_az
        self.enc_el = enc_el
        self.state = state
        self.targets = targets
        self.tables = tables
        self.paths: list | None = None
        self.values: tuple[dict, dict] | None = None

    def read(self, which: int) -> dict[str, float]:
        """Power (``which`` 0) or std (1) per channel (K), computed when first read."""
        if self.values is None:
            self.antenna.flush()
            if self.values is None:  # its block raised when first read
                raise RuntimeError("this integration's samples could not be computed "
                                   "(see the error raised when they were first read)")
        return self.values[which]
