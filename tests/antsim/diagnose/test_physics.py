"""antsim/diagnose/physics.py: a harmonic named as one, and what would tell two candidates
apart that the data cannot."""

from __future__ import annotations

import numpy as np

from antsim.diagnose import diagnose
from antsim.diagnose.candidates.library import candidate
from antsim.diagnose.physics import harmonic_words, signature_words, tell_apart
from antsim.diagnose.problem import term_columns
from tests.conftest import tpoint_like


def test_harmonic_terms_in_words():
    assert harmonic_words(["HESA2", "HECA2"]) == "dE varies as sin 2A and cos 2A"
    assert harmonic_words(["HASA", "HACA", "HASA2", "HACA2"]) == \
        "dA varies as sin A, cos A, sin 2A and cos 2A"
    assert harmonic_words(["HSSE7", "HSCE7"]) == "dA cos E varies as sin 7E and cos 7E"
    assert harmonic_words(["HDSD3"]) == "dDec varies as sin 3 Dec"
    assert harmonic_words(["IA"]) == ""  # not a harmonic: the candidate's signature
    assert signature_words(candidate("step"), ("el_arcsec",)) == candidate("step").signature


def test_every_harmonic_of_the_library_names_its_mechanisms_and_asserts_none():
    """What a finding of each pure harmonic says: several mechanisms, none asserted; a
    candidate with a signature beyond a harmonic names its own."""
    for name in ("az_track_2a", "az_runout_1a_2a", "el_periodic_el", "az_periodic_az"):
        c = candidate(name)
        assert c.harmonic and c.mechanisms
    assert not candidate("sunset_drift").harmonic
    d = diagnose(tpoint_like(n=160, seed=3, extra={"HESA3": 1.0, "HECA3": 0.5}),
                 held_out=False)
    doc = d.findings[0].to_json()
    assert doc["effect"] == "az_track_3a" and doc["mechanism_asserted"] is False
    assert doc["signature"] == "dE varies as sin 3A and cos 3A"
    assert "None of them is asserted" in doc["explanation"]


def test_what_tells_two_models_apart():
    """An elevation error of three cycles against one of four, fitted to stars of 40-85
    deg, part below 40 deg: the words name an elevation there and how far apart the two
    predict; models that differ in time need a second night."""
    obs = tpoint_like(n=120, seed=1, el_deg=(40.0, 85.0), extra={"HESE3": 3.0})
    base = ["IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX"]
    family = candidate("el_periodic_el")
    y = np.concatenate([obs.xel_arcsec, obs.el_arcsec])
    coefs, models = [], []
    for n in (3, 4):
        x = term_columns([*base, *family.order_terms(n)], obs)
        coefs.append(np.linalg.lstsq(x, y, rcond=None)[0])
        models.append([(family, n, None)])
    words = tell_apart(obs, base, models, coefs)
    el = float(words.split("elevation ")[1].split(" deg")[0])
    assert words.startswith("observations near azimuth") and el < 40.0, words
    apart, here = (float(v.split('"')[0]) for v in words.split("predict ")[1].split("most "))
    assert apart > 2.0 * here
    timed = tell_apart(obs, base, [[(candidate("sunset_drift"), 3600.0, None)],
                                   [(family, 3, None)]], coefs)
    assert timed.startswith("a second night")
