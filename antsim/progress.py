"""Progress of long work: a tqdm bar on a terminal, a line every few seconds off one.

A command opens one :class:`Progress` for its whole run and names each stage as it starts
(``stage("members", total=800, unit="member")``), counting where it can (``advance``). So
that no stage looks stuck, a daemon thread ticks about once a second: on a terminal it
redraws the bar (the elapsed time moves while a stage has nothing to count); off a terminal
(a pipe, a CI log) it writes one line to stderr whenever :data:`EVERY_S` seconds have passed
since the last, naming the stage, its count and the time so far. A command that ends within
that time writes nothing. The clock is injectable (tests pass a fake one).
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from typing import IO, Literal

from tqdm import tqdm

__all__ = ["EVERY_S", "Progress", "progress_for", "span_words"]

#: seconds between two lines off a terminal
EVERY_S = 5.0

Mode = Literal["bar", "lines", "off"]


class Progress:
    """The progress of one command (``antsim <command>``); see the module docstring.

    ``show``: True a bar, False nothing, None (the default) a bar on a terminal and lines
    off one. Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, command: str, show: bool | None = None, *, every_s: float | None = None,
                 clock: Callable[[], float] = time.monotonic, stream: IO[str] | None = None):
        self.command = command
        self.stream = stream if stream is not None else sys.stderr
        self.every_s = EVERY_S if every_s is None else every_s
        self.clock = clock
        isatty = getattr(self.stream, "isatty", lambda: False)()
        self.mode: Mode = ("off" if show is False else
                           "bar" if show or isatty else "lines")
        self.text, self.total, self.unit, self.n, self.now = "", None, "", 0, ""
        self._bar = None
        self._lock = threading.RLock()
        self._t0 = self._last = clock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        if self.mode != "off":
            self._thread = threading.Thread(target=self._run, name="antsim-progress",
                                            daemon=True)
            self._thread.start()

    # ------------------------------------------------------------------ what the work says
    def stage(self, text: str, total: int | float | None = None, unit: str = "") -> None:
        """A new stage: ``text`` says what is being done; ``total`` (in ``unit``) when it
        can be counted."""
        with self._lock:
            self.text, self.total, self.unit, self.n, self.now = text, total, unit, 0, ""
            if self.mode == "bar":
                self._close_bar()
                self._bar = tqdm(total=total, unit=unit or "it", desc=text, leave=False,
                                 file=self.stream, dynamic_ncols=True)

    def advance(self, n: int | float = 1) -> None:
        """``n`` more of the stage's total done."""
        self.set(self.n + n)

    def set(self, n: int | float) -> None:
        """The stage's count is now ``n``."""
        with self._lock:
            self.n = n
            if self._bar is not None:
                self._bar.n = n
                self._bar.refresh()

    def detail(self, text: str) -> None:
        """What the stage is busy with now (e.g. the runs still going), shown after it."""
        with self._lock:
            self.now = text
            if self._bar is not None:
                self._bar.set_postfix_str(text, refresh=True)

    def write(self, text: str, file: IO[str] | None = None) -> None:
        """Print ``text`` (to stdout) without breaking the bar."""
        with self._lock:
            if self._bar is not None:
                self._bar.clear()
            print(text, file=file or sys.stdout, flush=True)
            if self._bar is not None:
                self._bar.refresh()

    # ------------------------------------------------------------------ the clock's side
    def line(self) -> str:
        """The line written off a terminal: command, stage, count, time so far."""
        elapsed = self.clock() - self._t0
        count = ""
        if self.total:
            count = f": {_number(self.n)}/{_number(self.total)}"
            count += f" {self.unit}" if self.unit else ""
            count += f" ({100.0 * self.n / self.total:.0f}%)"
        elif self.n:
            count = f": {_number(self.n)}" + (f" {self.unit}" if self.unit else "")
        now = f"; {self.now}" if self.now else ""
        return (f"antsim {self.command}: {self.text or 'working'}{count}{now}, "
                f"{elapsed:.0f} s")

    def tick(self) -> None:
        """What the thread does about once a second (tests call it with a fake clock)."""
        with self._lock:
            if self.mode == "bar" and self._bar is not None:
                self._bar.refresh()
            elif self.mode == "lines" and self.clock() - self._last >= self.every_s:
                self._last = self.clock()
                print(self.line(), file=self.stream, flush=True)

    def _run(self) -> None:
        while not self._stop.wait(min(1.0, max(self.every_s / 5.0, 0.01))):
            self.tick()

    # ------------------------------------------------------------------ the end
    def close(self) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        with self._lock:
            self._close_bar()

    def _close_bar(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def progress_for(value: Progress | bool | None, command: str) -> tuple[Progress, bool]:
    """``value`` if it is a :class:`Progress` (the caller's, not closed here), else a new
    one for ``command`` with ``show = value``; and whether the caller owns (closes) it."""
    if isinstance(value, Progress):
        return value, False
    return Progress(command, value), True


def _number(x: float) -> str:
    return f"{x:g}" if isinstance(x, int) or float(x).is_integer() else f"{x:.1f}"


def span_words(duration_s: float) -> str:
    """A campaign's length in words for a progress line: "20 days", "8 hours", "1 hour"."""
    if duration_s >= 2 * 86400.0:
        return f"{duration_s / 86400.0:.3g} days"
    hours = f"{duration_s / 3600.0:.3g}"
    return f"{hours} hour{'s' if hours != '1' else ''}"
