"""TPOINT files (controller.pointing.tpoint): the two real data files, hand-made edge cases,
malformed lines, round trips (hypothesis) and format sniffing; files as observatories write
them: comments after records, masked records whatever their fields, the rotator column
reaching the terms that read it, and the refusals that name the real problem (no caption, two
mounts, an observation given twice).

Hand-made files are in ``tests/data/tpoint``; the real ones in ``examples/`` (their sources and
licences in ``examples/README.md``).
"""

from __future__ import annotations

import datetime
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from controller.errors import InputError
from controller.pointing.fitting import fit_model
from controller.pointing.model import PointingModel
from controller.pointing.tpoint import (
    RunParameters,
    TPointData,
    TPointModel,
    caption_problem,
    format_mod,
    format_tpoint,
    parse_mod,
    parse_tpoint,
    read_mod,
    read_tpoint,
    sniff_format,
    write_mod,
    write_tpoint,
)

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


HERE = Path(__file__).resolve().parents[2]  # tests/
DATA = HERE / "data" / "tpoint"
REAL = HERE.parent / "examples"


def real_file(name: str) -> Path:
    return REAL / name


# ---------------------------------------------------------------------------------------------
# the real files
# ---------------------------------------------------------------------------------------------
def test_mmt_file_parses():
    data = read_tpoint(real_file("mmt_20210821_k_and_e.dat"))
    assert len(data) == 80
    assert data.caption == "MMT Pointing Data from 08/21/2021"
    assert data.options == ("ALTAZ",)
    assert data.mount == "ALTAZ" and data.coordinates == "azel"
    run = data.run
    assert run.latitude_deg == pytest.approx(31 + 41 / 60 + 19.6 / 3600, abs=1e-12)
    assert run.date == datetime.date(2021, 8, 21)
    assert (run.temperature_c, run.pressure_mb, run.height_m, run.humidity) == (
        13.0, 741.0, 2608.0, 0.75)
    assert run.wavelength_um is None and run.extra == ()
    assert not data.has_end  # the MMT file simply stops
    assert not data.has_rotator and not data.masked.any()
    assert data.comments[0] == "MMT Pointing Data from 08/21/2021"
    # first record "192.3860283 77.3468410111111 -167.2778909 77.3475476": azimuths as the
    # file gives them (TPOINT reads them North-based), within 0..360 deg
    assert data.az_obs_deg[0] == pytest.approx(192.3860283, abs=1e-9)
    assert data.az_raw_deg[0] == pytest.approx(192.7221091, abs=1e-9)
    assert data.el_obs_deg[0] == pytest.approx(77.3468410111111, abs=1e-12)
    assert data.line_numbers[0] == 21 and data.line_numbers[-1] == 100
    # the last record crosses the wrap (231.97 vs -127.70): a 0.33 deg error
    points = data.pointing_data()
    assert len(points) == 80
    assert np.abs(points.xel_arcsec).max() < 1300.0
    assert points.xel_arcsec[-1] == pytest.approx(
        (360.0 - 127.6968663 - 231.9735792) * 3600.0 * math.cos(math.radians(75.9554129111111)),
        rel=1e-9)


def test_auxtel_file_parses_with_rotator_and_end():
    data = read_tpoint(real_file("auxtel_20200315.dat"))
    assert len(data) == 44
    assert data.caption == "LSST Auxiliary Telescope, 2020 Mar 15 UTC 2 27 13"
    assert data.options == ("ALTAZ", "ROTNR")
    assert data.run.latitude_deg == pytest.approx(-(30 + 14 / 60 + 40.2 / 3600), abs=1e-12)
    assert data.run.latitude_deg == pytest.approx(-30.2445, abs=1e-12)
    assert data.run.date is None
    assert data.has_end and data.has_rotator
    assert data.rotator_deg[0] == pytest.approx(314.4605341)
    assert data.rotator_deg[-1] == pytest.approx(287.9991321)
    assert data.az_obs_deg[6] == pytest.approx(18.8692942)  # "018.8692942", as written


def test_masked_lines_comments_and_end():
    path = DATA / "masked.dat"
    data = read_tpoint(path)
    assert len(data) == 6
    assert data.masked.tolist() == [False, False, True, False, True, False]
    assert data.line_numbers.tolist() == [6, 7, 8, 9, 10, 11]
    assert data.options == ("ALTAZ", "NODA")
    assert data.run.humidity == 0.40 and data.run.height_m == 800.0
    assert data.has_end
    assert len(data.pointing_data()) == 4
    everything = data.pointing_data(include_masked=True)
    assert len(everything) == 6
    # second observation: dA = 0.01 deg at E = 45: xel = 36" cos 45
    assert everything.xel_arcsec[1] == pytest.approx(36.0 * math.cos(math.radians(45.0)), rel=1e-9)
    assert everything.el_arcsec[1] == pytest.approx(0.004 * 3600.0, rel=1e-9)


def test_sexagesimal_equatorial_records_parse_but_do_not_fit(tmp_path):
    path = DATA / "radec_sexagesimal.dat"
    data = read_tpoint(path)
    assert data.coordinates == "radec" and data.mount == "EQUAT"
    assert len(data) == 2
    assert data.lon_obs_deg[0] == pytest.approx((10 + 11 / 60 + 12.345 / 3600) * 15.0, abs=1e-12)
    assert data.lat_obs_deg[1] == pytest.approx(-0.5, abs=1e-12)  # "-00 30 00.00"
    assert data.lst_hours[1] == pytest.approx(23 + 1.25 / 60, abs=1e-12)
    assert data.extra_fields[1] == ("RX1", "0.5")
    assert data.run.wavelength_um == pytest.approx(866.963)
    with pytest.raises(InputError, match="equatorial"):
        data.pointing_data()
    with pytest.raises(InputError):
        _ = data.az_obs_deg
    again = parse_tpoint(format_tpoint(data))
    _assert_same_data(data, again)


def test_equatorial_decimal_records_parse_but_do_not_fit():
    data = read_tpoint(DATA / "equat_decimal.dat")
    assert data.coordinates == "decimal" and data.mount == "EQUAT"
    assert data.lon_obs_deg[1] == 190.0  # as written
    with pytest.raises(InputError, match="not supported by the alt-az term set"):
        data.pointing_data()
    # the user may say otherwise (--mount altaz): then the records are Az/El, the azimuth
    # North-based as written
    forced = read_tpoint(DATA / "equat_decimal.dat", mount="altaz")
    assert forced.coordinates == "azel" and forced.notes == ()
    assert forced.lon_obs_deg[1] == 190.0
    assert len(forced.pointing_data()) == 2


def test_decimal_records_without_a_mount_option_are_read_as_altaz_with_a_note(tmp_path):
    """Many TPOINT files (the MMT's among them) carry no ': ALTAZ' line although their
    records are Az/El: read so, with a one-line note naming the file; the same numbers as
    the file with the line, or with mount="altaz" (no note then)."""
    with_line = parse_tpoint(BASE, "with.dat")
    without = parse_tpoint(BASE.replace(": ALTAZ\n", ""), "without.dat")
    assert without.options == () and without.coordinates == "azel"
    assert without.mount == "ALTAZ"
    assert len(without.notes) == 1 and "\n" not in without.notes[0]
    assert without.notes[0].startswith("without.dat: no mount option line")
    a, b = with_line.pointing_data(), without.pointing_data()
    for name in ("az_rad", "el_rad", "xel_arcsec", "el_arcsec"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    told = parse_tpoint(BASE.replace(": ALTAZ\n", ""), "told.dat", mount="altaz")
    assert told.coordinates == "azel" and told.notes == ()
    with pytest.raises(InputError, match="--mount"):
        parse_tpoint(BASE, "x.dat", mount="equat")


def test_a_file_that_cannot_be_altaz_keeps_the_clear_error():
    """No mount option, but a second coordinate below 0 deg (a declination, not an
    elevation): TPOINT's default, equatorial, and the one-line error; sexagesimal RA/Dec
    records cannot be read as Az/El even when asked."""
    text = BASE.replace(": ALTAZ\n", "").replace("190.0 45.0 190.01 45.004",
                                                  "190.0 -45.0 190.01 -45.004")
    data = parse_tpoint(text, "dec.dat")
    assert data.coordinates == "decimal" and data.mount == "EQUAT" and data.notes == ()
    with pytest.raises(InputError, match="without a mount option") as info:
        data.pointing_data()
    assert "\n" not in str(info.value)
    with pytest.raises(InputError, match="cannot be read as Az/El"):
        read_tpoint(DATA / "radec_sexagesimal.dat", mount="altaz")


def test_fit_and_diagnose_print_the_note_in_one_line(tmp_path, capsys):
    from antsim.cli import main as cli

    path = tmp_path / "no_option.dat"
    lines = BASE.replace(": ALTAZ\n", "").splitlines()
    rng = np.random.default_rng(5)
    body = [f"{a:.5f} {e:.5f} {a + rng.normal(0, 0.003):.5f} {e + rng.normal(0, 0.003):.5f}"
            for a, e in zip(rng.uniform(0, 360, 30), rng.uniform(15, 85, 30), strict=True)]
    path.write_text("\n".join([*lines[:3], *body, "END"]) + "\n", encoding="utf-8")
    for argv, head in ((["fit", str(path), "--json"], "antsim fit: note:"),
                       (["diagnose", str(path), "--json"], "note:")):
        assert cli(argv) == 0
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"{head} {path}: no mount option"), err
        assert cli([*argv, "--mount", "altaz"]) == 0
        assert capsys.readouterr().err == ""
    assert cli(["fit", str(DATA / "equat_decimal.dat")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "mount = 'EQUAT'" in err[0]


# ---------------------------------------------------------------------------------------------
# malformed lines: one InputError, one line, naming file and line number
# ---------------------------------------------------------------------------------------------
BASE = """! comment
Caption
: ALTAZ
+38 25 48.0 1990 2 8 5.0 920.0 800.0 0.40
10.0 30.0 10.01 30.005
190.0 45.0 190.01 45.004
END
"""

# (line number to replace, new text, field named in the error)
MALFORMED = [
    (5, "10.0 30.0 10.01 3O.005", "E_raw"),
    (5, "10.0 30.0 10.01", "observation"),
    (5, "10.0 30.0 10.01 30.0 1.0 2.0 3.0", "observation"),
    (5, "10.0 95.0 10.01 95.0", "E_obs"),
    (5, "10.5 30 10 20 10 10 10.5 30 10 20 10 10", "observation"),
    (5, "10 75 12.3 +20 30 40.5 10 11 13.0 +20 30 30.0", "RA_obs"),
    (5, "24 00 00.0 +20 30 40.5 10 11 13.0 +20 30 30.0", "RA_obs"),
    (5, "10 11 12.3 +20 30 40.5 10 11 13.0 -95 30 30.0", "Dec_raw"),
    (5, ";", "observation"),
    (5, "nan 30.0 10.01 30.005", "A_obs"),
    (4, "+38 65 48.0", "latitude"),
    (4, "+95 00 00.0", "latitude"),
    (4, "+38 25", "run parameters"),
    (4, "+38 25 48.0 1990 13 8", "date"),
    (4, "+38 25 48.0 1990 2", "date"),
    (4, "+38 25 48.0 1990 2 8 5.0 920.0 800.0 1.40", "relative humidity (0-1)"),
    (4, "+38 25 48.0 1990 2 8 hot", "temperature (C)"),
    (3, ":", "option"),
    (6, ": ROTNR", "option"),
]


@pytest.mark.parametrize(("line_no", "text", "field"), MALFORMED)
def test_malformed_data_lines_name_file_line_and_field(tmp_path, line_no, text, field):
    lines = BASE.splitlines()
    lines[line_no - 1] = text
    path = tmp_path / "broken_pointing.dat"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(InputError) as info:
        read_tpoint(path)
    err = info.value
    message = str(err)
    assert "\n" not in message
    assert f"{path}:{line_no}" in message
    assert err.where == f"{path}:{line_no}"
    assert err.field == field
    assert field in message


def test_mixed_record_kinds_are_rejected(tmp_path):
    path = tmp_path / "mixed.dat"
    path.write_text(BASE.replace("190.0 45.0 190.01 45.004",
                                 "10 11 12.3 +20 30 40.5 10 11 13.0 +20 30 30.0 09 15.5"))
    with pytest.raises(InputError, match=r"mixed\.dat:6.*sexagesimal record in a file of "
                                         r"decimal records"):
        read_tpoint(path)


@pytest.mark.parametrize(("text", "field"), [("", "caption"), ("Caption only\n", "run parameters"),
                                             ("! just a comment\n\n", "caption")])
def test_files_without_caption_or_run_record(tmp_path, text, field):
    path = tmp_path / "short.dat"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        read_tpoint(path)
    assert info.value.field == field and str(path) in str(info.value)


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_tpoint(tmp_path / "absent.dat")
    binary = tmp_path / "binary.dat"
    binary.write_bytes(b"\xff\xfe\x00caption\n")
    with pytest.raises(InputError, match="UTF-8"):
        read_tpoint(binary)
    with pytest.raises(InputError, match="directory"):
        read_tpoint(tmp_path)


MOD_BASE = """Caption
T  10  1.000  0.0000  0.0000
  IA        +10.0000     1.00000
  IE         -2.0000     0.50000
END
"""

MOD_MALFORMED = [
    (3, "  XYZZY     +10.0000     1.00000", "term"),
    (3, "  IA        +1O.0000     1.00000", "IA value"),
    (3, "  IA        +10.0000    -1.00000", "IA sigma"),
    (3, "  IA        +10.0000     1.00000  7.0", "IA"),
    (4, "  IA        -2.0000     0.50000", "term"),
    (2, "T  ten  1.000", "parameters"),
    (3, "  IA1209.2612", "term"),
]


@pytest.mark.parametrize(("line_no", "text", "field"), MOD_MALFORMED)
def test_malformed_mod_lines(tmp_path, line_no, text, field):
    lines = MOD_BASE.splitlines()
    lines[line_no - 1] = text
    path = tmp_path / "broken_model.mod"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as info:
        read_mod(path)
    message = str(info.value)
    assert "\n" not in message and f"{path}:{line_no}" in message
    assert info.value.field == field


# ---------------------------------------------------------------------------------------------
# round trips
# ---------------------------------------------------------------------------------------------
def _assert_same_data(a: TPointData, b: TPointData, decimals: int = 7) -> None:
    """Equal to the printed precision: positions to half a unit of the last decimal (azimuth
    modulo 360), the latitude to 0.005" (printed to 0.01")."""
    assert a.caption == b.caption and a.options == b.options
    assert a.coordinates == b.coordinates and len(a) == len(b)
    tol = 0.5 * 10.0**-decimals + 1e-9
    if a.coordinates == "radec":
        tol = 0.0005 * 15 / 3600 + 1e-12  # RA printed to 1 ms of time
    for name in ("lon_obs_deg", "lon_raw_deg"):
        diff = (getattr(a, name) - getattr(b, name) + 180.0) % 360.0 - 180.0
        assert np.all(np.abs(diff) <= tol), name
    for name in ("lat_obs_deg", "lat_raw_deg"):
        assert np.allclose(getattr(a, name), getattr(b, name), rtol=0, atol=tol), name
    assert np.array_equal(np.isnan(a.rotator_deg), np.isnan(b.rotator_deg))
    finite = np.isfinite(a.rotator_deg)
    assert np.allclose(a.rotator_deg[finite], b.rotator_deg[finite], rtol=0, atol=tol)
    assert np.array_equal(a.masked, b.masked)
    assert a.run.latitude_deg == pytest.approx(b.run.latitude_deg, abs=0.005 / 3600 + 1e-12)
    for name in ("date", "temperature_c", "pressure_mb", "height_m", "humidity",
                 "wavelength_um", "lapse_rate_k_per_m", "extra"):
        assert getattr(a.run, name) == getattr(b.run, name), name


def test_real_files_round_trip(tmp_path):
    for name in ("mmt_20210821_k_and_e.dat", "auxtel_20200315.dat"):
        data = read_tpoint(real_file(name))
        out = tmp_path / name
        write_tpoint(data, out)
        _assert_same_data(data, read_tpoint(out))
        # and the text is stable once written
        assert format_tpoint(read_tpoint(out)) == out.read_text()


def test_masked_file_round_trip():
    data = read_tpoint(DATA / "masked.dat")
    _assert_same_data(data, parse_tpoint(format_tpoint(data)))


finite_deg = st.floats(min_value=-720.0, max_value=720.0, allow_nan=False)
elevations = st.floats(min_value=-90.0, max_value=90.0, allow_nan=False)


@st.composite
def tpoint_data(draw):
    n = draw(st.integers(min_value=0, max_value=12))
    rows = draw(st.lists(st.tuples(finite_deg, elevations, finite_deg, elevations,
                                   st.floats(0.0, 360.0), st.booleans()),
                         min_size=n, max_size=n))
    with_rotator = draw(st.booleans())
    latitude = draw(st.floats(min_value=-90.0, max_value=90.0))
    if draw(st.booleans()):
        weather = dict(
            date=draw(st.dates(datetime.date(1950, 1, 1), datetime.date(2100, 12, 31))),
            temperature_c=draw(st.floats(-40.0, 40.0).map(lambda x: round(x, 2))),
            pressure_mb=draw(st.floats(500.0, 1100.0).map(lambda x: round(x, 1))),
            height_m=draw(st.floats(0.0, 5000.0).map(lambda x: round(x, 1))),
            humidity=draw(st.floats(0.0, 1.0).map(lambda x: round(x, 3))),
        )
    else:
        weather = {}
    options = ["ALTAZ"] + (["ROTNR"] if with_rotator else []) + draw(
        st.lists(st.sampled_from(["NODA", "ROTNL", "SOME OTHER OPTION"]), max_size=2))
    caption = draw(st.text(st.characters(min_codepoint=32, max_codepoint=126,
                                         exclude_characters="!"), min_size=1, max_size=40)
                   .filter(lambda s: s.strip() != "" and caption_problem(s) is None))
    cols = list(zip(*rows, strict=True)) if rows else [()] * 6
    return TPointData.from_azel(
        caption, RunParameters(latitude, **weather),
        np.array(cols[0], float), np.array(cols[1], float), np.array(cols[2], float),
        np.array(cols[3], float), rotator_deg=np.array(cols[4], float) if with_rotator else None,
        masked=np.array(cols[5], bool), options=options)


@settings(max_examples=80, deadline=None)
@given(data=tpoint_data())
def test_write_read_round_trip(data):
    text = format_tpoint(data)
    records = [line for line in text.splitlines()[len(data.options) + 2:-1]
               if not line.startswith(";")]
    # a repeated observation is refused: the reader compares the numbers (0 and -0 alike)
    values = [tuple(float(x) for x in line.split()) for line in records]
    assume(len(set(values)) == len(values))
    again = parse_tpoint(text)
    _assert_same_data(data, again)
    assert again.has_end


def test_from_azel_refuses_bad_input():
    run = RunParameters(10.0)
    with pytest.raises(ValueError, match="ALTAZ"):
        TPointData.from_azel("c", run, [1.0], [2.0], [1.0], [2.0], options=("EQUAT",))
    with pytest.raises(ValueError, match="elevations"):
        TPointData.from_azel("c", run, [1.0], [92.0], [1.0], [2.0])
    with pytest.raises(ValueError, match="length"):
        TPointData.from_azel("c", run, [1.0, 2.0], [2.0], [1.0], [2.0])


# ---------------------------------------------------------------------------------------------
# .mod files
# ---------------------------------------------------------------------------------------------
def test_mod_file_reads_as_a_pointing_model():
    model = read_mod(DATA / "mmt_k_and_e_tpoint.mod")
    assert isinstance(model, PointingModel)
    assert model.names == ("IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX")
    assert model["IA"] == 1209.2612 and model["TX"] == -2.7165
    assert model.sigma_arcsec[0] == 1.28477
    assert model.parameters == ("T", "80", "0.932", "0.0000", "0.0000")
    assert model.caption.startswith("MMT K&E model")
    # usable as any model: its offset is the TPOINT correction negated
    d_az, _ = model.offset_rad(0.0, 0.5)
    assert np.isfinite(d_az)


@pytest.mark.parametrize("name", ["mmt_k_and_e_tpoint.mod", "flags.mod"])
def test_mod_round_trip_is_exact_text(tmp_path, name):
    path = DATA / name
    model = read_mod(path)
    out = tmp_path / name
    write_mod(model, out)
    assert out.read_text() == path.read_text()


def test_mod_flags_and_adjacent_eight_character_name():
    model = read_mod(DATA / "flags.mod")
    assert model.names[3] == "HSCA5CE8" and model["HSCA5CE8"] == 1234.5678
    assert model.fixed == (False, True, False, False, False, True, False, False, False)
    assert model.parallel == (False, False, True, True, False, False, False, False, False)
    assert math.isnan(model.sigma_arcsec[1])  # fixed IE: no sigma
    assert model.sigma_arcsec[8] == 131.179


def test_pointing_model_converts_both_ways():
    plain = PointingModel(["IA", "HESA2", "W6"], [1.5, -2.25, 734.4], name="mine")
    as_mod = TPointModel.from_model(plain, [0.1, float("nan"), 0.3])
    text = format_mod(as_mod)
    back = parse_mod(text)
    assert back.names == plain.names and back.name == "mine"
    np.testing.assert_array_equal(back.values_arcsec, plain.values_arcsec)
    assert back.sigma_arcsec[0] == 0.1 and math.isnan(back.sigma_arcsec[1])
    again = back.to_pointing_model()
    assert type(again) is PointingModel and again.as_dict() == plain.as_dict()
    # a plain model is written with its name as caption and no sigmas
    assert format_mod(plain).splitlines()[0] == "mine"
    assert parse_mod(format_mod(plain)).as_dict() == plain.as_dict()


mod_names = st.sampled_from(["IA", "IE", "CA", "NPAE", "AN", "AW", "TF", "TX", "HESA2",
                             "HSCA5CE8", "HZCZ", "W6", "P5", "ECES"])


@settings(max_examples=80, deadline=None)
@given(
    names=st.lists(mod_names, min_size=0, max_size=8, unique=True),
    data=st.data(),
)
def test_mod_write_read_round_trip(names, data):
    m = len(names)
    values = data.draw(st.lists(st.floats(-99999.0, 99999.0), min_size=m, max_size=m))
    sigmas = data.draw(st.lists(st.one_of(st.none(), st.floats(0.0, 9999.0)),
                                min_size=m, max_size=m))
    fixed = data.draw(st.lists(st.booleans(), min_size=m, max_size=m))
    parallel = data.draw(st.lists(st.booleans(), min_size=m, max_size=m))
    model = TPointModel(names, values, sigma_arcsec=sigmas, fixed=fixed, parallel=parallel,
                        caption="Round trip")
    back = parse_mod(format_mod(model))
    assert back.names == model.names
    # written to 4 (values) and 5 (sigmas) decimals: off by at most half the last digit, plus
    # the binary representation of the decimal read back (below 1e-9 for |x| < 1e5; 1.09375
    # is written 1.0938, which reads back 5.00000000001e-05 away)
    represented = 1e-9
    np.testing.assert_allclose(back.values_arcsec, model.values_arcsec, rtol=0,
                               atol=0.5e-4 + represented)
    expected_sigma = np.array([np.nan if s is None else s for s in sigmas], float)
    np.testing.assert_allclose(back.sigma_arcsec, expected_sigma, rtol=0,
                               atol=0.5e-5 + represented)
    assert back.fixed == model.fixed and back.parallel == model.parallel
    assert format_mod(back) == format_mod(model)


# ---------------------------------------------------------------------------------------------
# format sniffing: by content, never by extension
# ---------------------------------------------------------------------------------------------
def test_sniff_format_by_content(tmp_path):
    assert sniff_format(DATA / "masked.dat") == "tpoint"
    assert sniff_format(DATA / "radec_sexagesimal.dat") == "tpoint"
    assert sniff_format(DATA / "mmt_k_and_e_tpoint.mod") == "mod"
    disguised = tmp_path / "model.dat"
    disguised.write_text((DATA / "flags.mod").read_text())
    assert sniff_format(disguised) == "mod"
    ecsv = tmp_path / "recordings.txt"
    ecsv.write_text("# %ECSV 1.0\n# ---\n")
    assert sniff_format(ecsv) == "ecsv"
    no_params = tmp_path / "bare.mod"
    no_params.write_text("Caption\n  IA   +1.0\nEND\n")
    assert sniff_format(no_params) == "mod" and read_mod(no_params).parameters is None


def test_sniff_format_real_files():
    assert sniff_format(real_file("mmt_20210821_k_and_e.dat")) == "tpoint"
    assert sniff_format(real_file("auxtel_20200315.dat")) == "tpoint"


@pytest.mark.parametrize("text", ["", "only a caption\n", "caption\n%%% what is this\n"])
def test_sniff_format_refuses_unknown_content(tmp_path, text):
    path = tmp_path / "mystery.bin"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        sniff_format(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_model_file_from_a_fit(tmp_path):
    from controller.pointing.fitting import fit_model

    data = read_tpoint(DATA / "masked.dat").pointing_data(include_masked=True)
    result = fit_model(data, ["IA", "IE", "P2"], robust=False)
    model = TPointModel.from_fit(result, caption="Fitted to masked.dat")
    path = tmp_path / "fitted.mod"
    write_mod(model, path)
    back = read_mod(path)
    assert back.caption == "Fitted to masked.dat"
    assert back.parameters[:3] == ("T", "6", f"{result.sky_rms_arcsec:.3f}")
    np.testing.assert_allclose(back.values_arcsec, result.model.values_arcsec, atol=0.5e-4)
    assert math.isnan(back.sigma_arcsec[2])  # P2 is unconstrained: written without sigma
    assert back.sigma_arcsec[0] == pytest.approx(result.sigma_arcsec[0], abs=0.5e-5)
