"""The quiet run in a second process, its schedule streamed to the members as it is recorded.

The baseline of ``antsim diagnose`` is the quiet (noise-free) campaign of the scenario, whose
schedule its members share (:mod:`antsim.simulate.schedule`), and the members integrated on that
schedule (:class:`~antsim.simulate.vectorized.MemberEngine`). The members integrate the schedule
in time order, a scan's integrations at a time, and every random number they use comes from
their own generators whatever the schedule's length, so they need not wait for the quiet run
to end.

:func:`prestart` forks a process that runs the quiet campaign of a scenario as soon as the
scenario is read, and sends each recorded integration back. The command meanwhile imports the
analysis and reads the recordings; :class:`ScheduleStream` then integrates the members behind
the quiet run as the integrations arrive, and takes the finished schedule at its end. On two
cores the command's own start-up and the members' cost both hide under the quiet run. The
powers are bit-identical to :meth:`~antsim.simulate.vectorized.MemberEngine.simulate` on the
finished schedule.

The process is forked, not spawned: it starts with this process's imports done (a spawned one
pays about a second of imports before its first integration). Whether the schedule can be
shared at all (no search, one integration length) is only known at its end; the caller checks
it as before and discards the members' powers when it cannot.
"""

from __future__ import annotations

import atexit
import multiprocessing
import os
import queue
from collections.abc import Iterator, Sequence
from dataclasses import replace
from typing import Any

import simpy

from antsim.world.world import World

from ..scenario import Scenario
from .schedule import REFERENCE_SEED, quiet_scenario, record_schedule
from .vectorized import MemberEngine, SharedSchedule

__all__ = ["ScheduleStream", "prestart", "release_prestarted", "stream_available"]

#: integrations per message: few enough messages, small enough to start the members early
BATCH = 32
#: how often the waiting parent checks that the quiet run's process is alive (s)
POLL_S = 0.5
#: the recorder's keywords that the members need
ITEM_KEYS = ("t", "enc_az", "enc_el", "state", "paths")


def stream_available(jobs: int) -> bool:
    """Whether a second process may run the quiet campaign (``jobs`` >= 2, two cores, and
    an operating system that forks)."""
    return (jobs >= 2 and (os.cpu_count() or 1) >= 2
            and "fork" in multiprocessing.get_all_start_methods())


def _quiet_run_process(quiet: Scenario, seed: int, outbox) -> None:
    """The second process: the quiet campaign of ``quiet``, its integrations sent in batches
    ("items", [...]), then ("done", the schedule without its integrations) or ("error",
    message)."""
    try:
        batch: list[dict[str, Any]] = []

        def send(**item: Any) -> None:
            nonlocal batch
            batch.append({k: item[k] for k in ITEM_KEYS})
            if len(batch) >= BATCH:
                outbox.put(("items", batch))
                batch = []  # the queue pickles the sent list later, in its own thread

        shared, _ = record_schedule(quiet, seed=seed, on_integration=send)
        if batch:
            outbox.put(("items", batch))
        outbox.put(("done", replace(shared, t=[], enc_az=[], enc_el=[], state=[], paths=[])))
    except Exception as err:  # reported to the parent, which raises it
        outbox.put(("error", f"{type(err).__name__}: {err}"))


class ScheduleStream:
    """The quiet campaign of ``quiet`` (seed ``seed``) running in a forked process: iterate
    :meth:`items` for its integrations as they are recorded, then take :meth:`schedule`."""

    def __init__(self, quiet: Scenario, seed: int):
        self.quiet, self.seed = quiet, int(seed)
        #: the scenario ``quiet`` was made from, when the caller says (see :func:`take`)
        self.source: Scenario | None = None
        ctx = multiprocessing.get_context("fork")
        self._outbox = ctx.Queue()
        self._process = ctx.Process(target=_quiet_run_process, daemon=True,
                                    args=(quiet, self.seed, self._outbox))
        self._process.start()
        self._items: list[dict[str, Any]] = []
        self._done = None

    def items(self) -> Iterator[dict[str, Any]]:
        """The recorded integrations in time order (the recorder's keywords ``t``,
        ``enc_az``, ``enc_el``, ``state``, ``paths``), as they arrive. Raises RuntimeError if
        the process fails or ends without finishing."""
        while self._done is None:
            kind, payload = self._next()
            if kind == "items":
                self._items.extend(payload)
                yield from payload
            elif kind == "done":
                self._done = payload
            else:
                raise RuntimeError(f"the quiet run's process failed: {payload}")

    def schedule(self):
        """The finished :class:`~antsim.simulate.schedule.SharedSchedule` (after :meth:`items`
        is exhausted; it drains the stream first if not)."""
        for _ in self.items():
            pass
        items = self._items
        return replace(self._done, **{k: [it[k] for it in items] for k in ITEM_KEYS})

    def _next(self) -> tuple[str, Any]:
        while True:
            alive = self._process.is_alive()  # before the wait: a message sent just before
            try:                              # the end is still read
                return self._outbox.get(timeout=POLL_S)
            except queue.Empty:
                if not alive:
                    raise RuntimeError("the quiet run's process ended without its schedule "
                                       f"(exit code {self._process.exitcode})") from None

    def close(self) -> None:
        """End the process (finished or not) and release its queue."""
        if self._process.is_alive():
            self._process.terminate()
        self._process.join()
        self._outbox.close()
        self._outbox.cancel_join_thread()

    def __enter__(self) -> ScheduleStream:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


_PRESTARTED: ScheduleStream | None = None


def prestart(jobs: int, scenario: Scenario) -> None:
    """Start the quiet campaign of ``scenario`` now in a second process, if
    :func:`stream_available`, so that it runs while the caller imports and reads its inputs
    (``antsim diagnose`` calls this as soon as the scenario is read). :func:`take` hands it
    to the baseline; an unused one ends at exit or at :func:`release_prestarted`."""
    global _PRESTARTED
    if _PRESTARTED is None and stream_available(jobs):
        _PRESTARTED = ScheduleStream(quiet_scenario(scenario), REFERENCE_SEED)
        _PRESTARTED.source = scenario
        atexit.unregister(release_prestarted)  # once, however often this is called
        atexit.register(release_prestarted)


def take(scenario: Scenario, seed: int) -> ScheduleStream:
    """The prestarted stream if it runs the quiet campaign of ``scenario`` (the same object,
    or an equal one) with ``seed``, else a new one."""
    global _PRESTARTED
    stream, _PRESTARTED = _PRESTARTED, None
    if stream is not None and not (stream.seed == int(seed) and (
            stream.source is scenario or stream.quiet == quiet_scenario(scenario))):
        stream.close()
        stream = None
    return stream if stream is not None else ScheduleStream(quiet_scenario(scenario), seed)


def release_prestarted() -> None:
    """End a prestarted quiet run that no baseline will use (e.g. the baseline was cached):
    a busy second core would slow this process's multi-threaded numpy several times."""
    global _PRESTARTED
    if _PRESTARTED is not None:
        _PRESTARTED.close()
        _PRESTARTED = None


def stream_members(stream: ScheduleStream, scenario: Scenario,
                   seeds: Sequence[int]):
    """Members ``seeds`` of ``scenario`` integrated behind ``stream``'s quiet run: returns
    the finished schedule and the members' (power, std), (integrations, members, channels).
    Raises RuntimeError if the stream fails or the members cannot follow it."""
    quiet = stream.quiet
    reference = World(quiet, simpy.Environment(), stream.seed)
    channels = tuple(c.name for c in quiet.receiver.channels)
    engine = MemberEngine(scenario, SharedSchedule.arriving(quiet.duration_s, channels),
                          reference, (), "baseline")
    run = engine.member_run([int(s) for s in seeds])
    for item in stream.items():
        _following(run.integrate, item["t"], item["enc_az"], item["enc_el"], item["state"],
                   item["paths"])
    result = _following(run.result)  # the last block
    return stream.schedule(), result


def _following(call, *args):
    """``call(*args)`` for the members; whatever stops them becomes a RuntimeError (e.g. a
    schedule that cannot be shared: the caller then redoes it in one process)."""
    try:
        return call(*args)
    except Exception as err:
        raise RuntimeError("the members could not follow the quiet run "
                           f"({type(err).__name__}: {err})") from err
