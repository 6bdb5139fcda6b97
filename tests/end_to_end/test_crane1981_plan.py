"""``antsim plan`` on the equatorial 140-ft: a reduced scenarios/plans/crane1981_days.toml.

The full plan (four variants of three and four days, 20 members each, questions over eight
days) is ``python benchmarks/crane1981_days.py``; here one-day variants with a few members
and questions over two days, in this process (``workers=0``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from antsim.plan.planfile import load_plan
from antsim.plan.study import run_plan
from controller.errors import InputError
from controller.pointing.crane import CRANE_NAMES, crane_terms
from controller.pointing.terms import evaluate_basis

REPO = Path(__file__).resolve().parents[2]


def _scenario(band: int) -> Path:
    return REPO / "scenarios" / f"crane1981_140ft_{band}.toml"


#: Table 4's 4990 MHz errors plus half their last digit (arcsec), as the plan file's
TARGETS = "{C1 = 3.3, C2 = 2.1, C3 = 3.9, C4 = 3.9, C5 = 1.5, C6 = 8.1, C7 = 5.1, " \
          "C8 = 8.1, C9 = 14.1, C10 = 8.7, C11 = 13.5}"


def _plan_text(questions: str = "") -> str:
    return f'''name = "crane1981_days_reduced"
scenario = "{_scenario(4990)}"
seed = 1981
members = 3

[[variants]]
name = "4990 1 day"
duration_days = 1

[[variants]]
name = "10500 1 day"
scenario = "{_scenario(10500)}"
duration_days = 1
members = 2

[[variants]]
name = "10500 1 day without tipping"
scenario = "{_scenario(10500)}"
duration_days = 1
tipping = false
members = 2
{questions}'''


QUESTIONS = f'''
[[answers.duration]]
based_on = "4990 1 day"
terms = {list(CRANE_NAMES)!r}
targets_arcsec = {TARGETS}
unit = "run_day"
max_days = 2
note = "Crane summary 7: three days"

[[answers.coverage]]
based_on = "4990 1 day"
dec_max_deg = 20.0
max_days = 2
note = "complete coverage below +20 deg"
'''.replace("'", '"')


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    path = tmp_path_factory.mktemp("plan") / "plan.toml"
    path.write_text(_plan_text(QUESTIONS), encoding="utf-8")
    return run_plan(load_plan(path), workers=0, progress=False)


def test_fisher_design_is_hour_angle_and_declination(result):
    # the plan's design for the equatorial mount is the fit's: C1..C11 at the scans' hour
    # angles and declinations, cross-declination rows x = dH cos(dec). Its correlations equal
    # those of the design built independently from the study's basis (to rounding: the same
    # matrix); an alt-az design at the same rows would differ at the level of 1
    v = result.variants[0]
    cols, rows = v.shared.columns, v.noise.scans
    ha = np.radians(cols["ha_deg"][rows].astype(float))
    dec = np.radians(cols["dec_deg"][rows].astype(float))
    b_h, b_d = evaluate_basis(crane_terms(v.scenario.site.latitude_deg), ha, dec)
    a = np.vstack([b_h * np.cos(dec)[:, None], b_d])
    cov = np.linalg.inv(a.T @ a)
    corr = cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov)))
    assert v.prediction.names == CRANE_NAMES
    np.testing.assert_allclose(v.prediction.design_correlation, corr, atol=1e-9)
    # and the predicted errors are those of the observatory's fit: within 2 sampling errors
    # of the members' scatter would need many members (the benchmark's check); here the
    # prediction is of the order of the noise over the root of the scans
    rms = np.hypot(*[v.noise.budget()["jitter"][k] for k in ("xel_arcsec", "el_arcsec")])
    assert np.all(v.prediction.sigma_arcsec[[0, 5]] > rms / np.sqrt(rows.size) / 2)


def test_monte_carlo_members_fit_the_truth(result):
    # every member is simulated in full (the running correction follows each scan) and
    # fitted; the mean of each C lies within 4 predicted sigmas / sqrt(n) of Table 4's truth
    # (C5: the refraction scale, 60" per unit)
    for v in result.variants:
        assert v.unshareable and int(v.ok.sum()) == v.n_requested
        n = int(v.ok.sum())
        bound = 4.0 * v.prediction.sigma_arcsec / np.sqrt(n)
        assert np.all(np.abs(v.bias_mc()) < bound), (v.spec.name, np.round(v.bias_mc(), 1))
    assert result.variants[0].truth[CRANE_NAMES.index("C5")] == pytest.approx(0.97 * 60.0)


def test_the_tipping_scans_take_time(result):
    # the same day at 10500 MHz without the tipping scans holds more pointing scans
    with_tipping, without = result.variants[1].shared, result.variants[2].shared
    assert without.n_scans > with_tipping.n_scans


def test_duration_answer_per_term_and_beside_the_memo(result):
    (a,) = result.answers["duration"]
    assert [c["count"] for c in a["curve"]] == [1, 2]
    one, two = (np.array(list(c["sigma_arcsec"].values())) for c in a["curve"])
    assert np.all(two < one)  # a second day shrinks every error
    assert set(a["first_count"]) == set(CRANE_NAMES)
    for name, first in a["first_count"].items():
        sig = [c["sigma_arcsec"][name] for c in a["curve"]]
        expect = next((c["count"] for c, s in zip(a["curve"], sig, strict=True)
                       if s <= a["targets_arcsec"][name]), None)
        assert first == expect, name
    text = result.text(timing=False)
    assert "beside: Crane summary 7: three days" in text and "each term's first" in text


def test_coverage_below_20_deg(result):
    (a,) = result.answers["coverage"]
    filled = [c["filled"] for c in a["curve"]]
    assert a["cells"] > 20 and 0 < filled[0] <= filled[1] <= a["cells"]
    assert (a["answer_days"] is None) == (filled[-1] < a["cells"])


def test_plan_file_errors_name_the_key(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(_plan_text(QUESTIONS.replace("C11 = 13.5", "C12 = 13.5")), encoding="utf-8")
    with pytest.raises(InputError, match=r"answers.duration\[0\].targets_arcsec"):
        load_plan(bad)
    ghigo = tmp_path / "ghigo.toml"
    ghigo.write_text(
        f'name = "g"\nscenario = "{REPO / "scenarios" / "ghigo1990.toml"}"\n'
        '[[variants]]\nname = "as run"\n[[answers.coverage]]\nbased_on = "as run"\n'
        'dec_max_deg = 20.0\n', encoding="utf-8")
    with pytest.raises(InputError, match="must be equatorial"):
        load_plan(ghigo)
