"""The scheduler (controller.program.scheduler) through whole campaigns: the 1990 campaign's
scans spread over every source and the sky, and a night window keeps the Sun down."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from antsim.simulate.runner import simulate


def test_ghigo1990_gives_about_300_scans_over_all_sources(ghigo):
    result = simulate(ghigo)
    avg = [r for r in result.rows if r["polarization"] == "AVG"]
    assert 250 <= len(avg) <= 350
    assert {r["source"] for r in avg} == {s.name for s in ghigo.sources}
    # scans are spread over the sky: every quadrant of azimuth is visited, low and high
    az = np.array([r["az_deg"] for r in avg])
    el = np.array([r["el_deg"] for r in avg])
    for lo in (0, 90, 180, 270):
        assert np.any((az >= lo) & (az < lo + 90))
    assert el.min() < 20 and el.max() > 60
    # by day and by night
    sun = np.array([r["sun_el_deg"] for r in avg])
    assert (sun > 0).sum() > 60 and (sun < -12).sum() > 60
    # three rows per scan: XR, XL and their average
    pols = [r["polarization"] for r in result.rows]
    assert pols.count("XR") == pols.count("XL") == pols.count("AVG")


def test_night_window_keeps_the_sun_down(ghigo):
    sched = replace(ghigo.controller.scheduler, window="night")
    sc = replace(ghigo, controller=replace(ghigo.controller, scheduler=sched))
    result = simulate(sc)
    sun = np.array([r["sun_el_deg"] for r in result.rows])
    assert len(sun) > 0
    # the scan starts at night; it lasts about 4 minutes, in which the Sun rises < 1 deg
    assert sun.max() < -11.0
