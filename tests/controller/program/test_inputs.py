"""The front door to a user's pointing file: one reader for every kind and every command."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from controller.errors import InputError
from controller.program import inputs
from controller.program.inputs import read_pointing_file

DATA = Path(__file__).resolve().parents[2] / "data" / "bad_inputs"


@pytest.mark.parametrize(("name", "kind", "words"), [
    ("tpoint/_base.dat", "tpoint", "TPOINT data"), ("ecsv/_base.ecsv", "ecsv", "recordings"),
    ("csv/_base.csv", "csv", "CSV measurements"),
])
def test_each_kind_is_read_into_one_named_result(name, kind, words):
    """The three files hold the same twelve scans (the CSV and the TPOINT file are the
    recordings' average rows): read through the front door they are the same measurements."""
    file = read_pointing_file(DATA / name)
    assert (file.kind, file.kind_name, file.mount) == (kind, words, "altaz")
    points = file.pointing_data()
    reference = read_pointing_file(DATA / "ecsv" / "_base.ecsv").pointing_data()
    assert len(points) == 12
    np.testing.assert_allclose(np.degrees(points.el_rad), np.degrees(reference.el_rad),
                               atol=1e-5)  # the CSV and TPOINT files print 5 decimals
    np.testing.assert_allclose(points.el_arcsec, reference.el_arcsec, atol=0.05)


def test_the_notes_name_the_file_and_depend_on_the_purpose():
    csv = DATA / "csv" / "_base.csv"
    assert read_pointing_file(csv).notes == ()  # what a fit does not miss is not said
    assert read_pointing_file(csv, purpose="diagnose").notes == ()
    ecsv = DATA / "ecsv" / "_base.ecsv"
    assert read_pointing_file(ecsv).notes == ()


@pytest.mark.parametrize(("name", "options", "says"), [
    ("model/_base.mod", {}, "is a TPOINT model (.mod) file, not pointing data"),
    ("model/_base.json", {}, "is JSON (a model such as a fit.json), not pointing data"),
    ("ecsv/_base.ecsv", {"mount": "altaz"}, "applies to TPOINT data files only"),
    ("csv/_base.csv", {"mount": "altaz"}, "applies to TPOINT data files only"),
    ("tpoint/_base.dat", {"csv_options": ("sign: true-minus-indicated",)}, "is not a CSV file"),
    ("nowhere.ecsv", {}, "no such file"),
])
def test_what_no_reader_of_data_takes_is_one_line(name, options, says):
    with pytest.raises(InputError, match=re.escape(says)):
        read_pointing_file(DATA / name, **options)


def test_fit_and_diagnose_read_through_the_front_door(monkeypatch, capsys):
    from antsim.cli import main

    calls = []
    real = inputs.read_pointing_file

    def counting(path, **kwargs):
        calls.append((Path(path).name, kwargs.get("purpose")))
        return real(path, **kwargs)

    # every module that took the front door's function by name (fit's at its top, diagnose's
    # in the function that reads) gets the counting one
    import antsim.diagnose.data
    import antsim.fit.fitfile

    for module in (inputs, antsim.fit.fitfile, antsim.diagnose.data):
        if hasattr(module, "read_pointing_file"):
            monkeypatch.setattr(module, "read_pointing_file", counting)
    tpoint = str(DATA / "tpoint" / "_base.dat")
    assert main(["fit", tpoint, "--no-progress"]) == 0
    assert main(["diagnose", tpoint, "--no-progress"]) == 0
    capsys.readouterr()
    assert calls == [("_base.dat", "fit"), ("_base.dat", "diagnose")]
