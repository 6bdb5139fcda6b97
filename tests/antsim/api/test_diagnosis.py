"""antsim/api/diagnosis.py: ``antsim.diagnose_model`` is ``antsim diagnose``: the same JSON
(``--json``), the same files with ``out=``, the same one-line refusals; its figures are the
ones ``--out`` writes, drawn in memory."""

from __future__ import annotations

import io
import json
from pathlib import Path

import astropy.units as u
import pytest

import antsim
from controller.errors import InputError

from .conftest import command, command_error

#: an uneven azimuth track hidden in the 3-hour campaign (the walk-through's fault, larger:
#: three hours of scans must show it)
HIDDEN = '\n[[truth.effects]]\neffect = "terms"\nHESA2 = -120\n'


@pytest.fixture(scope="module")
def hidden(tmp_path_factory, short_path) -> Path:
    """``antsim run`` of the short scenario with the hidden fault, seed 3: its recordings."""
    base = tmp_path_factory.mktemp("api_hidden")
    scenario = base / "hidden.toml"
    scenario.write_text(short_path.read_text(encoding="utf-8") + HIDDEN, encoding="utf-8")
    status, _, err = command(["run", str(scenario), "--seed", "3", "--out", str(base / "run"),
                              "--no-report", "--no-progress"])
    assert status == 0, err
    return base / "run" / "recordings.ecsv"


def test_a_diagnosis_is_the_commands(hidden, short_path, diagnose_cache):
    options = ["--scenario", str(short_path), "--cache", str(diagnose_cache)]
    status, printed, err = command(["diagnose", str(hidden), *options, "--json",
                                    "--no-progress"])
    assert status == 0, err
    found = antsim.diagnose_model(hidden, scenario=short_path, cache=diagnose_cache)
    assert found.to_json() == json.loads(printed)
    assert found.effects and found.effects[0] == "az_track_2a", found.text()
    assert found.mismatch
    status, printed, _ = command(["diagnose", str(hidden), *options, "--no-progress"])
    assert printed == found.text() + "\n"
    summary = found.to_json()["summary"]
    assert found.sky_rms_after.to_value(u.arcsec) == summary["sky_rms_after_arcsec"]
    assert found.sky_rms_after < found.sky_rms_before
    assert "az_track_2a" in found._repr_html_() and "az_track_2a" in repr(found)


def test_with_out_it_writes_the_commands_files(hidden, short_path, diagnose_cache, tmp_path):
    options = ["--scenario", str(short_path), "--cache", str(diagnose_cache),
               "--resimulate", "2"]
    status, printed, err = command(["diagnose", str(hidden), *options, "--json", "--out",
                                    str(tmp_path / "cli"), "--no-progress"])
    assert status == 0, err
    found = antsim.diagnose_model(hidden, scenario=short_path, cache=diagnose_cache,
                                  resimulate=2, out=tmp_path / "api")
    assert found.to_json() == json.loads(printed)
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "api").iterdir())
    for name in names:
        api, cli = (tmp_path / "api" / name), (tmp_path / "cli" / name)
        assert api.read_bytes() == cli.read_bytes(), name
    # the figures in memory are the files'
    from antsim.figures.style import FIG_DPI

    figures = found.figures()
    assert {f"{k}.png" for k in figures} == {n for n in names if n.endswith(".png")}
    png = io.BytesIO()
    found.plot_residuals().savefig(png, format="png", dpi=FIG_DPI,
                                   metadata={"Software": "antsim"},
                                   pil_kwargs={"compress_level": 3})
    assert png.getvalue() == (tmp_path / "cli" / "diagnose_residuals.png").read_bytes()


@pytest.mark.parametrize(("kwargs", "options"), [
    ({"sims": 1}, ["--sims", "1"]),
    ({"jobs": 0}, ["--jobs", "0"]),
    ({"model": " "}, ["--model", " "]),
    ({"scenario": "no-such-scenario"}, ["--scenario", "no-such-scenario"]),
    ({"resimulate": 2000}, ["--resimulate", "2000"]),
])
def test_bad_input_is_the_commands_line(kwargs, options, hidden):
    line = command_error(["diagnose", str(hidden), *options, "--no-progress"])
    with pytest.raises(InputError) as err:
        antsim.diagnose_model(hidden, **kwargs)
    assert str(err.value) == line
