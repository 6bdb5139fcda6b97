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

from .base import Effect, Key, PointingState

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


def _on_a_turn(series, n: int) -> np.ndarray:
    """The series at ``n + 1`` equally spaced angles from 0 to 2 pi (both ends): the inverse
    real FFT of its harmonics (the sum of a_n cos(n x + p_n) on the grid, to rounding)."""
    orders, amplitudes, phases = series
    spectrum = np.zeros(n // 2 + 1, dtype=complex)
    spectrum[orders] = 0.5 * n * amplitudes * np.exp(1j * phases)
    turn = np.fft.irfft(spectrum, n)
    return np.append(turn, turn[0])


class MountIrregularities(Effect):
    """Repeatable errors of encoders, gears and the azimuth track (see the module)."""

    name: ClassVar[str] = "irregularities"
    explanation: ClassVar[str] = (
        "encoder and gear errors and an uneven azimuth track: errors fixed in azimuth and "
        "elevation, the same every night, beyond the pointing model's terms"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "az_encoder_rms_arcsec": Key(0.0, "rms over a turn of the azimuth encoder and gear "
                                     "errors (arcsec of azimuth; 5-40 on antennas of the era)",
                                     min=0.0, source="Gawronski, Baher and Gama 2006 (DSS-25)"),
        "el_encoder_rms_arcsec": Key(0.0, "rms over a turn of the elevation encoder and gear "
                                     "errors (arcsec)", min=0.0),
        "track_rms_arcsec": Key(0.0, "rms of the alidade's rocking on its track, forward and "
                                "sideways each (arcsec)", min=0.0,
                                source="Gawronski, Baher and Gama 2006 (DSS-25's track)"),
        "harmonics": Key(24.0, "highest harmonic per turn (the lowest is the second)",
                         min=2.0, max=360.0, unit="1"),
        "pattern_seed": Key(1.0, "the antenna's own pattern (the same in every campaign)",
                            min=0.0, max=2.0**31, unit="1"),
        "beyond_model": Key("", "the pointing model whose fit over the sky is taken out of "
                            "the pattern: the 1990 report's ten W's, or none", kind="string",
                            choices=("", "ghigo10")),
    }
    #: the tables the pattern is read from: every 0.01 deg of azimuth over a turn and of
    #: elevation from 1 to 90 deg (linear interpolation of 24 harmonics: below 2e-4")
    TABLE_STEP_DEG = 0.01
    TABLE_EL_MIN_DEG = 1.0
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
        self._tabulate()

    def _tabulate(self) -> None:
        """The four series on their tables, the model part folded in: the ten W's are
        functions of azimuth alone or elevation alone times cos E or sin E (their shapes, the
        report's section II), but W10, constant on the sky (:attr:`_xel_constant`)."""
        s = self.series
        n = round(360.0 / self.TABLE_STEP_DEG)
        self._az_grid = np.linspace(0.0, 2.0 * np.pi, n + 1)
        first = round(self.TABLE_EL_MIN_DEG / self.TABLE_STEP_DEG)
        last = round(90.0 / self.TABLE_STEP_DEG)
        self._el_grid = self._az_grid[first:last + 1]
        a = self._az_grid
        e = self._el_grid
        az_cos = _on_a_turn(s["az_encoder"], n)        # times cos E: dA cos E
        az_sin = _on_a_turn(s["track_sideways"], n)    # times sin E
        az_el = _on_a_turn(s["track_forward"], n)      # dE
        el_el = _on_a_turn(s["el_encoder"], n)[first:last + 1]  # dE
        self._xel_constant = 0.0
        if self.model_part is not None:
            w = self.model_part.as_dict()
            az_cos = az_cos - w["W6"]
            az_sin = az_sin - (w["W7"] * np.cos(a) + w["W8"] * np.sin(a) + w["W9"])
            az_el = az_el - (w["W1"] + w["W2"] * np.cos(a) + w["W3"] * np.sin(a))
            el_el = el_el - (w["W4"] * np.cos(e) + w["W5"] / np.tan(e))
            self._xel_constant = -w["W10"]
        self._tables = (az_cos, az_sin, az_el, el_el)

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
        """(dA cos E, dE) in arcsec, indicated minus true, at (``az_rad``, ``el_rad``), from
        the tables (:meth:`_tabulate`)."""
        az_cos, az_sin, az_el, el_el = self._tables
        a = np.mod(az_rad, 2.0 * np.pi)
        el = np.asarray(el_rad, dtype=float)
        xel = (np.interp(a, self._az_grid, az_cos) * np.cos(el)
               + np.interp(a, self._az_grid, az_sin) * np.sin(el) + self._xel_constant)
        d_el = np.interp(a, self._az_grid, az_el) + np.interp(el, self._el_grid, el_el)
        return xel, d_el

    def exact_errors_arcsec(self, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`errors_arcsec` from the series themselves, not the tables (for tests)."""
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
