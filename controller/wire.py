"""An antenna driven over KATCP: :class:`controller.protocol.Antenna` as a network client.

:class:`KatcpAntenna` speaks the request set of ``docs/katcp.md`` (served by ``antsim
serve``; a real antenna's control unit could serve the same) with a blocking socket and
aiokatcp's message encoding. Floats cross the wire as ``repr`` (aiokatcp's encoding), so
they arrive to the bit.

Tracking: the controller hands :meth:`KatcpAntenna.track` a trajectory (a callable of clock
time). The antenna is sent a program track: the trajectory's own table where it has one
(:meth:`controller.scans.tracking.SourceTrajectory.program_track`), which the antenna interpolates
exactly as the trajectory does; elsewhere the trajectory's exact positions: at the instant
slew planning looks ahead to (now + the mount's wrap margin), at the instants the antenna's
position is read (:meth:`encoder_deg`, the start of the next slew), and every
``FEED_STEP_S`` ahead of each command past the table's end (an integration there would be
interpolated between exact positions; the project's scans end within their tables). A plain
callable without a table is sampled every ``FEED_STEP_S``. So the project's controller
against ``antsim serve --clock virtual`` records what it records in process, byte for byte.

Integrations are made with ``defer`` and their powers fetched (``?powers``) when the
controller first reads one, all outstanding at once: as the in-process antenna computes
them, so with the same numbers, and one round trip per scan instead of one per integration.
With a virtual clock the antenna's clock changes only with this client's commands, whose
replies carry it: :meth:`clock_s` then needs no round trip.
"""

from __future__ import annotations

import math
import socket
import time
from functools import partial

import numpy as np

from .protocol import (
    AntennaError,
    ChannelValues,
    Integration,
    OffsetReading,
    Trajectory,
    WeatherReading,
)

__all__ = ["ConnectionLostError", "KatcpAntenna"]

#: positions sent ahead of the trajectory's table, this far apart (s)
FEED_STEP_S = 2.0
#: and this far beyond the end of each command (s)
FEED_AHEAD_S = 120.0
#: a generic trajectory (no table of its own) is sampled this far ahead at a track (s)
SAMPLE_SPAN_S = 900.0
#: seconds to wait for a reply beyond the time the command takes on the antenna's clock
REPLY_TIMEOUT_S = 60.0


class ConnectionLostError(ConnectionError):
    """The antenna's server cannot be reached or closed the connection."""


class KatcpAntenna:
    """The protocol of :mod:`controller.protocol` over KATCP, for a simpy controller in
    ``env`` (commands return events of ``env`` that have already fired: the antenna's own
    clock, not ``env``'s, measures time)."""

    def __init__(self, host: str, port: int, env, timeout_s: float = REPLY_TIMEOUT_S):
        import aiokatcp

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
        #: requests made, and the wall time from sending each to its reply (s)
        self.requests = 0
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
        self._clock = float(self._request("clock")[0][0])
        self._traj: Trajectory | None = None
        self._table_end = -math.inf
        self._exact: set[float] = set()
        self._deferred: dict[int, tuple[dict, dict] | None] = {}

    # ------------------------------------------------------------------ the wire
    def _request(self, name: str, *args, wait_s: float = 0.0) -> tuple[list[bytes], list]:
        """Send ``?name args``; the reply's arguments after ``ok`` and the informs that
        came with it. A failure reply raises :class:`AntennaError` with its message."""
        self._mid += 1
        mid = self._mid
        self.requests += 1
        t0 = time.perf_counter()
        try:
            self._sock.sendall(bytes(self._message(name, args, mid)))
            self._sock.settimeout(self.timeout_s + wait_s / self.factor)
            informs = []
            while True:
                line = self._file.readline()
                if not line:
                    raise ConnectionLostError(f"the antenna at {self.address} closed the "
                                              "connection")
                if not line.strip():
                    continue
                msg = self._Message.parse(line)
                if msg.mid != mid:
                    continue  # an asynchronous inform (#log, #sensor-status, ...)
                if msg.mtype == msg.Type.INFORM:
                    informs.append(msg)
                    continue
                break
        except TimeoutError:
            raise ConnectionLostError(f"no reply to ?{name} from the antenna at "
                                      f"{self.address} within {self._sock.gettimeout():.0f} s"
                                      ) from None
        except OSError as err:
            raise ConnectionLostError(f"lost the connection to the antenna at {self.address}: "
                                      f"{err.strerror or err}") from None
        finally:
            self.waited_s += time.perf_counter() - t0
        if not msg.reply_ok():
            text = b" ".join(msg.arguments[1:]).decode("utf-8", "replace")
            raise AntennaError(f"?{name}: {text}")
        return msg.arguments[1:], informs

    def _message(self, name: str, args: tuple, mid: int):
        if args and isinstance(args[0], _Encoded):  # a table, already encoded (_floats)
            msg = self._Message.request(name, mid=mid)
            msg.arguments = args[0]
            return msg
        return self._Message.request(name, *args, mid=mid)

    def _command(self, name: str, *args, wait_s: float = 0.0) -> list[bytes]:
        """A command: its reply starts with the antenna's clock after it."""
        values, _ = self._request(name, *args, wait_s=wait_s)
        self._clock = float(values[0])
        return values[1:]

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
        if not self.virtual:
            self._clock = float(self._request("clock")[0][0])
        return self._clock

    def weather(self) -> WeatherReading:
        return WeatherReading(*(float(v) for v in self._request("weather")[0]))

    def encoder_deg(self) -> tuple[float, float]:
        self._exact_at(self.clock_s())
        az, el = self._request("encoder")[0]
        return float(az), float(el)

    def feed_angle_deg(self) -> float:
        return float(self._command("feed-angle")[0])

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
            a, e = trajectory(np.array([look]))
            points = [np.append(points[0], look), np.append(points[1], a),
                      np.append(points[2], e)]
            exact.add(look)
        (duration,) = self._command("track", _floats(np.stack(points, axis=1)))
        self._traj = trajectory
        self._table_end = float(t[-1])
        self._exact = exact
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
        until = self._clock + seconds + FEED_AHEAD_S
        if traj is None or until <= self._table_end or self._covers(traj, until):
            return
        start = max(self._table_end, self._clock - FEED_STEP_S)
        t = start + FEED_STEP_S * np.arange(1, math.ceil((until - start) / FEED_STEP_S) + 1)
        az, el = traj(t)
        self._command("track-append", _floats(np.stack([t, az, el], axis=1)))
        self._table_end = float(t[-1])
        self._exact.update(t.tolist())

    # ------------------------------------------------------------------ commands
    def set_offset(self, d_az_deg: float, d_el_deg: float):
        return self._event(self._offset, float(d_az_deg), float(d_el_deg))

    def _offset(self, d_az_deg: float, d_el_deg: float) -> float:
        self._feed(0.0)
        return float(self._command("offset", d_az_deg, d_el_deg)[0])

    def wait(self, seconds: float):
        return self._event(self._wait, float(seconds))

    def _wait(self, seconds: float) -> None:
        self._feed(seconds)
        self._command("wait", seconds, wait_s=seconds)

    def set_feed_angle(self, angle_deg: float):
        return self._event(self._feed_angle, float(angle_deg))

    def _feed_angle(self, angle_deg: float) -> float:
        self._feed(0.0)
        return float(self._command("feed-angle", angle_deg)[1])

    def integrate(self, seconds: float):
        return self._event(self._integrate, float(seconds))

    def _integrate(self, seconds: float) -> Integration:
        self._feed(seconds)
        v = self._command("integrate", seconds, "defer", wait_s=seconds)
        ident = int(v[0])
        self._deferred[ident] = None
        return Integration(
            t_start_s=float(v[1]), t_end_s=float(v[2]),
            power_k=ChannelValues(partial(self._powers, ident, 0)),
            std_k=ChannelValues(partial(self._powers, ident, 1)),
            enc_az_deg=float(v[4]), enc_el_deg=float(v[5]),
            weather=WeatherReading(*(float(x) for x in v[6:10])), n_samples=int(v[3]))

    def _powers(self, ident: int, which: int) -> dict[str, float]:
        """Power (``which`` 0) or std (1) per channel of a deferred integration: all those
        not fetched yet are fetched together (the antenna computes them together, see the
        module)."""
        values = self._deferred.get(ident)
        if values is not None:
            return values[which]
        waiting = sorted(i for i, v in self._deferred.items() if v is None)
        _, informs = self._request("powers", waiting[0], waiting[-1])
        for msg in informs:
            numbers = [float(a) for a in msg.arguments[1:]]
            self._deferred[int(msg.arguments[0])] = (
                dict(zip(self.channels, numbers[0::2], strict=True)),
                dict(zip(self.channels, numbers[1::2], strict=True)))
        return self._deferred[ident][which]

    def measure_offset(self, seconds: float):
        return self._event(self._camera, float(seconds))

    def _camera(self, seconds: float) -> OffsetReading:
        self._feed(seconds)
        v = self._command("camera", seconds, wait_s=seconds)
        return OffsetReading(
            t_start_s=float(v[0]), t_end_s=float(v[1]), found=v[2] == b"1",
            xel_arcsec=float(v[3]), el_arcsec=float(v[4]), enc_az_deg=float(v[5]),
            enc_el_deg=float(v[6]), weather=WeatherReading(*(float(x) for x in v[7:11])))


class _Encoded(list):
    """Message arguments already encoded (bytes)."""


def _floats(table: np.ndarray) -> _Encoded:
    """The numbers of ``table`` (row by row) as KATCP arguments, encoded as aiokatcp
    encodes a float (``repr``) but without its per-argument dispatch: a program track has
    a thousand of them."""
    return _Encoded(repr(x).encode("ascii") for x in table.ravel().tolist())
