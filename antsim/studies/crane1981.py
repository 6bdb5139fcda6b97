"""Crane (1981, NRAO Engineering Memo 147): the memo's numbers and the comparisons with a run.

The memo's Table 4 (pointing coefficients C1..C11 in arcmin with standard errors, number of
points and rms per point, per band, all data and night) and Table 5 (gain curves in K/Jy) as
data, and what ``benchmarks/crane1981.py`` and ``tests/test_crane1981.py`` compare with the
simulated runs of ``scenarios/crane1981_140ft_*.toml``:

* :func:`sigma_pattern`: the standard errors of C1..C11 that a run's schedule and noise give,
  per axis weighted as Crane's rms per axis implies (weighted least squares with the run's own
  rms per axis), for the chosen definitions or a candidate (:mod:`controller.pointing.crane`);
* :func:`rounding_ratio`: our standard error against the memo's, outside the rounding
  interval of its last digit (0.01' is printed for anything from 0.005' to 0.015');
* :func:`difference_chi2`: the day-night (all against night) comparison as a chi-square of
  the coefficient differences in units of the night fit's standard error (the memo's errors
  are rounded to one digit, too coarse for the nested-fit sqrt(s_night^2 - s_all^2));
* :func:`channel_gain`: a harmonic gain curve per receiver channel (Table 5 lists 3245 MHz per
  feed).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from controller.pointing.crane import CRANE_NAMES, candidate_terms
from controller.pointing.terms import evaluate_basis

__all__ = ["BANDS", "TABLE4", "TABLE5", "channel_gain", "difference_chi2", "rounding_ratio",
           "sigma_pattern"]

BANDS = (3245, 4990, 10500)

#: Table 4: per band and data set ("all", "night"): number of points, rms per point in RA
#: and Dec (arcsec), and C1..C11 as (value, standard error) in arcmin. 10500 MHz: "too few
#: nighttime observations were available for a fit" (section IV).
TABLE4: dict[int, dict[str, dict]] = {
    3245: {
        "all": {"n": 400, "rms": (18.2, 11.9), "c": (
            (2.14, .04), (-.51, .03), (-2.22, .06), (.86, .05), (.98, .01), (-1.65, .13),
            (-.47, .07), (1.16, .13), (-.15, .21), (-.30, .12), (.04, .21))},
        "night": {"n": 172, "rms": (18.2, 9.3), "c": (
            (2.02, .07), (-.51, .04), (-2.15, .09), (.86, .08), (1.00, .02), (-1.45, .21),
            (-.48, .10), (.95, .23), (-.41, .38), (-.33, .19), (.32, .38))},
    },
    4990: {
        "all": {"n": 353, "rms": (20.7, 11.0), "c": (
            (5.83, .05), (-.45, .03), (-2.03, .06), (.63, .06), (.97, .02), (-5.16, .13),
            (-.29, .08), (1.45, .13), (-.62, .23), (-.15, .14), (-.16, .22))},
        "night": {"n": 139, "rms": (17.4, 9.0), "c": (
            (5.72, .07), (-.46, .04), (-1.95, .08), (.70, .09), (1.02, .02), (-5.51, .20),
            (-.20, .10), (1.80, .20), (-.35, .40), (-.45, .24), (-.36, .37))},
    },
    10500: {
        "all": {"n": 182, "rms": (22.4, 10.8), "c": (
            (1.78, .07), (-.41, .04), (-1.98, .09), (.58, .09), (.99, .02), (-2.07, .17),
            (-.56, .10), (.52, .18), (-.38, .31), (-.15, .20), (-.37, .29))},
    },
}

#: Table 5: gain curves (K/Jy): Y00, Y10, Y11E, Y11O with standard errors, points, rms/point.
#: 3245 MHz: constants per feed (feed 1 north-south, feed 2 east-west, section II).
TABLE5: dict[str, dict] = {
    "3245 feed 1": {"n": 339, "rms": 0.0079, "y": ((0.2611, 0.0004),)},
    "3245 feed 2": {"n": 339, "rms": 0.0088, "y": ((0.2468, 0.0005),)},
    "4990": {"n": 261, "rms": 0.0054, "y": ((0.1900, 0.0010), (0.0060, 0.0010),
                                             (0.0170, 0.0013), (0.0046, 0.0007))},
    "10500 uncorrected": {"n": 184, "rms": 0.0136, "y": ((0.1721, 0.0027), (0.0327, 0.0027),
                                                          (0.0681, 0.0039), (0.0107, 0.0018))},
    "10500 corrected": {"n": 184, "rms": 0.0147, "y": ((0.1933, 0.0030), (0.0193, 0.0030),
                                                        (0.0549, 0.0042), (0.0120, 0.0020))},
}


def sigma_pattern(ha_rad: np.ndarray, dec_rad: np.ndarray, xel_rms_arcsec: float,
                  dec_rms_arcsec: float, latitude_deg: float,
                  definition: str | tuple[str, ...] = "crane1981") -> np.ndarray:
    """Standard errors (arcmin) of C1..C11 of ``definition`` at the rows' hour angles and
    declinations (rad) for the rms per axis given (arcsec): weighted least squares, each axis
    weighted by its own rms (Table 4 gives them apart). C5's is in its own unit (a scale)."""
    terms = candidate_terms(definition, latitude_deg)
    b_h, b_d = evaluate_basis(terms, np.asarray(ha_rad, float), np.asarray(dec_rad, float))
    x = b_h * np.cos(np.asarray(dec_rad, float))[:, None]
    a = np.vstack([x / xel_rms_arcsec, b_d / dec_rms_arcsec])
    cov = np.linalg.inv(a.T @ a)
    return np.sqrt(np.diag(cov)) / 60.0


def rounding_ratio(ours: Sequence[float], memo: Sequence[float],
                   last_digit: float = 0.01) -> np.ndarray:
    """Ours over the memo's, measured from the rounding interval of the memo's last digit:
    1 inside memo +- last_digit / 2, else the ratio to its nearer end."""
    ours = np.asarray(ours, float)
    memo = np.asarray(memo, float)
    hi = ours / (memo + 0.5 * last_digit)
    lo = ours / (memo - 0.5 * last_digit)
    return np.where(hi > 1.0, hi, np.where(lo < 1.0, lo, 1.0))


def difference_chi2(all_fit: Sequence[tuple[float, float]],
                    night_fit: Sequence[tuple[float, float]]) -> tuple[float, int, float]:
    """(chi-square, degrees of freedom, probability of a larger one) of night minus all
    coefficient differences, each in units of the night fit's standard error."""
    from scipy.stats import chi2

    total = 0.0
    for (va, _), (vn, sn) in zip(all_fit, night_fit, strict=True):
        total += ((vn - va) / sn) ** 2
    dof = len(all_fit)
    return total, dof, float(chi2.sf(total, dof))


def channel_gain(cols: Mapping[str, np.ndarray], channel: str, flux_jy: Mapping[str, float],
                 hpbw_arcmin: float, opacity: float = 0.0):
    """The harmonic gain curve (controller.scans.gaincurve) of one channel's good rows."""
    from controller.scans.gaincurve import corrected_amplitudes, fit_harmonic_gain

    sel = ((np.asarray(cols["polarization"]).astype(str) == channel)
           & np.asarray(cols["good"]).astype(bool))
    sub = {k: np.asarray(v)[sel] for k, v in cols.items()}
    amp = corrected_amplitudes(sub, hpbw_arcmin, opacity)
    flux = [flux_jy[s] for s in sub["source"].astype(str)]
    return fit_harmonic_gain(np.radians(sub["ha_deg"].astype(float)),
                             np.radians(sub["dec_deg"].astype(float)), amp, flux)


def table4_arcmin(band: int, which: str = "all") -> dict[str, tuple[float, float]]:
    """Table 4 as {C1: (value, sigma)} in arcmin."""
    return dict(zip(CRANE_NAMES, TABLE4[band][which]["c"], strict=True))
