"""The 1990 report's fit variants A-F from one set of recordings.

| fit | data |
|---|---|
| A | XR and XL averaged (the AVG rows), filtered |
| B | XR only, filtered |
| C | XL only, filtered |
| D | AVG, by day (Sun above 0 deg), filtered |
| E | AVG, at night (Sun below -12 deg unless the campaign sets another night), filtered |
| F | AVG, unfiltered: every scan with a defined offset, plain least squares |

"Filtered" is the report's procedure: scans the reduction flagged (S/N < 4, undefined log
ratio, ...) are dropped, then the robust fit (LAD, 4x mean absolute deviation, least
squares, 3x rms, least squares) rejects outliers. The total pointing error fitted is the
measured offset plus the model in use plus any correction the controller applied.
Recordings of an equatorial mount (columns ``ha_deg``, ``dec_deg``) are fitted in hour angle
and declination; a ``feed_angle_deg`` column feeds the feed terms (``HSCF``...).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG

from .data import PointingData
from .fitting import fit_model
from .result import FitResult

__all__ = ["VARIANTS", "Variant", "columns", "fit_variants", "pointing_data", "variant_mask"]


@dataclass(frozen=True)
class Variant:
    name: str
    description: str
    polarization: str
    window: str  # "all", "day", "night"
    filtered: bool

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
)

_NEEDED = ("polarization", "az_deg", "el_deg", "xel_arcmin", "el_arcmin", "model_xel_arcmin",
           "model_el_arcmin", "applied_xel_arcmin", "applied_el_arcmin", "good", "sun_el_deg",
           "t_s")
#: taken when present: equatorial coordinates and the feed angle
_OPTIONAL = ("ha_deg", "dec_deg", "feed_angle_deg")


def columns(recordings) -> dict[str, np.ndarray]:
    """Column arrays from an astropy Table of recordings or a list of row dicts."""
    if isinstance(recordings, Sequence) and (not recordings or isinstance(recordings[0],
                                                                           Mapping)):
        cols = {c: np.array([r[c] for r in recordings]) for c in _NEEDED}
        present = [c for c in _OPTIONAL if recordings and c in recordings[0]]
        cols.update({c: np.array([r[c] for r in recordings]) for c in present})
        return cols
    cols = {c: np.asarray(recordings[c]) for c in _NEEDED}
    cols.update({c: np.asarray(recordings[c]) for c in _OPTIONAL if c in recordings.colnames})
    return cols


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


def pointing_data(cols: Mapping[str, np.ndarray], mask: np.ndarray) -> PointingData:
    """Total pointing errors (measured + model in use + applied) of the selected rows."""
    f = {k: np.asarray(v)[mask].astype(float) for k, v in cols.items()
         if k not in ("polarization", "good")}
    lon, lat = ("ha_deg", "dec_deg") if "ha_deg" in f else ("az_deg", "el_deg")
    return PointingData(
        az_rad=np.radians(f[lon]),
        el_rad=np.radians(f[lat]),
        xel_arcsec=60.0 * (f["xel_arcmin"] + f["model_xel_arcmin"] + f["applied_xel_arcmin"]),
        el_arcsec=60.0 * (f["el_arcmin"] + f["model_el_arcmin"] + f["applied_el_arcmin"]),
        t_s=f["t_s"],
        feed_rad=np.radians(f["feed_angle_deg"]) if "feed_angle_deg" in f else None,
    )


def fit_variants(recordings, terms: Sequence[str] | str, name: str = "custom",
                 variants: Sequence[Variant] = VARIANTS,
                 night_sun_max_deg: float = NIGHT_SUN_MAX_DEG,
                 fixed: Mapping[str, float] | None = None) -> dict[str, FitResult | None]:
    """Fit every variant (night: the Sun below ``night_sun_max_deg``); a variant with too
    few observations maps to None. ``fixed``: terms held at these values (arcsec), see
    :func:`~controller.pointing.fitting.fit_model`."""
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
            out[variant.name] = fit_model(pointing_data(cols, mask), terms,
                                          robust=variant.filtered, name=name, fixed=fixed)
        except ValueError:
            out[variant.name] = None  # e.g. fewer usable observations than terms
    return out
