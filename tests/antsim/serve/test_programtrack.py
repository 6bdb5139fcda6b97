"""The program track (antsim.serve.programtrack): the table the antenna interpolates."""

from __future__ import annotations

import math

import numpy as np
import pytest

from antsim.scenario import load_scenario
from antsim.serve.programtrack import ProgramTrack, TableError


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
