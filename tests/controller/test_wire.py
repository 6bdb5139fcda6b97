"""The project's KATCP client (controller.wire.KatcpAntenna) against antsim serve: antenna
errors as the in-process antenna gives them, and a cross scan's round trips."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pytest
import simpy

from antsim.scenario import load_scenario
from controller.protocol import AntennaError
from controller.wire import KatcpAntenna


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
