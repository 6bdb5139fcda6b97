"""What each source gave a run: its points in fit A (the 1990 report's Table 1) and the
hours it spent inside the scheduler's elevation window."""

from __future__ import annotations

import numpy as np

from controller.astro.ephemeris import Ephemeris
from controller.astro.site import Site
from controller.astro.sources import FixedSource
from controller.pointing.result import FitResult
from controller.pointing.variants import VARIANTS, columns, variant_mask

__all__ = ["points_per_source", "visible_hours"]


def points_per_source(rows, fit: FitResult | None) -> dict[str, int]:
    """Observations of each source that fit A used (the 1990 report's Table 1), in the order
    the sources first appear."""
    if fit is None:
        return {}
    cols = columns(rows)
    mask = variant_mask(cols, VARIANTS[0])
    source = np.array([r["source"] for r in rows]) if isinstance(rows, list) else \
        np.asarray(rows["source"])
    used = source[mask][np.asarray(fit.used, dtype=bool)]
    names = list(dict.fromkeys(source[mask].tolist()))
    return {n: int((used == n).sum()) for n in names}


def visible_hours(scenario, step_s: float = 60.0) -> dict[str, float]:
    """Hours each catalogue source spends inside the scheduler's elevation window during the
    campaign (sampled every ``step_s``): what a source's share of the scans is measured by."""
    c = scenario.controller
    site = Site(c.site_latitude_deg, c.site_longitude_deg, c.site_height_m)
    sources = [FixedSource(s.name, s.ra_deg, s.dec_deg, s.frame) for s in c.sources]
    ephemeris = Ephemeris(site, c.epoch_utc, c.duration_s, sources)
    t = np.arange(0.0, c.duration_s, step_s)
    out = {}
    for i, s in enumerate(sources):
        el = np.degrees(ephemeris.altaz_rad(i, t)[1])
        inside = (el >= c.scheduler.elevation_min_deg) & (el <= c.scheduler.elevation_max_deg)
        out[s.name] = float(inside.sum()) * step_s / 3600.0
    return out
