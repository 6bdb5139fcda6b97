"""A run's figures drawn in two processes forked before the campaign starts.

Drawing the ten figures of ``antsim run`` costs about as much as the 24-hour campaign
itself, and importing matplotlib a good part of that. :meth:`FigureProcess.start` forks a
process as the command starts: it imports matplotlib and :mod:`antsim.figures` and draws a
first figure to nothing (:func:`antsim.figures.warm_up`) while this process simulates on the
other core, then waits. :meth:`FigureProcess.run_figures` sends it the recordings and fits;
it forks once more (the copy starts warmed up, with the data in memory) and the two draw
the figures of :func:`antsim.figures.run_figure_jobs` between them, the costliest first,
each taking the next one not yet taken.

The files are byte-identical to :func:`antsim.figures.run_figures` in this process (each
figure is drawn from the same inputs with matplotlib's style reset, whatever process draws
it). Where the operating system does not fork, or on one core, there is no process and the
caller draws the figures itself; if the process fails, :meth:`FigureProcess.run_figures`
warns and does so too.
"""

from __future__ import annotations

import os
import pickle
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["FigureProcess", "rendering_available"]

#: how often the waiting parent checks that the figure process is alive (s)
POLL_S = 0.5
#: relative drawing cost by figure function, as measured on the 1990 run (0.1 s = 1): the
#: costliest are handed out first, so that the two processes end together
_COST = {"histogram_figure": 3.0, "pointing_errors_figure": 2.4, "amplitude_figure": 1.4,
         "sky_distribution_figure": 1.2, "coefficients_figure": 1.2,
         "residual_time_figure": 1.1, "comparison_figure": 1.0,
         "residual_quiver_figure": 0.5}


def rendering_available() -> bool:
    """Whether the figures may be drawn in forked processes: an operating system that
    forks, two cores, and no other thread in this process (a fork copies only the calling
    thread, and a lock another one held, such as the import lock, would never be released
    in the copy)."""
    import multiprocessing
    import threading

    return ((os.cpu_count() or 1) >= 2 and threading.active_count() == 1
            and "fork" in multiprocessing.get_all_start_methods())


def _take_jobs(jobs: list, order: list[int], counter) -> dict[int, Any]:
    """Draw jobs in ``order``, each the next not yet taken by either process."""
    done = {}
    while True:
        with counter.get_lock():
            k = counter.value
            counter.value = k + 1
        if k >= len(order):
            return done
        done[order[k]] = jobs[order[k]]()


def draw_in_two(jobs: list) -> list:
    """Run the figure ``jobs`` (calls returning a FigureFile) in this process and a forked
    copy of it; their results in the order of ``jobs``."""
    import multiprocessing

    ctx = multiprocessing.get_context("fork")
    order = sorted(range(len(jobs)), key=lambda i: -_COST.get(jobs[i].func.__name__, 1.0))
    counter = ctx.Value("i", 0)
    receive, send = ctx.Pipe(duplex=False)
    pid = os.fork()
    if pid == 0:  # the copy: draw, send what it drew, and leave without running exit hooks
        status = 1
        try:
            receive.close()
            try:
                send.send(("ok", _take_jobs(jobs, order, counter)))
                status = 0
            except BaseException as err:
                send.send(("error", f"{type(err).__name__}: {err}"))
        finally:
            os._exit(status)
    send.close()
    try:
        mine = _take_jobs(jobs, order, counter)
        try:
            kind, theirs = receive.recv()
        except EOFError:
            kind, theirs = "error", "the second drawing process ended without an answer"
    finally:
        os.waitpid(pid, 0)
    if kind != "ok":
        raise RuntimeError(theirs)
    mine.update(theirs)
    return [mine[i] for i in range(len(jobs))]


def _serve(conn) -> None:
    """The figure process: import matplotlib, then draw what is asked and answer ("ok",
    [FigureFile, ...]) or ("error", message)."""
    from . import figures

    figures.warm_up()  # while the command simulates: neither drawing process pays it
    try:
        rows, fits, out_dir, options = conn.recv()
    except EOFError:  # the command ended (or failed) before its figures
        return
    try:
        conn.send(("ok", draw_in_two(figures.run_figure_jobs(rows, fits, out_dir,
                                                             **options))))
    except Exception as err:  # reported to the parent, which draws the figures itself
        conn.send(("error", f"{type(err).__name__}: {err}"))


class FigureProcess:
    """A forked process, ready to draw a run's figures: see the module docstring."""

    def __init__(self) -> None:
        import multiprocessing

        ctx = multiprocessing.get_context("fork")
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=_serve, args=(child,), daemon=True)
        self._process.start()
        child.close()

    @classmethod
    def start(cls) -> FigureProcess | None:
        """The process, or None where figures are better drawn in this process."""
        return cls() if rendering_available() else None

    def run_figures(self, rows, fits: Mapping[str, Any], out_dir: str | Path,
                    **options: Any) -> list:
        """:func:`antsim.figures.run_figures` drawn by the process (once: it ends after)."""
        try:
            answer = self._ask((rows, fits, str(out_dir), options))
        except RuntimeError as err:
            warnings.warn(f"drawing the figures here: {err}", RuntimeWarning, stacklevel=2)
            from .figures import run_figures

            return run_figures(rows, fits, out_dir, **options)
        return answer

    def _ask(self, request) -> list:
        try:
            try:
                self._conn.send(request)
            except (pickle.PicklingError, TypeError, AttributeError) as err:
                raise RuntimeError(f"the figures' inputs cannot be sent: {err}") from None
            while not self._conn.poll(POLL_S):
                if not self._process.is_alive() and not self._conn.poll(0):
                    raise EOFError
            kind, payload = self._conn.recv()
        except (EOFError, OSError):  # ended before or while it was asked
            self._process.join(timeout=POLL_S)
            raise RuntimeError("the figure process ended without an answer (exit code "
                               f"{self._process.exitcode})") from None
        finally:
            self.close()
        if kind != "ok":
            raise RuntimeError(f"the figure process failed: {payload}")
        return payload

    def close(self) -> None:
        """End the process (it ends by itself once it has answered)."""
        self._conn.close()
        self._process.join(timeout=POLL_S)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join()
