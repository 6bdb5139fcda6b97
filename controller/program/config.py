"""Configuration of the control program: what an observer sets before a pointing run.

:class:`ControllerConfig` holds all of it; the settings of the scans themselves (cross scan,
tipping, a-priori sky, gain curve) are in :mod:`controller.scans.config`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from controller.astro.sun import NIGHT_SUN_MAX_DEG
from controller.pointing.equatorial import equatorial_terms
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.scans.config import GainCurveConfig, ScanConfig, SkyConfig, TippingConfig

__all__ = ["CatalogSource", "ControllerConfig", "OpticalConfig", "SchedulerConfig",
           "SearchConfig"]


@dataclass(frozen=True)
class CatalogSource:
    """A pointing source as the observer's catalogue gives it (position, expected flux)."""

    name: str
    ra_deg: float
    dec_deg: float
    frame: str = "fk4"
    flux_jy: float = 0.0
    #: Gaussian FWHM of the source's brightness (arcmin); 0 for a point source
    size_arcmin: float = 0.0


@dataclass(frozen=True)
class SchedulerConfig:
    """Which source next: a coverage-spreading policy over the visible sources."""

    policy: str = "spread"
    elevation_min_deg: float = 10.0
    elevation_max_deg: float = 85.0
    #: do not observe the same source again within this time (s)
    min_revisit_s: float = 900.0
    #: weight of the slew time (per minute) against the sky-coverage gain
    slew_weight: float = 0.5
    #: windows to observe in: "all", "day" (Sun above 0 deg) or "night" (Sun below
    #: ControllerConfig.night_sun_max_deg)
    window: str = "all"
    sources: tuple[str, ...] = ()
    #: equatorial mounts: observe only within +-this hour angle for the whole scan (deg)
    hour_angle_limit_deg: float | None = None
    #: the control program cannot point above this declination (deg; None: no limit). The
    #: 140-ft's program of 1981 could not run its pointing verb above +72 deg (Crane 1981,
    #: section II and summary item 7)
    declination_max_deg: float | None = None


@dataclass(frozen=True)
class SearchConfig:
    """How the controller finds a source it misses (cold start, large errors)."""

    enabled: bool = True
    #: step of the wide search cross scan, as a multiple of the scan step
    step_factor: float = 2.0
    #: smoothing of the running pointing correction (0: none, 1: last scan only)
    update_gain: float = 0.5
    #: what the running correction is: an offset on the sky ("sky") or of the two encoders
    #: ("encoders": a cross-elevation offset x found at elevation E is held as the azimuth
    #: offset x / cos E, as an encoder zero offset is)
    correction: str = "sky"
    #: adopt a search's offset in one axis only where the offset it found in the other is
    #: within this many beams (that half of the cross passed the source that far aside);
    #: None: every axis found
    max_cross_offset_beams: float | None = None


@dataclass(frozen=True)
class OpticalConfig:
    """Optical pointing with a TV camera: exposure per star and time per star outside it."""

    exposure_s: float = 5.0
    overhead_s: float = 10.0


@dataclass(frozen=True)
class ControllerConfig:
    """Everything the control program is told; never the truth of a simulation."""

    site_latitude_deg: float
    site_longitude_deg: float
    site_height_m: float
    epoch_utc: str
    duration_s: float
    sources: tuple[CatalogSource, ...]
    model: PointingModel = field(default_factory=PointingModel)
    scan: ScanConfig = field(default_factory=ScanConfig)
    scheduler: SchedulerConfig = field(default_factory=SchedulerConfig)
    search: SearchConfig = field(default_factory=SearchConfig)
    #: refraction the controller corrects: "weather" (from its sensors), "standard"
    #: (fixed 10 C, 1013.25 hPa scaled to the site height, 50% RH) or "none"
    refraction: str = "weather"
    frequency_ghz: float = 8.4
    scenario_name: str = ""
    site_name: str = ""
    #: terms the observatory fits to the campaign (default: those of the model in use, or
    #: TPOINT's eight when no model is in use)
    fit_terms: tuple[str, ...] = ()
    fit_model_name: str = ""
    #: terms of the fit held at a value instead of fitted, (name, arcsec) pairs (Fomalont
    #: 1973 held refraction at 1'.1)
    fit_fixed: tuple[tuple[str, float], ...] = ()
    #: the mount's axes: "altaz" (azimuth, elevation) or "equatorial" (hour angle, dec)
    mount: str = "altaz"
    #: how offsets are measured: "five_point" cross scans or "optical" (a TV camera on stars)
    method: str = "five_point"
    #: feed (rotator) angles to cycle through, one per scan (deg); empty: no feed command
    feed_angles_deg: tuple[float, ...] = ()
    tipping: TippingConfig | None = None
    sky: SkyConfig | None = None
    optical: OpticalConfig | None = None
    gain_curve: GainCurveConfig | None = None
    #: the Sun's elevation below which it is night (deg): the scheduler's "night" window and
    #: the night fit (E). The 1990 report's night is not defined either; -12 deg (nautical
    #: twilight over) is this project's reading of it
    night_sun_max_deg: float = NIGHT_SUN_MAX_DEG
    #: the antenna's structure temperature sensors the controller reads during each half of
    #: a cross scan and records (empty: none, as on the 1990 antenna)
    structure_sensors: tuple[str, ...] = ()
    #: their response time (s, first order; the datasheet's): the fits correct for it
    structure_lag_s: float = 0.0

    def reduction_width_arcmin(self, source: str) -> float:
        """The width (FWHM, arcmin) the reduction assumes for the catalogue's ``source``
        (the beam's for a source the catalogue does not list)."""
        size = next((s.size_arcmin for s in self.sources if s.name == source), 0.0)
        return self.scan.width_for(size)

    def fit_spec(self) -> tuple[tuple[str, ...], str]:
        """(terms, model name) to fit. For an equatorial mount the terms are
        :class:`~controller.pointing.terms.Term` objects bound to the site's latitude."""
        if self.mount == "equatorial":
            if self.fit_terms:
                return (equatorial_terms(self.fit_terms, self.site_latitude_deg),
                        self.fit_model_name or "custom")
            return self.model.terms, self.model.name or "custom"
        if self.fit_terms:
            return self.fit_terms, self.fit_model_name or "custom"
        if len(self.model):
            return self.model.names, self.model.name
        return NAMED_MODELS["tpoint8"], "tpoint8"
