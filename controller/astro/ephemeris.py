"""Site and sky: apparent topocentric positions of fixed radio sources and the Sun, fast.

The control program and the simulated world ask for source positions many thousands of times
per simulated day, so positions come from a vectorized evaluator instead of per-call astropy
transforms (milliseconds each):

1. each source is converted once to ICRS with astropy (FK4 B1950 by default);
2. on a uniform time grid covering the campaign (600 s by default) ERFA computes the exact
   apparent topocentric hour angle and declination without refraction, with the same
   functions, IERS tables (UT1-UTC, polar motion) and Earth ephemeris as astropy's own
   ``AltAz``/``HADec`` transforms (``erfa.apco`` + ``atciqz`` + ``atioq``); the expensive,
   slowly varying parts (precession-nutation, Earth ephemeris) are evaluated every 3 hours and
   interpolated onto the grid;
3. the smooth quantities "hour angle minus sidereal rotation" and declination are stored as
   piecewise cubics (Hermite, derivatives by 4th-order finite differences), evaluated with
   plain numpy, and turned into azimuth/elevation by exact spherical trigonometry.

Measured against per-point astropy ``AltAz(pressure=0)`` the error is a few micro-arcseconds
(``benchmarks/ephemeris.py``, ``tests/test_astro.py``); one ``altaz_rad`` call costs tens of
microseconds.

Conventions: angles in radians unless the name says otherwise; azimuth from North through
East (N = 0, E = pi/2) in [0, 2 pi); hour angle positive West; times are float seconds since the
campaign epoch, a UTC instant (SI seconds, so leap seconds are handled by astropy ``Time``).
astropy ``Time`` appears only at this module's edges (``epoch``, :meth:`Ephemeris.time`).

Offline: IERS auto-download is off (:mod:`controller.astro.offline`); the bundled
``astropy-iers-data`` tables are used. astropy.coordinates (most of a second) and erfa are
imported inside functions so that importing this module stays cheap.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np

from . import offline as _offline

if TYPE_CHECKING:
    from astropy.coordinates import EarthLocation
    from astropy.time import Time

__all__ = [
    "GHIGO1990_SOURCES",
    "GREEN_BANK_45FT",
    "Ephemeris",
    "FixedSource",
    "Site",
    "Weather",
    "dec_dms_to_deg",
    "icrs_radec_rad",
    "ra_hms_to_deg",
    "refraction_rad",
    "standard_pressure_hpa",
    "sunrise_times_s",
    "sunset_times_s",
]

TWO_PI = 2.0 * math.pi
_BELOW_TWO_PI = math.nextafter(TWO_PI, 0.0)
#: Earth rotation angle rate (rad per UT1 second; IAU 2000 ERA). UT1 runs within ~3e-8 of SI
#: seconds; that difference lives in the interpolated residual.
SIDEREAL_RATE_RAD_S = TWO_PI * 1.00273781191135448 / 86400.0
#: step of the support grid for precession-nutation and the Earth ephemeris (s): their
#: fastest significant terms have periods of days (nutation 13.7 d, Moon 27.3 d)
_SUPPORT_STEP_S = 3.0 * 3600.0
#: longest campaign accepted: beyond a year the grid is large and IERS tables run out
MAX_DURATION_S = 366.0 * 86400.0
#: the grid step must resolve a sidereal day (the diurnal terms); measured error < 1e-4" at 1 h
MAX_GRID_STEP_S = 3600.0
#: astropy's fallback polar motion (50-year mean) for dates outside the IERS tables (arcsec)
_DEFAULT_POLAR_MOTION_ARCSEC = (0.035, 0.29)
#: ERFA's limits in eraAtioq's refraction: minimum cos(el) and sin(el) (the model is not
#: meant for elevations below about 3 degrees; the bending is held near its value there)
_CELMIN = 1e-6
_SELMIN = 0.05
#: any wavelength above 100 micrometres selects ERFA's radio refraction formula
_RADIO_WAVELENGTH_UM = 1.0e4
_SPEED_OF_LIGHT_UM_GHZ = 299792.458  # micrometres * GHz
_LIGHT_TIME_DAY_PER_AU = 499.004783836 / 86400.0  # light time for 1 au (day)
_SUPPORTED_FRAMES = ("fk4", "fk5", "icrs")


# --------------------------------------------------------------------------- validation
def _require_finite(value: Any, name: str) -> None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is not a number; give a plain number.") from None
    if not math.isfinite(number):
        raise ValueError(f"{name} = {value!r} is not finite; give a finite number.")


def _finite_fields(instance: Any, label: str, *names: str) -> None:
    """Check that the named dataclass fields are finite numbers and store them as floats."""
    for name in names:
        value = getattr(instance, name)
        _require_finite(value, f"{label} {name}")
        object.__setattr__(instance, name, float(value))


def _seconds_value(value: Any, name: str) -> float:
    """A duration in seconds from a number or an astropy Quantity of time."""
    if hasattr(value, "unit"):
        try:
            value = value.to_value("s")
        except Exception:
            raise ValueError(f"{name} = {value} is not a time; give seconds.") from None
    _require_finite(value, name)
    return float(value)


# --------------------------------------------------------------------------- site and weather
@dataclass(frozen=True)
class Site:
    """An antenna's position on the WGS84 ellipsoid.

    ``latitude_deg`` geodetic, North positive (deg); ``longitude_deg`` East positive (deg);
    ``height_m`` above the ellipsoid (m); ``name`` for reports.
    """

    latitude_deg: float
    longitude_deg: float
    height_m: float
    name: str = ""

    def __post_init__(self) -> None:
        _finite_fields(self, "Site", "latitude_deg", "longitude_deg", "height_m")
        if not -90.0 <= self.latitude_deg <= 90.0:
            raise ValueError(
                f"Site latitude_deg = {self.latitude_deg} is outside -90..90; give the geodetic "
                "latitude in degrees, North positive."
            )
        if not -360.0 <= self.longitude_deg <= 360.0:
            raise ValueError(
                f"Site longitude_deg = {self.longitude_deg} is outside -360..360; give the "
                "longitude in degrees, East positive (Green Bank is -79.84)."
            )
        if not -500.0 <= self.height_m <= 10000.0:
            raise ValueError(
                f"Site height_m = {self.height_m} is not a plausible antenna height; give the "
                "height above the WGS84 ellipsoid in metres."
            )

    @property
    def latitude_rad(self) -> float:
        """Geodetic latitude (rad)."""
        return math.radians(self.latitude_deg)

    @property
    def longitude_rad(self) -> float:
        """Longitude, East positive (rad)."""
        return math.radians(self.longitude_deg)

    def earth_location(self) -> EarthLocation:
        """The site as an astropy ``EarthLocation`` (WGS84), for exact astropy transforms."""
        from astropy import units as u
        from astropy.coordinates import EarthLocation

        return EarthLocation.from_geodetic(
            lon=self.longitude_deg * u.deg, lat=self.latitude_deg * u.deg,
            height=self.height_m * u.m, ellipsoid="WGS84",
        )


#: The NRAO 45-ft (13.7 m) alt-az antenna at Green Bank (at Green Bank since 1988, after its
#: years as the GBI's remote element at Huntersville). No published survey of the 45-ft's
#: own pad was found, so these are DESIGN.md's nominal Green Bank values (latitude +38.43 deg,
#: longitude -79.84 deg, height 800 m), an assumption. The GBT, a few hundred metres away, is
#: published at 38.4331 N, 79.8398 W, about 810-825 m; the nominal values may be off the
#: 45-ft by some 10-20 arcsec of latitude/longitude. That matters only when comparing with
#: real recordings at the arcsecond level: the simulated world and the controller use the
#: same site.
GREEN_BANK_45FT = Site(38.43, -79.84, 800.0, "NRAO Green Bank 45-ft")


def standard_pressure_hpa(height_m: float) -> float:
    """Air pressure of the ICAO standard atmosphere at ``height_m`` metres (hPa).

    About 921 hPa at Green Bank (800 m): the pressure this module's refraction figures assume
    when no barometer reading is given.
    """
    _require_finite(height_m, "height_m")
    return 1013.25 * (1.0 - 2.25577e-5 * float(height_m)) ** 5.25588


@dataclass(frozen=True)
class Weather:
    """Surface weather for refraction: air temperature (deg C), pressure (hPa), relative
    humidity (fraction 0..1, not percent)."""

    temperature_c: float
    pressure_hpa: float
    relative_humidity: float

    def __post_init__(self) -> None:
        _finite_fields(self, "Weather", "temperature_c", "pressure_hpa", "relative_humidity")
        if not -90.0 <= self.temperature_c <= 60.0:
            raise ValueError(
                f"Weather temperature_c = {self.temperature_c} is not a plausible air "
                "temperature; give it in degrees Celsius."
            )
        if not 0.0 <= self.pressure_hpa <= 1100.0:
            raise ValueError(
                f"Weather pressure_hpa = {self.pressure_hpa} is outside 0..1100; give the "
                "station pressure in hPa (about 920 at 800 m; 0 means no atmosphere)."
            )
        if not 0.0 <= self.relative_humidity <= 1.0:
            raise ValueError(
                f"Weather relative_humidity = {self.relative_humidity} is outside 0..1; give "
                "a fraction (0.5 for 50 %), not a percentage."
            )


# --------------------------------------------------------------------------- sources
_SEXAGESIMAL = re.compile(
    r"^\s*([+-]?)\s*(\d+(?:\.\d*)?)\s*[hd:\s]\s*(\d+(?:\.\d*)?)\s*[m:'\s]\s*"
    r"(\d+(?:\.\d*)?)\s*[s\"]?\s*$"
)


def _parse_sexagesimal(text: str, what: str, example: str) -> tuple[float, float, float, float]:
    match = _SEXAGESIMAL.match(str(text))
    if match is None:
        raise ValueError(f"{what} {text!r} is not sexagesimal; write it like {example!r}.")
    sign = -1.0 if match.group(1) == "-" else 1.0
    return sign, float(match.group(2)), float(match.group(3)), float(match.group(4))


def ra_hms_to_deg(text: str) -> float:
    """Right ascension ``"03h16m29.57s"`` (or ``"03:16:29.57"``, ``"03 16 29.57"``) in degrees."""
    sign, hours, minutes, seconds = _parse_sexagesimal(text, "right ascension", "03h16m29.57s")
    if sign < 0 or hours >= 24.0 or minutes >= 60.0 or seconds >= 60.0:
        raise ValueError(f"right ascension {text!r} is out of range; use 00h00m00s..23h59m59.9s.")
    return 15.0 * (hours + minutes / 60.0 + seconds / 3600.0)


def dec_dms_to_deg(text: str) -> float:
    """Declination ``"+41d19m51.9s"`` (or ``"-05:25:16"``, ``"-05 25 16"``) in degrees; the
    sign applies to the whole angle, so ``"-00d30m00s"`` is -0.5."""
    sign, degrees, minutes, seconds = _parse_sexagesimal(text, "declination", "+41d19m51.9s")
    value = sign * (degrees + minutes / 60.0 + seconds / 3600.0)
    if minutes >= 60.0 or seconds >= 60.0 or abs(value) > 90.0:
        raise ValueError(f"declination {text!r} is out of range; use -90d..+90d.")
    return value


@dataclass(frozen=True)
class FixedSource:
    """A source fixed on the sky (no proper motion or parallax: radio sources).

    ``ra_deg``, ``dec_deg`` in degrees in ``frame``: ``"fk4"`` (default; equinox B1950 unless
    ``equinox`` is given), ``"fk5"`` (equinox J2000 unless given) or ``"icrs"``. ``obstime``
    (FK4 only) is the epoch at which an FK4 position was determined; the default is astropy's,
    the equinox (B1950). FK4 rotates slowly relative to inertial frames (Aoki et al. 1983), so
    the same B1950 numbers taken as "observed in 1990" land ~0.1-0.2 arcsec elsewhere.
    Equinox and obstime are strings astropy ``Time`` understands ("B1950", "J2000",
    "1990-02-08").
    """

    name: str
    ra_deg: float
    dec_deg: float
    frame: str = "fk4"
    equinox: str | None = None
    obstime: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError(
                f"source name {self.name!r} is not usable; give every source a non-empty name."
            )
        frame = str(self.frame).strip().lower()
        if frame not in _SUPPORTED_FRAMES:
            raise ValueError(
                f"source {self.name!r}: frame {self.frame!r} is not supported; use 'fk4' "
                "(B1950), 'fk5' (J2000) or 'icrs'."
            )
        object.__setattr__(self, "frame", frame)
        _finite_fields(self, f"source {self.name!r}", "ra_deg", "dec_deg")
        if not 0.0 <= self.ra_deg < 360.0:
            raise ValueError(
                f"source {self.name!r}: ra_deg = {self.ra_deg} is outside 0..360; give the "
                "right ascension in degrees (hours times 15)."
            )
        if not -90.0 <= self.dec_deg <= 90.0:
            raise ValueError(
                f"source {self.name!r}: dec_deg = {self.dec_deg} is outside -90..90; give the "
                "declination in degrees."
            )
        if frame == "icrs" and (self.equinox is not None or self.obstime is not None):
            raise ValueError(
                f"source {self.name!r}: ICRS has no equinox or obstime; leave them unset or "
                "use frame 'fk4'/'fk5'."
            )
        if frame == "fk5" and self.obstime is not None:
            raise ValueError(
                f"source {self.name!r}: obstime only matters for FK4; leave it unset for FK5."
            )

    @classmethod
    def from_sexagesimal(cls, name: str, ra: str, dec: str, frame: str = "fk4",
                         **kwargs: Any) -> FixedSource:
        """A source from ``"03h16m29.57s"``, ``"+41d19m51.9s"`` style strings."""
        return cls(name, ra_hms_to_deg(ra), dec_dms_to_deg(dec), frame, **kwargs)


#: The 8 sources of the Ghigo 8-9 February 1990 run (report Table 1), B1950 FK4.
GHIGO1990_SOURCES: tuple[FixedSource, ...] = tuple(
    FixedSource.from_sexagesimal(name, ra, dec, "fk4")
    for name, ra, dec in (
        ("3C84", "03h16m29.57s", "+41d19m51.9s"),
        ("Taurus A", "05h31m31.40s", "+21d58m54.0s"),
        ("Orion A", "05h32m49.0s", "-05d25m16s"),
        ("3C273", "12h26m33.25s", "+02d19m43.3s"),
        ("Virgo A", "12h28m17.57s", "+12d40m01.7s"),
        ("W31", "18h07m30s", "-19d56m00s"),
        ("Cygnus A", "19h57m44.44s", "+40d35m46.3s"),
        ("Cassiopeia A", "23h21m07.0s", "+58d32m48s"),
    )
)

#: ICRS (ra, dec) in radians of every source converted so far: astropy is asked once per source
_ICRS_CACHE: dict[FixedSource, tuple[float, float]] = {}


def icrs_radec_rad(sources: Sequence[FixedSource]) -> np.ndarray:
    """ICRS right ascension and declination (rad) of ``sources``, shape ``(n, 2)``.

    Converted with astropy (``SkyCoord(...).icrs``), grouped by frame so each group is one
    vectorized call, and cached per source.
    """
    missing = [s for s in dict.fromkeys(sources) if s not in _ICRS_CACHE]
    if missing:
        from astropy import units as u
        from astropy.coordinates import FK4, FK5, ICRS, SkyCoord

        groups: dict[tuple[str, str | None, str | None], list[FixedSource]] = {}
        for source in missing:
            groups.setdefault((source.frame, source.equinox, source.obstime), []).append(source)
        for (frame, equinox, obstime), members in groups.items():
            try:
                if frame == "icrs":
                    astropy_frame = ICRS()
                elif frame == "fk5":
                    astropy_frame = FK5(equinox=equinox or "J2000")
                else:
                    attributes = {"equinox": equinox or "B1950"}
                    if obstime is not None:
                        attributes["obstime"] = obstime
                    astropy_frame = FK4(**attributes)
            except ValueError as err:
                raise ValueError(
                    f"source {members[0].name!r}: equinox {equinox!r} / obstime {obstime!r} "
                    f"is not a time astropy understands ({err}); write e.g. 'B1950' or 'J2000'."
                ) from None
            coords = SkyCoord(
                [m.ra_deg for m in members] * u.deg, [m.dec_deg for m in members] * u.deg,
                frame=astropy_frame,
            ).icrs
            for member, ra, dec in zip(members, coords.ra.rad, coords.dec.rad, strict=True):
                _ICRS_CACHE[member] = (float(ra), float(dec))
    if not sources:
        return np.zeros((0, 2))
    return np.array([_ICRS_CACHE[s] for s in sources], dtype=float)


# --------------------------------------------------------------------------- piecewise cubics
def _hermite_table(values: np.ndarray, step: float) -> np.ndarray:
    """Piecewise-cubic coefficients for samples on a uniform grid along axis 0.

    ``values`` has shape ``(n, ...)`` with ``n >= 5``; returns ``(n, 4, ...)`` holding, per
    interval, the coefficients of s^3, s^2, s, 1 (s = seconds into the interval); the extra
    last row is the linear continuation from the last node, so a time exactly at the grid's
    end needs no clipping. Slopes at the nodes come from 5-point finite differences (4th
    order; one-sided at the two ends), so the interpolant is C1 and its error ~ h^4 f''''/384,
    like a cubic spline's, without a linear solve (and without importing scipy).
    """
    f = values
    d = np.empty_like(f)
    d[2:-2] = (f[:-4] - 8.0 * f[1:-3] + 8.0 * f[3:-1] - f[4:]) / (12.0 * step)
    d[0] = (-25.0 * f[0] + 48.0 * f[1] - 36.0 * f[2] + 16.0 * f[3] - 3.0 * f[4]) / (12.0 * step)
    d[1] = (-3.0 * f[0] - 10.0 * f[1] + 18.0 * f[2] - 6.0 * f[3] + f[4]) / (12.0 * step)
    d[-1] = (25.0 * f[-1] - 48.0 * f[-2] + 36.0 * f[-3] - 16.0 * f[-4] + 3.0 * f[-5]) / (
        12.0 * step
    )
    d[-2] = (3.0 * f[-1] + 10.0 * f[-2] - 18.0 * f[-3] + 6.0 * f[-4] - f[-5]) / (12.0 * step)
    slope = (f[1:] - f[:-1]) / step
    table = np.zeros((f.shape[0], 4, *f.shape[1:]))
    table[:-1, 0] = (d[:-1] + d[1:] - 2.0 * slope) / step**2
    table[:-1, 1] = (3.0 * slope - 2.0 * d[:-1] - d[1:]) / step
    table[:, 2] = d
    table[:, 3] = f
    return table


def _hermite_evaluate(table: np.ndarray, start: float, step: float, t: np.ndarray) -> np.ndarray:
    """Evaluate a :func:`_hermite_table` at times ``t`` (1-d) inside its grid; ``(len(t), ...)``."""
    position = (t - start) / step
    k = position.astype(np.intp)
    s = ((position - k) * step).reshape((-1,) + (1,) * (table.ndim - 2))
    c = table[k]
    return ((c[:, 0] * s + c[:, 1]) * s + c[:, 2]) * s + c[:, 3]


# --------------------------------------------------------------------------- the ephemeris
class Ephemeris:
    """Apparent topocentric positions of fixed sources and the Sun over one campaign.

    ``site``: the antenna's :class:`Site`. ``epoch_utc``: the UTC instant of campaign time 0
    (ISO string such as ``"1990-02-08T00:00:00"`` or an astropy ``Time``). ``duration_s``:
    campaign length (s, >= 0, at most a year). ``sources``: :class:`FixedSource` instances,
    addressed by index in the evaluators (may be empty for a Sun-only ephemeris).
    ``grid_step_s``: spacing of the exact ERFA samples (s, at most 3600). ``margin_s``: the
    evaluators also accept times this far before 0 and after ``duration_s`` (s).

    Evaluators take a source index (int or integer array) and times ``t_s`` (float seconds
    since the epoch, scalar or array, or an astropy Quantity of time); index and times
    broadcast together, and scalars give numpy scalars. Positions are vacuum (no refraction,
    see :func:`refraction_rad`), apparent (precession, nutation, annual and diurnal aberration,
    light deflection, polar motion, UT1) and topocentric.

    Attributes: ``site``, ``sources`` (tuple), ``names`` (tuple of str), ``epoch`` (UTC astropy
    ``Time``), ``duration_s``, ``grid_step_s``, ``margin_s``.
    """

    def __init__(self, site: Site, epoch_utc: str | Time, duration_s: float,
                 sources: Sequence[FixedSource], *, grid_step_s: float = 600.0,
                 margin_s: float = 3600.0):
        if not isinstance(site, Site):
            raise ValueError(
                f"site must be a controller.astro.Site, got {type(site).__name__}; build one "
                "with Site(latitude_deg, longitude_deg, height_m)."
            )
        duration_s = _seconds_value(duration_s, "duration_s")
        grid_step_s = _seconds_value(grid_step_s, "grid_step_s")
        margin_s = _seconds_value(margin_s, "margin_s")
        if duration_s < 0.0:
            raise ValueError(
                f"duration_s = {duration_s} is negative; give the campaign length in seconds "
                "(e.g. 86400 for a day)."
            )
        if duration_s > MAX_DURATION_S:
            raise ValueError(
                f"duration_s = {duration_s} is longer than a year ({MAX_DURATION_S:.0f} s); "
                "split the campaign into shorter ones."
            )
        if not 0.0 < grid_step_s <= MAX_GRID_STEP_S:
            raise ValueError(
                f"grid_step_s = {grid_step_s} is outside (0, {MAX_GRID_STEP_S:.0f}] s; the grid "
                "must resolve the daily terms (600 s is the default)."
            )
        if not 0.0 <= margin_s <= 86400.0:
            raise ValueError(f"margin_s = {margin_s} is outside 0..86400 s; use e.g. 3600.")
        sources = tuple(sources)
        for source in sources:
            if not isinstance(source, FixedSource):
                raise ValueError(
                    f"sources must be FixedSource instances, got {type(source).__name__}; "
                    "build them with FixedSource(name, ra_deg, dec_deg, frame)."
                )
        names = tuple(s.name for s in sources)
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(
                f"source names must be unique; {', '.join(map(repr, duplicates))} appear more "
                "than once."
            )

        self.site = site
        self.sources: tuple[FixedSource, ...] = sources
        self.names: tuple[str, ...] = names
        self.epoch: Time = _utc_instant(epoch_utc)
        self.duration_s = duration_s
        self.grid_step_s = grid_step_s
        self.margin_s = margin_s
        self._t_lo = -margin_s
        self._t_hi = duration_s + margin_s
        n_steps = max(math.ceil((self._t_hi - self._t_lo) / grid_step_s - 1e-9), 4)
        self._grid_start_s = self._t_lo
        self._inverse_step = 1.0 / grid_step_s
        self._sin_lat = math.sin(site.latitude_rad)
        self._cos_lat = math.cos(site.latitude_rad)
        self._sun_index = len(sources)
        grid_s = self._grid_start_s + grid_step_s * np.arange(n_steps + 1)
        ha_rad, dec_rad = self._exact_hadec(grid_s)
        # hour angle minus the Earth's rotation is smooth (slow precession-nutation, annual and
        # diurnal aberration, polar motion, UT1 drift); unwrap removes the 2 pi jumps
        residual = np.unwrap(ha_rad - SIDEREAL_RATE_RAD_S * grid_s, axis=1)
        samples = np.stack([residual, dec_rad], axis=-1).transpose(1, 0, 2)  # (grid, body, 2)
        # rows (body x interval, power, quantity): one gather per evaluation; each body's
        # last row continues its last node, for a time exactly at the grid's end
        table = _hermite_table(samples, grid_step_s)  # (row, power, body, quantity)
        self._rows_per_body = table.shape[0]
        self._coef = np.ascontiguousarray(table.transpose(2, 0, 1, 3)).reshape(
            (-1, 4, 2)
        )

    # ------------------------------------------------------------------ exact samples (ERFA)
    def _exact_hadec(self, grid_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact apparent topocentric (HA, Dec) in rad at ``grid_s``, shape (bodies, grid);
        the last body is the Sun."""
        import erfa
        from astropy.time import TimeDelta

        site = self.site
        times = self.epoch + TimeDelta(grid_s, format="sec")
        ut1 = _ut1(times)
        xp, yp = _polar_motion_rad(times)
        epoch_tt = self.epoch.tt
        tt1 = np.full(grid_s.shape, epoch_tt.jd1)
        tt2 = epoch_tt.jd2 + grid_s / 86400.0  # TT runs in SI seconds, like campaign time

        # precession-nutation (CIP X, Y, CIO locator s) and the Earth's barycentric and
        # heliocentric state: costly, slow, so sampled every 3 h and interpolated
        n_support = max(math.ceil((grid_s[-1] - grid_s[0]) / _SUPPORT_STEP_S), 4) + 1
        support_s = grid_s[0] + _SUPPORT_STEP_S * np.arange(n_support)
        sup1 = np.full(support_s.shape, epoch_tt.jd1)
        sup2 = epoch_tt.jd2 + support_s / 86400.0
        cip_x, cip_y = erfa.bpn2xy(erfa.pnm06a(sup1, sup2))
        cio_s = erfa.s06(sup1, sup2, cip_x, cip_y)
        # TT for TDB: the difference (< 2 ms) moves the Earth by < 60 m
        helio, bary = erfa.epv00(sup1, sup2)
        support = np.column_stack([cip_x, cip_y, cio_s, bary["p"], bary["v"], helio["p"],
                                   helio["v"]])
        slow = _hermite_evaluate(_hermite_table(support, _SUPPORT_STEP_S), support_s[0],
                                 _SUPPORT_STEP_S, grid_s)
        earth_pv = np.zeros(grid_s.shape, dtype=erfa.dt_pv)
        earth_pv["p"] = slow[:, 3:6]
        earth_pv["v"] = slow[:, 6:9]
        earth_helio_p = slow[:, 9:12]
        sun_bary_p = slow[:, 3:6] - slow[:, 9:12]
        sun_bary_v = slow[:, 6:9] - slow[:, 12:15]

        astrom = erfa.apco(
            tt1, tt2, earth_pv, earth_helio_p, slow[:, 0], slow[:, 1], slow[:, 2],
            erfa.era00(ut1[0], ut1[1]), site.longitude_rad, site.latitude_rad, site.height_m,
            xp, yp, erfa.sp00(tt1, tt2), 0.0, 0.0,
        )

        # fixed sources: ICRS -> topocentric CIRS (light deflection, aberration, bias-
        # precession-nutation), as astropy's ICRS -> AltAz does
        radec = icrs_radec_rad(self.sources)
        cirs_ra, cirs_dec = erfa.atciqz(radec[:, :1], radec[:, 1:], astrom[None, :])

        # the Sun: geometric direction from the observer, corrected for light time (the Sun
        # moves ~0.01" in 8 min about the barycentre), then annual aberration and rotation to
        # CIRS; no light deflection by the Sun itself
        sun_vector = sun_bary_p - astrom["eb"]
        light_time_day = np.linalg.norm(sun_vector, axis=1) * _LIGHT_TIME_DAY_PER_AU
        sun_vector = sun_vector - sun_bary_v * light_time_day[:, None]
        sun_natural = sun_vector / np.linalg.norm(sun_vector, axis=1)[:, None]
        sun_proper = erfa.ab(sun_natural, astrom["v"], astrom["em"], astrom["bm1"])
        sun_cirs = np.einsum("nij,nj->ni", astrom["bpn"], sun_proper)
        sun_ra, sun_dec = erfa.c2s(sun_cirs)

        all_ra = np.vstack([cirs_ra, sun_ra[None, :]])
        all_dec = np.vstack([cirs_dec, sun_dec[None, :]])
        # CIRS -> observed: Earth rotation, polar motion, diurnal aberration (no refraction)
        _az, _zd, ha_rad, dec_rad, _ra = erfa.atioq(all_ra, all_dec, astrom[None, :])
        return ha_rad, dec_rad

    # ------------------------------------------------------------------ fast evaluation
    def _check_index(self, index: Any) -> int | np.ndarray:
        n = len(self.sources)
        if isinstance(index, int | np.integer) and not isinstance(index, bool):
            if 0 <= index < n:
                return int(index)
            raise ValueError(
                f"source index {index} is out of range; this ephemeris has {n} sources "
                f"(0..{n - 1}); use Ephemeris.index(name) to look one up."
            )
        array = np.asarray(index)
        if array.dtype.kind not in "iu":
            raise ValueError(
                f"source index must be an integer or an integer array, got {index!r}; use "
                "Ephemeris.index(name) to look one up."
            )
        if array.size and (array.min() < 0 or array.max() >= n):
            raise ValueError(
                f"source index out of range (min {array.min()}, max {array.max()}); this "
                f"ephemeris has {n} sources (0..{n - 1})."
            )
        return array

    def _check_times(self, t_s: Any) -> np.ndarray:
        if hasattr(t_s, "unit"):  # astropy Quantity at the API boundary: convert, never guess
            t_s = t_s.to_value("s")
        t = np.asarray(t_s, dtype=float)
        if t.size == 0:
            return t
        t_min, t_max = (float(t), float(t)) if t.ndim == 0 else (t.min(), t.max())
        if not (self._t_lo <= t_min and t_max <= self._t_hi):  # written so NaN fails too
            raise ValueError(
                f"time {t_min if not self._t_lo <= t_min else t_max} s is outside this "
                f"ephemeris ({self._t_lo:g}..{self._t_hi:g} s: the campaign of "
                f"{self.duration_s:g} s plus a {self.margin_s:g} s margin); build the Ephemeris "
                "with a longer duration_s or margin_s."
            )
        return t

    def _evaluate(self, body: int | np.ndarray, t: np.ndarray, derivative: bool = False):
        """Interpolated (HA, Dec) in rad as the columns of an ``(N, 2)`` array over the
        flattened broadcast of ``body`` and ``t``, that broadcast's shape, and with
        ``derivative`` the rates (rad/s) likewise.

        This is the hot path: a handful of numpy calls on small arrays, no Python loops.
        """
        if isinstance(body, int):
            shape = t.shape
            t_flat = t.reshape(-1)
        else:
            shape = np.broadcast_shapes(body.shape, t.shape)
            t_flat = np.broadcast_to(t, shape).reshape(-1)
            body = np.broadcast_to(body, shape).reshape(-1)
        position = (t_flat - self._grid_start_s) * self._inverse_step
        k = position.astype(np.intp)  # times were checked: 0 <= position <= intervals
        s = ((position - k) * self.grid_step_s)[:, None]
        # ndarray.take is several times faster than fancy indexing on small arrays
        c = self._coef.take(k + body * self._rows_per_body, axis=0)
        value = c[:, 0] * s
        value += c[:, 1]
        value *= s
        value += c[:, 2]
        value *= s
        value += c[:, 3]
        value[:, 0] += SIDEREAL_RATE_RAD_S * t_flat
        if not derivative:
            return value, shape
        rate = 3.0 * c[:, 0] * s
        rate += 2.0 * c[:, 1]
        rate *= s
        rate += c[:, 2]
        rate[:, 0] += SIDEREAL_RATE_RAD_S
        return value, shape, rate

    def _horizon(self, hadec: np.ndarray):
        """Exact spherical trigonometry (as erfa.hd2ae) from (HA, Dec) columns: the unit
        vector's south, east and up components, and the sines and cosines used."""
        sines = np.sin(hadec)
        cosines = np.cos(hadec)
        sin_ha, sin_dec = sines[:, 0], sines[:, 1]
        cos_ha, cos_dec = cosines[:, 0], cosines[:, 1]
        cos_dec_cos_ha = cos_dec * cos_ha
        east = -cos_dec * sin_ha
        south = cos_dec_cos_ha * self._sin_lat - sin_dec * self._cos_lat
        up = sin_dec * self._sin_lat + cos_dec_cos_ha * self._cos_lat
        return south, east, up, (sin_ha, cos_ha, sin_dec, cos_dec)

    def altaz_rad(self, index: int | np.ndarray, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Vacuum apparent topocentric azimuth (N = 0, E = pi/2, in [0, 2 pi)) and elevation
        (rad) of source ``index`` at ``t_s`` (s since the epoch)."""
        hadec, shape = self._evaluate(self._check_index(index), self._check_times(t_s))
        south, east, up, _ = self._horizon(hadec)
        return _az_el(south, east, up, shape)

    def hadec_rad(self, index: int | np.ndarray, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Vacuum apparent topocentric hour angle (positive West, in [-pi, pi)) and
        declination (rad) of source ``index`` at ``t_s`` (s), for equatorial mounts."""
        hadec, shape = self._evaluate(self._check_index(index), self._check_times(t_s))
        ha = np.remainder(hadec[:, 0] + math.pi, TWO_PI)
        np.minimum(ha, _BELOW_TWO_PI, out=ha)  # a remainder can round up to 2 pi itself
        ha -= math.pi
        return _scalar(ha.reshape(shape)), _scalar(hadec[:, 1].reshape(shape))

    def rates_rad_s(self, index: int | np.ndarray, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Rates d(az)/dt and d(el)/dt (rad/s) of source ``index`` at ``t_s`` (s): analytic
        derivatives of the interpolant. The azimuth rate is the axis rate (not multiplied by
        cos el) and diverges at the zenith (inf or nan exactly there)."""
        hadec, shape, rate = self._evaluate(
            self._check_index(index), self._check_times(t_s), derivative=True
        )
        south, east, up, (sin_ha, cos_ha, sin_dec, cos_dec) = self._horizon(hadec)
        ha_rate, dec_rate = rate[:, 0], rate[:, 1]
        s_lat, c_lat = self._sin_lat, self._cos_lat
        d_south = -(cos_dec * c_lat + sin_dec * cos_ha * s_lat) * dec_rate - (
            cos_dec * sin_ha * s_lat * ha_rate
        )
        d_east = sin_dec * sin_ha * dec_rate - cos_dec * cos_ha * ha_rate
        d_up = (cos_dec * s_lat - sin_dec * cos_ha * c_lat) * dec_rate - (
            cos_dec * sin_ha * c_lat * ha_rate
        )
        horizontal_sq = south * south + east * east
        with np.errstate(divide="ignore", invalid="ignore"):
            # az = atan2(east, north) with north = -south
            az_rate = (east * d_south - south * d_east) / horizontal_sq
            el_rate = (horizontal_sq * d_up - up * (south * d_south + east * d_east)) / (
                np.sqrt(horizontal_sq) * (horizontal_sq + up * up)
            )
        return _scalar(az_rate.reshape(shape)), _scalar(el_rate.reshape(shape))

    def sun_altaz_rad(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Vacuum apparent topocentric azimuth and elevation of the Sun's centre (rad) at
        ``t_s`` (s); agrees with astropy ``get_body("sun")`` to a few milli-arcseconds."""
        hadec, shape = self._evaluate(self._sun_index, self._check_times(t_s))
        south, east, up, _ = self._horizon(hadec)
        return _az_el(south, east, up, shape)

    def index(self, name: str) -> int:
        """Index of the source called ``name``."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(
                f"no source called {name!r} in this ephemeris; known: {', '.join(self.names)}."
            ) from None

    def time(self, t_s) -> Time:
        """The UTC astropy ``Time`` of campaign time(s) ``t_s`` (s), for reports."""
        from astropy.time import TimeDelta

        if hasattr(t_s, "unit"):
            t_s = t_s.to_value("s")
        return self.epoch + TimeDelta(np.asarray(t_s, dtype=float), format="sec")

    def __repr__(self) -> str:
        return (
            f"Ephemeris(site={self.site.name or self.site}, epoch={self.epoch.isot}, "
            f"duration_s={self.duration_s:g}, sources={list(self.names)})"
        )


def _az_el(south, east, up, shape) -> tuple[np.ndarray, np.ndarray]:
    """Azimuth in [0, 2 pi) (N = 0, E = pi/2) and elevation (rad), reshaped to ``shape``."""
    # atan2(east, north) = atan2(-east, south) + pi lies in (0, 2 pi]; the one value outside
    # the half-open range (2 pi, due north) becomes the double just below it
    az = np.arctan2(-east, south)
    az += math.pi
    np.minimum(az, _BELOW_TWO_PI, out=az)
    el = np.arctan2(up, np.hypot(south, east))
    return _scalar(az.reshape(shape)), _scalar(el.reshape(shape))


def _scalar(array: np.ndarray):
    """0-d arrays become numpy scalars; other arrays pass through."""
    return array[()] if np.ndim(array) == 0 else array


# --------------------------------------------------------------------------- refraction
@lru_cache(maxsize=256)
def _refraction_constants(pressure_hpa: float, temperature_c: float, relative_humidity: float,
                          wavelength_um: float) -> tuple[float, float]:
    import erfa

    refa, refb = erfa.refco(pressure_hpa, temperature_c, relative_humidity, wavelength_um)
    return float(refa), float(refb)


def refraction_rad(el_vacuum_rad, weather: Weather, *,
                   frequency_ghz: float | None = None) -> np.ndarray:
    """Elevation increase due to atmospheric refraction (rad): observed = vacuum + this.

    ``el_vacuum_rad``: vacuum (unrefracted) elevation(s) in rad. ``weather``: surface
    :class:`Weather`. ``frequency_ghz``: observing frequency; ``None`` means radio. Radio
    refraction (any frequency below 3000 GHz, i.e. wavelengths above 100 um) does not depend
    on frequency; above that ERFA's optical formula for that wavelength is used.

    The model is ERFA's (``erfa.refco`` A tan z + B tan^3 z, inverted as in ``eraAtioq``), the
    one astropy's ``AltAz`` uses with pressure, temperature, humidity and ``obswl``: at 10 C,
    50 % humidity, 920 hPa it gives 5.29' at 10 deg, 2.63' at 20 deg, 0.965' at 45 deg
    (DESIGN: 5.3', 2.6', 0.97'). Below about 3 deg elevation (ERFA's limit) the bending is
    held near its 3 deg value (about 11.5' at 920 hPa); the model is not meant for the horizon.
    """
    if not isinstance(weather, Weather):
        raise ValueError(
            f"weather must be a controller.astro.Weather, got {type(weather).__name__}; build "
            "one with Weather(temperature_c, pressure_hpa, relative_humidity)."
        )
    if frequency_ghz is None:
        wavelength_um = _RADIO_WAVELENGTH_UM
    else:
        frequency = float(frequency_ghz)
        if not (math.isfinite(frequency) and frequency > 0.0):
            raise ValueError(
                f"frequency_ghz = {frequency_ghz} must be a positive number of GHz (8.4 for "
                "X-band), or None for radio."
            )
        wavelength_um = _SPEED_OF_LIGHT_UM_GHZ / frequency
    refa, refb = _refraction_constants(weather.pressure_hpa, weather.temperature_c,
                                       weather.relative_humidity, wavelength_um)
    el = np.asarray(el_vacuum_rad, dtype=float)
    sin_el = np.sin(el)
    cos_el_true = np.cos(el)
    cos_el = np.maximum(cos_el_true, _CELMIN)
    sin_el_clamped = np.maximum(sin_el, _SELMIN)
    tan_z = cos_el / sin_el_clamped
    w = refb * tan_z * tan_z
    # A tan z + B tan^3 z evaluated at the observed zenith distance by one Newton step
    delta = (refa + w) * tan_z / (1.0 + (refa + 3.0 * w) / (sin_el_clamped * sin_el_clamped))
    cos_delta = 1.0 - 0.5 * delta * delta
    horizontal = cos_el_true * np.abs(cos_delta - delta * sin_el_clamped / cos_el)
    up = cos_delta * sin_el + delta * cos_el
    return _scalar(np.arctan2(up, horizontal) - el)


# --------------------------------------------------------------------------- sunrise, sunset
def _sun_crossings_s(ephemeris: Ephemeris, horizon_deg: float, rising: bool) -> np.ndarray:
    _require_finite(horizon_deg, "horizon_deg")
    if not isinstance(ephemeris, Ephemeris):
        raise ValueError(f"expected an Ephemeris, got {type(ephemeris).__name__}.")
    horizon = math.radians(horizon_deg)
    # 5-minute scan: the Sun's elevation changes by at most ~1.25 deg in that time, so only
    # grazing passes (polar sites) could hide two crossings in one step
    n = max(math.ceil(ephemeris.duration_s / 300.0), 1)
    t = np.linspace(0.0, ephemeris.duration_s, n + 1)
    above = ephemeris.sun_altaz_rad(t)[1] >= horizon
    steps = np.flatnonzero(above[1:] & ~above[:-1] if rising else above[:-1] & ~above[1:])
    lo, hi = t[steps], t[steps + 1]
    for _ in range(40):  # bisection to well below a millisecond
        mid = 0.5 * (lo + hi)
        mid_above = ephemeris.sun_altaz_rad(mid)[1] >= horizon
        after = mid_above if rising else ~mid_above
        hi = np.where(after, mid, hi)
        lo = np.where(after, lo, mid)
    return 0.5 * (lo + hi)


def sunset_times_s(ephemeris: Ephemeris, *, horizon_deg: float = -0.833) -> np.ndarray:
    """Times (s since the epoch) at which the Sun's centre sets inside [0, duration].

    The event is the vacuum elevation of the Sun's centre crossing ``horizon_deg`` downward;
    the default -0.833 deg is the almanac sunset (upper limb on the horizon: 16' semidiameter
    plus 34' standard refraction); use 0 for the geometric centre. Accurate to well under a
    second.
    """
    return _sun_crossings_s(ephemeris, horizon_deg, rising=False)


def sunrise_times_s(ephemeris: Ephemeris, *, horizon_deg: float = -0.833) -> np.ndarray:
    """Times (s since the epoch) at which the Sun's centre rises inside [0, duration]: the
    upward crossing of ``horizon_deg`` (see :func:`sunset_times_s`)."""
    return _sun_crossings_s(ephemeris, horizon_deg, rising=True)


# --------------------------------------------------------------------------- helpers
def _utc_instant(epoch_utc: Any) -> Time:
    from astropy.time import Time

    if isinstance(epoch_utc, Time):
        epoch = epoch_utc
    else:
        try:
            epoch = Time(epoch_utc, scale="utc")
        except (ValueError, TypeError):
            raise ValueError(
                f"epoch_utc = {epoch_utc!r} is not a time astropy can read; write an ISO UTC "
                "time such as '1990-02-08T00:00:00'."
            ) from None
    if not epoch.isscalar:
        raise ValueError("epoch_utc must be a single instant, not an array of times.")
    return epoch.utc


def _ut1(times: Time) -> tuple[np.ndarray, np.ndarray]:
    """UT1 as two-part Julian dates, exactly as astropy's transforms obtain it."""
    from astropy.utils import iers

    _offline.use_cached_eop_table()
    try:
        ut1 = times.ut1
    except iers.IERSRangeError as err:  # astropy's own transforms fall back the same way
        warnings.warn(f"{err} Assuming UT1-UTC = 0.", stacklevel=4)
        ut1 = times
    return ut1.jd1, ut1.jd2


def _polar_motion_rad(times: Time) -> tuple[np.ndarray, np.ndarray]:
    """Polar motion (xp, yp) in rad from the IERS tables, with astropy's fallback (the
    50-year mean) outside them, so positions match astropy's transforms."""
    from astropy import units as u
    from astropy.utils import iers

    _offline.use_cached_eop_table()
    xp, yp, status = iers.earth_orientation_table.get().pm_xy(times, return_status=True)
    xp = np.array(xp.to_value(u.rad), dtype=float, ndmin=1)
    yp = np.array(yp.to_value(u.rad), dtype=float, ndmin=1)
    outside = np.isin(status, (iers.TIME_BEFORE_IERS_RANGE, iers.TIME_BEYOND_IERS_RANGE))
    if np.any(outside):
        xp[outside] = math.radians(_DEFAULT_POLAR_MOTION_ARCSEC[0] / 3600.0)
        yp[outside] = math.radians(_DEFAULT_POLAR_MOTION_ARCSEC[1] / 3600.0)
        warnings.warn(
            "Some campaign times are outside the bundled IERS tables; using the 50-year mean "
            "polar motion there (arcsecond-level error). Update astropy-iers-data for newer "
            "dates.",
            stacklevel=4,
        )
    return xp, yp
