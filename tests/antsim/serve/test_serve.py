"""`antsim serve` (the simulated antenna as a KATCP device) and its clients.

Everything runs on loopback with ephemeral ports (``--port 0``); every socket read has a
timeout, and servers are stopped by their context managers, so a hung server fails a test
instead of hanging the suite.
"""

from __future__ import annotations

import json
import math
import pickle
import shutil
import signal
import socket
import subprocess
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import simpy

from antsim.cli import main as cli_main
from antsim.scenario import load_scenario
from antsim.serve.clock import parse_clock
from antsim.serve.process import ServerProcess
from antsim.serve.programtrack import ProgramTrack, TableError
from antsim.serve.remote import connect
from antsim.simulate.runner import run_campaign
from controller.protocol import AntennaError
from controller.wire import KatcpAntenna

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
def short_path(tmp_path_factory, short_ghigo_text) -> Path:
    path = tmp_path_factory.mktemp("serve") / "short.toml"
    path.write_text(short_ghigo_text, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def server(short_path):
    """One virtual-clock server of the 3-hour 1990 scenario for the robustness tests."""
    with ServerProcess(short_path) as srv:
        yield srv


# ---------------------------------------------------------------------------------------------
# the program track
# ---------------------------------------------------------------------------------------------
def test_program_track_reproduces_the_trajectory_bit_for_bit(ghigo_path):
    """The table of a SourceTrajectory, interpolated by the antenna, gives the trajectory's
    own positions to the bit inside the table; outside, a point sent at the instant used."""
    from controller.program.campaign import plan_targets
    from controller.scans.tracking import RefractionCorrection, SourceTrajectory, standard_weather

    config = load_scenario(ghigo_path).controller
    observer, targets = plan_targets(config)
    refraction = RefractionCorrection("weather", standard_weather(800.0), 8.4)
    traj = SourceTrajectory(observer.ephemeris, targets[-1].index, config.model, refraction,
                            1234.5, (0.3, -0.2))
    track = ProgramTrack(*traj.program_track())
    t = np.random.default_rng(7).uniform(track.start_s, track.end_s, 500)
    for got, want in zip(track(t), traj(t), strict=True):
        assert np.array_equal(got, want)
    later = track.end_s + 3600.0  # outside the table: computed exactly by the trajectory
    assert not traj.covers([later])
    az, el = traj(np.array([later]))
    track.add([later], az, el)
    assert np.array_equal(track(np.array([later]))[0], az)
    assert np.array_equal(track(np.array([later]))[1], el)


def test_program_track_interpolates_azimuth_the_short_way_and_names_bad_points():
    track = ProgramTrack([0.0, 10.0], [359.0, 1.0], [45.0, 46.0])
    az, el = track(np.array([2.5, 5.0, 10.0, 20.0]))
    assert np.allclose(az, [359.5, 0.0, 1.0, 1.0]) and np.allclose(el, [45.25, 45.5, 46, 46])
    with pytest.raises(TableError, match=r"point 2: time 5\.0 s does not follow 10\.0 s"):
        ProgramTrack([10.0, 5.0], [1.0, 2.0], [45.0, 45.0])
    with pytest.raises(TableError, match=r"point 1: elevation 91\.0 deg is outside"):
        ProgramTrack([0.0], [1.0], [91.0])
    with pytest.raises(TableError, match="triplets of time, azimuth, elevation: got 4 numbers"):
        ProgramTrack.from_numbers([0.0, 1.0, 2.0, 3.0])
    with pytest.raises(TableError, match=r"point 1: azimuth nan is not a finite number"):
        ProgramTrack.from_numbers([0.0, math.nan, 2.0])


@pytest.mark.parametrize(("text", "factor"), [("virtual", math.inf), ("realtime", 1.0),
                                               ("x10", 10.0), ("X2.5", 2.5)])
def test_clock_specifications(text, factor):
    assert parse_clock(text).factor == factor


@pytest.mark.parametrize("text", ["x0", "x-3", "fast", "x", "xinf"])
def test_bad_clock_specifications(text):
    with pytest.raises(ValueError, match="use virtual, realtime, or xK"):
        parse_clock(text)


# ---------------------------------------------------------------------------------------------
# the project's controller over the wire: the same recordings, to the byte
# ---------------------------------------------------------------------------------------------
def test_controller_over_the_wire_records_the_same_bytes(tmp_path, ghigo_path, capsys):
    """The 24-hour 1990 campaign: `antsim run --connect` against `antsim serve` (virtual
    clock) writes the recordings `antsim run` writes in process, byte for byte; the
    server's truth.json is the in-process run's but for the recoverable truth (what a fit of
    the campaign's scans should recover: the server sees no fit); the server logged every
    request."""
    run_campaign(load_scenario(ghigo_path), tmp_path / "in", show_progress=False)
    with ServerProcess(ghigo_path, out=tmp_path / "server") as srv:
        code = cli_main(["run", str(ghigo_path), "--out", str(tmp_path / "wire"),
                         "--no-report", "--connect", f"127.0.0.1:{srv.port}"])
        assert code == 0
        assert srv.stop() == 0
    assert "truth.json" not in capsys.readouterr().out  # the client has no truth to write
    assert not (tmp_path / "wire" / "truth.json").exists()
    wire = (tmp_path / "wire" / "recordings.ecsv").read_bytes()
    assert wire == (tmp_path / "in" / "recordings.ecsv").read_bytes()
    in_process = json.loads((tmp_path / "in" / "truth.json").read_text())
    assert "recoverable" in in_process
    assert json.loads((tmp_path / "server" / "truth.json").read_text()) == \
        {k: v for k, v in in_process.items() if k != "recoverable"}
    log = [json.loads(line) for line in
           (tmp_path / "server" / "requests.jsonl").read_text().splitlines()]
    requests = int(next(line for line in srv.lines if " after " in line)
                   .split(" after ")[1].split()[0])
    assert len(log) == requests > 5000
    assert {e["request"] for e in log} >= {"track", "offset", "integrate", "powers", "wait"}
    assert all(e["reply"] == "ok" for e in log if e["request"] == "integrate")


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


@pytest.mark.parametrize(("name", "hours", "what"), [
    ("fomalont1973_x.toml", 6.0, "feed angles"),
    ("fomalont1973_s.toml", 6.0, "feed angles, one channel"),
    ("crane1981_140ft_4990.toml", 6.0, "equatorial mount, idle beyond a track's table"),
    ("wright1992_bima_ant5.toml", 3.0, "optical camera"),
    ("ghigo1990_sensors.toml", 2.0, "structure temperatures read mid-scan"),
])
def test_other_telescopes_over_the_wire(tmp_path, repo_root, write_scenario, name, hours,
                                       what):
    text = (repo_root / "scenarios" / name).read_text(encoding="utf-8")
    old = next(line for line in text.splitlines() if line.startswith("duration_h = "))
    path = write_scenario(text, [(old, f"duration_h = {hours}")], name)
    scenario = load_scenario(path)
    inproc = run_campaign(scenario, tmp_path / "in", show_progress=False)
    assert inproc.n_scans > 10, what
    with ServerProcess(path) as srv:
        antenna, seed = connect(scenario, f"127.0.0.1:{srv.port}")
        with antenna:
            run_campaign(scenario, tmp_path / "wire", seed=seed, show_progress=False,
                         antenna=antenna)
    assert (tmp_path / "wire" / "recordings.ecsv").read_bytes() == \
        (tmp_path / "in" / "recordings.ecsv").read_bytes(), what


# ---------------------------------------------------------------------------------------------
# robustness
# ---------------------------------------------------------------------------------------------
def test_listens_on_loopback_and_says_so(server):
    assert server.host == "127.0.0.1"
    listening = next(line for line in server.lines if "listening on" in line)
    assert "loopback only" in listening and "--host 0.0.0.0" in listening


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


def test_the_python_client_fails_commands_with_antenna_errors(server):
    """As the in-process antenna does: the command's event fails with the reason; a command
    sent without waiting for its reply fails at the next reply read, naming the request,
    and those sent behind it are carried out."""
    with KatcpAntenna("127.0.0.1", server.port, simpy.Environment()) as antenna:
        assert antenna.channels == ("XR", "XL") and antenna.virtual
        low = antenna.track(lambda t: (np.full(np.shape(t), 10.0), np.full(np.shape(t), 2.0)))
        assert not low.ok and isinstance(low.value, AntennaError)
        assert "target elevation 2.00 deg at arrival is outside the limits" in str(low.value)
        camera = antenna.measure_offset(5.0)
        assert not camera.ok and "this antenna has no camera" in str(camera.value)
        assert antenna.track(lambda t: (np.full(np.shape(t), 200.0),
                                        np.full(np.shape(t), 45.0))).ok
        before = antenna.clock_s()
        bad = antenna.integrate(-1.0)  # sent; the reply is read later
        antenna.wait(2.0)
        with pytest.raises(AntennaError, match=r"^\?integrate -1\.0 defer: argument 1 "
                                               r"\(SECONDS\) '-1\.0': must be positive"):
            antenna.clock_s()
        assert antenna.clock_s() == before + 2.0  # the wait behind it was carried out
        with pytest.raises(AntennaError, match=r"\?integrate -1\.0 defer"):
            _ = bad.value.t_start_s
        antenna.release()


def test_a_cross_scan_waits_for_the_antenna_once_per_azimuth_point_and_once_after(
        server, short_path):
    """The project's cross scan over the wire: the track's reply is read at once, the clock
    before each azimuth point after the first (the step is divided by the cosine of the
    elevation at the point's middle), and everything else (the elevation points, the return
    to zero offset, the wait and the powers) in one round trip when the powers are read.
    What an integration command returned copies, pickles and is replaced as a plain
    Integration."""
    from controller.program.campaign import plan_targets
    from controller.protocol import Integration
    from controller.scans.scan import cross_scan
    from controller.scans.tracking import RefractionCorrection, SourceTrajectory

    config = load_scenario(short_path).controller
    observer, targets = plan_targets(config)
    env = simpy.Environment()
    with KatcpAntenna("127.0.0.1", server.port, env) as antenna:
        now = antenna.clock_s()
        refraction = RefractionCorrection("none", None, config.frequency_ghz)
        trajectories = [SourceTrajectory(observer.ephemeris, t.index, config.model,
                                         refraction, now, (0.0, 0.0)) for t in targets]
        traj = max(trajectories, key=lambda tr: tr.sky_elevation_deg(now + 300.0))
        requests, trips = antenna.requests, antenna.round_trips
        scan = env.process(cross_scan(env, antenna, traj, config.scan))
        env.run(scan)
        raw = scan.value
        assert antenna.round_trips - trips == 5  # the track and the azimuth points 2..5
        power, _, times = raw.powers()
        assert antenna.round_trips - trips == 6
        assert antenna.requests - requests == 1 + 11 + 10 + (config.scan.overhead_s > 0) + 1
        assert np.all(np.isfinite(power)) and np.all(np.diff(times[0, 0]) > 0)
        later = raw.integrations["el"][2]
        plain = replace(later)
        assert type(plain) is Integration and plain.t_start_s == later.t_start_s
        copied = pickle.loads(pickle.dumps(later))
        assert type(copied) is Integration and copied.power_k == dict(later.power_k)
        antenna.release()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signals_stop_the_server_cleanly_with_its_outputs(tmp_path, short_path, sig):
    with ServerProcess(short_path, out=tmp_path) as srv:
        c = LineClient(srv.port)
        c.request("?track 0 200 45 7200 230 60")
        c.request("?integrate 15")
        assert srv.stop(sig) == 0
        c.close()
    assert f"stopped ({sig.name}) after 2 requests" in srv.lines[-1]
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert truth["seed"] == 1 and "W6" in truth["terms"]
    log = [json.loads(line) for line in (tmp_path / "requests.jsonl").read_text().splitlines()]
    assert [e["request"] for e in log] == ["track", "integrate"]
    assert log[1]["reply"] == "ok" and len(log[1]["values"]) == 15


def test_accelerated_clock_follows_the_wall_clock(short_path):
    with ServerProcess(short_path, clock="x20") as srv:
        c = LineClient(srv.port)
        try:
            t0, w0 = float(c.request("?clock")[0].split()[2]), time.monotonic()
            assert c.request("?clock")[0].endswith(" x20")
            time.sleep(0.3)
            t1, w1 = float(c.request("?clock")[0].split()[2]), time.monotonic()
            # 20 simulated seconds per second; the bounds allow for a busy machine's delays
            assert 0.5 * 20 * (w1 - w0) < t1 - t0 < 1.5 * 20 * (w1 - w0) + 2.0
            w0 = time.monotonic()
            reply, _ = c.request("?wait 6")  # 6 simulated seconds: 0.3 s of wall time
            assert reply.startswith("!wait ok ") and time.monotonic() - w0 >= 0.25
            # between commands the antenna keeps following its track (1 deg per 100 s)
            t = float(c.request("?clock")[0].split()[2])
            c.request(f"?track {t} 180 45 {t + 1000} 190 45")  # from the park: no slew
            az0 = float(c.request("?encoder")[0].split()[2])
            time.sleep(0.5)
            az1 = float(c.request("?encoder")[0].split()[2])
            assert 0.05 < az1 - az0 < 0.5
            # commands sent together wait for one another: the second ?wait starts when
            # the first ends (0.1 s of wall time each)
            replies = c.pipeline(["?wait[51] 2", "?wait[52] 2"])
            first, second = (float(replies[m][0].split()[2]) for m in (51, 52))
            assert replies[52][0].startswith("!wait[52] ok ") and second >= first + 2.0
        finally:
            c.close()


def test_controller_on_an_accelerated_clock(tmp_path, ghigo_text, write_scenario):
    """The project's controller against a real-time clock (600 times accelerated): the
    antenna's clock runs on, so the client asks for it; half an hour of scans, all good."""
    path = write_scenario(ghigo_text, [
        ("duration_h = 24.0", "duration_h = 0.5"),
        ('policy = "spread"', 'policy = "spread"\nsources = ["Cygnus A", "Cassiopeia A"]')])
    scenario = load_scenario(path)
    with ServerProcess(path, clock="x600") as srv:
        antenna, seed = connect(scenario, f"127.0.0.1:{srv.port}")
        with antenna:
            assert not antenna.virtual and antenna.factor == 600.0
            result = run_campaign(scenario, tmp_path, seed=seed, show_progress=False,
                                  antenna=antenna)
    avg = [r for r in result.rows if r["polarization"] == "AVG"]
    assert len(avg) >= 3 and all(r["good"] for r in avg)
    assert max(abs(r["el_arcmin"]) for r in avg) < 3.0  # the model in use is within 0.4'


# ---------------------------------------------------------------------------------------------
# the command lines
# ---------------------------------------------------------------------------------------------
def test_bad_options_give_one_line_and_status_2(tmp_path, short_path, capsys):
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen()
    try:
        closed = socket.socket()
        closed.bind(("127.0.0.1", 0))
        free = closed.getsockname()[1]
        closed.close()  # nothing listens there now
        out = str(tmp_path / "o")
        cases = [
            (["serve", str(short_path), "--port", str(busy.getsockname()[1])],
             f"--port = {busy.getsockname()[1]}: address already in use"),
            (["serve", str(short_path), "--clock", "x0"], "--clock = 'x0': use virtual"),
            (["serve", str(short_path), "--port", "70000"], "--port = 70000: must be in"),
            (["serve", str(tmp_path / "missing.toml")], "missing.toml"),
            (["run", str(short_path), "--out", out, "--connect", "nowhere"],
             "--connect = 'nowhere': expected HOST:PORT"),
            (["run", str(short_path), "--out", out, "--seed", "3", "--connect",
              f"127.0.0.1:{free}"], "--seed = True: not with --connect"),
            (["run", str(short_path), "--out", out, "--connect", f"127.0.0.1:{free}"],
             "cannot connect to the antenna"),
        ]
        for argv, expected in cases:
            assert cli_main(argv) == 2, argv
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and "Traceback" not in err, err
            assert expected in err, (expected, err)
    finally:
        busy.close()


def test_connecting_with_another_epoch_is_refused(server, short_ghigo_text, write_scenario,
                                                  tmp_path, capsys):
    """The controller's ephemeris counts time from its scenario's epoch: another epoch
    than the antenna's would point at the wrong sky."""
    path = write_scenario(short_ghigo_text, [('start_utc = "1990-02-08T17:00:00"',
                                              'start_utc = "1990-02-08T18:00:00"')])
    assert cli_main(["run", str(path), "--out", str(tmp_path / "o"), "--connect",
                     f"127.0.0.1:{server.port}"]) == 2
    err = capsys.readouterr().err
    assert "the antenna's epoch is '1990-02-08T17:00:00.000', the scenario's " \
           "'1990-02-08T18:00:00.000'" in err and err.count("\n") == 1
    assert not (tmp_path / "o" / "recordings.ecsv").exists()


def test_serve_has_help(capsys):
    with pytest.raises(SystemExit):
        cli_main(["serve", "--help"])
    out = capsys.readouterr().out
    assert "--clock" in out and "realtime" in out and "127.0.0.1" in out


# ---------------------------------------------------------------------------------------------
# a client in another language
# ---------------------------------------------------------------------------------------------
def test_node_client_knows_the_1990_sources_where_the_scenario_has_them(repo_root, ghigo_path):
    """docs/katcp_client.mjs's source list (B1950 degrees, 5 decimals: 0.02" in declination,
    0.02" cos dec in right ascension) is the scenario's, i.e. the 1990 report's Table 1."""
    import re

    text = (repo_root / "docs" / "katcp_client.mjs").read_text(encoding="utf-8")
    listed = {name: (float(ra), float(dec)) for name, ra, dec in re.findall(
        r'"([^"]+)": \[([-0-9.]+), ([-0-9.]+)\]', text.split("const SOURCES")[1].split("};")[0])}
    scenario = {s.name: (s.ra_deg, s.dec_deg) for s in load_scenario(ghigo_path).sources}
    assert listed.keys() == scenario.keys()
    for name, (ra, dec) in scenario.items():
        assert listed[name] == pytest.approx((ra, dec), abs=5e-6), name


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed")
def test_node_client_scans_a_source_and_finds_what_its_model_misses(tmp_path, repo_root,
                                                                     ghigo_path):
    """docs/katcp_client.mjs tracks Cas A with its own ephemeris and the 1990 model in use,
    deliberately put 4' off in elevation zero (W1) and 3' in azimuth zero (W6; the report's
    section II), runs one cross scan and prints the offsets: they must be the injected truth
    minus its model, plus the mount's repeatable irregularities there (the world's truth
    beyond the ten W's), scaled by 0.91 (Cas A's 3.46' size shrinks measured offsets by
    11^2 / (11^2 + 3.46^2), docs/physics.md). The client corrects refraction from the
    antenna's weather, as the world refracts; the Sun's heating at noon (about 2' in
    elevation at Cas A) is added as the world's heating effect gives it in the scan's first
    minutes (the virtual clock starts the campaign there; the feed legs and the yoke at their
    equilibrium for Cas A). Tolerance 0.5': the heating's change over the scan's minutes and
    the legs' approach to equilibrium (about 0.1'), the client's ephemeris and refraction (no
    nutation or aberration, a cot E law: about 0.3')."""
    from antsim.world.effects import EFFECTS
    from antsim.world.world import World
    from controller.pointing.model import PointingModel

    model = {"W1": -5.6, "W2": 0.0, "W3": -1.8, "W4": -2.0, "W5": 0.6, "W6": 15.0, "W7": 1.5,
             "W8": -0.5, "W9": -3.0, "W10": -1.5}
    with ServerProcess(ghigo_path) as srv:
        run = subprocess.run(["node", str(repo_root / "docs" / "katcp_client.mjs"), "--port",
                              str(srv.port), "--model",
                              ",".join(f"{k}={v}" for k, v in model.items())],
                             capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert "tracking Cassiopeia A" in run.stderr
    result = json.loads(run.stdout)
    az, el = math.radians(result["az_deg"] % 360.0), math.radians(result["el_deg"])
    scenario = load_scenario(ghigo_path)
    truth = scenario.truth_model
    used = PointingModel("ghigo10", {k: 60.0 * v for k, v in model.items()})
    (ta, te), (ma, me) = truth.offset_rad(az, el), used.offset_rad(az, el)
    (spec,) = [e for e in scenario.effects if e.name == "irregularities"]
    irregular = EFFECTS[spec.name](**spec.params)
    irregular.start(None, None)  # the antenna's own pattern: no generator of the run's
    i_xel, i_el = irregular.errors_arcsec(az, el)
    world = World(scenario, simpy.Environment(), None)  # the server's world: its seed
    heating = next(e for e in world.effects if e.name == "thermal")
    h_xel, h_el = (float(v) for v in heating.equilibrium_errors_arcsec(120.0, az, el))
    expected_xel = 0.91 * (math.degrees(float(ta - ma)) * 60.0 * math.cos(el)
                           + (i_xel + h_xel) / 60.0)
    expected_el = 0.91 * (math.degrees(float(te - me)) * 60.0 + (i_el + h_el) / 60.0)
    # the test can tell a sign: a flipped one is off by twice the value, beyond 2 x 0.5'
    assert abs(expected_xel) > 1.0 and abs(expected_el) > 2.0
    assert result["xel_arcmin"] == pytest.approx(expected_xel, abs=0.5)
    assert result["el_arcmin"] == pytest.approx(expected_el, abs=0.5)
