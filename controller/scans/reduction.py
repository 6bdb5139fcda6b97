"""Five-point cross-scan reduction: five total powers along one axis -> offset and amplitude.

A cross scan integrates total power at sky offsets ``n * D`` for ``n = -4, -1, 0, +1, +4``
(:data:`OFFSETS_N`), one after another in that order, so time increases with ``n``. Every
function here takes arrays whose last axis holds those five points in that order and is
vectorized over any leading (batch) axes: a campaign reduces ``(2 axes, 3 polarizations, 5)``
per scan, a Monte Carlo study ``(10**6, 5)`` at once; a single scan ``(5,)`` is a batch of one
and gives 0-d arrays.

Two estimators share the result type :class:`AxisReduction` and the quality :class:`Flag` s
(:data:`ESTIMATORS` maps their names to the functions):

- :func:`reduce_clark`: Clark's (1968) three-point method exactly as the Ghigo (1990) report's
  section VI gives it. Closed form, cheap; reaches its bound only near zero offset.
- :func:`reduce_lsq`: a fixed-width Gaussian plus a baseline linear in *time* (as the VLBI
  Field System's ``fivpt``) fitted to all five points by least squares. Reaches the
  Cramér-Rao bound of its own model (:func:`cramer_rao_offset_arcmin`) for S/N >= 8.

Conventions: offsets in arcmin on the sky, positive when the source lies at positive offset,
i.e. the returned offset is the pointing correction to apply along that axis. Powers and
their standard deviations in kelvin, times in seconds. ``std_k`` is used as the 1-sigma noise
of each mean power ``P`` (for S/N, weights and formal errors), as the report's
``S/N = A / stddev(P)`` does; if a receiver reports the standard deviation of N independent
samples instead, the formal errors are conservative by sqrt(N) and the S/N cut stricter.
Astropy Quantities are accepted for every input and converted to the unit in the name.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

__all__ = [
    "ESTIMATORS",
    "FWHM_PER_SIGMA",
    "OFFSETS_N",
    "OUTSIDE_PATTERN_STEPS",
    "WIDTH_BAND",
    "WIDTH_GATE_SIGMA",
    "AxisReduction",
    "Flag",
    "cramer_rao_offset_arcmin",
    "flag_names",
    "reduce_clark",
    "reduce_lsq",
]

#: Offsets of the five integrations in units of the step D, in observing (time) order.
OFFSETS_N = np.array([-4, -1, 0, 1, 4])
OFFSETS_N.setflags(write=False)
_N_POINTS = OFFSETS_N.size
_I_M4, _I_M1, _I_0, _I_P1, _I_P4 = range(_N_POINTS)

#: FWHM / sigma of a Gaussian, 2 sqrt(2 ln 2) = 2.3548.
FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))

#: |offset| beyond this many steps D is flagged OUTSIDE_PATTERN (see :class:`Flag`).
OUTSIDE_PATTERN_STEPS = 2.0

#: Band of estimated / nominal beam width (sigma) accepted as consistent with the beam.
#: Below 0.7: no response of a diffraction-limited beam is that narrow (a spike or
#: interference). Up to 1.5: keeps the partly resolved calibrators of the 1990 run (Tau A,
#: Cas A broaden the beam by ~5-10%) and a moderately defocused beam; a source twice the
#: beam (the response then 2.2x wider) or a confused field falls outside.
WIDTH_BAND = (0.7, 1.5)

#: The width flag also requires the estimate to lie this many of its own formal standard
#: deviations beyond the band, so that noise alone (the log-parabola through three noisy
#: points scatters by ~1.1/SNR in relative width at zero offset and far more off-centre)
#: does not throw away good low-S/N scans.
WIDTH_GATE_SIGMA = 3.0

# Least-squares offset search: grid over +-_LSQ_GRID_STEPS * D, spacing beam sigma / 8 (the
# profile likelihood varies on the beam's scale, so a local maximum cannot hide between
# nodes), then safeguarded Newton in the best node's bracket.
_LSQ_GRID_STEPS = 3.0
_LSQ_GRID_PER_SIGMA = 8.0
_LSQ_MAX_ITERATIONS = 60
_LSQ_TOLERANCE_SIGMA = 1e-10  # convergence of the offset, in beam sigmas
_CHUNK = 1 << 16  # scans per block: bounds memory of the (scans x grid) work array

BaselineModel = Literal["constant", "linear_time"]
_BOUND_BASELINES = ("constant", "linear_time", "linear_offset")


class Flag(enum.IntFlag):
    """Quality flags of one reduced axis; ``0`` means good. Bits combine.

    - ``LOG_ARGUMENT``: a baseline-subtracted side power B(-1) or B(+1) is <= 0, so Clark's
      ln[B(+1)/B(-1)] is undefined; offset, amplitude and S/N are NaN (Clark only).
    - ``OUTSIDE_PATTERN``: |offset| > 2 D. The source then sits beyond the inner points, its
      beam reaches the +-4D points and contaminates the baseline, and the offset is an
      extrapolation (Clark's log ratio in particular breaks down there).
    - ``AMPLITUDE_NONPOSITIVE``: fitted amplitude <= 0: no source, or a dip. For LSQ the
      offset is then NaN (no positive-amplitude solution exists on the searched range).
    - ``LOW_SNR``: S/N = amplitude / rms(std_k) below ``snr_min`` (the report rejects < 4).
    - ``WIDTH_INCONSISTENT``: the beam width estimated from the log-parabola through the
      three inner baseline-subtracted powers lies outside :data:`WIDTH_BAND` x the nominal
      width by more than :data:`WIDTH_GATE_SIGMA` of its formal error (extended or
      confused source, wrong beam, interference). Not evaluated where that width is
      undefined (an inner power <= 0).
    - ``FIT_FAILED``: non-finite input, a degenerate design, or (LSQ) no convergence.
    """

    LOG_ARGUMENT = 1
    OUTSIDE_PATTERN = 2
    AMPLITUDE_NONPOSITIVE = 4
    LOW_SNR = 8
    WIDTH_INCONSISTENT = 16
    FIT_FAILED = 32


def flag_names(flags: int) -> list[str]:
    """Names of the :class:`Flag` bits set in ``flags`` (e.g. for a recording's column)."""
    value = int(flags)
    return [flag.name for flag in Flag if flag.name is not None and value & flag]


@dataclass(frozen=True, eq=False)
class AxisReduction:
    """Reduction of one axis of a cross scan; every field is an array of the batch shape.

    - ``offset_arcmin``: source position relative to the pattern centre = pointing
      correction to apply along the axis (arcmin on the sky; NaN where undefined).
    - ``amplitude_k``: peak antenna temperature of the source above the baseline (K).
    - ``snr``: ``amplitude_k / rms(std_k)`` over the five integrations (the report's S/N).
    - ``sigma_offset_arcmin``: formal 1-sigma error of the offset from ``std_k`` by linear
      propagation (Clark) or the fit's covariance (LSQ), arcmin.
    - ``width_arcmin``: beam sigma estimated from the three inner points (arcmin; NaN where
      undefined). Diagnostic only: the offset uses the nominal width.
    - ``baseline_k``: the estimator's baseline at the centre point n = 0 (K).
    - ``flags``: :class:`Flag` bits (int64); 0 = good.
    """

    offset_arcmin: np.ndarray
    amplitude_k: np.ndarray
    snr: np.ndarray
    sigma_offset_arcmin: np.ndarray
    width_arcmin: np.ndarray
    baseline_k: np.ndarray
    flags: np.ndarray

    def good(self) -> np.ndarray:
        """Boolean array of the batch shape: True where no flag is set."""
        return np.asarray(self.flags) == 0


# ---------------------------------------------------------------------------------------------
# Input handling


def _as_float_array(value: Any, unit: str, name: str) -> np.ndarray:
    """Plain float array of ``value``, converting an astropy Quantity to ``unit``."""
    if hasattr(value, "unit") and hasattr(value, "to_value"):
        value = value.to_value(unit)
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name} must be numeric ({unit}); got {type(value).__name__}") from exc


def _positive_scalar(value: Any, unit: str, name: str) -> float:
    number = _as_float_array(value, unit, name)
    if number.ndim != 0 or not np.isfinite(number) or number <= 0.0:
        raise ValueError(f"{name} must be a finite positive scalar ({unit}); got {value!r}")
    return float(number)


def _beam(step_arcmin: Any, hpbw_arcmin: Any) -> tuple[float, float]:
    """(step D, beam sigma s) in arcmin, validated."""
    step = _positive_scalar(step_arcmin, "arcmin", "step_arcmin")
    hpbw = _positive_scalar(hpbw_arcmin, "arcmin", "hpbw_arcmin")
    return step, hpbw / FWHM_PER_SIGMA


def _snr_threshold(snr_min: Any) -> float:
    value = _as_float_array(snr_min, "", "snr_min")
    if value.ndim != 0 or not np.isfinite(value) or value < 0.0:
        raise ValueError(f"snr_min must be a finite scalar >= 0; got {snr_min!r}")
    return float(value)


def _scan_arrays(
    power_k: Any, std_k: Any, times_s: Any | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Broadcast power, std (and times) to one (..., 5) shape; raise on malformed input.

    Non-finite values are not errors (a dropped integration in a large batch must not abort
    the batch): they are returned as they are and flagged FIT_FAILED by the caller.
    """
    power = _as_float_array(power_k, "K", "power_k")
    std = _as_float_array(std_k, "K", "std_k")
    if power.ndim == 0 or power.shape[-1] != _N_POINTS:
        raise ValueError(
            f"power_k must have last axis of length {_N_POINTS} (offsets n = -4, -1, 0, +1, +4);"
            f" got shape {power.shape}"
        )
    arrays = [power, std]
    names = ["power_k", "std_k"]
    if times_s is not None:
        arrays.append(_as_float_array(times_s, "s", "times_s"))
        names.append("times_s")
    if times_s is not None and (arrays[2].ndim == 0 or arrays[2].shape[-1] != _N_POINTS):
        raise ValueError(
            f"times_s must have last axis of length {_N_POINTS}; got shape {arrays[2].shape}"
        )
    try:
        broadcast = np.broadcast_arrays(*arrays)
    except ValueError:
        shapes = ", ".join(f"{n} {a.shape}" for n, a in zip(names, arrays, strict=True))
        raise ValueError(f"input shapes do not broadcast: {shapes}") from None
    power, std = broadcast[0], broadcast[1]
    if np.any(std <= 0.0):
        raise ValueError("std_k must be > 0 (the noise of each integration); got a value <= 0")
    times = None
    if times_s is not None:
        times = broadcast[2]
        finite = np.isfinite(times).all(axis=-1)
        if np.any(np.diff(times, axis=-1)[finite] <= 0.0):
            raise ValueError(
                "times_s must increase strictly along the last axis (the integrations are"
                " made in the order n = -4, -1, 0, +1, +4)"
            )
    return power, std, times


def _noise_k(std: np.ndarray) -> np.ndarray:
    """stddev(P) of the report's S/N: rms of the five integrations' standard deviations."""
    return np.sqrt(np.mean(std**2, axis=-1))


# ---------------------------------------------------------------------------------------------
# Width diagnostic shared by both estimators


def _width_check(
    signal_k: np.ndarray,
    std_k: np.ndarray,
    baseline_adjoint: Callable[[np.ndarray], np.ndarray],
    *,
    step: float,
    sigma_beam: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Beam sigma from the inner log-parabola and the WIDTH_INCONSISTENT mask.

    For a Gaussian, q = ln B(-1) - 2 ln B(0) + ln B(+1) = -D^2 / s^2 whatever the offset.
    ``baseline_adjoint(u)`` returns the transpose of the estimator's (linear) baseline
    operator applied to ``u``, so that the formal error of q includes the baseline's noise.
    """
    inner = signal_k[..., _I_M1 : _I_P1 + 1]
    defined = np.all(inner > 0.0, axis=-1)
    safe = np.where(defined[..., None], inner, 1.0)
    q = np.log(safe[..., 0]) - 2.0 * np.log(safe[..., 1]) + np.log(safe[..., 2])
    with np.errstate(invalid="ignore", divide="ignore"):
        width = np.where(defined & (q < 0.0), step / np.sqrt(np.where(q < 0.0, -q, 1.0)), np.nan)
    gradient = np.zeros_like(signal_k)
    gradient[..., _I_M1] = 1.0 / safe[..., 0]
    gradient[..., _I_0] = -2.0 / safe[..., 1]
    gradient[..., _I_P1] = 1.0 / safe[..., 2]
    gradient = gradient - baseline_adjoint(gradient)
    sigma_q = np.sqrt(np.sum((std_k * gradient) ** 2, axis=-1))
    q_nominal = -((step / sigma_beam) ** 2)
    q_narrowest = q_nominal / WIDTH_BAND[0] ** 2
    q_widest = q_nominal / WIDTH_BAND[1] ** 2
    gate = WIDTH_GATE_SIGMA * sigma_q
    inconsistent = defined & ((q < q_narrowest - gate) | (q > q_widest + gate))
    return width, inconsistent


# ---------------------------------------------------------------------------------------------
# Clark


def _end_point_weights(positions: np.ndarray) -> np.ndarray:
    """Weight of P(+4D) in the straight line through the two end points, at each point.

    ``positions`` (..., 5) is where the line runs: sky offsets for Clark's baseline, times
    for the time-linear one. The line is ``P(-4D) (1 - w) + P(+4D) w``.
    """
    first, last = positions[..., :1], positions[..., -1:]
    return (positions - first) / (last - first)


def _end_point_adjoint(u: np.ndarray, weight_hi: np.ndarray) -> np.ndarray:
    """Transpose of the end-point line operator (baseline = K P) applied to ``u``."""
    out = np.zeros(np.broadcast_shapes(u.shape, weight_hi.shape))
    out[..., _I_M4] = np.sum(u * (1.0 - weight_hi), axis=-1)
    out[..., _I_P4] = np.sum(u * weight_hi, axis=-1)
    return out


#: Weight of P(+4D) in Clark's baseline at each point, per reading of "baseline from the
#: +-4D points": ``"line"`` = the straight line through them in offset, ``"mean"`` = their
#: mean (a constant level).
_CLARK_WEIGHTS: dict[str, np.ndarray] = {
    "line": _end_point_weights(OFFSETS_N.astype(float)),
    "mean": np.full(_N_POINTS, 0.5),
}
ClarkBaseline = Literal["line", "mean"]


def _clark_core(
    power: np.ndarray, std: np.ndarray, step: float, sigma_beam: float, reading: str = "line"
) -> tuple[np.ndarray, ...]:
    """Clark's offset, amplitude, formal sigma, baseline, B, log-defined mask, weights."""
    weight_hi = _CLARK_WEIGHTS[reading]
    baseline = power[..., _I_M4, None] * (1.0 - weight_hi) + power[..., _I_P4, None] * weight_hi
    signal = power - baseline
    b_minus, b_zero, b_plus = signal[..., _I_M1], signal[..., _I_0], signal[..., _I_P1]
    log_ok = (b_minus > 0.0) & (b_plus > 0.0)
    safe_minus = np.where(log_ok, b_minus, 1.0)
    safe_plus = np.where(log_ok, b_plus, 1.0)
    scale = sigma_beam**2 / (2.0 * step)
    offset = np.where(log_ok, scale * (np.log(safe_plus) - np.log(safe_minus)), np.nan)
    with np.errstate(over="ignore", invalid="ignore"):
        amplitude = b_zero * np.exp(offset**2 / (2.0 * sigma_beam**2))
    # Linear propagation of the five powers' noise through the log ratio and the baseline.
    gradient = np.zeros_like(power)
    gradient[..., _I_M1] = -1.0 / safe_minus
    gradient[..., _I_P1] = 1.0 / safe_plus
    gradient = gradient - _end_point_adjoint(gradient, weight_hi)
    sigma_offset = np.where(log_ok, scale * np.sqrt(np.sum((std * gradient) ** 2, axis=-1)), np.nan)
    return offset, amplitude, sigma_offset, baseline[..., _I_0], signal, log_ok, weight_hi


def reduce_clark(
    power_k: Any,
    std_k: Any,
    times_s: Any | None = None,
    *,
    step_arcmin: Any = 7.0,
    hpbw_arcmin: Any = 11.0,
    snr_min: float = 4.0,
    baseline: ClarkBaseline = "line",
) -> AxisReduction:
    """Clark's method (Ghigo 1990, section VI) on five-point scans of shape (..., 5).

    With s = HPBW / 2.3548: B(n) = P(n) - baseline(n), a = (s^2 / 2D) ln[B(+1) / B(-1)],
    A = B(0) exp(a^2 / 2s^2), S/N = A / rms(std_k).

    "Baseline from the +-4D points" is read, by default (``baseline="line"``), as the straight
    line through the two +-4D powers evaluated at each offset, ``P(-4) + (P(+4) - P(-4))
    (n + 4) / 8``: it removes a baseline linear in offset exactly, at a cost of 3% in the
    offset's noise at zero offset (the line's slope is antisymmetric, like an offset). The
    other reading, ``baseline="mean"`` (a constant level, the mean of the two), reaches the
    constant-baseline bound at zero offset and reproduces the efficiencies 0.67, 0.27,
    0.10 at 1', 2', 3' (docs/physics.md; the line gives 0.64, 0.26, 0.096). Neither removes a
    drift linear in *time* (the offsets are unevenly spaced in time): a drift of d per integration
    biases the offset by about 4.8' d / A (line) or 9.6' d / A (mean) at zero offset.

    ``times_s`` is accepted (and only shape-checked) so that both :data:`ESTIMATORS` share a
    call signature; Clark's method does not use time. Powers and std in K (``std_k``
    broadcasts against ``power_k``), angles in arcmin. Returns an :class:`AxisReduction`;
    see :class:`Flag` for the flags.
    """
    if baseline not in _CLARK_WEIGHTS:
        raise ValueError(f"baseline must be one of {tuple(_CLARK_WEIGHTS)}; got {baseline!r}")
    power, std, _ = _scan_arrays(power_k, std_k, times_s)
    step, sigma_beam = _beam(step_arcmin, hpbw_arcmin)
    threshold = _snr_threshold(snr_min)
    finite = np.isfinite(power).all(axis=-1) & np.isfinite(std).all(axis=-1)
    power = np.where(finite[..., None], power, 0.0)
    std = np.where(finite[..., None], std, 1.0)

    offset, amplitude, sigma_offset, baseline_k, signal, log_ok, weight_hi = _clark_core(
        power, std, step, sigma_beam, baseline
    )
    snr = amplitude / _noise_k(std)
    width, width_bad = _width_check(
        signal,
        std,
        lambda u: _end_point_adjoint(u, weight_hi),
        step=step,
        sigma_beam=sigma_beam,
    )

    flags = np.zeros(power.shape[:-1], dtype=np.int64)
    flags |= np.where(~log_ok, int(Flag.LOG_ARGUMENT), 0)
    outside = log_ok & (np.abs(offset) > OUTSIDE_PATTERN_STEPS * step)
    flags |= np.where(outside, int(Flag.OUTSIDE_PATTERN), 0)
    flags |= np.where(log_ok & (amplitude <= 0.0), int(Flag.AMPLITUDE_NONPOSITIVE), 0)
    flags |= np.where(log_ok & (snr < threshold), int(Flag.LOW_SNR), 0)
    flags |= np.where(width_bad, int(Flag.WIDTH_INCONSISTENT), 0)
    return _finish(offset, amplitude, snr, sigma_offset, width, baseline_k, flags, finite)


def _finish(
    offset: np.ndarray,
    amplitude: np.ndarray,
    snr: np.ndarray,
    sigma_offset: np.ndarray,
    width: np.ndarray,
    baseline: np.ndarray,
    flags: np.ndarray,
    finite: np.ndarray,
) -> AxisReduction:
    """Blank the outputs of non-finite inputs (FIT_FAILED only) and package the result."""
    nan = np.nan

    def blank(values: np.ndarray) -> np.ndarray:
        return np.asarray(np.where(finite, values, nan), dtype=float)

    flags = np.where(finite, flags, int(Flag.FIT_FAILED)).astype(np.int64)
    return AxisReduction(
        offset_arcmin=blank(offset),
        amplitude_k=blank(amplitude),
        snr=blank(snr),
        sigma_offset_arcmin=blank(sigma_offset),
        width_arcmin=blank(width),
        baseline_k=blank(baseline),
        flags=np.asarray(flags),
    )


# ---------------------------------------------------------------------------------------------
# Weighted linear algebra on (..., 5) arrays (the five points are the last axis)


def _wdot(weight: np.ndarray, left: np.ndarray, right: np.ndarray) -> np.ndarray:
    return np.sum(weight * left * right, axis=-1)


def _orthonormal_basis(weight: np.ndarray, columns: list[np.ndarray]) -> list[np.ndarray]:
    """Weighted Gram-Schmidt (twice, for stability) of ``columns`` -> orthonormal (..., 5)."""
    basis: list[np.ndarray] = []
    for column in columns:
        vector = np.broadcast_to(column, weight.shape).astype(float)
        for _ in range(2):
            for e in basis:
                vector = vector - _wdot(weight, vector, e)[..., None] * e
        norm = np.sqrt(_wdot(weight, vector, vector))
        basis.append(vector / norm[..., None])
    return basis


def _baseline_columns(
    model: str, times: np.ndarray | None, offsets: np.ndarray, shape: tuple[int, ...]
) -> list[np.ndarray]:
    """Nuisance baseline columns of ``model`` broadcast to ``shape`` (..., 5)."""
    ones = np.ones(shape)
    if model == "constant":
        return [ones]
    if model == "linear_time":
        if times is None:
            raise ValueError("baseline='linear_time' needs times_s")
        centred = times - times.mean(axis=-1, keepdims=True)
        span = times.max(axis=-1, keepdims=True) - times.min(axis=-1, keepdims=True)
        return [ones, np.broadcast_to(centred / span, shape)]
    if model == "linear_offset":
        return [ones, np.broadcast_to(offsets / np.abs(offsets).max(), shape)]
    raise ValueError(f"baseline must be one of {_BOUND_BASELINES}; got {model!r}")


def _gaussian_and_derivatives(
    offsets: np.ndarray, centre: np.ndarray, sigma_beam: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit Gaussian g(x - a) and its first two derivatives with respect to the centre a."""
    u = offsets - centre[..., None]
    g = np.exp(-(u**2) / (2.0 * sigma_beam**2))
    g1 = g * u / sigma_beam**2
    g2 = g * (u**2 / sigma_beam**4 - 1.0 / sigma_beam**2)
    return g, g1, g2


def _offset_information(
    weight: np.ndarray,
    basis: list[np.ndarray],
    g: np.ndarray,
    g1: np.ndarray,
) -> np.ndarray:
    """Fisher information on the offset per unit amplitude^2: ||dg/da outside span(basis, g)||^2."""
    gg = _wdot(weight, g, g)
    gg1 = _wdot(weight, g, g1)
    g1g1 = _wdot(weight, g1, g1)
    for e in basis:
        c0, c1 = _wdot(weight, g, e), _wdot(weight, g1, e)
        gg = gg - c0**2
        gg1 = gg1 - c0 * c1
        g1g1 = g1g1 - c1**2
    with np.errstate(invalid="ignore", divide="ignore"):
        return g1g1 - gg1**2 / gg


# ---------------------------------------------------------------------------------------------
# Least squares


def _lsq_block(
    power: np.ndarray,
    std: np.ndarray,
    times: np.ndarray | None,
    *,
    model: str,
    step: float,
    sigma_beam: float,
    threshold: float,
) -> tuple[np.ndarray, ...]:
    """LSQ reduction of a flat block of finite scans (scans, 5) -> per-scan output arrays.

    Steps: the baseline projected out of the data; a start where the profiled fit is best,
    on a grid over the pattern or at Clark's value; safeguarded Newton to the maximum; the
    linear parameters and the offset's formal error there; the width check; the flags.
    """
    offsets = OFFSETS_N * step
    weight = 1.0 / std**2
    basis = _orthonormal_basis(weight, _baseline_columns(model, times, offsets, power.shape))
    profile = _Profile(weight, _outside(power, weight, basis), basis, offsets, sigma_beam)
    half_range = _LSQ_GRID_STEPS * step
    start, phi_start, spacing = _grid_start(profile, half_range)
    start, phi_start = _clark_start(profile, power, std, step, half_range, start, phi_start)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        centre, converged, downhill = _newton_maximum(profile, start, phi_start, spacing,
                                                      half_range)
        amplitude, sigma_offset, baseline_curve, den = _at_maximum(profile, power, centre)
    width, width_bad = _end_point_width(power, std, times, step, sigma_beam)
    snr = amplitude / _noise_k(std)
    positive = amplitude > 0.0
    failed = ~(converged | downhill) | (positive & ~np.isfinite(sigma_offset)) | ~(den > 0.0)

    flags = np.zeros(centre.shape, dtype=np.int64)
    flags |= np.where(
        positive & (np.abs(centre) > OUTSIDE_PATTERN_STEPS * step), int(Flag.OUTSIDE_PATTERN), 0
    )
    flags |= np.where(~positive, int(Flag.AMPLITUDE_NONPOSITIVE), 0)
    flags |= np.where(snr < threshold, int(Flag.LOW_SNR), 0)
    flags |= np.where(positive & width_bad, int(Flag.WIDTH_INCONSISTENT), 0)
    flags |= np.where(failed, int(Flag.FIT_FAILED), 0)
    offset = np.where(positive, centre, np.nan)
    sigma_offset = np.where(positive, sigma_offset, np.nan)
    width = np.where(positive, width, np.nan)
    return offset, amplitude, snr, sigma_offset, width, baseline_curve[..., _I_0], flags


def _outside(power: np.ndarray, weight: np.ndarray, basis: list[np.ndarray]) -> np.ndarray:
    """The data with the baseline projected out: with r orthogonal to the baseline,
    <r, g> is the numerator of the profiled amplitude for any centre."""
    residual = power.copy()
    for e in basis:
        residual = residual - _wdot(weight, power, e)[..., None] * e
    return residual


class _Profile:
    """The profiled fit of a block of scans as a function of the centre a: phi(a) = <r, g_a> /
    ||g_a outside the baseline||, the signed square root of the chi^2 reduction (its maximum
    is the positive-amplitude fit), with r the data outside the baseline."""

    def __init__(self, weight: np.ndarray, residual: np.ndarray, basis: list[np.ndarray],
                 offsets: np.ndarray, sigma_beam: float):
        self.weight = weight
        self.residual = residual
        self.basis = basis
        self.offsets = offsets
        self.sigma_beam = sigma_beam

    def __call__(
        self, centre: np.ndarray, rows: slice | np.ndarray = slice(None)
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """phi and its first two derivatives in the centre a, for the scans ``rows``."""
        w, r, es = self.weight[rows], self.residual[rows], [e[rows] for e in self.basis]
        g, g1, g2 = _gaussian_and_derivatives(self.offsets, centre, self.sigma_beam)
        num, num1, num2 = (_wdot(w, r, v) for v in (g, g1, g2))
        gg, gg1, g1g1, gg2 = (_wdot(w, g, g), _wdot(w, g, g1), _wdot(w, g1, g1), _wdot(w, g, g2))
        for e in es:
            c0, c1, c2 = (_wdot(w, v, e) for v in (g, g1, g2))
            gg, gg1, g1g1, gg2 = gg - c0**2, gg1 - c0 * c1, g1g1 - c1**2, gg2 - c0 * c2
        den, den1, den2 = gg, 2.0 * gg1, 2.0 * (g1g1 + gg2)
        root = np.sqrt(den)
        phi = num / root
        phi1 = num1 / root - 0.5 * num * den1 / den**1.5
        phi2 = (
            num2 / root
            - num1 * den1 / den**1.5
            - 0.5 * num * den2 / den**1.5
            + 0.75 * num * den1**2 / den**2.5
        )
        return phi, phi1, phi2


def _grid_start(profile: _Profile, half_range: float
                ) -> tuple[np.ndarray, np.ndarray, float]:
    """The best node of a coarse grid over the pattern (s/8 apart): start, phi there, and
    the grid's spacing."""
    weight, offsets, sigma_beam = profile.weight, profile.offsets, profile.sigma_beam
    spacing = sigma_beam / _LSQ_GRID_PER_SIGMA
    n_nodes = max(round(2.0 * half_range / spacing) + 1, 3)  # a pattern narrow to the beam
    grid = np.linspace(-half_range, half_range, n_nodes)
    spacing = grid[1] - grid[0]
    g_grid = np.exp(-((offsets[None, :] - grid[:, None]) ** 2) / (2.0 * sigma_beam**2))
    numerator = (weight * profile.residual) @ g_grid.T
    denominator = weight @ (g_grid**2).T
    for e in profile.basis:
        denominator = denominator - ((weight * e) @ g_grid.T) ** 2
    phi_grid = numerator / np.sqrt(denominator)
    best = np.argmax(phi_grid, axis=-1)
    phi_start = np.take_along_axis(phi_grid, best[:, None], axis=-1)[:, 0]
    return grid[best], phi_start, spacing


def _clark_start(profile: _Profile, power: np.ndarray, std: np.ndarray, step: float,
                 half_range: float, start: np.ndarray, phi_start: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Clark's value as the start where it beats the best node (it can fall between nodes
    near a narrow maximum at high S/N); the start and phi there."""
    clark_offset = _clark_core(power, std, step, profile.sigma_beam)[0]
    usable = np.isfinite(clark_offset) & (np.abs(clark_offset) <= half_range)
    clark_start = np.where(usable, clark_offset, 0.0)
    phi_clark = np.where(usable, profile(clark_start)[0], -np.inf)
    use_clark = phi_clark > phi_start
    return np.where(use_clark, clark_start, start), np.where(use_clark, phi_clark, phi_start)


def _newton_maximum(profile: _Profile, start: np.ndarray, phi_start: np.ndarray,
                    spacing: float, half_range: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Safeguarded Newton (rtsafe) for phi' = 0 inside [start - h, start + h]: Newton where it
    stays inside the bracket on a concave phi, bisection otherwise; iterate only on the
    scans not yet converged (most take three steps). The centre, whether each converged, and
    where the start was kept because the refinement went downhill."""
    low = np.maximum(start - spacing, -half_range)
    high = np.minimum(start + spacing, half_range)
    centre = start.copy()
    tolerance = _LSQ_TOLERANCE_SIGMA * profile.sigma_beam
    converged = np.zeros(centre.shape, dtype=bool)
    active = np.arange(centre.size)
    for _ in range(_LSQ_MAX_ITERATIONS):
        if active.size == 0:
            break
        here = centre[active]
        _, slope, curvature = profile(here, active)
        lo = np.where(slope > 0.0, here, low[active])
        hi = np.where(slope <= 0.0, here, high[active])
        step_newton = -slope / curvature
        concave = curvature < 0.0
        newton = here + step_newton
        # A Newton step below tolerance ends the search even if roundoff puts it a hair
        # outside the bracket (bisecting there would jump half a bracket away).
        small = concave & (np.abs(step_newton) < tolerance)
        inside = concave & (newton > lo) & (newton < hi)
        updated = np.where(small | inside, newton, 0.5 * (lo + hi))
        updated = np.where(slope == 0.0, here, updated)
        done = small | (hi - lo < tolerance) | (slope == 0.0)
        centre[active], low[active], high[active] = updated, lo, hi
        converged[active[done]] = True
        active = active[~done]
    phi_end = profile(centre)[0]
    # Keep the start if the refinement went clearly downhill (cannot happen on a
    # unimodal bracket; a guard against a non-bracketing start). "Clearly": phi is flat
    # at its maximum, so a start within 1e-7' of it can win by rounding alone.
    downhill = ~(phi_end >= phi_start - 1e-10 * np.abs(phi_start))
    return np.where(downhill, start, centre), converged, downhill


def _at_maximum(profile: _Profile, power: np.ndarray, centre: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """At the fitted centre: the amplitude, the offset's formal error (all parameters free),
    the fitted baseline at the five points, and ||g outside the baseline||^2."""
    weight, basis = profile.weight, profile.basis
    g, g1, _ = _gaussian_and_derivatives(profile.offsets, centre, profile.sigma_beam)
    projections = [_wdot(weight, g, e) for e in basis]
    g_outside = g - sum(c[..., None] * e for c, e in zip(projections, basis, strict=True))
    den = _wdot(weight, g_outside, g_outside)
    amplitude = _wdot(weight, profile.residual, g) / den
    data_on_basis = [_wdot(weight, power, e) for e in basis]
    baseline_curve = sum(
        (d - amplitude * c)[..., None] * e
        for d, c, e in zip(data_on_basis, projections, basis, strict=True)
    )
    information = amplitude**2 * _offset_information(weight, basis, g, g1)
    return amplitude, 1.0 / np.sqrt(information), baseline_curve, den


def _end_point_width(power: np.ndarray, std: np.ndarray, times: np.ndarray | None,
                     step: float, sigma_beam: float) -> tuple[np.ndarray, np.ndarray]:
    """Width diagnostic on a baseline that does not depend on the assumed width: the line
    through the two +-4D powers in time (level = their mean for a constant baseline), where
    the beam is 1.6e-8 of its peak. The fitted baseline would absorb part of a wider
    source's wings and pull the estimated width back towards the nominal one."""
    if times is None:
        weight_hi = np.full(power.shape, 0.5)
    else:
        weight_hi = _end_point_weights(times)
    line = power[..., _I_M4, None] * (1.0 - weight_hi) + power[..., _I_P4, None] * weight_hi
    return _width_check(
        power - line,
        std,
        lambda u: _end_point_adjoint(u, weight_hi),
        step=step,
        sigma_beam=sigma_beam,
    )


def reduce_lsq(
    power_k: Any,
    std_k: Any,
    times_s: Any | None = None,
    *,
    step_arcmin: Any = 7.0,
    hpbw_arcmin: Any = 11.0,
    snr_min: float = 4.0,
    baseline: BaselineModel = "linear_time",
) -> AxisReduction:
    """Fixed-width Gaussian + baseline least-squares fit of five-point scans (..., 5).

    Model: P(n) = c0 + c1 t(n) + A exp(-(nD - a)^2 / 2s^2), s = HPBW / 2.3548, weights
    1 / std_k^2 (``std_k`` broadcasts against ``power_k``). The baseline is linear in time,
    as in the VLBI Field System's ``fivpt``, so that gain drift during the scan does not turn
    into offset bias; ``baseline="constant"`` drops c1 (``times_s`` may then be None).

    The linear parameters (c0, c1, A) are profiled out; the offset maximizes the profiled fit
    over +-3D: a grid at s/8 spacing and Clark's value as starting points, then safeguarded
    Newton (bisection fallback) to 1e-10 beam sigma. A > 0 is enforced: where no positive-amplitude
    solution exists, AMPLITUDE_NONPOSITIVE and offset NaN. ``sigma_offset_arcmin`` is the
    formal error from the covariance with all parameters free (equal to
    :func:`cramer_rao_offset_arcmin` with ``baseline="linear_time"`` at the true values).
    ``width_arcmin`` and the width flag use the inner log-parabola after removing the line
    through the two +-4D powers in time (not the fitted baseline, which depends on the
    assumed width). Outputs as :class:`AxisReduction`; flags as :class:`Flag`.

    Powers and std in K, times in s (any origin, strictly increasing), angles in arcmin.
    """
    if baseline not in ("constant", "linear_time"):
        raise ValueError(f"baseline must be 'constant' or 'linear_time'; got {baseline!r}")
    if baseline == "linear_time" and times_s is None:
        raise ValueError(
            "reduce_lsq with baseline='linear_time' needs times_s (shape (..., 5), seconds)"
        )
    power, std, times = _scan_arrays(power_k, std_k, times_s if baseline != "constant" else None)
    step, sigma_beam = _beam(step_arcmin, hpbw_arcmin)
    threshold = _snr_threshold(snr_min)
    batch_shape = power.shape[:-1]
    finite = np.isfinite(power).all(axis=-1) & np.isfinite(std).all(axis=-1)
    if times is not None:
        finite &= np.isfinite(times).all(axis=-1)

    flat_power = power.reshape(-1, _N_POINTS)
    flat_std = std.reshape(-1, _N_POINTS)
    flat_times = None if times is None else times.reshape(-1, _N_POINTS)
    flat_finite = finite.reshape(-1)
    n_scans = flat_power.shape[0]
    outputs = [np.full(n_scans, np.nan) for _ in range(6)]
    flags = np.full(n_scans, int(Flag.FIT_FAILED), dtype=np.int64)
    index = np.flatnonzero(flat_finite)
    for begin in range(0, index.size, _CHUNK):
        rows = index[begin : begin + _CHUNK]
        *values, block_flags = _lsq_block(
            flat_power[rows],
            flat_std[rows],
            None if flat_times is None else flat_times[rows],
            model=baseline,
            step=step,
            sigma_beam=sigma_beam,
            threshold=threshold,
        )
        for output, value in zip(outputs, values, strict=True):
            output[rows] = value
        flags[rows] = block_flags
    offset, amplitude, snr, sigma_offset, width, baseline_k = (
        o.reshape(batch_shape) for o in outputs
    )
    return AxisReduction(
        offset_arcmin=offset,
        amplitude_k=amplitude,
        snr=snr,
        sigma_offset_arcmin=sigma_offset,
        width_arcmin=width,
        baseline_k=baseline_k,
        flags=flags.reshape(batch_shape),
    )


# ---------------------------------------------------------------------------------------------
# Cramér-Rao bound


def cramer_rao_offset_arcmin(
    snr: Any,
    offset_arcmin: Any,
    *,
    step_arcmin: Any = 7.0,
    hpbw_arcmin: Any = 11.0,
    baseline: Literal["constant", "linear_time", "linear_offset"] = "constant",
    times_s: Any | None = None,
) -> np.ndarray:
    """Cramér-Rao lower bound on the standard deviation of the offset (arcmin).

    Model: the five points P(n) = baseline + A g(nD - a) with white noise sigma = A / snr
    per point, s = HPBW / 2.3548 and the width known. The bound is 1 / sqrt(F_aa) after the
    nuisance parameters are profiled out of the Fisher matrix (Schur complement):

    - ``"constant"``: level and amplitude free. At a = 0 it equals
      sigma s^2 exp(D^2 / 2s^2) / (sqrt(2) A D) = 6.77' / snr for the 45-ft.
    - ``"linear_time"``: level, slope in time and amplitude free (the model of
      :func:`reduce_lsq`). Larger: the time slope is antisymmetric about the centre
      integration, like the signature of an offset, and absorbs part of it (x1.118 at a = 0
      for equally spaced times).
    - ``"linear_offset"``: level, slope in offset and amplitude free (the baseline model of
      :func:`reduce_clark`; x1.031 at a = 0).

    ``snr`` (> 0) and ``offset_arcmin`` broadcast together; ``times_s`` (5,) defaults to
    equally spaced integrations in the order of :data:`OFFSETS_N` (only its spacing
    pattern matters).
    """
    step, sigma_beam = _beam(step_arcmin, hpbw_arcmin)
    ratio = _as_float_array(snr, "", "snr")
    centre = _as_float_array(offset_arcmin, "arcmin", "offset_arcmin")
    if np.any(~(ratio > 0.0)):
        raise ValueError("snr must be > 0 (amplitude / noise per point)")
    if np.any(~np.isfinite(centre)):
        raise ValueError("offset_arcmin must be finite")
    if baseline not in _BOUND_BASELINES:
        raise ValueError(f"baseline must be one of {_BOUND_BASELINES}; got {baseline!r}")
    if times_s is None:
        times = np.arange(_N_POINTS, dtype=float)
    else:
        times = _as_float_array(times_s, "s", "times_s")
        if times.shape != (_N_POINTS,) or np.any(np.diff(times) <= 0.0):
            raise ValueError(f"times_s must be {_N_POINTS} strictly increasing values (s)")
    ratio, centre = np.broadcast_arrays(ratio, centre)
    offsets = OFFSETS_N * step
    shape = (*centre.shape, _N_POINTS)
    weight = np.ones(shape)
    basis = _orthonormal_basis(
        weight, _baseline_columns(baseline, np.broadcast_to(times, shape), offsets, shape)
    )
    g, g1, _ = _gaussian_and_derivatives(offsets, centre, sigma_beam)
    information = _offset_information(weight, basis, g, g1)
    return np.asarray(1.0 / (ratio * np.sqrt(information)))


#: Estimators by name; all take ``(power_k, std_k, times_s, **options)``.
ESTIMATORS: dict[str, Callable[..., AxisReduction]] = {
    "clark": reduce_clark,
    "lsq": reduce_lsq,
}
