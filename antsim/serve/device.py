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
import contextlib
import functools
import json
import logging
import os
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import aiokatcp
import numpy as np
import simpy
from astropy.time import Time

from controller.astro.earth import UtcLabeller
from controller.errors import InputError
from controller.protocol import AntennaError

from .._version import __version__
from ..scenario import MAX_SAMPLES
from ..world.world import EPHEMERIS_MARGIN_S, World
from .arguments import ArgumentError, at_most, integer, number, numbers, quoted, within
from .clock import ClockSpec, OutOfTimeError, make_clock
from .programtrack import ProgramTrack, TableError
from .sensors import add_sensors, set_structure, update_sensors

if TYPE_CHECKING:
    from ..scenario import Scenario

__all__ = ["AntennaDevice", "RequestLog"]

logger = logging.getLogger(__name__)

#: a feed box turns within these angles (deg; the scenarios' feed_angles_deg too)
FEED_LIMIT_DEG = 360.0
#: at most this many deferred integrations wait for ?powers (a backend's buffer), holding
#: at most MAX_DEFERRED_SAMPLES samples together (each waits with its sample times and
#: encoder commands: 1000 of 100,000 samples would hold 2.4 GB)
MAX_DEFERRED = 1000
MAX_DEFERRED_SAMPLES = 1_000_000
#: program-track times lie within a day before the epoch and a day after the end (s)
TRACK_MARGIN_S = 86400.0
#: the shortest sensor sampling period a client may ask for (s): the real-time clock
#: refreshes the sensors every 0.1 s, faster sampling would repeat the same values
MIN_SAMPLING_PERIOD_S = 0.1


class RequestLog:
    """``requests.jsonl``: one JSON line per request served, flushed as it is written. The
    file is made new (``O_EXCL``: an earlier session's log is never truncated) and never
    through a link."""

    def __init__(self, path: Path):
        self.path = path
        self.lines = 0
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL
                         | getattr(os, "O_NOFOLLOW", 0), 0o644)
        except FileExistsError:
            raise InputError("command line", "--out", str(path.parent),
                             f"already holds {path.name}",
                             "serve into an empty or new directory") from None
        self._file = os.fdopen(fd, "w", encoding="utf-8")

    def write(self, entry: dict) -> None:
        self._file.write(json.dumps(entry) + "\n")
        self._file.flush()
        self.lines += 1

    def close(self) -> None:
        with contextlib.suppress(OSError):  # a full disk: what was flushed is kept
            self._file.close()


def _request(kind: str):
    """A request handler: ``kind`` "command" (the controlling client only), "reading", or
    "command-with-args" (a reading without arguments, a command with them)."""

    def wrap(func: Callable):
        @functools.wraps(func)
        async def handler(self: "AntennaDevice", ctx: aiokatcp.RequestContext, *args: bytes):
            return await self._serve(ctx, kind, func, args)

        handler.antsim_kind = kind  # for the request list (antsim serve --requests)
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

    def _fresh_sensors(self) -> None:
        """Sensors brought up to date before a client reads them; a failure is a failure
        reply saying what failed, never a traceback sent to the client."""
        if not self._sensors_stale:
            return
        try:
            self.refresh_sensors()
        except Exception as err:
            logger.exception("refreshing the sensors failed")
            raise aiokatcp.FailReply(f"internal error: {type(err).__name__}: {err}") from err

    def _get_sensors(self, name: str | None) -> list:
        # aiokatcp's one lookup for ?sensor-value and ?sensor-list: a /regex/ is checked
        # first (a pattern such as /(.*)*x/ took 2.8 s per sensor name, holding every client)
        if name is not None and len(name) > 1 and name.startswith("/") and name.endswith("/"):
            try:
                check_name_pattern(name[1:-1])
                re.compile(name[1:-1])
            except ArgumentError as err:
                raise aiokatcp.FailReply(str(err)) from None
            except re.error as err:
                raise aiokatcp.FailReply(f"argument 1 (NAME) {quoted(name.encode())}: not a "
                                         f"regular expression ({err})") from None
        return super()._get_sensors(name)

    async def request_sensor_value(self, ctx: aiokatcp.RequestContext,
                                   name: str | None = None) -> None:
        """Request the value of a sensor or sensors."""
        self._fresh_sensors()
        await super().request_sensor_value(ctx, name)

    async def request_sensor_sampling(self, ctx: aiokatcp.RequestContext, name: str,
                                      strategy: aiokatcp.SensorSampler.Strategy | None = None,
                                      *args: bytes) -> tuple:
        """Configure or query the way a sensor is sampled."""
        if strategy is not None:
            try:
                _check_sampling(strategy, args)
            except ArgumentError as err:
                raise aiokatcp.FailReply(str(err)) from None
        self._fresh_sensors()
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
        self._write_log({"wall_utc": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime()),
                        "clock_s": clock_s, "client": str(ctx.conn.address), "request": name,
                        "args": [a.decode("utf-8", "replace") for a in args], "reply": status,
                        "values": [repr(v) if isinstance(v, float) else str(v)
                                   for v in (reply if isinstance(reply, tuple) else ())]})

    def _write_log(self, entry: dict) -> None:
        """One line of the request log; a log that cannot be written (a full disk) is said
        once and closed: the server goes on serving, the lines written are kept."""
        try:
            self.log.write(entry)
        except OSError as err:
            log, self.log = self.log, None
            log.close()
            self.say(f"{log.path}: cannot be written ({err.strerror or err}); requests are "
                     f"no longer logged, the {log.lines} lines written before are kept")

    def handle_message(self, conn, msg: aiokatcp.Message) -> None:
        # requests the handlers above do not log (aiokatcp's own, unknown ones) go into the
        # log here, without their reply
        if msg.mtype != msg.Type.REQUEST:
            return super().handle_message(conn, msg)
        self.requests += 1
        if self.log is not None and msg.name not in _LOGGED:
            self._write_log({"wall_utc": time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime()),
                            "clock_s": self.antenna.clock_s(), "client": str(conn.address),
                            "request": msg.name,
                            "args": [a.decode("utf-8", "replace") for a in msg.arguments],
                            "reply": None, "values": []})
        return super().handle_message(conn, msg)

    async def _complete(self, event):
        """The value of a command's simpy event, once the world has carried it out. Clients
        watching sensors see the command start (``mount.mode`` slewing or moving) with the
        clock at its start, then its end: with the virtual clock no tick shows it between."""
        if self._watched:
            self.refresh_sensors()
        return await self.clock.complete(event)

    def _clock(self) -> float:
        return float(self.antenna.clock_s())

    # ------------------------------------------------------------------ commands
    @_request("command")
    async def request_track(self, ctx, *args: bytes):
        """Follow a program track: ?track T AZ EL [T AZ EL ...] -> clock, slew+settle s.

        Times on the antenna clock (s), encoder degrees. Replaces the track and resets the
        offsets; the antenna interpolates linearly (azimuth the shorter way round), holds
        the first point before the table and the last after it, and refuses a track whose
        elevation at arrival is outside the mount's limits (?antenna)."""
        self.clock.check_room(0.0, "?track")
        track = ProgramTrack.from_numbers(numbers(args), times_s=self._track_times())
        slew_s, _, _ = self.world.mount.plan_slew(track)  # what the antenna will take
        self.clock.check_room(slew_s + self.world.mount.config.settle_s,
                              "the slew and settle of ?track")
        duration = await self._complete(self.antenna.track(track))
        self._track = track
        return self._clock(), float(duration)

    @_request("command")
    async def request_track_append(self, ctx, *args: bytes):
        """Add to the program track: ?track-append T AZ EL ... -> clock, points, first, last.

        Points may come in any order; one at a time already in the table replaces it."""
        if self._track is None or self.world.mount.trajectory is not self._track:
            raise ArgumentError("no program track is being followed: send ?track first")
        ProgramTrack.from_numbers(numbers(args), self._track, times_s=self._track_times())
        return self._clock(), len(self._track), self._track.start_s, self._track.end_s

    def _track_times(self) -> tuple[float, float]:
        """The times a program-track point may have (clock s): a day around the simulation."""
        return -TRACK_MARGIN_S, self.end_s + TRACK_MARGIN_S

    @_request("command")
    async def request_offset(self, ctx, *args: bytes):
        """Offset from the track: ?offset DAZ DEL (encoder deg) -> clock, move+settle s.

        Needs a track being followed (?track); refused when the track plus the offsets would
        leave the mount's axis limits, now or when the move ends."""
        at_most(args, 2, "?offset DAZ DEL")
        d_az, d_el = number(args, 0, "DAZ"), number(args, 1, "DEL")
        mount = self.world.mount
        if not mount.on_track:
            raise ArgumentError("no program track is being followed: send ?track first")
        move_s = mount.offset_move_s(d_az, d_el)
        self._check_offset(args, d_az, d_el, move_s)
        self.clock.check_room(move_s, f"arguments 1 and 2 (DAZ DEL) {quoted(args[0])} "
                                      f"{quoted(args[1])}: the move of ?offset")
        duration = await self._complete(self.antenna.set_offset(d_az, d_el))
        return self._clock(), float(duration)

    def _check_offset(self, args: tuple[bytes, ...], d_az: float, d_el: float,
                      move_s: float) -> None:
        """The track plus the new offsets must stay within the mount's limits, now and when
        the move ends; else the argument that leaves them is refused."""
        mount = self.world.mount
        now = mount.clock()
        az, el = mount.commanded_deg(np.array([now, now + move_s]))
        limits = self.scenario.mount
        for i, (name, axis, track, offset, old, limit) in enumerate((
                ("DAZ", "first axis", az, d_az, mount.offset_deg[0], limits.az),
                ("DEL", "second axis", el, d_el, mount.offset_deg[1], limits.el))):
            position = np.asarray(track, dtype=float) - old + offset
            outside = (position < limit.min_deg) | (position > limit.max_deg)
            if outside.any():
                at = float(position[int(np.argmax(outside))])
                raise ArgumentError(
                    f"argument {i + 1} ({name}) {quoted(args[i])}: the {axis} would be at "
                    f"{at:.6g} deg, outside the mount's limits {limit.min_deg:g}.."
                    f"{limit.max_deg:g} deg")

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
        samples = self._check_samples(args, seconds)
        if defer and len(self._deferred) >= MAX_DEFERRED:
            raise ArgumentError(f"{len(self._deferred)} deferred integrations wait for ?powers, "
                                "the most the antenna keeps: read them first")
        waiting = sum(integ.n_samples for integ in self._deferred.values())
        if defer and waiting + samples > MAX_DEFERRED_SAMPLES:
            raise ArgumentError(f"argument 1 (SECONDS) {quoted(args[0])}: {samples} samples "
                                f"more than the {waiting} waiting for ?powers would pass "
                                f"{MAX_DEFERRED_SAMPLES}: read them first")
        self.clock.check_room(seconds, f"argument 1 (SECONDS) {quoted(args[0])}: ?integrate")
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

    def _check_samples(self, args: tuple[bytes, ...], seconds: float) -> int:
        """The receiver samples of an integration or exposure of ``seconds``: at most
        MAX_SAMPLES (as a scenario's scan integration)."""
        interval_s = self.world.receiver.config.sample_interval_s
        samples = seconds / interval_s
        if samples > MAX_SAMPLES:
            raise ArgumentError(f"argument 1 (SECONDS) {quoted(args[0])}: {samples:.3g} "
                                f"samples of {interval_s:g} s; at most {MAX_SAMPLES}")
        return max(1, round(samples))  # as the receiver counts them

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
            if last < first:
                raise ArgumentError(f"argument 2 (LAST) {quoted(args[1])}: comes before "
                                    f"FIRST {first}")
            idents = range(first, last + 1)
            # at most len(deferred) + 1 ids looked at: a range wider than what waits has an
            # id missing among its first ones (a range of 10^12 ids costs nothing)
            missing = next((i for i in idents[:len(self._deferred) + 1]
                            if i not in self._deferred), None)
            if missing is not None:
                raise ArgumentError(f"integration {missing} is not waiting for ?powers (never "
                                    "made with defer, or already read)")
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
        self.clock.check_room(seconds, f"argument 1 (SECONDS) {quoted(args[0])}: ?wait")
        await self._complete(self.antenna.wait(seconds))
        return (self._clock(),)

    @_request("command-with-args")
    async def request_feed_angle(self, ctx, *args: bytes):
        """Turn the feed box or read it: ?feed-angle [ANGLE] -> clock, angle, turn s."""
        at_most(args, 1, "?feed-angle [ANGLE]")
        if not args:
            return self._clock(), self.antenna.feed_angle_deg(), 0.0
        angle = within(args, 0, "ANGLE", -FEED_LIMIT_DEG, FEED_LIMIT_DEG, "deg")
        self.clock.check_room(self.antenna.feed_turn_s(angle),
                              f"argument 1 (ANGLE) {quoted(args[0])}: the turn of ?feed-angle")
        duration = await self._complete(self.antenna.set_feed_angle(angle))
        return self._clock(), self.antenna.feed_angle_deg(), float(duration)

    @_request("command")
    async def request_camera(self, ctx, *args: bytes):
        """Optical camera: ?camera SECONDS -> clock, times, found, xel el arcsec, ...

        Replies clock, start and end (s), found (1/0), the star's offset xel and el
        (arcsec), mean encoders (deg), weather."""
        at_most(args, 1, "?camera SECONDS")
        seconds = number(args, 0, "SECONDS")
        if seconds <= 0:
            raise ArgumentError(f"argument 1 (SECONDS) {quoted(args[0])}: must be positive")
        self._check_samples(args, seconds)
        self.clock.check_room(seconds, f"argument 1 (SECONDS) {quoted(args[0])}: ?camera")
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


#: a sensor name pattern repeats at most this many characters or classes
MAX_PATTERN_REPEATS = 4
MAX_PATTERN_LENGTH = 100


def check_name_pattern(pattern: str) -> None:
    """A KATCP sensor name pattern (``?sensor-value /PATTERN/``) that Python's regular
    expressions match in bounded time against the short sensor names: at most 100
    characters and 4 repeats, each of a single character or class. A repeated group is
    refused: nested repeats backtrack catastrophically (``(.*)*x``: 2.8 s per name)."""
    shown = quoted(f"/{pattern}/".encode())
    if len(pattern) > MAX_PATTERN_LENGTH:
        raise ArgumentError(f"argument 1 (NAME) {shown}: a pattern of {len(pattern)} "
                            f"characters; at most {MAX_PATTERN_LENGTH}")
    repeats, i, in_class = 0, 0, False
    previous = ""
    while i < len(pattern):
        ch = pattern[i]
        if ch == "\\" and i + 1 < len(pattern):
            previous, i = "atom", i + 2
            continue
        if in_class:
            in_class = ch != "]"
            previous = "atom" if not in_class else previous
        elif ch == "[":
            in_class = True
        elif ch in "*+?{":
            if previous == "group":
                raise ArgumentError(f"argument 1 (NAME) {shown}: a repeated group is not "
                                    "allowed in a sensor name pattern (it can take minutes)")
            if ch != "?" or previous != "repeat":  # a lazy *? is one repeat
                repeats += 1
            previous = "repeat"
            if ch == "{":
                i = pattern.find("}", i) if "}" in pattern[i:] else len(pattern)
        elif ch == ")":
            previous = "group"
        else:
            previous = "atom"
        i += 1
    if repeats > MAX_PATTERN_REPEATS:
        raise ArgumentError(f"argument 1 (NAME) {shown}: {repeats} repeats; at most "
                            f"{MAX_PATTERN_REPEATS} in a sensor name pattern")


def _check_sampling(strategy: aiokatcp.SensorSampler.Strategy, args: tuple[bytes, ...]) -> None:
    """A sampling strategy's parameters (?sensor-sampling NAME STRATEGY ARGS: argument 3 on)
    are finite, not negative, and periods not shorter than MIN_SAMPLING_PERIOD_S: a NaN
    period would send informs as fast as the server can."""
    s = aiokatcp.SensorSampler.Strategy
    names = {s.PERIOD: ("PERIOD",), s.DIFFERENTIAL: ("DIFFERENCE",),
             s.EVENT_RATE: ("SHORTEST", "LONGEST"),
             s.DIFFERENTIAL_RATE: ("DIFFERENCE", "SHORTEST", "LONGEST")}.get(strategy, ())
    if len(args) != len(names):
        usage = " ".join((strategy.name.lower().replace("_", "-"), *names))
        raise ArgumentError(f"{strategy.name.lower().replace('_', '-')} takes {len(names)} "
                            f"parameter(s), got {len(args)}: usage ?sensor-sampling NAME "
                            f"{usage}")
    full = (b"NAME", b"STRATEGY", *args)  # numbered as the request's arguments
    values = {name: number(full, i + 2, name) for i, name in enumerate(names)}
    for i, (name, value) in enumerate(values.items()):
        if value < 0.0:
            raise ArgumentError(f"argument {i + 3} ({name}) {quoted(args[i])}: must not be "
                                "negative")
    for name in ("PERIOD", "LONGEST"):
        if name in values and values[name] < MIN_SAMPLING_PERIOD_S:
            i = names.index(name)
            raise ArgumentError(f"argument {i + 3} ({name}) {quoted(args[i])}: at least "
                                f"{MIN_SAMPLING_PERIOD_S:g} s")
    if "SHORTEST" in values and values["SHORTEST"] > values["LONGEST"]:
        i = names.index("SHORTEST")
        raise ArgumentError(f"argument {i + 3} (SHORTEST) {quoted(args[i])}: longer than "
                            f"LONGEST {values['LONGEST']:g} s")


#: requests whose handlers log themselves
_LOGGED = frozenset(name for name in AntennaDevice._request_handlers
                    if getattr(getattr(AntennaDevice, "request_" + name.replace("-", "_"),
                                       None), "__wrapped__", None) is not None)
