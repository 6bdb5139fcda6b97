"""The alt-az mount as simpy processes: slew, settle, track, offset; limits and cable wrap.

Each axis moves with a trapezoidal velocity profile (maximum speed and acceleration, rest
to rest) and the mount then settles for ``settle_s`` before it reports being on track.
A moving target is met by iterating the slew time against the target's position at arrival.
Azimuth is on a cable wrap (encoder range wider than 360 deg): the mount chooses the turn
that is quickest to reach while leaving ``wrap_margin_s`` of tracking before a limit.

The 45-ft's own slew figures were not found (DESIGN section 5); the scenario states the
values used and their analogues (VLBA: 90 deg/min in azimuth, 30 deg/min in elevation).

An equatorial mount uses the same logic with hour angle as the first axis (its limits around
0; the "wrap" then only maps the trajectory's [0, 360) hour angle onto them) and declination
as the second.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controller.protocol import AntennaError, Trajectory

__all__ = ["AxisConfig", "Mount", "MountConfig", "move_time_s"]


@dataclass(frozen=True)
class AxisConfig:
    speed_deg_s: float
    accel_deg_s2: float
    min_deg: float
    max_deg: float


@dataclass(frozen=True)
class MountConfig:
    """The mount. ``kind`` "altaz": axes ``az`` (on a cable wrap) and ``el``; "equatorial":
    ``az`` is the hour-angle axis (limits around 0, no wrap needed) and ``el`` the
    declination axis: the motion logic is the same for both. ``feed_speed_deg_s``: how fast
    a turnable feed box rotates (assumption: 2 deg/s)."""

    kind: str = "altaz"
    az: AxisConfig = AxisConfig(1.5, 0.5, -90.0, 450.0)
    el: AxisConfig = AxisConfig(0.5, 0.5, 5.0, 90.0)
    settle_s: float = 4.0
    wrap_margin_s: float = 3600.0
    feed_speed_deg_s: float = 2.0


def move_time_s(distance_deg, speed_deg_s: float, accel_deg_s2: float):
    """Rest-to-rest time of a trapezoidal (or triangular) velocity profile (s)."""
    if isinstance(distance_deg, float):  # one move (the simulation's case): plain floats
        d = abs(distance_deg)
        if d <= speed_deg_s ** 2 / accel_deg_s2:
            return 2.0 * math.sqrt(d / accel_deg_s2)
        return d / speed_deg_s + speed_deg_s / accel_deg_s2
    d = np.abs(np.asarray(distance_deg, dtype=float))
    ramp = speed_deg_s ** 2 / accel_deg_s2  # distance covered accelerating + braking
    return np.where(d <= ramp, 2.0 * np.sqrt(d / accel_deg_s2),
                    d / speed_deg_s + speed_deg_s / accel_deg_s2)


class Mount:
    """Axis state and motion commands; positions in encoder degrees."""

    def __init__(self, env, config: MountConfig, park_az_deg: float = 180.0,
                 park_el_deg: float = 45.0):
        self.env = env
        self.config = config
        self.trajectory: Trajectory | None = None
        self.wrap_turns = 0
        self.offset_deg = (0.0, 0.0)
        self.on_track = False
        self.parked = (park_az_deg, park_el_deg)
        self.approach = (1.0, 1.0)
        self.moves = 0
        self._wrap_ref = 0.0

    # ------------------------------------------------------------------ positions
    def commanded_deg(self, t_clock_s) -> tuple[np.ndarray, np.ndarray]:
        """Encoder command (trajectory + offset on the chosen wrap turn) at clock time(s)."""
        if self.trajectory is None:
            az0, el0 = self.parked
            shape = np.shape(t_clock_s)
            return np.full(shape, az0), np.full(shape, el0)
        az, el = self.trajectory(np.asarray(t_clock_s, dtype=float))
        return self._unwrap(az) + self.offset_deg[0], el + self.offset_deg[1]

    def _unwrap(self, az_deg):
        """Trajectory azimuth [0, 360) on the current cable-wrap turn, continuous in time."""
        base = self._wrap_ref
        return base + ((np.asarray(az_deg) - base + 180.0) % 360.0 - 180.0)

    def current_deg(self) -> tuple[float, float]:
        """Encoder position now (the commanded position; the servo holds it)."""
        if self.trajectory is None:
            return self.parked
        az, el = self.commanded_deg(np.array([self.clock()]))
        return float(az[0]), float(el[0])

    def clock(self) -> float:
        return self._clock(self.env.now)

    def _clock(self, t_s: float) -> float:  # replaced by the world when a clock error exists
        return t_s

    # ------------------------------------------------------------------ motion planning
    def _axis_times(self, d_az, d_el):
        c = self.config
        return (move_time_s(d_az, c.az.speed_deg_s, c.az.accel_deg_s2),
                move_time_s(d_el, c.el.speed_deg_s, c.el.accel_deg_s2))

    def _choose_wrap(self, az_target: float, start_az: float, trajectory: Trajectory,
                     t_arrive: float) -> float:
        """Encoder azimuth for ``az_target`` (0..360): quickest turn with tracking margin."""
        c = self.config
        later_az, _ = trajectory(np.array([t_arrive + c.wrap_margin_s]))
        drift = (float(later_az[0]) - az_target + 180.0) % 360.0 - 180.0
        best = None
        for k in range(-3, 4):
            cand = az_target + 360.0 * k
            if not (c.az.min_deg <= cand <= c.az.max_deg):
                continue
            keeps = c.az.min_deg <= cand + drift <= c.az.max_deg
            cost = (0 if keeps else 1, abs(cand - start_az))
            if best is None or cost < best[0]:
                best = (cost, cand)
        if best is None:
            raise AntennaError(f"azimuth {az_target:.2f} deg is outside the cable wrap")
        return best[1]

    def plan_slew(self, trajectory: Trajectory) -> tuple[float, float, float]:
        """Slew time (s, without settle) and the encoder position at arrival."""
        start_az, start_el = self.current_deg()
        now = self.clock()
        t_arrive = now
        az_enc = el = None
        turn = None
        for _ in range(4):  # converge on the moving target
            az, el_arr = trajectory(np.array([t_arrive]))
            el = float(el_arr[0])
            if turn is None:
                az_enc = self._choose_wrap(float(az[0]), start_az, trajectory, t_arrive)
                turn = az_enc - float(az[0])
            else:
                # keep the chosen turn, continuous across 0/360 while the target moves
                az_enc = az_enc + ((float(az[0]) + turn - az_enc + 180.0) % 360.0 - 180.0)
            t_az, t_el = self._axis_times(az_enc - start_az, el - start_el)
            t_arrive = now + float(max(t_az, t_el))
        return t_arrive - now, az_enc, el

    # ------------------------------------------------------------------ commands (processes)
    def track(self, trajectory: Trajectory):
        """simpy process: slew to the trajectory, settle, then track it."""
        c = self.config
        slew_s, az_enc, el = self.plan_slew(trajectory)
        if not (c.el.min_deg <= el <= c.el.max_deg):
            raise AntennaError(
                f"target elevation {el:.2f} deg at arrival is outside the limits "
                f"{c.el.min_deg:g}..{c.el.max_deg:g} deg")
        start_az, start_el = self.current_deg()
        self.approach = (math.copysign(1.0, az_enc - start_az) if az_enc != start_az
                         else self.approach[0],
                         math.copysign(1.0, el - start_el) if el != start_el
                         else self.approach[1])
        self.on_track = False
        self.trajectory = None
        self.parked = (start_az, start_el)  # in transit; readings are not meaningful
        self.moves += 1
        yield self.env.timeout(slew_s + c.settle_s)
        self.trajectory = trajectory
        self._wrap_ref = az_enc
        self.offset_deg = (0.0, 0.0)
        # re-anchor the wrap reference to the trajectory at this instant
        self._wrap_ref = float(self._unwrap(trajectory(np.array([self.clock()]))[0][0]))
        self.on_track = True
        return slew_s + c.settle_s

    def offset_move_s(self, d_az_deg: float, d_el_deg: float) -> float:
        """Time to move from the present offset to (``d_az_deg``, ``d_el_deg``) and settle
        (s), without moving."""
        old_az, old_el = self.offset_deg
        t_az, t_el = self._axis_times(d_az_deg - old_az, d_el_deg - old_el)
        return float(max(t_az, t_el)) + self.config.settle_s

    def set_offset(self, d_az_deg: float, d_el_deg: float):
        """simpy process: move to a new offset from the trajectory and settle."""
        old_az, old_el = self.offset_deg
        duration = self.offset_move_s(d_az_deg, d_el_deg)
        if d_az_deg != old_az:
            self.approach = (math.copysign(1.0, d_az_deg - old_az), self.approach[1])
        if d_el_deg != old_el:
            self.approach = (self.approach[0], math.copysign(1.0, d_el_deg - old_el))
        self.offset_deg = (d_az_deg, d_el_deg)
        self.moves += 1
        yield self.env.timeout(duration)
        return duration
