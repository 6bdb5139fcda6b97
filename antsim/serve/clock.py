"""How simulated time passes in `antsim serve`: virtual, real time, or accelerated.

* ``virtual``: simulated time advances only while a command is served, by exactly what the
  command takes (the simpy environment runs until the command's event): a 24-hour campaign
  takes as long as its computing, and the project's controller driven over the wire
  reproduces the in-process run to the bit.
* ``realtime``: simulated time follows the wall clock from the moment the server starts; a
  15 s integration replies after 15 s, and the antenna keeps tracking between commands.
* ``xK`` (K > 0, e.g. ``x10``): as ``realtime``, K simulated seconds per wall second.

Simulated time never passes the end of what the world can simulate (the scenario's
duration plus the ephemeris margin): commands that would run beyond it are refused.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["ClockSpec", "OutOfTimeError", "RealtimeClock", "VirtualClock", "make_clock",
           "parse_clock"]

#: the real-time clock advances the world and refreshes sensors at least this often (s)
TICK_S = 0.1


@dataclass(frozen=True)
class ClockSpec:
    """``virtual``, or real time accelerated ``factor`` times (``realtime``: factor 1)."""

    text: str
    factor: float  # simulated seconds per wall second; inf for virtual

    @property
    def virtual(self) -> bool:
        return math.isinf(self.factor)


#: the accelerations a real-time clock may have: below, a minute of simulation takes more
#: than a day; above, a 24-hour campaign passes in a tenth of a second
MIN_FACTOR, MAX_FACTOR = 1e-3, 1e6


def parse_clock(text: str) -> ClockSpec:
    """A clock specification; raises ValueError saying what is accepted."""
    spec = text.strip().lower()
    if spec == "virtual":
        return ClockSpec("virtual", math.inf)
    if spec == "realtime":
        return ClockSpec("realtime", 1.0)
    if spec.startswith("x"):
        try:
            factor = float(spec[1:])
        except ValueError:
            factor = math.nan
        if MIN_FACTOR <= factor <= MAX_FACTOR:
            return ClockSpec(f"x{factor:g}", factor)
    raise ValueError(f"use virtual, realtime, or xK with K a positive number within "
                     f"{MIN_FACTOR:g}..{MAX_FACTOR:g} (x10: ten simulated seconds per second)")


class _Clock:
    """The part both clocks share: the world's environment and where time must stop."""

    def __init__(self, env, end_s: float):
        self.env = env
        self.end_s = float(end_s)

    def sync(self) -> None:
        """Bring simulated time up to the clock's present (real-time clocks)."""

    def check_room(self, seconds: float, what: str) -> None:
        """Refuse a command that would run past the end of the simulation; ``what`` names
        the command (and the argument that sets its time)."""
        end = self.env.now + seconds
        if end > self.end_s:
            shown = f"{end:.1f}" if abs(end) < 1e9 else f"{end:.6g}"
            raise OutOfTimeError(f"{what} would end at {shown} s, after the end of the "
                                 f"simulation ({self.end_s:.1f} s: the scenario's duration "
                                 "plus an hour's margin)")


class OutOfTimeError(RuntimeError):
    """A command that would run past the end of the simulation."""


class VirtualClock(_Clock):
    """Simulated time advances only while commands run."""

    spec = ClockSpec("virtual", math.inf)

    async def complete(self, event):
        """Run the world until ``event`` (a command's simpy event) is processed; its value,
        or its exception raised."""
        return self.env.run(until=event)


class RealtimeClock(_Clock):
    """Simulated time follows the wall clock, ``spec.factor`` times faster."""

    def __init__(self, env, end_s: float, spec: ClockSpec,
                 wall: Callable[[], float] = time.monotonic):
        super().__init__(env, end_s)
        self.spec = spec
        self._wall = wall
        self._wall0 = wall()
        self._sim0 = float(env.now)

    def present_s(self) -> float:
        """Simulated time now according to the wall clock (capped at the end)."""
        return min(self._sim0 + (self._wall() - self._wall0) * self.spec.factor, self.end_s)

    def sync(self) -> None:
        target = self.present_s()
        if target > self.env.now:
            self.env.run(until=target)

    async def complete(self, event):
        """Wait (in wall time) until ``event`` has been processed; its value, or its
        exception raised."""
        outcome: asyncio.Future = asyncio.get_running_loop().create_future()

        def done(ev) -> None:
            ev.defused = True  # the failure goes to the request, not to the world
            if not outcome.done():
                outcome.set_result(ev)

        if event.callbacks is None:  # already processed
            done(event)
        else:
            event.callbacks.append(done)
        while not outcome.done():
            self.sync()
            if outcome.done():
                break
            if self.env.now >= self.end_s:
                raise OutOfTimeError(f"the simulation ended ({self.end_s:.1f} s) before "
                                     "the command completed")
            await asyncio.sleep(self.sleep_s())
        ev = outcome.result()
        if not ev.ok:
            raise ev.value
        return ev.value

    def sleep_s(self) -> float:
        """Wall time until the next event or the next tick, whichever is first (s)."""
        gap = self.env.peek() - self.env.now
        return max(0.0, min(TICK_S, gap / self.spec.factor))

    async def run(self, on_tick: Callable[[], None], stopped: asyncio.Event) -> None:
        """Keep simulated time in step with the wall clock until ``stopped``."""
        while not stopped.is_set():
            self.sync()
            on_tick()
            await asyncio.sleep(self.sleep_s())


def make_clock(spec: ClockSpec, env, end_s: float) -> VirtualClock | RealtimeClock:
    return VirtualClock(env, end_s) if spec.virtual else RealtimeClock(env, end_s, spec)
