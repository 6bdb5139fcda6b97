"""How simulated time passes in antsim serve (antsim.serve.clock): the clock options, and
an accelerated clock against the wall clock and under the project's controller."""

from __future__ import annotations

import math
import time

import pytest

from antsim.scenario import load_scenario
from antsim.serve.clock import parse_clock
from antsim.serve.process import ServerProcess
from antsim.serve.remote import connect
from antsim.simulate.runner import run_campaign
from tests.antsim.serve.conftest import LineClient


@pytest.mark.parametrize(("text", "factor"), [("virtual", math.inf), ("realtime", 1.0),
                                               ("x10", 10.0), ("X2.5", 2.5)])
def test_clock_specifications(text, factor):
    assert parse_clock(text).factor == factor


@pytest.mark.parametrize("text", ["x0", "x-3", "fast", "x", "xinf"])
def test_bad_clock_specifications(text):
    with pytest.raises(ValueError, match="use virtual, realtime, or xK"):
        parse_clock(text)


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
