"""`antsim serve` in a child process: what a closed-loop test of control software starts.

    with ServerProcess("scenarios/ghigo1990.toml", out=tmp_path) as server:
        antenna = KatcpAntenna("127.0.0.1", server.port, env)   # or your own client
        ...

The server listens on a free loopback port (``--port 0``), which :class:`ServerProcess`
reads from its first lines; its progress lines are collected in ``lines``. Leaving the
``with`` block stops it with SIGTERM (a clean stop: the request log and ``truth.json`` are
written) and waits for it.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
from pathlib import Path

__all__ = ["ServerProcess"]

_LISTENING = re.compile(r"listening on (\S+):(\d+) ")


class ServerProcess:
    """``python -m antsim serve SCENARIO --port 0 ...`` as a child process."""

    def __init__(self, scenario: str | Path, *, clock: str = "virtual", seed: int | None = None,
                 out: str | Path | None = None, args: tuple[str, ...] = (),
                 timeout_s: float = 60.0):
        self.command = [sys.executable, "-m", "antsim", "serve", str(scenario), "--port", "0",
                        "--clock", clock, *args]
        if seed is not None:
            self.command += ["--seed", str(seed)]
        if out is not None:
            self.command += ["--out", str(out)]
        self.timeout_s = timeout_s
        self.host = "127.0.0.1"
        self.port: int | None = None
        self.lines: list[str] = []
        self.process: subprocess.Popen | None = None
        self._listening = threading.Event()
        self._reader: threading.Thread | None = None

    def start(self) -> ServerProcess:
        self.process = subprocess.Popen(self.command, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                        text=True, env=os.environ.copy())
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        if not self._listening.wait(self.timeout_s) or self.port is None:
            self.stop()
            raise RuntimeError("antsim serve did not start listening within "
                               f"{self.timeout_s:g} s:\n" + "\n".join(self.lines[-20:]))
        return self

    def _read(self) -> None:
        for line in self.process.stderr:
            self.lines.append(line.rstrip("\n"))
            match = _LISTENING.search(line)
            if match and self.port is None:
                self.host, self.port = match.group(1), int(match.group(2))
                self._listening.set()
        self._listening.set()  # the process ended (before listening, if port is None)

    def stop(self, sig: int = signal.SIGTERM, timeout_s: float = 30.0) -> int:
        """Send ``sig`` and wait for the server to end; its exit status."""
        if self.process is None:
            return 0
        if self.process.poll() is None:
            self.process.send_signal(sig)
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._reader.join(timeout_s)  # every line it printed is in ``lines``
        return self.process.returncode

    def __enter__(self) -> ServerProcess:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
