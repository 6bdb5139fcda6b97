"""The KATCP server through clients written by others: aiokatcp's ``Client`` (the library
the server is built on, but its client half) and katcp-python's ``BlockingClient`` (the
MeerKAT/SKA-SA reference implementation, tornado-based, a different code base).

katcp-python cannot be a dependency of the ``test`` extra: every release that runs on
Python 3 (0.9.x) pins ``tornado>=4.3,<5``, which ``dask[distributed]`` (``tornado>=6.2``)
excludes, so pip backtracks to katcp 0.6.2, whose source is Python 2 (``except
struct.error, e:``, a SyntaxError on import). Its 0.9.3 works with tornado 6 when installed
without its pins (``pip install --no-deps katcp==0.9.3 ply future``); CI does so after the
README's test command and runs this module again (``.ci/run``); its test skips where
katcp-python is not installed.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from antsim.serve.process import ServerProcess

REPO = Path(__file__).resolve().parents[3]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"
TIMEOUT_S = 20.0

#: (request arguments, what the failure says): requests once mishandled and neighbours
REFUSED = [
    (("offset", "1e12", "1e12"), "argument 1 (DAZ) '1e12': the first axis would be at 1e+12"),
    (("offset", "0", "100"), "argument 2 (DEL) '100': the second axis would be at 14"),
    (("feed-angle", "1e12"), "argument 1 (ANGLE) '1e12': must lie within -360..360 deg"),
    (("track", "0", "1e300", "45"), "point 1: azimuth 1e+300 deg is outside -720..720"),
    (("track", "-1e300", "180", "45"), "point 1: time -1e+300 s is outside"),
    (("powers", "1", "10000000"), "integration 1 is not waiting for ?powers"),
    (("sensor-sampling", "encoder.az", "period", "nan"),
     "argument 3 (PERIOD) 'nan' is not a finite number"),
    (("integrate", "1e300"), "argument 1 (SECONDS) '1e300': 1e+300 samples"),
]


@pytest.fixture(scope="module")
def server():
    with ServerProcess(BASE) as srv:
        yield srv


def test_aiokatcps_client(server):
    import aiokatcp

    async def session() -> dict:
        client = await asyncio.wait_for(
            aiokatcp.Client.connect("127.0.0.1", server.port, auto_reconnect=False),
            TIMEOUT_S)
        statuses: list[tuple[bytes, ...]] = []
        client.add_inform_callback("sensor-status", lambda *args: statuses.append(args))
        try:
            _, informs = await client.request("antenna")
            items = {m.arguments[0].decode(): m.arguments[1].decode() for m in informs}
            await client.request("sensor-sampling", "mount.mode", "event")
            reply, _ = await client.request("clock")
            clock = float(reply[0])
            await client.request("track", clock, 180.0, 45.0, clock + 2000.0, 190.0, 50.0)
            failures = {}
            for args, _ in REFUSED:
                with pytest.raises(aiokatcp.FailReply) as failed:
                    await client.request(*args)
                failures[args] = str(failed.value)
            after, _ = await client.request("clock")
            await client.request("offset", 0.1, 0.0)
            powers, _ = await client.request("integrate", 5.0)
            await client.request("release")
            await asyncio.sleep(0.2)  # the last sensor-status informs
            return {"items": items, "failures": failures, "clock": clock,
                    "after": float(after[0]), "powers": powers, "statuses": statuses}
        finally:
            client.close()
            await client.wait_closed()

    got = asyncio.run(session())
    assert got["items"]["mount"] == "altaz" and got["items"]["end-s"] == "7200.0"
    for args, says in REFUSED:
        assert says in got["failures"][args], (args, got["failures"][args])
        assert "Traceback" not in got["failures"][args]
    assert got["clock"] < got["after"] < 7200.0  # the slew only: no refused request moved it
    assert len(got["powers"]) == 15
    modes = [s[4].decode() for s in got["statuses"] if s[2] == b"mount.mode"]
    assert modes[:3] == ["parked", "slewing", "tracking"] and "moving" in modes


@pytest.mark.filterwarnings("ignore:setDaemon:DeprecationWarning")  # katcp-python's own
def test_katcp_pythons_blocking_client(server):
    katcp = pytest.importorskip("katcp", minversion="0.9",
                                reason="katcp-python is not installed (see this module's "
                                       "docstring: pip install --no-deps katcp==0.9.3 ply)")
    client = katcp.BlockingClient("127.0.0.1", server.port)
    client.start()
    try:
        client.wait_protocol(timeout=TIMEOUT_S)

        def request(*args) -> tuple[list[str], list[list[str]]]:
            reply, informs = client.blocking_request(katcp.Message.request(*args),
                                                     timeout=TIMEOUT_S)
            return ([_text(a) for a in reply.arguments],
                    [[_text(a) for a in m.arguments] for m in informs])

        items = dict(inform[:2] for inform in request("antenna")[1])
        assert items["scenario"] == "bad_inputs_base" and items["axis2-min-deg"] == "5.0"
        clock = float(request("clock")[0][1])
        reply, _ = request("track", clock, 180, 45, clock + 2000, 190, 50)
        assert reply[0] == "ok"
        after_track = float(request("clock")[0][1])
        for args, says in REFUSED:
            reply, _ = request(*args)
            assert reply[0] == "fail" and says in reply[1], (args, reply)
            assert "Traceback" not in reply[1]
        assert float(request("clock")[0][1]) == after_track  # none of them moved the clock
        reply, _ = request("integrate", 5)
        assert reply[0] == "ok" and len(reply) == 16
        reply, informs = request("sensor-value", "mount.on-target")
        assert reply[0] == "ok" and informs[0][2:] == ["mount.on-target", "nominal", "1"]
        assert request("release")[0] == ["ok"]
    finally:
        client.stop()
        client.join(timeout=TIMEOUT_S)


def _text(arg) -> str:
    return arg.decode("utf-8") if isinstance(arg, bytes) else str(arg)
