"""Gain curves from the amplitudes of pointing scans.

Two forms, from the two source reports:

* **elevation** (Ghigo 1990, section V): the 45-ft's relative gain against elevation, flat
  above 30 deg, 95% at 20 deg, 90% at 10 deg. Fitted here as a piecewise-linear curve with
  ``knots_deg`` (10, 20, 30): free relative gains at every knot but the last, 1 at and above
  the last, the first segment's slope continued below the first knot; each source has its own
  scale (its flux density times the antenna's peak gain), so only the shape is needed and the
  receiver gain must be constant ("under constant receiver gain"). Nonlinear least squares
  (source scales times knot gains).
* **harmonics** (Crane 1981, section I, the 140-ft): gain in K/Jy as the spherical harmonics
  Y00, Y10, Y11e, Y11o. The memo writes theta = hour angle and phi = 90 deg - declination;
  only with theta the co-declination and phi the hour angle, unnormalised, do its Table 5
  coefficients give its own peaks and Figures 23 and 25's extrema (docs/telescopes.md):

      Y00 = 1, Y10 = cos(phi) = sin(dec),
      Y11e = sin(phi) cos(theta) = cos(dec) cos(H), Y11o = sin(phi) sin(theta) = cos(dec) sin(H),

  with coefficients in K/Jy.
  ``sin E = sin(lat) Y10 + cos(lat) Y11e`` lies in this span, so a gain linear in sin E is
  one special case. Linear least squares of
  the amplitudes on ``S_i Y(H_i, dec_i)`` (S: catalogue flux density, Jy).

Amplitudes. Each scan's amplitude is the mean of its two axes' Clark amplitudes, each first
corrected for the pointing offset across its scan (the azimuth scan is made at the elevation
offset the elevation scan then measures: ``A_az exp(el^2 / 2 s^2)``, s = HPBW / 2.3548; point
sources assumed), then for atmospheric extinction, ``exp(+tau A)`` with the zenith opacity
``tau`` from tipping scans (:mod:`controller.scans.tipping`) or from the scans' off-source powers.

Errors: heteroscedasticity-consistent (HC1 sandwich) standard errors for the harmonics; for
the elevation curve the Gauss-Newton covariance scaled by the residual variance.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from scipy.optimize import least_squares

from controller.astro.frames import altaz_to_hadec

from .config import GainCurveConfig
from .tipping import opacity_from_scans

__all__ = [
    "HARMONIC_NAMES",
    "STRONG_SOURCES",
    "Calibration",
    "ElevationGainFit",
    "HarmonicGainFit",
    "calibrate",
    "corrected_amplitudes",
    "fit_elevation_gain",
    "fit_harmonic_gain",
    "harmonic_basis",
    "piecewise_gain",
]

HARMONIC_NAMES = ("Y00", "Y10", "Y11E", "Y11O")
FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))


def harmonic_basis(ha_rad, dec_rad) -> np.ndarray:
    """Y00, Y10, Y11e, Y11o (unnormalised; see the module) at hour angle and declination
    (rad): array of shape (..., 4)."""
    ha = np.asarray(ha_rad, dtype=float)
    dec = np.asarray(dec_rad, dtype=float)
    cd = np.cos(dec)
    return np.stack(np.broadcast_arrays(np.ones_like(ha * dec), np.sin(dec), cd * np.cos(ha),
                                        cd * np.sin(ha)), axis=-1)


def piecewise_gain(el_deg, knots_deg: Sequence[float], gains: Sequence[float]) -> np.ndarray:
    """Relative gain at elevation(s) (deg): linear between ``knots_deg`` with ``gains`` at all
    knots but the last (1 there and above), the first slope continued below the first knot."""
    el = np.asarray(el_deg, dtype=float)
    k = np.asarray(knots_deg, dtype=float)
    g = np.append(np.asarray(gains, dtype=float), 1.0)
    out = np.interp(el, k, g)
    below = el < k[0]
    if below.any():
        slope = (g[1] - g[0]) / (k[1] - k[0])
        out = np.where(below, g[0] + slope * (el - k[0]), out)
    return out


def corrected_amplitudes(cols: Mapping[str, np.ndarray], hpbw_arcmin: float | np.ndarray,
                         zenith_opacity: float) -> np.ndarray:
    """Per row: the mean of the two axes' amplitudes (K), each corrected for the offset
    across its scan, times ``exp(tau / sin E)`` (the module's recipe). ``hpbw_arcmin``: the
    width the reduction assumed (arcmin), one for all rows or one per row."""
    s = np.asarray(hpbw_arcmin, dtype=float) / FWHM_PER_SIGMA
    xel = np.asarray(cols["xel_arcmin"], dtype=float)
    el_off = np.asarray(cols["el_arcmin"], dtype=float)
    a_az = np.asarray(cols["xel_amp_k"], dtype=float) * np.exp(el_off ** 2 / (2 * s * s))
    a_el = np.asarray(cols["el_amp_k"], dtype=float) * np.exp(xel ** 2 / (2 * s * s))
    el = np.radians(np.asarray(cols["el_deg"], dtype=float))
    airmass = 1.0 / np.sin(np.maximum(el, math.radians(1.0)))
    return 0.5 * (a_az + a_el) * np.exp(zenith_opacity * airmass)


@dataclass(frozen=True)
class HarmonicGainFit:
    """Gain (K/Jy) = sum of ``values`` times Y00, Y10, Y11e, Y11o; HC1 ``sigma``."""

    values: np.ndarray
    sigma: np.ndarray
    rms_k_per_jy: float
    n: int
    names: tuple[str, ...] = HARMONIC_NAMES

    def gain(self, ha_rad, dec_rad) -> np.ndarray:
        return harmonic_basis(ha_rad, dec_rad) @ self.values

    def to_json(self) -> dict:
        return {"form": "spherical harmonics of hour angle and declination (Crane 1981): "
                        "gain_k_per_jy = Y00 + Y10 sin(dec) + Y11E cos(dec) cos(H) "
                        "+ Y11O cos(dec) sin(H)",
                "coefficients_k_per_jy": {n: float(v) for n, v in
                                          zip(self.names, self.values, strict=True)},
                "sigma_k_per_jy": {n: float(v) for n, v in
                                   zip(self.names, self.sigma, strict=True)},
                "rms_k_per_jy": self.rms_k_per_jy, "n": self.n}


def _sandwich(x: np.ndarray, r: np.ndarray, bread: np.ndarray) -> np.ndarray:
    n, p = x.shape
    meat = (x * r[:, None]).T @ (x * r[:, None])
    cov = bread @ meat @ bread * n / max(n - p, 1)
    return np.sqrt(np.clip(np.diag(cov), 0.0, None))


def fit_harmonic_gain(ha_rad, dec_rad, amp_k, flux_jy) -> HarmonicGainFit:
    """Least squares of amplitudes (K) on flux (Jy) times the harmonics (see the module)."""
    y = np.asarray(amp_k, dtype=float)
    s = np.asarray(flux_jy, dtype=float)
    basis = harmonic_basis(ha_rad, dec_rad)
    keep = np.isfinite(y) & np.isfinite(s) & np.all(np.isfinite(basis), axis=1) & (s > 0)
    x = basis[keep] * s[keep, None]
    y = y[keep]
    if y.size <= x.shape[1]:
        raise ValueError(f"{y.size} amplitudes cannot determine the 4 gain harmonics")
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    r = y - x @ coef
    bread = np.linalg.inv(x.T @ x)
    per_jy = r / s[keep]
    return HarmonicGainFit(coef, _sandwich(x, r, bread),
                           math.sqrt(float(np.mean(per_jy ** 2))), int(y.size))


@dataclass(frozen=True)
class ElevationGainFit:
    """Relative gains at ``knots_deg`` (the last is 1 by definition) with their sigma, and
    each source's scale (K at relative gain 1)."""

    knots_deg: tuple[float, ...]
    gains: np.ndarray
    sigma: np.ndarray
    scales_k: dict[str, float]
    rms_relative: float
    n: int

    def gain(self, el_deg) -> np.ndarray:
        return piecewise_gain(el_deg, self.knots_deg, self.gains)

    def to_json(self) -> dict:
        knots = [f"{k:g}" for k in self.knots_deg]
        return {"form": "relative gain against elevation, piecewise linear between the knots, "
                        "1 at and above the last knot (Ghigo 1990, section V)",
                "knots_deg": list(self.knots_deg),
                "gain": {k: float(g) for k, g in zip(knots, [*self.gains, 1.0], strict=True)},
                "sigma": {k: float(g) for k, g in zip(knots, [*self.sigma, 0.0], strict=True)},
                "source_scale_k": self.scales_k, "rms_relative": self.rms_relative,
                "n": self.n}


def fit_elevation_gain(el_deg, amp_k, source, knots_deg: Sequence[float] = (10.0, 20.0, 30.0)
                       ) -> ElevationGainFit:
    """Fit ``amp = K_source * piecewise_gain(el)`` (see the module) by Gauss-Newton."""
    el = np.asarray(el_deg, dtype=float)
    y = np.asarray(amp_k, dtype=float)
    src = np.asarray(source).astype(str)
    keep = np.isfinite(el) & np.isfinite(y) & (y > 0)
    el, y, src = el[keep], y[keep], src[keep]
    names = sorted(set(src.tolist()))
    knots = tuple(float(k) for k in knots_deg)
    m = len(knots) - 1
    if len(knots) < 2 or any(b <= a for a, b in pairwise(knots)):
        raise ValueError(f"knots_deg must be at least two increasing elevations, not {knots}")
    if y.size <= m + len(names):
        raise ValueError(f"{y.size} amplitudes cannot determine {m} gains and "
                         f"{len(names)} source scales")
    idx = np.array([names.index(s) for s in src])
    start = np.array([np.median(y[idx == k]) for k in range(len(names))] + [1.0] * m)

    def resid(p: np.ndarray) -> np.ndarray:
        return (p[idx] * piecewise_gain(el, knots, p[len(names):]) - y) / p[idx]

    sol = least_squares(resid, start, method="lm", x_scale="jac")
    r = sol.fun
    dof = max(y.size - sol.x.size, 1)
    cov = np.linalg.pinv(sol.jac.T @ sol.jac) * float(np.sum(r ** 2)) / dof
    sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    return ElevationGainFit(knots, sol.x[len(names):], sigma[len(names):],
                            {n: float(v) for n, v in zip(names, sol.x[:len(names)],
                                                         strict=True)},
                            math.sqrt(float(np.mean(r ** 2))), int(y.size))


# ---------------------------------------------------------------------------------------------
# From recordings to a gain curve: the observatory's procedure
# ---------------------------------------------------------------------------------------------
#: the 1990 report's strong sources, the default calibrators of an elevation gain curve
STRONG_SOURCES = ("Cassiopeia A", "Cygnus A")

_COLUMNS = ("polarization", "good", "source", "az_deg", "el_deg", "xel_arcmin", "el_arcmin",
            "xel_amp_k", "el_amp_k", "p_az_m4", "p_az_p4")


@dataclass
class Calibration:
    """What :func:`calibrate` found: the zenith opacity used (and where it came from), the
    tipping scans, and the gain-curve fit (elevation or harmonic form)."""

    opacity: float
    opacity_sigma: float
    opacity_source: str
    tippings: list
    fit: ElevationGainFit | HarmonicGainFit | None
    sources: tuple[str, ...]
    scan_opacity: object = None

    def to_json(self) -> dict:
        return {
            "zenith_opacity": {"value": self.opacity, "sigma": self.opacity_sigma,
                               "from": self.opacity_source,
                               **({"from_scan_baselines": self.scan_opacity.to_json()}
                                  if self.scan_opacity is not None else {})},
            "tippings": [t.to_json() for t in self.tippings],
            "gain_curve": None if self.fit is None else {"sources": list(self.sources),
                                                         **self.fit.to_json()},
        }


def _cols(rows) -> dict[str, np.ndarray]:
    if isinstance(rows, Sequence) and (not rows or isinstance(rows[0], Mapping)):
        keys = [c for c in (*_COLUMNS, "ha_deg", "dec_deg") if rows and c in rows[0]]
        return {c: np.array([r[c] for r in rows]) for c in keys}
    return {c: np.asarray(rows[c]) for c in (*_COLUMNS, "ha_deg", "dec_deg")
            if c in rows.colnames}


def calibrate(rows, config, tippings: Sequence = ()) -> Calibration | None:
    """The gain curve of ``config.gain_curve`` (a ControllerConfig) from recordings ``rows``
    (row dicts or a Table) and tipping scans; None when there is nothing to fit.

    Opacity: the mean of the tippings' fits (polarization average) when there are any, else
    ``gain_curve.zenith_opacity`` if set, else the fit of the scans' off-source powers.
    """
    gc = config.gain_curve
    cols = _cols(rows)
    if not cols or "polarization" not in cols:
        return None
    names = [s.name for s in config.sources]
    if gc is None:
        if config.method != "five_point" or not all(s in names for s in STRONG_SOURCES):
            return None
        gc = GainCurveConfig(sources=STRONG_SOURCES)
    sel = ((cols["polarization"].astype(str) == "AVG") & cols["good"].astype(bool)
           & np.isfinite(cols["xel_amp_k"].astype(float))
           & np.isfinite(cols["el_amp_k"].astype(float)))
    scan_fit = None
    with contextlib.suppress(ValueError):
        scan_fit = opacity_from_scans({k: v[sel] for k, v in cols.items()}, gc.t_atm_k)
    fits = [t.fits["AVG"] for t in tippings if "AVG" in t.fits]
    if fits:
        taus = np.array([f.tau for f in fits])
        tau = float(taus.mean())
        sigma = (float(taus.std(ddof=1) / math.sqrt(taus.size)) if taus.size > 1
                 else fits[0].sigma_tau)
        origin = f"tipping scans ({taus.size})"
    elif gc.zenith_opacity is not None:
        tau, sigma, origin = float(gc.zenith_opacity), 0.0, "assumed (scenario)"
    elif scan_fit is not None:
        tau, sigma = scan_fit.tau, scan_fit.sigma_tau
        origin = "sky emission in the scans' off-source (+-4D) powers"
    else:
        return None
    sources = gc.sources or tuple(s.name for s in config.sources if s.flux_jy > 0)
    use = sel & np.isin(cols["source"].astype(str), list(sources))
    fit = None
    if use.sum() > 8:
        width = np.array([config.reduction_width_arcmin(str(name))
                          for name in cols["source"][use]])
        amp = corrected_amplitudes({k: v[use] for k, v in cols.items()}, width, tau)
        try:
            if gc.kind == "harmonics":
                flux = {s.name: s.flux_jy for s in config.sources}
                lon, lat = (("ha_deg", "dec_deg") if "ha_deg" in cols else (None, None))
                if lon is None:
                    ha, dec = altaz_to_hadec(np.radians(cols["az_deg"][use].astype(float)),
                                             np.radians(cols["el_deg"][use].astype(float)),
                                             math.radians(config.site_latitude_deg))
                else:
                    ha = np.radians(cols[lon][use].astype(float))
                    dec = np.radians(cols[lat][use].astype(float))
                fit = fit_harmonic_gain(ha, dec, amp, [flux[s] for s in
                                                       cols["source"][use].astype(str)])
            else:
                fit = fit_elevation_gain(cols["el_deg"][use].astype(float), amp,
                                         cols["source"][use], gc.knots_deg)
        except ValueError:
            fit = None
    return Calibration(tau, sigma, origin, list(tippings), fit, tuple(sources), scan_fit)
