"""antsim/api/fitting.py and fit.py: ``antsim.fit_model`` is ``antsim fit``: the same JSON,
text and model file for the same options, the same one-line refusals; a :class:`Fit`'s model
is its model file's."""

from __future__ import annotations

import json

import astropy.units as u
import pytest

import antsim
from controller.errors import InputError
from controller.pointing.modelio import load_model

from .conftest import command, command_error


@pytest.mark.parametrize(("kwargs", "options"), [
    ({}, []),
    ({"model": "tpoint8", "robust": False}, ["--model", "tpoint8", "--no-robust"]),
    ({"terms": ["W1", "W2", "W3", "W5", "W6"], "fixed": {"W5": 66 * u.arcsec}},
     ["--terms", "W1,W2,W3,W5,W6", "--fixed", "W5=66"]),
    ({"terms": "IA,IE,CA", "fixed": {"IE": 0.5 * u.arcmin}}, ["--terms", "IA,IE,CA",
                                                               "--fixed", "IE=30"]),
])
def test_a_fit_is_the_commands(kwargs, options, command_run):
    recordings = command_run / "recordings.ecsv"
    status, printed, _ = command(["fit", str(recordings), *options, "--json",
                                  "--no-progress"])
    assert status == 0
    fit = antsim.fit_model(recordings, **kwargs)
    assert fit.to_json() == json.loads(printed)
    status, printed, _ = command(["fit", str(recordings), *options, "--no-progress"])
    assert printed == f"{recordings} (recordings)\n{fit.summary()}\n"


def test_a_campaign_written_is_fitted_from_its_recordings(short_path, command_run, tmp_path):
    campaign = antsim.run_campaign(short_path, out=tmp_path / "run", report=False)
    assert antsim.fit_model(campaign).to_json() == \
        antsim.fit_model(command_run / "recordings.ecsv").to_json()
    with pytest.raises(InputError, match="was run without out=, so it has no recordings"):
        antsim.fit_model(antsim.run_campaign(short_path))


def test_the_model_written_and_the_model_in_memory_are_the_commands(command_run, tmp_path):
    recordings = command_run / "recordings.ecsv"
    status, _, err = command(["fit", str(recordings), "--write-model",
                              str(tmp_path / "cli.dat"), "--no-progress"])
    assert status == 0, err
    fit = antsim.fit_model(recordings, write_model=tmp_path / "api.dat")
    assert (tmp_path / "api.dat").read_bytes() == (tmp_path / "cli.dat").read_bytes()
    read_back = load_model(tmp_path / "cli.dat")
    in_memory = fit.pointing_model()
    assert in_memory.name == read_back.name == f"{recordings.name}: antsim fit, model ghigo10"
    assert in_memory.as_dict() == read_back.as_dict()
    # the file's precision (4 decimals), not the fit's
    assert in_memory.as_dict() != dict(zip(fit.names, fit.result.values_arcsec, strict=True))


def test_quantities_and_tables(command_run):
    fit = antsim.fit_model(command_run / "recordings.ecsv")
    table = fit.coefficients()
    assert list(table["term"]) == list(fit.names)
    assert table["value"].unit == u.arcsec
    assert fit.coefficient("W6") == fit.values[fit.names.index("W6")]
    with pytest.raises(KeyError, match="IA is not a term of this fit"):
        fit.coefficient("IA")
    assert sorted(fit.figures()) == ["histograms", "residuals", "sky"]
    assert f"{fit.result.sky_rms_arcsec:.2f}" in repr(fit)


@pytest.mark.parametrize(("kwargs", "options"), [
    ({"terms": ["W1", "NOPE"]}, ["--terms", "W1,NOPE"]),
    ({"terms": "W1,W1"}, ["--terms", "W1,W1"]),
    ({"model": "nonesuch"}, ["--model", "nonesuch"]),
    ({"fixed": {"IA": 3.0}}, ["--fixed", "IA=3"]),
    ({"fixed": {"W5": float("inf")}}, ["--fixed", "W5=inf"]),
    ({"csv": ["sign: true-minus-indicated"]}, ["--csv", "sign: true-minus-indicated"]),
    ({"write_model": "{run}/recordings.ecsv"}, ["--write-model", "{run}/recordings.ecsv"]),
])
def test_bad_input_is_the_commands_line(kwargs, options, command_run):
    recordings = command_run / "recordings.ecsv"

    def filled(value):
        return value.replace("{run}", str(command_run)) if isinstance(value, str) else value

    line = command_error(["fit", str(recordings), *map(filled, options), "--no-progress"])
    with pytest.raises(InputError) as err:
        antsim.fit_model(recordings, **{k: filled(v) for k, v in kwargs.items()})
    assert str(err.value) == line


def test_a_missing_file_is_the_commands_line(tmp_path):
    line = command_error(["fit", str(tmp_path / "none.dat"), "--no-progress"])
    with pytest.raises(InputError) as err:
        antsim.fit_model(tmp_path / "none.dat")
    assert str(err.value) == line


def test_an_angle_that_is_not_one_is_refused(command_run):
    with pytest.raises(InputError, match=r"fixed\['W5'\] = '3.0 s': must be one angle"):
        antsim.fit_model(command_run / "recordings.ecsv", fixed={"W5": 3 * u.s})
    with pytest.raises(InputError, match="must be an angle: an astropy Quantity or a number"):
        antsim.fit_model(command_run / "recordings.ecsv", fixed={"W5": "66"})
