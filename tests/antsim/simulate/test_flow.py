"""antsim/simulate/flow.py: chains of tasks on one executor."""

from __future__ import annotations

import time
from concurrent.futures import Future

import pytest

from antsim.simulate.ensemble import Executor, PoolExecutor
from antsim.simulate.flow import Flow, Task, running_words


def _slow_square(x, delay_s: float = 0.0):
    time.sleep(delay_s)
    return x * x if isinstance(x, int) else x


def _fail(message: str) -> None:
    raise ValueError(message)


def _chain(name: str, log: list):
    one = yield Task(_slow_square, (2, 0.2), "step")
    several = yield [Task(_slow_square, (k, 0.1 * (3 - k)), "step") for k in range(3)]
    nothing = yield []
    log.append(name)
    return one, several, nothing


@pytest.mark.parametrize("workers", [0, 2])
def test_chains_receive_their_results_in_the_order_they_asked(workers):
    """Two chains at once; the later tasks of a list finish first on a pool of 2, and each
    chain still receives its results in its own order; on_done sees every task."""
    executor = Executor() if workers == 0 else PoolExecutor(workers)
    done, log = [], []
    try:
        flow = Flow(executor, on_done=lambda task, value: done.append(value))
        a, b = flow.start(_chain("a", log)), flow.start(_chain("b", log))
        flow.run()
    finally:
        executor.close()
    assert a.done and b.done
    assert a.result == b.result == (4, [0, 1, 4], [])
    assert sorted(done) == sorted([4, 0, 1, 4] * 2)
    assert sorted(log) == ["a", "b"]


def test_run_until_some_chains_leaves_the_others_running():
    flow = Flow(Executor())
    short = flow.start(_one_step())
    long = flow.start(_chain("long", []))
    flow.run(until=[short])
    assert short.done and short.result == 9
    flow.run()
    assert long.done


def _one_step():
    value = yield Task(_slow_square, (3,))
    return value


def _renaming():
    try:
        yield Task(_fail, ("the task's words",))
    except ValueError as err:
        raise KeyError(f"the chain's words for {err}") from None


def test_a_tasks_error_is_thrown_into_its_chain_which_may_name_it():
    flow = Flow(Executor())
    with pytest.raises(KeyError, match="the chain's words for the task's words"):
        flow.start(_renaming())
        flow.run()


class _Recording(Executor):
    """Runs tasks later, in the order given, recording what it was given when."""

    workers = 1

    def __init__(self):
        self.given: list = []
        self._futures: list[tuple[Future, tuple]] = []

    def submit(self, fn, *args):
        future: Future = Future()
        self.given.append(args)
        self._futures.append((future, (fn, args)))
        return future

    def as_completed(self, futures):
        future, (fn, args) = next((f, c) for f, c in self._futures if f in futures)
        future.set_result(fn(*args))
        self._futures = [(f, c) for f, c in self._futures if f is not future]
        return iter([future])


def test_a_free_worker_takes_the_highest_priority_first():
    """A worker (and one task waiting) at a time: the long chain's second step, asked after
    six short tasks, goes to the worker before the short ones left."""
    executor = _Recording()

    def long():
        yield Task(_slow_square, ("long 1",), priority=2)
        yield Task(_slow_square, ("long 2",), priority=2)

    def short():
        yield [Task(_slow_square, (f"short {k}",)) for k in range(6)]

    flow = Flow(executor)
    flow.start(long())
    flow.start(short())
    flow.run()
    order = [args[0] for args in executor.given]
    assert order[:2] == ["long 1", "short 0"]  # capacity: one running, one waiting
    assert order.index("long 2") == 2, order


@pytest.mark.parametrize(("labels", "words"), [
    (["schedule{s} of 20 days"], "running: schedule of 20 days"),
    (["noise model{s} of 24 hours"] * 3 + ["noise model{s} of 8 hours"],
     "running: 3 noise models of 24 hours and noise model of 8 hours"),
    (["schedule{s} of 8 hours", "schedule{s} of 8 hours", "block{s} of members",
      "noise model{s} of 20 days"],
     "running: 2 schedules of 8 hours, block of members and noise model of 20 days"),
    ([], "")])
def test_running_tasks_are_counted_in_words_once_each(labels, words):
    """One noise model is "noise model", never "1 noise models"; two schedules of the same
    length are counted, not repeated."""
    assert running_words([Task(_slow_square, (), label=x) for x in labels]) == words
