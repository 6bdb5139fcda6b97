"""Structure temperature sensors (antsim.world.sensors): they read the temperatures that drive
the thermal deformation, with their imperfections; the controller records them; the 1990
antenna (no sensors) is unchanged; the KATCP server serves them."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import simpy

from antsim.cli import main as cli_main
from antsim.run.outputs import run_fits
from antsim.scenario import load_scenario
from antsim.serve.process import ServerProcess
from antsim.simulate.runner import run_campaign, simulate
from antsim.world.sensors import _lagged_step
from antsim.world.world import World
from controller.errors import InputError
from controller.pointing.model import PointingModel
from controller.pointing.modelio import model_to_json
from controller.pointing.thermal import SENSOR_FAMILY, STRUCTURE_SENSORS, structure_column
from controller.program.recordings import COLUMNS, read_recordings, recording_columns
from tests.conftest import SHORT_EDITS, edit_text

#: the sensors without imperfections: what they read is the structure's temperature
IDEAL = (("noise_k = 0.05", "noise_k = 0.0"), ("resolution_k = 0.1", "resolution_k = 0.0"),
         ("lag_s = 60.0", "lag_s = 0.0"), ("local_k = 0.3", "local_k = 0.0"))


@pytest.fixture(scope="module")
def sensors_text(repo_root) -> str:
    return (repo_root / "scenarios" / "ghigo1990_sensors.toml").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def short_sensors(tmp_path_factory, sensors_text):
    """The sensor scenario cut to its first 3 hours, as the 1990 one in conftest."""
    path = tmp_path_factory.mktemp("sensors") / "short.toml"
    path.write_text(edit_text(sensors_text, SHORT_EDITS), encoding="utf-8")
    return path


def test_the_sensor_scenario_is_the_1990_scenario_with_sensors(sensors_text, ghigo_text):
    """Everything but the header (name, description, comments) and the [structure_sensors]
    table is ghigo1990.toml's, line for line: the two cannot drift apart."""
    def body(text: str) -> list[str]:
        return text[text.index("[site]"):].splitlines()

    ours, base = body(sensors_text), body(ghigo_text)
    assert ours[:len(base)] == base
    extra = "\n".join(ours[len(base):])
    assert "[structure_sensors]" in extra and "[[" not in extra
    assert load_scenario_text_name(sensors_text) == "ghigo1990_sensors"


def load_scenario_text_name(text: str) -> str:
    return next(line for line in text.splitlines() if line.startswith("name = ")).split('"')[1]


def test_ideal_sensors_read_the_temperatures_that_bend_the_structure(short_sensors,
                                                                      write_scenario):
    """Without noise, resolution, lag or local wander, each pair's difference is the thermal
    effect's own difference (the pedestal on its grid; the feed legs and the yoke at the
    instants their state advanced to), and a pair's mean is the structure's mean temperature:
    the sensors see the members, not their deformation."""
    path = write_scenario(short_sensors.read_text(), IDEAL, "ideal.toml")
    result = simulate(load_scenario(path))
    world = result.world
    sensors, thermal = world.sensors, world.sensors.thermal
    t = 5000.3
    r = sensors.read(t, 0.0, 0.5)
    grid = thermal.t_grid
    assert r["pedestal_east"] - r["pedestal_west"] == pytest.approx(
        np.interp(t, grid, thermal.pedestal_e_k), abs=1e-9)
    assert r["pedestal_north"] - r["pedestal_south"] == pytest.approx(
        np.interp(t, grid, thermal.pedestal_n_k), abs=1e-9)
    assert 0.5 * (r["pedestal_north"] + r["pedestal_south"]) == pytest.approx(
        np.interp(t, grid, thermal.structure_c), abs=1e-9)
    last = max(thermal.parts_log)
    _, values, _, _ = thermal.parts_log[last]
    r = sensors.read(last, 0.0, 0.5)
    pairs = (("dish_front", "dish_back"), ("dish_right", "dish_left"),
             ("yoke_front", "yoke_back"), ("yoke_right", "yoke_left"))
    for (plus, minus), value in zip(pairs, values, strict=True):
        assert r[plus] - r[minus] == pytest.approx(value, abs=1e-9), plus
    assert max(abs(v) for v in values) > 0.1  # the Sun was up: the check compares something
    assert result.truth["thermal_terms"]["TEYFB"] == thermal.k["yoke_bow"]
    assert result.truth["thermal_terms"]["TPYRL"] == thermal.k["yoke_roll"]


def test_a_lagged_sensor_follows_its_member_as_the_equations_say():
    """The sensor's exact step (member relaxing towards f with tau_g, sensor lagging with
    tau_s) against a fine Euler integration of the same two equations."""
    s, g, f, tau_g, tau_s = 0.0, 4.0, -1.0, 180.0, 60.0
    dt = 0.01
    for _ in range(int(150.0 / dt)):
        s += (g - s) / tau_s * dt
        g += (f - g) / tau_g * dt
    assert _lagged_step(0.0, 4.0, -1.0, 150.0, tau_g, tau_s) == pytest.approx(s, abs=2e-3)
    equal = _lagged_step(0.0, 4.0, -1.0, 150.0, 60.0, 60.0)
    assert equal == pytest.approx(_lagged_step(0.0, 4.0, -1.0, 150.0, 60.0 + 1e-6, 60.0),
                                  abs=1e-6)
    assert _lagged_step(0.0, 4.0, -1.0, 150.0, tau_g, 0.0) == pytest.approx(
        -1.0 + 5.0 * math.exp(-150.0 / tau_g))


def test_readings_have_the_resolution_and_noise_of_the_thermometers(short_sensors):
    """Readings are whole tenths of a kelvin; a reading depends on its time only (twice at
    one time: the same values); without the Sun the two faces of a part differ by the noise
    alone, 0.05 K per sensor (quantised to 0.1 K: the difference's rms is about 0.1 K)."""
    scenario = load_scenario(short_sensors)
    world = World(scenario, simpy.Environment())
    night = np.arange(40) * 97.0 + 30000.0  # after 01:20 UTC: Sun set, faces relaxed
    readings = [world.sensors.read(t, 0.0, 0.5) for t in night]
    assert readings[3] == world.sensors.read(night[3], 0.0, 0.5)
    for r in readings:
        assert all(abs(v * 10 - round(v * 10)) < 1e-6 for v in r.values())
    diff = np.array([r["dish_front"] - r["dish_back"] for r in readings])
    # rms of the quantised difference of two N(0, 0.05) readings: 0.07-0.13 K for 40 draws
    assert 0.05 < np.sqrt(np.mean(diff ** 2)) < 0.15
    assert set(readings[0]) == set(STRUCTURE_SENSORS)


@pytest.fixture(scope="module")
def short_runs(tmp_path_factory, short_sensors, short_ghigo_text):
    """The 3-hour campaign without and with sensors (seed 1): results and directories."""
    out = tmp_path_factory.mktemp("runs")
    (out / "plain.toml").write_text(short_ghigo_text, encoding="utf-8")
    plain = run_campaign(load_scenario(out / "plain.toml"), out / "plain", show_progress=False)
    withs = run_campaign(load_scenario(short_sensors), out / "sensors", show_progress=False)
    return plain, withs, out


def test_sensors_change_nothing_of_the_world_and_are_recorded(short_runs):
    """The same seed with and without sensors: the same scans and offsets (to 1e-8', the
    last bits change with which integrations the antenna computes together when it reads
    the dish's temperatures), the recordings gain the sensors' columns only; the 1990
    antenna's columns are the 1990 set."""
    plain, withs, tmp_path = short_runs
    assert len(plain.rows) == len(withs.rows) > 50
    for a, b in zip(plain.rows, withs.rows, strict=True):
        assert a["scan"] == b["scan"] and a["source"] == b["source"]
        assert a["xel_arcmin"] == pytest.approx(b["xel_arcmin"], abs=1e-8)
        assert a["el_arcmin"] == pytest.approx(b["el_arcmin"], abs=1e-8)
    assert recording_columns() == COLUMNS
    names = read_recordings(tmp_path / "plain" / "recordings.ecsv").colnames
    assert not any(c.startswith("temp_") for c in names)
    table = read_recordings(tmp_path / "sensors" / "recordings.ecsv")
    extra = [c for c in table.colnames if c not in names]
    assert len(extra) == 2 + 2 * len(STRUCTURE_SENSORS)
    assert table[structure_column("dish_front", "el")].unit == "deg_C"
    gap = np.asarray(table["temp_el_t_s"]) - np.asarray(table["temp_xel_t_s"])
    assert np.all((gap > 80.0) & (gap < 140.0))  # one half of a cross scan apart
    assert table.meta["structure_sensors"]["lag_s"] == 60.0
    truth = json.loads((tmp_path / "sensors" / "truth.json").read_text())
    assert "thermal_terms" in truth and "thermal_terms" not in plain.truth


def test_antsim_fit_reads_the_structure_temperatures(short_runs, capsys):
    """`antsim fit --terms ...,TEDFB` fits the recorded temperatures (corrected for the
    sensors' lag, as fit T); on recordings without sensors it is one line naming what is
    missing, status 2; proxies need no sensors."""
    _, _, out = short_runs
    terms = ",".join([*(f"W{i}" for i in range(1, 11)), "TEDFB"])
    assert cli_main(["fit", str(out / "sensors" / "recordings.ecsv"), "--terms", terms,
                     "--json"]) == 0
    fitted = json.loads(capsys.readouterr().out)["terms"]
    # fitted, with TPOINT's sigma; the honest one is blank: three hours are three time
    # blocks, too few for a jackknife (docs/outputs.md, "The honest sigma")
    assert math.isfinite(fitted["TEDFB"]["value_arcsec"])
    assert math.isfinite(fitted["TEDFB"]["sigma_arcsec"])
    assert cli_main(["fit", str(out / "plain" / "recordings.ecsv"), "--terms", terms]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "dish_back, dish_front" in err
    assert cli_main(["fit", str(out / "plain" / "recordings.ecsv"), "--terms",
                     terms.replace("TEDFB", "TEFACE")]) == 0


@pytest.fixture(scope="module")
def sunny_day(repo_root):
    """The 24-hour run with sensors, seed 1."""
    return simulate(load_scenario(repo_root / "scenarios" / "ghigo1990_sensors.toml"))


def test_fit_t_of_a_sunny_day_with_sensors(sunny_day):
    """The 24-hour run with sensors (seed 1): fit T adds the six pair terms together, each
    within 3 honest sigma of the truth, and its Sky RMS is lower than fit A's."""
    result = sunny_day
    fits = run_fits(result)
    fit_t, truth = fits["T"], result.truth["thermal_terms"]
    assert fit_t.names[10:] == SENSOR_FAMILY
    assert fit_t.notes[1].startswith(", ".join(SENSOR_FAMILY) + " added together (F = ")
    for name in fit_t.names[10:]:
        j = fit_t.names.index(name)
        assert abs(fit_t.values_arcsec[j] - truth[name]) < 3 * fit_t.sigma_honest_arcsec[j]
    assert fit_t.sky_rms_arcsec < 0.95 * fits["A"].sky_rms_arcsec
    assert fit_t.notes[0].startswith("thermal terms tested: (TEDFB TSDRL TEYFB")


def test_a_model_with_thermal_terms_is_refused_as_the_controller_model(
        tmp_path, short_ghigo_text, write_scenario, capsys):
    """The controller applies no thermal model (it would need the temperatures at every
    instant): --model and a scenario's model file with TEDFB are one line, status 2."""
    model = tmp_path / "thermal.json"
    model.write_text(json.dumps(model_to_json(PointingModel(["W1", "TEDFB"], [-100.0, 20.0]))))
    path = write_scenario(short_ghigo_text, (), "short.toml")
    code = cli_main(["run", str(path), "--out", str(tmp_path / "out"), "--model", str(model)])
    err = capsys.readouterr().err
    assert code == 2 and len(err.splitlines()) == 1 and "thermal terms (TEDFB)" in err
    in_file = write_scenario(short_ghigo_text, [('model = "ghigo10"\nunits = "arcmin"\n'
                                                 '[controller.terms]',
                                                 f'model = "{model}"\n[controller.terms]')],
                             "in_file.toml")
    with pytest.raises(InputError, match=r"controller.model.*thermal terms"):
        load_scenario(in_file)


def test_the_server_serves_the_structure_temperatures(short_sensors):
    """?antenna counts the sensors, ?structure-temperatures reads them (one inform each),
    and the structure.NAME sensors hold that reading."""
    from tests.antsim.serve.conftest import LineClient

    with ServerProcess(short_sensors) as srv:
        client = LineClient(srv.port)
        try:
            _, informs = client.request("?antenna")
            assert "#antenna structure-temperatures 12" in informs
            client.request("?wait 3600")
            reply, informs = client.request("?structure-temperatures")
            assert reply == "!structure-temperatures ok 12"
            reading = dict(line.split()[1:3] for line in informs)
            assert set(reading) == set(STRUCTURE_SENSORS)
            reply, informs = client.request("?sensor-value structure.dish_front")
            assert informs[0].split()[-1] == reading["dish_front"]
        finally:
            client.close()


def test_diagnose_names_the_thermal_effect_in_the_sensors_terms(sunny_day, tmp_path):
    """The same recordings against their model in use (the ten W's, no thermal terms):
    diagnose names the thermal effect first, with the sensors' terms, and the Sky RMS falls
    in sample and on held-out scans (5-fold, interleaved in time); the finding goes into the
    updated model, and the outputs say why not into the scenario."""
    from antsim.diagnose.core import diagnose
    from antsim.diagnose.data import from_rows
    from antsim.diagnose.modelit import write_outputs
    from antsim.simulate.runner import recording_meta

    scenario = sunny_day.scenario
    obs = from_rows(sunny_day.rows, recording_meta(scenario, 1, scenario.controller.model))
    assert set(obs.structure) == set(STRUCTURE_SENSORS)
    diag = diagnose(obs)
    first = diag.findings[0].to_json()
    assert first["effect"] == "thermal" and {"TEDFB", "TSDRL"} <= set(first["terms"])
    assert "structure temperature sensors see it" in first["explanation"]
    s = diag.summary
    # seed 1: 45.3" -> 22.8" in sample, 45.9" -> 24.1" held out (before the pedestal's tilt
    # went towards the cooler side in both directions 39.5" -> 22.0", 40.1" -> 22.9"); 5% is
    # beyond the held-out Sky RMS's own noise on the same scans
    assert s["sky_rms_after_arcsec"] < 0.95 * s["sky_rms_before_arcsec"]
    assert s["cv_sky_rms_after_arcsec"] < 0.95 * s["cv_sky_rms_before_arcsec"]
    readme = " ".join((Path(__file__).resolve().parents[3] / "docs" / "results.md").read_text(
        encoding="utf-8").split())
    assert (f"Sky RMS {s['sky_rms_before_arcsec']:.1f}\" -> {s['sky_rms_after_arcsec']:.1f}\" "
            f"in sample, {s['cv_sky_rms_before_arcsec']:.1f}\" -> "
            f"{s['cv_sky_rms_after_arcsec']:.1f}\" held out") in readme
    written = write_outputs(diag, tmp_path)
    assert "TEDFB" in diag.updated_model().names and "thermal" in written["not_in_scenario"]
