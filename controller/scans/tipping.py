"""Tipping scans: the sky's brightness at several elevations gives the zenith opacity.

A plane-parallel atmosphere of zenith opacity ``tau`` and mean radiating temperature
``T_atm`` adds ``T_atm (1 - exp(-tau A))`` to the system temperature at airmass
``A = 1 / sin E``; its transmission is ``exp(-tau A)``. A tipping scan (Crane 1981, section
IV) measures the total power on blank sky at several elevations and fits

    P(A) = T0 + T_atm (1 - exp(-tau A))

for ``T0`` (receiver and everything that does not change with elevation) and ``tau``, with
``T_atm`` the observer's assumed value (about 0.95 of the surface air temperature in kelvin;
an error of x% in it is an error of about x% in ``tau``). Amplitudes measured at airmass A
are then corrected by ``exp(+tau A)``.

:func:`tipping_scan` is the simpy process the control program runs through the antenna
protocol (fixed positions, total power); :func:`fit_opacity` the fit, also usable on the
off-source (+-4D) powers of ordinary cross scans, which sample the same curve for free
(:func:`opacity_from_scans`).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar

from controller.astro.frames import MountFrame
from controller.protocol import Antenna, AntennaError

from .config import TippingConfig
from .tracking import ProgramTrack

__all__ = ["FixedTrajectory", "OpacityFit", "Tipping", "airmass", "fit_opacity",
           "opacity_from_scans", "tipping_scan"]

#: a tipping position must be this far from every catalogue source (deg)
CLEAR_DEG = 3.0


def airmass(el_rad) -> np.ndarray:
    """Plane-parallel airmass 1 / sin E (E in radians, held above 1 deg)."""
    return 1.0 / np.sin(np.maximum(np.asarray(el_rad, dtype=float), math.radians(1.0)))


@dataclass(frozen=True)
class OpacityFit:
    """Fitted zenith opacity ``tau`` (nepers) with its standard error, the elevation-
    independent power ``t0_k`` (K), the rms of the fit (K) and the number of points."""

    tau: float
    sigma_tau: float
    t0_k: float
    rms_k: float
    n: int
    t_atm_k: float

    def to_json(self) -> dict:
        return {"zenith_opacity": self.tau, "sigma": self.sigma_tau, "t0_k": self.t0_k,
                "rms_k": self.rms_k, "n": self.n, "t_atm_k": self.t_atm_k}


def fit_opacity(airmass_values, power_k, t_atm_k: float) -> OpacityFit:
    """Least-squares fit of ``P = T0 + T_atm (1 - exp(-tau A))`` (see the module).

    For each trial ``tau`` the best ``T0`` is the mean residual, so the fit is a 1-D search
    (bounded Brent) followed by the linearised covariance for the standard error of ``tau``.
    Raises ValueError for fewer than three points or a single airmass.
    """
    a = np.asarray(airmass_values, dtype=float).reshape(-1)
    p = np.asarray(power_k, dtype=float).reshape(-1)
    keep = np.isfinite(a) & np.isfinite(p)
    a, p = a[keep], p[keep]
    if a.size < 3 or np.ptp(a) <= 0:
        raise ValueError("a tipping fit needs at least three powers at different airmasses")
    if not (math.isfinite(t_atm_k) and t_atm_k > 0):
        raise ValueError(f"t_atm_k must be a positive temperature, not {t_atm_k!r}")

    def cost(tau: float) -> float:
        r = p - t_atm_k * (1.0 - np.exp(-tau * a))
        return float(np.sum((r - r.mean()) ** 2))

    # the cost has a second, shallow minimum where the atmosphere saturates (tau of order 1):
    # a logarithmic grid finds the right basin, a bounded Brent search refines it
    grid = np.concatenate([[0.0], np.geomspace(1e-5, 3.0, 241)])
    k = int(np.argmin([cost(x) for x in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": 1e-12})
    tau = float(best.x)
    r = p - t_atm_k * (1.0 - np.exp(-tau * a))
    t0 = float(r.mean())
    resid = r - t0
    dof = max(a.size - 2, 1)
    s2 = float(np.sum(resid ** 2)) / dof
    jac = np.column_stack([np.ones_like(a), t_atm_k * a * np.exp(-tau * a)])
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
        sigma = math.sqrt(max(float(cov[1, 1]), 0.0))
    except np.linalg.LinAlgError:
        sigma = math.nan
    return OpacityFit(tau, sigma, t0, math.sqrt(float(np.mean(resid ** 2))), int(a.size),
                      float(t_atm_k))


@dataclass
class Tipping:
    """One tipping scan: positions, powers per channel and the fit per channel."""

    t_s: float
    az_deg: float
    el_deg: list[float] = field(default_factory=list)
    power_k: dict[str, list[float]] = field(default_factory=dict)
    air_temp_c: float = math.nan
    fits: dict[str, OpacityFit] = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"t_s": self.t_s, "az_deg": self.az_deg, "el_deg": self.el_deg,
                "airmass": [float(x) for x in airmass(np.radians(self.el_deg))],
                "power_k": self.power_k, "air_temp_c": self.air_temp_c,
                "fits": {k: v.to_json() for k, v in self.fits.items()}}


class FixedTrajectory:
    """A fixed encoder position (deg): what a tipping scan tracks."""

    def __init__(self, lon_deg: float, lat_deg: float):
        self.lon_deg = float(lon_deg) % 360.0
        self.lat_deg = float(lat_deg)

    def __call__(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        shape = np.shape(t_s)
        return np.full(shape, self.lon_deg), np.full(shape, self.lat_deg)

    def elevation_deg(self, t_s: float) -> float:
        return self.lat_deg

    def program_track(self) -> ProgramTrack:
        """One point: a program track that holds it (see SourceTrajectory.program_track)."""
        return ProgramTrack(np.zeros(1), np.array([self.lon_deg]), np.array([self.lat_deg]))

    def covers(self, t_s) -> bool:
        return True

    def sky_elevation_deg(self, t_s: float) -> float:
        return self.lat_deg


def _clear_azimuth(config: TippingConfig, frame: MountFrame, observer, t_s: float,
                   hour_angle_limit_deg: float | None) -> float | None:
    """The first azimuth (preferred, then +-30 deg steps) whose tipping positions are all
    CLEAR_DEG from every catalogue source and inside an equatorial mount's hour angles."""
    eph = observer.ephemeris
    index = np.arange(len(eph.sources))
    if index.size:
        src_az, src_el = eph.altaz_rad(index, np.full(index.size, float(t_s)))
    el = np.radians(np.asarray(config.elevations_deg, dtype=float))
    for k in (0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6):
        az = math.radians((config.azimuth_deg + 30.0 * k) % 360.0)
        if index.size:
            cos_sep = (np.sin(el)[:, None] * np.sin(src_el)[None, :] + np.cos(el)[:, None]
                       * np.cos(src_el)[None, :] * np.cos(az - src_az)[None, :])
            if np.any(cos_sep > math.cos(math.radians(CLEAR_DEG))):
                continue
        if not frame.is_altaz and hour_angle_limit_deg is not None:
            ha, _ = frame.from_altaz(np.full(el.shape, az), el)
            if np.any(np.abs(np.degrees(ha)) > hour_angle_limit_deg):
                continue
        return math.degrees(az)
    return None


def tipping_scan(env, antenna: Antenna, config: TippingConfig, frame: MountFrame, observer,
                 targets: Sequence, hour_angle_limit_deg: float | None):
    """simpy process: total power on blank sky at each of ``config.elevations_deg`` (in that
    order) at one azimuth; returns a fitted :class:`Tipping`, or None if no clear azimuth.
    ``hour_angle_limit_deg``: an equatorial mount's hour-angle limit (the scheduler's)."""
    t0 = antenna.clock_s()
    az_deg = _clear_azimuth(config, frame, observer, t0, hour_angle_limit_deg)
    if az_deg is None:
        return None
    tip = Tipping(t_s=t0, az_deg=az_deg)
    for ch in antenna.channels:
        tip.power_k[ch] = []
    temps = []
    for el_deg in config.elevations_deg:
        lon, lat = frame.from_altaz(math.radians(az_deg), math.radians(el_deg))
        traj = FixedTrajectory(math.degrees(float(lon)), math.degrees(float(lat)))
        try:
            yield antenna.track(traj, label="tipping")
        except AntennaError:
            continue
        integ = yield antenna.integrate(config.integration_s)
        tip.el_deg.append(float(el_deg))
        for ch in antenna.channels:
            tip.power_k[ch].append(float(integ.power_k[ch]))
        temps.append(integ.weather.temperature_c)
    tip.t_s = 0.5 * (t0 + antenna.clock_s())
    tip.air_temp_c = float(np.mean(temps)) if temps else math.nan
    am = airmass(np.radians(tip.el_deg))
    for ch, powers in tip.power_k.items():
        with contextlib.suppress(ValueError):
            tip.fits[ch] = fit_opacity(am, powers, config.t_atm_k)
    if tip.power_k and len(tip.el_deg) >= 3:
        avg = np.mean([tip.power_k[ch] for ch in antenna.channels], axis=0)
        tip.fits["AVG"] = fit_opacity(am, avg, config.t_atm_k)
    return tip


def opacity_from_scans(rows: Mapping[str, np.ndarray] | Sequence[Mapping], t_atm_k: float,
                       polarization: str = "AVG") -> OpacityFit:
    """The zenith opacity from the off-source powers of cross scans: the mean of the azimuth
    scan's two outer (+-4D) points of each row against the row's airmass (the same curve a
    tipping scan samples; the source adds 1.6e-8 of its peak there)."""
    if isinstance(rows, Mapping):
        cols = rows
    else:
        cols = {k: np.array([r[k] for r in rows]) for k in
                ("polarization", "el_deg", "p_az_m4", "p_az_p4")}
    pol = np.asarray(cols["polarization"]).astype(str)
    sel = pol == polarization
    base = 0.5 * (np.asarray(cols["p_az_m4"], float) + np.asarray(cols["p_az_p4"], float))
    el = np.radians(np.asarray(cols["el_deg"], float))
    return fit_opacity(airmass(el[sel]), base[sel], t_atm_k)
