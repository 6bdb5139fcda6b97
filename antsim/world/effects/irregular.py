"""Repeatable irregularities of a mount: encoder and gear errors, an uneven azimuth track.

Errors fixed in azimuth and elevation, the same every night and in every campaign: an
antenna's own, not the weather's. Each is a harmonic series with amplitudes falling as
``1/n`` (the spectrum measured track profiles and gear errors show: Gawronski, Baher and
Gama 2006 for DSS-25's azimuth track) and phases drawn once from ``pattern_seed`` (the
antenna's, not the run's: two campaigns of one antenna share the pattern):

* **azimuth encoder and gear**: ``dA = sum a_n cos(n A + p_n)``, on the sky ``dA cos E``;
* **elevation encoder and gear**: ``dE = sum b_n cos(n E + q_n)``, ``n`` per turn of the
  elevation axis;
* **azimuth track or bearing**: the alidade rocks as it turns, forward and sideways by
  ``f(A)`` and ``s(A)``: ``dE = f(A)``, ``dA cos E = s(A) sin E`` (Gawronski et al. 2006:
  three rotations of the alidade per azimuth, here the two that point).

Every series runs from the second harmonic up to ``harmonics`` (the first is the pointing
model's own: an encoder's eccentricity or the azimuth axis' tilt) and is scaled to its rms
over a turn (``*_rms_arcsec``). Over the sky a campaign samples, the smooth parts of these
series look like the pointing model's own terms and a fit takes them in: a real antenna's
fitted model already holds them. With ``beyond_model`` naming the fitted model (the 1990
scenario: ``ghigo10``, whose truth is the report's fitted Table 3) the effect is the pattern
less its least-squares fit by that model over the sky (azimuth every 5 deg, elevation 10-85
deg every 2.5 deg): what the model cannot take in, the part of the residual that more scans
do not average down.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from controller.pointing.model import PointingModel
from controller.units import RAD_PER_ARCSEC

from .base import Effect, Param, PointingState

__all__ = ["MountIrregularities", "harmonic_series"]

#: the series' order in the pattern: azimuth encoder, elevation encoder, track forward, sideways
SERIES = ("az_encoder", "el_encoder", "track_forward", "track_sideways")


def harmonic_series(rng: np.random.Generator, rms: float, n_max: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orders 2..``n_max``, amplitudes falling as 1/n scaled so that the series' rms over a
    turn is ``rms``, and phases uniform in [0, 2 pi): (orders, amplitudes, phases)."""
    orders = np.arange(2, max(int(n_max), 2) + 1)
    amplitudes = 1.0 / orders
    phases = rng.uniform(0.0, 2.0 * np.pi, orders.size)
    # the rms of sum a_n cos(n x + p) over a turn is sqrt(sum a_n^2 / 2)
    amplitudes *= rms / np.sqrt(0.5 * np.sum(amplitudes ** 2))
    return orders, amplitudes, phases


def _evaluate(series, x):
    orders, amplitudes, phases = series
    x = np.asarray(x, dtype=float)
    return np.sum(amplitudes * np.cos(orders * x[..., None] + phases), axis=-1)


class MountIrregularities(Effect):
    """Repeatable errors of encoders, gears and the azimuth track (see the module)."""

    name: ClassVar[str] = "irregularities"
    explanation: ClassVar[str] = (
        "encoder and gear errors and an uneven azimuth track: errors fixed in azimuth and "
        "elevation, the same every night, beyond the pointing model's terms"
    )
    PARAMS: ClassVar[dict[str, Param]] = {
        "az_encoder_rms_arcsec": Param(0.0, "rms of the azimuth encoder and gear errors "
                                       "(arcsec of azimuth)", min=0.0),
        "el_encoder_rms_arcsec": Param(0.0, "rms of the elevation encoder and gear errors "
                                       "(arcsec)", min=0.0),
        "track_rms_arcsec": Param(0.0, "rms of the alidade's rocking on its track, "
                                  "forward and sideways each (arcsec)", min=0.0),
        "harmonics": Param(24.0, "highest harmonic per turn", min=2.0, max=360.0),
        "pattern_seed": Param(1.0, "the antenna's own pattern (the same in every campaign)",
                              min=0.0, max=2.0**31),
        "beyond_model": Param("", "a named pointing model whose fit over the sky is taken "
                              "out of the pattern (empty: none)", kind="string"),
    }
    #: the sky over which the pattern's model part is fitted (deg)
    SKY_AZ_DEG = np.arange(0.0, 360.0, 5.0)
    SKY_EL_DEG = np.arange(10.0, 85.01, 2.5)

    def start(self, world, rng: np.random.Generator) -> None:
        pattern = np.random.default_rng(int(self.p["pattern_seed"]))
        n_max = round(self.p["harmonics"])
        rms = (self.p["az_encoder_rms_arcsec"], self.p["el_encoder_rms_arcsec"],
               self.p["track_rms_arcsec"], self.p["track_rms_arcsec"])
        self.series = {name: harmonic_series(pattern, r, n_max)
                       for name, r in zip(SERIES, rms, strict=True)}
        self.model_part = None
        if self.p["beyond_model"]:
            self.model_part = self._model_part(PointingModel(self.p["beyond_model"]).names)

    def _pattern_arcsec(self, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        s = self.series
        el = np.asarray(el_rad, dtype=float)
        xel = _evaluate(s["az_encoder"], az_rad) * np.cos(el) \
            + _evaluate(s["track_sideways"], az_rad) * np.sin(el)
        d_el = _evaluate(s["el_encoder"], el) + _evaluate(s["track_forward"], az_rad)
        return xel, d_el

    def _model_part(self, names) -> PointingModel:
        """The least-squares fit of the terms ``names`` to the pattern over the sky grid."""
        az, el = (np.radians(g).ravel() for g in np.meshgrid(self.SKY_AZ_DEG, self.SKY_EL_DEG))
        xel, d_el = self._pattern_arcsec(az, el)
        columns = []
        for name in names:  # each term's error on the sky per arcsec of coefficient
            c_az, c_el = PointingModel([name], [1.0]).offset_rad(az, el)
            columns.append(np.concatenate([c_az * np.cos(el), c_el]) / RAD_PER_ARCSEC)
        values, *_ = np.linalg.lstsq(np.array(columns).T, np.concatenate([xel, d_el]),
                                     rcond=None)
        return PointingModel(list(names), [float(v) for v in values])

    def errors_arcsec(self, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """(dA cos E, dE) in arcsec, indicated minus true, at (``az_rad``, ``el_rad``)."""
        xel, d_el = self._pattern_arcsec(az_rad, el_rad)
        if self.model_part is not None:
            m_az, m_el = self.model_part.offset_rad(az_rad, el_rad)
            xel = xel - m_az * np.cos(el_rad) / RAD_PER_ARCSEC
            d_el = d_el - m_el / RAD_PER_ARCSEC
        return xel, d_el

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        xel, d_el = self.errors_arcsec(state.az_rad, state.el_rad)
        d_az = xel / np.cos(state.el_rad) * RAD_PER_ARCSEC
        if np.ndim(d_az) == 0:
            return float(d_az), float(d_el) * RAD_PER_ARCSEC
        return d_az, d_el * RAD_PER_ARCSEC

    block_error = pointing_error  # elementwise in the state
