"""The ephemeris: apparent topocentric positions of fixed radio sources and the Sun, fast.

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
(``benchmarks/ephemeris.py``, ``tests/controller/astro/test_ephemeris.py``); one ``altaz_rad``
call costs tens of microseconds.

Conventions: angles in radians unless the name says otherwise; azimuth from North through
East (N = 0, E = pi/2) in [0, 2 pi); hour angle positive West; times are float seconds since the
campaign epoch, a UTC instant (SI seconds, so leap seconds are handled by astropy ``Time``).
astropy ``Time`` appears only at this module's edges (``epoch``, :meth:`Ephemeris.time`).

The site is a :class:`~controller.astro.site.Site`, the sources
:class:`~controller.astro.sources.FixedSource` s; refraction is added by
:func:`~controller.astro.refraction.refraction_rad`, sunrise and sunset found by
:mod:`controller.astro.sun`.

Offline: IERS auto-download is off (:mod:`controller.astro.offline`); the bundled
``astropy-iers-data`` tables are used. astropy.coordinates (most of a second) and erfa are
imported inside functions so that importing this module stays cheap.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import erfa
import numpy as np
from astropy.time import TimeDelta

from .earth import polar_motion_rad, ut1_two_part, utc_instant
from .hermite import hermite_evaluate, hermite_table
from .site import Site
from .sources import FixedSource
from .values import scalar, seconds_value

if TYPE_CHECKING:
    from astropy.time import Time

__all__ = ["MAX_GRID_STEP_S", "SIDEREAL_RATE_RAD_S", "Ephemeris", "icrs_radec_rad"]

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
_LIGHT_TIME_DAY_PER_AU = 499.004783836 / 86400.0  # light time for 1 au (day)

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
    see :func:`~controller.astro.refraction.refraction_rad`), apparent (precession, nutation, annual
    and diurnal aberration, light deflection, polar motion, UT1) and topocentric.

    Attributes: ``site``, ``sources`` (tuple), ``names`` (tuple of str), ``epoch`` (UTC astropy
    ``Time``), ``duration_s``, ``grid_step_s``, ``margin_s``.
    """

    def __init__(self, site: Site, epoch_utc: str | Time, duration_s: float,
                 sources: Sequence[FixedSource], *, grid_step_s: float = 600.0,
                 margin_s: float = 3600.0):
        if not isinstance(site, Site):
            raise ValueError(
                f"site must be a controller.astro.site.Site, got {type(site).__name__}; build one "
                "with Site(latitude_deg, longitude_deg, height_m)."
            )
        duration_s = seconds_value(duration_s, "duration_s")
        grid_step_s = seconds_value(grid_step_s, "grid_step_s")
        margin_s = seconds_value(margin_s, "margin_s")
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
        self.epoch: Time = utc_instant(epoch_utc)
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
        table = hermite_table(samples, grid_step_s)  # (row, power, body, quantity)
        self._rows_per_body = table.shape[0]
        self._coef = np.ascontiguousarray(table.transpose(2, 0, 1, 3)).reshape(
            (-1, 4, 2)
        )

    # ------------------------------------------------------------------ exact samples (ERFA)
    def _exact_hadec(self, grid_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact apparent topocentric (HA, Dec) in rad at ``grid_s``, shape (bodies, grid);
        the last body is the Sun."""
        site = self.site
        times = self.epoch + TimeDelta(grid_s, format="sec")
        ut1 = ut1_two_part(times)
        xp, yp = polar_motion_rad(times)
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
        slow = hermite_evaluate(hermite_table(support, _SUPPORT_STEP_S), support_s[0],
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
        return scalar(ha.reshape(shape)), scalar(hadec[:, 1].reshape(shape))

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
        return scalar(az_rate.reshape(shape)), scalar(el_rate.reshape(shape))

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
    return scalar(az.reshape(shape)), scalar(el.reshape(shape))
