"""antsim/api/planning.py: ``antsim.answer_plan`` is ``antsim plan``: the same document
(``--json``, ``plan.json``), the same files with ``out=``, the same one-line refusals; the
comparison figures drawn in memory."""

from __future__ import annotations

import json
from pathlib import Path

import astropy.units as u
import pytest

import antsim
from controller.errors import InputError

from .conftest import command, command_error

PLAN = """name = "short"
scenario = "{scenario}"
seed = 7
members = 4
block_members = 2

[[variants]]
name = "as run"

[[variants]]
name = "longer scans"
integration_s = 20.0
"""


@pytest.fixture(scope="module")
def plan(tmp_path_factory, short_path) -> Path:
    path = tmp_path_factory.mktemp("api_plan") / "plan.toml"
    path.write_text(PLAN.format(scenario=short_path.as_posix()), encoding="utf-8")
    return path


def test_a_plan_answered_is_the_commands(plan, tmp_path):
    status, _, err = command(["plan", str(plan), "--workers", "0", "--no-answers",
                              "--out", str(tmp_path / "cli"), "--no-progress"])
    assert status == 0, err
    answered = antsim.answer_plan(plan, workers=0, answers=False, out=tmp_path / "api")
    saved = (tmp_path / "cli" / "plan.json").read_text(encoding="utf-8")
    assert json.dumps(answered.to_json(), indent=2) + "\n" == saved
    assert answered.text() == (tmp_path / "cli" / "plan.txt").read_text(encoding="utf-8")
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "api").iterdir())
    for name in names:
        api, cli = (tmp_path / "api" / name), (tmp_path / "cli" / name)
        assert api.read_bytes() == cli.read_bytes(), name
    assert answered.variants == ["as run", "longer scans"]
    table = answered.terms("longer scans")
    doc = json.loads(saved)["plans"][1]["terms"]
    assert list(table["term"]) == list(doc)
    for row in table:
        assert row["sigma_predicted"].to_value(u.arcsec) == \
            doc[row["term"]]["sigma_fisher_arcsec"]
    figures = answered.figures()
    assert {f"{k}.png" for k in figures} == {n for n in names if n.endswith(".png")}
    assert answered.plot_sigmas() is figures["sigma_predicted"]
    assert "longer scans" in answered._repr_html_() and "longer scans" in repr(answered)
    # in memory, nothing written
    assert antsim.answer_plan(plan, workers=0, answers=False).to_json() == json.loads(saved)


@pytest.mark.parametrize(("kwargs", "options"), [
    ({"members": 1}, ["--members", "1"]),
    ({"workers": -1}, ["--workers", "-1"]),
    ({"workers": 1, "scheduler": "tcp://127.0.0.1:1"},
     ["--workers", "1", "--scheduler", "tcp://127.0.0.1:1"]),
])
def test_bad_input_is_the_commands_line(kwargs, options, plan):
    line = command_error(["plan", str(plan), *options, "--no-progress"])
    with pytest.raises(InputError) as err:
        antsim.answer_plan(plan, **kwargs)
    assert str(err.value) == line


def test_an_unknown_plan_is_the_commands_line():
    line = command_error(["plan", "no-such-plan", "--no-progress"])
    with pytest.raises(InputError) as err:
        antsim.answer_plan("no-such-plan")
    assert str(err.value) == line
