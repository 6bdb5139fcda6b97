"""Scenarios: the 1990 scenario loads as documented, runs are reproducible, and malformed
scenarios are refused by the command line with one line naming the file, key and value.

Every malformed scenario is the real ``scenarios/ghigo1990.toml`` with one small textual edit
(``(old, new)`` replacement; ``old`` must occur exactly once), so each case shows which edit
breaks what. Each goes through ``antsim run BAD.toml --out DIR``: in-process through
``antsim.cli.main`` (stderr captured), and a few through a ``python -m antsim`` subprocess.
"""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import pytest

from antsim.cli import main
from antsim.documents import GHIGO1990_TABLE1_POSITIONS
from antsim.scenario import load_scenario
from antsim.simulate.runner import simulate
from controller.astro.sources import dec_dms_to_deg, ra_hms_to_deg


def test_ghigo1990_loads_as_documented(ghigo_path):
    s = load_scenario(ghigo_path)
    assert s.name == "ghigo1990"
    assert s.seed == 1
    assert (s.site.latitude_deg, s.site.longitude_deg, s.site.height_m) == (38.43, -79.84,
                                                                            800.0)
    assert s.duration_s == 24 * 3600.0
    assert s.epoch_utc.startswith("1990-02-08T17:00:00")
    assert [src.name for src in s.sources] == ["3C84", "Taurus A", "Orion A", "3C273",
                                               "Virgo A", "W31", "Cygnus A", "Cassiopeia A"]
    # at the report's Table 1 positions (B1950), to the precision it prints
    for src in s.sources:
        ra, dec = GHIGO1990_TABLE1_POSITIONS[src.name]
        assert (src.ra_deg, src.dec_deg) == pytest.approx(
            (ra_hms_to_deg(ra), dec_dms_to_deg(dec)), abs=1e-9)
        assert src.frame == "fk4"
    # 8 Feb 1990 (section IV): 0 to 15 C by day, -4 to 3 C at night
    assert (s.weather.air_min_c, s.weather.air_max_c) == (-4.0, 15.0)
    # Table 3 is given in arcmin and held in arcsec
    assert s.truth_model.as_dict()["W6"] == pytest.approx(12.24 * 60.0, abs=1e-9)
    assert [e.name for e in s.effects] == ["thermal", "irregularities", "tracking_jitter"]
    tsys = {c.name: c.tsys_k for c in s.receiver.channels}
    assert tsys["XL"] == pytest.approx(1.15 * tsys["XR"], rel=1e-9)  # XL 15% above XR
    # XL differs from XR by its Tsys alone (section IV): the same gain stability
    assert {c.gain_fluctuation for c in s.receiver.channels} == {None}
    # the control program carried refraction in its model's W5 (docs/physics.md)
    assert s.controller.refraction == "none" and s.truth_model.as_dict()["W5"] == 0.0
    assert s.controller.scan.step_arcmin == 7.0
    assert s.controller.scan.integration_s == 15.0
    # the catalogue carries the source sizes and the reduction widens the beam by them
    cat = {c.name: c for c in s.controller.sources}
    assert cat["Cassiopeia A"].size_arcmin == 3.46 and cat["3C84"].size_arcmin == 0.0
    assert s.controller.scan.use_source_size
    assert s.controller.scan.width_for(3.46) == pytest.approx(11.531, abs=1e-3)
    assert s.controller.scan.width_for(0.0) == 11.0
    assert (s.controller.sky.zenith_opacity, s.controller.sky.t_atm_k) == (0.010, 260.0)


def test_the_random_night_scenario_is_the_1990_one_but_for_the_night_residual(repo_root,
                                                                          ghigo_text):
    """scenarios/ghigo1990_random_night.toml (the plan's all-random night) is ghigo1990.toml
    from [site] on, but without the repeatable irregularities and with servo noise and
    buffeting large enough to give the night's rms alone: the two cannot drift apart."""
    random_text = (repo_root / "scenarios" / "ghigo1990_random_night.toml").read_text()
    base = load_scenario(repo_root / "scenarios" / "ghigo1990.toml")
    other = load_scenario(repo_root / "scenarios" / "ghigo1990_random_night.toml")
    assert [e.name for e in other.effects] == ["thermal", "tracking_jitter"]
    jitter = {e.name: e.params for e in base.effects}["tracking_jitter"]
    random_jitter = {e.name: e.params for e in other.effects}["tracking_jitter"]
    changed = {k for k in jitter if jitter[k] != random_jitter[k]}
    assert changed == {"xel_rms_arcsec", "el_rms_arcsec", "timescale_s"}
    assert random_jitter["el_rms_arcsec"] > 4 * jitter["el_rms_arcsec"]
    for name in ("site", "weather", "receiver", "beam", "atmosphere", "sources", "mount"):
        assert getattr(other, name) == getattr(base, name), name
    assert other.truth_model.as_dict() == base.truth_model.as_dict()
    assert other.controller.model.as_dict() == base.controller.model.as_dict()
    assert replace(other.controller, scenario_name="", model=None) == \
        replace(base.controller, scenario_name="", model=None)
    assert {e.name: e.params for e in other.effects}["thermal"] == \
        {e.name: e.params for e in base.effects}["thermal"]
    assert "[site]" in random_text and ghigo_text.count("[[truth.effects]]") == 3


# ---------------------------------------------------------------------------------------------
# reproducibility
def _rows_text(rows) -> str:
    """Rows as text: exact float reprs (shortest round-trip), NaN equal to NaN."""
    return repr(rows)


@pytest.fixture(scope="module")
def short_scenario(tmp_path_factory, short_ghigo_text):
    path = tmp_path_factory.mktemp("short") / "ghigo1990_3h.toml"
    path.write_text(short_ghigo_text, encoding="utf-8")
    return path


def test_same_scenario_and_seed_give_identical_rows_different_seeds_differ(short_scenario):
    scenario = load_scenario(short_scenario)
    first = simulate(scenario)
    second = simulate(load_scenario(short_scenario))
    assert first.n_scans > 10
    assert _rows_text(first.rows) == _rows_text(second.rows)
    assert first.truth == second.truth
    other = simulate(scenario, seed=scenario.seed + 1)
    assert other.truth["seed"] == scenario.seed + 1
    assert _rows_text(other.rows) != _rows_text(first.rows)
    # not only the bookkeeping: the measured offsets themselves differ
    assert [r["el_arcmin"] for r in other.rows[:6]] != [r["el_arcmin"] for r in first.rows[:6]]


def test_antsim_run_twice_writes_identical_bytes(short_scenario, tmp_path, capsys):
    outputs = []
    for name in ("a", "b"):
        out = tmp_path / name
        assert main(["run", str(short_scenario), "--out", str(out), "--no-progress"]) == 0
        outputs.append(out)
    capsys.readouterr()
    for filename in ("recordings.ecsv", "truth.json"):
        a, b = (o / filename for o in outputs)
        assert a.read_bytes() == b.read_bytes(), filename
    truth = json.loads((outputs[0] / "truth.json").read_text(encoding="utf-8"))
    assert set(truth) == {"seed", "model", "w_terms", "sign_convention", "terms", "effects",
                          "recoverable"}
    assert truth["terms"]["W6"]["value_arcsec"] == pytest.approx(734.4, abs=1e-9)  # 12.24'
    # and a different seed gives different recordings
    out = tmp_path / "c"
    assert main(["run", str(short_scenario), "--out", str(out), "--seed", "2",
                 "--no-progress"]) == 0
    capsys.readouterr()
    assert (out / "recordings.ecsv").read_bytes() != (outputs[0] / "recordings.ecsv"
                                                      ).read_bytes()


# ---------------------------------------------------------------------------------------------
# malformed scenarios: (edit old -> new) and the key and value the error line must name
BAD = {
    "missing key": (
        [("flux_jy = 50.0\n", "")], "sources[0].flux_jy", "'<missing>'"),
    "wrong type": (
        [('hpbw_arcmin = 11.0\n# Aperture', 'hpbw_arcmin = "11"\n# Aperture')],
        "beam.hpbw_arcmin", "'11'"),
    "unknown key": (
        [("settle_s = 2.5", "settle_s = 2.5\nsettle_time_s = 2.0")],
        "mount.settle_time_s", "2.0"),
    "unknown source in controller.scheduler.sources": (
        [('policy = "spread"', 'policy = "spread"\nsources = ["3C84", "3C286"]')],
        "controller.scheduler.sources", "'3C286'"),
    "negative integration time": (
        [("integration_s = 15.0", "integration_s = -15.0")],
        "controller.scan.integration_s", "-15.0"),
    "zero integration time": (
        [("integration_s = 15.0", "integration_s = 0")],
        "controller.scan.integration_s", "0.0"),
    "impossible site latitude": (
        [("latitude_deg = 38.43", "latitude_deg = 98.43")], "site.latitude_deg", "98.43"),
    "bad start time": (
        [('start_utc = "1990-02-08T17:00:00"', 'start_utc = "1990-02-30T17:00:00"')],
        "campaign.start_utc", "'1990-02-30T17:00:00'"),
    "zero duration": (
        [("duration_h = 24.0", "duration_h = 0.0")], "campaign.duration_h", "0.0"),
    "unknown effect": (
        [('effect = "tracking_jitter"', 'effect = "wind_gusts"')],
        "truth.effects[2].effect", "'wind_gusts'"),
    "bad effect parameter": (
        [("cloud_timescale_s = 1800.0", "cloud_timescale_s = 10.0")],
        "truth.effects[0].cloud_timescale_s", "10.0"),
    "unknown effect parameter": (
        [("xel_rms_arcsec = 5.0", "xel_rms_arcsecs = 5.0")],
        "truth.effects[2].xel_rms_arcsecs", "5.0"),
    "unknown term in the truth": (
        [("W10 = -1.79", "W11 = -1.79")], "truth.terms.W11", "-1.79"),
    "efficiency table length mismatch": (
        [("efficiency = [0.87, 0.90, 0.95, 1.0, 1.0]", "efficiency = [0.87, 0.90, 0.95, 1.0]")],
        "beam.efficiency", "[0.87, 0.9, 0.95, 1.0]"),
    "duplicate source": (
        [('name = "Virgo A"', 'name = "3C273"')], "sources[4].name", "'3C273'"),
    "source position out of range": (
        [('ra = "03h16m29.6s"', 'ra = "25h16m29.6s"')], "sources[0].ra", "'25h16m29.6s'"),
    "negative flux density": (
        [("flux_jy = 40.0", "flux_jy = -40.0")], "sources[3].flux_jy", "-40.0"),
    "step too large for the beam": (
        [("step_arcmin = 7.0", "step_arcmin = 14.0")], "controller.scan.step_arcmin", "14.0"),
    "elevation limit below the horizon": (
        [("min_deg = 5.0", "min_deg = -5.0")], "mount.el.min_deg", "-5.0"),
    "negative seed": ([("seed = 1\n", "seed = -1\n")], "seed", "-1"),
    # W31 moved to declination -60: from latitude 38.4 it culminates at -8 deg. The runner
    # names the declination key and its value in degrees.
    "source never above the elevation limit": (
        [('dec = "-20d19m36s"', 'dec = "-60d00m00s"')], "sources[5].dec", "-60.0"),
    "fixed term not fitted": (
        [('fit_model = "ghigo10"', 'fit_model = "ghigo10"\nfit_fixed = { P5 = 1.1 }')],
        "controller.fit_fixed.P5", "1.1"),
    "TOML syntax error": ([("seed = 1\n", "seed = = 1\n")], "TOML syntax", "line 7"),
    "negative a-priori sky opacity": (
        [("zenith_opacity = 0.010\nt_atm_k", "zenith_opacity = -0.01\nt_atm_k")],
        "controller.sky.zenith_opacity", "-0.01"),
    "unknown structure temperature sensor": (
        [("[controller.search]", '[structure_sensors]\nnames = ["dish_fornt"]\n\n'
                                 '[controller.search]')],
        "structure_sensors.names", "'dish_fornt'"),
    "negative structure sensor noise": (
        [("[controller.search]", "[structure_sensors]\nnoise_k = -0.1\n\n[controller.search]")],
        "structure_sensors.noise_k", "-0.1"),
    "source size switch not a boolean": (
        [("use_source_size = true", 'use_source_size = "yes"')],
        "controller.scan.use_source_size", "'yes'"),
}


def _check_error_line(err: str, path, key: str, value: str) -> None:
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith("antsim run: error: "), line
    assert str(path) in line, line
    assert key in line, line
    assert value in line, line


@pytest.mark.parametrize("case", list(BAD))
def test_malformed_scenario_one_line_error(case, ghigo_text, write_scenario, tmp_path, capsys):
    edits, key, value = BAD[case]
    path = write_scenario(ghigo_text, edits, name="bad.toml")
    out = tmp_path / "out"
    status = main(["run", str(path), "--out", str(out), "--no-progress"])
    captured = capsys.readouterr()
    assert status == 2
    assert captured.out == ""
    _check_error_line(captured.err, path, key, value)
    # the key is named as "key = value"
    assert f"{key} = " in captured.err or key == "TOML syntax"


def test_the_good_scenario_passes_the_same_check(ghigo_text, write_scenario):
    """The edits above are what breaks each file: the unedited text loads."""
    assert load_scenario(write_scenario(ghigo_text, [], name="good.toml")).name == "ghigo1990"


@pytest.mark.parametrize("case", ["missing key", "source never above the elevation limit"])
def test_a_refused_scenario_leaves_no_recordings_behind(case, ghigo_text, write_scenario,
                                                        tmp_path, capsys):
    """After fixing the file, the same ``--out`` must be usable without ``--resume``."""
    edits, _, _ = BAD[case]
    path = write_scenario(ghigo_text, edits, name="bad.toml")
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--no-progress"]) == 2
    capsys.readouterr()
    assert not (out / "recordings.ecsv").exists()


@pytest.mark.parametrize("case", ["negative integration time", "unknown effect",
                                  "source never above the elevation limit"])
def test_malformed_scenario_through_a_subprocess(case, ghigo_text, write_scenario, tmp_path,
                                                 repo_root):
    edits, key, value = BAD[case]
    path = write_scenario(ghigo_text, edits, name="bad.toml")
    proc = subprocess.run([sys.executable, "-m", "antsim", "run", str(path), "--out",
                           str(tmp_path / "out")], capture_output=True, text=True,
                          cwd=repo_root, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stdout == ""
    _check_error_line(proc.stderr, path, key, value)
