"""Configuration of the control program: what an observer sets before a pointing run."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from controller.pointing.model import PointingModel

__all__ = ["CatalogSource", "ControllerConfig", "GainCurveConfig", "OpticalConfig", "ScanConfig",
           "SchedulerConfig", "SearchConfig", "SkyConfig", "TippingConfig"]


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
class ScanConfig:
    """Five-point cross scan: offsets ``n * step`` (sky), integrations per position."""

    step_arcmin: float = 7.0
    integration_s: float = 15.0
    offsets_n: tuple[int, ...] = (-4, -1, 0, 1, 4)
    hpbw_arcmin: float = 11.0
    estimator: str = "clark"
    snr_min: float = 4.0
    #: time spent per scan outside the integrations: noise-cal firing, data logging (s)
    overhead_s: float = 0.0
    #: reduce a source the catalogue gives a size with the width it appears with,
    #: sqrt(hpbw^2 + size^2), instead of the beam's: a fixed-width estimator with the
    #: beam's width scales an extended source's offsets by hpbw^2 / (hpbw^2 + size^2)
    use_source_size: bool = False

    def width_for(self, size_arcmin: float) -> float:
        """The width (FWHM, arcmin) the reduction assumes for a source of ``size_arcmin``."""
        if not self.use_source_size or size_arcmin <= 0.0:
            return self.hpbw_arcmin
        return math.hypot(self.hpbw_arcmin, size_arcmin)


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
    #: windows to observe in: "all", "day" (Sun above 0 deg) or "night" (Sun below -12 deg)
    window: str = "all"
    sources: tuple[str, ...] = ()
    #: equatorial mounts: observe only within +-this hour angle for the whole scan (deg)
    hour_angle_limit_deg: float | None = None


@dataclass(frozen=True)
class SearchConfig:
    """How the controller finds a source it misses (cold start, large errors)."""

    enabled: bool = True
    #: step of the wide search cross scan, as a multiple of the scan step
    step_factor: float = 2.0
    #: smoothing of the running pointing correction (0: none, 1: last scan only)
    update_gain: float = 0.5


@dataclass(frozen=True)
class TippingConfig:
    """Tipping scans (sky brightness at several elevations) to measure the zenith opacity
    (Crane 1981, section IV): one every ``interval_s``, first at the campaign's start."""

    elevations_deg: tuple[float, ...] = (88.0, 60.0, 40.0, 30.0, 23.0, 18.0, 14.0, 11.5)
    #: preferred azimuth of the blank sky (deg, N = 0); moved if a source is near
    azimuth_deg: float = 180.0
    integration_s: float = 10.0
    interval_s: float = 4.0 * 3600.0
    #: the observer's assumed mean radiating temperature of the atmosphere (K)
    t_atm_k: float = 260.0


@dataclass(frozen=True)
class SkyConfig:
    """The observer's a-priori atmosphere: its emission ``t_atm_k (1 - exp(-tau / sin E))``
    is subtracted from every integration before the reduction while no tipping scan has
    measured the opacity. Clark's straight baseline through the +-4D points removes the
    emission's slope across a scan but not its change in time as a source rises or sets,
    which biases elevation offsets with the sign of sin A (docs/assumptions.md)."""

    zenith_opacity: float = 0.0
    t_atm_k: float = 260.0


@dataclass(frozen=True)
class OpticalConfig:
    """Optical pointing with a TV camera: exposure per star and time per star outside it."""

    exposure_s: float = 5.0
    overhead_s: float = 10.0


@dataclass(frozen=True)
class GainCurveConfig:
    """Which gain curve the observatory fits to the amplitudes of which sources.

    ``kind`` ``"elevation"``: relative gain against elevation, flat above the last knot
    (1990 report, section V); ``"harmonics"``: gain in K/Jy as spherical harmonics Y00, Y10,
    Y11e, Y11o of hour angle and declination (Crane 1981, section I). ``sources``: the
    calibrators used (empty: every source with a catalogue flux). ``zenith_opacity``: the
    opacity used to correct the amplitudes when no tipping measured it (None: from the sky
    emission in the scans' own off-source points, see :mod:`controller.scans.tipping`).
    """

    kind: str = "elevation"
    sources: tuple[str, ...] = ()
    knots_deg: tuple[float, ...] = (10.0, 20.0, 30.0)
    zenith_opacity: float | None = None
    t_atm_k: float = 260.0


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

    def reduction_width_arcmin(self, source: str) -> float:
        """The width (FWHM, arcmin) the reduction assumes for the catalogue's ``source``
        (the beam's for a source the catalogue does not list)."""
        size = next((s.size_arcmin for s in self.sources if s.name == source), 0.0)
        return self.scan.width_for(size)

    def fit_spec(self) -> tuple[tuple[str, ...], str]:
        """(terms, model name) to fit. For an equatorial mount the terms are
        :class:`~controller.pointing.terms.Term` objects bound to the site's latitude."""
        if self.mount == "equatorial":
            from controller.pointing.equatorial import equatorial_terms

            if self.fit_terms:
                return (equatorial_terms(self.fit_terms, self.site_latitude_deg),
                        self.fit_model_name or "custom")
            return self.model.terms, self.model.name or "custom"
        if self.fit_terms:
            return self.fit_terms, self.fit_model_name or "custom"
        if len(self.model):
            return self.model.names, self.model.name
        from controller.pointing.model import NAMED_MODELS

        return NAMED_MODELS["tpoint8"], "tpoint8"
