"""docs/katcp_client.mjs, a client in another language (node), against antsim serve."""

from __future__ import annotations

import json
import math
import shutil
import subprocess

import pytest
import simpy

from antsim.scenario import load_scenario
from antsim.serve.process import ServerProcess


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
