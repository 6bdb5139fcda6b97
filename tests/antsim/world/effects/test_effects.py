"""The physical-effects catalogue (antsim.world.effects): every registered effect plugs in: a
scenario with it loads and runs, and its truth appears in ``World.truth()`` (the truth.json
content). Each effect's physics is tested in the file of its module."""

from __future__ import annotations

import pytest

from antsim.scenario import load_scenario
from antsim.simulate.runner import simulate
from antsim.world.effects import EFFECTS

SMOKE = {
    "terms": ({"HESA2": 6.0, "HACA2": -4.0}, {"terms_arcsec": {"HESA2": 6.0, "HACA2": -4.0}}),
    "thermal": ({"absorptivity": 0.3, "yoke_plate_m": 0.01}, None),
    "sunset_drift": ({"amplitude_arcsec": 64.48, "tau_s": 5400.0}, None),
    "tracking_jitter": ({"xel_rms_arcsec": 5.0, "el_rms_arcsec": 7.0, "timescale_s": 60.0},
                        None),
    "irregularities": ({"az_encoder_rms_arcsec": 10.0, "el_encoder_rms_arcsec": 12.0,
                        "track_rms_arcsec": 8.0, "pattern_seed": 3.0}, None),
    "clock_error": ({"offset_s": 2.0, "drift_s_per_day": 0.5}, None),
    "servo_lag": ({"lag_s": 0.5}, None),
    "backlash": ({"az_arcsec": 10.0, "el_arcsec": 6.0}, None),
    "polarization_squint": ({"separation_arcsec": 12.0, "angle_deg": 30.0}, None),
    "beam_width": ({"scale": 1.1}, None),
    "source_structure": ({"source": "Cygnus A", "size_arcmin": 2.0, "xel_arcsec": 5.0}, None),
    "refraction_anomaly": ({"scale": 1.05}, None),
    "exact_tilt_collimation": ({"tilt_arcmin": 1.0, "tilt_az_deg": 30.0,
                                "collimation_arcmin": 0.5}, None),
    # the effects for diagnosis (antsim/world/effects/harmonics.py, drifts.py)
    **{name: ({"amplitude_arcsec": 6.0, "phase_deg": 30.0}, None)
       for name in ("az_track_2a", "az_track_3a", "az_runout_1a", "az_runout_2a", "el_nod_1a",
                    "el_eccentricity", "el_eccentricity_2e")},
    "feed_offset": ({"offset_arcsec": 10.0, "angle_deg": 45.0}, None),
    "temperature_drift": ({"arcsec_per_k": 2.0, "tau_s": 3600.0, "reference_c": 5.0}, None),
    # a change at one instant (antsim/world/effects/steps.py)
    "step": ({"t_s": 3600.0, "az_arcsec": 20.0, "el_arcsec": -30.0}, None),
    # the equatorial effect (antsim/world/effects/equatorial.py), run on the 140-ft
    "polar_torsion": ({"amplitude_arcsec": 30.0, "phase_deg": 315.0}, None),
}


#: the effects of an equatorial mount: smoke-tested in the 140-ft's 4990 MHz scenario cut to
#: 6 hours (about 20 scans)
EQUATORIAL_ONLY = {"polar_torsion"}


def test_every_registered_effect_has_a_smoke_test():
    assert set(SMOKE) == set(EFFECTS)


def _toml_value(value) -> str:
    return f'"{value}"' if isinstance(value, str) else repr(float(value))


@pytest.mark.parametrize("name", sorted(SMOKE))
def test_effect_runs_in_a_scenario_and_reports_its_truth(short_ghigo_text, write_scenario,
                                                         name):
    """The 3-hour 1990 scenario (an equatorial mount's effect: the 140-ft's 4990 MHz run)
    with its own effects replaced by this one alone."""
    given, expected_params = SMOKE[name]
    base = short_ghigo_text
    if name in EQUATORIAL_ONLY:
        from tests.conftest import REPO, edit_text

        base = edit_text((REPO / "scenarios" / "crane1981_140ft_4990.toml").read_text(),
                         (("duration_h = 96.0", "duration_h = 6.0"),))
    start = base.index("[[truth.effects]]")
    end = base.index("[controller]")
    table = f'[[truth.effects]]\neffect = "{name}"\n' + "".join(
        f"{k} = {_toml_value(v)}\n" for k, v in given.items())
    text = base[:start] + table + "\n" + base[end:]
    scenario = load_scenario(write_scenario(text))
    assert [e.name for e in scenario.effects] == [name]
    result = simulate(scenario)
    assert result.n_scans > 10  # ran the campaign (3 h: ~30 scans)
    truth = result.world.truth()
    # the run's truth is the world's and the fit's recoverable truth beside it
    assert truth == {k: v for k, v in result.truth.items() if k != "recoverable"}
    (entry,) = truth["effects"]
    assert entry["effect"] == name
    params = entry["params"]
    for key, value in (expected_params or given).items():
        assert params[key] == value, (key, params)
    if name == "exact_tilt_collimation":
        assert entry["terms"] == ["AN", "AW", "CA"]
