"""The 1990 report's (Ghigo 1990) studies: refraction as W5, Table 2 over seeds.

**Refraction.** The 45-ft's control program carried refraction in its pointing model: the
report fits ``W5 cot E`` among the W's and calls it "refraction" (Table 3: 0.80' +- 0.05'),
as Fomalont's 1973 solution held it at 1'.1 (memo I, comment 6). The simulated atmosphere
refracts by ERFA's radio formula for the weather of the moment
(:func:`controller.astro.refraction.refraction_rad`); what a fit of the report's ten terms
makes of it is its least-squares projection on the terms over the scans the fit used
(:func:`antsim.simulate.equivalents.refraction_equivalent_arcsec`), and
:func:`w5_of_atmosphere` the W5 part of that for a humidity (the report gives none).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from antsim.simulate.equivalents import (
    heating_equivalent_arcsec,
    pattern_equivalent_arcsec,
    refraction_equivalent_arcsec,
)

__all__ = ["campaign_statistics", "w5_of_atmosphere"]


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
