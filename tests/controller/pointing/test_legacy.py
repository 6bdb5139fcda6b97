"""Files written before antsim followed the 1990 report's W1..W10.

The reconstruction used until then put the same ten functions under other names (its
definitions, from the docs/assumptions.md of that time, are written out below). Files that
name W terms without saying which definition they follow are renamed to the report's, with
one note; the renamed model points exactly as the old one did.
"""

from __future__ import annotations

import json
import math
import warnings
from contextlib import redirect_stderr, redirect_stdout
from io import StringIO

import numpy as np
import pytest

from antsim.cli import main as cli
from controller.pointing.legacy import (
    RECONSTRUCTED_TO_REPORT,
    W_TERMS,
    W_TERMS_COMMENT,
    W_TERMS_KEY,
    RelabelledTermsWarning,
)
from controller.pointing.model import PointingModel
from controller.pointing.modelio import model_from_json, model_to_json
from controller.pointing.tpoint import format_mod, parse_mod
from controller.program.recordings import read_recordings
from controller.units import ARCSEC_PER_RAD

_AZ, _EL = np.meshgrid(np.radians(np.arange(0.0, 360.0, 20.0)),
                       np.radians(np.arange(5.0, 86.0, 10.0)))
AZ, EL = _AZ.ravel(), _EL.ravel()

#: the reconstruction's W terms, indicated minus true (dA, dE) per unit coefficient, as
#: docs/assumptions.md wrote them before the report was at hand:
#:     dA = W1 + W2 sec E + W3 tan E + W9 sin A tan E + W10 cos A tan E
#:     dE = W4 cos E + W5 cot E + W6 + W7 cos A + W8 sin A
RECONSTRUCTION = {
    "W1": lambda a, e: (1 + 0 * a, 0 * a),
    "W2": lambda a, e: (1 / np.cos(e) + 0 * a, 0 * a),
    "W3": lambda a, e: (np.tan(e) + 0 * a, 0 * a),
    "W4": lambda a, e: (0 * a, np.cos(e) + 0 * a),
    "W5": lambda a, e: (0 * a, 1 / np.tan(e) + 0 * a),
    "W6": lambda a, e: (0 * a, 1 + 0 * a),
    "W7": lambda a, e: (0 * a, np.cos(a) + 0 * e),
    "W8": lambda a, e: (0 * a, np.sin(a) + 0 * e),
    "W9": lambda a, e: (np.sin(a) * np.tan(e), 0 * a),
    "W10": lambda a, e: (np.cos(a) * np.tan(e), 0 * a),
}


@pytest.mark.parametrize("old", sorted(RECONSTRUCTION))
def test_a_renamed_term_is_the_same_function_with_the_same_sign(old):
    new = RECONSTRUCTED_TO_REPORT[old]
    d_az, d_el = PointingModel([new], [1.0]).offset_rad(AZ, EL)
    want_az, want_el = RECONSTRUCTION[old](AZ, EL)
    np.testing.assert_allclose(d_az * ARCSEC_PER_RAD, want_az, rtol=0, atol=1e-12)
    np.testing.assert_allclose(d_el * ARCSEC_PER_RAD, want_el, rtol=0, atol=1e-12)


def test_the_renaming_is_a_permutation():
    assert sorted(RECONSTRUCTED_TO_REPORT) == sorted(RECONSTRUCTED_TO_REPORT.values())


OLD_VALUES = {"W1": -113.0, "W6": 734.4, "W9": 20.0, "IA": 5.0}  # arcsec, old names


def test_a_model_json_without_the_marker_is_renamed_with_one_note():
    doc = {"model": "ghigo10", "terms": {k: {"value_arcsec": v} for k, v in OLD_VALUES.items()}}
    with pytest.warns(RelabelledTermsWarning) as notes:
        model = model_from_json(doc, "old/fit.json")
    assert len(notes) == 1
    note = str(notes[0].message)
    assert note.startswith("old/fit.json: ") and "\n" not in note and "W1->W6" in note
    assert model.as_dict() == {"W1": 734.4, "W6": -113.0, "W8": 20.0, "IA": 5.0}
    # the renamed model points as the old file meant: the reconstruction's functions
    old_az = sum(v * RECONSTRUCTION[k](AZ, EL)[0] for k, v in OLD_VALUES.items() if k != "IA")
    d_az, _ = model.offset_rad(AZ, EL)
    np.testing.assert_allclose(d_az * ARCSEC_PER_RAD, old_az + 5.0, atol=1e-9)


def test_files_written_now_carry_the_marker_and_load_unchanged():
    model = PointingModel(["W1", "W6", "IA"], [-113.0, 734.4, 5.0], name="ghigo10")
    doc = model_to_json(model)
    assert doc[W_TERMS_KEY] == W_TERMS
    text = format_mod(model)
    assert W_TERMS_COMMENT in text.splitlines()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no note
        assert model_from_json(doc, "new.json").as_dict() == model.as_dict()
        assert parse_mod(text, "new.mod").as_dict() == model.as_dict()
    # models without W terms are written as before
    tpoint = PointingModel(["IA", "IE"], [1.0, 2.0])
    assert W_TERMS_KEY not in model_to_json(tpoint) and "!" not in format_mod(tpoint)


def test_a_mod_file_without_the_marker_is_renamed_with_its_sigmas_and_flags():
    text = "fit A\n  W1   +10.0000     1.50000\n =W6  +700.0000     2.00000\nEND\n"
    with pytest.warns(RelabelledTermsWarning, match="old.mod"):
        model = parse_mod(text, "old.mod")
    assert model.names == ("W1", "W6")  # the report's order
    assert model.as_dict() == {"W1": 700.0, "W6": 10.0}
    assert list(model.sigma_arcsec) == [2.0, 1.5] and list(model.fixed) == [True, False]


@pytest.fixture(scope="module")
def old_recordings(tmp_path_factory, quiet_path):
    """A one-hour noise-free run with a W model in use, and the same file as the
    reconstruction would have written it (its model's W terms under their old names, no
    marker)."""
    from astropy.table import Table

    from tests.conftest import edit_text

    root = tmp_path_factory.mktemp("legacy")
    scenario = root / "quiet_w.toml"
    scenario.write_text(edit_text(quiet_path.read_text(encoding="utf-8"), [(
        'model = "none"',
        'model = "ghigo10"\nunits = "arcsec"\n[controller.terms]\nW1 = -113.0\nW6 = 40.0')]),
        encoding="utf-8")
    new = root / "new"
    assert cli(["run", str(scenario), "--out", str(new), "--no-report", "--no-progress"]) == 0
    table = Table.read(new / "recordings.ecsv", format="ascii.ecsv")
    model = table.meta["model"]
    assert model.pop(W_TERMS_KEY) == W_TERMS
    back = {v: k for k, v in RECONSTRUCTED_TO_REPORT.items()}
    model["terms_arcsec"] = {back[k]: v for k, v in model["terms_arcsec"].items()}
    old = root / "old"
    old.mkdir()
    table.write(old / "recordings.ecsv", format="ascii.ecsv")
    return new, old


def test_old_recordings_load_with_one_note(old_recordings):
    new, old = old_recordings
    with pytest.warns(RelabelledTermsWarning) as notes:
        meta = read_recordings(old / "recordings.ecsv").meta
    assert len(notes) == 1
    terms = meta["model"]["terms_arcsec"]
    assert list(terms) == [f"W{i}" for i in range(1, 11)]
    assert {k: v for k, v in terms.items() if v} == {"W1": -113.0, "W6": 40.0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_recordings(new / "recordings.ecsv").meta["model"]["terms_arcsec"] == \
            meta["model"]["terms_arcsec"]


def _cli(argv):
    out, err = StringIO(), StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        status = cli(argv)
    return status, out.getvalue(), err.getvalue()


def test_the_command_line_prints_the_note_in_one_line(old_recordings):
    new, old = old_recordings
    # the file is read twice by the command (data and metadata): one note
    status, out, err = _cli(["fit", str(old / "recordings.ecsv"), "--terms", "W1,W6", "--json"])
    assert status == 0
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("antsim fit: note: ")
    assert "renamed to the report's" in lines[0]
    # the fit itself never depended on the names: the same as the file written now
    status_new, out_new, err_new = _cli(["fit", str(new / "recordings.ecsv"), "--terms", "W1,W6",
                                         "--json"])
    assert status_new == 0 and err_new == ""
    a, b = json.loads(out), json.loads(out_new)
    assert a["terms"] == b["terms"] and math.isfinite(a["sky_rms_arcsec"])
