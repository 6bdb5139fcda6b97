"""A run's outputs written by a process forked before the campaign starts, its figures
drawn in two.

After the campaign, ``antsim run`` fits the recordings (importing the fitter: scipy), writes
the fits, tables and model, and draws ten figures, which cost more than the 24-hour campaign
itself. :meth:`OutputProcess.start` forks a process as the command starts; while this
process simulates on the other core, it imports matplotlib, the fitter and
:mod:`antsim.run.outputs`, and draws a first figure to nothing (:func:`antsim.figures.run.warm_up`),
then waits. :meth:`OutputProcess.write_outputs` sends it the run's result as soon as the
campaign ends. It forks once more at once (:class:`SecondDrawer`): the copy draws the
figures of the recordings alone (:func:`antsim.figures.run.recording_figure_jobs`) while the
process fits and writes the files of :func:`antsim.run.outputs.write_outputs`; then the two draw
the rest of :func:`antsim.figures.run.run_figure_jobs` between them, the costliest first, each
taking the next one not yet taken. The command waits for the summary line.

The files are byte-identical to those of :func:`antsim.run.outputs.write_outputs` in this process
(the same code on the same inputs; each figure is drawn with matplotlib's style reset,
whatever process draws it). Off Linux, on one core, or with another thread running there is
no process and the caller writes the outputs itself; if the process fails,
:meth:`OutputProcess.write_outputs` warns and does so too.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
import threading
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["OutputProcess", "SecondDrawer", "recording_figure_options",
           "rendering_available"]

#: how often the waiting command checks that the output process is alive (s)
POLL_S = 0.5
#: relative drawing cost by figure function, as measured on the 1990 run (0.1 s = 1): the
#: costliest are handed out first, so that the two processes end together
_COST = {"histogram_figure": 3.0, "pointing_errors_figure": 2.4, "amplitude_figure": 1.4,
         "sky_distribution_figure": 1.2, "coefficients_figure": 1.2,
         "residual_time_figure": 1.1, "comparison_figure": 1.0,
         "residual_quiver_figure": 0.5}


def recording_figure_options(result) -> dict[str, Any]:
    """The options of a run's figures of the recordings alone
    (:func:`antsim.figures.run.recording_figure_jobs`): the scenario's name for the titles and
    its scheduler's elevation limit. ``result``: an :class:`antsim.run.runner.RunResult`.
    One function for the report and :class:`SecondDrawer`, which must agree on them."""
    scenario = result.scenario
    return {"name": scenario.name,
            "el_limit_deg": scenario.controller.scheduler.elevation_min_deg}


def rendering_available() -> bool:
    """Whether the figures may be drawn in forked processes: Linux (macOS can fork, but
    its system libraries are not safe to use in a forked copy, which is why Python spawns
    there by default), two cores, and no other thread in this process (a fork copies only
    the calling thread, and a lock another one held, such as the import lock, would never
    be released in the copy)."""
    return (sys.platform.startswith("linux") and (os.cpu_count() or 1) >= 2
            and threading.active_count() == 1)


def draw_order(jobs: list, first: int = 0) -> list[int]:
    """Indices of the figure ``jobs`` in drawing order: the ``first`` ones as they are, then
    the rest costliest first (:data:`_COST`), so that two processes end together."""
    rest = sorted(range(first, len(jobs)),
                  key=lambda i: -_COST.get(jobs[i].func.__name__, 1.0))
    return list(range(first)) + rest


class SecondDrawer:
    """In the output process: a forked copy of it that draws the figures of the recordings
    alone (:func:`antsim.figures.run.recording_figure_jobs`) at once, while this process fits,
    then shares the other figures with it in :meth:`run_figures` (each process takes the next
    figure not yet taken). Use as a context manager: leaving it ends the copy.

    ``result``: the :class:`antsim.run.runner.RunResult` whose figures go to
    ``result.out_dir / "figures"``.
    """

    def __init__(self, result) -> None:
        import multiprocessing

        from .figures import run as figures

        ctx = multiprocessing.get_context("fork")
        self.rows = result.rows
        self.out_dir = str(Path(result.out_dir) / "figures")
        self.early_options = recording_figure_options(result)
        self.early = figures.recording_figure_jobs(self.rows, self.out_dir,
                                                   **self.early_options)
        self.counter = ctx.Value("i", 0)
        fits_in, self._fits_out = ctx.Pipe(duplex=False)  # this process -> the copy
        self._drawn_in, drawn_out = ctx.Pipe(duplex=False)  # the copy -> this process
        self._parent = os.getpid()
        self.pid = os.fork()
        if self.pid == 0:  # the copy: draw, send what it drew, leave without exit hooks
            status = 1
            try:
                self._fits_out.close()
                self._drawn_in.close()
                try:
                    drawn = self._take(lambda: self._jobs_from(fits_in), in_copy=True)
                    drawn_out.send(("ok", drawn))
                    status = 0
                except BaseException as err:
                    drawn_out.send(("error", f"{type(err).__name__}: {err}"))
            finally:
                os._exit(status)
        fits_in.close()
        drawn_out.close()
        _second_drawers.add(self.pid)

    def _jobs_from(self, fits_in) -> list | None:
        """The copy's figure jobs, once this process has sent the fits (None: it never
        will, having failed before)."""
        from .figures import run as figures

        try:
            fits, options = pickle.loads(fits_in.recv_bytes())
        except EOFError:
            return None
        return figures.run_figure_jobs(self.rows, fits, self.out_dir, **options)

    def _take(self, get_jobs, in_copy: bool = False) -> dict[int, Any]:
        """Draw figures, each the next not yet taken by either process: first those of the
        recordings alone, then, with the jobs ``get_jobs()`` gives, the others. The copy
        stops when the process it was forked from has gone (killed without its handler)."""
        done: dict[int, Any] = {}
        order: list[int] | None = None
        jobs: list | None = None
        n_early = len(self.early)
        while True:
            if in_copy and os.getppid() != self._parent:
                os._exit(1)
            with self.counter.get_lock():
                k = self.counter.value
                self.counter.value = k + 1
            if k < n_early:
                done[k] = self.early[k]()
                continue
            if jobs is None:
                jobs = get_jobs()
                if jobs is None:
                    return done
                order = draw_order(jobs, n_early)
            if k >= len(order):
                return done
            done[order[k]] = jobs[order[k]]()

    def run_figures(self, rows, fits: Mapping[str, Any], out_dir: str | Path,
                    **options: Any) -> list:
        """:func:`antsim.figures.run.run_figures` drawn by this process and the copy; for the
        run this drawer was made for (anything else is a programming error)."""
        from .figures import run as figures

        early = {k: options.get(k) for k in self.early_options}
        if str(out_dir) != self.out_dir or early != self.early_options or rows is not self.rows:
            raise RuntimeError("the figures asked for are not those of the run begun")
        try:
            message = pickle.dumps((fits, options))
        except (pickle.PicklingError, TypeError, AttributeError) as err:
            raise RuntimeError(f"the fits cannot be sent to the second drawer: {err}") from None
        # sent by a thread: the fits are larger than a pipe holds, and the copy reads them
        # only when it has drawn the figures of the recordings (a plain send waited for that)
        sender = threading.Thread(target=self._send_quietly, args=(message,), daemon=True)
        sender.start()
        jobs = figures.run_figure_jobs(rows, fits, out_dir, **options)
        if [j.func for j in jobs[:len(self.early)]] != [j.func for j in self.early]:
            raise RuntimeError("the figures of the recordings are not the first figures")
        mine = self._take(lambda: jobs)
        try:
            kind, theirs = self._drawn_in.recv()
        except EOFError:
            kind, theirs = "error", "the second drawing process ended without an answer"
        sender.join()
        if kind != "ok":
            raise RuntimeError(theirs)
        mine.update(theirs)
        return [mine[i] for i in range(len(jobs))]

    def _send_quietly(self, message: bytes) -> None:
        with contextlib.suppress(OSError):  # the copy ended: its answer says why
            self._fits_out.send_bytes(message)

    def __enter__(self) -> SecondDrawer:
        return self

    def __exit__(self, exc_type, *exc) -> None:
        if exc_type is not None:  # this process failed: the copy's figures are not wanted
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, signal.SIGKILL)
        self._fits_out.close()  # a copy still waiting for the fits sees EOF and ends
        self._drawn_in.close()
        os.waitpid(self.pid, 0)
        _second_drawers.discard(self.pid)


#: the pids of this process's second drawers, stopped with it (:func:`_stop`)
_second_drawers: set[int] = set()


def _stop(signum: int, frame) -> None:
    """SIGTERM in the output process (the command stops it: interrupted, or failed): its
    second drawer goes with it, at once, not after the figures it has in hand."""
    for pid in _second_drawers:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    os._exit(128 + signum)


def _serve(conn, parent_end) -> None:
    """The output process: import matplotlib and the fitter; on ("outputs", result) write
    the run's outputs with :class:`SecondDrawer` and answer ("ok", summary) or ("error",
    message)."""
    # the command's end of the pipe, inherited by the fork: closed, so that the command's
    # end (by exit, failure or SIGKILL) reaches this process as EOF and it ends too
    parent_end.close()
    # Ctrl-C reaches the whole process group: the command handles it and ends this process
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop)
    from .figures import run as figures
    from .run import outputs, report  # noqa: F401  (imported while the command simulates)

    figures.warm_up()  # neither drawing process pays it
    try:
        _, result = conn.recv()
    except EOFError:  # the command ended (or failed) before its outputs
        return
    try:
        with SecondDrawer(result) as drawer:
            summary = outputs.write_outputs(result, report=True, renderer=drawer)
        conn.send(("ok", summary))
    except Exception as err:  # reported to the command, which writes the outputs itself
        conn.send(("error", f"{type(err).__name__}: {err}"))


class OutputProcess:
    """A forked process, ready to write a run's outputs: see the module docstring."""

    def __init__(self) -> None:
        import multiprocessing

        ctx = multiprocessing.get_context("fork")
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=_serve, args=(child, self._conn), daemon=True)
        self._process.start()
        child.close()
        self._answered = False

    @classmethod
    def start(cls) -> OutputProcess | None:
        """The process, or None where the outputs are better written in this process."""
        return cls() if rendering_available() else None

    def write_outputs(self, result) -> str:
        """:func:`antsim.run.outputs.write_outputs` of ``result`` (an
        :class:`antsim.run.runner.RunResult`) with the report, written by the process (once: it
        ends after); its summary. If the process fails, a warning, and they are written
        here."""
        try:
            return self._ask(("outputs", result.portable()))
        except RuntimeError as err:
            warnings.warn(f"writing the outputs here: {err}", RuntimeWarning, stacklevel=2)
            from .run.outputs import write_outputs

            return write_outputs(result, report=True)

    def _ask(self, request) -> str:
        try:
            try:
                self._conn.send(request)
            except (pickle.PicklingError, TypeError, AttributeError) as err:
                raise RuntimeError(f"the run cannot be sent: {err}") from None
            while not self._conn.poll(POLL_S):
                if not self._process.is_alive() and not self._conn.poll(0):
                    raise EOFError
            kind, payload = self._conn.recv()
            self._answered = True
        except (EOFError, OSError):  # ended before or while it was asked
            self._process.join(timeout=POLL_S)
            raise RuntimeError("the output process ended without an answer (exit code "
                               f"{self._process.exitcode})") from None
        finally:
            self.close()
        if kind != "ok":
            raise RuntimeError(f"the output process failed: {payload}")
        return payload

    def close(self) -> None:
        """End the process: it ends by itself once it has answered; before that (the command
        failed, or ends without outputs) it is stopped at once."""
        self._conn.close()
        if self._answered:
            self._process.join(timeout=POLL_S)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join()
