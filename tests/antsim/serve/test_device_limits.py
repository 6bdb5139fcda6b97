"""The KATCP device's limits: every request's arguments are bounded before they touch the
simulated clock or the mount, a bad one gets a failure reply that names the argument and its
value, and no request stops the server or sends a traceback.

Before these limits ``?offset 1e12 1e12``, ``?offset 1e300 0``, ``?offset 200000 0`` and
``?feed-angle 1e12`` moved the virtual clock past the end of the simulation (every later
command refused, ``?clock`` an OverflowError, ``?sensor-value`` a traceback sent to the
client); ``?offset 0 100`` gave an encoder elevation of 160 deg on target; ``?powers 1
10000000`` held every client 1.2 s and 415 MB; ``?sensor-sampling NAME period nan`` sent
about 18,000 informs a second; ``mount.mode`` sent no event under the virtual clock.

Servers run on loopback with ephemeral ports (``--port 0``); every read has a timeout. The
scenario is ``tests/data/bad_inputs/scenario/_base.toml``: one hour (the end of the
simulation at 7200 s), azimuth limits -90..450 deg, elevation 5..90 deg, settle 2.5 s,
1 s samples.
"""

from __future__ import annotations

import asyncio
import errno
import math
import os
import select
import socket
import time
from pathlib import Path

import pytest

from antsim.serve.process import ServerProcess
from tests.antsim.serve.conftest import TIMEOUT_S, LineClient

REPO = Path(__file__).resolve().parents[3]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"
END_S = 7200.0  # one hour plus the hour's margin


def unescape(text: str) -> str:
    """A KATCP argument as text (the escapes a reply uses)."""
    out, i = [], 0
    table = {"_": " ", "n": "\n", "\\": "\\", "t": "\t", "0": "\0", "e": "\x1b", "r": "\r",
             "@": ""}
    while i < len(text):
        if text[i] == "\\" and i + 1 < len(text):
            out.append(table.get(text[i + 1], text[i + 1]))
            i += 2
        else:
            out.append(text[i])
            i += 1
    return "".join(out)


@pytest.fixture(scope="module")
def server():
    with ServerProcess(BASE) as srv:
        yield srv


@pytest.fixture
def client(server):
    """A client that controls the antenna, tracking a source at elevation 45-50 deg."""
    c = LineClient(server.port)
    clock = _clock(c)
    assert c.track_once_free(f"?track {clock} 180 45 {clock + 2000} 190 50").startswith(
        "!track ok ")
    yield c
    c.request("?release")
    c.close()


def _clock(c: LineClient) -> float:
    reply, _ = c.request("?clock")
    assert reply.startswith("!clock ok "), reply
    return float(reply.split()[2])


def _fails(c: LineClient, line: str) -> str:
    """The failure reply's message, checked for no traceback and no change of the clock."""
    before = _clock(c)
    reply, _ = c.request(line)
    name = line.split()[0][1:]
    assert reply.startswith(f"!{name} fail ") or reply.startswith(f"!{name} invalid "), reply
    message = unescape(reply.split(" ", 2)[2])
    assert "Traceback" not in message and "internal error" not in message, message
    assert _clock(c) == before, line
    return message


#: (request, what the failure reply says): each names the argument and its value
BAD = [
    # requests once accepted: offsets and a feed angle that moved the clock past its end
    ("?offset 1e12 1e12", "argument 1 (DAZ) '1e12': the first axis would be at 1e+12 deg, "
                          "outside the mount's limits -90..450 deg"),
    ("?offset 1e300 0", "argument 1 (DAZ) '1e300': the first axis would be at 1e+300 deg"),
    ("?offset 200000 0", "argument 1 (DAZ) '200000': the first axis would be at 200"),
    ("?feed-angle 1e12", "argument 1 (ANGLE) '1e12': must lie within -360..360 deg"),
    # offsets held to the mount's limits
    ("?offset 0 100", "argument 2 (DEL) '100': the second axis would be at 14"),
    ("?offset 0 -80", "argument 2 (DEL) '-80': the second axis would be at -3"),
    ("?offset -400 0", "argument 1 (DAZ) '-400': the first axis would be at -2"),
    ("?offset 0 -1e300", "argument 2 (DEL) '-1e300': the second axis would be at -1e+300"),
    ("?offset nan 0", "argument 1 (DAZ) 'nan' is not a finite number"),
    ("?offset 0 inf", "argument 2 (DEL) 'inf' is not a finite number"),
    ("?offset -inf 0", "argument 1 (DAZ) '-inf' is not a finite number"),
    ("?offset 1", "argument 2 (DEL) is missing"),
    ("?offset", "argument 1 (DAZ) is missing"),
    ("?offset 0x10 0", "argument 1 (DAZ) '0x10' is not a number"),
    ("?offset 1 2 3", "too many arguments (3): usage ?offset DAZ DEL"),
    # the feed box
    ("?feed-angle -1e12", "argument 1 (ANGLE) '-1e12': must lie within -360..360 deg"),
    ("?feed-angle 360.5", "argument 1 (ANGLE) '360.5': must lie within -360..360 deg"),
    ("?feed-angle nan", "argument 1 (ANGLE) 'nan' is not a finite number"),
    ("?feed-angle 1 2", "too many arguments (2): usage ?feed-angle [ANGLE]"),
    # program-track points: azimuths and times bounded
    ("?track 0 1e300 45", "point 1: azimuth 1e+300 deg is outside -720..720"),
    ("?track 0 -1e300 45", "point 1: azimuth -1e+300 deg is outside -720..720"),
    ("?track 0 180 45 60 721 45", "point 2: azimuth 721.0 deg is outside -720..720"),
    ("?track 1e300 180 45", "point 1: time 1e+300 s is outside -86400..93600 s"),
    ("?track -1e300 180 45", "point 1: time -1e+300 s is outside -86400..93600 s"),
    ("?track 0 180 45 1e300 190 50", "point 2: time 1e+300 s is outside -86400..93600 s"),
    ("?track nan 180 45", "point 1: time nan is not a finite number"),
    ("?track 0 180 1e300", "point 1: elevation 1e+300 deg is outside -90..90"),
    ("?track 0 180", "a table is triplets of time, azimuth, elevation: got 2 numbers"),
    ("?track", "got 0 numbers (none)"),
    ("?track-append 1e300 180 45", "point 1: time 1e+300 s is outside -86400..93600 s"),
    ("?track-append 100 1e300 45", "point 1: azimuth 1e+300 deg is outside -720..720"),
    # integrations and the camera: at most 100,000 samples
    ("?integrate 1e6", "argument 1 (SECONDS) '1e6': 1e+06 samples of 1 s; at most 100000"),
    ("?integrate 1e300", "argument 1 (SECONDS) '1e300': 1e+300 samples of 1 s"),
    ("?integrate nan", "argument 1 (SECONDS) 'nan' is not a finite number"),
    ("?integrate 0", "argument 1 (SECONDS) '0': must be positive"),
    ("?integrate -5 defer", "argument 1 (SECONDS) '-5': must be positive"),
    ("?integrate 5 later", "argument 2 'later': the only option is 'defer'"),
    ("?camera 1", "this antenna has no camera"),
    # ?powers: ranges answered without walking them
    ("?powers 1 10000000", "integration 1 is not waiting for ?powers"),
    ("?powers 1 1e12", "argument 2 (LAST) '1e12' is not an integer"),
    ("?powers 1 99999999999999999999999999", "integration 1 is not waiting for ?powers"),
    ("?powers 5 1", "argument 2 (LAST) '1': comes before FIRST 5"),
    ("?powers -3", "integration -3 is not waiting for ?powers"),
    ("?powers a", "argument 1 (FIRST) 'a' is not an integer"),
    ("?powers 1 2 3", "too many arguments (3): usage ?powers [FIRST [LAST]]"),
    # waiting: the end of the simulation
    ("?wait 1e300", "argument 1 (SECONDS) '1e300': ?wait would end at 1e+300 s, after the "
                    "end of the simulation (7200.0 s"),
    ("?wait -1", "argument 1 (SECONDS) '-1': must not be negative"),
    ("?wait inf", "argument 1 (SECONDS) 'inf' is not a finite number"),
    # readings take no arguments
    ("?clock 1", "too many arguments (1): usage ?clock"),
    ("?encoder x", "too many arguments (1): usage ?encoder"),
    # sensor name patterns: no catastrophic backtracking (/(.*)*x/ took 2.8 s per name)
    ("?sensor-value /(.*)*x/", "argument 1 (NAME) '/(.*)*x/': a repeated group is not "
                               "allowed in a sensor name pattern"),
    ("?sensor-list /(a+)+$/", "argument 1 (NAME) '/(a+)+$/': a repeated group is not"),
    ("?sensor-list /(?:.*)*!/", "a repeated group is not allowed"),
    ("?sensor-value /.*.*.*.*.*x/", "argument 1 (NAME) '/.*.*.*.*.*x/': 5 repeats; at most 4"),
    ("?sensor-value /" + "a" * 101 + "/", "a pattern of 101 characters; at most 100"),
    ("?sensor-value /[/", "argument 1 (NAME) '/[/': not a regular expression (unterminated "
                          "character set"),
    # sensor sampling: finite, not negative, periods at least 0.1 s
    ("?sensor-sampling encoder.az period nan", "argument 3 (PERIOD) 'nan' is not a finite "
                                                "number"),
    ("?sensor-sampling encoder.az period inf", "argument 3 (PERIOD) 'inf' is not a finite"),
    ("?sensor-sampling encoder.az period 0", "argument 3 (PERIOD) '0': at least 0.1 s"),
    ("?sensor-sampling encoder.az period 1e-9", "argument 3 (PERIOD) '1e-9': at least 0.1 s"),
    ("?sensor-sampling encoder.az period -1", "argument 3 (PERIOD) '-1': must not be "
                                               "negative"),
    ("?sensor-sampling encoder.az period", "period takes 1 parameter(s), got 0"),
    ("?sensor-sampling encoder.az period 1 2", "period takes 1 parameter(s), got 2"),
    ("?sensor-sampling encoder.az event 1", "event takes 0 parameter(s), got 1"),
    ("?sensor-sampling encoder.az event-rate nan 1", "argument 3 (SHORTEST) 'nan' is not a "
                                                      "finite number"),
    ("?sensor-sampling encoder.az event-rate 0 nan", "argument 4 (LONGEST) 'nan' is not a "
                                                      "finite number"),
    ("?sensor-sampling encoder.az event-rate 0 0.001", "argument 4 (LONGEST) '0.001': at "
                                                        "least 0.1 s"),
    ("?sensor-sampling encoder.az event-rate 5 1", "argument 3 (SHORTEST) '5': longer than "
                                                    "LONGEST 1 s"),
    ("?sensor-sampling encoder.az differential nan", "argument 3 (DIFFERENCE) 'nan' is not a "
                                                      "finite number"),
    ("?sensor-sampling encoder.az differential -0.1", "argument 3 (DIFFERENCE) '-0.1': must "
                                                       "not be negative"),
    ("?sensor-sampling encoder.az differential-rate 0.1 0 nan", "argument 5 (LONGEST) 'nan'"),
    ("?sensor-sampling encoder.az differential-rate inf 0 1", "argument 3 (DIFFERENCE) 'inf'"),
]


@pytest.mark.parametrize(("line", "says"), BAD, ids=[b[0] for b in BAD])
def test_a_bad_argument_fails_naming_it_and_leaves_the_clock(client, line, says):
    assert says in _fails(client, line)


def test_a_sensor_name_pattern_of_single_repeats_is_served(client):
    reply, informs = client.request(r"?sensor-value /^[a-z]+\\.(az|el)$/")  # KATCP: \\ is \
    assert reply == "!sensor-value ok 4" and len(informs) == 4  # encoder.*, offset.*
    t0 = time.perf_counter()
    reply, informs = client.request("?sensor-list /.*.*.*.*!/")
    assert reply == "!sensor-list ok 0" and time.perf_counter() - t0 < 1.0


def test_the_issues_requests_leave_the_server_serving(client):
    """After every such request, the clock is where it was, ``?clock`` and
    ``?sensor-value`` answer, and a scan goes on as usual."""
    start = _clock(client)
    for line in ("?offset 1e12 1e12", "?offset 1e300 0", "?offset 200000 0",
                 "?feed-angle 1e12", "?offset 0 100", "?offset 0 -80",
                 "?track 0 1e300 45", "?track 1e300 180 45", "?track -1e300 180 45",
                 "?powers 1 10000000", "?powers 1 1e12"):
        client.request(line)
    assert _clock(client) == start < END_S
    reply, informs = client.request("?sensor-value")
    assert reply.startswith("!sensor-value ok ") and len(informs) >= 14
    assert all("nominal" in i for i in informs)
    assert client.request("?offset 0.1 0")[0].startswith("!offset ok ")
    values = client.request("?integrate 5")[0].split()[2:]
    assert len(values) == 15 and all(math.isfinite(float(v)) for v in values)


def test_an_offset_within_the_limits_moves_the_encoders_there(client):
    """The limits apply to the track plus the offset: 40 deg up from 45-50 is refused,
    30 deg is carried out and the encoder reads it, on target."""
    assert "outside the mount's limits 5..90 deg" in _fails(client, "?offset 0 46")
    assert client.request("?offset 0 30")[0].startswith("!offset ok ")
    el = float(client.request("?encoder")[0].split()[3])
    assert 75.0 < el < 81.0
    assert client.request("?sensor-value mount.on-target")[1][0].endswith(" 1")


def test_a_track_that_leaves_the_limits_is_not_on_target(client):
    """A table may set below the elevation limit (the antenna holds nothing back): the
    mount then is not on target, and an offset further down is refused."""
    clock = _clock(client)
    reply, _ = client.request(f"?track {clock} 180 12 {clock + 1000} 180 2")
    assert reply.startswith("!track ok "), reply
    assert client.request("?sensor-value mount.on-target")[1][0].endswith(" 1")
    assert client.request("?wait 800")[0].startswith("!wait ok ")
    el = float(client.request("?encoder")[0].split()[3])
    assert el < 5.0
    assert client.request("?sensor-value mount.on-target")[1][0].endswith(" 0")
    assert "outside the mount's limits" in _fails(client, "?offset 0 -1")


def test_a_wide_powers_range_is_answered_at_once(client):
    """Ten million ids were walked (1.2 s, 415 MB): now at most the waiting ones are."""
    assert client.request("?integrate 1 defer")[0].startswith("!integrate ok ")
    t0 = time.perf_counter()
    reply, _ = client.request("?powers 1 10000000")
    assert time.perf_counter() - t0 < 0.5  # generous: a loaded machine; it was 1.2 s
    assert "is not waiting for ?powers" in unescape(reply)
    reply, informs = client.request("?powers")
    assert reply == "!powers ok 1" and len(informs) == 1


def test_deferred_integrations_are_bounded(client):
    """A backend buffers a finite number of dumps: the 1001st waiting one is refused,
    ?powers then reads the thousand."""
    lines = [f"?integrate[{k}] 0.01 defer" for k in range(1, 1002)]
    replies = client.pipeline(lines)
    assert all(replies[k][0].startswith(f"!integrate[{k}] ok ") for k in range(1, 1001))
    assert "1000 deferred integrations wait for ?powers" in unescape(replies[1001][0])
    reply, informs = client.request("?powers")
    assert reply == "!powers ok 1000" and len(informs) == 1000


def test_deferred_samples_are_bounded(write_scenario):
    """With 0.01 s samples, ten deferred integrations of 1000 s (100,000 samples each) wait;
    the eleventh would pass 1,000,000 waiting samples and is refused, naming its argument;
    ?powers reads the ten."""
    path = write_scenario(BASE.read_text(encoding="utf-8"), [
        ("duration_h = 1.0", "duration_h = 4.0"),
        ("sample_interval_s = 1.0", "sample_interval_s = 0.01")])
    with ServerProcess(path) as srv:
        c = LineClient(srv.port)
        try:
            assert c.request("?track 0 180 45 14000 190 50")[0].startswith("!track ok ")
            replies = c.pipeline([f"?integrate[{k}] 1000 defer" for k in range(1, 12)])
            assert all(replies[k][0].startswith(f"!integrate[{k}] ok ") for k in range(1, 11))
            assert unescape(replies[11][0]).endswith(
                "argument 1 (SECONDS) '1000': 100000 samples more than the 1000000 waiting "
                "for ?powers would pass 1000000: read them first")
            reply, informs = c.request("?powers")
            assert reply == "!powers ok 10" and len(informs) == 10
        finally:
            c.close()


def test_commands_that_would_pass_the_end_are_refused():
    """Near the end of the simulation a move's time is checked before it starts: an offset,
    a turn of the feed box and a slew that would end after it are refused."""
    with ServerProcess(BASE) as srv:
        c = LineClient(srv.port)
        try:
            assert c.request("?track 0 180 45 7200 190 50")[0].startswith("!track ok ")
            clock = _clock(c)
            assert c.request(f"?wait {END_S - clock - 1.0}")[0].startswith("!wait ok ")
            assert _clock(c) == END_S - 1.0
            for line in ("?offset 1 0", "?feed-angle 90", "?track 7199 20 80",
                         "?integrate 2", "?wait 1.5"):
                assert "after the end of the simulation (7200.0 s" in _fails(c, line), line
            assert c.request("?wait 1")[0] == "!wait ok 7200.0"
            reply, informs = c.request("?sensor-value")
            assert reply.startswith("!sensor-value ok ") and len(informs) >= 14
            assert c.request("?clock")[0] == "!clock ok 7200.0 1990-02-08T19:00:00.000 virtual"
        finally:
            c.close()


def test_a_nan_sampling_period_sends_no_flood(client, server):
    """The refused strategy leaves the sensor unsampled: no inform in half a second (a NaN
    period sent about 18,000 a second); a valid 0.1 s period sends about five."""
    def informs_within(line: str, seconds: float) -> tuple[str, int]:
        """Send ``line`` on a fresh connection; its reply, and the #sensor-status informs
        that came within ``seconds``."""
        with socket.create_connection(("127.0.0.1", server.port), timeout=TIMEOUT_S) as s:
            s.sendall(line.encode() + b"\n")
            data = b""
            deadline = time.monotonic() + seconds
            while time.monotonic() < deadline:
                ready, _, _ = select.select([s], [], [], max(0.0, deadline - time.monotonic()))
                if ready:
                    data += s.recv(1 << 16)
        lines = data.decode().splitlines()
        reply = next(x for x in lines if x.startswith("!sensor-sampling"))
        return reply, sum(x.startswith("#sensor-status") for x in lines)

    reply, count = informs_within("?sensor-sampling clock.seconds period nan", 0.5)
    assert "is not a finite number" in unescape(reply) and count == 0
    reply, count = informs_within("?sensor-sampling clock.seconds period 0.1", 0.5)
    assert reply == "!sensor-sampling ok clock.seconds period 0.1"
    assert 1 <= count <= 10  # about 5, the first at once; a busy machine sends fewer


def test_mount_mode_sends_events_under_the_virtual_clock(client, server):
    """A watcher of ``mount.mode`` sees every move start and end, stamped with the
    simulated time: slewing then tracking for ?track, moving then tracking for ?offset and
    ?feed-angle (none came before: the virtual clock has no tick between)."""
    w = LineClient(server.port)
    try:
        assert w.request("?sensor-sampling mount.mode event")[0] == \
            "!sensor-sampling ok mount.mode event"
        clock = _clock(client)
        client.request(f"?track {clock} 200 40 {clock + 2000} 210 45")
        client.request("?offset 0.2 0")
        client.request("?feed-angle 5")
        done = _clock(client)
        stamp = 634496400.0 + done  # the epoch, 1990-02-08T17:00:00 UTC, plus the clock

        def events() -> list[list[str]]:
            return [u.split() for u in w.asynchronous if u.startswith("#sensor-status ")]

        deadline = time.monotonic() + TIMEOUT_S
        while (not events() or abs(float(events()[-1][1]) - stamp) > 1e-3) \
                and time.monotonic() < deadline:
            w.asynchronous.append(w.line())
        modes = [e[5] for e in events()]
        assert modes[-6:] == ["slewing", "tracking", "moving", "tracking", "moving",
                              "tracking"], modes
        times = [float(e[1]) for e in events()]
        assert times == sorted(times)
    finally:
        w.close()


# ---------------------------------------------------------------------------------------------
# other mounts: an equatorial mount's axes, a camera
# ---------------------------------------------------------------------------------------------
def test_an_equatorial_mounts_offsets_are_held_to_its_limits(repo_root):
    with ServerProcess(repo_root / "scenarios" / "crane1981_140ft_3245.toml") as srv:
        c = LineClient(srv.port)
        try:
            informs = dict(i.split()[1:3] for i in c.request("?antenna")[1])
            assert informs["mount"] == "equatorial"
            clock = _clock(c)
            assert c.request(f"?track {clock} 10 30 {clock + 600} 12.5 30")[0].startswith(
                "!track ok ")
            high = informs["axis2-max-deg"]
            said = _fails(c, f"?offset 0 {high}")
            assert said.startswith(f"argument 2 (DEL) '{high}': the second axis would be at")
            assert "outside the mount's limits" in said
            assert c.request("?offset 0.1 0.1")[0].startswith("!offset ok ")
        finally:
            c.close()


def test_camera_exposures_are_bounded(repo_root):
    with ServerProcess(repo_root / "scenarios" / "wright1992_bima_ant5.toml") as srv:
        c = LineClient(srv.port)
        try:
            clock = _clock(c)
            assert c.request(f"?track {clock} 180 45 {clock + 600} 181 46")[0].startswith(
                "!track ok ")
            assert "samples of" in _fails(c, "?camera 1e9")
            assert "must be positive" in _fails(c, "?camera -1")
            assert "is not a finite number" in _fails(c, "?camera nan")
            assert c.request("?camera 1")[0].startswith("!camera ok ")
        finally:
            c.close()


# ---------------------------------------------------------------------------------------------
# in process: a failure inside the server, a request log that cannot be written
# ---------------------------------------------------------------------------------------------
def _device(say=lambda text: None):
    from antsim.scenario import load_scenario
    from antsim.serve.clock import parse_clock
    from antsim.serve.device import AntennaDevice

    return AntennaDevice("127.0.0.1", 0, load_scenario(BASE), None, parse_clock("virtual"),
                         say=say)


def test_a_failure_while_reading_sensors_is_a_reply_not_a_traceback():
    import aiokatcp

    async def scenario() -> str:
        device = _device()
        await device.start()
        try:
            port = device.server.sockets[0].getsockname()[1]
            client = await aiokatcp.Client.connect("127.0.0.1", port)

            def broken() -> None:
                raise OverflowError("date value out of range")

            device.refresh_sensors = broken
            device._sensors_stale = True
            try:
                with pytest.raises(aiokatcp.FailReply) as failed:
                    await client.request("sensor-value")
                reply, _ = await client.request("watchdog")  # still serving
                assert reply == []
                return str(failed.value)
            finally:
                client.close()
                await client.wait_closed()
        finally:
            await device.stop()

    said = asyncio.run(scenario())
    assert said == "internal error: OverflowError: date value out of range"


def test_a_request_log_that_cannot_be_written_is_said_once(tmp_path):
    """A full disk under requests.jsonl: one line says so, the lines written are kept, and
    the server goes on serving."""
    import aiokatcp

    from antsim.serve.device import RequestLog

    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full (a Linux device whose writes fail with ENOSPC)")
    said: list[str] = []

    async def scenario() -> None:
        device = _device(said.append)
        device.log = RequestLog(tmp_path / "requests.jsonl")
        await device.start()
        try:
            port = device.server.sockets[0].getsockname()[1]
            client = await aiokatcp.Client.connect("127.0.0.1", port)
            try:
                await client.request("clock")
                await client.request("clock")
                device.log._file.close()
                device.log._file = open("/dev/full", "w", encoding="utf-8")  # noqa: SIM115
                for _ in range(3):
                    reply, _ = await client.request("clock")
                    assert reply[2] == b"virtual"
            finally:
                client.close()
                await client.wait_closed()
        finally:
            await device.stop()

    asyncio.run(scenario())
    full = [s for s in said if "cannot be written" in s]
    assert full == [f"{tmp_path / 'requests.jsonl'}: cannot be written "
                    f"({os.strerror(errno.ENOSPC)}); requests are no longer "
                    "logged, the 2 lines written before are kept"]
    assert len((tmp_path / "requests.jsonl").read_text().splitlines()) == 2
