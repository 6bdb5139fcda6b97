"""Shared by the tests of antsim serve: a bare KATCP client and one virtual-clock
server of the 3-hour 1990 scenario.

Everything runs on loopback with ephemeral ports (``--port 0``); every socket read has a
timeout, and servers are stopped by their context managers, so a hung server fails a test
instead of hanging the suite.
"""

from __future__ import annotations

import socket
import time

import pytest

from antsim.serve.process import ServerProcess

TIMEOUT_S = 20.0


class LineClient:
    """A bare KATCP client: raw lines, as a user's program would send them."""

    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT_S)
        self.file = self.sock.makefile("rb")
        self.asynchronous: list[str] = []

    def send(self, line: str) -> None:
        self.sock.sendall(line.encode() + b"\n")

    def line(self) -> str:
        text = self.file.readline().decode().rstrip("\n")
        assert text, "the server closed the connection"
        return text

    def request(self, line: str) -> tuple[str, list[str]]:
        """Send ``line``; the reply line and the informs of this request (by name)."""
        self.send(line)
        name = line.split()[0][1:]
        informs = []
        while True:
            text = self.line()
            if text.startswith("!" + name + " ") or text == "!" + name:
                return text, informs
            if text.startswith("#" + name + " "):
                informs.append(text)
            else:
                self.asynchronous.append(text)

    def pipeline(self, lines: list[str]) -> dict[int, tuple[str, list[str]]]:
        """Send ``lines`` (requests with message ids, ``?name[id] ...``) in one write, then
        read every reply: ``{id: (reply line, informs)}`` in the order the replies came."""
        self.sock.sendall("".join(line + "\n" for line in lines).encode())
        mids = {int(line.split("[")[1].split("]")[0]) for line in lines}
        out: dict[int, tuple[str, list[str]]] = {}
        informs: dict[int, list[str]] = {}
        while len(out) < len(mids):
            text = self.line()
            head = text.split()[0]
            mid = int(head.split("[")[1].rstrip("]")) if "[" in head else None
            if mid not in mids:
                self.asynchronous.append(text)
            elif text.startswith("#"):
                informs.setdefault(mid, []).append(text)
            else:
                out[mid] = text, informs.get(mid, [])
        return out

    def track_once_free(self, track: str) -> str:
        """Send ``track`` (a ?track line) until the antenna takes it: a client that just
        disconnected keeps control until the server notices (asynchronously)."""
        deadline = time.monotonic() + TIMEOUT_S
        while True:
            reply, _ = self.request(track)
            if reply.startswith("!track ok ") or time.monotonic() > deadline:
                return reply
            time.sleep(0.05)

    def close(self) -> None:
        self.file.close()
        self.sock.close()


@pytest.fixture(scope="module")
def server(short_path):
    """One virtual-clock server of the 3-hour 1990 scenario for the robustness tests."""
    with ServerProcess(short_path) as srv:
        yield srv
