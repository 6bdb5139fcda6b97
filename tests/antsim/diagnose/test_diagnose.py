"""antsim diagnose without simulation: the library, the new effects, the statistics on
synthetic data of known noise, the JSON contract, the command line and the real TPOINT data.

Synthetic data: random positions over the sky, the eight TPOINT terms, white noise of known
rms, fixed seeds. Real data tests read the files that ship in examples/.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from antsim.cli import main as cli
from antsim.diagnose import diagnose, load_observations
from antsim.diagnose.candidates.base import source_rates_arcsec_s
from antsim.diagnose.candidates.library import CANDIDATES, candidate
from antsim.diagnose.data import Observations
from antsim.diagnose.problem import term_columns
from antsim.diagnose.shapefit import shape_fit
from antsim.world.effects import EFFECTS
from antsim.world.effects.harmonics import HARMONIC_EFFECTS, AzimuthTrack2A
from controller.units import RAD_PER_ARCSEC

REAL = Path(__file__).resolve().parents[3] / "examples"
FINDING_KEYS = {"effect", "terms", "explanation", "where", "params", "significance",
                "sky_rms_before_arcsec", "sky_rms_after_arcsec"}


def synthetic(n: int = 160, seed: int = 3, noise_arcsec: float = 1.0,
              extra: dict[str, float] | None = None, lat_deg: float = 38.43) -> Observations:
    """TPOINT-like observations: random (az, el), eight terms, white noise (arcsec)."""
    rng = np.random.default_rng(seed)
    az = rng.uniform(0.0, 2 * math.pi, n)
    el = np.radians(rng.uniform(15.0, 85.0, n))
    geo = Observations(t_s=np.arange(n, dtype=float), az_rad=az, el_rad=el,
                       xel_arcsec=np.zeros(n), el_arcsec=np.zeros(n), good=np.ones(n, bool),
                       meta={"latitude_deg": lat_deg}, kind="tpoint")
    truth = {"IA": 30.0, "IE": -12.0, "NPAE": 5.0, "CA": -8.0, "AN": 4.0, "AW": -6.0,
             "TF": 10.0, "TX": 2.0, **(extra or {})}
    err = term_columns(list(truth), geo) @ np.array(list(truth.values()))
    err += rng.normal(0.0, noise_arcsec, 2 * n)
    return Observations(t_s=geo.t_s, az_rad=az, el_rad=el, xel_arcsec=err[:n],
                        el_arcsec=err[n:], good=geo.good, meta=geo.meta, kind="tpoint")


def test_term_columns_scale_by_the_kept_cosine_of_elevation():
    """term_columns reads cos(el) kept on the observations (asked for ~150 times at 200,000
    scans): the bytes of computing it each time, read-only, and a selection's its own."""
    from controller.pointing.model import PointingModel

    obs = synthetic(n=50)
    obs = replace(obs, az_rad=np.concatenate([[0.0], obs.az_rad[1:]]))  # sin(-0.0): -0.0
    names = ["IA", "IE", "CA", "HESA2", "HECA7", "AN", "HSCA", "TX"]
    ba, be = PointingModel(obs.terms(names)).design_matrix(obs.az_rad, obs.el_rad)
    direct = -np.vstack([ba * np.cos(obs.el_rad)[:, None], be])
    cols = term_columns(names, obs)
    assert cols.tobytes() == direct.tobytes() and cols.flags.c_contiguous
    assert not obs.cos_el.flags.writeable
    part = obs.select(obs.el_rad > np.median(obs.el_rad))
    assert part.cos_el.tobytes() == np.cos(part.el_rad).tobytes()



def test_polarization_differences_of_scans_with_both_hands_only():
    """XR minus XL of each scan that has both, good (arcsec); NaN elsewhere, and for
    recordings of the average alone (which skip the loop over the scans)."""
    from antsim.diagnose.data import from_columns

    pol = np.array(["AVG", "XR", "XL", "AVG", "XR", "AVG", "XR", "XL"])
    cols = {"scan": np.array([0, 0, 0, 1, 1, 2, 2, 2]), "polarization": pol,
            "t_s": np.array([0.0, 0, 0, 60, 60, 120, 120, 120]),
            "az_deg": np.full(8, 100.0), "el_deg": np.full(8, 40.0),
            "xel_arcmin": np.array([0.0, 0.5, 0.2, 0, 0.1, 0, 0.3, 0.4]),
            "el_arcmin": np.array([0.0, -0.1, 0.1, 0, 0, 0, 0.2, 0.2]),
            "good": np.array([True, True, True, True, True, True, True, False])}
    obs = from_columns(cols)
    np.testing.assert_allclose(obs.pol_xel_arcsec[0], 18.0, rtol=1e-12)
    np.testing.assert_allclose(obs.pol_el_arcsec[0], -12.0, rtol=1e-12)
    assert np.isnan(obs.pol_xel_arcsec[1:]).all()  # scan 1 has no XL, scan 2's XL is bad
    avg = pol == "AVG"
    alone = from_columns({k: v[avg] for k, v in cols.items()})
    assert np.isnan(alone.pol_xel_arcsec).all() and np.isnan(alone.pol_el_arcsec).all()
    assert alone.xel_arcsec.tobytes() == obs.xel_arcsec.tobytes()

def test_source_candidate_reads_the_kept_sources_of_the_good_scans():
    """The source candidate's sources come from ``Observations.good_sources``, counted once
    per recordings (several times a round at 200,000 scans): np.unique's, read-only, and a
    selection's its own."""
    from antsim.diagnose.candidates.optics import SourceCandidate

    obs = synthetic(n=60)
    names = np.array(["3C84", "Cygnus A", "Orion A"])[np.arange(60) % 3]
    good = np.ones(60, dtype=bool)
    good[[2, 5, 8, 1]] = False  # Orion A keeps 17 good scans, Cygnus A 19, 3C84 all 20
    obs = replace(obs, source=names, good=good)
    want, counts = np.unique(names[good], return_counts=True)
    got, got_counts = obs.good_sources
    assert got.tolist() == want.tolist() and got_counts.tolist() == counts.tolist()
    assert not got.flags.writeable and not got_counts.flags.writeable
    part = obs.select(np.arange(60) < 20)
    assert part.good_sources[1].tolist() == np.unique(names[:20][good[:20]],
                                                      return_counts=True)[1].tolist()
    c = SourceCandidate()
    c.MIN_SCANS = 18
    assert c.thetas(obs) == ["3C84", "Cygnus A"]
    assert counts.tolist() == [20, 19, 17]

# ------------------------------------------------------------------------------ the library
def test_library_covers_the_signature_table_and_the_non_harmonic_effects():
    names = {c.name for c in CANDIDATES}
    required = {"az_track_2a", "az_track_3a", "az_runout_1a", "az_runout_2a", "el_nod_1a",
                "el_eccentricity", "el_eccentricity_2e", "refraction", "gravity",
                "feed_offset", "sunset_drift", "temperature_drift", "clock_error",
                "servo_lag", "backlash", "polarization_squint", "source_structure",
                "beam_width", "exact_tilt_collimation"}
    assert required <= names
    for c in CANDIDATES:
        d = c.describe()
        assert d["signature"] and d["explanation"] and d["parameters"], c.name
        if c.effect not in (None, "terms"):
            assert c.effect in EFFECTS, c.name  # the simulator can reproduce it
    assert candidate("az_track_2a").terms == ("HESA2", "HECA2")


def test_harmonic_effect_amplitude_and_phase_round_trip():
    e = AzimuthTrack2A(amplitude_arcsec=6.0, phase_deg=30.0)
    coeff = e.coefficients()
    # TPOINT's HESA2 is dE = c sin 2A_T with A_T = 180 deg - A_N: minus sin 2(A_N - 180 deg)
    assert coeff["HESA2"] == pytest.approx(-6.0 * math.cos(math.radians(30.0)))
    assert coeff["HECA2"] == pytest.approx(6.0 * math.sin(math.radians(30.0)))
    amp, phase = AzimuthTrack2A.amplitude_phase(coeff["HESA2"], coeff["HECA2"])
    assert (amp, phase) == pytest.approx((6.0, 30.0))
    # the effect's error is minus its correction a sin(2 (A_N - 180 deg) + phase) (indicated
    # minus true)
    from antsim.world.effects.base import PointingState

    st = PointingState(t_s=0.0, az_rad=0.4, el_rad=0.7)
    d_az, d_el = e.pointing_error(st)
    expected = -6.0 * math.sin(2 * (0.4 - math.pi) + math.radians(30.0))
    assert d_az == 0.0
    assert d_el == pytest.approx(math.radians(expected / 3600.0), rel=1e-9)


#: each harmonic effect's correction: (axis, cycles, argument) of a sin(n X + phase)
HARMONIC_PHYSICS = {
    "az_track_2a": ("E", 2, "A"), "az_track_3a": ("E", 3, "A"), "az_runout_1a": ("A", 1, "A"),
    "az_runout_2a": ("A", 2, "A"), "el_nod_1a": ("E", 1, "A"), "el_eccentricity": ("E", 1, "E"),
    "el_eccentricity_2e": ("E", 2, "E"),
}


@pytest.mark.parametrize("name", sorted(HARMONIC_PHYSICS))
@pytest.mark.parametrize("phase_deg", [0.0, 30.0, 135.0, 250.0])
def test_harmonic_effects_are_the_documented_sinusoid(name, phase_deg):
    """The error of every harmonic effect is minus a sin(nX + phase), X the azimuth counted
    from South through West, A_N - 180 deg, or the elevation, in dA or dE: whatever the term
    library's sign convention, and the inverse amplitude_phase gives the parameters back."""
    from antsim.world.effects.base import PointingState

    axis, n, arg = HARMONIC_PHYSICS[name]
    cls = EFFECTS[name]
    assert cls in HARMONIC_EFFECTS
    e = cls(amplitude_arcsec=7.0, phase_deg=phase_deg)
    coeff = e.coefficients()
    amp, phase = cls.amplitude_phase(coeff[cls.sin_term], coeff[cls.cos_term])
    assert amp == pytest.approx(7.0, rel=1e-12)
    assert (phase - phase_deg + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=1e-9)
    for az, el in ((0.4, 0.7), (2.0, 0.3), (3.9, 1.1), (5.5, 0.9)):
        x = az - math.pi if arg == "A" else el
        want = -7.0 * math.sin(n * x + math.radians(phase_deg)) * RAD_PER_ARCSEC
        d_az, d_el = e.pointing_error(PointingState(t_s=0.0, az_rad=az, el_rad=el))
        got, other = (d_az, d_el) if axis == "A" else (d_el, d_az)
        assert got == pytest.approx(want, abs=1e-15)
        assert other == 0.0


@pytest.mark.parametrize("name", sorted(HARMONIC_PHYSICS))
def test_harmonic_candidates_share_the_effects_phase(name):
    """A library candidate's phase is its simulator effect's: the unit signal at a phase is
    the effect's coefficients through the term columns, and a fit's coefficients give the
    effect's amplitude and phase back (the blind test and modelit rely on it)."""
    obs = synthetic(n=40, noise_arcsec=0.0)
    c = candidate(name)
    e = EFFECTS[name](amplitude_arcsec=5.0, phase_deg=200.0)
    coeff = e.coefficients()
    cols = term_columns(c.terms, obs)
    want = cols @ np.array([coeff[t] for t in c.terms])
    np.testing.assert_allclose(5.0 * c.unit_signal(obs, {"phase_deg": 200.0}), want,
                               rtol=0, atol=1e-12)
    params, amp, _ = c.params_from(obs, None, np.array([coeff[t] for t in c.terms]),
                                   np.eye(2), c.terms)
    assert amp == pytest.approx(5.0, rel=1e-12)
    assert params["phase_deg"] == pytest.approx(200.0, abs=1e-9)


def test_new_effects_load_from_a_scenario(ghigo_text, write_scenario):
    from antsim.scenario import load_scenario
    from controller.errors import InputError

    blocks = ('\n[[truth.effects]]\neffect = "az_track_3a"\namplitude_arcsec = 5.0\n'
              'phase_deg = 10.0\n\n[[truth.effects]]\neffect = "temperature_drift"\n'
              'arcsec_per_k = 1.5\ntau_s = 3600.0\nreference_c = 4.0\n')
    sc = load_scenario(write_scenario(ghigo_text + blocks))
    names = [e.name for e in sc.effects]
    assert names[-2:] == ["az_track_3a", "temperature_drift"]
    bad = ghigo_text + '\n[[truth.effects]]\neffect = "temperature_drift"\ntau_s = -5.0\n'
    with pytest.raises(InputError, match="tau_s"):
        load_scenario(write_scenario(bad, name="bad.toml"))


def test_temperature_drift_lags_the_air():
    from antsim.world.effects.drifts import structure_temperature_c

    t = np.arange(0.0, 2 * 86400.0, 60.0)
    air = 5.0 + 5.0 * np.sin(2 * math.pi * t / 86400.0)
    lagged = structure_temperature_c(t, air, 3600.0)
    # on the second day a first-order lag of a daily sinusoid peaks atan(w tau)/w later:
    # 3465 s for tau = 1 h
    day2 = t >= 86400.0
    late = t[day2][np.argmax(lagged[day2])] - t[day2][np.argmax(air[day2])]
    assert late == pytest.approx(86400.0 / (2 * math.pi) * math.atan(2 * math.pi * 3600.0
                                                                     / 86400.0), abs=120.0)
    assert np.array_equal(structure_temperature_c(t, air, 0.0), air)


def test_clock_regressor_is_the_apparent_motion_of_the_source():
    """dA/dt and dE/dt from (A, E, latitude) agree with the ephemeris to 0.1%."""
    from controller.astro.ephemeris import Ephemeris
    from controller.astro.site import Site
    from controller.astro.sources import FixedSource

    site = Site(38.43, -79.84, 800.0)
    src = FixedSource("x", 80.0, 30.0, "icrs")
    eph = Ephemeris(site, "1990-02-08T17:00:00", 7200.0, (src,))
    t = np.linspace(600.0, 6600.0, 7)
    az, el = eph.altaz_rad(0, t)
    h = 1.0
    az1, el1 = eph.altaz_rad(0, t + h)
    az0, el0 = eph.altaz_rad(0, t - h)
    num_x = ((az1 - az0 + math.pi) % (2 * math.pi) - math.pi) / (2 * h) * np.cos(el)
    num_e = (el1 - el0) / (2 * h)
    obs = Observations(t_s=t, az_rad=az, el_rad=el, xel_arcsec=t * 0, el_arcsec=t * 0,
                       good=np.ones(t.size, bool), meta={"latitude_deg": 38.43})
    rx, re_ = source_rates_arcsec_s(obs)
    assert np.allclose(rx, np.degrees(num_x) * 3600.0, rtol=2e-3, atol=0.02)
    assert np.allclose(re_, np.degrees(num_e) * 3600.0, rtol=2e-3, atol=0.02)


# ------------------------------------------------------------------------------ statistics
def test_data_explained_to_the_noise_give_no_finding():
    for seed in (3, 4, 5):
        d = diagnose(synthetic(seed=seed))
        doc = d.to_json()
        assert doc["mismatch"] is False and doc["findings"] == [], seed


def test_a_hidden_harmonic_is_named_with_its_terms_and_amplitude():
    """HESA2/HECA2 of 1.2" amplitude in 1" noise on 160 stars: about 8 sigma."""
    a, phase = 1.2, math.radians(40.0)
    obs = synthetic(extra={"HESA2": a * math.cos(phase), "HECA2": a * math.sin(phase)})
    d = diagnose(obs)
    doc = d.to_json()
    assert doc["mismatch"] is True
    first = doc["findings"][0]
    assert set(first) == FINDING_KEYS
    assert first["effect"] == "az_track_2a"
    assert first["terms"] == ["HESA2", "HECA2"]
    r = d.findings[0].result
    assert abs(r.amplitude - a) < 3 * r.amplitude_sigma
    assert first["sky_rms_after_arcsec"] < first["sky_rms_before_arcsec"]
    assert first["significance"] > 3.0
    model = d.updated_model()
    assert {"HESA2", "HECA2"} <= set(model.names)


def test_a_term_the_model_mimics_is_judged_by_what_the_model_cannot_absorb():
    """sin E on top of IE, TF (cos E) and TX (cot E) over 15-85 deg: r = 1.00 with the model,
    but the part those terms cannot absorb (0.32 per arcsec of HESE over these 160 stars)
    is 25 sigma for 40" in 0.5" noise: accepted, with its correlation in TPOINT's words and
    the separation in sigma (it used to be refused). Without a noise prediction
    the F test takes the noise from the residuals, which still hold the effect (1.1" instead
    of 0.5" in elevation before it is fitted): 13 sigma, hence the bound of 10."""
    d = diagnose(synthetic(extra={"HESE": 40.0}, noise_arcsec=0.5))
    first = d.findings[0]
    assert first.effect == "el_eccentricity" and first.terms == ["HESE"]  # HECE is -TF
    sp = first.step.separation
    assert sp.r > 0.99 and "IE" in sp.partners
    assert "cannot reliably be distinguished (r = 1.00)" in sp.words
    assert sp.sigma > 10.0
    r = first.result
    assert abs(r.params["terms_arcsec"]["HESE"] - 40.0) < 3 * r.amplitude_sigma
    assert r.amplitude_sigma > 1.0  # a near-degenerate term's error bar is wide: honest
    text = d.text()
    assert "correlated: el_eccentricity and IE" in text and "the data separate it by" in text
    doc = d.to_json()
    assert doc["separations"][0]["finding"] == "el_eccentricity"
    assert doc["separations"][0]["sigma"] == pytest.approx(sp.sigma, abs=0.01)


#: held-out style TPOINT cases: effects of elevation alone that IE, TF and TX nearly
#: mimic (r = 1.00), and an azimuth runout once per turn that was named as the elevation nod
#: of the same order; 160 stars, 1" noise, seed 3 (8-12 sigma separated)
HELD_OUT_STYLE = [({"HECE2": 30.0}, "el_eccentricity_2e"),
                  ({"HESE": 30.0, "HECE": 20.0}, "el_eccentricity"),
                  ({"HASA": 1.0, "HACA": -0.8}, "az_runout_1a")]


@pytest.mark.parametrize(("extra", "effect"), HELD_OUT_STYLE)
def test_held_out_style_effects_are_named(extra, effect):
    d = diagnose(synthetic(extra=extra, seed=3))
    first = d.findings[0]
    assert first.effect == effect and first.step.heldout is None
    assert first.step.significance > 4.0
    r = first.result
    hidden = np.array([extra.get(t, 0.0) for t in r.comp_names])
    fitted = np.array([r.params["terms_arcsec"][t] for t in r.comp_names])
    assert np.linalg.norm(fitted - hidden) < 3 * max(r.amplitude_sigma, 1e-9) + 1e-9


def test_orders_of_a_family_the_data_cannot_tell_apart_are_reported():
    """Three cycles of elevation error (HESE3/HECE3, 10" in 1" noise, seed 3): over 15-85 deg
    the elevation-only effects left by IE, TF and TX are alike (r > 0.95 between their
    fitted signatures), and the simplest of them is named; the hidden order is among the
    alternatives, the family's orders said in one line, each its own entry in the JSON."""
    d = diagnose(synthetic(extra={"HESE3": 6.0, "HECE3": 8.0}, seed=3))
    first = d.findings[0]
    assert first.effect in ("el_eccentricity", "el_eccentricity_2e")
    orders = {a.result.candidate.label(a.result.theta): a for a in first.step.alternatives
              if a.sibling}
    assert "el_periodic_el[3]" in orders and orders["el_periodic_el[3]"].correlation > 0.95
    lines = [w for w in d.text().splitlines() if "and el_periodic_el with n = " in w]
    assert len(lines) == 1 and "3" in lines[0].split("n = ")[1], lines
    doc = d.to_json()
    assert "el_periodic_el[3]" in [a["alternative"] for a in doc["alternatives"]]


def test_a_mimicked_term_below_detection_is_refused_in_words():
    """The same sin E at 3.6 sigma of orthogonal part expected (11.3" in 1" noise), below
    the family's detection level (3.5-3.7 sigma two-sided for one parameter and 14-18
    candidates) at seed 4, where the data give 3.2 sigma: no finding, and the refusal says
    why in TPOINT's words (seeds 3, 5 and 11 give it at 4-5 sigma, and it is accepted)."""
    d = diagnose(synthetic(seed=4, extra={"HESE": 11.34}))
    assert d.findings == []
    words = [r.reason for r in d.selection.refused]
    assert any(w.startswith("el_eccentricity and IE") and "cannot reliably be distinguished"
               in w and "below detection" in w for w in words), words
    found = diagnose(synthetic(seed=5, extra={"HESE": 11.34})).findings
    assert found[0].effect == "el_eccentricity" and found[0].step.heldout is None


def test_a_pair_that_one_term_matches_is_offered_in_that_form():
    """A runout twice per turn with only its sine term (HASA2 1.5" in 1" noise): the pair is
    named, and HASA2 alone explains as much (the MMT case, where one TPOINT term
    matched a pair's improvement to 0.001"); the updated model takes that form."""
    d = diagnose(synthetic(extra={"HASA2": 1.5}, seed=7))
    first = d.findings[0]
    assert first.effect == "az_runout_2a" and first.terms == ["HASA2", "HACA2"]
    simple = first.step.simplest
    assert simple is not None and simple.terms == ("HASA2",)
    assert simple.sky_rms_after == pytest.approx(first.step.sky_rms_after, abs=0.01)
    assert "HASA2 alone explains as much" in d.text()
    model = d.updated_model()
    assert "HASA2" in model.names and "HACA2" not in model.names
    # a pair both of whose terms matter has no one-term form
    both = diagnose(synthetic(extra={"HASA2": 1.5, "HACA2": -1.5}, seed=7))
    assert both.findings[0].effect == "az_runout_2a" and both.findings[0].step.simplest is None


def test_heldout_losses_are_refits_without_each_star():
    """The cross-validated stage's closed-form leave-one-star-out losses (each star's two
    rows together) equal plain refits without the star, and the fold version equals its own
    refits (rounding only)."""
    from antsim.diagnose.crossval import heldout_losses
    from antsim.diagnose.linalg import lstsq

    obs = synthetic(n=30, extra={"HASA2": 3.0}, seed=9)
    x = term_columns(["IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX", "HASA2"], obs)
    y = np.concatenate([obs.xel_arcsec, obs.el_arcsec])
    used = np.ones(30, bool)
    used[4] = False  # an unused star is neither fitted nor predicted
    folds = np.arange(30) % 3
    for f in (None, folds):
        got = heldout_losses(x, y, used, f)
        want = []
        for i in np.flatnonzero(used):
            train = used & ((np.arange(30) != i) if f is None else (folds != folds[i]))
            coef, _ = lstsq(x[np.concatenate([train, train])], y[np.concatenate([train, train])])
            r = (y - x @ coef).reshape(2, 30)[:, i]
            want.append(float(r @ r))
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_without_a_noise_prediction_prediction_extends_a_significant_model():
    """TPOINT-like data with three effects in 1" noise on 160 stars (seed 11): the track's
    twice-per-turn pair and the azimuth runout are significant, the fourth-order track term
    (0.6") is not (1.5 sigma after the family's correction); the cross-validated stage adds
    it because it lowers the held-out Sky RMS by more than a standard error, said so, never
    beyond 4 findings in all; with a noise prediction (a scenario) the stage does not run,
    and data without a significant finding get none (the nulls above)."""
    from dataclasses import replace

    from antsim.diagnose.problem import Prediction

    obs = synthetic(extra={"HESA2": 2.0, "HECA2": 1.0, "HASA": 0.6, "HACA": -0.6,
                           "HESA4": 0.6}, seed=11)
    d = diagnose(obs)
    first, *rest = d.findings
    assert first.effect == "az_track_2a" and first.step.heldout is None
    kept = [f for f in rest if f.step.heldout is not None]
    assert [f.result.candidate.label(f.result.theta) for f in kept] == ["el_periodic_az[4]"]
    assert len(d.findings) <= 4 and "kept by cross-validation" in d.text()
    for f in kept:
        before, after = f.step.heldout
        assert after < before
        assert f.step.separation.r <= 0.95  # the stage adds nothing the model mimics
    assert d.summary["cv_sky_rms_after_arcsec"] < d.summary["cv_sky_rms_before_arcsec"]
    # the same data with the noise known (as a scenario's simulations predict it): only the
    # significance tests decide
    n = obs.n
    known = Prediction("simulated", np.zeros(n), np.zeros(n), np.ones(n), np.ones(n))
    k = diagnose(replace(obs, kind="ecsv"), prediction=known)
    assert all(f.step.heldout is None for f in k.findings)


def test_the_step_scans_look_elsewhere_bound_holds():
    """The step's null distribution: the largest chi^2 decrease over every change time of
    either axis. The tube formula's bound (Davies 1987) against 20,000 draws of white noise
    through the projected step columns of 120 scans: never below the Monte Carlo tail (a
    bound), and within a factor 3 of it (not uselessly loose; measured 1.3-1.9). The Monte
    Carlo's own error at these tails is 3-8%."""
    from antsim.diagnose.candidates.changes import curve_length, tube_trials
    from antsim.diagnose.candidates.library import candidate as named
    from antsim.diagnose.problem import Prediction, Problem
    from antsim.diagnose.pvalues import chi2_sf

    n = 120
    rng = np.random.default_rng(21)
    obs = Observations(t_s=np.sort(rng.uniform(0.0, 86400.0, n)), az_rad=rng.uniform(0, 6.28, n),
                       el_rad=np.radians(rng.uniform(15.0, 85.0, n)), xel_arcsec=np.zeros(n),
                       el_arcsec=np.zeros(n), good=np.ones(n, bool),
                       meta={"latitude_deg": 38.43})
    ones = np.ones(n)
    problem = Problem(obs, Prediction("simulated", 0 * ones, 0 * ones, ones, ones),
                      ["IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX"])
    step = named("step")
    xp = problem.projector()(step._all_columns(obs))
    u = xp / np.linalg.norm(xp, axis=0)
    length = curve_length(xp, split=xp.shape[1] // 2)
    draws = rng.standard_normal((2 * n, 20000))
    largest = ((u.T @ draws) ** 2).max(axis=0)
    for level in (9.0, 12.0, 16.0):
        tail = float(np.mean(largest > level))
        bound = chi2_sf(level, 1) * tube_trials(level, length, ends=2)
        assert tail <= bound <= 3.0 * tail, (level, tail, bound)


def test_the_steps_running_sums_are_its_projected_columns(monkeypatch):
    """Two code paths of the step test: running sums over the scans in time order (white
    noise, any number of scans) and the projected step columns themselves. On 150 scans out
    of time order, some unused, each with its own noise and offset scale, with a step of 40"
    in elevation, they agree to float rounding: the sums subtract the model's projection
    from the columns' norms (|c|^2 - |Q'c|^2), which loses digits in proportion to
    |c|^2 / |xp|^2 (at most 1e9 for a kept column: relative 1e-6 at worst, 1e-9 here)."""
    from antsim.diagnose.candidates.library import candidate as named
    from antsim.diagnose.problem import Prediction, Problem

    n = 150
    rng = np.random.default_rng(7)
    t = rng.permutation(np.linspace(0.0, 5 * 86400.0, n))
    el = np.radians(rng.uniform(15.0, 85.0, n))
    obs = Observations(t_s=t, az_rad=rng.uniform(0, 6.28, n), el_rad=el,
                       xel_arcsec=rng.normal(0.0, 5.0, n),
                       el_arcsec=rng.normal(0.0, 5.0, n) + 40.0 * (t > 2.2 * 86400.0),
                       good=rng.random(n) > 0.1, meta={"latitude_deg": 38.43})
    problem = Problem(obs, Prediction("white", np.zeros(n), np.zeros(n),
                                      rng.uniform(3.0, 8.0, n), rng.uniform(3.0, 8.0, n)),
                      ["IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX"],
                      offset_scale=rng.uniform(0.7, 1.0, n))
    step = named("step")
    perp, z_perp = problem.perp_for(problem.used)
    assert problem.white()
    summed = step._all_stats(problem, perp, z_perp)
    fast = step.test(problem, perp, z_perp, float(z_perp @ z_perp))
    monkeypatch.setattr(problem, "white", lambda used=None: False)
    dense = step._all_stats(problem, perp, z_perp)
    slow = step.test(problem, perp, z_perp, float(z_perp @ z_perp))
    m2 = dense[1].size
    np.testing.assert_allclose(summed[0], dense[0], rtol=1e-9, atol=1e-9 * np.abs(dense[0]).max())
    np.testing.assert_allclose(summed[1], dense[1], rtol=1e-9, atol=1e-9 * dense[1].max())
    a = np.concatenate([np.arange(m2 // 2 - 1), np.arange(m2 // 2, m2 - 1)])  # one axis
    b = a + 1  # neighbours of one axis (a pair across the axes is never asked for)
    np.testing.assert_allclose(summed[2](a, b), dense[2](a, b), rtol=1e-9,
                               atol=1e-9 * dense[1].max())
    assert fast.theta == slow.theta and fast.theta[0] == "el"
    assert abs(fast.theta[1] - 2.2 * 86400.0) < 86400.0 / n * 3  # found where it was put
    assert fast.trials == pytest.approx(slow.trials, rel=1e-9)
    # the cross-validated stage compares each axis' most likely change time only
    assert fast.theta[:2] in step.cv_thetas(problem)
    # a run of consecutive columns is read as a view: the same bits as the gathered rows
    from antsim.diagnose.candidates.changes import _as_slice, _rows_dot
    run = np.arange(3, m2 // 2 - 1)
    assert _as_slice(run) == slice(3, m2 // 2 - 1)
    assert _as_slice(a) is a  # two runs: gathered
    sq, qc = np.arange(m2, dtype=float) ** 2, np.linspace(-1.0, 1.0, m2 * 3).reshape(m2, 3)
    gathered = sq[run + 1] - np.einsum("ij,ij->i", qc[run], qc[run + 1])
    # bit-equal here; rounding's tolerance, should another CPU's einsum sum a view that
    # starts off its alignment in another order
    np.testing.assert_allclose(_rows_dot(sq, qc, _as_slice(run), _as_slice(run + 1)),
                               gathered, rtol=1e-14, atol=1e-14 * np.abs(gathered).max())
    assert fast.delta_chi2 == pytest.approx(slow.delta_chi2, rel=1e-12)


def test_the_transient_after_sunset_and_the_step_effect():
    """A transient is 1 at each sunset and falls by e per time constant; before the first
    sunset of the grid it is 0; the relaxation is the lag of the night indicator. A step is
    0 before its time and its two offsets after, for one instant or a block with a member
    axis."""
    from antsim.world.effects.base import PointingState
    from antsim.world.effects.steps import Step
    from antsim.world.effects.thermal import (
        relax,
        since_sunset,
        sunset_level,
        transient_level,
    )

    night = np.r_[np.zeros(100), np.ones(300), np.zeros(200), np.ones(100)]
    transient = sunset_level(night, 60.0, 600.0, "transient")
    assert np.all(transient[:100] == 0.0) and transient[100] == 1.0
    assert transient[110] == pytest.approx(math.exp(-1.0), rel=1e-12)
    assert transient[600] == 1.0  # the next sunset starts it again
    # from the steps since sunset kept for every tau (the diagnose candidate's way): the
    # bytes of the direct formula
    idx = np.arange(night.size)
    sets = np.r_[False, (night[1:] > 0.5) & (night[:-1] < 0.5)]
    last = np.maximum.accumulate(np.where(sets, idx, -1))
    steps = since_sunset(night)
    for tau_s in (600.0, 1234.567, 10800.0):
        direct = np.where(last >= 0, np.exp(-(idx - last) * 60.0 / tau_s), 0.0)
        assert transient_level(steps, 60.0, tau_s).tobytes() == direct.tobytes()
    # a grid's length (SIMD loops and their tails) and steps of up to two years: the bytes of
    # the expression transient_level computed in place
    many = np.random.default_rng(5).integers(-1, 1_000_000, 100_003).astype(np.int32)
    for tau_s in (600.0, 1234.567, 10800.0):
        direct = np.where(many >= 0, np.exp(-many * 60.0 / tau_s), 0.0)
        assert transient_level(many, 60.0, tau_s).tobytes() == direct.tobytes()
    np.testing.assert_array_equal(sunset_level(night, 60.0, 600.0),
                                  relax(night, 60.0, 600.0, 0.0))
    with pytest.raises(ValueError, match="shape"):
        sunset_level(night, 60.0, 600.0, "spike")
    eff = Step(t_s=100.0, az_arcsec=20.0, el_arcsec=-30.0)
    assert eff.pointing_error(PointingState(t_s=99.0, az_rad=1.0, el_rad=0.5)) == (0.0, 0.0)
    d_az, d_el = eff.pointing_error(PointingState(t_s=100.0, az_rad=1.0, el_rad=0.5))
    assert (d_az, d_el) == pytest.approx((20.0 * RAD_PER_ARCSEC, -30.0 * RAD_PER_ARCSEC))
    block = PointingState(t_s=np.array([[50.0], [150.0]]), az_rad=np.zeros((2, 3)),
                          el_rad=np.full((2, 3), 0.5))
    b_az, b_el = eff.block_error(block)
    assert np.broadcast_shapes(np.shape(b_el), (2, 3)) == (2, 3)
    assert np.all(np.asarray(b_el)[0] == 0.0) and np.all(np.asarray(b_el)[1] == d_el)
    assert np.all(np.asarray(b_az)[0] == 0.0) and np.all(np.asarray(b_az)[1] == d_az)


# ------------------------------------------------------------------------------ command line
def test_diagnose_command_on_tpoint_data_json(tmp_path, capsys):
    from controller.pointing.tpoint import RunParameters, TPointData, write_tpoint

    obs = synthetic(extra={"HASA2": 1.5}, seed=7)
    az_raw = np.degrees(obs.az_rad + np.radians(obs.xel_arcsec / 3600.0) / np.cos(obs.el_rad))
    el_raw = np.degrees(obs.el_rad) + obs.el_arcsec / 3600.0
    data = TPointData.from_azel("synthetic", RunParameters(38.43), np.degrees(obs.az_rad),
                                np.degrees(obs.el_rad), az_raw, el_raw)
    path = tmp_path / "syn.dat"
    write_tpoint(data, path)
    assert cli(["diagnose", str(path), "--json", "--out", str(tmp_path / "out")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["findings"][0]["effect"] == "az_runout_2a"
    assert (tmp_path / "out" / "model_updated.dat").exists()
    assert (tmp_path / "out" / "diagnose.json").exists()
    assert (tmp_path / "out" / "report.html").exists()


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert cli(["diagnose", str(tmp_path / "missing.ecsv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no such file" in err[0]
    assert cli(["diagnose", str(tmp_path / "missing.ecsv"), "--sims", "1"]) == 2
    assert cli(["blindtest", "--n", "0"]) == 2
    assert "--n" in capsys.readouterr().err


def test_list_prints_the_library(capsys):
    assert cli(["diagnose", "--list"]) == 0  # as the docs write it: no recordings needed
    out = capsys.readouterr().out
    assert "az_track_2a [HESA2 HECA2]" in out and "sunset_drift" in out
    assert cli(["diagnose", "x", "--list"]) == 0
    assert cli(["diagnose"]) == 2  # without --list the recordings are required, in one line
    err = capsys.readouterr().err
    assert "RECORDINGS" in err and "--list" in err and len(err.strip().splitlines()) == 1


# ------------------------------------------------------------------------------ real data
def test_auxtel_stays_parsimonious_and_reports_the_degeneracy():
    d = diagnose(load_observations(REAL / "auxtel_20200315.dat"))
    assert d.baseline.terms == ("IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX")
    assert len(d.findings) <= 4
    text = d.text()
    assert "cannot reliably be distinguished" in text
    assert any("TF" in w and "TX" in w for w in d.degeneracies()), d.degeneracies()
    s = d.summary
    assert s["cv_sky_rms_after_arcsec"] < s["cv_sky_rms_before_arcsec"]
    # the data's README: a good selector keeps no term whose size is set by a near-degenerate
    # partner; what prediction alone keeps is never one the model mimics
    kept = [f for f in d.findings if f.step.heldout is not None]
    assert all(f.step.separation.r <= 0.95 for f in kept)
    # docs/diagnose.md quotes the findings as the command prints them
    readme = (Path(__file__).resolve().parents[3] / "docs" / "diagnose.md").read_text(
        encoding="utf-8")
    headlines = [line for line in text.splitlines() if line[:3] in ("1. ", "2. ", "3. ", "4. ")]
    assert len(headlines) == len(d.findings)
    for line in headlines:
        assert f"    {line}\n" in readme, line


def test_auxtel_procedure_predicts_held_out_stars():
    """Diagnose as a procedure, its selection repeated inside each fold (11 folds of 4 stars
    here; every star alone in benchmarks/blind.py --real --nested: 10.37" against 11.11"
    for an automatic 22-term search and 20.16" for the eight terms): at most 4 findings in
    every fold, and the held-out Sky RMS well below the eight terms' (measured 12.7" against
    20.1", a ratio of 0.63; 0.75 would still be 3.7" better, the first finding's worth)."""
    from antsim.diagnose.linalg import lstsq

    obs = load_observations(REAL / "auxtel_20200315.dat")
    y = np.concatenate([obs.xel_arcsec, obs.el_arcsec])
    folds = np.arange(obs.n) % 11
    sq = {"diagnose": 0.0, "eight": 0.0}
    for k in range(11):
        train = folds != k
        d = diagnose(obs.select(train))
        assert len(d.findings) <= 4
        for key, names in (("diagnose", d.updated_model().names), ("eight", d.baseline.terms)):
            x = term_columns(list(names), obs)
            rows = np.concatenate([train, train])
            coef, _ = lstsq(x[rows], y[rows])
            r = (y - x @ coef).reshape(2, -1)[:, ~train]
            sq[key] += float(np.sum(r**2))
    held = {key: math.sqrt(v / obs.n) for key, v in sq.items()}
    assert held["diagnose"] < 0.75 * held["eight"], held


def test_mmt_needs_at_most_a_small_addition():
    """By significance at most one marginal pair; the cross-validated stage may add terms
    that predict held-out stars better, each said to be kept by cross-validation."""
    d = diagnose(load_observations(REAL / "mmt_20210821_k_and_e.dat"))
    assert sum(f.step.heldout is None for f in d.findings) <= 1
    assert len(d.findings) <= 4
    for f in d.findings[1:]:
        assert f.step.heldout is not None and f.step.heldout[1] < f.step.heldout[0]
        assert "kept by cross-validation" in d.text()
    s = d.summary
    assert s["sky_rms_before_arcsec"] == pytest.approx(0.9318, abs=0.002)
    assert s["cv_sky_rms_after_arcsec"] <= s["cv_sky_rms_before_arcsec"] + 1e-9


def _short_run(tmp_path: Path, scenario: str) -> tuple[Path, Path]:
    """A 3-hour run of one of the repository's scenarios: (scenario file, recordings)."""
    root = Path(__file__).resolve().parents[3]
    text = re.sub(r"(?m)^duration_h = [0-9.]+$", "duration_h = 3.0",
                  (root / "scenarios" / scenario).read_text())
    path = tmp_path / scenario
    path.write_text(text)
    out = tmp_path / "run"
    assert cli(["run", str(path), "--out", str(out), "--no-report"]) == 0
    return path, out / "recordings.ecsv"


def test_equatorial_recordings_are_diagnosed_on_their_axes(tmp_path, capsys):
    """An equatorial mount's recordings (the 140-ft's) are read in hour angle and
    declination with the model in their metadata (Crane's C1..C11); a mount diagnose does
    not know is refused in one line."""
    _, recordings = _short_run(tmp_path, "crane1981_140ft_3245.toml")
    capsys.readouterr()
    assert cli(["diagnose", str(recordings), "--out", str(tmp_path / "diag")]) == 0
    out = capsys.readouterr().out
    assert "baseline C1 C2 C3 C4 C5 C6 C7 C8 C9 C10 C11" in out and "RA/Dec rms" in out
    assert "cross-declination" in out and "azimuth" not in out.split("\nwrote ")[0]
    # the figure against the mount's own axes, on the report page
    page = (tmp_path / "diag" / "report.html").read_text()
    assert 'data-file="diagnose_residuals.png"' in page and "RA/Dec rms in-sample" in page
    bad = tmp_path / "gimbal.ecsv"
    bad.write_text(recordings.read_text().replace("mount: equatorial", "mount: gimbal"))
    assert cli(["diagnose", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "mount = 'gimbal'" in err and "altaz, equatorial" in err


def test_feed_angle_terms_in_the_baseline_are_refused_in_one_line(tmp_path, capsys):
    scenario, recordings = _short_run(tmp_path, "fomalont1973_x.toml")
    capsys.readouterr()
    assert cli(["diagnose", str(recordings), "--scenario", str(scenario), "--sims", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "HSCF HSSF HECF HESF" in err and "--model ghigo10" in err


def test_a_failed_quiet_run_process_falls_back_to_this_one(tmp_path, monkeypatch):
    """When the second process fails, the baseline warns and runs the quiet campaign and
    the members here: the same columns as without the second process."""
    from antsim.diagnose.fastsim import shared_schedule_columns
    from antsim.scenario import load_scenario

    root = Path(__file__).resolve().parents[3]
    path = tmp_path / "two_hours.toml"
    path.write_text((root / "scenarios" / "ghigo1990.toml").read_text()
                    .replace("duration_h = 24.0", "duration_h = 2.0"))
    scenario = load_scenario(path)
    here = shared_schedule_columns(scenario, [11], jobs=1)

    def broken(stream, scenario, seeds):
        raise RuntimeError("the quiet run's process failed: test")

    monkeypatch.setattr("antsim.simulate.streaming.stream_members", broken)
    monkeypatch.setattr("antsim.simulate.streaming.stream_available", lambda jobs: True)
    with pytest.warns(RuntimeWarning, match="baseline's members in this process"):
        fallback = shared_schedule_columns(scenario, [11], jobs=2)
    assert set(fallback) == {11} and len(here[11]["t_s"]) > 10
    for name, values in here[11].items():
        np.testing.assert_array_equal(fallback[11][name], values, err_msg=name)
    monkeypatch.undo()
    streamed = shared_schedule_columns(scenario, [11], jobs=2)  # two cores: the stream
    for name, values in here[11].items():
        np.testing.assert_array_equal(streamed[11][name], values, err_msg=name)


def test_shared_schedule_baseline_is_the_full_simulation(tmp_path):
    """The baseline's vectorized simulations (one shared schedule, antsim.plan's engine) give
    each seed's scans as a full simulation of that seed does: same scans, same times to a
    few ms, offsets within 0.2" rms (measured 0.03": the weather's wander moves a full run's
    refraction and timing slightly) against a scatter of ~50"."""
    from antsim.diagnose.fastsim import shared_schedule_columns
    from antsim.scenario import load_scenario
    from antsim.simulate.runner import simulate

    root = Path(__file__).resolve().parents[3]
    path = tmp_path / "four_hours.toml"
    path.write_text((root / "scenarios" / "ghigo1990.toml").read_text()
                    .replace("duration_h = 24.0", "duration_h = 4.0"))
    scenario = load_scenario(path)
    fast = shared_schedule_columns(scenario, [11, 12])
    assert set(fast) == {11, 12}
    streamed = shared_schedule_columns(scenario, [11, 12], jobs=2)  # members in a 2nd process
    for seed in (11, 12):
        for name, values in fast[seed].items():
            np.testing.assert_array_equal(streamed[seed][name], values, err_msg=name)
    for seed in (11, 12):
        rows = simulate(scenario, seed).rows
        for pol in ("XR", "XL", "AVG"):
            full = [r for r in rows if r["polarization"] == pol]
            mine = fast[seed]["polarization"] == pol
            assert len(full) == int(mine.sum()) > 30
            dt = np.array([r["t_s"] for r in full]) - fast[seed]["t_s"][mine]
            assert np.abs(dt).max() < 0.01
            for axis in ("xel", "el"):
                diff = np.array([r[f"{axis}_arcmin"] for r in full]) \
                    - fast[seed][f"{axis}_arcmin"][mine]
                assert 60.0 * np.sqrt(np.mean(diff**2)) < 0.2, (seed, pol, axis)


def test_offset_scale_follows_the_width_the_reduction_assumed():
    """The fraction of a pointing error a scan's measured offset shows is
    assumed^2 / (beam^2 + size^2): 1 for every source when the controller reduces with the
    catalogued sizes, 0.91 for Cas A (3.46') with the bare 11' beam, from the scenario or
    from the widths the recordings measured and the widths they say were assumed."""
    from dataclasses import replace

    from antsim.diagnose.baseline import offset_scale
    from antsim.scenario import load_scenario

    scenario = load_scenario(Path(__file__).resolve().parents[3] / "scenarios" / "ghigo1990.toml")
    names = np.array(["3C84", "Cassiopeia A", "W31"] * 4)
    n = names.size
    width = np.array([11.0, math.hypot(11.0, 3.46), math.hypot(11.0, 4.0)] * 4)
    obs = Observations(t_s=np.arange(n, dtype=float), az_rad=np.zeros(n),
                       el_rad=np.full(n, 0.5), xel_arcsec=np.zeros(n), el_arcsec=np.zeros(n),
                       good=np.ones(n, bool), source=names, width_xel_arcmin=width,
                       width_el_arcmin=width, meta={"beam_hpbw_arcmin": 11.0})
    bare = 121.0 / (121.0 + np.array([0.0, 3.46**2, 16.0] * 4))
    assert scenario.controller.scan.use_source_size
    np.testing.assert_allclose(offset_scale(obs, scenario), 1.0, rtol=1e-12)
    beam_only = replace(scenario, controller=replace(scenario.controller, scan=replace(
        scenario.controller.scan, use_source_size=False)))
    np.testing.assert_allclose(offset_scale(obs, beam_only), bare, rtol=1e-12)
    np.testing.assert_allclose(offset_scale(obs), bare, rtol=1e-12)
    assumed = {"3C84": 11.0, "Cassiopeia A": width[1], "W31": width[2]}
    told = replace(obs, meta={**obs.meta, "reduction_width_arcmin": assumed})
    np.testing.assert_allclose(offset_scale(told), 1.0, rtol=1e-12)


def _scans_with_unused_and_scaled(n: int = 150):
    """A small problem: scans some unused, each with its own noise and offset scale, a 30"
    sin 2A elevation error, the eight 1990 terms as the model (outliers rejected)."""
    from antsim.diagnose.problem import Prediction, Problem

    rng = np.random.default_rng(28)
    t = np.sort(rng.uniform(0.0, 6 * 86400.0, n))
    az = rng.uniform(0, 6.28, n)
    obs = Observations(t_s=t, az_rad=az, el_rad=np.radians(rng.uniform(15.0, 85.0, n)),
                       xel_arcsec=rng.normal(0.0, 5.0, n) * (1 + 9 * (rng.random(n) < 0.03)),
                       el_arcsec=rng.normal(0.0, 5.0, n) + 30.0 * np.sin(2 * az),
                       good=rng.random(n) > 0.1, meta={"latitude_deg": 38.43})
    problem = Problem(obs, Prediction("white", np.zeros(n), np.zeros(n),
                                      rng.uniform(3.0, 8.0, n), rng.uniform(3.0, 8.0, n)),
                      ["IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX"],
                      offset_scale=rng.uniform(0.7, 1.0, n))
    problem.update_outliers()
    return problem


@pytest.mark.parametrize("scaled", [True, False])
def test_a_candidates_test_is_the_projection_it_states(scaled):
    """Two code paths: a candidate's test (:meth:`Candidate.linear_test`: it reuses its outlier
    mask's last added-columns fit, whitens the raw columns once where the offset scale is 1,
    and keeps no columns but makes them again when read) against the computation in its
    definition (the mask, the cached projector over it, the columns projected and fitted by
    SVD). The same numbers in another order: 1e-9 relative (the design's condition number
    is 60, rounding is ~1e-14); the masks and the columns identical. A result's columns made
    from another shape than the tested one are refused when read, not returned."""
    from antsim.diagnose.candidates.base import ABSORBED_1MR2, nyholt_trials
    from antsim.diagnose.linalg import lstsq

    problem = _scans_with_unused_and_scaled()
    if not scaled:
        problem.offset_scale = np.ones(problem.n)
    assert problem.unscaled is not scaled
    for c, theta in ((candidate("az_track_2a"), None), (candidate("el_periodic_az"), 3),
                     (candidate("refraction"), None)):
        raw, names = c.columns(problem.obs, theta)
        res = c.linear_test(problem, None, None, raw, names, theta)
        cols = problem.cand(raw)
        mask = problem.mask_for(cols)
        perp, z_perp = problem.perp_for(mask)
        full = np.linalg.norm(problem.whiten(raw, mask), axis=0)
        left = np.linalg.norm(perp(raw), axis=0)
        keep = (left / full) ** 2 > ABSORBED_1MR2
        if not keep.any():  # refraction: TX, in the model already
            assert res.dof == 0 and res.absorbed == names and np.array_equal(res.columns, cols)
            continue
        coef, cov = lstsq(perp(cols)[:, keep], z_perp)
        fitted = perp(cols)[:, keep] @ coef
        assert np.array_equal(res.mask, mask) and res.comp_names == tuple(
            n for n, k in zip(names, keep, strict=True) if k)
        assert res.delta_chi2 == pytest.approx(float(fitted @ fitted), rel=1e-9)
        np.testing.assert_allclose(res.coef, coef, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.cov, cov, rtol=1e-9, atol=1e-12)
        assert res.chi2_now == pytest.approx(float(z_perp @ z_perp), rel=1e-9)
        assert res._columns is None and np.array_equal(res.columns, cols[:, keep])
    other, names = candidate("el_periodic_az").columns(problem.obs, 4)
    res = candidate("el_periodic_az").linear_test(problem, None, None, other, names, 3)
    with pytest.raises(RuntimeError, match="not the tested ones"):
        _ = res.columns
    res.columns = other  # set: held as given
    assert res.columns is other
    grid = np.random.default_rng(1).normal(size=(300, 6))
    assert nyholt_trials(grid.copy(), overwrite=True) == nyholt_trials(grid)


@pytest.mark.parametrize("scaled", [True, False])
def test_a_shape_test_from_inner_products_is_the_explicit_one(scaled):
    """Two code paths: a shape's test from inner products with the model's cached basis over
    its used scans (:func:`shape_fit`: one pass over it, the other scan sets the
    outlier mask tries by row corrections, the mask from a bound on what the rest of the
    fit changes) against the explicit projections it replaces (:meth:`_linear_explicit`,
    today's reference). 150 scans, some unused, noise and offset scale per scan, a 30"
    sin 2A elevation error the model leaves out, so that az_track_2a takes back scans the
    model rejects (the row corrections serve). The same least-squares problems in another
    order: 1e-9 relative (the design's condition number is 60 and every column kept is far
    from the model's span, 1 - R^2 > 1e-3, so the Gram's rounding is ~1e-13); the masks,
    kept and absorbed columns identical. The trials of a grid of 1-column shapes from its
    Gram against Nyholt's count of the projected columns: 1e-9 relative, also where one
    shape is in the model's span (the grid is then projected) or came projected."""
    import scipy.linalg

    from antsim.diagnose.candidates.base import _grid_trials, nyholt_trials

    problem = _scans_with_unused_and_scaled()
    if not scaled:
        problem.offset_scale = np.ones(problem.n)
    obs = problem.obs
    served, checked = [], []
    shapes = [(candidate("az_track_2a"), None), (candidate("el_periodic_az"), 3),
              (candidate("el_periodic_az"), 5), (candidate("refraction"), None)]
    for c, theta in shapes:
        raw, names = c.columns(obs, theta)
        fast = c._linear_xp(problem, raw, names, theta)[0]
        ref = c._linear_explicit(problem, raw, problem.cand(raw), names, theta)[0]
        served.append(shape_fit(problem, raw) is not None)
        assert fast.dof == 0 or np.array_equal(fast.columns, ref.columns)
        checked.append((fast, ref))
    # columns that take back the scans the model rejects (each one's error, plus a shape
    # over every scan): the row corrections serve
    out = np.flatnonzero(problem.valid & ~problem.used)
    raw = np.zeros((2 * obs.n, out.size))
    raw[out, np.arange(out.size)] = problem.y[out]
    raw[obs.n:] = 0.1 * np.sin(np.outer(obs.az_rad, np.arange(1, out.size + 1)))
    names = tuple(f"s{i}" for i in range(out.size))
    c = candidate("az_track_2a")
    fast = c._linear_xp(problem, raw, names, None)[0]
    ref = c._linear_explicit(problem, raw, problem.cand(raw), names, None)[0]
    assert out.size == 2 and fast.mask[out].all()
    served.append(shape_fit(problem, raw) is not None)
    checked.append((fast, ref))
    for fast, ref in checked:
        assert np.array_equal(fast.mask, ref.mask) and fast.dof == ref.dof
        assert (fast.comp_names, fast.absorbed) == (ref.comp_names, ref.absorbed)
        assert fast.delta_chi2 == pytest.approx(ref.delta_chi2, rel=1e-9, abs=1e-9)
        np.testing.assert_allclose(fast.coef, ref.coef, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(fast.cov, ref.cov, rtol=1e-9, atol=1e-12)
        if fast.dof:
            assert fast.chi2_now == pytest.approx(ref.chi2_now, rel=1e-9)
            assert fast.r_model == pytest.approx(ref.r_model, rel=1e-9, abs=1e-12)
    assert all(served) and checked[3][0].dof == 0  # refraction: TX is in the model
    # the partners' inputs: the columns' coefficients on the model over the mask (here
    # not the model's scans) and the model's whitened column norms there, against its
    # factor over those scans
    r = problem.factors.qr(problem.used).r
    on_model, gram = fast._on_model
    x = problem.whiten(problem.cand(raw), fast.mask)
    np.testing.assert_allclose(scipy.linalg.solve_triangular(r, on_model),
                               problem.coef_on_current(x, fast.mask), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.sqrt(np.diag(r.T @ gram @ r)),
                               problem.current_norms(fast.mask), rtol=1e-9)
    az, el = obs.az_rad, obs.el_rad
    cols = [np.concatenate([np.zeros(obs.n), np.sin(n * az + 0.3 * n)]) for n in range(1, 6)]
    cols += [term_columns(("TX",), obs)[:, 0]]  # in the model's span
    q = problem.basis()
    perp, _ = problem.perp_for(problem.used)
    near = cols[5] + 1e-3 * np.std(cols[5]) / np.std(cols[0]) * cols[0]  # 1 - R^2 ~ 1e-6
    xn = problem.whiten(near[:, None])
    assert 1e-8 < float(np.sum(perp(near[:, None]) ** 2) / np.sum(xn**2)) < 1e-5
    ref = nyholt_trials(perp(np.column_stack(cols[:5])))
    for shapes_now in (cols[:5], cols, [*cols[:5], near]):
        x = problem.whiten(np.column_stack(shapes_now))
        grid, qgrid = x.copy(), [q.T @ x[:, i] for i in range(x.shape[1])]
        grid[:, 1], qgrid[1] = perp(shapes_now[1][:, None])[:, 0], None  # came projected
        # the shape in the model's span (rounding off it) is no trial
        want = nyholt_trials(perp(np.column_stack(shapes_now))) if len(
            shapes_now) == 6 and shapes_now[5] is near else ref
        assert _grid_trials(problem, grid, qgrid) == pytest.approx(want, rel=1e-9)
    assert 1.0 < ref < 5.0 and np.cos(el).size  # correlated shapes: fewer than 5 trials


def test_a_partly_absorbed_signature_is_fitted_on_the_columns_the_model_leaves():
    """A signature one of whose columns is in the model's span (TX beside az_track_2a's sin
    2A and cos 2A, offset scale 1: what an accepted term leaves of a signature) is tested
    from inner products (:func:`shape_fit`; the explicit path served it before), its
    outlier mask fitted on the columns the model leaves a part of (the explicit path fitted
    the in-span column's rounding-level remainder too). Against the explicit path on those
    columns and on all of them: the same mask, kept and absorbed columns, and numbers to
    1e-9 relative (as the test above: the design's condition number is 60, the kept columns
    far from the span, 1 - R^2 > 1e-3)."""
    problem = _scans_with_unused_and_scaled()
    problem.offset_scale = np.ones(problem.n)
    obs = problem.obs
    c = candidate("az_track_2a")
    two_a, names2 = c.columns(obs, None)
    raw = np.column_stack([term_columns(("TX",), obs), two_a])
    names = ("TX", *names2)
    assert shape_fit(problem, raw) is not None
    fast = c._linear_xp(problem, raw, names, None)[0]
    assert fast.absorbed == ("TX",) and fast.comp_names == names2 and fast.dof == len(names2)
    for ref in (c._linear_explicit(problem, two_a, two_a, names2, None)[0],
                c._linear_explicit(problem, raw, raw, names, None)[0]):
        assert np.array_equal(fast.mask, ref.mask) and fast.comp_names == ref.comp_names
        assert fast.delta_chi2 == pytest.approx(ref.delta_chi2, rel=1e-9)
        np.testing.assert_allclose(fast.coef, ref.coef, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(fast.cov, ref.cov, rtol=1e-9, atol=1e-12)
        assert fast.chi2_now == pytest.approx(ref.chi2_now, rel=1e-9)
        assert fast.r_model == pytest.approx(ref.r_model, rel=1e-9, abs=1e-12)


def test_the_added_columns_fit_and_the_closed_form_held_out_fits_are_the_refits():
    """Two code paths each: the current model plus a candidate's columns fitted by
    Frisch-Waugh-Lovell on the model's cached QR (:meth:`Problem.fit_added`) against one
    least-squares fit of the whole design (SVD), and each fold predicted by the closed
    leave-group-out form (:func:`heldout_lstsq`) against refitting without it (also where a
    fold is a tenth of the data). 150 scans, some unused, each with its own noise and offset
    scale. They are the same projections computed in another order, so they agree to float
    rounding: 1e-9 relative (measured: coefficients 4e-13, residuals and held-out residuals
    1e-14 at most; the whitened design's condition number is 60, so rounding stays far below
    1e-9 on any machine's BLAS), and the outlier masks the two fits give are identical."""
    from antsim.diagnose.crossval import heldout_losses
    from antsim.diagnose.linalg import added_basis, economic_qr, heldout_lstsq, lstsq

    n = 150
    problem = _scans_with_unused_and_scaled(n)
    az = problem.obs.az_rad
    rng = np.random.default_rng(29)
    extra = problem.cand(np.concatenate([np.zeros((n, 2)),
                                         np.column_stack([np.sin(2 * az), np.cos(2 * az)])]))
    whole = np.column_stack([problem.current_columns(), extra])
    for used in (problem.used, problem.valid):
        fast, slow = problem.fit_added(extra, used), problem.fit(whole, used)
        np.testing.assert_allclose(fast.coef, slow.coef, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(fast.resid, slow.resid, rtol=1e-9, atol=1e-9)
        assert fast.chi2 == pytest.approx(slow.chi2, rel=1e-9)
        np.testing.assert_allclose(fast.cov, slow.cov[-2:, -2:], rtol=1e-9, atol=1e-12)
    mask = problem.mask_for(extra)
    old = problem.valid.copy()  # the mask as the whole design's fits give it
    for _ in range(2):
        r = np.abs(problem.fit(whole, old).resid)
        keep = problem.valid & (r[:n] <= 4.0) & (r[n:] <= 4.0)
        if np.array_equal(keep, old):
            break
        old = keep
    assert np.array_equal(mask, old) and 0 < (problem.valid & ~mask).sum() < 10

    x, z = rng.normal(size=(300, 6)), rng.normal(size=300)
    for groups in (10, 75):
        labels = rng.integers(0, groups, 300)
        closed = heldout_lstsq(x, z, labels)
        refit = np.empty(300)
        for k in np.unique(labels):
            coef, _ = lstsq(x[labels != k], z[labels != k])
            refit[labels == k] = (z - x @ coef)[labels == k]
        np.testing.assert_allclose(closed, refit, rtol=1e-9, atol=1e-12)
    assert heldout_lstsq(x, z, np.zeros(300, int)) is None  # nothing left to fit on
    folds = (np.arange(n) * 5) // n
    losses = heldout_losses(whole, problem.y_raw, problem.used, folds)
    rows = problem.rows(problem.used)
    ref = []
    for k in range(5):
        train, test = problem.used & (folds != k), problem.used & (folds == k)
        coef, _ = lstsq(whole[np.concatenate([train, train])],
                         problem.y_raw[np.concatenate([train, train])])
        ref.append(((problem.y_raw - whole @ coef).reshape(2, n) ** 2).sum(axis=0)[test])
    np.testing.assert_allclose(losses, np.concatenate(ref), rtol=1e-9)
    assert rows.sum() == 2 * losses.size
    # the cross-validated stage's path: the model's basis plus the option's columns
    q0, r0 = economic_qr(problem.current_columns()[rows])
    blocks, d1 = added_basis(q0, extra[rows])
    q = np.hstack(blocks)
    np.testing.assert_allclose(q.T @ q, np.eye(q.shape[1]), atol=1e-12)
    d = np.concatenate([np.abs(np.diag(r0)), d1])
    for basis in (blocks, q):  # in blocks (what the stage passes) and stacked
        via = heldout_losses(whole, problem.y_raw, problem.used, folds, (basis, d))
        np.testing.assert_allclose(via, losses, rtol=1e-9)
    assert problem.cv_chi2(whole, folds) == pytest.approx(
        sum(float(np.sum(problem.whiten(problem.y - whole @ problem.fit(whole, problem.used
            & (folds != k)).coef, problem.used & (folds == k)) ** 2)) for k in range(5)),
        rel=1e-9)


def test_the_cross_validated_stage_makes_its_options_parameters_before_its_basis(monkeypatch):
    """Each round of the cross-validated stage asks every option for its parameters (a
    step's change time: O(n k) sums over every scan) before it factors the model's
    unweighted basis over the used rows, so that the two are never held together (200,000
    scans: ~40 MB each at the command's peak, benchmarks/diagnose_scale.py); the data of the
    test above, where the stage adds a finding and tries again."""
    import antsim.diagnose.crossval as crossval
    from antsim.diagnose.candidates.base import Candidate

    calls = []
    qr = crossval.economic_qr

    def logged_qr(*args, **kwargs):
        calls.append("basis")
        return qr(*args, **kwargs)

    def logged(cv_thetas):
        def logged_thetas(self, problem):
            calls.append("parameters")
            return cv_thetas(self, problem)
        return logged_thetas

    monkeypatch.setattr(crossval, "economic_qr", logged_qr)
    for cls in {type(c) for c in CANDIDATES} | {Candidate}:
        if "cv_thetas" in vars(cls):
            monkeypatch.setattr(cls, "cv_thetas", logged(vars(cls)["cv_thetas"]))
    obs = synthetic(extra={"HESA2": 2.0, "HECA2": 1.0, "HASA": 0.6, "HACA": -0.6,
                           "HESA4": 0.6}, seed=11)
    diagnose(obs)
    rounds = "".join("b" if c == "basis" else "p" for c in calls)
    assert rounds.count("b") >= 2  # a finding added, then another round
    assert re.fullmatch(r"(p+b)+", rounds), rounds


def test_the_cross_validated_stage_ranks_its_options_as_the_held_out_losses_do(monkeypatch):
    """Two code paths of the cross-validated stage's choice: the options' summed held-out
    losses from per-fold Gram matrices (:class:`FoldSums`) against the losses computed in
    full (:func:`heldout_losses`, the reference: every option's, the least sum winning, the
    first of equals). The same projections in another order: 1e-9 relative (measured 1e-15;
    the design's condition number is 60), the choice the same; an option nearly inside the
    model's span (r^2 = 1 - 1e-8) is left to the full losses (None), and of two options with
    the same columns the first is chosen, as the full losses choose it."""
    from antsim.diagnose.crossval import (
        FoldSums,
        Ranked,
        _best,
        _losses,
        contiguous_folds,
        mimicked,
    )
    from antsim.diagnose.linalg import economic_qr, rows_fortran

    problem = _scans_with_unused_and_scaled()
    obs, n = problem.obs, problem.n
    folds = contiguous_folds(obs.t_s, 5)
    cur, rows = problem.current_columns(), problem.rows()
    q0, r0 = economic_qr(rows_fortran(cur, rows))
    d0 = np.abs(np.diag(r0))
    labels = np.concatenate([folds[problem.used]] * 2)
    sums = FoldSums(q0, d0, problem.y_raw[rows], labels, np.flatnonzero(rows))
    options = [(candidate("el_periodic_az"), k) for k in (1, 2, 3, 4)] + [
        (candidate("az_track_2a"), None), (candidate("az_runout_1a"), None)]
    ranked = []
    idx = np.flatnonzero(rows)
    f2 = np.concatenate([problem.offset_scale, problem.offset_scale])
    for c, theta in options:
        raw, names = c.columns(obs, theta)
        total = sums.total(problem.cand(raw))
        # the option's rows gathered once for the mimicry check and the sums (cv_stage):
        # the same products, the same bits
        xg = raw.take(idx, axis=0)
        assert sums.total_rows(xg * f2[idx, None]) == total
        assert mimicked(problem, raw, xg) == mimicked(problem, raw)
        assert np.array_equal(xg * problem.weights()[:, None], problem.whiten(raw))
        losses = _losses(problem, cur, q0, d0, folds, raw)
        assert total == pytest.approx(float(losses.sum()), rel=1e-9)
        # the basis grouped by fold in a copy (scans out of time order) instead of read in
        # place by runs: the same sums in another order, 1e-12 (the 1e-15 above, with room)
        monkeypatch.setattr(FoldSums, "MAX_RUNS", 0)
        grouped = FoldSums(q0, d0, problem.y_raw[rows], labels, np.flatnonzero(rows))
        monkeypatch.undo()
        assert grouped.total(problem.cand(raw)) == pytest.approx(total, rel=1e-12)
        ranked.append(Ranked(total, c, theta, names))
    def best_of(ranked):  # the reference: the least full sum, the first of equals
        i = min(range(len(ranked)), key=lambda i: (float(_losses(
            problem, cur, q0, d0, folds, ranked[i][1].columns(obs, ranked[i][2])[0]).sum()), i))
        return ranked[i][1].name, ranked[i][2]

    got = _best(problem, cur, q0, d0, folds, ranked)
    assert (got[1].name, got[2]) == best_of(ranked)
    assert got[1].name in ("el_periodic_az", "az_track_2a")  # the hidden 30" sin 2A
    np.testing.assert_array_equal(got[0], _losses(problem, cur, q0, d0, folds, got[3]))
    # el_periodic_az[2] has az_track_2a's columns: sums equal to rounding, and the full
    # losses decide between them as the reference does, in either order
    twin, track = ranked[1], ranked[4]
    assert twin[0] == pytest.approx(track[0], rel=1e-12)
    for pair in ([track, twin], [twin, track]):
        assert (lambda b: (b[1].name, b[2]))(_best(problem, cur, q0, d0, folds, pair)) \
            == best_of(pair)
    inside = cur[:, :1] + 1e-4 * np.std(cur[:, 0]) * np.random.default_rng(5).normal(
        size=(2 * n, 1))
    assert sums.total(inside) is None
    assert sums.total(1e-9 * problem.cand(options[0][0].columns(obs, 1)[0])) is None  # tiny
    # a model with dependent columns: the full losses refit fold by fold, no sums
    twice = np.column_stack([cur, cur[:, :1]])
    q2, r2 = economic_qr(rows_fortran(twice, rows))
    assert FoldSums(q2, np.abs(np.diag(r2)), problem.y_raw[rows], labels,
                    np.flatnonzero(rows)).total(problem.cand(ranked[4][1].columns(
                        obs, None)[0])) is None
    assert _best(problem, cur, q0, d0, folds, []) is None


def test_the_current_models_fit_is_kept_while_what_it_depends_on_stays():
    """The current model's last fit (:meth:`Problem.fit_current`) is reused while the scans,
    the noise scale and the model stay, and made again (the same numbers as a fresh fit,
    bit for bit: one code path) when any of them changes; its raw residuals
    (:meth:`Problem.raw_residuals`, alone or with a finding's columns) are those of the
    stacked design."""
    problem = _scans_with_unused_and_scaled()
    n = problem.n
    az = problem.obs.az_rad
    extra = problem.cand(np.concatenate([np.zeros((n, 2)),
                                         np.column_stack([np.sin(2 * az), np.cos(2 * az)])]))

    def same(f, g):
        return f.chi2 == g.chi2 and np.array_equal(f.coef, g.coef) and np.array_equal(
            f.resid, g.resid)

    f = problem.fit_current()
    assert problem.fit_current() is f and same(f, problem.fit(problem.current_columns().copy()))
    # the model's own columns over its scans (the summary's degeneracies): the kept fit
    assert problem.fit(problem.current_columns()) is f
    problem.scale[0] *= 1.5
    assert problem.fit_current() is not f
    assert same(problem.fit_current(), problem.fit(problem.current_columns().copy()))
    less = problem.used.copy()
    less[np.flatnonzero(less)[:5]] = False
    assert same(problem.fit_current(less), problem.fit(problem.current_columns(), less))
    r = problem.raw_residuals()
    np.testing.assert_array_equal(problem.raw_residuals(problem.current_columns()), r)
    whole = np.column_stack([problem.current_columns(), extra])
    added = problem.sky_rms_added(extra)
    assert added == problem.sky_rms(whole) and problem.sky_rms_added(extra) == added
    assert problem.sky_rms_added(extra[:, :1]) != added  # other columns: fitted again
    problem.extra.append(extra)
    problem.extra_names += ["x:HESA2", "x:HECA2"]
    assert same(problem.fit_current(), problem.fit(whole))
    assert problem.sky_rms() == problem.sky_rms(whole) == added
    problem.used = less
    np.testing.assert_array_equal(problem.raw_residuals(), problem.raw_residuals(whole, less))


def test_a_findings_fitted_signal_comes_from_the_fit_the_outlier_update_starts_from():
    """A finding's fitted signal is taken from the current model's kept fit once the finding
    is added (:meth:`Problem.add`), the fit the outlier update then starts from: the same
    numbers, bit for bit, as its definition (a joint fit of the model's columns and the
    finding's, the finding's part less what the model's terms take); and the update makes no
    second fit of that design."""
    from antsim.diagnose.select import _fitted_signal

    problem = _scans_with_unused_and_scaled()
    n = problem.n
    az = problem.obs.az_rad
    extra = problem.cand(np.concatenate([np.zeros((n, 2)),
                                         np.column_stack([np.sin(2 * az), np.cos(2 * az)])]))
    cols = problem.current_columns()
    joint = problem.fit(np.column_stack([cols, extra]))
    signal = extra @ joint.coef[cols.shape[1]:]
    beta, *_ = np.linalg.lstsq(problem.whiten(cols), problem.whiten(signal), rcond=None)
    want = signal - cols @ beta
    before = problem.add("sin2a", extra, ("HESA2", "HECA2"))
    assert before is cols and problem.current_names[-2:] == ["sin2a:HESA2", "sin2a:HECA2"]
    assert np.array_equal(_fitted_signal(problem, before, extra), want)
    assert problem.fit_current().chi2 == joint.chi2
    kept = (problem.used.tobytes(), problem.scale.tobytes())
    made = []
    fit = problem._fit
    problem._fit = lambda c, u: made.append((u.tobytes(), problem.scale.tobytes())) or fit(c, u)
    problem.update_outliers()
    assert made and kept not in made  # fits of other scans or noise scales only


def test_the_hours_since_sunset_are_those_of_the_last_sunset_before_each_scan():
    """Two code paths: the hours since the last sunset of each scan looked up at once
    (sorted search) against the definition's scan-by-scan search of the sunsets before it;
    the same subtraction, so bit for bit (one machine, one expression): NaN by day and before
    the first sunset."""
    from dataclasses import replace

    from antsim.diagnose.candidates.base import sun_el_grid_deg, time_grid
    from antsim.diagnose.locate import _hours_since_sunset

    obs = synthetic(n=400, seed=4)
    rng = np.random.default_rng(4)
    t = np.sort(rng.uniform(0.0, 5 * 86400.0, obs.n))
    obs = replace(obs, kind="ecsv", t_s=t,
                  sun_el_deg=40.0 * np.sin(2 * np.pi * (t / 86400.0 - 0.3)))
    got = _hours_since_sunset(obs)
    grid = time_grid(obs)
    sun = sun_el_grid_deg(obs, grid)
    sets = grid[1:][(sun[:-1] >= 0.0) & (sun[1:] < 0.0)]
    want = np.full(obs.n, np.nan)
    for i, ti in enumerate(t):
        before = sets[sets <= ti]
        if before.size and not obs.sun_el_deg[i] >= 0.0:
            want[i] = (ti - before[-1]) / 3600.0
    np.testing.assert_array_equal(got, want)
    assert 50 < np.isfinite(got).sum() < obs.n - 50 and sets.size >= 4


def _tilted(n: int, rng: np.random.Generator):
    """``n`` scans with a 30' exact tilt towards 60 deg and 5' of collimation hidden (5"
    noise; their linear part in the model's AN, AW, CA): the problem, its projector and
    projected data over the used scans, and the candidate."""
    from antsim.diagnose.problem import Prediction, Problem
    from antsim.world.effects.optics import ExactTiltCollimation

    az = rng.uniform(0.0, 2 * math.pi, n)
    el = np.radians(rng.uniform(10.0, 87.0, n))
    effect = ExactTiltCollimation(tilt_arcmin=30.0, tilt_az_deg=60.0, collimation_arcmin=5.0)
    az_enc, el_enc = effect.encoder_from_true(az, el)
    d_az = (az_enc - az + math.pi) % (2 * math.pi) - math.pi
    obs = Observations(t_s=np.arange(n) * 300.0, az_rad=az, el_rad=el,
                       xel_arcsec=d_az * np.cos(el) / RAD_PER_ARCSEC + rng.normal(0, 5.0, n),
                       el_arcsec=(el_enc - el) / RAD_PER_ARCSEC + rng.normal(0, 5.0, n),
                       good=np.ones(n, bool), meta={"latitude_deg": 38.43})
    problem = Problem(obs, Prediction("white", np.zeros(n), np.zeros(n), np.full(n, 5.0),
                                      np.full(n, 5.0)),
                      ["IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX"])
    return (problem, *problem.perp_for(problem.used), candidate("exact_tilt_collimation"))


def _same_tilt(res, other) -> np.ndarray:
    """Assert that two exact-tilt tests of :func:`_tilted`'s scans found the hidden 30' and
    the same optimum, up to the sign the even signature cannot tell (tolerances: the tests'
    docstrings); ``res``'s sigmas."""
    assert res.params["tilt_arcmin"] == pytest.approx(30.0, abs=3 * res.amplitude_sigma)
    assert other.delta_chi2 == pytest.approx(res.delta_chi2, rel=1e-6)
    a, b = np.array(res.theta), np.array(other.theta)
    sig = np.sqrt(np.diag(res.cov))
    assert min(np.abs(a - b).max() / sig.min(), np.abs(a + b).max() / sig.min()) < 0.05
    return sig


def test_the_exact_tilts_subsample_search_finds_the_full_searchs_optimum(monkeypatch):
    """Two code paths of the exact tilt's fit: its nine starts on all the scans, and (many
    scans) on every k-th scan with only the best refined on all. On 3,000 scans with a 30'
    tilt and 5' of collimation hidden (their linear part in the model's AN, AW, CA) both end
    in the same optimum, up to the sign the even signature cannot tell: Levenberg-Marquardt
    stops when the chi^2 falls by less than 1e-8 of itself, which leaves the chi^2 decrease
    within 1e-6 of itself (measured 2e-12) and each parameter within sqrt(2e-8 chi^2) ~ 0.04
    of its sigma (measured 5e-4; 0.05 asked)."""
    from antsim.diagnose.candidates import optics

    n = 3000
    rng = np.random.default_rng(30)
    problem, perp, z_perp, tilt = _tilted(n, rng)
    # the projection of the used scans alone is the problem's own projector
    rows = np.flatnonzero(problem.used)
    proj, _ = optics._projection(problem, problem.used, rows)
    v = rng.standard_normal((2 * rows.size, 2))
    full = np.zeros((2 * n, 2))
    full[np.concatenate([rows, rows + n])] = v
    np.testing.assert_allclose(proj(v), perp(full), rtol=0, atol=1e-12 * np.abs(v).max())
    with monkeypatch.context() as m:  # and the path of correlated noise (through perp)
        m.setattr(problem, "white", lambda used=None: False)
        dense, _ = optics._projection(problem, problem.used, rows)
        np.testing.assert_allclose(dense(v), perp(full), rtol=0, atol=1e-12 * np.abs(v).max())
        np.testing.assert_allclose(dense(v[:, 0]), perp(full)[:, 0], rtol=0,
                                   atol=1e-12 * np.abs(v).max())
    monkeypatch.setattr(type(tilt), "SEARCH_SCANS", 10 * n)
    whole = tilt.test(problem, perp, z_perp, float(z_perp @ z_perp))
    monkeypatch.setattr(type(tilt), "SEARCH_SCANS", 300)
    sub = tilt.test(problem, perp, z_perp, float(z_perp @ z_perp))
    _same_tilt(whole, sub)



def test_the_exact_tilts_analytic_jacobian_ends_where_finite_differences_did(monkeypatch):
    """The exact tilt's Levenberg-Marquardt with its analytic Jacobian against the same
    search with scipy's finite differences (the path before): on 3,000 scans with a 30' tilt
    and 5' of collimation hidden, the Jacobian of the error as the recordings show it equals
    central differences (step 1e-4': truncation ~(1e-4/30)^2 and rounding ~1e-16/1e-4 of
    it; measured 7e-8, 1e-6 asked), and both searches stop where the chi^2 falls by less
    than 1e-8 of itself: the chi^2 decreases agree within 1e-6 of themselves (measured
    6e-13) and each parameter within 0.05 of its sigma (measured 2e-4; as for the
    subsample's path, above); the covariance (analytic, was central differences of 0.5':
    their truncation ~(0.5/30)^2 = 3e-4 of it) within 1e-3 in each sigma (measured 2e-6)."""
    from scipy import optimize

    from antsim.diagnose.candidates import optics
    from antsim.diagnose.linalg import lstsq
    from antsim.diagnose.problem import term_columns

    n = 3000
    rng = np.random.default_rng(30)
    problem, perp, z_perp, tilt = _tilted(n, rng)
    err = tilt._shown(problem, np.flatnonzero(problem.used),
                      term_columns(("AN", "AW", "CA"), problem.obs))
    h = 1e-4
    for theta in ((25.0, 17.0, 5.0), (-3.0, 1.0, -2.0)):
        jac = err.jac_rows(np.array(theta)).T
        fd = np.column_stack([(err(np.add(theta, h * e)) - err(np.subtract(theta, h * e)))
                              / (2 * h) for e in np.eye(3)])
        assert np.abs(jac - fd).max() < 1e-6 * np.abs(jac).max()
    monkeypatch.setattr(type(tilt), "SEARCH_SCANS", 10 * n)
    new = tilt.test(problem, perp, z_perp, float(z_perp @ z_perp))
    least_squares = optimize.least_squares

    def differences(*args, jac=None, **kwargs):
        return least_squares(*args, **kwargs)

    monkeypatch.setattr(optics.optimize, "least_squares", differences)
    old = tilt.test(problem, perp, z_perp, float(z_perp @ z_perp))
    sig = _same_tilt(new, old)
    rows = np.flatnonzero(problem.used)
    proj, z_used = optics._projection(problem, problem.used, rows)
    x = np.array(new.theta)
    fd = np.column_stack([proj((err(x + 0.5 * e) - err(x - 0.5 * e)) / 1.0) for e in np.eye(3)])
    _, cov = lstsq(fd, z_used)
    np.testing.assert_allclose(sig, np.sqrt(np.diag(cov)), rtol=1e-3)


def test_the_exact_tilts_covariance_is_that_of_the_jacobian_made_again(monkeypatch):
    """The exact tilt's covariance comes from the Jacobian least_squares evaluated at its
    solution (not made again): the same bits as the projected analytic Jacobian made at
    the test's theta (3,000 scans, a 30' tilt hidden; the whole search and the subsample's),
    and the best start's cost below theta = 0's so that it is that path."""
    from antsim.diagnose.candidates import optics
    from antsim.diagnose.linalg import lstsq
    from antsim.diagnose.problem import term_columns

    n = 3000
    problem, perp, z_perp, tilt = _tilted(n, np.random.default_rng(30))
    rows = np.flatnonzero(problem.used)
    err = tilt._shown(problem, rows, term_columns(("AN", "AW", "CA"), problem.obs))
    proj, z_used = optics._projection(problem, problem.used, rows)
    for search_scans in (10 * n, 300):
        monkeypatch.setattr(type(tilt), "SEARCH_SCANS", search_scans)
        res = tilt.test(problem, perp, z_perp, float(z_perp @ z_perp))
        assert res.delta_chi2 > 100.0
        again = np.column_stack([proj(row) for row in err.jac_rows(np.array(res.theta))])
        np.testing.assert_array_equal(res.cov, lstsq(again, z_used)[1])

def _svd_reference_lstsq(a: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pseudo-inverse least squares by the SVD of the whole ``a`` (what
    :func:`antsim.diagnose.problem.lstsq` computed before its tall-matrix paths)."""
    u, s, vt = np.linalg.svd(a, full_matrices=False)
    keep = s > 1e-10 * s[0]
    inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    uz = u.T @ z
    return vt.T @ ((inv[:, None] if uz.ndim == 2 else inv) * uz), (vt.T * inv**2) @ vt


@pytest.mark.parametrize("rows, cols, cond", [(2000, 1, 1.0), (2000, 2, 3.0), (2000, 3, 9.9),
                                              (2000, 3, 10.1), (2000, 6, 1e6),
                                              (2000, 10, 1e12), (6, 4, 30.0)])
def test_least_squares_paths_are_the_svds_solution(rows, cols, cond):
    """Two code paths: :func:`lstsq` on a tall matrix (the normal equations when its
    condition number is at most 10, else a QR without Q and the SVD of R) against the SVD of
    the whole. Tolerance: the normal equations' rounding grows as cond^2 eps (100 x 2.2e-16
    here), the QR's like the SVD's own (both backward stable); 1e-12 of the largest
    coefficient (and covariance entry) is a factor 40 over the first bound (measured at
    most 7e-14, at cond 9.9; 3e-15 at cond 1e12). A rank-deficient matrix gets the SVD's
    minimum-norm solution, and a NaN the SVD's ValueError."""
    from antsim.diagnose.linalg import lstsq

    rng = np.random.default_rng(rows + cols)
    u, _ = np.linalg.qr(rng.normal(size=(rows, cols)))
    v, _ = np.linalg.qr(rng.normal(size=(cols, cols)))
    a = (u * np.geomspace(1.0, 1.0 / cond, cols)) @ v.T * 7.0
    for z in (rng.normal(size=rows), rng.normal(size=(rows, 3))):
        coef, cov = lstsq(a, z)
        ref_coef, ref_cov = _svd_reference_lstsq(a, z)
        np.testing.assert_allclose(coef, ref_coef, rtol=0, atol=1e-12 * np.abs(ref_coef).max())
        np.testing.assert_allclose(cov, ref_cov, rtol=0, atol=1e-12 * np.abs(ref_cov).max())
    twice = np.column_stack([a[:, 0], 2.0 * a[:, 0]])  # rank 1: the same minimum-norm answer
    z = rng.normal(size=rows)
    np.testing.assert_allclose(lstsq(twice, z)[0], _svd_reference_lstsq(twice, z)[0],
                               rtol=1e-12)
    a[rows // 2, 0] = np.nan
    with pytest.raises(ValueError, match="infs or NaNs"):
        lstsq(a, z)


def test_cached_factors_let_the_least_recently_used_go_first(monkeypatch):
    """The model's cached QR factors and projectors stay within FACTOR_CACHE_BYTES, and the
    one asked for last stays when another set of scans needs room (the cache cleared itself
    whole before, and factored them again). A factor's projector (which holds its basis)
    goes with it. Those over the model's used scans stay whatever their age: every shape
    test reads them. Measured in the entries' own byte counts."""
    problem = _scans_with_unused_and_scaled()
    sets = [problem.used.copy() for _ in range(4)]
    for k, used in enumerate(sets, start=1):
        used[np.flatnonzero(used)[:k]] = False  # four sets of scans, not the model's
    one = 8 * (problem.factors.qr(problem.used).q.size + 2 * 2 * int(problem.used.sum()))
    problem.factors.clear()
    monkeypatch.setattr(problem.factors.cache, "max_bytes", int(2.5 * one))
    key = [(used.tobytes(), 0) for used in sets]  # ("projection", *key): a projector's
    qr0 = problem.factors.qr(sets[0])
    problem.perp_for(sets[0])  # its projector (a tenth of the factor's bytes here)
    problem.factors.qr(sets[1])
    assert problem.factors.qr(sets[0]) is qr0  # a hit, now the most recent
    problem.factors.qr(sets[2])  # no room for three factors: the oldest go, sets[0]'s stays
    assert problem.factors.cache.keys() == [("qr", *key[0]), ("qr", *key[2])]
    assert problem.factors.qr(sets[0]) is qr0
    problem.perp_for(sets[0])
    problem.factors.qr(sets[2])
    problem.perp_for(sets[0])  # a hit: its projector newer than every factor
    assert problem.factors.cache.keys() == [("qr", *key[0]), ("qr", *key[2]),
                                            ("projection", *key[0])]
    problem.factors.qr(sets[3])  # sets[0]'s factor is the oldest: it goes, its projector too
    assert problem.factors.cache.keys() == [("qr", *key[2]), ("qr", *key[3])]
    assert problem.factors.cache.nbytes <= problem.factors.cache.max_bytes
    own = ("qr", problem.used.tobytes(), 0)
    mine = problem.factors.qr(problem.used)
    problem.factors.qr(sets[0])
    problem.factors.qr(sets[1])  # the model's is the oldest, but stays
    assert problem.factors.cache.keys() == [own, ("qr", *key[1])]
    assert problem.factors.qr(problem.used) is mine


def test_selection_lets_the_models_factors_go_when_it_accepts_a_finding(monkeypatch):
    """Every cached factor and projector is keyed by the number of accepted columns: once a
    finding is accepted none is asked for again, and the problem lets them go as it adds the
    finding, before the whole design is fitted for the finding's figures (at 200,000 scans
    up to 128 MiB beside those fits' copies of the design). On a 30" sin 2A elevation
    error, found."""
    import antsim.diagnose.select as select_module

    problem = _scans_with_unused_and_scaled()
    held = []
    fitted_signal = select_module._fitted_signal

    def watched(problem_, cols, extra):
        held.append(problem_.factors.cache.nbytes)
        return fitted_signal(problem_, cols, extra)

    monkeypatch.setattr(select_module, "_fitted_signal", watched)
    sel = select_module.select(problem)
    assert [s.result.name for s in sel.steps][:1] == ["az_track_2a"]
    assert held and held == [0] * len(held)


def test_the_held_out_check_whitens_column_blocks_as_their_stack():
    """The held-out check of a finding takes the model's columns and the finding's as two
    blocks, whitened a column at a time into one Fortran-ordered design (no stacked copy
    beside it): the same numbers as the stacked columns whitened (the same products, each
    element alone), so the same held-out chi^2 to the last bit, on scans some unused."""
    problem = _scans_with_unused_and_scaled()
    cur = problem.current_columns()
    extra = np.column_stack([np.sin(2 * problem.obs.az_rad), np.cos(2 * problem.obs.az_rad)])
    extra = np.vstack([np.zeros_like(extra), extra])
    whole = np.column_stack([cur, extra])
    used = problem.used
    design = problem._whitened_fortran((cur, extra), used)
    assert design.flags.f_contiguous
    assert np.array_equal(design, problem.whiten(whole, used, fortran=True))
    folds = np.arange(problem.n) % 5
    assert problem.cv_chi2((cur, extra), folds) == problem.cv_chi2(whole, folds)


def test_the_current_models_held_out_chi2_is_from_its_cached_factor():
    """The current model's held-out chi^2 comes from its cached factor over the scans asked
    for (the same factorization of the same whitened design: the same bits as whitening and
    factoring a copy of its columns)."""
    problem = _scans_with_unused_and_scaled()
    cur = problem.current_columns()
    folds = np.arange(problem.n) % 5
    some = problem.used.copy()
    some[np.flatnonzero(some)[:3]] = False
    for used in (problem.used, some):
        want = problem.cv_chi2(cur.copy(), folds, used=used)
        got = problem.cv_chi2(cur, folds, used=used)
        assert got == want
        assert ("qr", used.tobytes(), 0) in problem.factors.cache
    problem.scale[1] *= 2.0
    problem._rescale(problem.fit_current())  # a new noise scale (the cached factors go)
    assert problem.cv_chi2(cur, folds) == problem.cv_chi2(cur.copy(), folds) != want


def test_rows_gathered_into_fortran_order_a_block_at_a_time_are_the_whole_gathered():
    """:func:`take_rows_fortran` gathers (and scales) a block of rows at a time: the same
    numbers, bit for bit, as gathering the whole, scaling it and copying it into Fortran
    order (a copy and one product per element either way), over several blocks, a last
    partial one, a strided view and into columns of a larger array; blocks of
    FORTRAN_BLOCK_ELEMENTS // k rows for these k = 4 and 7 columns (at least FORTRAN_BLOCK)."""
    from antsim.diagnose.linalg import FORTRAN_BLOCK_ELEMENTS, take_rows_fortran

    rng = np.random.default_rng(5)
    n = 3 * FORTRAN_BLOCK_ELEMENTS // 4 + 17
    whole = rng.standard_normal((n, 7))
    x = whole[:, 1:5]  # a strided view, as the model's base columns are
    idx = np.flatnonzero(rng.random(n) < 0.9)
    scale = rng.random(idx.size) + 0.5
    gathered = x[idx]
    gathered *= scale[:, None]
    out = take_rows_fortran(x, idx, scale)
    assert out.flags.f_contiguous and np.array_equal(out, gathered)
    copied = take_rows_fortran(x)
    assert copied.flags.f_contiguous and np.array_equal(copied, np.array(x, order="F"))
    assert np.array_equal(take_rows_fortran(x, idx), x[idx])
    into = np.full((idx.size, 6), np.nan, order="F")
    take_rows_fortran(x, idx, scale, into[:, 1:5])
    assert np.array_equal(into[:, 1:5], gathered) and np.isnan(into[:, [0, 5]]).all()
    wide = take_rows_fortran(whole, idx, scale)
    assert wide.flags.f_contiguous and np.array_equal(wide, whole[idx] * scale[:, None])


def test_rows_near_the_threshold_found_a_block_at_a_time_are_the_wholes():
    """:func:`near_rows` (``shape_fit``'s rows whose residual u = zp - x c lies past
    a limit) forms u a block of QT_BLOCK rows at a time: the same rows and the same values,
    bit for bit, as the whole expression it replaced, with one BLAS thread as diagnose runs
    (OpenBLAS's threads split the whole's rows where they like: rounding then differs), for
    the leading columns, chosen columns and none, over whole blocks and a partial one."""
    from antsim.blas import one_blas_thread
    from antsim.diagnose.linalg import QT_BLOCK, near_rows

    rng = np.random.default_rng(12)
    n_rows = 3 * QT_BLOCK + 4094  # an odd tail of rows beside whole blocks
    x = np.asfortranarray(rng.standard_normal((n_rows, 4)) * 2)
    zp = rng.standard_normal(n_rows) * 2
    with one_blas_thread():
        for cols in (slice(0, 2), np.array([0, 3]), slice(0, 0)):
            coef = rng.standard_normal(x[:, cols].shape[1])
            u = zp - x[:, cols] @ coef
            want = np.flatnonzero(np.abs(u) > 3.0)
            near, u_near = near_rows(x, cols, coef, zp, 3.0)
            assert want.size > 100 and np.array_equal(near, want)
            assert np.array_equal(u_near, u[want])


def test_blocked_products_over_the_models_basis_match_the_whole_to_rounding():
    """:func:`qt_dot` and :func:`shape_products` sum q^T x, x^T x and x^T z over blocks of
    rows (a faster order for OpenBLAS on thin tall products), compared with the one product
    over the whole, kept here as the reference: x bit for bit (the same products per
    element), the sums within 1e-12 relative (each is a sum of ~2e4 products here; in
    another order it moves by at most ~n eps |a| |b| = 4e-12 |a| |b| in the worst case,
    ~sqrt(n) eps typically: the bound below, 1e-12 of |a| |b| by Cauchy-Schwarz, is 100
    times the typical rounding and far below the 6 digits diagnose prints)."""
    from antsim.diagnose.linalg import QT_BLOCK, qt_dot, shape_products

    rng = np.random.default_rng(11)
    n_rows = 2 * QT_BLOCK + 3001  # two whole blocks and a partial one
    raw = rng.standard_normal((n_rows + 40, 2))
    idx = np.sort(rng.choice(n_rows + 40, n_rows, replace=False))
    wu = rng.random(n_rows) + 0.5
    f2u = rng.random(n_rows) * 0.3 + 0.7
    q, _ = np.linalg.qr(rng.standard_normal((n_rows, 6)))
    zp = rng.standard_normal(n_rows)
    for f in (f2u, None):
        x_ref = raw[idx] if f is None else np.column_stack([raw[idx] * f[:, None], raw[idx]])
        x_ref *= wu[:, None]
        x, qx, xx, xz = shape_products(raw, idx, wu, f, q, zp)
        assert x.flags.f_contiguous and np.array_equal(x, x_ref)
        norms = np.linalg.norm(x_ref, axis=0)
        for got, ref, scale in ((qx, q.T @ x_ref, np.outer(np.ones(6), norms)),
                                (qt_dot(q, x_ref), q.T @ x_ref, np.outer(np.ones(6), norms)),
                                (xx, x_ref.T @ x_ref, np.outer(norms, norms)),
                                (xz, x_ref.T @ zp, norms * np.linalg.norm(zp))):
            assert np.all(np.abs(got - ref) <= 1e-12 * scale)
        assert np.array_equal(xx, xx.T)
    small = rng.standard_normal((QT_BLOCK, 3))  # up to two blocks: the one product itself
    assert np.array_equal(qt_dot(q[:QT_BLOCK], small), q[:QT_BLOCK].T @ small)


def test_diagnose_runs_with_one_blas_thread(monkeypatch):
    """diagnose limits BLAS to one thread while it runs (its products are thin and bound by
    memory: a second OpenBLAS thread cost up to 3.5 times the time under load) and gives
    the limit back after."""
    from threadpoolctl import threadpool_info

    import antsim.diagnose.core as core

    def blas_threads() -> list[int]:
        return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]

    seen = []
    monkeypatch.setattr(core, "_diagnose", lambda *args: seen.append(blas_threads()))
    before = blas_threads()
    core.diagnose(None)
    assert seen and seen[0] and all(n == 1 for n in seen[0])
    assert blas_threads() == before
