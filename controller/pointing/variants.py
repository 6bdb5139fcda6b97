"""The 1990 report's fit variants A-F from one set of recordings.

| fit | data |
|---|---|
| A | XR and XL averaged (the AVG rows), filtered |
| B | XR only, filtered |
| C | XL only, filtered |
| D | AVG, by day (Sun above 0 deg), filtered |
| E | AVG, at night (Sun below -12 deg unless the campaign sets another night), filtered |
| F | AVG, unfiltered: every scan with a defined offset, plain least squares |
| T | as A, with the thermal terms the data support (not the report's) |

"Filtered" is the report's procedure: scans the reduction flagged (S/N < 4, undefined log
ratio, ...) are dropped, then the robust fit (LAD, 4x mean absolute deviation, least
squares, 3x rms, least squares) rejects outliers. The total pointing error fitted is the
measured offset plus the model in use plus any correction the controller applied.
Recordings of an equatorial mount (columns ``ha_deg``, ``dec_deg``) are fitted in hour angle
and declination; a ``feed_angle_deg`` column feeds the feed terms (``HSCF``...).

Fit T (this project's, not the report's) is fit A with thermal terms
(:mod:`controller.pointing.thermal`) added where the data support them
(:mod:`controller.pointing.selection`): in the structure temperatures where the recordings
have them, else in proxies for them (:mod:`controller.pointing.proxies`: the Sun and the air
temperature, which need the site and the epoch; alt-az recordings only). Fit A itself says
what the heating leaves in it: for each term, the difference between the day and the night
fits (D - E) with its honest sigma, and a warning where that difference exceeds
``SYSTEMATIC_SIGMAS`` times its sigma (:func:`day_minus_night`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG

from .data import PointingData
from .fitting import fit_model
from .model import named_model_terms
from .proxies import proxy_aux
from .result import FitResult
from .selection import select_terms
from .thermal import (
    PROXY_TERMS,
    SENSOR_FAMILY,
    SENSOR_TERMS,
    sensor_aux,
    structure_column,
    structure_sensor_names,
    structure_time_column,
    thermal_regressors,
)

__all__ = ["SYSTEMATIC_SIGMAS", "VARIANTS", "Variant", "columns", "day_minus_night",
           "fit_variants", "pointing_data", "thermal_fit", "variant_mask"]

#: fit A warns of a term whose day-minus-night difference exceeds this many sigma of it
#: (3: a false alarm in 0.3% of terms, 3% of ten-term campaigns, without any systematic)
SYSTEMATIC_SIGMAS = 3.0


@dataclass(frozen=True)
class Variant:
    name: str
    description: str
    polarization: str
    window: str  # "all", "day", "night"
    filtered: bool
    #: thermal terms added where the data support them (fit T)
    thermal: bool = False

    def describe(self, night_sun_max_deg: float = NIGHT_SUN_MAX_DEG) -> str:
        """The description, with the campaign's night threshold for the night fit."""
        if self.window != "night":
            return self.description
        return self.description.replace(f"{NIGHT_SUN_MAX_DEG:g} deg", f"{night_sun_max_deg:g} deg")


VARIANTS: tuple[Variant, ...] = (
    Variant("A", "XR+XL averaged, filtered", "AVG", "all", True),
    Variant("B", "XR, filtered", "XR", "all", True),
    Variant("C", "XL, filtered", "XL", "all", True),
    Variant("D", "averaged, day (Sun above 0 deg), filtered", "AVG", "day", True),
    Variant("E", "averaged, night (Sun below -12 deg), filtered", "AVG", "night", True),
    Variant("F", "averaged, unfiltered", "AVG", "all", False),
    Variant("T", "as A, with the thermal terms the data support", "AVG", "all", True,
            thermal=True),
)

_NEEDED = ("polarization", "az_deg", "el_deg", "xel_arcmin", "el_arcmin", "model_xel_arcmin",
           "model_el_arcmin", "applied_xel_arcmin", "applied_el_arcmin", "good", "sun_el_deg",
           "t_s")
#: taken when present: equatorial coordinates, the feed angle, the air temperature (a proxy
#: of the structure's), and the structure temperatures (controller.pointing.thermal)
_OPTIONAL = ("ha_deg", "dec_deg", "feed_angle_deg", "air_temp_c")


def columns(recordings) -> dict[str, np.ndarray]:
    """Column arrays from an astropy Table of recordings or a list of row dicts."""
    if isinstance(recordings, Sequence) and (not recordings or isinstance(recordings[0],
                                                                           Mapping)):
        names = list(recordings[0]) if recordings else []
        wanted = [*_NEEDED, *(c for c in _OPTIONAL if c in names), *_structure(names)]
        return {c: np.array([r[c] for r in recordings]) for c in wanted}
    names = list(recordings.colnames)
    wanted = [*_NEEDED, *(c for c in _OPTIONAL if c in names), *_structure(names)]
    return {c: np.asarray(recordings[c]) for c in wanted}


def _structure(names) -> list[str]:
    """The structure temperature columns among ``names`` (both halves of every sensor, and
    when they were read)."""
    sensors = structure_sensor_names(names)
    times = [structure_time_column(a) for a in ("xel", "el")
             if sensors and structure_time_column(a) in names]
    both = [structure_column(s, a) for s in sensors for a in ("xel", "el")]
    return [*times, *(c for c in both if c in names),
            *(f"temp_{s}_c" for s in sensors if f"temp_{s}_c" in names)]


def variant_mask(cols: Mapping[str, np.ndarray], variant: Variant,
                 night_sun_max_deg: float = NIGHT_SUN_MAX_DEG) -> np.ndarray:
    """Rows that enter ``variant``: its polarization and window (night: the Sun below
    ``night_sun_max_deg``), and (if filtered) only scans the reduction did not flag; always
    only rows whose offsets are defined."""
    mask = cols["polarization"] == variant.polarization
    mask &= np.isfinite(cols["xel_arcmin"].astype(float))
    mask &= np.isfinite(cols["el_arcmin"].astype(float))
    if variant.filtered:
        mask &= cols["good"].astype(bool)
    sun = cols["sun_el_deg"].astype(float)
    if variant.window == "day":
        mask &= sun > DAY_SUN_MIN_DEG
    elif variant.window == "night":
        mask &= sun < night_sun_max_deg
    return mask


def pointing_data(cols: Mapping[str, np.ndarray], mask: np.ndarray,
                  sensor_lag_s: float = 0.0) -> PointingData:
    """Total pointing errors (measured + model in use + applied) of the selected rows, with
    the structure temperatures where the recordings have them (``aux``; corrected for the
    sensors' response time ``sensor_lag_s``, :func:`~controller.pointing.thermal.sensor_aux`)."""
    f = {k: np.asarray(v)[mask].astype(float) for k, v in cols.items()
         if k not in ("polarization", "good")}
    lon, lat = ("ha_deg", "dec_deg") if "ha_deg" in f else ("az_deg", "el_deg")
    sensors = structure_sensor_names(list(f))
    return PointingData(
        az_rad=np.radians(f[lon]),
        el_rad=np.radians(f[lat]),
        xel_arcsec=60.0 * (f["xel_arcmin"] + f["model_xel_arcmin"] + f["applied_xel_arcmin"]),
        el_arcsec=60.0 * (f["el_arcmin"] + f["model_el_arcmin"] + f["applied_el_arcmin"]),
        t_s=f["t_s"],
        feed_rad=np.radians(f["feed_angle_deg"]) if "feed_angle_deg" in f else None,
        aux=sensor_aux(f, sensors, sensor_lag_s) if sensors else None,
    )


def fit_variants(recordings, terms: Sequence[str] | str, name: str = "custom",
                 variants: Sequence[Variant] = VARIANTS,
                 night_sun_max_deg: float = NIGHT_SUN_MAX_DEG,
                 fixed: Mapping[str, float] | None = None,
                 context: Mapping | None = None) -> dict[str, FitResult | None]:
    """Fit every variant (night: the Sun below ``night_sun_max_deg``); a variant with too
    few observations maps to None, and so does fit T where there is nothing to drive
    thermal terms. ``fixed``: terms held at these values (arcsec), see
    :func:`~controller.pointing.fitting.fit_model`. ``context``: the recordings' ``site``
    (``latitude_deg``, ``longitude_deg``, ``height_m``) and ``epoch_utc``, for the proxies
    of fit T without structure temperatures, and ``sensor_lag_s``, the structure sensors'
    response time. Fit A carries the day-minus-night warnings of :func:`day_minus_night`."""
    cols = columns(recordings)
    out: dict[str, FitResult | None] = {}
    n_terms = len(terms) if not isinstance(terms, str) else None
    for variant in variants:
        mask = variant_mask(cols, variant, night_sun_max_deg)
        n = int(mask.sum())
        if n == 0 or (n_terms is not None and 2 * n <= n_terms):
            out[variant.name] = None
            continue
        try:
            if variant.thermal:
                out[variant.name] = thermal_fit(cols, mask, terms, name, fixed, context)
            else:
                out[variant.name] = fit_model(pointing_data(cols, mask), terms,
                                              robust=variant.filtered, name=name, fixed=fixed)
        except ValueError:
            out[variant.name] = None  # e.g. fewer usable observations than terms
    fit_a = out.get("A")
    if fit_a is not None:
        warnings = [w for term, (d, s, w) in day_minus_night(out).items() if w]
        if warnings:
            out["A"] = dataclasses.replace(fit_a, warnings=(*fit_a.warnings, *warnings))
    return out


def thermal_fit(cols: Mapping[str, np.ndarray], mask: np.ndarray, terms: Sequence[str] | str,
                name: str, fixed: Mapping[str, float] | None = None,
                context: Mapping | None = None) -> FitResult | None:
    """Fit T of the rows ``mask``: the terms ``terms`` and the thermal terms the data
    support (:func:`~controller.pointing.selection.select_terms`), in the structure
    temperatures where the recordings have them, else in proxies (alt-az recordings with a
    ``context``); None where there are neither. The selection's tests are the fit's
    ``notes``.

    The structure-sensor terms are one candidate: the pair terms of :data:`SENSOR_FAMILY`
    that the recorded sensors allow enter together, when an F test of the group (one dof
    per term, at ``ALPHA``) and the held-out check say the data support them, or not at all.
    They are one physical mechanism (the structure's thermal bending) measured by one set of
    thermometers (the Sun that warms one part of the structure warms the others); tested
    one at a time, a weak term is left out in most campaigns (pre-test estimation: Judge and Bock
    1978; Giles and Giles 1993, J. Econ. Surveys 7, 145) and what it explains goes into the
    geometric terms that share its pattern: W3 and W5 by about a third of their sigma in
    every campaign alike (``benchmarks/recovery.py``). ``antsim diagnose`` tests the same
    family as one candidate (``thermal_sensors``). TTILT (TNPNS and TWPEW with one
    coefficient) is a restriction of the family, not a member. The proxies stay single
    candidates: they are not measurements of separate parts but alternative descriptions of
    the same heating (the Sun's height, its direction, the air), largely collinear, among
    which the selection chooses."""
    base = list(named_model_terms(terms) if isinstance(terms, str) else terms)
    data = pointing_data(cols, mask, float((context or {}).get("sensor_lag_s", 0.0)))
    family = tuple(t for t in SENSOR_FAMILY
                   if data.aux and thermal_regressors((SENSOR_TERMS[t],)) <= set(data.aux))
    candidates: list[str | tuple[str, ...]] = [family] if family else []
    if not candidates:
        if context is None or "ha_deg" in cols or "epoch_utc" not in context:
            return None
        air = cols["air_temp_c"][mask].astype(float) if "air_temp_c" in cols else None
        aux = proxy_aux(data.t_s, data.az_rad, data.el_rad, air, context["site"],
                        context["epoch_utc"])
        data = dataclasses.replace(data, aux=aux)
        candidates = [t for t, term in PROXY_TERMS.items()
                      if thermal_regressors((term,)) <= set(aux)]
    selection = select_terms(data, base, candidates, fixed=fixed)
    fit = fit_model(data, selection.terms, name=f"{name}+thermal", fixed=fixed)
    tested = ", ".join(c if isinstance(c, str) else "(" + " ".join(c) + ")" for c in candidates)
    notes = [f"thermal terms tested: {tested} (family of "
             f"{selection.n_family}); added: {', '.join(selection.accepted) or 'none'}"]
    notes += [step.describe() for step in selection.steps]
    return dataclasses.replace(fit, notes=tuple(notes))


def day_minus_night(fits: Mapping[str, FitResult | None]) -> dict[str, tuple[float, float, str]]:
    """Per term of fit A that fits D and E both fitted: the difference D - E (arcsec), its
    sigma (the honest sigmas of D and E in quadrature), and a warning where the difference
    exceeds ``SYSTEMATIC_SIGMAS`` of them: then the day's pointing differs from the night's
    beyond the noise, and fit A's value is the pointing of the mixture, with a systematic
    error that its statistical sigma does not include ("" otherwise)."""
    a, d, e = fits.get("A"), fits.get("D"), fits.get("E")
    if a is None or d is None or e is None:
        return {}
    out = {}
    sd, se, sa = d.sigma_honest_arcsec, e.sigma_honest_arcsec, a.sigma_honest_arcsec
    for j, term in enumerate(a.names):
        if term in a.fixed or term not in d.names or term not in e.names:
            continue
        jd, je = d.names.index(term), e.names.index(term)
        diff = float(d.values_arcsec[jd] - e.values_arcsec[je])
        sigma = float(np.hypot(sd[jd], se[je]))
        warn = ""
        if np.isfinite(sigma) and sigma > 0 and abs(diff) > SYSTEMATIC_SIGMAS * sigma:
            warn = (f"{term}: day minus night (fits D - E) {diff:+.1f}\" +- {sigma:.1f}\" "
                    f"({diff / sigma:+.1f} sigma), against fit A's statistical sigma "
                    f"{sa[j]:.1f}\": a systematic error (thermal?) that fit A's sigma does not "
                    "include; fit A gives the pointing of the day and night mixed")
        out[term] = (diff, sigma, warn)
    return out
