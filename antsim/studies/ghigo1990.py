"""The 1990 report's (Ghigo 1990) studies: refraction as W5, Table 2 over seeds.

**Refraction.** The 45-ft's control program carried refraction in its pointing model: the
report fits ``W5 cot E`` among the W's and calls it "refraction" (Table 3: 0.80' +- 0.05'),
as Fomalont's 1973 solution held it at 1'.1 (memo I, comment 6). The simulated atmosphere
refracts by ERFA's radio formula for the weather of the moment
(:func:`controller.astro.refraction.refraction_rad`); what a fit of the report's ten terms
makes of it is its least-squares projection on the terms over the scans the fit used
(:func:`refraction_equivalent_arcsec`), and :func:`w5_of_atmosphere` the W5 part of that for
a humidity (the report gives none).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from controller.astro.refraction import refraction_rad
from controller.astro.site import Weather
from controller.pointing.model import PointingModel
from controller.units import ARCSEC_PER_RAD

__all__ = ["campaign_statistics", "equivalent_arcsec", "pattern_equivalent_arcsec",
           "refraction_arcsec", "refraction_equivalent_arcsec", "w5_of_atmosphere"]


def _good(rows: Sequence[Mapping]) -> list[Mapping]:
    return [r for r in rows if r["polarization"] == "AVG" and r["good"]]


def refraction_arcsec(rows: Sequence[Mapping], frequency_ghz: float,
                      relative_humidity: float | None = None) -> np.ndarray:
    """The atmosphere's refraction (arcsec, elevation increase) at each row's elevation and
    recorded weather (``relative_humidity`` instead of the recorded one when given)."""
    out = []
    for r in rows:
        humidity = r["humidity"] if relative_humidity is None else relative_humidity
        weather = Weather(float(r["air_temp_c"]), float(r["pressure_hpa"]), float(humidity))
        out.append(float(refraction_rad(np.radians(float(r["el_deg"])), weather,
                                        frequency_ghz=frequency_ghz)))
    return np.array(out) * ARCSEC_PER_RAD


def equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str], xel_arcsec: np.ndarray,
                      el_arcsec: np.ndarray) -> dict[str, float]:
    """What a least-squares fit of ``terms`` to the good averaged rows makes of errors
    ``xel_arcsec`` (dA cos E) and ``el_arcsec`` (dE) at them (indicated minus true, one
    value per good row): the terms' share of a systematic error."""
    good = _good(rows)
    az = np.radians([float(r["az_deg"]) for r in good])
    el = np.radians([float(r["el_deg"]) for r in good])
    model = PointingModel(list(terms))
    basis_az, basis_el = model.design_matrix(az, el)
    # the W's sign (indicated minus true) is minus TPOINT's basis; both axes of the fit
    design = -np.vstack([basis_az * np.cos(el)[:, None], basis_el])
    target = np.concatenate([xel_arcsec, el_arcsec])
    values, *_ = np.linalg.lstsq(design, target, rcond=None)
    return dict(zip(model.names, (float(v) for v in values), strict=True))


def refraction_equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str],
                                 frequency_ghz: float,
                                 relative_humidity: float | None = None) -> dict[str, float]:
    """What a least-squares fit of ``terms`` to the good averaged rows makes of the
    atmosphere's refraction alone (arcsec per term, indicated minus true: the control
    program points at unrefracted positions, so the encoders read the refraction more)."""
    good = _good(rows)
    d_el = refraction_arcsec(good, frequency_ghz, relative_humidity)
    return equivalent_arcsec(rows, terms, np.zeros(d_el.size), d_el)


def pattern_equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str],
                              world) -> dict[str, float]:
    """What the fit makes of the world's repeatable irregularities (encoders, gears, track)
    at the good rows' positions: the bias a fixed pattern gives the terms on this schedule
    (zero without the effect)."""
    effect = next((e for e in world.effects if e.name == "irregularities"), None)
    good = _good(rows)
    if effect is None:
        return dict.fromkeys(terms, 0.0)
    xel, d_el = effect.errors_arcsec(np.radians([float(r["az_deg"]) for r in good]),
                                     np.radians([float(r["el_deg"]) for r in good]))
    return equivalent_arcsec(rows, terms, xel, d_el)


def heating_equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str],
                              world) -> dict[str, float]:
    """What the fit makes of the Sun's heating at the good rows' times and positions: the
    pedestal's tilt as the world has it, the feed legs and the yoke at their equilibrium for
    pointing there (their time constants, 17-55 min, are long beside a scan, short beside
    the day, so this is the shift a day's fit shares; zero without the effect)."""
    effect = next((e for e in world.effects if e.name == "thermal"), None)
    good = _good(rows)
    if effect is None or not hasattr(effect, "equilibrium_errors_arcsec"):
        return dict.fromkeys(terms, 0.0)
    xel, d_el = effect.equilibrium_errors_arcsec(
        np.array([float(r["t_s"]) for r in good]),
        np.radians([float(r["az_deg"]) for r in good]),
        np.radians([float(r["el_deg"]) for r in good]))
    return equivalent_arcsec(rows, terms, np.asarray(xel), np.asarray(d_el))


def w5_of_atmosphere(rows: Sequence[Mapping], frequency_ghz: float,
                     relative_humidity: float | None = None) -> float:
    """The W5 (arcmin) that the report's ten terms fitted to the refraction alone give."""
    terms = [f"W{i}" for i in range(1, 11)]
    return refraction_equivalent_arcsec(rows, terms, frequency_ghz, relative_humidity)["W5"] \
        / 60.0


# --------------------------------------------------------------------------- Table 2 over seeds
#: the criteria of the reproduction (the physics issue's): each fit's points and rms within
#: 25% of Table 2, the day and night counts within 20%, points per source within 30%
TABLE2_TOLERANCE = 0.25
COUNTS_TOLERANCE = 0.20
TABLE1_TOLERANCE = 0.30
#: the reduction's S/N threshold (report section VI)
SNR_MIN = 4.0


def campaign_statistics(result, fits: Mapping, points: Mapping[str, int]) -> dict:
    """One campaign's figures beside the report's: per fit (xel rms, el rms, points), the
    points per source of fit A (``points``, ``antsim.run.sources.points_per_source``), fit
    A's terms (arcsec), the refraction's, the repeatable irregularities' and the heating's
    shares of them,
    the outliers fit A rejected, and the S/N of every scan (its lowest axis and channel)
    with its source and elevation."""
    a = fits["A"]
    frequency = result.scenario.receiver.frequency_ghz
    snr = [(min(float(r["xel_snr"]), float(r["el_snr"])), r["source"], float(r["el_deg"]))
           for r in result.rows if r["polarization"] in ("XR", "XL")]
    return {
        "rms": {k: (f.xel_rms_arcsec, f.el_rms_arcsec, f.n_used) for k, f in fits.items()
                if f is not None and k in "ABCDEF"},
        "points": dict(points),
        "names": tuple(a.names),
        "values": np.asarray(a.values_arcsec, dtype=float),
        "sigma": np.asarray(a.sigma_arcsec, dtype=float),
        "honest": np.asarray(a.sigma_honest_arcsec, dtype=float),
        "refraction": refraction_equivalent_arcsec(result.rows, a.names, frequency),
        "pattern": pattern_equivalent_arcsec(result.rows, a.names, result.world),
        "heating": heating_equivalent_arcsec(result.rows, a.names, result.world),
        "rejected": int(fits["F"].n_used - a.n_used) if fits.get("F") is not None else 0,
        "snr": snr,
    }
