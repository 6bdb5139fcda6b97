"""Effects of the optics and the sources: squint, beam width, structure, refraction, tilt."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from controller.pointing.bima import tilt_collimation_equivalents
from controller.pointing.model import PointingModel
from controller.units import RAD_PER_ARCMIN, RAD_PER_ARCSEC

from .base import Effect, Key, PointingState

__all__ = ["BeamWidthError", "ExactTiltCollimation", "PolarizationSquint", "RefractionAnomaly",
           "SourceStructure", "TiltedSky"]


class PolarizationSquint(Effect):
    """Right and left circular beams point apart by ``separation_arcsec`` at ``angle_deg``
    (0: cross-elevation, 90: elevation); the average of the two is on axis."""

    name: ClassVar[str] = "polarization_squint"
    explanation: ClassVar[str] = (
        "an offset feed makes the right- and left-circular beams point to opposite sides of "
        "the axis; XR and XL then disagree by a constant amount"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "separation_arcsec": Key(0.0, "XR beam minus XL beam separation (arcsec)"),
        "angle_deg": Key(0.0, "direction of the separation, 0 = +xel, 90 = +el"),
    }

    def beam_offset(self, channel: str, state: PointingState) -> tuple[float, float]:
        half = 0.5 * self.p["separation_arcsec"] * RAD_PER_ARCSEC
        sign = {"XR": 1.0, "XL": -1.0}.get(channel, 0.0)
        angle = math.radians(self.p["angle_deg"])
        return sign * half * math.cos(angle), sign * half * math.sin(angle)


class BeamWidthError(Effect):
    """The true beam is ``scale`` times wider than the controller assumes."""

    name: ClassVar[str] = "beam_width"
    explanation: ClassVar[str] = (
        "the beam is wider (or narrower) than the reduction assumes, so every measured "
        "offset is scaled by the same factor"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "scale": Key(1.0, "true HPBW / nominal HPBW", min=0.5, max=2.0, unit="1"),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        world.beam.hpbw_arcmin = world.beam.config.hpbw_arcmin * self.p["scale"]


class SourceStructure(Effect):
    """Sources larger than the scenario says, or with their centroid off the catalogue
    position: offsets scaled and shifted, residuals clustered by source."""

    name: ClassVar[str] = "source_structure"
    explanation: ClassVar[str] = (
        "an extended or double source is not a point: its measured offsets are scaled "
        "down by theta_b^2/(theta_b^2+theta_s^2) and its centroid may lie off the "
        "catalogue position"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "source": Key("", "name of the source", kind="string"),
        "size_arcmin": Key(0.0, "Gaussian FWHM of the source (arcmin)", min=0.0, max=60.0),
        "xel_arcsec": Key(0.0, "centroid offset from the catalogue, cross-elevation"),
        "el_arcsec": Key(0.0, "centroid offset from the catalogue, elevation"),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        try:
            i = world.sky.index(self.p["source"])
        except ValueError:
            raise ValueError(f"source_structure: unknown source {self.p['source']!r}") from None
        world.sky.size_arcmin[i] = self.p["size_arcmin"]
        world.sky.position_offset_arcsec[i] = (self.p["xel_arcsec"], self.p["el_arcsec"])


class RefractionAnomaly(Effect):
    """Refraction actually present differs from the formula by a factor ``scale``."""

    name: ClassVar[str] = "refraction_anomaly"
    terms: ClassVar[tuple[str, ...]] = ("TX",)
    explanation: ClassVar[str] = (
        "the refraction the controller corrects differs from the refraction present (wrong "
        "humidity or pressure, or an inadequate formula): a cot E residual in elevation"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "scale": Key(1.0, "true refraction / formula refraction", min=0.0, max=3.0,
                     unit="1"),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        world.sky.refraction_scale = self.p["scale"]


class ExactTiltCollimation(Effect):
    """Exact (not small-angle) azimuth-axis tilt and collimation (BIMA memo 23, eqs. 3-4).

    The azimuth axis is tilted by ``tilt_arcmin`` towards azimuth ``tilt_az_deg`` and the beam
    is off the plane perpendicular to the elevation axis by ``collimation_arcmin``. The error is
    computed with rotations, so it stays right near the zenith and near azimuth 90 deg where
    the linear TPOINT terms (AN, AW, CA) fail for large angles. For small angles it equals
    AN = tilt cos(tilt_az), AW = -tilt sin(tilt_az), CA = -collimation (TPOINT's meaning: the
    pole of the azimuth axis north of the zenith by AN, west of it by AW; tested).
    """

    name: ClassVar[str] = "exact_tilt_collimation"
    terms: ClassVar[tuple[str, ...]] = ("AN", "AW", "CA")
    explanation: ClassVar[str] = (
        "a large tilt of the azimuth axis or a large collimation error: the small-angle "
        "model fails near the zenith and near azimuth 90 deg"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "tilt_arcmin": Key(0.0, "tilt of the azimuth axis (arcmin)", min=0.0),
        "tilt_az_deg": Key(0.0, "azimuth towards which the axis tilts (deg, N = 0)"),
        "collimation_arcmin": Key(0.0, "collimation error (arcmin)"),
        "linear_part": Key(1.0, "1: the whole error; 0: only what the small-angle terms "
                           "(AN, AW, CA) leave, when a scenario's linear terms carry them",
                           min=0.0, max=1.0, unit="1"),
    }

    def coefficients(self) -> dict[str, float]:
        """Small-angle equivalents (arcsec, TPOINT's sign) in TPOINT's terms (AN, AW, CA) and
        in the BIMA memo's separate azimuth and elevation tilt terms (HSSASE, HECA, HSCASE,
        HESA): what a linear fit of either model should recover."""
        tilt_arcsec = self.p["tilt_arcmin"] * 60.0
        phi = math.radians(self.p["tilt_az_deg"])
        linear = {"AN": tilt_arcsec * math.cos(phi), "AW": -tilt_arcsec * math.sin(phi),
                  "CA": -self.p["collimation_arcmin"] * 60.0}
        params = {k: v for k, v in self.params().items() if k != "linear_part"}
        return {**linear, **tilt_collimation_equivalents(**params)}

    def truth(self) -> dict[str, Any]:
        return {**super().truth(), "coefficients_arcsec": self.coefficients()}

    def encoder_from_true(self, az_rad, el_rad):
        """Encoder (indicated) azimuth and elevation that put the beam on the true direction."""
        az = np.asarray(az_rad, dtype=float)
        el = np.asarray(el_rad, dtype=float)
        # true direction as a unit vector (x north, y east, z up)
        v = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        tilt = self.p["tilt_arcmin"] * RAD_PER_ARCMIN
        phi = math.radians(self.p["tilt_az_deg"])
        # the mount's frame: rotate by -tilt about the horizontal axis perpendicular to phi
        axis = np.array([-math.sin(phi), math.cos(phi), 0.0])
        v_mount = _rotate(v, axis, -tilt)
        x, y, z = v_mount
        el_m = np.arcsin(np.clip(z, -1.0, 1.0))
        az_m = np.arctan2(y, x)
        # collimation c: the beam lies at angle c from the plane perpendicular to the
        # elevation axis; pointing at elevation-axis-plane angle: sin(el_beam) relation
        c = self.p["collimation_arcmin"] * RAD_PER_ARCMIN
        # beam direction in mount frame for encoders (A, E): the elevation axis is
        # horizontal along azimuth A + 90; beam = cos c * (in-plane direction at E) +
        # sin c * (along the elevation axis). Invert exactly:
        sin_e = np.clip(np.sin(el_m) / math.cos(c), -1.0, 1.0)
        el_enc = np.arcsin(sin_e)
        # azimuth offset of the beam from the in-plane azimuth: tan(da) = sin c / (cos c cos E)
        da = np.arctan2(math.sin(c), math.cos(c) * np.cos(el_enc))
        az_enc = az_m - da
        return az_enc % (2 * math.pi), el_enc

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        az_enc, el_enc = self.encoder_from_true(state.az_rad, state.el_rad)
        d_az = (float(az_enc) - state.az_rad + math.pi) % (2 * math.pi) - math.pi
        d_el = float(el_enc) - state.el_rad
        if self.p["linear_part"] != 1.0:  # remove (part of) the small-angle equivalents
            lin_az, lin_el = self._linear().offset_rad(state.az_rad, state.el_rad)
            weight = 1.0 - self.p["linear_part"]
            d_az -= weight * float(lin_az)
            d_el -= weight * float(lin_el)
        return d_az, d_el

    def _linear(self):
        model = getattr(self, "_linear_model", None)
        if model is None:
            c = self.coefficients()
            model = PointingModel(["AN", "AW", "CA"], [c["AN"], c["AW"], c["CA"]])
            self._linear_model = model
        return model


class TiltedSky:
    """True directions (azimuth, elevation, rad) prepared once for the errors of many exact
    tilts and collimations (a fit's repeated evaluations): the arithmetic of
    :meth:`ExactTiltCollimation.encoder_from_true` rearranged (the rotation as one 3x3
    matrix, the azimuth difference from one arctan2 in the true azimuth's frame, no
    arcsin-then-sine), equal to it within rounding (tested)."""

    def __init__(self, az_rad: np.ndarray, el_rad: np.ndarray):
        az = np.asarray(az_rad, dtype=float)
        self.el_rad = np.asarray(el_rad, dtype=float)
        self.cos_az, self.sin_az = np.cos(az), np.sin(az)
        self.cos_el = np.cos(self.el_rad)
        self.v = np.stack([self.cos_el * self.cos_az, self.cos_el * self.sin_az,
                           np.sin(self.el_rad)])

    def _rotated(self, tilt_rad: float, tilt_az_rad: float) -> np.ndarray:
        """The directions in the tilted axis' frame, (3, k): x, y, z."""
        return _rotation(tilt_rad, tilt_az_rad) @ self.v

    def errors_rad(self, tilt_rad: float, tilt_az_rad: float,
                   collimation_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """Encoder minus true (azimuth, elevation), rad, of an azimuth axis tilted by
        ``tilt_rad`` towards ``tilt_az_rad`` and a collimation error ``collimation_rad``."""
        x, y, z = self._rotated(tilt_rad, tilt_az_rad)
        cos_c = math.cos(collimation_rad)
        el_enc = np.arcsin(np.clip(z / cos_c, -1.0, 1.0))
        da = np.arctan2(math.sin(collimation_rad), cos_c * np.cos(el_enc))
        d_az = np.arctan2(y * self.cos_az - x * self.sin_az,
                          x * self.cos_az + y * self.sin_az) - da
        return wrap_pi(d_az), el_enc - self.el_rad

    def derivatives_rad(self, tilt_north_rad: float, tilt_east_rad: float,
                        collimation_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """d(azimuth error)/dp and d(elevation error)/dp, each (3, k), of :meth:`errors_rad`
        with respect to p = (the tilt's north and east components, the collimation), rad,
        analytic: the axis rotation R = exp([r]x), r = (east, -north, 0), moves a direction
        u = R v = (x, y, z) by du = a x u, a = J_l(r) dr (J_l the rotation group's left
        Jacobian), so that the azimuth arctan2 moves by a_z - z (a_x x + a_y y) / (x^2 + y^2)
        (the true azimuth's turn drops out) and z by a_x y - a_y x."""
        tilt = math.hypot(tilt_north_rad, tilt_east_rad)
        x, y, z = self._rotated(tilt, math.atan2(tilt_east_rad, tilt_north_rad))
        skew = np.array([[0.0, 0.0, -tilt_north_rad], [0.0, 0.0, -tilt_east_rad],
                         [tilt_north_rad, tilt_east_rad, 0.0]])  # [r]x
        if tilt < 1e-4:  # the series: 1/2 - t^2/24, 1/6 - t^2/120 (rounding below 1e-16)
            c1, c2 = 0.5 - tilt**2 / 24.0, 1.0 / 6.0 - tilt**2 / 120.0
        else:
            c1 = 2.0 * math.sin(0.5 * tilt) ** 2 / tilt**2
            c2 = (tilt - math.sin(tilt)) / tilt**3
        j_left = np.eye(3) + c1 * skew + c2 * (skew @ skew)
        cos_c, sin_c = math.cos(collimation_rad), math.sin(collimation_rad)
        sin_e = np.clip(z / cos_c, -1.0, 1.0)  # the encoder elevation's sine
        cos_e = np.sqrt(1.0 - sin_e**2)
        # d(arcsin s) = ds / cos E: zero where errors_rad clips s (a direction past the pole)
        inv = np.divide(1.0 / cos_c, cos_e, out=np.zeros_like(cos_e), where=cos_e > 0.0)
        # the collimation's azimuth term da = arctan2(sin c, q), q = cos c cos E:
        # d(da) = (q d(sin c) - sin c dq) / (sin^2 c + q^2)
        q = cos_c * cos_e
        pq = sin_c**2 + q**2
        inv_pq = np.divide(1.0, pq, out=np.zeros_like(pq), where=pq > 0.0)
        rho2 = x * x + y * y  # zero only exactly at the pole, where arctan2 is taken as 0
        z_rho = np.divide(z, rho2, out=np.zeros_like(z), where=rho2 > 0.0)
        k_da = (sin_c * cos_c) * sin_e * inv_pq  # d(da)/dE for a fixed collimation
        d_az, d_el = np.empty((3, z.size)), np.empty((3, z.size))
        # dr/d(north) = (0, -1, 0), dr/d(east) = (1, 0, 0)
        for i, a in enumerate((-j_left[:, 1], j_left[:, 0])):
            d_el[i] = (a[0] * y - a[1] * x) * inv
            d_az[i] = a[2] - z_rho * (a[0] * x + a[1] * y) - k_da * d_el[i]
        d_el[2] = sin_e * sin_c * inv
        d_az[2] = -(q * cos_c + sin_c * (sin_c * cos_e + cos_c * sin_e * d_el[2])) * inv_pq
        return d_az, d_el


def _rotation(tilt_rad: float, tilt_az_rad: float) -> np.ndarray:
    """The 3x3 matrix that rotates true directions to the tilted axis' frame: Rodrigues'
    rotation by -tilt about the horizontal axis k perpendicular to the tilt (see _rotate)."""
    k = np.array([-math.sin(tilt_az_rad), math.cos(tilt_az_rad), 0.0])
    cos_a, sin_a = math.cos(-tilt_rad), math.sin(-tilt_rad)
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return cos_a * np.eye(3) + sin_a * cross + (1.0 - cos_a) * np.outer(k, k)


def wrap_pi(angle_rad: np.ndarray) -> np.ndarray:
    """``(angle_rad + pi) % (2 pi) - pi``, bit for bit, in place of ``angle_rad``: the
    remainder (5 ms at 200,000 values, each evaluation of a fit's exact error) only where
    ``angle_rad + pi`` is outside (0, 2 pi), since inside it is that value itself."""
    two_pi = 2 * math.pi
    a = np.add(angle_rad, math.pi, out=angle_rad)
    inside = (a > 0.0) & (a < two_pi)
    if not inside.all():
        outside = ~inside
        a[outside] = np.remainder(a[outside], two_pi)
    a -= math.pi
    return a


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues rotation of vectors ``v`` (3, ...) about unit ``axis`` by ``angle``."""
    k = axis.reshape(3, *([1] * (v.ndim - 1)))
    cos_a, sin_a = math.cos(angle), math.sin(angle)
    cross = np.stack([k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2],
                      k[0] * v[1] - k[1] * v[0]])
    dot = (k * v).sum(axis=0)
    return v * cos_a + cross * sin_a + k * dot * (1 - cos_a)
