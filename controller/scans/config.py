"""What an observer sets for the scans: the five-point cross scan, tipping scans, the a-priori
sky and the gain curve fitted to the scans' amplitudes."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["GainCurveConfig", "ScanConfig", "SkyConfig", "TippingConfig"]


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
