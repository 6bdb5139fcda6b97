"""BIMA memo 23's study: how well the linear equations fit an exact tilt and collimation.

Wright (1992) generated pointing data with a large azimuth-axis tilt (6') and collimation
(9'), computed exactly with rotations (his equations (3) and (4); here
:class:`antsim.world.effects.optics.ExactTiltCollimation`), fitted the linear 7 + 7 term equations
(1) and (2) (``bima14``) and showed where they fail: the residuals grow near azimuth 90 deg
and elevation 90 deg (with the tilt towards azimuth 90: assumption, the memo's direction was
not available), and shrink to about 1" rms with a 1' tilt or 5' of collimation.
:func:`memo23_study` repeats it on a grid of positions (noise-free, plain least squares);
``benchmarks/bima_study.py`` prints the memo's quantities.

The memo also gives the delay of an antenna whose axes do not intersect
(:func:`axis_offset_delay_s`). When an alt-az antenna's elevation axis is displaced horizontally by
``D`` from its azimuth axis (towards the direction the antenna points), the point that stays fixed
as the antenna turns (on the azimuth axis) is not the point that defines the antenna's position in
the array. The elevation axis lies ``D`` from the azimuth axis along the horizontal direction of
the source, so a wavefront from elevation E reaches it earlier by the path ``D cos(E)``: an
extra delay term ``D cos(E) / c`` that depends on elevation alone (Wright 1992 writes it as
D cos(El)), to be removed from the array's geometric delay model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.stats import f as f_dist

from antsim.world.effects.optics import ExactTiltCollimation
from controller.pointing.bima import BIMA_TERMS
from controller.pointing.data import PointingData
from controller.pointing.fitting import fit_model
from controller.pointing.result import FitResult
from controller.units import ARCSEC_PER_RAD

__all__ = ["SPEED_OF_LIGHT_M_S", "TABLE1_ANT5", "StudyResult", "TermTest", "WorstResidual",
           "axis_offset_delay_s", "axis_offset_path_m", "exact_errors_arcsec", "memo23_study",
           "term_significance"]


def exact_errors_arcsec(tilt_arcmin: float, collimation_arcmin: float, tilt_az_deg: float,
                        az_rad: np.ndarray, el_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact pointing error (indicated minus true) of a tilt and a collimation at true
    positions (rad): cross-elevation dA cos E and elevation, arcsec."""
    effect = ExactTiltCollimation(tilt_arcmin=tilt_arcmin, tilt_az_deg=tilt_az_deg,
                                  collimation_arcmin=collimation_arcmin)
    az_enc, el_enc = effect.encoder_from_true(az_rad, el_rad)
    d_az = (az_enc - az_rad + math.pi) % (2 * math.pi) - math.pi
    return d_az * np.cos(el_rad) * ARCSEC_PER_RAD, (el_enc - el_rad) * ARCSEC_PER_RAD



class WorstResidual(NamedTuple):
    """The largest residual: its azimuth and elevation (deg) and its size (arcsec)."""

    az_deg: float
    el_deg: float
    residual_arcsec: float

@dataclass(frozen=True)
class StudyResult:
    """The fit of the linear equations to exact errors on a grid, and where it fails."""

    tilt_arcmin: float
    collimation_arcmin: float
    tilt_az_deg: float
    az_deg: np.ndarray
    el_deg: np.ndarray
    fit: FitResult

    @property
    def residual_arcsec(self) -> np.ndarray:
        """Total residual sqrt(xel^2 + el^2) per grid point (arcsec)."""
        return np.hypot(self.fit.residual_xel_arcsec, self.fit.residual_el_arcsec)

    @property
    def sky_rms_arcsec(self) -> float:
        return self.fit.sky_rms_arcsec

    def rms_by(self, which: str, lo: float = -math.inf, hi: float = math.inf,
               el_min_deg: float = -math.inf) -> dict[float, float]:
        """Sky rms (arcsec) of the residuals in each distinct ``which`` ("az" or "el") value,
        for points with elevation >= ``el_min_deg``."""
        key = self.az_deg if which == "az" else self.el_deg
        r2 = self.residual_arcsec ** 2
        out = {}
        for v in np.unique(key):
            sel = (key == v) & (self.el_deg >= el_min_deg) & (key >= lo) & (key <= hi)
            if sel.any():
                out[float(v)] = math.sqrt(float(r2[sel].mean()))
        return out

    def worst(self) -> WorstResidual:
        """Where the largest residual is, and its size."""
        k = int(np.argmax(self.residual_arcsec))
        return WorstResidual(float(self.az_deg[k]), float(self.el_deg[k]),
                             float(self.residual_arcsec[k]))


def memo23_study(tilt_arcmin: float = 6.0, collimation_arcmin: float = 9.0,
                 tilt_az_deg: float = 90.0, az_step_deg: float = 10.0,
                 el_min_deg: float = 10.0, el_max_deg: float = 85.0,
                 el_step_deg: float = 5.0) -> StudyResult:
    """Fit the memo's linear equations to exact tilt + collimation errors on an az/el grid
    (plain least squares, no noise) and return the fit with the grid."""
    az = np.arange(0.0, 360.0, az_step_deg)
    el = np.arange(el_min_deg, el_max_deg + 1e-9, el_step_deg)
    az_g, el_g = (a.ravel() for a in np.meshgrid(az, el))
    xel, d_el = exact_errors_arcsec(tilt_arcmin, collimation_arcmin, tilt_az_deg,
                                    np.radians(az_g), np.radians(el_g))
    data = PointingData(np.radians(az_g), np.radians(el_g), xel, d_el)
    fit = fit_model(data, BIMA_TERMS, robust=False, name="bima14")
    return StudyResult(tilt_arcmin, collimation_arcmin, tilt_az_deg, az_g, el_g, fit)


# ---------------------------------------------------------------------------------------------
# the delay of non-intersecting axes
# ---------------------------------------------------------------------------------------------
SPEED_OF_LIGHT_M_S = 299792458.0


def axis_offset_path_m(offset_m, el_rad) -> np.ndarray:
    """Path (m) by which the wavefront reaches the elevation axis before the azimuth axis,
    ``D cos(E)``, for axis offset ``offset_m`` (m, positive: the elevation axis lies towards
    the pointing direction) at elevation(s) ``el_rad``."""
    return np.asarray(offset_m, dtype=float) * np.cos(np.asarray(el_rad, dtype=float))


def axis_offset_delay_s(offset_m, el_rad) -> np.ndarray:
    """The delay term ``D cos(E) / c`` (s) of :func:`axis_offset_path_m`."""
    return axis_offset_path_m(offset_m, el_rad) / SPEED_OF_LIGHT_M_S


#: Table 1 of the memo, antenna 5 (arcmin): a(1)..a(7) and b(1)..b(7)
TABLE1_ANT5 = {"A1": 70.41, "A2": 9.31, "A3": -0.40, "A4": 2.06, "A5": -3.39, "A6": 0.00,
               "A7": 0.00, "B1": 33.17, "B2": -2.06, "B3": -2.94, "B4": 3.87, "B5": 2.27,
               "B6": 0.17, "B7": 0.85}


@dataclass(frozen=True)
class TermTest:
    """A fit with and without one term: rms per axis (arcsec), F statistic and p-value, and
    the correlation of the reduced fit's elevation residual with ``pattern``."""

    term: str
    el_rms_with_arcsec: float
    el_rms_without_arcsec: float
    sky_rms_with_arcsec: float
    sky_rms_without_arcsec: float
    f_statistic: float
    p_value: float
    correlation: float


def term_significance(data: PointingData, terms: tuple[str, ...], term: str,
                      pattern: np.ndarray) -> TermTest:
    """Least-squares fits of ``terms`` with and without ``term``; the F test of the residual
    sums of squares (both axes, 1 and n - m degrees of freedom)."""
    full = fit_model(data, terms, robust=False)
    reduced = fit_model(data, tuple(t for t in terms if t != term), robust=False)
    n = 2 * len(data)
    rss_full = 0.5 * n * full.sky_rms_arcsec ** 2
    rss_reduced = 0.5 * n * reduced.sky_rms_arcsec ** 2
    dof = n - len(terms)
    f_stat = (rss_reduced - rss_full) / (rss_full / dof)
    corr = float(np.corrcoef(reduced.residual_el_arcsec, pattern)[0, 1])
    return TermTest(term, full.el_rms_arcsec, reduced.el_rms_arcsec, full.sky_rms_arcsec,
                    reduced.sky_rms_arcsec, float(f_stat), float(f_dist.sf(f_stat, 1, dof)),
                    corr)
