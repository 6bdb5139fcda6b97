"""Model files in TPOINT's vocabulary (controller.pointing.vocabulary): every term that is a
TPOINT term up to sign is written under TPOINT's name with TPOINT's sign, the old name in a
comment; the file points exactly as the model did and reads back; old files still read;
every output says its units and sign."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from antsim.cli import main
from controller.pointing.legacy import RelabelledTermsWarning
from controller.pointing.model import PointingModel
from controller.pointing.modelio import load_model
from controller.pointing.signs import sign_convention
from controller.pointing.terms import GHIGO_EQUIVALENTS, KATPOINT_EQUIVALENTS, WRIGHT_EQUIVALENTS
from controller.pointing.tpoint import TPointModel, format_mod, parse_mod
from controller.pointing.vocabulary import in_tpoint_terms
from controller.units import ARCSEC_PER_RAD

RNG = np.random.default_rng(27)
AZ = np.radians(RNG.uniform(0.0, 360.0, 400))
EL = np.radians(RNG.uniform(8.0, 86.0, 400))


def _sky_arcsec(model) -> np.ndarray:
    """(dA cos E, dE) of ``model`` at the random sky positions, arcsec."""
    d_az, d_el = model.offset_rad(AZ, EL)
    return np.array([d_az * np.cos(EL), d_el]) * ARCSEC_PER_RAD


@pytest.mark.parametrize("table", [GHIGO_EQUIVALENTS, KATPOINT_EQUIVALENTS, WRIGHT_EQUIVALENTS],
                         ids=["ghigo", "katpoint", "wright"])
def test_every_mapped_term_is_written_under_tpoints_name_and_points_the_same(table):
    names = list(table)
    values = RNG.uniform(-300.0, 300.0, len(names)).round(4)
    sigmas = RNG.uniform(0.5, 5.0, len(names)).round(5)
    model = TPointModel.from_model(PointingModel(names, values), sigmas, caption="fit",
                                   n_obs=120, sky_rms_arcsec=12.5)
    text = format_mod(in_tpoint_terms(model))
    back = parse_mod(text)
    assert back.names == tuple(table[n][0] for n in names)
    np.testing.assert_array_equal(back.values_arcsec, [table[n][1] * v
                                                       for n, v in zip(names, values, strict=True)])
    np.testing.assert_array_equal(back.sigma_arcsec, sigmas)
    # the same corrections everywhere (the values were rounded to the file's 4 decimals)
    np.testing.assert_allclose(_sky_arcsec(back), _sky_arcsec(model), rtol=0, atol=1e-9)
    assert back.fit_sky_rms_arcsec == 12.5 and back.fit_observations == 120
    lines = text.splitlines()
    assert lines[1] == "! Units: arcsec. Sign: TPOINT's: true (observed) = raw (encoder) + " \
                       "correction."
    for name, line in zip(names, lines[4:], strict=False):
        twin, sign = table[name]
        assert line.split("!")[1].startswith(f" {name} = {'-' if sign < 0 else ''}{twin} (")


def test_the_reports_tied_pairs_are_the_azimuth_axis_tilt():
    # W2 = W8 and W3 = -W7 (the report's ties, section II) are AN and AW
    model = PointingModel(["W6", "W2", "W3", "W7", "W8"], [700.0, -12.0, 30.0, -30.0, -12.0])
    back = parse_mod(format_mod(in_tpoint_terms(TPointModel.from_model(model))))
    assert back.as_dict() == {"IA": 700.0, "AN": -12.0, "AW": -30.0}
    np.testing.assert_allclose(_sky_arcsec(back), _sky_arcsec(model), rtol=0, atol=1e-9)
    # untied (as fits leave them) they are harmonics: W2 = HECA, W3 = -HESA, W7 = -HSCASE,
    # W8 = HSSASE
    untied = PointingModel(["W2", "W3", "W7", "W8"], [-12.0, 30.0, -29.0, -11.0])
    back = parse_mod(format_mod(in_tpoint_terms(TPointModel.from_model(untied))))
    assert back.as_dict() == {"HECA": -12.0, "HESA": -30.0, "HSCASE": 29.0, "HSSASE": -11.0}
    np.testing.assert_allclose(_sky_arcsec(back), _sky_arcsec(untied), rtol=0, atol=1e-9)


def test_terms_without_a_twin_or_whose_twin_is_taken_keep_their_names():
    model = PointingModel(["IA", "W6", "P9", "W1"], [5.0, 700.0, 2.0, -110.0])
    written = in_tpoint_terms(TPointModel.from_model(model))
    assert written.names == ("IA", "W6", "P9", "IE")
    text = format_mod(written)
    assert "P1..P22 (katpoint): indicated minus true" in text.splitlines()[1]
    np.testing.assert_allclose(_sky_arcsec(parse_mod(text)), _sky_arcsec(model), atol=1e-9)


def test_sign_convention_in_words():
    assert sign_convention(["IA", "HESA2"]) == \
        "TPOINT's: true (observed) = raw (encoder) + correction"
    assert sign_convention([f"W{i}" for i in range(1, 11)]) == \
        "W1..W10 (Ghigo 1990, NRAO EDIR 288, section II): indicated minus true (the " \
        "negative of TPOINT's correction)"
    assert sign_convention(["W5", "HSCF"]).endswith(
        "; the other terms TPOINT's: true (observed) = raw (encoder) + correction")
    assert "Crane 1981" in sign_convention(["C1", "C11"])


def test_fit_writes_a_model_that_run_reads_back(tmp_path, capsys, repo_root):
    data = repo_root / "examples" / "mmt_20210821_k_and_e.dat"
    target = tmp_path / "fitted.mod"
    assert main(["fit", str(data), "--model", "ghigo10", "--write-model", str(target)]) == 0
    out = capsys.readouterr().out
    assert f"wrote {target} (TPOINT's term names and signs)" in out
    assert "units: arcsec; sign: W1..W10 (Ghigo 1990" in out and "honest sigma (\")" in out
    assert main(["fit", str(data), "--model", "ghigo10", "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)
    model = load_model(target)
    assert model.names == tuple(GHIGO_EQUIVALENTS[f"W{i}"][0] for i in range(1, 11))
    ours = PointingModel(list(fit["terms"]), [t["value_arcsec"] for t in fit["terms"].values()])
    # 4 decimals per value; on the sky each function is at most cot E (7.1 at 8 deg)
    np.testing.assert_allclose(_sky_arcsec(model), _sky_arcsec(ours), rtol=0, atol=1e-3)
    assert model.fit_sky_rms_arcsec == pytest.approx(fit["sky_rms_arcsec"], abs=5e-4)
    assert main(["fit", str(data), "--write-model", str(tmp_path / "no" / "x.mod")]) == 2
    assert "--write-model" in capsys.readouterr().err


def test_old_model_files_still_read(tmp_path):
    # written by the report's W terms with the marker, and before it (renamed, with a note)
    marked = format_mod(PointingModel(["W1", "W6"], [-110.0, 700.0]))
    assert parse_mod(marked).as_dict() == {"W1": -110.0, "W6": 700.0}
    old = "old fit\nT  0  0.000  0.0000  0.0000\n  W1      +700.0000\n  W6      -110.0000\nEND\n"
    with pytest.warns(RelabelledTermsWarning):
        assert parse_mod(old).as_dict() == {"W6": 700.0, "W1": -110.0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit_json = tmp_path / "fit.json"
        fit_json.write_text(json.dumps({
            "model": "ghigo10", "w_terms": "Ghigo 1990 (NRAO EDIR 288) section II",
            "n_used": 200, "sky_rms_arcsec": 40.0,
            "terms": {"W1": {"value_arcsec": -110.0, "sigma_arcsec": 9.0}}}))
        model = load_model(fit_json)
    assert model.as_dict() == {"W1": -110.0} and model.fit_sky_rms_arcsec == 40.0
    assert model.fit_observations == 200 and model.sigma_arcsec[0] == 9.0
