"""Plan files (antsim.plan.planfile): bad values are one-line errors naming the key, and
variants change what they say."""

from __future__ import annotations

import pytest

from antsim.cli import main as cli_main
from antsim.plan.planfile import load_plan
from controller.errors import InputError

BAD_VARIANTS = [
    ('windw = "night"', "variants[0].windw", "unknown key"),
    ('window = "dusk"', "variants[0].window", "must be one of all, day, night"),
    ('sources = ["3C84", "Sirius"]', "variants[0].sources", "not a source of the scenario"),
    ("step_arcmin = 20.0", "variants[0].step_arcmin", "outside the main beam"),
    ("duration_h = -3.0", "variants[0].duration_h", "must be > 0"),
    ("elevation_min_deg = 40.0\nelevation_max_deg = 30.0", "variants[0].elevation_max_deg",
     "must exceed elevation_min_deg"),
    ('estimator = "gauss"', "variants[0].estimator", "must be one of clark, lsq"),
    ("members = 1", "variants[0].members", "must be >= 2"),
]


@pytest.mark.parametrize(("variant", "key", "problem"), BAD_VARIANTS)
def test_bad_plan_values_are_one_line_errors(write_plan, variant, key, problem):
    path = write_plan(variant=variant)
    with pytest.raises(InputError) as info:
        load_plan(path)
    line = str(info.value)
    assert "\n" not in line
    assert line.startswith(f"{path}: {key} = ")
    assert problem in line


def test_bad_questions_and_scenario_reference(write_plan, tmp_path):
    path = write_plan(more='[[answers.duration]]\nbased_on = "as run"\nterms = ["IA"]\n'
                           'target_arcsec = 5.0\n')
    with pytest.raises(InputError, match=r"answers\.duration\[0\]\.terms = 'IA': is not fitted"):
        load_plan(path)
    path = write_plan(more='[[answers.sources]]\nbased_on = "by night"\n')
    with pytest.raises(InputError, match=r"answers\.sources\[0\]\.based_on = 'by night': not "
                                         "a variant"):
        load_plan(path)
    path = tmp_path / "lost.toml"
    path.write_text('name = "x"\nscenario = "nowhere.toml"\n[[variants]]\nname = "a"\n',
                    encoding="utf-8")
    with pytest.raises(InputError, match=r"scenario = 'nowhere.toml': no such scenario file"):
        load_plan(path)


def test_cli_bad_input_exits_2_with_one_line(write_plan, capsys):
    path = write_plan(variant='window = "dusk"')
    assert cli_main(["plan", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "variants[0].window = 'dusk'" in err
    assert cli_main(["plan", str(write_plan()), "--members", "1"]) == 2
    assert "--members = 1" in capsys.readouterr().err


def test_variants_change_what_they_say(write_plan):
    path = write_plan(variant='window = "day"\nduration_h = 3.0\nstep_arcmin = 6.0\n'
                              'integration_s = 10.0\nestimator = "lsq"\nmodel = "truth"\n'
                              'elevation_min_deg = 10.5\nfit_model = "tpoint6"')
    plan = load_plan(path)
    s = plan.scenarios[0]
    c = s.controller
    assert (c.scheduler.window, s.duration_s, c.duration_s) == ("day", 10800.0, 10800.0)
    assert (c.scan.step_arcmin, c.scan.integration_s, c.scan.estimator) == (6.0, 10.0, "lsq")
    assert c.scheduler.elevation_min_deg == 10.5
    assert c.model.as_dict() == s.truth_model.as_dict()
    assert c.fit_spec() == (("IA", "IE", "NPAE", "CA", "AN", "AW"), "tpoint6")
    # a source that never enters the window is refused, naming the variant's key
    path = write_plan(variant="duration_h = 2.0\nelevation_min_deg = 15.0", name="p2.toml")
    with pytest.raises(InputError, match=r"variants\[0\]\.sources = 'Taurus A': never between"):
        load_plan(path)
