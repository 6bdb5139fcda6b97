"""The KATCP device of antsim serve (antsim.serve.device): requests through a bare client,
one controlling client and others watching, clients that go mid-scan or mid-pipeline, and
a track served as the in-process antenna takes it."""

from __future__ import annotations

import math
import time

import numpy as np
import simpy

from antsim.scenario import load_scenario
from antsim.serve.process import ServerProcess
from controller.wire import KatcpAntenna
from tests.antsim.serve.conftest import TIMEOUT_S, LineClient


class _SetWithinTheHour:
    """A trajectory with a 900 s table, and beyond it the elevation a SourceTrajectory gives
    an hour ahead for a source that has set by then: the 1990 model's W5 = 0.6' cot E at an
    observed elevation of 0.0054 deg (the 24-hour 1990 run's Virgo A at 14:13 UTC looked
    to 15:13) put the encoder at 105.87 deg. The azimuth there is 160 deg past the table's:
    on the turn nearer the parked antenna (300 deg on the -90..450 wrap) the source would run
    into the limit within the hour, so the slew planner takes the other turn (-60 deg)."""

    def __init__(self, now_s: float):
        self.t = now_s - 30.0 + 2.0 * np.arange(451)
        self.az = np.linspace(300.0, 301.0, self.t.size)
        self.el = np.linspace(30.0, 28.0, self.t.size)

    def program_track(self):
        return self.t.copy(), self.az.copy(), self.el.copy()

    def covers(self, t_s) -> bool:
        t = np.asarray(t_s, dtype=float)
        return bool(t.min() >= self.t[0] and t.max() <= self.t[-1])

    def __call__(self, t_s):
        t = np.asarray(t_s, dtype=float)
        if self.covers(t):
            return np.interp(t, self.t, self.az), np.interp(t, self.t, self.el)
        return np.full(t.shape, 100.0), np.full(t.shape, 105.8694715614095)


def test_a_track_whose_look_ahead_has_set_is_the_in_process_track(short_path):
    """The slew planner's look an hour ahead (for the cable wrap) reads only the azimuth;
    over the wire the track is not refused for the meaningless elevation there, and the
    antenna slews as the in-process one does, to the bit (the turn chosen from the look's
    azimuth)."""
    from antsim.world.world import SimulatedAntenna, World

    scenario = load_scenario(short_path)
    env = simpy.Environment()
    local = SimulatedAntenna(World(scenario, env))
    here = local.track(_SetWithinTheHour(local.clock_s()))
    env.run(here)
    with ServerProcess(short_path) as srv, \
            KatcpAntenna("127.0.0.1", srv.port, simpy.Environment()) as antenna:
        there = antenna.track(_SetWithinTheHour(antenna.clock_s()))
        assert there.ok, there.value
        assert there.value == here.value
        assert antenna.encoder_deg() == local.encoder_deg()
        antenna.release()
    assert -90.0 < local.encoder_deg()[0] < 0.0  # the turn the look's azimuth chose


def test_bad_requests_get_failure_replies_and_the_connection_stays_usable(server):
    c = LineClient(server.port)
    try:
        assert c.request("?integrate abc")[0] == \
            r"!integrate fail argument\_1\_(SECONDS)\_'abc'\_is\_not\_a\_number"
        assert c.request("?integrate")[0] == \
            r"!integrate fail argument\_1\_(SECONDS)\_is\_missing"
        assert c.request("?integrate -2")[0].endswith(r"must\_be\_positive")
        assert c.request("?offset 1 2 3")[0].startswith(r"!offset fail too\_many\_arguments")
        assert c.request("?track 0 180 45 0 181 45")[0].endswith(
            r"point\_2:\_time\_0.0\_s\_does\_not\_follow\_0.0\_s\_(times\_must\_increase)")
        assert c.request("?no-such-request 1")[0] == \
            r"!no-such-request invalid unknown\_request\_no-such-request"
        assert c.request("?powers 99")[0].startswith(r"!powers fail integration\_99\_is\_not")
        c.send("this is not katcp")  # no request name to reply to: a #log error inform
        reply, _ = c.request("?watchdog")
        assert reply == "!watchdog ok"
        assert any(line.startswith("#log error") for line in c.asynchronous)
        reply, _ = c.request("?clock")
        assert reply.startswith("!clock ok ") and reply.endswith(" virtual")
    finally:
        c.request("?release")
        c.close()


def test_one_client_controls_others_watch_sensors(server):
    a, b = LineClient(server.port), LineClient(server.port)
    try:
        reply, _ = a.request("?track 0 120 40 7200 150 50")
        assert reply.startswith("!track ok ")
        refused, _ = b.request("?wait 10")
        assert refused.startswith("!wait fail client\\_127.0.0.1:")
        assert "controls\\_the\\_antenna" in refused and "?release" in refused
        # the watcher reads and subscribes; the controller's commands reach it as updates
        assert b.request("?encoder")[0].startswith("!encoder ok ")
        reply, _ = b.request("?sensor-sampling encoder.az event")
        assert reply == "!sensor-sampling ok encoder.az event"
        a.request("?offset 0.5 0")
        clock = float(a.request("?wait 30")[0].split()[2])
        # sensor times are simulated UTC: the epoch, 1990-02-08T17:00:00 UTC, plus the clock
        stamp = 634496400.0 + clock

        def after_wait() -> list[list[str]]:
            updates = [u.split() for u in b.asynchronous if u.startswith("#sensor-status ")]
            return [u for u in updates if abs(float(u[1]) - stamp) < 1e-3]

        deadline = time.monotonic() + TIMEOUT_S
        while not after_wait() and time.monotonic() < deadline:
            b.asynchronous.append(b.line())
        _, _, _, name, status, value = after_wait()[0]
        assert (name, status) == ("encoder.az", "nominal")
        assert 120.5 < float(value) < 151.0
        assert a.request("?release")[0] == "!release ok"
        assert b.request("?wait 1")[0].startswith("!wait ok ")  # now b controls
    finally:
        b.request("?release")
        a.close()
        b.close()


def test_a_client_that_disconnects_mid_scan_leaves_the_server_ready(server):
    a = LineClient(server.port)
    assert a.request("?track 0 200 45 7200 230 60")[0].startswith("!track ok ")
    a.request("?offset 0.2 0")
    assert a.request("?integrate 5 defer")[0].startswith("!integrate ok ")
    a.request("?offset 0.4 0")
    a.close()  # gone mid-scan: an integration never read, an offset set
    b = LineClient(server.port)
    try:
        assert b.track_once_free("?track 0 200 45 7200 230 60").startswith("!track ok ")
        values = b.request("?integrate 5")[0].split()[2:]
        assert len(values) == 11 + 2 * 2  # ... and the powers and std of XR and XL
        assert all(math.isfinite(float(v)) for v in values)
    finally:
        b.request("?release")
        b.close()


def test_pipelined_commands_are_carried_out_in_order_and_matched_by_id(server):
    """A scan's offsets and deferred integrations in one write: carried out one after the
    other (each reply's clock follows the one before by at least what the command took),
    the replies matched by message id, and ?powers without arguments reads the integrations
    this client left waiting."""
    c = LineClient(server.port)
    try:
        assert c.request("?track 0 200 45 90000 230 60")[0].startswith("!track ok ")
        lines = []
        for k, step in enumerate((-0.2, 0.0, 0.2)):
            lines += [f"?offset[{10 + 2 * k}] {step} 0", f"?integrate[{11 + 2 * k}] 5 defer"]
        lines += ["?offset[16] 0 0", "?wait[17] 3", "?powers[18]"]
        replies = c.pipeline(lines)
        assert all(r.split()[1] == "ok" for r, _ in replies.values()), replies
        clock = {mid: float(replies[mid][0].split()[2]) for mid in range(10, 18)}
        took = {11: 5.0, 13: 5.0, 15: 5.0, 17: 3.0}  # the offsets' moves: in their replies
        for mid in range(11, 18):
            seconds = took.get(mid) or float(replies[mid][0].split()[3])
            assert clock[mid] >= clock[mid - 1] + seconds - 1e-6, (mid, clock)
        idents = [int(replies[mid][0].split()[3]) for mid in (11, 13, 15)]
        reply, informs = replies[18]
        assert reply == "!powers[18] ok 3"
        assert [int(i.split()[1]) for i in informs] == idents
        assert c.pipeline(["?powers[19]"])[19][0] == "!powers[19] ok 0"  # none left
    finally:
        c.request("?release")
        c.close()


def test_a_pipelined_client_that_disconnects_mid_pipeline_leaves_the_server_ready(server):
    """A client sends a scan's commands in one write, the last cut short, and goes without
    reading a reply: the next client gets the antenna, none of the first client's
    integrations is waiting for it, and its own scan works. The server says once that the
    first client left (if it got as far as controlling), not once per reply it could not
    send."""
    a = LineClient(server.port)
    a_address = "{}:{}".format(*a.sock.getsockname())
    for _ in range(3):  # #version-connect: read, so that closing is a clean end of stream
        a.line()
    lines = ["?track[1] 0 200 45 90000 230 60"]
    for k in range(20):
        lines += [f"?offset[{2 + 2 * k}] {0.1 * (k % 5 - 2)} 0",
                  f"?integrate[{3 + 2 * k}] 5 defer"]
    a.sock.sendall(("\n".join(lines) + "\n?integrate[99] 5 de").encode())
    a.close()
    b = LineClient(server.port)
    b_address = "{}:{}".format(*b.sock.getsockname())
    try:
        assert b.track_once_free("?track 0 200 45 90000 230 60").startswith("!track ok ")
        replies = b.pipeline(["?offset[1] 0.1 0", "?integrate[2] 5 defer", "?powers[3]"])
        ident = int(replies[2][0].split()[3])
        reply, informs = replies[3]
        assert reply == "!powers[3] ok 1" and int(informs[0].split()[1]) == ident
        assert all(math.isfinite(float(v)) for v in informs[0].split()[2:])
    finally:
        b.request("?release")
        b.close()
    deadline = time.monotonic() + TIMEOUT_S  # the server's lines arrive through a pipe
    while not any(f"client {b_address} controls" in line for line in server.lines) \
            and time.monotonic() < deadline:
        time.sleep(0.05)
    mine = server.lines[next(i for i, line in enumerate(server.lines)
                             if f"client {a_address} connected" in line):]
    if any(f"client {a_address} controls the antenna" in line for line in mine):
        assert any(f"client {a_address} no longer controls the antenna (disconnected)" in line
                   for line in mine), mine
    assert not any("socket.send()" in line for line in mine), mine
