"""Members simulated in a second process while the quiet run records their schedule.

The members integrate the shared schedule in time order, one integration after another
(:class:`~antsim.plan.vectorized._MemberRun`), and every random number they use comes from
their own generators, whatever the schedule's length. So they need not wait for the quiet run
to finish: :class:`MemberStream` starts a process that takes the schedule's integrations as
the quiet run records them and integrates the members behind it. On two cores the members'
cost then hides under the quiet run's. The powers are bit-identical to
:meth:`~antsim.plan.vectorized.MemberEngine.simulate` on the finished schedule.

Whether the finished schedule can be shared at all (no search, one integration length) is only
known at its end: the caller checks it with a :class:`MemberEngine` of the whole schedule and
discards the stream's powers when it cannot (:meth:`MemberStream.close`).

:func:`prestart` starts the process before the caller has imported the simulation or read its
inputs, so that the process's own imports (about a second) are done when the schedule starts
to arrive.
"""

from __future__ import annotations

import os
import queue
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..scenario import Scenario
from .workers import single_threaded

__all__ = ["MemberStream", "prestart", "release_prestarted", "stream_available"]

#: integrations per message: few enough messages, small enough to start the members early
BATCH = 32
#: how often the waiting parent checks that the members' process is alive (s)
POLL_S = 0.5


def stream_available(jobs: int) -> bool:
    """Whether a second process may run the members (``jobs`` >= 2 and two cores)."""
    return jobs >= 2 and (os.cpu_count() or 1) >= 2


def _members_process(inbox, outbox) -> None:
    """The second process: takes (scenario, quiet scenario, seeds) from ``inbox``, then the
    integrations arriving there (lists of recorder items, then None); sends ("ok", power,
    std) or ("error", message)."""
    try:
        import simpy

        from ..world import World
        from .ensemble import REFERENCE_SEED
        from .vectorized import MemberEngine, SharedSchedule

        scenario, quiet, seeds = inbox.get()
        reference = World(quiet, simpy.Environment(), REFERENCE_SEED)
        channels = tuple(c.name for c in quiet.receiver.channels)
        engine = MemberEngine(scenario, SharedSchedule.arriving(quiet.duration_s, channels),
                              reference, (), "baseline")
        run = engine.member_run(seeds)
        while (batch := inbox.get()) is not None:
            for item in batch:
                run.integrate(item["t"], item["enc_az"], item["enc_el"], item["state"],
                              item["paths"])
        outbox.put(("ok", *run.result()))
    except Exception as err:  # reported to the parent, which raises it
        outbox.put(("error", f"{type(err).__name__}: {err}"))


class _Helper:
    """A started process waiting for its members' job (it imports while the parent works)."""

    def __init__(self):
        import multiprocessing

        ctx = multiprocessing.get_context("spawn")  # no fork of a process with BLAS threads
        self.inbox = ctx.Queue()  # put() never blocks: the quiet run never waits
        self.outbox = ctx.Queue()
        with single_threaded():
            self.process = ctx.Process(target=_members_process, daemon=True,
                                       args=(self.inbox, self.outbox))
            self.process.start()

    def close(self) -> None:
        """End the process (done, waiting for work, or busy) and release its queues."""
        if self.process.is_alive():
            self.process.terminate()
        self.process.join()
        for q in (self.inbox, self.outbox):
            q.close()
            q.cancel_join_thread()


_PRESTARTED: _Helper | None = None


def prestart(jobs: int) -> None:
    """Start the members' process now, if :func:`stream_available`, so that its imports
    overlap the caller's (``antsim diagnose`` calls this first thing). The next
    :class:`MemberStream` takes it; an unused one ends at exit."""
    global _PRESTARTED
    if _PRESTARTED is None and stream_available(jobs):
        import atexit

        _PRESTARTED = _Helper()
        atexit.unregister(release_prestarted)  # once, however often this is called
        atexit.register(release_prestarted)


def release_prestarted() -> None:
    """End a prestarted process that no stream will use (e.g. the baseline was cached): a
    busy second core would slow this process's multi-threaded numpy several times."""
    global _PRESTARTED
    if _PRESTARTED is not None:
        _PRESTARTED.close()
        _PRESTARTED = None


class MemberStream:
    """A process integrating members ``seeds`` of ``scenario`` behind the quiet run of
    ``quiet``: pass :meth:`send` as the quiet run's ``on_integration``, then :meth:`result`."""

    def __init__(self, scenario: Scenario, quiet: Scenario, seeds: Sequence[int]):
        global _PRESTARTED
        self._helper, _PRESTARTED = (_PRESTARTED or _Helper()), None
        self._inbox, self._outbox = self._helper.inbox, self._helper.outbox
        self._process = self._helper.process
        self._batch: list[dict[str, Any]] = []
        self._inbox.put((scenario, quiet, [int(s) for s in seeds]))

    def send(self, **item: Any) -> None:
        """One recorded integration (the antenna recorder's keywords). The queue pickles
        it later, in its own thread: the arrays and state must not change afterwards (the
        world hands the recorder fresh ones, which the shared schedule keeps too)."""
        self._batch.append({k: item[k] for k in ("t", "enc_az", "enc_el", "state", "paths")})
        if len(self._batch) >= BATCH:
            self._inbox.put(self._batch)
            self._batch = []

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean power and sample std (K), (integrations, members, channels), once the quiet
        run has ended."""
        if self._batch:
            self._inbox.put(self._batch)
            self._batch = []
        self._inbox.put(None)
        while True:
            alive = self._process.is_alive()  # before the wait: a result sent just before
            try:                              # the end is still read
                status, *payload = self._outbox.get(timeout=POLL_S)
                break
            except queue.Empty:
                if not alive:
                    raise RuntimeError("the members' process ended without a result "
                                       f"(exit code {self._process.exitcode})") from None
        if status != "ok":
            raise RuntimeError(f"the members' process failed: {payload[0]}")
        return payload[0], payload[1]

    def close(self) -> None:
        """Stop the process (whether or not its result was taken)."""
        self._helper.close()

    def __enter__(self) -> MemberStream:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
