"""Several pieces of work sharing one executor: each a generator of the tasks it needs next.

A feature writes each piece of its work as a generator ("chain") that yields a :class:`Task`
(or a list of them) and receives its result (or their results, in the same order) when it
is done; what it returns is the chain's result. :class:`Flow` drives any number of chains on
one :class:`~antsim.simulate.ensemble.Executor` at once, so that the workers stay busy with
every chain's tasks (a plan's Monte Carlo members and its answers' long runs side by side),
and reports each task done to the caller (progress). The executor is given about as many
tasks as it has workers, the ones of highest priority first; the rest wait here. An
exception from a task is thrown into its chain, which may name it better; one the chain
lets through ends :meth:`Flow.run`.

Nothing here knows what the tasks compute: the logic stays in the chains; results do not
depend on the order tasks finish in, since each chain receives its results in the order it
asked for them.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Generator, Sequence
from dataclasses import dataclass, field
from typing import Any

from .ensemble import Executor

__all__ = ["Chain", "Flow", "Handle", "Task", "running_words"]


@dataclass(frozen=True)
class Task:
    """A call ``fn(*args)`` for the executor (module-level ``fn``, picklable ``args``);
    ``kind`` and ``label`` say what it is (the caller's progress counts by kind and names
    what is running by label, :func:`running_words`); tasks of a higher ``priority`` go to
    the workers first (the steps of the longest chains: a worker free then takes them, not
    the queue's older and shorter tasks)."""

    fn: Callable[..., Any]
    args: tuple = ()
    kind: str = ""
    label: str = ""
    priority: int = 0


#: a chain: yields a Task (receives its result) or a list of Tasks (receives their results)
Chain = Generator[Task | list[Task], Any, Any]


@dataclass
class Handle:
    """A chain started on a :class:`Flow`: ``done`` once it has returned, with ``result``."""

    chain: Chain
    done: bool = False
    result: Any = None
    _started: bool = False
    _tasks: list[Task] = field(default_factory=list)
    _results: list[Any] = field(default_factory=list)
    _waiting: int = 0
    _single: bool = False


class Flow:
    """Chains driven on ``executor``; ``on_done(task, result)`` is called in this process
    for every task as it finishes (before its chain resumes)."""

    def __init__(self, executor: Executor,
                 on_done: Callable[[Task, Any], None] | None = None):
        self.executor = executor
        self.on_done = on_done
        self._pending: dict[Any, tuple[Handle, int]] = {}  # submitted: future -> task
        self._ready: list[tuple[int, int, Handle, int]] = []  # (-priority, order, task)
        self._order = 0
        #: tasks in the executor at once: one per worker and one waiting, so that a worker
        #: done takes the next at once, and the rest are chosen by priority as they free
        self.capacity = max(1, int(executor.workers)) + 1

    def start(self, chain: Chain) -> Handle:
        """Start ``chain``: run it to its first yield and submit what it asks for."""
        handle = Handle(chain)
        self._advance(handle, None, None)
        return handle

    def running(self) -> list[Task]:
        """The tasks given to the executor and not yet done (running, or next)."""
        return [h._tasks[i] for h, i in self._pending.values()]

    def run(self, until: Sequence[Handle] | None = None,
            tick: Callable[[], None] | None = None) -> None:
        """Wait for tasks and resume their chains until every chain in ``until`` (default:
        every chain started) is done; ``tick`` is called before each wait."""
        def finished() -> bool:
            return until is not None and all(h.done for h in until)

        while (self._pending or self._ready) and not finished():
            if tick is not None:
                tick()
            self._submit()
            future = next(iter(self.executor.as_completed(list(self._pending))))
            handle, i = self._pending.pop(future)
            try:
                value = future.result()
            except Exception as err:  # thrown into its chain, which may name it better
                for other in [f for f, (h, _) in self._pending.items() if h is handle]:
                    del self._pending[other]  # the rest of what it waited for is moot
                    other.cancel()
                self._ready = [r for r in self._ready if r[2] is not handle]
                heapq.heapify(self._ready)
                self._advance(handle, None, err)
                continue
            if self.on_done is not None:
                self.on_done(handle._tasks[i], value)
            handle._results[i] = value
            handle._waiting -= 1
            if handle._waiting == 0:
                results = handle._results
                self._advance(handle, results[0] if handle._single else list(results), None)
        if until is not None and not finished():
            raise RuntimeError("a chain waits for nothing: it yielded no task")

    def _advance(self, handle: Handle, value: Any, error: Exception | None) -> None:
        """Resume ``handle``'s chain with ``value`` (or ``error``) and submit what it asks
        for next; an empty list is answered at once."""
        while True:
            try:
                if error is not None:
                    step = handle.chain.throw(error)
                elif not handle._started:
                    handle._started = True
                    step = next(handle.chain)
                else:
                    step = handle.chain.send(value)
            except StopIteration as stop:
                handle.done, handle.result = True, stop.value
                handle._tasks, handle._results = [], []
                return
            error = None
            tasks = [step] if isinstance(step, Task) else list(step)
            handle._single = isinstance(step, Task)
            handle._tasks, handle._results = tasks, [None] * len(tasks)
            handle._waiting = len(tasks)
            if tasks:
                for i, task in enumerate(tasks):
                    heapq.heappush(self._ready, (-task.priority, self._order, handle, i))
                    self._order += 1
                self._submit()
                return
            value = []

    def _submit(self) -> None:
        """Give the executor the waiting tasks of highest priority while it has room."""
        while self._ready and len(self._pending) < self.capacity:
            _, _, handle, i = heapq.heappop(self._ready)
            task = handle._tasks[i]
            self._pending[self.executor.submit(task.fn, *task.args)] = (handle, i)


def running_words(tasks: Sequence[Task]) -> str:
    """What ``tasks`` are, counted by label, in the order they first appear: "running:
    schedule of 20 days, 2 noise models of 8 hours and block of members". A label marks
    where its plural takes an "s" with ``{s}`` ("block{s} of members")."""
    counts: dict[str, int] = {}
    for task in tasks:
        if task.label:
            counts[task.label] = counts.get(task.label, 0) + 1
    if not counts:
        return ""
    words = []
    for label, n in counts.items():
        words.append(label.replace("{s}", "") if n == 1
                     else f"{n} " + label.replace("{s}", "s"))
    shown = words if len(words) == 1 else [", ".join(words[:-1]) + " and " + words[-1]]
    return "running: " + shown[0]
