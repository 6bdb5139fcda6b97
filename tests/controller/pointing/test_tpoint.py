"""TPOINT data files as observatories write them: comments after records, masked records
whatever their fields, the rotator column reaching the terms that read it, and the refusals
that name the real problem (no caption, two mounts, an observation given twice).

(The older tests of the module, the real files' parsing and the round trips, are in
tests/test_tpoint.py.)"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from controller.errors import InputError
from controller.pointing.fitting import fit_model
from controller.pointing.tpoint import format_tpoint, parse_tpoint

REPO = Path(__file__).resolve().parents[3]
AUXTEL = REPO / "examples" / "auxtel_20200315.dat"

HEAD = "a run\n: ALTAZ\n: ROTNR\n-30 14 40.2\n"
RECORDS = ("154.5139233 46.1577658 154.4096955 46.2199866 314.4605341",
           "357.5678314 17.9506751 357.4900009 18.0435750 288.4585002",
           "357.1805839 31.6160368 357.1093148 31.6954934 301.9815193")


def test_a_comment_after_a_record_is_a_comment():
    """Rubin's files end records with '; [0026] AT_O_...': the fields before it are the
    record, as TPOINT reads them; a run record may carry one too."""
    plain = parse_tpoint(HEAD + "\n".join(RECORDS) + "\nEND\n")
    commented = parse_tpoint(HEAD.replace("-30 14 40.2", "-30 14 40.2 ; the site")
                             + "\n".join(f"{r} ; [{i:04d}] AT_O_20200315_{i:06d}"
                                         for i, r in enumerate(RECORDS)) + "\nEND ; done\n")
    assert len(commented) == 3 and not commented.masked.any() and commented.has_end
    for name in ("lon_obs_deg", "lat_obs_deg", "lon_raw_deg", "lat_raw_deg", "rotator_deg"):
        np.testing.assert_array_equal(getattr(commented, name), getattr(plain, name))
    assert commented.run == plain.run


def test_a_masked_record_is_masked_whatever_its_fields():
    """'; nan nan nan nan' (a star not found), '; 12' or '; see the log' are read as masked
    records: kept, never fitted unless asked, and then refused naming the line."""
    text = (HEAD + RECORDS[0] + "\n; nan nan nan nan\n; 12\n; see the log ; [0026] X\n"
            + RECORDS[1] + "\n" + RECORDS[2] + "\nEND\n")
    data = parse_tpoint(text, source="run.dat")
    assert data.masked.tolist() == [False, True, True, True, False, False]
    assert data.line_numbers.tolist() == [5, 6, 7, 8, 9, 10]
    assert np.isnan(data.lat_obs_deg[1:4]).all()
    assert len(data.pointing_data()) == 3
    with pytest.raises(InputError, match=r"run.dat:6: observation = 'nan nan nan nan': is a "
                                         "masked record whose fields are not an observation"):
        data.pointing_data(include_masked=True)
    again = parse_tpoint(format_tpoint(data), source="again.dat")
    assert again.masked.tolist() == data.masked.tolist()
    np.testing.assert_allclose(again.lat_obs_deg, data.lat_obs_deg, equal_nan=True)


def test_a_masked_record_is_not_the_kind_of_the_file():
    """A masked sexagesimal record in a file of decimal records is masked, not a refusal;
    unmasked it is refused as before."""
    sexagesimal = "12 30 00 +10 00 00 12 30 01 +10 00 05 14 20"
    data = parse_tpoint(HEAD + RECORDS[0] + f"\n; {sexagesimal}\n" + RECORDS[1] + "\nEND\n")
    assert data.coordinates == "azel" and data.masked.tolist() == [False, True, False]
    with pytest.raises(InputError, match="is a sexagesimal record in a file of decimal"):
        parse_tpoint(HEAD + RECORDS[0] + f"\n{sexagesimal}\nEND\n")


def test_the_rotator_column_reaches_the_terms_that_read_it():
    """The AuxTel file's fifth column (': ROTNR') is the angle a feed-angle term reads: a
    HECF (dE = c cos F) injected on it is recovered; a file without it cannot fit one."""
    data = parse_tpoint(AUXTEL.read_text(encoding="utf-8"), source=str(AUXTEL))
    points = data.pointing_data()
    np.testing.assert_allclose(points.feed_rad, np.radians(data.rotator_deg))
    injected = 30.0 * np.cos(points.feed_rad)  # arcsec, dE = +HECF cos F (TPOINT's sign)
    clean = fit_model(points, ["IA", "IE", "CA", "NPAE", "AN", "AW", "TF"], robust=False)
    from dataclasses import replace

    shifted = replace(points, el_arcsec=points.el_arcsec + injected)
    fit = fit_model(shifted, ["IA", "IE", "CA", "NPAE", "AN", "AW", "TF", "HECF"],
                    robust=False)
    # the rotator follows E + 268 deg on this file, so HECF is not far from TF's cos E:
    # the injected 30" come back within a few sigma of the fit without them
    assert fit.model["HECF"] == pytest.approx(30.0, abs=4 * fit.sigma_arcsec[-1])
    assert fit.sky_rms_arcsec == pytest.approx(clean.sky_rms_arcsec, rel=0.05)
    no_rotator = parse_tpoint(HEAD.replace(": ROTNR\n", "") + "\n".join(
        " ".join(r.split()[:4]) for r in RECORDS) + "\nEND\n").pointing_data()
    assert no_rotator.feed_rad is None


def test_tpoints_nasmyth_terms_fit_the_auxtel_file(capsys):
    """`antsim fit --terms ...,NRX,NRY` on Rubin's AuxTel run (a Nasmyth telescope): one fit,
    both terms with a value and a sigma. (NRY = NPAE + ECEC and NRX = IA - ECES: with NPAE
    in the set NRY could not be fitted, so the set is TPOINT's basic terms without it.)"""
    import json

    from antsim.cli import main

    assert main(["fit", str(AUXTEL), "--terms", "IA,IE,CA,AN,AW,TF,NRX,NRY", "--json",
                 "--no-progress", "--no-robust"]) == 0
    terms = json.loads(capsys.readouterr().out)["terms"]
    for name in ("NRX", "NRY"):
        assert math.isfinite(terms[name]["value_arcsec"])
        assert terms[name]["sigma_arcsec"] > 0


@pytest.mark.parametrize(("text", "line", "says"), [
    (": ALTAZ\n-30 14 40.2\n" + RECORDS[0] + "\n", 1, "is an option record: the caption"),
    ("-30 14 40.2\n" + RECORDS[0] + "\n", 1, "is a record of numbers: the caption"),
    ("c\n: ALTAZ\n: GIMBAL\n-30 14 40.2\n", 3, "contradicts ': ALTAZ' on line 2"),
    ("c\n: altaz\n: EQUAT 1 2\n-30 14 40.2\n", 3, "contradicts ': ALTAZ' on line 2"),
    ("c\n: ALTAZ\n-30 14 40.2\n" + RECORDS[0] + "\n" + RECORDS[0] + "\n", 5,
     "repeats line 4 exactly"),
])
def test_the_real_problem_is_named(text, line, says):
    with pytest.raises(InputError, match=says) as err:
        parse_tpoint(text, source="f.dat")
    assert err.value.where == f"f.dat:{line}"


def test_a_masked_copy_of_an_observation_is_no_repeat():
    """Masking a record and writing it again unmasked (as one does to try both) is kept."""
    data = parse_tpoint(HEAD + RECORDS[0] + "\n; " + RECORDS[0] + "\nEND\n")
    assert data.masked.tolist() == [False, True]
