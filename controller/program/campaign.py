"""The control program: a pointing campaign as one simpy process.

Loop until the campaign window ends: ask the scheduler for the next source, compute its
trajectory (apparent place, the controller's refraction, the pointing model in use and any
running correction), run a five-point cross scan, reduce it, and record one row per
polarization. When a scan misses its source (large errors, e.g. a cold start with no model:
the 45-ft's azimuth encoder offset alone, 12.24', is 11.5' on the sky at 20 deg elevation,
more than the beam) the controller searches with a wider cross, adopts what it finds as a
running correction, and scans again. The running correction is an offset on the sky
(cross-elevation, elevation; ``search.correction = "sky"``) or of the two encoders
(``"encoders"``, as the errors of a cold start of the 45-ft are: an encoder zero offset): then
a cross-elevation offset x found at elevation E is the azimuth offset x / cos E, applied to
every later source as x cos E' / cos E on the sky at its elevation E'.

It uses only the protocol (:mod:`controller.protocol`) and its own configuration.

Beyond the 45-ft of 1990: on an equatorial mount (``config.mount``) trajectories, scan axes,
model and running correction are in hour angle and declination and each row also records
``ha_deg``/``dec_deg``; with ``config.feed_angles_deg`` the feed box is turned to the next
angle before each scan and the row records ``feed_angle_deg``; with ``config.tipping`` tipping
scans (:mod:`controller.scans.tipping`) measure the zenith opacity at intervals, and each scan is
reduced after removing the sky emission they predict, T_atm (1 - exp(-tau / sin E)), from
every integration (its recorded raw powers are kept as measured): neither five-point baseline
can carry both the emission's slope across an elevation scan and its drift in time as the
source rises, and on an equatorial mount both scans cross the slope. Without tipping scans
an a-priori atmosphere (``config.sky``) can play their part.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from controller.astro.ephemeris import Ephemeris
from controller.astro.frames import MountFrame
from controller.astro.site import Site, Weather
from controller.astro.sources import FixedSource
from controller.pointing.thermal import structure_column, structure_time_column
from controller.protocol import Antenna, AntennaError
from controller.scans.reduction import Flag
from controller.scans.scan import AXES, RawScan, ReducedScan, cross_scan, reduce_scan
from controller.scans.tipping import tipping_scan
from controller.scans.tracking import RefractionCorrection, SourceTrajectory, standard_weather
from controller.units import ARCMIN_PER_RAD

from .config import ControllerConfig
from .observer import Observer, Target
from .scheduler import make_scheduler

__all__ = ["ControlProgram", "ScanOutcome", "plan_targets"]

#: the controller's ephemeris reaches this far past the window (scans running at its end)
EPHEMERIS_MARGIN_S = 3600.0
#: flags that do not invalidate a search detection (wide steps distort the width estimate)
SEARCH_TOLERATED = Flag.WIDTH_INCONSISTENT
FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))


@dataclass
class ScanOutcome:
    """One recorded scan: the raw data, its reduction and the rows written."""

    target: Target
    reduced: ReducedScan
    rows: list[dict]
    searches: int
    #: the sky emission subtracted before the reduction (K; axes, positions, channels)
    sky_k: np.ndarray | None = None


def plan_targets(config: ControllerConfig,
                 ephemeris: Ephemeris | None = None) -> tuple[Observer, list[Target]]:
    """The controller's view of the sky for ``config``: its observer and its targets."""
    if ephemeris is None:
        site = Site(config.site_latitude_deg, config.site_longitude_deg, config.site_height_m,
                    config.site_name)
        sources = tuple(FixedSource(s.name, s.ra_deg, s.dec_deg, s.frame)
                        for s in config.sources)
        ephemeris = Ephemeris(site, config.epoch_utc, config.duration_s + EPHEMERIS_MARGIN_S,
                              sources)
    names = config.scheduler.sources or tuple(s.name for s in config.sources)
    all_names = [s.name for s in config.sources]
    return (Observer(ephemeris, config.night_sun_max_deg),
            [Target(n, all_names.index(n)) for n in names])


class ControlProgram:
    """The 1990-style pointing program, driving any :class:`~controller.protocol.Antenna`."""

    def __init__(self, config: ControllerConfig, antenna: Antenna,
                 sink: Callable[[list[dict]], None] | None = None,
                 progress: Callable[[float], None] | None = None,
                 ephemeris: Ephemeris | None = None):
        self.config = config
        self.antenna = antenna
        self.sink = sink
        self.progress = progress
        self.observer, self.targets = plan_targets(config, ephemeris)
        self.ephemeris = self.observer.ephemeris
        self.frame = MountFrame(config.mount, config.site_latitude_deg)
        self.scan_duration_s = self._scan_duration_s()
        #: scan settings per target: the assumed width follows the catalogued source size
        self.scan_for = {t.name: replace(config.scan,
                                         hpbw_arcmin=config.reduction_width_arcmin(t.name))
                         for t in self.targets}
        self.scheduler = make_scheduler(config.scheduler, self.observer, self.targets,
                                        self.scan_duration_s)
        #: the running correction (arcmin): on the sky (cross-elevation, elevation) or, with
        #: ``search.correction = "encoders"``, of the encoders (azimuth or hour angle, and
        #: elevation or declination)
        self.running_correction_arcmin = (0.0, 0.0)
        self.outcomes: list[ScanOutcome] = []
        self.scan_number = 0
        self.searches = 0
        self.misses = 0
        self._standard = standard_weather(config.site_height_m)
        #: tipping scans made (controller.tipping.Tipping), and when the next is due (s)
        self.tippings: list = []
        self._next_tipping_s = 0.0 if config.tipping is not None else math.inf
        #: the feed angle last commanded (deg), None before the first
        self.feed_angle_deg: float | None = None

    def _scan_duration_s(self) -> float:
        """Time one observation takes, for the scheduler's look-ahead (s)."""
        scan = self.config.scan
        n_pos = len(scan.offsets_n)
        return 2 * n_pos * (scan.integration_s + 6.0) + scan.overhead_s

    # ------------------------------------------------------------------ helpers
    def refraction(self) -> RefractionCorrection:
        mode = self.config.refraction
        if mode == "weather":
            w = self.antenna.weather()
            weather = Weather(w.temperature_c, w.pressure_hpa, w.relative_humidity)
        elif mode == "standard":
            weather = self._standard
        else:
            weather = None
        return RefractionCorrection(mode, weather, self.config.frequency_ghz)

    def trajectory(self, target: Target, t_s: float) -> SourceTrajectory:
        feed = None if self.feed_angle_deg is None else math.radians(self.feed_angle_deg)
        return SourceTrajectory(self.ephemeris, target.index, self.config.model,
                                self.refraction(), t_s, self.correction_arcmin(target, t_s),
                                frame=self.frame, feed_rad=feed)

    def correction_arcmin(self, target: Target, t_s: float) -> tuple[float, float]:
        """The running correction on the sky at ``target`` at ``t_s``: (cross-elevation,
        elevation) arcmin (cross-declination and declination on an equatorial mount); an
        encoders' correction's azimuth offset times the cosine of the source's elevation."""
        d_lon, d_lat = self.running_correction_arcmin
        if self.config.search.correction == "encoders":
            d_lon *= self._cos_lat(target, t_s)
        return d_lon, d_lat

    def _cos_lat(self, target: Target, t_s: float) -> float:
        az, el = self.ephemeris.altaz_rad(target.index, float(t_s))
        if not self.frame.is_altaz:
            _, el = self.frame.from_altaz(az, el)
        return max(math.cos(float(el)), 1e-3)

    def _adopt(self, target: Target, t_s: float, xel_arcmin: float, el_arcmin: float) -> None:
        """Add a sky offset found at ``target`` at ``t_s`` to the running correction."""
        if self.config.search.correction == "encoders":
            xel_arcmin /= self._cos_lat(target, t_s)
        d_lon, d_lat = self.running_correction_arcmin
        self.running_correction_arcmin = (d_lon + xel_arcmin, d_lat + el_arcmin)

    def position_altaz_deg(self) -> tuple[float, float]:
        """The encoder position as azimuth and elevation (deg), for the scheduler."""
        lon, lat = self.antenna.encoder_deg()
        return self.frame.to_altaz_deg(lon, lat)

    # ------------------------------------------------------------------ the campaign
    def run(self, env):
        """simpy process: the whole campaign."""
        end = self.config.duration_s
        while True:
            now = self.antenna.clock_s()
            if self.progress:
                self.progress(now)
            if now + self.scan_duration_s > end:
                break
            if now >= self._next_tipping_s:
                self._next_tipping_s = now + self.config.tipping.interval_s
                tip = yield env.process(tipping_scan(env, self.antenna, self.config.tipping,
                                                     self.frame, self.observer, self.targets,
                                                     self.config.scheduler.hour_angle_limit_deg))
                if tip is not None:
                    self.tippings.append(tip)
                continue
            target = self.scheduler.next_target(now + 30.0, self.position_altaz_deg())
            if target is None:
                yield self.antenna.wait(60.0)
                continue
            try:
                outcome = yield env.process(self.observe(env, target))
            except AntennaError:
                # the target left the limits while we slewed: let the revisit rule skip it
                self.scheduler.record(now, target)
                continue
            if outcome is not None:
                self.outcomes.append(outcome)
        if self.progress:
            self.progress(end)

    def observe(self, env, target: Target):
        """simpy process: scan ``target`` (searching if it is missed) and record it."""
        if self.config.feed_angles_deg:
            angles = self.config.feed_angles_deg
            angle = float(angles[self.scan_number % len(angles)])
            if angle != self.feed_angle_deg:
                yield self.antenna.set_feed_angle(angle)
                self.feed_angle_deg = angle
        before = self.antenna.encoder_deg()
        searches = 0
        scan = self.scan_for[target.name]
        while True:
            traj = self.trajectory(target, self.antenna.clock_s())
            raw = yield env.process(cross_scan(env, self.antenna, traj, scan,
                                               label=target.name,
                                               structure=bool(self.config.structure_sensors)))
            sky_k = self.sky_emission_k(raw)
            reduced = reduce_scan(self.sky_corrected(raw, sky_k), scan)
            reduced.raw = raw
            if self._detected(reduced, tolerated=Flag(0)) or searches >= 2 \
                    or not self.config.search.enabled:
                break
            if self.antenna.clock_s() + self.scan_duration_s > self.config.duration_s:
                break  # no time left in the campaign for a search and a scan after it
            found = yield env.process(self.search(env, target))
            searches += 1
            if not found:
                break
        if not self._detected(reduced, tolerated=Flag(0)):
            self.misses += 1
        self.scheduler.record(raw.t_mid_s, target)
        rows = self.rows(target, traj, reduced, before)
        if self.sink:
            self.sink(rows)
        self.scan_number += 1
        gain = self.config.search.update_gain
        if gain > 0 and self._detected(reduced, tolerated=Flag(0)):
            avg = reduced.axes
            self._adopt(target, raw.t_mid_s, gain * float(avg["az"].offset_arcmin[-1]),
                        gain * float(avg["el"].offset_arcmin[-1]))
        return ScanOutcome(target, reduced, rows, searches, sky_k)

    def search(self, env, target: Target):
        """simpy process: a wide cross scan; adopt the offsets it finds. Returns found axes.

        Each half of the cross is made at zero offset in the other axis, so it passes the
        source as far away as the other axis misses: an elevation scan made 9' beside the
        source in cross-elevation (a cold start of the 45-ft at low elevation: its 12.24'
        azimuth encoder offset is 12.24' cos E on the sky) sees a fifth of the peak and can
        place it arcminutes wrong. With ``search.max_cross_offset_beams`` (0.5 for the 45-ft)
        an axis' offset is adopted only where the other axis' offset found is within that
        many beams (if neither is, the larger: its half passed nearer the source); the other
        is left to the next scan (or search), which is then made on the source in the
        adopted axis. Without it every axis found is adopted."""
        self.searches += 1
        scan = self.scan_for[target.name]
        step = scan.step_arcmin * self.config.search.step_factor
        traj = self.trajectory(target, self.antenna.clock_s())
        raw = yield env.process(cross_scan(env, self.antenna, traj, scan, label=target.name,
                                           step_arcmin=step,
                                           integration_s=max(scan.integration_s / 3.0, 1.0)))
        reduced = reduce_scan(raw, scan, estimator="lsq", step_arcmin=step)
        offsets = {}
        for axis in AXES:
            red = reduced.axes[axis]
            flags = int(red.flags[-1]) & ~int(SEARCH_TOLERATED)
            if flags == 0 and math.isfinite(float(red.offset_arcmin[-1])):
                offsets[axis] = float(red.offset_arcmin[-1])
        limit = self.config.search.max_cross_offset_beams
        beside = {"az": abs(offsets.get("el", 0.0)), "el": abs(offsets.get("az", 0.0))}
        adopted = {a: d for a, d in offsets.items()
                   if limit is None or beside[a] <= limit * scan.hpbw_arcmin}
        if offsets and not adopted:
            farther = max(offsets, key=lambda a: abs(offsets[a]))
            adopted = {farther: offsets[farther]}
        self._adopt(target, raw.t_mid_s, adopted.get("az", 0.0), adopted.get("el", 0.0))
        return len(adopted)

    def sky_emission_k(self, raw: RawScan) -> np.ndarray | None:
        """The sky emission (K) the controller subtracts from each integration of ``raw``,
        shape (axes, positions, channels): from the latest tipping scan's fit, else from
        the a-priori ``config.sky``; None when it knows neither (see the module)."""
        fits = [t.fits for t in self.tippings if t.fits]
        if fits:
            latest = fits[-1]
            models = [latest.get(ch, latest.get("AVG")) for ch in raw.channels]
            sky = [(f.tau, f.t_atm_k) for f in models]
        elif self.config.sky is not None and self.config.sky.zenith_opacity > 0.0:
            sky = [(self.config.sky.zenith_opacity, self.config.sky.t_atm_k)] * len(raw.channels)
        else:
            return None
        out = np.empty((len(AXES), len(raw.offsets_n), len(raw.channels)))
        for a, axis in enumerate(AXES):
            for k, integ in enumerate(raw.integrations[axis]):
                _, el_deg = self.frame.to_altaz_deg(integ.enc_az_deg, integ.enc_el_deg)
                airmass = 1.0 / math.sin(math.radians(max(el_deg, 1.0)))
                for c, (tau, t_atm_k) in enumerate(sky):
                    out[a, k, c] = t_atm_k * (1.0 - math.exp(-tau * airmass))
        return out

    def sky_corrected(self, raw: RawScan, sky_k: np.ndarray | None) -> RawScan:
        """``raw`` with the emission ``sky_k`` (see :meth:`sky_emission_k`) removed."""
        if sky_k is None:
            return raw
        out = replace(raw, integrations={})
        for a, axis in enumerate(AXES):
            out.integrations[axis] = [
                replace(integ, power_k={ch: p - sky_k[a, k, raw.channels.index(ch)]
                                        for ch, p in integ.power_k.items()})
                for k, integ in enumerate(raw.integrations[axis])]
        return out

    @staticmethod
    def _detected(reduced: ReducedScan, tolerated: Flag) -> bool:
        return all((int(reduced.axes[a].flags[-1]) & ~int(tolerated)) == 0 for a in AXES)

    # ------------------------------------------------------------------ recording
    def rows(self, target: Target, traj: SourceTrajectory, reduced: ReducedScan,
             before: tuple[float, float]) -> list[dict]:
        raw: RawScan = reduced.raw
        t_mid = raw.t_mid_s
        az, el = traj.observed_rad(np.array([t_mid]))
        az, el = float(az[0]), float(el[0])
        cmd_az, cmd_el = traj(np.array([t_mid]))
        lon, lat = self.frame.from_altaz(az, el)
        if self.frame.is_altaz and traj.feed_rad is None:
            d_az, d_el = self.config.model.offset_rad(az, el)
        else:
            d_az, d_el = self.config.model.offset_rad(lon, lat, traj.feed_rad)
        model_xel = float(d_az) * math.cos(lat) * ARCMIN_PER_RAD
        model_el = float(d_el) * ARCMIN_PER_RAD
        mid = raw.integrations["el"][0]
        weather = mid.weather
        sun_el = float(self.observer.sun_el_deg(t_mid)[0])
        first = raw.integrations["az"][0]
        slew_az = int(np.sign(round((first.enc_az_deg - before[0]) * 1000)))
        slew_el = int(np.sign(round((first.enc_el_deg - before[1]) * 1000)))
        power, std, _ = raw.powers()
        std_axis = np.sqrt(np.mean(std ** 2, axis=-1))  # (axes, channels + AVG)
        rows = []
        for p, pol in enumerate(reduced.polarizations):
            ax, ex = reduced.axes["az"], reduced.axes["el"]
            row = {
                "scan": self.scan_number,
                "time": "",  # filled by the sink, which knows the epoch's calendar
                "t_s": t_mid,
                "source": target.name,
                "polarization": pol,
                "az_deg": math.degrees(az) % 360.0,
                "el_deg": math.degrees(el),
                "cmd_az_deg": float(cmd_az[0]),
                "cmd_el_deg": float(cmd_el[0]),
                "model_xel_arcmin": model_xel,
                "model_el_arcmin": model_el,
                "applied_xel_arcmin": traj.correction_arcmin[0],
                "applied_el_arcmin": traj.correction_arcmin[1],
                "xel_arcmin": float(ax.offset_arcmin[p]),
                "el_arcmin": float(ex.offset_arcmin[p]),
                "xel_sigma_arcmin": float(ax.sigma_offset_arcmin[p]),
                "el_sigma_arcmin": float(ex.sigma_offset_arcmin[p]),
                "xel_amp_k": float(ax.amplitude_k[p]),
                "el_amp_k": float(ex.amplitude_k[p]),
                "xel_snr": float(ax.snr[p]),
                "el_snr": float(ex.snr[p]),
                "xel_std_k": float(std_axis[0, p]),
                "el_std_k": float(std_axis[1, p]),
                "xel_width_arcmin": float(ax.width_arcmin[p]) * FWHM_PER_SIGMA,
                "el_width_arcmin": float(ex.width_arcmin[p]) * FWHM_PER_SIGMA,
                "xel_flags": int(ax.flags[p]),
                "el_flags": int(ex.flags[p]),
                "good": bool(int(ax.flags[p]) == 0 and int(ex.flags[p]) == 0),
                "air_temp_c": weather.temperature_c,
                "pressure_hpa": weather.pressure_hpa,
                "humidity": weather.relative_humidity,
                "wind_m_s": weather.wind_speed_m_s,
                "sun_el_deg": sun_el,
                "slew_az": slew_az,
                "slew_el": slew_el,
            }
            for a, axis in enumerate(AXES):
                for k, name in enumerate(("m4", "m1", "0", "p1", "p4")):
                    row[f"p_{axis}_{name}"] = float(power[a, p, k])
            row.update(self.extra_columns(lon, lat, raw))
            rows.append(row)
        return rows

    def extra_columns(self, lon_rad: float, lat_rad: float, raw: RawScan | None = None) -> dict:
        """Columns beyond the 1990 set: hour angle and declination on an equatorial mount,
        the feed angle when the feed is turned, each structure temperature read during
        each half of the cross scan (see :func:`recording_columns`)."""
        extra: dict = {}
        if not self.frame.is_altaz:
            extra["ha_deg"] = math.degrees(float(lon_rad))
            extra["dec_deg"] = math.degrees(float(lat_rad))
        if self.config.feed_angles_deg:
            extra["feed_angle_deg"] = float(self.feed_angle_deg)
        if self.config.structure_sensors:
            for axis, recorded in (("az", "xel"), ("el", "el")):
                extra[structure_time_column(recorded)] = float(
                    raw.structure_t_s.get(axis, math.nan) if raw is not None else math.nan)
        for sensor in self.config.structure_sensors:
            for axis, recorded in (("az", "xel"), ("el", "el")):
                reading = raw.structure_c.get(axis, {}) if raw is not None else {}
                if sensor not in reading:
                    raise AntennaError(f"the antenna gave no reading of structure temperature "
                                       f"sensor {sensor!r} (it lists "
                                       f"{', '.join(reading) or 'none'})")
                extra[structure_column(sensor, recorded)] = float(reading[sensor])
        return extra
