"""A run's figures drawn in two processes forked before the campaign starts.

Drawing the ten figures of ``antsim run`` costs about as much as the 24-hour campaign
itself, and importing matplotlib a good part of that. :meth:`FigureProcess.start` forks a
process as the command starts: it imports matplotlib and :mod:`antsim.figures` and draws a
first figure to nothing (:func:`antsim.figures.warm_up`) while this process simulates on the
other core, then waits. :meth:`FigureProcess.begin` sends it the recordings as soon as the
campaign ends, and it draws the figures of the recordings alone
(:func:`antsim.figures.recording_figure_jobs`) while this process fits.
:meth:`FigureProcess.run_figures` sends it the fits; it forks once more (the copy starts
warmed up, with the data in memory) and the two draw the rest of
:func:`antsim.figures.run_figure_jobs` between them, the costliest first, each taking the
next one not yet taken.

The files are byte-identical to :func:`antsim.figures.run_figures` in this process (each
figure is drawn from the same inputs with matplotlib's style reset, whatever process draws
it). Off Linux, on one core, or with another thread running there is no process and the
caller draws the figures itself; if the process fails, :meth:`FigureProcess.run_figures`
warns and does so too.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["FigureProcess", "recording_figure_options", "rendering_available"]

#: how often the waiting parent checks that the figure process is alive (s)
POLL_S = 0.5
#: relative drawing cost by figure function, as measured on the 1990 run (0.1 s = 1): the
#: costliest are handed out first, so that the two processes end together
_COST = {"histogram_figure": 3.0, "pointing_errors_figure": 2.4, "amplitude_figure": 1.4,
         "sky_distribution_figure": 1.2, "coefficients_figure": 1.2,
         "residual_time_figure": 1.1, "comparison_figure": 1.0,
         "residual_quiver_figure": 0.5}


def recording_figure_options(result) -> dict[str, Any]:
    """The options of a run's figures of the recordings alone
    (:func:`antsim.figures.recording_figure_jobs`): the scenario's name for the titles and
    its scheduler's elevation limit. ``result``: an :class:`antsim.runner.RunResult`.
    Here rather than in :mod:`antsim.figures`, which imports the fitter (scipy): the
    command asks for them before it imports that."""
    scenario = result.scenario
    return {"name": scenario.name,
            "el_limit_deg": scenario.controller.scheduler.elevation_min_deg}


def rendering_available() -> bool:
    """Whether the figures may be drawn in forked processes: Linux (macOS can fork, but
    its system libraries are not safe to use in a forked copy, which is why Python spawns
    there by default), two cores, and no other thread in this process (a fork copies only
    the calling thread, and a lock another one held, such as the import lock, would never
    be released in the copy)."""
    import threading

    return (sys.platform.startswith("linux") and (os.cpu_count() or 1) >= 2
            and threading.active_count() == 1)


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


def _serve(conn, parent_end) -> None:
    """The figure process: import matplotlib; on ("begin", rows, out_dir, options) draw
    :func:`antsim.figures.recording_figure_jobs`; on ("draw", rows, fits, out_dir, options)
    draw the rest of :func:`antsim.figures.run_figure_jobs` (all of it if what was begun
    differs) and answer ("ok", [FigureFile, ...]) or ("error", message)."""
    # the command's end of the pipe, inherited by the fork: closed, so that the command's
    # end (by exit, failure or SIGKILL) reaches this process as EOF and it ends too
    parent_end.close()
    # Ctrl-C reaches the whole process group: the command handles it and ends this process
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from . import figures

    figures.warm_up()  # while the command simulates: neither drawing process pays it
    early: tuple[tuple, list] | None = None
    try:
        while True:
            message = conn.recv()
            if message[0] == "begin":
                _, rows, out_dir, options = message
                try:
                    early = ((out_dir, options),
                             [job() for job in figures.recording_figure_jobs(
                                 rows, out_dir, **options)])
                except Exception:  # drawn (and reported) with the others
                    early = None
                continue
            _, rows, fits, out_dir, options = message
            break
    except EOFError:  # the command ended (or failed) before its figures
        return
    try:
        jobs = figures.run_figure_jobs(rows, fits, out_dir, **options)
        drawn: list = []
        if early is not None:
            (early_dir, early_options), drawn = early
            wanted = {k: options.get(k) for k in early_options}
            if early_dir != out_dir or wanted != early_options:
                drawn = []  # begun with other inputs: drawn again
        conn.send(("ok", drawn + draw_in_two(jobs[len(drawn):])))
    except Exception as err:  # reported to the parent, which draws the figures itself
        conn.send(("error", f"{type(err).__name__}: {err}"))


class FigureProcess:
    """A forked process, ready to draw a run's figures: see the module docstring."""

    def __init__(self) -> None:
        import multiprocessing

        ctx = multiprocessing.get_context("fork")
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=_serve, args=(child, self._conn), daemon=True)
        self._process.start()
        child.close()
        self._answered = False

    @classmethod
    def start(cls) -> FigureProcess | None:
        """The process, or None where figures are better drawn in this process."""
        return cls() if rendering_available() else None

    def begin(self, rows, out_dir: str | Path, **options: Any) -> None:
        """Have the process draw the figures of the recordings alone now
        (:func:`antsim.figures.recording_figure_jobs` with ``options``), while this process
        fits; :meth:`run_figures` with the same directory and options then draws only the
        others. A process that cannot be reached is left to :meth:`run_figures` to report."""
        with contextlib.suppress(OSError, pickle.PicklingError, TypeError, AttributeError):
            self._conn.send(("begin", rows, str(out_dir), options))

    def run_figures(self, rows, fits: Mapping[str, Any], out_dir: str | Path,
                    **options: Any) -> list:
        """:func:`antsim.figures.run_figures` drawn by the process (once: it ends after)."""
        try:
            answer = self._ask(("draw", rows, fits, str(out_dir), options))
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
            self._answered = True
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
        """End the process: it ends by itself once it has answered; before that (the command
        failed, or ends without figures) it is stopped at once."""
        self._conn.close()
        if self._answered:
            self._process.join(timeout=POLL_S)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join()
