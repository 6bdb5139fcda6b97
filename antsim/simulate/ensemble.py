"""Ensembles that scale out: a local process pool by default, or a Dask cluster.

Work is cut into tasks that depend only on their inputs: the deterministic run of a variant
(:func:`task_record`), blocks of members on the shared
schedule (:func:`task_block`) and members simulated in full (:func:`task_full`). Member ``i``
always has the seed :func:`~antsim.simulate.vectorized.member_seed` (plan seed, i) and always
belongs to block ``i // block`` (the block size is a property of the plan, not of the
machine), so the results are the same whatever the number of workers or the engine.

Engines (:func:`make_executor`): ``workers >= 1`` use a
:class:`concurrent.futures.ProcessPoolExecutor` (spawned processes, one BLAS thread each),
``workers == 0`` runs the tasks in this process; ``scheduler="tcp://host:port"`` submits them
to a Dask distributed scheduler (``pip install antsim[dask]``), sending each variant's shared
schedule once. Workers cache one engine (reference world, classified effects) per variant
(:func:`engine_for`); a feature's own tasks (the plan's noise model) use it too.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures import as_completed as futures_as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import simpy

from antsim.world.world import World
from controller.errors import InputError

from ..scenario import Scenario
from .schedule import REFERENCE_SEED
from .vectorized import (
    MemberEngine,
    MemberResults,
    SharedSchedule,
    full_member,
    member_seed,
    record_schedule,
)

__all__ = ["Job", "engine_for", "make_executor", "task_block", "task_full", "task_record"]

#: environment of spawned workers: one BLAS/OpenMP thread each (the pool is the parallelism)
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                     "MKL_NUM_THREADS": "1"}


@contextmanager
def single_threaded() -> Iterator[None]:
    """Processes spawned inside this block start with :data:`SINGLE_THREAD_ENV`; this
    process's environment is restored after it."""
    saved = {k: os.environ.get(k) for k in SINGLE_THREAD_ENV}
    os.environ.update(SINGLE_THREAD_ENV)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@dataclass(frozen=True)
class Job:
    """Everything a worker needs for one variant (picklable). ``token`` names it in the
    workers' caches."""

    token: str
    scenario: Scenario
    quiet: Scenario
    shared: SharedSchedule
    terms: tuple[str, ...]
    fit_name: str
    plan_seed: int


_ENGINES: dict[str, MemberEngine] = {}


def engine_for(job: Job) -> MemberEngine:
    """This process's engine for ``job`` (built once)."""
    engine = _ENGINES.get(job.token)
    if engine is None:
        reference = World(job.quiet, simpy.Environment(), REFERENCE_SEED)
        engine = MemberEngine(job.scenario, job.shared, reference, job.terms, job.fit_name)
        if len(_ENGINES) >= 8:
            _ENGINES.pop(next(iter(_ENGINES)))
        _ENGINES[job.token] = engine
    return engine


# ---------------------------------------------------------------------------------------------
# tasks (module level: picklable by reference)
# ---------------------------------------------------------------------------------------------
def task_record(quiet: Scenario) -> SharedSchedule:
    """The deterministic run of a variant: its shared schedule."""
    return record_schedule(quiet, seed=REFERENCE_SEED)[0]


def task_block(job: Job, members: tuple[int, ...]) -> tuple[MemberResults, list[int]]:
    """Members on the shared schedule; returns their fits and the members to simulate in
    full (all of them when the variant's schedule cannot be shared)."""
    engine = engine_for(job)
    if engine.unshareable:
        return MemberResults.empty(len(job.terms)), list(members)
    seeds = [member_seed(job.plan_seed, m) for m in members]
    return engine.run_block(list(members), seeds)


def task_full(job: Job, member: int) -> MemberResults:
    """One member simulated in full (its own schedule)."""
    return full_member(job.scenario, member, member_seed(job.plan_seed, member), job.terms,
                       job.fit_name)


# ---------------------------------------------------------------------------------------------
# executors
# ---------------------------------------------------------------------------------------------
class Executor:
    """Runs tasks here (one worker)."""

    workers = 1
    description = "this process"

    def share(self, obj: Any) -> Any:
        """A handle to pass ``obj`` to many tasks (sent once where that matters)."""
        return obj

    def submit(self, fn: Callable, *args: Any) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args))
        except BaseException as err:  # delivered when the result is asked for
            future.set_exception(err)
        return future

    def as_completed(self, futures: Iterable) -> Iterator:
        return iter(list(futures))

    def close(self) -> None:
        """Release the workers."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _warm_up(_: int) -> int:
    """Start a new worker: unpickling this function imports this module, and with it the
    simulation, so that the first tasks do not pay for it."""
    return os.getpid()


class PoolExecutor(Executor):
    """A local pool of spawned processes."""

    def __init__(self, workers: int):
        self.workers = workers
        self.description = f"local process pool of {workers} worker{'s' if workers != 1 else ''}"
        with single_threaded():
            self._pool = ProcessPoolExecutor(max_workers=workers,
                                             mp_context=multiprocessing.get_context("spawn"))
            # start the workers now, while the environment says one thread
            list(self._pool.map(_warm_up, range(workers)))

    def submit(self, fn: Callable, *args: Any) -> Future:
        return self._pool.submit(fn, *args)

    def as_completed(self, futures: Iterable) -> Iterator:
        return futures_as_completed(list(futures))

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor(Executor):
    """Tasks on a Dask distributed scheduler at ``address``."""

    def __init__(self, address: str):
        try:
            from distributed import Client
        except ImportError:
            raise InputError("command line", "--scheduler", address,
                             "Dask is not installed", "pip install 'antsim[dask]'") from None
        try:
            self._client = Client(address, timeout="20s", set_as_default=False)
        except (OSError, TimeoutError, ValueError) as err:
            raise InputError("command line", "--scheduler", address,
                             f"cannot connect to a Dask scheduler ({type(err).__name__})",
                             "give its address, e.g. tcp://127.0.0.1:8786") from None
        info = self._client.scheduler_info()
        self.workers = max(1, sum(w.get("nthreads", 1) for w in info["workers"].values()))
        self.description = (f"Dask scheduler {address} ({self.workers} worker "
                            f"thread{'s' if self.workers != 1 else ''})")

    def share(self, obj: Any) -> Any:
        return self._client.scatter(obj, broadcast=True, hash=False)

    def submit(self, fn: Callable, *args: Any) -> Any:
        return self._client.submit(fn, *args, pure=False)

    def as_completed(self, futures: Iterable) -> Iterator:
        from distributed import as_completed

        return iter(as_completed(list(futures), loop=self._client.loop))

    def close(self) -> None:
        self._client.close()


def make_executor(workers: int | None = None, scheduler: str | None = None) -> Executor:
    """The engine asked for: Dask at ``scheduler``, else a pool of ``workers`` processes
    (default: the machine's cores; each single-threaded), or this process for ``workers=0``
    (no start-up cost, but numpy's BLAS may then use several threads per small matrix)."""
    if scheduler:
        return DaskExecutor(scheduler)
    if workers is None:
        workers = os.cpu_count() or 1
    if workers < 0:
        raise InputError("command line", "--workers", workers, "must be >= 0")
    return Executor() if workers == 0 else PoolExecutor(workers)
