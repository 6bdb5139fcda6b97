"""Optical pointing: a TV camera on the antenna reads a star's offset directly (BIMA).

Wright (1992, BIMA memo 23) pointed BIMA's antennas optically: the antenna tracks a bright
star and a boresighted TV camera shows the star's offset from the optical axis to a few
arcseconds, with no radio scan. :class:`OpticalPointingProgram` is that procedure as a control
program: the same scheduler, trajectories (optical refraction, at the camera's wavelength) and
recordings as the five-point program, but each observation is ``track`` + ``measure_offset``
through :class:`~controller.protocol.CameraAntenna`. A row per star is written with the
polarization ``AVG`` (the camera is the only channel) so that the fit variants apply as they
are; the radio-only columns (amplitudes, S/N, powers) are NaN. A star not found in the field
is recorded with the flag ``AMPLITUDE_NONPOSITIVE`` (no source) and NaN offsets.

The memo's model (its terms in TPOINT's names) is :mod:`controller.pointing.bima`.
"""

from __future__ import annotations

import math

import numpy as np

from controller.scans.reduction import Flag
from controller.scans.tracking import SourceTrajectory

from .campaign import ControlProgram, ScanOutcome
from .observer import Target

__all__ = ["OpticalPointingProgram"]


class OpticalPointingProgram(ControlProgram):
    """The optical pointing program (see the module); drives a ``CameraAntenna``."""

    def _scan_duration_s(self) -> float:
        opt = self.config.optical
        exposure = 5.0 if opt is None else opt.exposure_s
        overhead = 10.0 if opt is None else opt.overhead_s
        return exposure + overhead + 60.0  # a slew of about a minute

    def observe(self, env, target: Target):
        """simpy process: track the star, read the camera, record one row."""
        opt = self.config.optical
        exposure = 5.0 if opt is None else opt.exposure_s
        before = self.antenna.encoder_deg()
        traj = self.trajectory(target, self.antenna.clock_s())
        yield self.antenna.track(traj, target.name)
        reading = yield self.antenna.measure_offset(exposure)
        if opt is not None and opt.overhead_s > 0:
            yield self.antenna.wait(opt.overhead_s)
        if not reading.found:
            self.misses += 1
        self.scheduler.record(reading.t_mid_s, target)
        rows = self.optical_rows(target, traj, reading, before)
        if self.sink:
            self.sink(rows)
        self.scan_number += 1
        return ScanOutcome(target, None, rows, 0)

    def optical_rows(self, target: Target, traj: SourceTrajectory, reading,
                     before: tuple[float, float]) -> list[dict]:
        """One recording row (polarization AVG) for a camera reading."""
        t_mid = reading.t_mid_s
        az, el = traj.observed_rad(np.array([t_mid]))
        az, el = float(az[0]), float(el[0])
        cmd_az, cmd_el = traj(np.array([t_mid]))
        lon, lat = self.frame.from_altaz(az, el)
        d_az, d_el = self.config.model.offset_rad(lon, lat, traj.feed_rad)
        nan = math.nan
        flags = 0 if reading.found else int(Flag.AMPLITUDE_NONPOSITIVE)
        row = {
            "scan": self.scan_number, "time": "", "t_s": t_mid, "source": target.name,
            "polarization": "AVG",
            "az_deg": math.degrees(az) % 360.0, "el_deg": math.degrees(el),
            "cmd_az_deg": float(cmd_az[0]), "cmd_el_deg": float(cmd_el[0]),
            "model_xel_arcmin": float(d_az) * math.cos(float(lat)) * 60.0 * 180.0 / math.pi,
            "model_el_arcmin": float(d_el) * 60.0 * 180.0 / math.pi,
            "applied_xel_arcmin": traj.correction_arcmin[0],
            "applied_el_arcmin": traj.correction_arcmin[1],
            "xel_arcmin": reading.xel_arcsec / 60.0, "el_arcmin": reading.el_arcsec / 60.0,
            "xel_sigma_arcmin": nan, "el_sigma_arcmin": nan,
            "xel_amp_k": nan, "el_amp_k": nan, "xel_snr": nan, "el_snr": nan,
            "xel_std_k": nan, "el_std_k": nan, "xel_width_arcmin": nan, "el_width_arcmin": nan,
            "xel_flags": flags, "el_flags": flags, "good": bool(reading.found),
            "air_temp_c": reading.weather.temperature_c,
            "pressure_hpa": reading.weather.pressure_hpa,
            "humidity": reading.weather.relative_humidity,
            "wind_m_s": reading.weather.wind_speed_m_s,
            "sun_el_deg": float(self.observer.sun_el_deg(t_mid)[0]),
            "slew_az": int(np.sign(round((reading.enc_az_deg - before[0]) * 1000))),
            "slew_el": int(np.sign(round((reading.enc_el_deg - before[1]) * 1000))),
        }
        for axis in ("az", "el"):
            for name in ("m4", "m1", "0", "p1", "p4"):
                row[f"p_{axis}_{name}"] = nan
        row.update(self.extra_columns(lon, lat))
        return [row]
