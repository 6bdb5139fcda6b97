"""The simulated antenna of a scenario as a KATCP device (aiokatcp).

Requests mirror :mod:`controller.protocol` (the request list with units and sign
conventions is ``docs/katcp.md``): commands (``?track``, ``?track-append``, ``?offset``,
``?integrate``, ``?powers``, ``?wait``, ``?feed-angle ANGLE``, ``?camera``, ``?release``)
and readings (``?clock``, ``?encoder``, ``?weather``, ``?channels``, ``?antenna``,
``?feed-angle``, ``?structure-temperatures``). Every command's reply starts with the
antenna's clock after it. Sensors report the encoders, the offsets, the mount's mode, the
clock, the weather, the feed angle and who controls the antenna, with the sampling
strategies of aiokatcp (``?sensor-sampling``); their timestamps are the simulated UTC.

One client controls the antenna: the first to send a command, until it disconnects or sends
``?release``; the others may read and watch sensors, and get a failure reply naming the
controlling client when they command. A command's bad argument gets a failure reply naming
the argument; the connection stays usable. The truth of the simulation is never sent.
"""

# no "from __future__ import annotations": aiokatcp reads the handlers' annotations
import asyncio
import functools
import json
import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import aiokatcp
import simpy

from controller.astro.earth import UtcLabeller
from controller.protocol import AntennaError

from .._version import __version__
from ..world.world import EPHEMERIS_MARGIN_S, World
from .arguments import ArgumentError, at_most, integer, number, numbers, quoted
from .clock import ClockSpec, OutOfTimeError, make_clock
from .programtrack import ProgramTrack, TableError
from .sensors import add_sensors, set_structure, update_sensors

if TYPE_CHECKING:
    from ..scenario import Scenario

__all__ = ["AntennaDevice", "RequestLog"]

logger = logging.getLogger(__name__)


class RequestLog:
    """``requests.jsonl``: one JSON line per request served, flushed as it is written."""

    def __init__(self, path: Path):
        self.path = path
        self._file = path.open("w", encoding="utf-8")

    def write(self, entry: dict) -> None:
        self._file.write(json.dumps(entry) + "\n")
        self._file.flush()

    def close(self) -> None:
        self._file.close()


def _request(kind: str):
    """A request handler: ``kind`` "command" (the controlling client only), "reading", or
    "command-with-args" (a reading without arguments, a command with them)."""

    def wrap(func: Callable):
        @functools.wraps(func)
        async def handler(self: "AntennaDevice", ctx: aiokatcp.RequestContext, *args: bytes):
            return await self._serve(ctx, kind, func, args)

        return handler

    return wrap


class AntennaDevice(aiokatcp.DeviceServer):
    """The KATCP device: a :class:`~antsim.world.world.World` driven by requests."""

    VERSION = "antsim-antenna-1.0"
    BUILD_STATE = f"antsim-{__version__}"

    def __init__(self, host: str, port: int, scenario: "Scenario", seed: int | None,
                 clock: ClockSpec, log: RequestLog | None = None,
                 say: Callable[[str], None] = lambda text: None):
        super().__init__(host, port)
        from astropy.time import Time

        self.scenario = scenario
        self.env = simpy.Environment()
        self.world = World(scenario, self.env, seed)
        self.seed = self.world.seed
        self.antenna = self.world.antenna
        self.end_s = scenario.duration_s + EPHEMERIS_MARGIN_S
        self.clock = make_clock(clock, self.env, self.end_s)
        self.log = log
        self.say = say
        self.requests = 0
        #: wall time spent in the handlers of this module's requests (s)
        self.serving_s = 0.0
        self.controller: aiokatcp.connection.Connection | None = None
        self._epoch_unix = float(Time(scenario.epoch_utc, scale="utc").unix)
        self._utc = UtcLabeller(scenario.epoch_utc, self.end_s)
        self._track: ProgramTrack | None = None
        #: the command being carried out (the mount's mode sensor shows it)
        self._busy: str | None = None
        self._in_order = asyncio.Lock()
        self._deferred: dict[int, object] = {}
        self._next_id = 1
        #: whether a client has asked for sensor updates (?sensor-sampling): until then
        #: sensors are brought up to date only when read, not after every command
        self._watched = False
        self._sensors_stale = True
        add_sensors(self.sensors, self.world.frame.is_altaz, self.antenna.structure_sensors)
        self.refresh_sensors()

    # ------------------------------------------------------------------ sensors
    def refresh_sensors(self) -> None:
        """Set every sensor to the world's present state."""
        clock_s = float(self.antenna.clock_s())
        controller = "" if self.controller is None else str(self.controller.address)
        update_sensors(self.sensors, self.world, self._busy, controller, self._utc(clock_s),
                       self._epoch_unix + clock_s)
        self._sensors_stale = False

    async def request_sensor_value(self, ctx: aiokatcp.RequestContext,
                                   name: str | None = None) -> None:
        """Request the value of a sensor or sensors."""
        if self._sensors_stale:
            self.refresh_sensors()
        await super().request_sensor_value(ctx, name)

    async def request_sensor_sampling(self, ctx: aiokatcp.RequestContext, name: str,
                                      strategy: aiokatcp.SensorSampler.Strategy | None = None,
                                      *args: bytes) -> tuple:
        """Configure or query the way a sensor is sampled."""
        if self._sensors_stale:
            self.refresh_sensors()
        if strategy is not None and strategy != aiokatcp.SensorSampler.Strategy.NONE:
            self._watched = True
        return await super().request_sensor_sampling(ctx, name, strategy, *args)

    # ------------------------------------------------------------------ connections
    # aiokatcp has no public hook for connections coming and going: these two extend its own
    def _connection_made(self, conn) -> None:
        super()._connection_made(conn)
        self.say(f"client {conn.address} connected ({len(self._connections)} connected)")

    def _connection_lost(self, conn, exc) -> None:
        super()._connection_lost(conn, exc)
        if conn is self.controller:
            self.release("disconnected")
        self.say(f"client {conn.address} disconnected ({len(self._connections)} connected)")

    def release(self, why: str) -> None:
        """The controlling client lets go: integrations it never read are computed (the
        world's random numbers continue as if they had been) and forgotten."""
        address = self.controller.address if self.controller is not None else "?"
        self.controller = None
        self._deferred.clear()
        self.antenna.flush()
        self.say(f"client {address} no longer controls the antenna ({why})")
        self.refresh_sensors()

    def _take_control(self, conn) -> None:
        if self.controller is None:
            self.controller = conn
            self.say(f"client {conn.address} controls the antenna")
        elif conn is not self.controller:
            raise aiokatcp.FailReply(
                f"client {self.controller.address} controls the antenna: this connection "
                "may read values and watch sensors, and may command once that client "
                "disconnects or sends ?release")

    # ------------------------------------------------------------------ serving
    async def _serve(self, ctx: aiokatcp.RequestContext, kind: str, func: Callable,
                     args: tuple[bytes, ...]):
        t0 = time.perf_counter()
        try:
            return await self._serve_timed(ctx, kind, func, args)
        finally:
            self.serving_s += time.perf_counter() - t0

    async def _serve_timed(self, ctx: aiokatcp.RequestContext, kind: str, func: Callable,
                           args: tuple[bytes, ...]):
        name = ctx.req.name
        command = kind == "command" or (kind == "command-with-args" and bool(args))
        clock_before = float(self.antenna.clock_s()) if self.log is not None else 0.0
        try:
            try:
                if command:
                    reply = await self._command(ctx, func, args)
                else:
                    self.clock.sync()
                    reply = await func(self, ctx, *args)
            except (ArgumentError, TableError, AntennaError, OutOfTimeError) as err:
                raise aiokatcp.FailReply(str(err)) from err
            except aiokatcp.FailReply:
                raise
            except Exception as err:
                logger.exception("?%s failed", name)
                raise aiokatcp.FailReply(f"internal error: {type(err).__name__}: {err}") from err
        except aiokatcp.FailReply as err:
            self._log(ctx, name, args, clock_before, "fail", [str(err)])
            raise
        self._log(ctx, name, args, clock_before, "ok", reply)
        return reply

    async def _command(self, ctx: aiokatcp.RequestContext, func: Callable,
                       args: tuple[bytes, ...]):
        """Carry out a command of the controlling client once those it sent before are
        done (a client may send several without waiting for their replies: they are carried
        out in the order they came). A command from a connection that has closed in the
        meantime is not carried out: the antenna is no longer that client's."""
        self._check_open(ctx.conn)
        self._take_control(ctx.conn)
        async with self._in_order:
            self._check_open(ctx.conn)
            self._take_control(ctx.conn)  # still: it may have released while waiting
            self._busy = ctx.req.name
            try:
                self.clock.sync()
                return await func(self, ctx, *args)
            finally:
                self._busy = None
                self._sensors_stale = True
                if self._watched:
                    self.refresh_sensors()

    def _check_open(self, conn) -> None:
        if conn not in self._connections:
            raise aiokatcp.FailReply("not carried out: the connection closed")

    def _log(self, ctx, name: str, args, clock_s: float, status: str, reply) -> None:
        if self.log is None:
            return
        self.log.write({"wall_utc": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime()),
                        "clock_s": clock_s, "client": str(ctx.conn.address), "request": name,
                        "args": [a.decode("utf-8", "replace") for a in args], "reply": status,
                        "values": [repr(v) if isinstance(v, float) else str(v)
                                   for v in (reply if isinstance(reply, tuple) else ())]})

    def handle_message(self, conn, msg: aiokatcp.Message) -> None:
        # requests the handlers above do not log (aiokatcp's own, unknown ones) go into the
        # log here, without their reply
        if msg.mtype != msg.Type.REQUEST:
            return super().handle_message(conn, msg)
        self.requests += 1
        if self.log is not None and msg.name not in _LOGGED:
            self.log.write({"wall_utc": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime()),
                            "clock_s": self.antenna.clock_s(), "client": str(conn.address),
                            "request": msg.name,
                            "args": [a.decode("utf-8", "replace") for a in msg.arguments],
                            "reply": None, "values": []})
        return super().handle_message(conn, msg)

    async def _complete(self, event):
        return await self.clock.complete(event)

    def _clock(self) -> float:
        return float(self.antenna.clock_s())

    # ------------------------------------------------------------------ commands
    @_request("command")
    async def request_track(self, ctx, *args: bytes):
        """Follow a program track: ?track T AZ EL [T AZ EL ...] -> clock, slew+settle s.

        Times on the antenna clock (s), encoder degrees; see docs/katcp.md."""
        self.clock.check_room(0.0, "?track")
        track = ProgramTrack.from_numbers(numbers(args))
        duration = await self._complete(self.antenna.track(track))
        self._track = track
        return self._clock(), float(duration)

    @_request("command")
    async def request_track_append(self, ctx, *args: bytes):
        """Add to the program track: ?track-append T AZ EL ... -> clock, points, first, last.

        Points may come in any order; one at a time already in the table replaces it."""
        if self._track is None or self.world.mount.trajectory is not self._track:
            raise ArgumentError("no program track is being followed: send ?track first")
        ProgramTrack.from_numbers(numbers(args), self._track)
        return self._clock(), len(self._track), self._track.start_s, self._track.end_s

    @_request("command")
    async def request_offset(self, ctx, *args: bytes):
        """Offset from the track: ?offset DAZ DEL (encoder deg) -> clock, move+settle s."""
        at_most(args, 2, "?offset DAZ DEL")
        d_az, d_el = number(args, 0, "DAZ"), number(args, 1, "DEL")
        if not self.world.mount.on_track:
            raise ArgumentError("no program track is being followed: send ?track first")
        duration = await self._complete(self.antenna.set_offset(d_az, d_el))
        return self._clock(), float(duration)

    @_request("command")
    async def request_integrate(self, ctx, *args: bytes):
        """Total power: ?integrate SECONDS [defer] -> clock, id, ..., power and std per channel.

        Replies clock, id, start and end (s), samples, mean encoders (deg), weather, then
        power and sample standard deviation (K) per channel; with defer without them (read
        them with ?powers)."""
        at_most(args, 2, "?integrate SECONDS [defer]")
        seconds = number(args, 0, "SECONDS")
        defer = len(args) == 2
        if defer and args[1] != b"defer":
            raise ArgumentError(f"argument 2 {quoted(args[1])}: the only option is 'defer'")
        if seconds <= 0:
            raise ArgumentError(f"argument 1 (SECONDS) {quoted(args[0])}: must be positive")
        self.clock.check_room(seconds, "?integrate")
        integ = await self._complete(self.antenna.integrate(seconds))
        ident = self._next_id
        self._next_id += 1
        w = integ.weather
        head = (self._clock(), ident, integ.t_start_s, integ.t_end_s, integ.n_samples,
                integ.enc_az_deg, integ.enc_el_deg, w.temperature_c, w.pressure_hpa,
                w.relative_humidity, w.wind_speed_m_s)
        if defer:
            self._deferred[ident] = integ
            return head
        return head + self._powers(integ)

    def _powers(self, integ) -> tuple[float, ...]:
        out: list[float] = []
        for ch in self.antenna.channels:
            out += [float(integ.power_k[ch]), float(integ.std_k[ch])]
        return tuple(out)

    @_request("command")
    async def request_powers(self, ctx, *args: bytes):
        """Powers of deferred integrations: ?powers [FIRST [LAST]] -> #powers informs, count.

        One inform per integration: id, then power and sample standard deviation (K) per
        channel. Without arguments: every integration waiting for ?powers."""
        at_most(args, 2, "?powers [FIRST [LAST]]")
        if args:
            first = integer(args, 0, "FIRST")
            last = integer(args, 1, "LAST") if len(args) == 2 else first
            missing = [i for i in range(first, last + 1) if i not in self._deferred]
            if missing or last < first:
                raise ArgumentError(f"integration {missing[0] if missing else last} is not "
                                    "waiting for ?powers (never made with defer, or already "
                                    "read)")
            idents = range(first, last + 1)
        else:
            idents = sorted(self._deferred)
        # one write for the informs and the reply ("ok COUNT"): one wake-up of the client
        ctx.informs([(ident, *self._powers(self._deferred.pop(ident))) for ident in idents])

    @_request("command")
    async def request_wait(self, ctx, *args: bytes):
        """Let time pass, tracking: ?wait SECONDS -> clock."""
        at_most(args, 1, "?wait SECONDS")
        seconds = number(args, 0, "SECONDS")
        if seconds < 0:
            raise ArgumentError(f"argument 1 (SECONDS) {quoted(args[0])}: must not be negative")
        self.clock.check_room(seconds, "?wait")
        await self._complete(self.antenna.wait(seconds))
        return (self._clock(),)

    @_request("command-with-args")
    async def request_feed_angle(self, ctx, *args: bytes):
        """Turn the feed box or read it: ?feed-angle [ANGLE] -> clock, angle, turn s."""
        at_most(args, 1, "?feed-angle [ANGLE]")
        if not args:
            return self._clock(), self.antenna.feed_angle_deg(), 0.0
        angle = number(args, 0, "ANGLE")
        duration = await self._complete(self.antenna.set_feed_angle(angle))
        return self._clock(), self.antenna.feed_angle_deg(), float(duration)

    @_request("command")
    async def request_camera(self, ctx, *args: bytes):
        """Optical camera: ?camera SECONDS -> clock, times, found, xel el arcsec, ...

        Replies clock, start and end (s), found (1/0), the star's offset xel and el
        (arcsec), mean encoders (deg), weather."""
        at_most(args, 1, "?camera SECONDS")
        seconds = number(args, 0, "SECONDS")
        self.clock.check_room(seconds, "?camera")
        r = await self._complete(self.antenna.measure_offset(seconds))
        w = r.weather
        return (self._clock(), r.t_start_s, r.t_end_s, bool(r.found), r.xel_arcsec,
                r.el_arcsec, r.enc_az_deg, r.enc_el_deg, w.temperature_c, w.pressure_hpa,
                w.relative_humidity, w.wind_speed_m_s)

    @_request("reading")
    async def request_release(self, ctx, *args: bytes):
        """Stop controlling the antenna: ?release (another client may then command)."""
        at_most(args, 0, "?release")
        if self.controller is not ctx.conn:
            raise ArgumentError("this connection does not control the antenna")
        self.release("?release")
        return ()

    async def request_halt(self, ctx: aiokatcp.RequestContext) -> None:
        """Halt the server (the controlling client, or any client when none controls)."""
        if self.controller is not None and ctx.conn is not self.controller:
            raise aiokatcp.FailReply(f"client {self.controller.address} controls the "
                                     "antenna: only it may halt the server")
        await super().request_halt(ctx)

    # ------------------------------------------------------------------ readings
    @_request("reading")
    async def request_clock(self, ctx, *args: bytes):
        """The antenna clock: ?clock -> seconds since the epoch, UTC, clock mode."""
        at_most(args, 0, "?clock")
        clock_s = self._clock()
        return clock_s, self._utc(clock_s), self.clock.spec.text

    @_request("reading")
    async def request_encoder(self, ctx, *args: bytes):
        """Encoders now: ?encoder -> first and second axis (deg).

        Azimuth and elevation, or hour angle and declination on an equatorial mount."""
        at_most(args, 0, "?encoder")
        az, el = self.antenna.encoder_deg()
        return float(az), float(el)

    @_request("reading")
    async def request_weather(self, ctx, *args: bytes):
        """Weather: ?weather -> air C, pressure hPa, humidity 0..1, wind m/s."""
        at_most(args, 0, "?weather")
        w = self.antenna.weather()
        return w.temperature_c, w.pressure_hpa, w.relative_humidity, w.wind_speed_m_s

    @_request("reading")
    async def request_channels(self, ctx, *args: bytes):
        """Receiver channels: ?channels -> names, in the order ?integrate reports them."""
        at_most(args, 0, "?channels")
        return tuple(self.antenna.channels)

    @_request("reading")
    async def request_structure_temperatures(self, ctx, *args: bytes):
        """Structure temperatures: ?structure-temperatures -> informs (name, C), count.

        Every sensor read now (the ``structure.NAME`` sensors take the reading); the count is
        0 where the scenario has no structure temperature sensors."""
        at_most(args, 0, "?structure-temperatures")
        if not self.antenna.structure_sensors:
            return (0,)
        reading = self.antenna.structure_temperatures()
        set_structure(self.sensors, reading, self._epoch_unix + float(self.antenna.clock_s()))
        ctx.informs(reading.items())
        return (len(reading),)

    @_request("reading")
    async def request_antenna(self, ctx, *args: bytes):
        """What control software needs to know: ?antenna -> #antenna informs, count.

        One inform per item (name, value): site, epoch, mount, limits, speeds, channels,
        capabilities."""
        at_most(args, 0, "?antenna")
        ctx.informs(self.description().items())

    def description(self) -> dict[str, object]:
        """The items of ``?antenna`` (nothing of the truth: no pointing errors, no
        effects; the seed only names the simulation)."""
        sc = self.scenario
        m = sc.mount
        return {
            "scenario": sc.name, "seed": int(self.seed), "epoch-utc": sc.epoch_utc,
            "duration-s": float(sc.duration_s), "end-s": float(self.end_s),
            "clock": self.clock.spec.text,
            "site-latitude-deg": sc.site.latitude_deg,
            "site-longitude-deg": sc.site.longitude_deg, "site-height-m": sc.site.height_m,
            "mount": m.kind,
            "axis1-min-deg": m.az.min_deg, "axis1-max-deg": m.az.max_deg,
            "axis1-speed-deg-s": m.az.speed_deg_s, "axis1-accel-deg-s2": m.az.accel_deg_s2,
            "axis2-min-deg": m.el.min_deg, "axis2-max-deg": m.el.max_deg,
            "axis2-speed-deg-s": m.el.speed_deg_s, "axis2-accel-deg-s2": m.el.accel_deg_s2,
            "settle-s": m.settle_s, "wrap-margin-s": m.wrap_margin_s,
            "feed-speed-deg-s": m.feed_speed_deg_s,
            "channels": ",".join(self.antenna.channels),
            "camera": self.world.camera is not None,
            "structure-temperatures": len(self.antenna.structure_sensors),
        }


#: requests whose handlers log themselves
_LOGGED = frozenset(name for name in AntennaDevice._request_handlers
                    if getattr(getattr(AntennaDevice, "request_" + name.replace("-", "_"),
                                       None), "__wrapped__", None) is not None)
