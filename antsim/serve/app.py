"""Running the KATCP device until it is stopped: start, progress lines, signals, outputs.

:func:`serve` listens (loopback unless told otherwise, and says so), prints one line per
client event and a status line every ``STATUS_EVERY_S`` of wall time while requests come,
and on SIGINT, SIGTERM or ``?halt`` stops cleanly: the request log is flushed line by line
as it is written, and ``truth.json`` (written at the start) is written again at the end.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import json
import logging
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from controller.errors import InputError

from ..outdir import write_file
from .clock import ClockSpec
from .device import AntennaDevice, RequestLog

if TYPE_CHECKING:
    from ..scenario import Scenario

__all__ = ["LOOPBACK", "PRODUCTS", "serve"]

LOOPBACK = ("127.0.0.1", "::1", "localhost")
#: the files a session writes into its --out (a directory holding either is refused)
PRODUCTS = ("truth.json", "requests.jsonl")
#: wall time between status lines while requests come (s)
STATUS_EVERY_S = 30.0


def _gone_client_writes(record: logging.LogRecord) -> bool:
    """False for asyncio's warning about a reply written to a client that has gone (one per
    reply after the fifth): a client may leave with pipelined requests in flight, and the
    server says that it left in one line of its own."""
    return record.getMessage() != "socket.send() raised exception."


def _say(text: str) -> None:
    print(f"antsim serve: {time.strftime('%H:%M:%S')} {text}", file=sys.stderr, flush=True)


async def serve(scenario: Scenario, clock: ClockSpec, host: str = "127.0.0.1", port: int = 0,
                seed: int | None = None, out: Path | None = None,
                say: Callable[[str], None] = _say,
                started: Callable[[AntennaDevice], None] | None = None) -> int:
    """Serve ``scenario`` until stopped; returns the exit status (0). The outputs are made
    once the server listens: a port in use leaves ``out`` as it was."""
    device = AntennaDevice(host, port, scenario, seed, clock, say=say)
    try:
        await device.start()
    except OSError as err:
        raise _bind_error(err, host, port) from None
    try:
        if out is not None:
            # both or neither: a session that cannot start leaves nothing to refuse the next
            out.mkdir(parents=True, exist_ok=True)
            _write_truth(device, out)
            try:
                device.log = RequestLog(out / "requests.jsonl")
            except BaseException:
                (out / "truth.json").unlink(missing_ok=True)
                raise
        return await _run(device, host, out, say, started)
    except BaseException:
        if device.server is not None and device.server.is_serving():
            await device.stop()
        raise
    finally:
        if device.log is not None:
            device.log.close()


async def _run(device: AntennaDevice, host: str, out: Path | None,
               say: Callable[[str], None], started) -> int:
    loop = asyncio.get_running_loop()
    logging.getLogger("asyncio").addFilter(_gone_client_writes)
    bound = device.server.sockets[0].getsockname()
    where = ("loopback only: other machines cannot connect; --host 0.0.0.0 serves them"
             if host in LOOPBACK else "REACHABLE FROM OTHER MACHINES")
    sc = device.scenario
    say(f"scenario {sc.name} (seed {device.seed}), clock {device.clock.spec.text}, "
        f"{sc.duration_s / 3600.0:g} h from {sc.epoch_utc} UTC")
    say(f"listening on {bound[0]}:{bound[1]} ({where}); the request list: docs/katcp.md")
    stopped = asyncio.Event()
    why = ["?halt"]

    def stop(name: str) -> None:
        why[0] = name
        stopped.set()

    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop, sig.name)
    tasks = [asyncio.ensure_future(_status(device, say, stopped))]
    if not device.clock.spec.virtual:
        tasks.append(asyncio.ensure_future(device.clock.run(device.refresh_sensors, stopped)))
    if started is not None:
        started(device)
    halted = asyncio.ensure_future(device.join())
    waiting = asyncio.ensure_future(stopped.wait())
    try:
        await asyncio.wait({halted, waiting}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        stopped.set()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(sig)
        await device.stop()
        for task in (*tasks, halted, waiting):
            task.cancel()
        await asyncio.gather(*tasks, halted, waiting, return_exceptions=True)
    wrote = ""
    if out is not None:
        _write_truth(device, out)
        wrote = f"; wrote {out / 'truth.json'}" + (
            f" and {out / 'requests.jsonl'}" if device.log is not None
            else f" ({out / 'requests.jsonl'} holds the requests logged before it failed)")
    say(f"stopped ({why[0]}) after {device.requests} requests ({device.serving_s:.2f} s "
        f"serving them) at clock "
        f"{device.antenna.clock_s():.1f} s{wrote}")
    return 0


async def _status(device: AntennaDevice, say: Callable[[str], None],
                  stopped: asyncio.Event) -> None:
    """A status line every STATUS_EVERY_S while requests come; one when simulated time
    reaches the end of the simulation."""
    last = device.requests
    ended = False
    while not stopped.is_set():
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(stopped.wait(), STATUS_EVERY_S)
        if not ended and device.env.now >= device.end_s:
            ended = True
            say(f"simulated time reached the end of the simulation ({device.end_s:.0f} s: the "
                "scenario's duration plus an hour); commands are refused from now on")
        if device.requests != last and not stopped.is_set():
            clock_s = device.antenna.clock_s()
            share = 100.0 * clock_s / device.scenario.duration_s
            say(f"clock {clock_s:.0f} s ({share:.0f}% of the campaign), {device.requests} "
                f"requests (+{device.requests - last}), {len(device._connections)} "
                "client(s)")
            last = device.requests


def _write_truth(device: AntennaDevice, out: Path) -> None:
    text = json.dumps(device.world.truth(), indent=2) + "\n"
    write_file(out / "truth.json", text)


def _bind_error(err: OSError, host: str, port: int) -> InputError:
    if err.errno == errno.EADDRINUSE:
        return InputError("command line", "--port", port, "address already in use",
                          "choose another port, or 0 for any free one")
    if err.errno in (errno.EADDRNOTAVAIL, errno.EACCES):
        field, value = ("--port", port) if err.errno == errno.EACCES else ("--host", host)
        return InputError("command line", field, value, f"cannot listen there: {err.strerror}")
    return InputError("command line", "--host", host, f"cannot listen on {host}:{port}: {err}")
