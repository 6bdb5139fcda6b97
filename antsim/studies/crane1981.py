"""Crane (1981, NRAO Engineering Memo 147): the memo's numbers and the comparisons with a run.

The memo's Table 4 (pointing coefficients C1..C11 in arcmin with standard errors, number of
points and rms per point, per band, all data and night) and Table 5 (gain curves in K/Jy) as
data, and what ``benchmarks/crane1981.py`` and ``tests/end_to_end/test_crane1981.py`` compare
with the simulated runs of ``scenarios/crane1981_140ft_*.toml``:

* :func:`sigma_pattern`: the standard errors of C1..C11 that a run's schedule and noise give,
  per axis weighted as Crane's rms per axis implies (weighted least squares with the run's own
  rms per axis), for the chosen definitions or a candidate (:mod:`controller.pointing.crane`);
* :func:`rounding_ratio`: our standard error against the memo's, outside the rounding
  interval of its last digit (0.01' is printed for anything from 0.005' to 0.015');
* :func:`difference_chi2`: the day-night (all against night) comparison as a chi-square of
  the coefficient differences in units of the night fit's standard error (the memo's errors
  are rounded to one digit, too coarse for the nested-fit sqrt(s_night^2 - s_all^2));
* :func:`channel_gain`: a harmonic gain curve per receiver channel (Table 5 lists 3245 MHz per
  feed);
* :func:`good_rows`: a run's rows that enter a fit, all or at night; :func:`table4_datasets`:
  Table 4's columns against runs;
* :func:`search_declination_terms`: the best declination terms C7..C11 from a library of
  functions, by the same standard-error pattern;
* :func:`absorbed_by_crane`: the part of an effect that a fit of C1..C11 takes (the memo's
  open question as a diagnose case: ``scenarios/crane1981_140ft_4990_torsion.toml`` carries
  a polar-drive torsion with Table 4's coefficients less that part, so that its fit gives
  Table 4's).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.stats import chi2

from controller.pointing.crane import CANDIDATES, CRANE_NAMES, candidate_terms
from controller.pointing.equatorial import equatorial_model
from controller.pointing.terms import evaluate_basis
from controller.scans.gaincurve import corrected_amplitudes, fit_harmonic_gain
from controller.units import ARCSEC_PER_RAD

__all__ = ["BANDS", "DEC_LIBRARY", "TABLE4", "TABLE5", "Chi2Test", "Dataset", "absorbed_by_crane",
           "channel_gain", "difference_chi2", "good_rows", "rounding_ratio",
           "search_declination_terms", "sigma_pattern", "table4_datasets", "worst_factor"]

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


def good_rows(cols: Mapping[str, np.ndarray], night_sun_max_deg: float | None = None
              ) -> np.ndarray:
    """The averaged (AVG) rows the reduction accepted; only those at night (the Sun below
    ``night_sun_max_deg``, deg) when it is given."""
    sel = ((np.asarray(cols["polarization"]).astype(str) == "AVG")
           & np.asarray(cols["good"]).astype(bool))
    if night_sun_max_deg is not None:
        sel &= np.asarray(cols["sun_el_deg"]).astype(float) < night_sun_max_deg
    return sel


def sigma_pattern(ha_rad: np.ndarray, dec_rad: np.ndarray, xel_rms_arcsec: float,
                  dec_rms_arcsec: float, latitude_deg: float,
                  definition: str | tuple[str, ...] = "crane1981",
                  weighted: bool = True) -> np.ndarray:
    """Standard errors (arcmin) of C1..C11 of ``definition`` at the rows' hour angles and
    declinations (rad) for the rms per axis given (arcsec): weighted least squares, each axis
    weighted by its own rms (Table 4 gives them apart); ``weighted=False``: the true scatter
    of plain least squares (both axes alike, as the observatory's fit A) with that noise, the
    sandwich (A^T A)^-1 A^T C A (A^T A)^-1. C5's is in its own unit (a scale)."""
    terms = candidate_terms(definition, latitude_deg)
    b_h, b_d = evaluate_basis(terms, np.asarray(ha_rad, float), np.asarray(dec_rad, float))
    x = b_h * np.cos(np.asarray(dec_rad, float))[:, None]
    if weighted:
        a = np.vstack([x / xel_rms_arcsec, b_d / dec_rms_arcsec])
        cov = np.linalg.inv(a.T @ a)
    else:
        a = np.vstack([x, b_d])
        noise = np.concatenate([np.full(len(x), xel_rms_arcsec ** 2),
                                np.full(len(b_d), dec_rms_arcsec ** 2)])
        bread = np.linalg.inv(a.T @ a)
        cov = bread @ (a.T * noise) @ a @ bread
    return np.sqrt(np.diag(cov)) / 60.0


#: the declination functions of the definition search (controller.pointing.crane's keys):
#: the standard equatorial ones (polar axis, flexure, encoder eccentricity, tube flexure) and
#: the harmonics of the hour angle
DEC_LIBRARY = ("dch", "dsh", "dcd", "dsd", "dc2h", "ds2h", "dchsd", "dtf", "dh")


@dataclass(frozen=True)
class Dataset:
    """One of Table 4's columns against a run: the rows' hour angles and declinations (rad),
    the rms per axis (arcsec) and the memo's standard errors (arcmin)."""

    label: str
    ha_rad: np.ndarray
    dec_rad: np.ndarray
    xel_rms_arcsec: float
    dec_rms_arcsec: float
    memo_sigma: tuple[float, ...]


def table4_datasets(runs: Mapping[int, Mapping], night_sun_max_deg: Mapping[int, float]
                    ) -> list[Dataset]:
    """Table 4's columns against runs ``{band: {"cols", "fit", "variants"}}`` (recording
    columns, fit.json, fit_variants.json): each column's rows (all, or at night: the Sun below
    the band's ``night_sun_max_deg``), our fit's rms per axis (A, or E at night) and the
    memo's standard errors."""
    out = []
    for band, r in runs.items():
        cols = r["cols"]
        for which in TABLE4[band]:
            sel = good_rows(cols, night_sun_max_deg[band] if which == "night" else None)
            fit = r["fit"] if which == "all" else r["variants"]["E"]
            out.append(Dataset(f"{band} {which}",
                               np.radians(np.asarray(cols["ha_deg"])[sel].astype(float)),
                               np.radians(np.asarray(cols["dec_deg"])[sel].astype(float)),
                               fit["xel_rms_arcsec"], fit["el_rms_arcsec"],
                               tuple(c[1] for c in TABLE4[band][which]["c"])))
    return out


def worst_factor(ratios: np.ndarray) -> float:
    """The largest factor by which ratios (ours over the memo's) miss 1, either way."""
    with np.errstate(divide="ignore"):
        return float(np.max(np.maximum(ratios, 1.0 / ratios)))


def search_declination_terms(datasets: Sequence[Dataset], latitude_deg: float,
                             first: tuple[str, ...] = CANDIDATES["crane1981"][:6],
                             library: Sequence[str] = DEC_LIBRARY, top: int = 3
                             ) -> list[tuple[float, tuple[str, ...]]]:
    """The best C7..C11 from ``library`` given C1..C6 (``first``): for every five functions,
    their standard errors on every data set, assigned to C7..C11 in the order that misses
    Table 4 least; ``top`` (worst factor, definition) pairs, best first."""
    memo = np.array([d.memo_sigma for d in datasets])  # (sets, 11)
    out = []
    for combo in itertools.combinations(library, 5):
        try:
            with np.errstate(invalid="ignore"):
                ours = np.array([sigma_pattern(d.ha_rad, d.dec_rad, d.xel_rms_arcsec,
                                               d.dec_rms_arcsec, latitude_deg, (*first, *combo))
                                 for d in datasets])
        except np.linalg.LinAlgError:  # functions that span the same space
            continue
        ours = np.where(np.isfinite(ours), ours, np.inf)
        base = max(worst_factor(rounding_ratio(ours[k, :6], memo[k, :6]))
                   for k in range(len(datasets)))
        # cost[f, s]: function f (of the five) as C(7 + s), over every data set
        cost = np.array([[worst_factor(rounding_ratio(ours[:, 6 + f], memo[:, 6 + s]))
                          for s in range(5)] for f in range(5)])
        best = min(itertools.permutations(range(5)),
                   key=lambda p: max(cost[f, p[f]] for f in range(5)))
        worst = max(base, max(cost[f, best[f]] for f in range(5)))
        out.append((worst, (*first, *(combo[best.index(slot)] for slot in range(5)))))
    out.sort()
    return out[:top]


def rounding_ratio(ours: Sequence[float], memo: Sequence[float],
                   last_digit: float = 0.01) -> np.ndarray:
    """Ours over the memo's, measured from the rounding interval of the memo's last digit:
    1 inside memo +- last_digit / 2, else the ratio to its nearer end."""
    ours = np.asarray(ours, float)
    memo = np.asarray(memo, float)
    hi = ours / (memo + 0.5 * last_digit)
    lo = ours / (memo - 0.5 * last_digit)
    return np.where(hi > 1.0, hi, np.where(lo < 1.0, lo, 1.0))


class Chi2Test(NamedTuple):
    """A chi-square test: the statistic, its degrees of freedom and the probability of a
    larger one."""

    chi2: float
    dof: int
    p_value: float


def difference_chi2(all_fit: Sequence[tuple[float, float]],
                    night_fit: Sequence[tuple[float, float]]) -> Chi2Test:
    """The chi-square test of night minus all coefficient differences, each in units of the
    night fit's standard error."""
    total = 0.0
    for (va, _), (vn, sn) in zip(all_fit, night_fit, strict=True):
        total += ((vn - va) / sn) ** 2
    dof = len(all_fit)
    return Chi2Test(total, dof, float(chi2.sf(total, dof)))


def channel_gain(cols: Mapping[str, np.ndarray], channel: str, flux_jy: Mapping[str, float],
                 hpbw_arcmin: float, opacity: float = 0.0):
    """The harmonic gain curve (controller.scans.gaincurve) of one channel's good rows."""
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


def absorbed_by_crane(ha_rad: np.ndarray, dec_rad: np.ndarray, latitude_deg: float,
                      terms_arcsec: Mapping[str, float]) -> dict[str, float]:
    """The part of an effect given as equatorial TPOINT terms (``terms_arcsec``, e.g. the
    polar torsion's HHSHCD and HHSHSD) that C1..C11 take at the rows' hour angles and
    declinations (rad): the least-squares fit of its errors (cross-declination and
    declination, both axes alike as fit A) by C1..C11, in arcmin (Crane's sign; C5 in its
    own unit, a refraction scale)."""
    ha = np.asarray(ha_rad, float)
    dec = np.asarray(dec_rad, float)
    effect = equatorial_model(list(terms_arcsec), latitude_deg, list(terms_arcsec.values()))
    d_h, d_dec = effect.offset_rad(ha, dec)  # indicated - true (rad)
    error = np.concatenate([d_h * np.cos(dec), d_dec]) * ARCSEC_PER_RAD
    b_h, b_d = evaluate_basis(candidate_terms("crane1981", latitude_deg), ha, dec)
    a = -np.vstack([b_h * np.cos(dec)[:, None], b_d])  # the error per arcsec of each C
    coef, *_ = np.linalg.lstsq(a, error, rcond=None)
    return {name: float(c) / 60.0 for name, c in zip(CRANE_NAMES, coef, strict=True)}
