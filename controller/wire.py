"""An antenna driven over KATCP: :class:`controller.protocol.Antenna` as a network client.

:class:`KatcpAntenna` speaks the request set of ``docs/katcp.md`` (served by ``antsim
serve``; a real antenna's control unit could serve the same) with a blocking socket and
aiokatcp's message encoding. Floats cross the wire as ``repr`` (aiokatcp's encoding), so
they arrive to the bit.

Pipelining: a command whose reply the controller does not need before its next decision is
sent without waiting for that reply (KATCP matches replies to requests by message id), and
the replies are read together when the controller next needs one: the clock, a reading, a
track's slew time, a number of an integration or the duration of a move. Offsets, deferred
integrations and waits go out so; the antenna carries out one client's commands in the order
they come. A five-point cross scan then waits for the antenna once per azimuth point (the
controller reads the clock before each, to step by the cosine of the elevation at its
middle) and once for all its elevation points, the return to zero offset, the wait and the
powers, instead of once per request. What such a command returns stands for its reply:
:class:`LaterIntegration` (an :class:`~controller.protocol.Integration` whose numbers are read
when first used) and :class:`LaterSeconds` (a move's duration, ``float()`` reads it). A
command that fails does not stop those sent behind it (KATCP has no transactions): its
failure is raised as :class:`~controller.protocol.AntennaError` naming the request at the
next read of a reply, whichever that is. A track, whose failure the controller handles at
once, goes out when every command before it is answered, and its reply is read before the
controller goes on.

Tracking: the controller hands :meth:`KatcpAntenna.track` a trajectory (a callable of clock
time). The antenna is sent a program track: the trajectory's own table where it has one
(:meth:`controller.scans.tracking.SourceTrajectory.program_track`), which the antenna
interpolates exactly as the trajectory does; elsewhere the trajectory's exact positions: at
the instant slew planning looks ahead to (now + the mount's wrap margin), at the instants
the antenna's position is read (:meth:`encoder_deg`, the start of the next slew), and every
``FEED_STEP_S`` ahead of each command past the table's end (an integration there would be
interpolated between exact positions; the project's scans end within their tables). Whether
a command needs points fed ahead is decided on the clock it starts at; behind unanswered
commands the client bounds that clock by their seconds and, for offset moves, by the
antenna's published speeds, accelerations and settling (``?antenna``), and reads their
replies first only where the bound leaves the answer open. A plain callable without a table
is sampled every ``FEED_STEP_S``. So the project's controller against ``antsim serve
--clock virtual`` records what it records in process, byte for byte.

Integrations are made with ``defer`` and their powers fetched (``?powers``) when the
controller first reads one, all outstanding at once: as the in-process antenna computes
them, so with the same numbers. With a virtual clock the antenna's clock and state change
only with this client's commands, whose replies carry the clock: :meth:`clock_s` then needs
no request, and the encoders and weather, read together, hold until the next command.
"""

from __future__ import annotations

import math
import socket
import time
from collections.abc import Callable
from dataclasses import fields
from functools import partial

import aiokatcp
import numpy as np

from .protocol import (
    AntennaError,
    ChannelValues,
    Integration,
    OffsetReading,
    Trajectory,
    WeatherReading,
)

__all__ = ["ConnectionLostError", "KatcpAntenna", "LaterIntegration", "LaterSeconds"]

#: positions sent ahead of the trajectory's table, this far apart (s)
FEED_STEP_S = 2.0
#: and this far beyond the end of each command (s)
FEED_AHEAD_S = 120.0
#: a generic trajectory (no table of its own) is sampled this far ahead at a track (s)
SAMPLE_SPAN_S = 900.0
#: seconds to wait for a reply beyond the time the command takes on the antenna's clock
REPLY_TIMEOUT_S = 60.0
#: the antenna clock's seconds per second of the time it measures may differ from 1 (a clock
#: error drifting by seconds a day); behind unanswered commands this much is added to the
#: bound of the clock (s)
CLOCK_SLACK_S = 1.0


class ConnectionLostError(ConnectionError):
    """The antenna's server cannot be reached or closed the connection."""


class _Reply:
    """A request sent: its reply's arguments after ``ok`` (or its failure) and its informs,
    once read; ``then`` is called with the arguments as the reply is read."""

    __slots__ = ("args", "error", "informs", "mid", "name", "powers", "result", "then",
                 "values")

    def __init__(self, mid: int, name: str, args: tuple,
                 then: Callable[[list[bytes]], None] | None):
        self.mid = mid
        self.name = name
        self.args = args
        self.then = then
        self.values: list[bytes] | None = None
        self.error: str | None = None
        self.informs: list = []
        self.result = None  # what the controller was given for it, once built
        self.powers: tuple[dict, dict] | None = None  # of a deferred integration

    def request(self) -> str:
        """The request as a message names it: ``?offset 0.1 0.0``, ``?track (451 points)``."""
        if self.args and isinstance(self.args[0], _Encoded):
            return f"?{self.name} ({len(self.args[0]) // 3} points)"
        return " ".join([f"?{self.name}", *(str(a) for a in self.args)])


class LaterSeconds:
    """A duration (s) that comes with a reply not read yet: ``float()`` gives it, reading the
    reply if need be (and raising its failure, :class:`AntennaError`)."""

    __slots__ = ("_get",)

    def __init__(self, get: Callable[[], float]):
        self._get = get

    def __float__(self) -> float:
        return self._get()

    def __repr__(self) -> str:
        return f"LaterSeconds({self._get()!r})"


class LaterIntegration(Integration):
    """An :class:`~controller.protocol.Integration` whose numbers come with a reply not read
    yet: the first use of any of them reads it (and raises its failure,
    :class:`AntennaError`). It copies and pickles as the plain Integration it stands for;
    ``dataclasses.replace`` makes a plain one."""

    def __new__(cls, get: Callable[[], Integration] | None = None, **values):
        if get is None:  # dataclasses.replace(later, ...) calls the class with every field
            return Integration(**values)
        return object.__new__(cls)

    def __init__(self, get: Callable[[], Integration]):
        object.__setattr__(self, "_get", get)  # Integration is frozen

    def __reduce_ex__(self, protocol):
        given = self._get()
        return Integration, tuple(getattr(given, f.name) for f in fields(Integration))


for _field in fields(Integration):  # each field read from the Integration the reply gives
    setattr(LaterIntegration, _field.name,
            property(lambda self, name=_field.name: getattr(self._get(), name)))
del _field


class KatcpAntenna:
    """The protocol of :mod:`controller.protocol` over KATCP, for a simpy controller in
    ``env`` (commands return events of ``env`` that have already fired: the antenna's own
    clock, not ``env``'s, measures time)."""

    def __init__(self, host: str, port: int, env, timeout_s: float = REPLY_TIMEOUT_S):
        self._Message = aiokatcp.Message
        self.env = env
        self.address = f"{host}:{port}"
        self.timeout_s = timeout_s
        try:
            self._sock = socket.create_connection((host, port), timeout=timeout_s)
        except OSError as err:
            raise ConnectionLostError(f"cannot connect to the antenna at {self.address}: "
                                      f"{err.strerror or err}") from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._file = self._sock.makefile("rb")
        self._mid = 0
        self._outbox: list[bytes] = []  # requests not sent yet
        self._unanswered: dict[int, _Reply] = {}  # by message id
        #: at most the seconds the unanswered commands take on the antenna's clock
        self._unanswered_s = 0.0
        #: requests made, times the client waited for replies (a round trip: one write, then
        #: the replies of everything unanswered), and the wall time spent waiting (s)
        self.requests = 0
        self.round_trips = 0
        self.waited_s = 0.0
        self.factor = 1.0  # simulated seconds per wall second, until ?antenna says
        _, informs = self._request("antenna")
        #: the antenna's description (?antenna): name -> value (strings)
        self.info = {m.arguments[0].decode(): m.arguments[1].decode() for m in informs}
        self.channels = tuple(self.info["channels"].split(","))
        self.virtual = self.info.get("clock") == "virtual"
        self.factor = (math.inf if self.virtual else
                       1.0 if self.info.get("clock") == "realtime"
                       else float(self.info.get("clock", "x1")[1:]))
        self.wrap_margin_s = float(self.info.get("wrap-margin-s", 0.0))
        self._axes = [self._axis(f"axis{k}") for k in (1, 2)]
        self._settle_s = float(self.info.get("settle-s", math.inf))
        self._clock = float(self._request("clock")[0][0])
        self._traj: Trajectory | None = None
        self._table_end = -math.inf
        self._exact: set[float] = set()
        self._offset_deg = (0.0, 0.0)
        self._deferred: list[_Reply] = []  # integrations whose powers are not fetched yet
        #: encoders and weather read since the last command (virtual clock: they hold)
        self._readings: tuple[tuple[float, float], WeatherReading] | None = None
        self._structure_names: tuple[str, ...] | None = None

    def _axis(self, prefix: str) -> tuple[float, float]:
        """An axis's speed (deg/s) and acceleration (deg/s^2) as ``?antenna`` gives them;
        (0, 1) where it does not (then no move has a bound: see :meth:`_move_bound_s`)."""
        try:
            return (float(self.info[f"{prefix}-speed-deg-s"]),
                    float(self.info[f"{prefix}-accel-deg-s2"]))
        except (KeyError, ValueError):
            return 0.0, 1.0

    # ------------------------------------------------------------------ the wire
    def _send(self, name: str, *args, seconds: float = 0.0,
              then: Callable[[list[bytes]], None] | None = None) -> _Reply:
        """Queue ``?name args`` to go out with the next round trip; ``seconds``: at most what
        it takes on the antenna's clock."""
        self._mid += 1
        self.requests += 1
        reply = _Reply(self._mid, name, args, then)
        self._outbox.append(bytes(self._message(name, args, self._mid)))
        self._unanswered[self._mid] = reply
        self._unanswered_s += seconds
        return reply

    def _sync(self) -> None:
        """One round trip: send what is queued and read the replies of every unanswered
        request (informs go with their request). Raises the first failure among them as
        :class:`AntennaError` naming the request, once all are read."""
        if not self._unanswered:
            return
        t0 = time.perf_counter()
        self.round_trips += 1
        failed = None
        try:
            if self._outbox:
                data = b"".join(self._outbox)
                self._outbox.clear()
                self._sock.sendall(data)
            # the commands' time on the antenna's clock, in wall seconds (a day at most: a
            # move's bound is infinite where the antenna does not publish its speeds)
            self._sock.settimeout(self.timeout_s
                                  + min(self._unanswered_s, 86400.0) / self.factor)
            while self._unanswered:
                line = self._file.readline()
                if not line:
                    raise ConnectionLostError(f"the antenna at {self.address} closed the "
                                              "connection")
                if not line.strip():
                    continue
                msg = self._Message.parse(line)
                reply = self._unanswered.get(msg.mid)
                if reply is None:
                    continue  # an asynchronous inform (#log, #sensor-status, ...)
                if msg.mtype == msg.Type.INFORM:
                    reply.informs.append(msg)
                    continue
                del self._unanswered[msg.mid]
                if msg.reply_ok():
                    reply.values = msg.arguments[1:]
                    if reply.then is not None:
                        reply.then(reply.values)
                else:
                    reply.error = b" ".join(msg.arguments[1:]).decode("utf-8", "replace")
                    failed = failed or reply
        except TimeoutError:
            first = self._unanswered[min(self._unanswered)]
            raise ConnectionLostError(f"no reply to {first.request()} from the antenna at "
                                      f"{self.address} within {self._sock.gettimeout():.0f} s"
                                      ) from None
        except OSError as err:
            raise ConnectionLostError(f"lost the connection to the antenna at {self.address}: "
                                      f"{err.strerror or err}") from None
        finally:
            self.waited_s += time.perf_counter() - t0
        self._unanswered_s = 0.0
        if failed is not None:
            raise AntennaError(f"{failed.request()}: {failed.error}")

    def _answer(self, reply: _Reply) -> list[bytes]:
        """``reply``'s arguments, read now if they are not yet."""
        if reply.mid in self._unanswered:
            self._sync()
        if reply.error is not None:
            raise AntennaError(f"{reply.request()}: {reply.error}")
        return reply.values

    def _request(self, name: str, *args) -> tuple[list[bytes], list]:
        """A reading (or a request other than a command): sent once every command before it
        is answered, its reply read at once; its arguments after ``ok`` and its informs."""
        self._sync()
        reply = self._send(name, *args)
        return self._answer(reply), reply.informs

    def _post(self, name: str, *args, seconds: float = 0.0) -> _Reply:
        """A command, its reply read later: it starts with the antenna's clock after it."""
        self._readings = None
        return self._send(name, *args, seconds=seconds, then=self._set_clock)

    def _command(self, name: str, *args, seconds: float = 0.0) -> list[bytes]:
        """A command whose reply the controller needs now: its arguments after the clock."""
        return self._answer(self._post(name, *args, seconds=seconds))[1:]

    def _set_clock(self, values: list[bytes]) -> None:
        self._clock = float(values[0])

    def _message(self, name: str, args: tuple, mid: int):
        if args and isinstance(args[0], _Encoded):  # a table, already encoded (_floats)
            msg = self._Message.request(name, mid=mid)
            msg.arguments = args[0]
            return msg
        return self._Message.request(name, *args, mid=mid)

    def _event(self, func, *args):
        """``func(*args)`` as an event that has fired (or failed with its AntennaError)."""
        event = self.env.event()
        try:
            event.succeed(func(*args))
        except AntennaError as err:
            event.fail(err)
        return event

    def release(self) -> None:
        """Stop controlling the antenna (another client may then command it)."""
        self._request("release")

    def close(self) -> None:
        """Close the connection (the server stays up)."""
        self._file.close()
        self._sock.close()

    def __enter__(self) -> KatcpAntenna:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------ readings
    def clock_s(self) -> float:
        self._sync()
        if not self.virtual:
            self._clock = float(self._request("clock")[0][0])
        return self._clock

    def weather(self) -> WeatherReading:
        if not self.virtual:
            return _weather(self._request("weather")[0])
        return self._state()[1]

    def encoder_deg(self) -> tuple[float, float]:
        self._exact_at(self.clock_s())
        if not self.virtual:
            az, el = self._request("encoder")[0]
            return float(az), float(el)
        return self._state()[0]

    def _state(self) -> tuple[tuple[float, float], WeatherReading]:
        """Encoders and weather, read together (virtual clock: until the next command)."""
        if self._readings is None:
            self._sync()
            encoder, weather = self._send("encoder"), self._send("weather")
            az, el = self._answer(encoder)
            self._readings = (float(az), float(el)), _weather(self._answer(weather))
        return self._readings

    def feed_angle_deg(self) -> float:
        return float(self._request("feed-angle")[0][1])

    @property
    def structure_sensors(self) -> tuple[str, ...]:
        """The antenna's structure temperature sensors (``?antenna``'s count; their names
        from the first ``?structure-temperatures``)."""
        if self._structure_names is None:
            count = int(float(self.info.get("structure-temperatures", 0)))
            self._structure_names = tuple(self.structure_temperatures()) if count else ()
        return self._structure_names

    def structure_temperatures(self) -> dict[str, float]:
        """Every structure temperature sensor's reading now (C)."""
        _, informs = self._request("structure-temperatures")
        reading = {m.arguments[0].decode(): float(m.arguments[1]) for m in informs}
        if self._structure_names is None:
            self._structure_names = tuple(reading)
        return reading

    # ------------------------------------------------------------------ tracking
    def track(self, trajectory: Trajectory, label: str = ""):
        return self._event(self._track, trajectory)

    def _track(self, trajectory: Trajectory) -> float:
        now = self.clock_s()
        self._exact_at(now)  # where the slew starts: the trajectory followed until now
        if hasattr(trajectory, "program_track"):
            t, az, el = trajectory.program_track()
        else:
            t = now + np.arange(0.0, SAMPLE_SPAN_S + FEED_STEP_S, FEED_STEP_S)
            az, el = trajectory(t)
        points = [np.asarray(t, float), np.asarray(az, float), np.asarray(el, float)]
        exact = set()
        look = now + self.wrap_margin_s  # where slew planning looks for the cable wrap
        if self.wrap_margin_s > 0 and not self._covers(trajectory, look):
            # slew planning reads only the azimuth there; the elevation, an hour ahead, may
            # be of a source that has set, where a model's cot E term diverges (the 1990
            # model's W5 = 0.6' cot E is 106 deg at 0.005 deg): the table takes -90..90 deg
            a, e = trajectory(np.array([look]))
            e = np.clip(e, -90.0, 90.0)
            points = [np.append(points[0], look), np.append(points[1], a),
                      np.append(points[2], e)]
            exact.add(look)
        (duration,) = self._command("track", _floats(np.stack(points, axis=1)))
        self._traj = trajectory
        self._table_end = float(t[-1])
        self._exact = exact
        self._offset_deg = (0.0, 0.0)
        return float(duration)

    @staticmethod
    def _covers(trajectory, t_s: float) -> bool:
        covers = getattr(trajectory, "covers", None)
        return bool(covers is not None and covers(np.array([t_s])))

    def _exact_at(self, t_s: float) -> None:
        """Make sure the antenna holds the followed trajectory's exact position at
        ``t_s`` (where its table does not reach): the antenna is about to use it."""
        traj = self._traj
        if traj is None or t_s in self._exact or self._covers(traj, t_s):
            return
        az, el = traj(np.array([t_s]))
        self._command("track-append", t_s, float(az[0]), float(el[0]))
        self._exact.add(t_s)

    def _feed(self, seconds: float) -> None:
        """Extend the program track past the end of a command of ``seconds`` (and
        ``FEED_AHEAD_S``) where the trajectory's own table ends before."""
        traj = self._traj
        if traj is None:
            return
        if self._unanswered:  # the clock is not known yet: at most ...
            latest = (self._clock + self._unanswered_s + CLOCK_SLACK_S + seconds
                      + FEED_AHEAD_S)
            if latest <= self._table_end or self._covers(traj, latest):
                return  # ... and even then the track reaches far enough
            self._sync()
        until = self._clock + seconds + FEED_AHEAD_S
        if until <= self._table_end or self._covers(traj, until):
            return
        start = max(self._table_end, self._clock - FEED_STEP_S)
        t = start + FEED_STEP_S * np.arange(1, math.ceil((until - start) / FEED_STEP_S) + 1)
        az, el = traj(t)
        self._command("track-append", _floats(np.stack([t, az, el], axis=1)))
        self._table_end = float(t[-1])
        self._exact.update(t.tolist())

    def _move_bound_s(self, d_az_deg: float, d_el_deg: float) -> float:
        """At most what moving the offset from the present one to (``d_az_deg``,
        ``d_el_deg``) takes (s): a move of d degrees at the axis's published speed v and
        acceleration a takes at most d / v + v / a (exactly that when it reaches v, less when
        it does not: 2 sqrt(d / a) <= d / v + v / a), then the settling; inf where the
        antenna does not publish them."""
        bound = 0.0
        for d, (speed, accel) in zip((d_az_deg - self._offset_deg[0],
                                      d_el_deg - self._offset_deg[1]), self._axes,
                                     strict=True):
            if d != 0.0:
                bound = max(bound, abs(d) / speed + speed / accel
                            if speed > 0 and accel > 0 else math.inf)
        return bound + self._settle_s

    # ------------------------------------------------------------------ commands
    def set_offset(self, d_az_deg: float, d_el_deg: float):
        return self._event(self._offset, float(d_az_deg), float(d_el_deg))

    def _offset(self, d_az_deg: float, d_el_deg: float) -> LaterSeconds:
        self._feed(0.0)
        reply = self._post("offset", d_az_deg, d_el_deg,
                           seconds=self._move_bound_s(d_az_deg, d_el_deg))
        self._offset_deg = (d_az_deg, d_el_deg)
        return LaterSeconds(lambda: float(self._answer(reply)[1]))

    def wait(self, seconds: float):
        return self._event(self._wait, float(seconds))

    def _wait(self, seconds: float) -> None:
        self._feed(seconds)
        self._post("wait", seconds, seconds=seconds)

    def set_feed_angle(self, angle_deg: float):
        return self._event(self._feed_angle, float(angle_deg))

    def _feed_angle(self, angle_deg: float) -> float:
        self._feed(0.0)
        return float(self._command("feed-angle", angle_deg)[1])

    def integrate(self, seconds: float):
        return self._event(self._integrate, float(seconds))

    def _integrate(self, seconds: float) -> LaterIntegration:
        self._feed(seconds)
        reply = self._post("integrate", seconds, "defer", seconds=seconds)
        self._deferred.append(reply)
        return LaterIntegration(partial(self._integration, reply))

    def _integration(self, reply: _Reply) -> Integration:
        if reply.result is None:
            v = self._answer(reply)[1:]  # after the clock: id, start, end, samples, ...
            reply.result = Integration(
                t_start_s=float(v[1]), t_end_s=float(v[2]),
                power_k=ChannelValues(partial(self._powers, reply, 0)),
                std_k=ChannelValues(partial(self._powers, reply, 1)),
                enc_az_deg=float(v[4]), enc_el_deg=float(v[5]), weather=_weather(v[6:10]),
                n_samples=int(v[3]))
        return reply.result

    def _powers(self, reply: _Reply, which: int) -> dict[str, float]:
        """Power (``which`` 0) or std (1) per channel of a deferred integration: all those
        not fetched yet are fetched together (the antenna computes them together, see the
        module), with ``?powers`` sent behind the commands still unanswered."""
        if reply.powers is None:
            fetch = self._send("powers")
            self._answer(fetch)
            by_id = {int(m.arguments[0]): [float(a) for a in m.arguments[1:]]
                     for m in fetch.informs}
            for r in self._deferred:
                numbers = by_id.get(int(r.values[1])) if r.values is not None else None
                if numbers is not None:
                    r.powers = (dict(zip(self.channels, numbers[0::2], strict=True)),
                                dict(zip(self.channels, numbers[1::2], strict=True)))
            self._deferred = [r for r in self._deferred
                              if r.powers is None and r.error is None]
            self._answer(reply)  # its own failure, if it failed
            if reply.powers is None:
                raise AntennaError(f"?powers gave nothing for {reply.request()}")
        return reply.powers[which]

    def measure_offset(self, seconds: float):
        return self._event(self._camera, float(seconds))

    def _camera(self, seconds: float) -> OffsetReading:
        self._feed(seconds)
        v = self._command("camera", seconds, seconds=seconds)
        return OffsetReading(
            t_start_s=float(v[0]), t_end_s=float(v[1]), found=v[2] == b"1",
            xel_arcsec=float(v[3]), el_arcsec=float(v[4]), enc_az_deg=float(v[5]),
            enc_el_deg=float(v[6]), weather=_weather(v[7:11]))


def _weather(values) -> WeatherReading:
    return WeatherReading(*(float(x) for x in values))


class _Encoded(list):
    """Message arguments already encoded (bytes)."""


def _floats(table: np.ndarray) -> _Encoded:
    """The numbers of ``table`` (row by row) as KATCP arguments, encoded as aiokatcp
    encodes a float (``repr``) but without its per-argument dispatch: a program track has
    a thousand of them (joined and split again: one encoding for all, no escapes needed)."""
    return _Encoded(" ".join(map(repr, table.ravel().tolist())).encode("ascii").split(b" "))
