"""Predicted error of every fitted term, from the design and a noise model of the physics.

The design is the schedule the controller produces (the deterministic run of
:func:`antsim.simulate.vectorized.record_schedule`): one row per scan its reduction accepts, at the
scan's position. The fitter's final estimate is least squares, so the predicted covariance of
the terms is the sandwich ``B A^T C A B`` with ``B = (A^T A)^-1`` and ``C`` the covariance of
the measured offsets (arcsec^2); for independent offsets of equal variance s^2 it is the
inverse Fisher information s^2 B (the JSON keeps the name ``sigma_fisher_arcsec``).

``C`` is predicted, scan by scan, by propagating each source of noise through the linear
response of the controller's own estimator (:func:`controller.scans.scan.reduce_sources`, finite
differences at the noise-free powers; for white noise this is the Cramer-Rao bound of
:func:`controller.scans.reduction.cramer_rao_offset_arcmin` where the estimator reaches it) and
through the beam (the world's :meth:`~antsim.world.world.World.sample_blocks`, nudged):

* receiver: gain fluctuations (Ornstein-Uhlenbeck of each channel: the exact covariance of
  the integration means, correlated between the five points of an axis and between scans)
  and radiometer noise, T_sys + source + sky emission per integration;
* tracking jitter: the OU wander averaged over each integration, its rms scaled by the wind
  at the time (the effect's own formula), correlated between points and between scans;
* gusts: their expected second moment (Poisson rate times the overlap of the effect's gust
  profile with the integrations; gusts are rare and heavy-tailed, so this is an average);
* thermal: the random part of the slow errors (cloud modulation, lateral forcing, weather
  wander), correlated over hours: from independent draws of those effects alone, solved along
  the schedule exactly as the world solves them (no receiver, reduction or fit involved).

The fitter is robust: it rejects the observations whose residuals exceed 4x the mean
absolute deviation of a LAD fit or 3x the rms. Which ones it rejects changes from campaign to
campaign, and each rejection moves the estimate: that adds scatter (with the deterministic
residuals of the day's thermal errors, about 7% in sigma for the 24-hour run, up to 70% for
W5 on a 3-hour day) and shifts the mean, both from the fitter's own stages run on draws of
the predicted noise (:func:`rejection_draws`).

Deterministic errors (the mean thermal and sunset drift, source structure, the controller's
refraction) are the same in every member: they bias the terms, predicted by least squares on
the noise-free run shifted by the expected rejections, and add no scatter. The estimator's
non-linearity beyond first order, and the heavy tails of gusts (their variance is used, the
rejections' draws are Gaussian), are left to the Monte Carlo.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from antsim.simulate.ensemble import Job, engine_for
from antsim.simulate.vectorized import MemberEngine, SharedSchedule
from antsim.world.effects.tracking import TrackingJitter
from controller.pointing.model import PointingModel
from controller.pointing.robust import (
    LAD_FACTOR,
    RMS_FACTOR,
    Equations,
    lad_fit,
    least_squares_fit,
    reject_beyond_mad,
    reject_beyond_rms,
)
from controller.pointing.thermal import sensor_aux, structure_sensor_names
from controller.scans.scan import reduce_sources

__all__ = ["NoiseModel", "Prediction", "RejectionDesign", "RejectionDraws", "noise_model",
           "predict", "predict_prefixes", "rejection_design", "rejection_draws", "task_noise",
           "task_thermal", "thermal_errors", "thermal_offsets", "truth_vector", "with_thermal"]

#: nudge of the pointing for the linear response of the powers (arcsec)
NUDGE_ARCSEC = 1.0
#: step in power for the estimator's gradient (K)
POWER_STEP_K = 1e-3
#: correlations beyond this many OU time constants are neglected
WINDOW_TAUS = 8.0
#: spawn key of the thermal draws (member keys are smaller)
THERMAL_KEY = 1 << 40
#: step of the gust start times integrated over (s)
GUST_STEP_S = 1.0
COMPONENTS = ("receiver", "jitter", "gusts", "thermal")
#: draws of the predicted noise through the robust fitter (:func:`rejection_draws`): the
#: rejection component's variance to sqrt(2 / 64) = 18%, a few percent of a sigma
REJECTION_DRAWS = 64
REJECTION_SEED = 1990


@dataclass
class NoiseModel:
    """Per-scan offset noise of one variant's design (arcsec).

    ``units`` are the (scan, axis) pairs of the design's scans (axis 0: cross-elevation,
    1: elevation), ``pairs`` (i, j) unit pairs with their covariance per component
    ``pair_cov[component]`` (white and short-range correlated components), ``thermal`` the
    offsets of ``n_thermal`` draws of the random slow errors (draws, units), ``scans`` the
    design's scan indices in time order.
    """

    scans: np.ndarray
    pairs: np.ndarray
    pair_cov: dict[str, np.ndarray]
    thermal: np.ndarray
    response: np.ndarray  # (scans, axes, 5 points, 2 displacement axes)
    gradient: np.ndarray  # (scans, axes, 5) arcsec per K
    quiet_offsets: np.ndarray  # (scans, axes) arcsec, the noise-free reduction
    notes: list[str] = field(default_factory=list)

    @property
    def n_thermal(self) -> int:
        return int(self.thermal.shape[0])

    def unit_variance(self, component: str) -> np.ndarray:
        """Variance of each unit's offset from one component (arcsec^2), (scans, axes)."""
        n = self.scans.size
        out = np.zeros(2 * n)
        if component == "thermal":
            if self.n_thermal > 1:
                out = self.thermal.var(axis=0, ddof=1)
        else:
            same = self.pairs[:, 0] == self.pairs[:, 1]
            np.add.at(out, self.pairs[same, 0], self.pair_cov[component][same])
        return out.reshape(2, n).T

    def budget(self) -> dict[str, dict[str, float]]:
        """rms over the scans of each component's offset noise, xel and el (arcsec)."""
        out = {}
        for c in COMPONENTS:
            var = self.unit_variance(c)
            out[c] = {"xel_arcsec": float(np.sqrt(var[:, 0].mean())),
                      "el_arcsec": float(np.sqrt(var[:, 1].mean()))}
        return out


@dataclass
class Prediction:
    """Predicted covariance of the fitted terms (arcsec^2) and what follows from it:
    ``components`` per noise source and for the robust fit's rejections, the predicted
    bias (the noise-free data's least-squares fit, shifted by the expected rejections, minus
    the truth), and the Sky RMS of the used observations."""

    names: tuple[str, ...]
    covariance: np.ndarray
    design_correlation: np.ndarray
    sky_rms_arcsec: float
    n_scans: int
    components: dict[str, np.ndarray]  # per-component covariance of the terms
    bias_arcsec: np.ndarray  # predicted mean of fitted minus true
    n_rejected: float  # expected observations the robust fit rejects
    #: sampling (Monte Carlo) error of the covariance's diagonal (arcsec^2) and of the bias
    #: (arcsec) from the prediction's two simulated parts: the thermal draws and the
    #: rejections' draws (:func:`_rejection`)
    variance_error: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bias_error_arcsec: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def sigma_arcsec(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    @property
    def sigma_error_arcsec(self) -> np.ndarray:
        """Sampling error of each sigma: that of its variance over 2 sigma."""
        sigma = self.sigma_arcsec
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(sigma > 0, self.variance_error / (2.0 * sigma), np.nan)

    def cannot_separate(self, level: float = 0.95) -> list[tuple[str, str, float]]:
        """Pairs of terms whose predicted correlation exceeds ``level`` in magnitude."""
        sd = self.sigma_arcsec
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = self.covariance / np.outer(sd, sd)
        out = []
        m = len(self.names)
        for i in range(m):
            for j in range(i + 1, m):
                r = float(corr[i, j])
                if math.isfinite(r) and abs(r) > level:
                    out.append((self.names[i], self.names[j], r))
        return out


# ---------------------------------------------------------------------------------------------
def truth_vector(scenario, terms) -> np.ndarray:
    """The injected value (arcsec) of each fitted term (names or terms), in fit order:
    :meth:`antsim.scenario.Scenario.truth_arcsec`."""
    names = tuple(t.strip().upper() if isinstance(t, str) else t.name for t in terms)
    truth = scenario.truth_arcsec(names)
    return np.array([truth[n] for n in names])


def _design(columns: dict[str, np.ndarray], terms, rows: np.ndarray,
            sensor_lag_s: float = 0.0) -> np.ndarray:
    """Design matrix of the fit (2n x m: cross-axis rows then the second axis' rows), as the
    fitter builds it (:func:`controller.pointing.variants.pointing_data`): on an equatorial
    mount's hour angle and declination when the rows carry them, else azimuth and
    elevation; thermal terms read the rows' structure temperatures, corrected for the
    sensors' response time ``sensor_lag_s``."""
    lon, lat = ("ha_deg", "dec_deg") if "ha_deg" in columns else ("az_deg", "el_deg")
    az = np.radians(columns[lon][rows].astype(float))
    el = np.radians(columns[lat][rows].astype(float))
    sensors = structure_sensor_names(list(columns))
    aux = sensor_aux({k: v[rows] for k, v in columns.items() if k.startswith("temp_")},
                     sensors, sensor_lag_s) if sensors else None
    basis_az, basis_el = PointingModel(list(terms)).design_matrix(az, el, aux=aux)
    return np.vstack([basis_az * np.cos(el)[:, None], basis_el])


def terms_without_lever_arm(shared: SharedSchedule, terms: Sequence[str]) -> list[str]:
    """The fit's terms whose column is zero at every scan of ``shared``, the noise-free run:
    a thermal term of a difference only random forcing drives (the yoke's left-right), a term
    of a sensor that reads constant. Neither the prediction nor the members can determine
    them: the least-squares normal matrix is singular in them. Zero exactly, not small: the
    sensors' readings are rounded to their resolution, so an undriven difference is 0.0."""
    rows = np.arange(len(shared.scan_times))
    a = _design(shared.columns, terms, rows, shared.sensor_lag_s)
    names = PointingModel(list(terms)).names
    return [name for name, peak in zip(names, np.abs(a).max(axis=0), strict=True)
            if not peak > 0.0]


def _ou_mean_cov(t1: np.ndarray, t2: np.ndarray, tau: float) -> np.ndarray:
    """Covariance of the means of a unit-rms OU process over sample sets: t1 (P, 5, n),
    t2 (P, 5, n) -> (P, 5, 5)."""
    diff = np.abs(t1[:, :, None, :, None] - t2[:, None, :, None, :])
    return np.exp(-diff / tau).mean(axis=(3, 4))


def noise_model(engine: MemberEngine, plan_seed: int, n_thermal: int = 256) -> NoiseModel:
    """The per-scan offset noise of ``engine``'s variant (see the module docstring), in
    steps: the noise-free powers and their response to a pointing nudge; the statistics of
    the receiver and of the tracking jitter per integration; the estimator's gradient at the
    noise-free powers; the pairs of offsets close enough in time to correlate and their
    covariance per component; the random slow (thermal) errors, drawn alone."""
    sh = engine.shared
    stats = _integration_statistics(engine)
    gradient, off, good, notes = _estimator_gradient(engine, stats)
    scans = np.flatnonzero(good)
    idx = sh.scan_int[scans]  # (n, 2, 5) integration indices
    slope_avg = stats.slope.mean(axis=1)  # (integrations, 2) dP_AVG per arcsec
    response = gradient[scans][..., None] * slope_avg[idx]  # (n, 2, 5, 2)
    pairs, unit_scan, unit_axis = _unit_pairs(sh, scans, stats)
    cov = _pair_covariances(sh, stats, pairs, unit_scan, unit_axis, idx, gradient[scans],
                            response)
    thermal = _thermal_draws(engine, plan_seed, n_thermal, response, idx)
    quiet = off[scans, :, 0]
    return NoiseModel(scans=scans, pairs=pairs, pair_cov=cov, thermal=thermal,
                      response=response, gradient=gradient[scans], quiet_offsets=quiet,
                      notes=notes)


@dataclass
class _Statistics:
    """Per integration (and channel): the noise-free power ``p0`` (K) and its response to
    the pointing ``slope`` (K/arcsec, xel and el); the receiver's gain fluctuation ``rms_g``
    and time constant ``tau_g``, radiometer variance per sample ``rad_var``, samples
    ``n_s``; the tracking jitter's rms ``jit_sd`` (arcsec, xel and el) and time constant
    ``tau_j``; the gusts' (energy, duration, time grid, profile) or None; and the expected
    sample std the estimator is given, ``exp_std``."""

    p0: np.ndarray
    slope: np.ndarray
    rms_g: np.ndarray
    tau_g: float
    rad_var: np.ndarray
    n_s: np.ndarray
    jit_sd: np.ndarray
    tau_j: float
    gust: tuple | None
    exp_std: np.ndarray


def task_noise(job: Job, n_thermal: int) -> tuple[NoiseModel, list[str]]:
    """The noise model of a variant and why its schedule cannot be shared (if so): a task for
    :mod:`antsim.simulate.ensemble`'s executors (module level, picklable by reference)."""
    engine = engine_for(job)
    return noise_model(engine, job.plan_seed, n_thermal=n_thermal), list(engine.unshareable)


def _integration_statistics(engine: MemberEngine) -> _Statistics:
    """The noise-free powers, their response to a nudge, the receiver's and the jitter's
    statistics per integration, and the sample std the estimator expects."""
    sh = engine.shared
    # noise-free powers and their response to a pointing nudge (members: 0, +-x, +-e)
    h = NUDGE_ARCSEC / 206264.80624709636
    nx = np.array([0.0, h, -h, 0.0, 0.0])
    ne = np.array([0.0, 0.0, 0.0, h, -h])
    power, _ = engine.simulate(None, nudges=(nx, ne), quiet=True)
    p0 = power[:, 0, :]  # (integrations, channels)
    slope = np.stack([(power[:, 1] - power[:, 2]), (power[:, 3] - power[:, 4])],
                     axis=-1) / (2 * NUDGE_ARCSEC)  # (integrations, channels, 2) K/arcsec
    rec = engine.scenario.receiver
    rms_g = np.array([rec.gain_fluctuation if c.gain_fluctuation is None else c.gain_fluctuation
                      for c in rec.channels])
    tau_g = rec.gain_timescale_s
    rad_var = p0 ** 2 / (rec.bandwidth_mhz * 1e6 * rec.sample_interval_s)  # per sample
    jit_sd, tau_j, gust = _jitter_statistics(engine)
    # expected sample std per integration and channel (the estimator's std_k)
    n_s = np.array([t.size for t in sh.t])
    same_g = np.array([_ou_mean_cov(t[None, None], t[None, None], tau_g)[0, 0, 0]
                       for t in sh.t])
    same_j = np.array([_ou_mean_cov(t[None, None], t[None, None], tau_j)[0, 0, 0]
                       for t in sh.t])
    var_s = (p0 ** 2 * rms_g ** 2 + rad_var
             + (slope ** 2 * jit_sd[:, None, :] ** 2).sum(axis=-1))
    var_m = (p0 ** 2 * rms_g ** 2 * same_g[:, None] + rad_var / n_s[:, None]
             + (slope ** 2 * jit_sd[:, None, :] ** 2).sum(axis=-1) * same_j[:, None])
    exp_std = np.sqrt(np.clip(n_s[:, None] / np.maximum(n_s[:, None] - 1, 1)
                              * (var_s - var_m), 1e-30, None))
    return _Statistics(p0, slope, rms_g, tau_g, rad_var, n_s, jit_sd, tau_j, gust, exp_std)


def _jitter_statistics(engine: MemberEngine) -> tuple[np.ndarray, float, tuple | None]:
    """The tracking jitter's rms per integration (arcsec, xel and el; the effect's own
    scaling with the wind), its time constant (s), and the gusts' expected energy (rate
    times amplitude squared), duration, and profile on a time grid (None without gusts)."""
    sh = engine.shared
    jit = [(i, spec) for kind, i, spec in engine._kinds if kind == "jitter"]
    n_int = sh.n_integrations
    jit_sd = np.zeros((n_int, 2))
    tau_j = 1.0
    gust = None
    if jit:
        _, spec = jit[0]
        effect = TrackingJitter(**spec.params)
        effect.start(engine._view(0), np.random.default_rng(0))
        tau_j = float(spec.params["timescale_s"])

        class _Ones:
            def sample(self, t):
                return np.ones((t.size, 2))

        effect.process = _Ones()
        effect.gust_start_s = np.zeros(0)
        for k in range(n_int):
            t = sh.t[k][:1]
            el = float(sh.enc_el[k][0])
            a, e = effect.sample_error(t, el)
            jit_sd[k] = (float(a[0]) * math.cos(el) * 206264.80624709636,
                         float(e[0]) * 206264.80624709636)
        rate = float(spec.params["gust_rate_per_h"]) / 3600.0
        if rate > 0 and (spec.params["gust_arcsec"] > 0 or effect.compliance > 0):
            dur = float(spec.params["gust_duration_s"])
            probe = TrackingJitter(**spec.params)
            probe.start(engine._view(0), np.random.default_rng(0))
            probe.gust_start_s = np.array([0.0])
            probe.gust_rad = np.array([[1.0, 1.0]])
            tau_grid = np.linspace(-1.0, dur + 1.0, 2000)
            profile = probe.gusts_rad(tau_grid)[:, 0]
            energy = (rate * float(spec.params["gust_arcsec"]) ** 2 if effect.compliance == 0
                      else probe.gust_energy_arcsec2_per_s(np.concatenate(sh.t)))
            gust = (energy, dur, tau_grid, profile)
    return jit_sd, tau_j, gust


def _estimator_gradient(engine: MemberEngine, stats: _Statistics
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """The controller's estimator at the noise-free powers with the expected std, and its
    gradient by finite differences (arcsec per K, (scans, axes, 5)); the offsets of every
    trial (arcsec); which scans enter the design (unflagged at the predicted noise); notes."""
    sh = engine.shared
    p_scan, s_scan, times = engine.scan_powers(stats.p0[:, None, :], stats.exp_std[:, None, :])
    p_avg, s_avg, t_avg = p_scan[0, :, :, -1], s_scan[0, :, :, -1], times[0, :, :, -1]
    n_scans = p_avg.shape[0]
    steps = np.concatenate([np.zeros((1, 5)), POWER_STEP_K * np.eye(5),
                            -POWER_STEP_K * np.eye(5)])  # (11, 5)
    trial = p_avg[:, :, None, :] + steps[None, None]
    reduced = engine_reduce(engine, trial, s_avg[:, :, None, :], t_avg[:, :, None, :])
    off = np.asarray(reduced.offset_arcmin) * 60.0  # (scans, axes, 11) arcsec
    flags = np.asarray(reduced.flags)[:, :, 0]
    gradient = (off[:, :, 1:6] - off[:, :, 6:11]) / (2 * POWER_STEP_K)  # arcsec per K
    good = (flags == 0).all(axis=1) & sh.columns["good"].astype(bool) \
        & np.isfinite(gradient).all(axis=(1, 2))
    notes = []
    if (~good).sum():
        notes.append(f"{int((~good).sum())} of {n_scans} scans left out of the design (the "
                     "reduction flags them at the predicted noise, e.g. S/N < snr_min)")
    return gradient, off, good, notes


def _unit_pairs(sh: SharedSchedule, scans: np.ndarray, stats: _Statistics
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The (unit, unit) pairs within the correlation window (a unit is one scan's offset on
    one axis: the scans' xel units, then their el units), and each unit's scan and axis."""
    n = scans.size
    unit_t = np.concatenate([sh.scan_times[scans, 0].mean(axis=1),
                             sh.scan_times[scans, 1].mean(axis=1)])
    unit_scan = np.concatenate([np.arange(n), np.arange(n)])
    unit_axis = np.concatenate([np.zeros(n, int), np.ones(n, int)])
    window = WINDOW_TAUS * max(stats.tau_g, stats.tau_j) + 300.0
    order = np.argsort(unit_t, kind="stable")
    pairs = []
    for a_pos, u in enumerate(order):
        hi = np.searchsorted(unit_t[order], unit_t[u] + window, side="right")
        for v in order[a_pos:hi]:
            pairs.append((u, v))
    pairs = np.array(pairs, dtype=np.int64).reshape(-1, 2)
    return pairs, unit_scan, unit_axis


def _pair_covariances(sh: SharedSchedule, stats: _Statistics, pairs: np.ndarray,
                      unit_scan: np.ndarray, unit_axis: np.ndarray, idx: np.ndarray,
                      grad_u: np.ndarray, response: np.ndarray) -> dict[str, np.ndarray]:
    """The covariance of each pair's offsets from the receiver (gain OU per channel and
    radiometer noise), the jitter's OU and the gusts' expected second moment (arcsec^2)."""
    p0, rms_g, rad_var, n_s, jit_sd = stats.p0, stats.rms_g, stats.rad_var, stats.n_s, \
        stats.jit_sd
    n_ch = len(sh.channels)
    n = grad_u.shape[0]
    cov = {c: np.zeros(len(pairs)) for c in ("receiver", "jitter", "gusts")}
    samples = np.stack([sh.t[k] for k in idx.reshape(-1)]).reshape(n, 2, 5, -1)
    chunk = 512
    for start in range(0, len(pairs), chunk):
        pp = pairs[start:start + chunk]
        su, au = unit_scan[pp[:, 0]], unit_axis[pp[:, 0]]
        sv, av = unit_scan[pp[:, 1]], unit_axis[pp[:, 1]]
        tu, tv = samples[su, au], samples[sv, av]
        ku, kv = idx[su, au], idx[sv, av]  # (P, 5)
        gu, gv = grad_u[su, au], grad_u[sv, av]
        # receiver: gain OU (per channel) + radiometer (same integration only)
        kg = _ou_mean_cov(tu, tv, stats.tau_g)
        r = np.zeros_like(kg)
        for c in range(n_ch):
            r += (p0[ku, c][:, :, None] * p0[kv, c][:, None, :] * rms_g[c] ** 2 * kg)
            same = ku[:, :, None] == kv[:, None, :]
            r += same * (rad_var[ku, c] / n_s[ku])[:, :, None]
        r /= n_ch ** 2
        cov["receiver"][start:start + len(pp)] = np.einsum("pi,pij,pj->p", gu, r, gv)
        wu, wv = response[su, au], response[sv, av]  # (P, 5, 2)
        kj = _ou_mean_cov(tu, tv, stats.tau_j)
        for d in range(2):
            sd_u, sd_v = jit_sd[ku, d], jit_sd[kv, d]
            cov["jitter"][start:start + len(pp)] += np.einsum(
                "pi,pij,pj->p", wu[..., d] * sd_u, kj, wv[..., d] * sd_v)
        if stats.gust is not None:
            _gust_covariances(cov["gusts"], start, stats.gust, tu, tv, wu, wv)
    return cov


def _gust_covariances(out: np.ndarray, start: int, gust: tuple, tu: np.ndarray,
                      tv: np.ndarray, wu: np.ndarray, wv: np.ndarray) -> None:
    """Add the gusts' expected second moment of a chunk of pairs (starting at ``start`` in
    ``out``): the overlap of the gust profile with the two offsets' integrations, for gusts
    starting on a grid of GUST_STEP_S, times the expected energy."""
    energy, dur, tau_grid, profile = gust
    near = (np.minimum(tu.max(axis=(1, 2)), tv.max(axis=(1, 2)))
            - np.maximum(tu.min(axis=(1, 2)), tv.min(axis=(1, 2)))) > -dur
    for q in np.flatnonzero(near):
        grid = np.arange(max(tu[q].min(), tv[q].min()) - dur,
                         min(tu[q].max(), tv[q].max()) + GUST_STEP_S, GUST_STEP_S)
        hu = np.interp(tu[q][..., None] - grid, tau_grid, profile, left=0.0,
                       right=0.0).mean(axis=1)  # (5, G)
        hv = np.interp(tv[q][..., None] - grid, tau_grid, profile, left=0.0,
                       right=0.0).mean(axis=1)
        ov = hu @ hv.T * (GUST_STEP_S * energy)
        for d in range(2):
            out[start + q] += wu[q, :, d] @ ov @ wv[q, :, d]


def _thermal_draws(engine: MemberEngine, plan_seed: int, n_thermal: int,
                   response: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """The offsets (draws, units) of ``n_thermal`` independent draws of the random slow
    errors alone (about their mean), through each scan's response; empty without them."""
    errors = thermal_errors(engine, plan_seed, n_thermal)
    if errors is None:
        return np.zeros((0, 2 * idx.shape[0]))
    return thermal_offsets(errors, response, idx)


def thermal_errors(engine: MemberEngine, plan_seed: int, n_thermal: int) -> np.ndarray | None:
    """``n_thermal`` independent draws of the random slow errors alone at every integration
    of ``engine``'s schedule, about their mean: (draws, integrations, 2) xel and el (arcsec);
    None when the variant has none (or one draw is asked for)."""
    if not any(kind == "member" for kind, _, _ in engine._kinds) or n_thermal <= 1:
        return None
    seeds = [int(np.random.SeedSequence(int(plan_seed), spawn_key=(THERMAL_KEY, j))
                 .generate_state(1, dtype=np.uint64)[0]) for j in range(n_thermal)]
    errs = engine.slow_errors(seeds)  # (draws, integrations, 2)
    return errs - errs.mean(axis=0)


def thermal_offsets(errors: np.ndarray, response: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """The offsets (draws, units) of slow errors ``errors`` (:func:`thermal_errors`) through
    each design scan's response (its integrations ``idx``)."""
    e_units = np.einsum("uaid,ruaid->rua", response, errors[:, idx, :])  # (draws, n, 2)
    return np.concatenate([e_units[:, :, 0], e_units[:, :, 1]], axis=1)


def task_thermal(job: Job, n_thermal: int) -> np.ndarray | None:
    """:func:`thermal_errors` of a variant: a task for the executors, beside
    :func:`task_noise` with no thermal draws of its own (the two halves of a long run's
    noise model at once; :func:`with_thermal` joins them)."""
    return thermal_errors(engine_for(job), job.plan_seed, n_thermal)


def with_thermal(noise: NoiseModel, shared: SharedSchedule,
                 errors: np.ndarray | None) -> NoiseModel:
    """``noise`` (made without thermal draws) with the draws ``errors`` of
    :func:`task_thermal`: the noise model :func:`noise_model` makes in one piece."""
    if errors is None:
        return noise
    return replace(noise, thermal=thermal_offsets(errors, noise.response,
                                                  shared.scan_int[noise.scans]))


def engine_reduce(engine: MemberEngine, power, std, times):
    """The controller's reduction of arbitrary (..., 5) arrays of one variant."""
    return reduce_sources(power, std, np.broadcast_to(times, power.shape),
                          engine.scenario.controller.scan, engine.scan_widths, 0)


# ---------------------------------------------------------------------------------------------
# the prediction of a design, or of every prefix of a growing one
# ---------------------------------------------------------------------------------------------
def predict(shared: SharedSchedule, terms: Sequence[str], noise: NoiseModel,
            n_scans: int | None = None, truth: np.ndarray | None = None) -> Prediction:
    """Predicted covariance and bias of the fitted ``terms`` for the design's first
    ``n_scans`` scans (default all) of the schedule ``shared``: the sandwich of the
    least-squares fit with the predicted offset noise, plus the scatter the robust fit's
    rejections add (see :func:`rejection_draws`)."""
    return predict_prefixes(shared, terms, noise, [n_scans], truth)[0]


def predict_prefixes(shared: SharedSchedule, terms: Sequence[str], noise: NoiseModel,
                     ends: Sequence[int | None], truth: np.ndarray | None = None,
                     draws: RejectionDraws | None = None) -> list[Prediction]:
    """:func:`predict` for the schedule's first ``ends[k]`` scans, for each k (ascending;
    None: all), the growing designs of a duration question. ``draws``: the rejections'
    draws of these designs (:func:`rejection_draws` of :func:`rejection_design`, which the
    answers run on the workers, in parts); else they are drawn here. The same standard
    normals for every row whatever the prefix (common random numbers): the predictions for
    growing designs differ by the rows added, not by a new draw of the rejections."""
    design = rejection_design(shared, terms, noise, ends)
    if draws is None:
        draws = rejection_draws(design, range(REJECTION_DRAWS))
    return [_prediction(shared, terms, noise, design, k, draws, truth)
            for k in range(len(design.sizes))]


def _prediction(sh: SharedSchedule, terms: Sequence[str], noise: NoiseModel,
                design: RejectionDesign, k: int, draws: RejectionDraws,
                truth: np.ndarray | None) -> Prediction:
    """The prediction of prefix ``k`` of ``design``: the sandwich of each noise component
    over the pairs of its units, the rejections from ``draws``."""
    scans = noise.scans
    n = design.sizes[k]
    keep_scan = np.arange(scans.size) < n
    unit_keep = np.concatenate([keep_scan, keep_scan])
    a_full = design.a
    a = a_full[unit_keep]
    m = len(terms)
    b = np.linalg.pinv(a.T @ a)
    comps: dict[str, np.ndarray] = {}
    pk = unit_keep[noise.pairs[:, 0]] & unit_keep[noise.pairs[:, 1]]
    pairs = noise.pairs[pk]
    for c, values in noise.pair_cov.items():
        v = values[pk]
        au, av = a_full[pairs[:, 0]], a_full[pairs[:, 1]]
        acc = np.einsum("p,pi,pj->ij", v, au, av)
        off = pairs[:, 0] != pairs[:, 1]
        acc = acc + np.einsum("p,pi,pj->ij", v[off], av[off], au[off])
        comps[c] = b @ acc @ b
    thermal_error = np.zeros(m)
    if noise.n_thermal > 1:
        e = noise.thermal[:, unit_keep]  # (draws, 2n)
        comps["thermal"] = np.cov(e @ a @ b, rowvar=False).reshape(m, m)
        # the sampling error of a variance from n_thermal Gaussian draws
        thermal_error = np.diag(comps["thermal"]) * math.sqrt(2.0 / (noise.n_thermal - 1))
    else:
        comps["thermal"] = np.zeros((m, m))
    coef = b @ (a.T @ design.y0[unit_keep])  # least squares on the noise-free data
    rej = _rejection(draws, k, m)
    comps["rejection"] = rej.covariance
    total = sum(comps.values())
    sd = np.sqrt(np.diag(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = b / np.outer(sd, sd)
    truth = np.zeros(m) if truth is None else truth
    return Prediction(names=design.names, covariance=total, design_correlation=corr,
                      sky_rms_arcsec=rej.sky_rms, n_scans=n, components=comps,
                      bias_arcsec=coef - rej.mean_shift - truth, n_rejected=rej.n_rejected,
                      variance_error=np.hypot(thermal_error, rej.variance_error),
                      bias_error_arcsec=rej.shift_error)


# ---------------------------------------------------------------------------------------------
# the robust fit's rejections, simulated
# ---------------------------------------------------------------------------------------------
#: rows about the LAD of the design one prefix shorter in the first LP of the next
#: (:func:`controller.pointing.robust.lad_fit`): the same optimum from LPs of a few hundred
#: rows in place of a few thousand
LAD_BAND_ROWS = 200


@dataclass(frozen=True)
class RejectionDesign:
    """What the simulation of the rejections needs of a design and its prefixes (small and
    picklable, for the workers): the design matrix ``a`` of every unit (the design's scans'
    cross-elevation rows, then their elevation rows), the noise-free data ``y0`` and each
    unit's predicted variance ``unit_var`` (arcsec^2) in that order, the terms' ``names``,
    and the design scans of each prefix ``sizes`` (ascending)."""

    a: np.ndarray
    y0: np.ndarray
    unit_var: np.ndarray
    names: tuple[str, ...]
    sizes: tuple[int, ...]

    def rows(self, k: int) -> np.ndarray:
        """The units of prefix ``k``: its scans' xel rows, then their el rows."""
        n_all, n = self.a.shape[0] // 2, self.sizes[k]
        return np.concatenate([np.arange(n), n_all + np.arange(n)])


def rejection_design(shared: SharedSchedule, terms: Sequence[str], noise: NoiseModel,
                     ends: Sequence[int | None]) -> RejectionDesign:
    """The :class:`RejectionDesign` of the schedule's first ``ends[k]`` scans (None: all)."""
    scans = noise.scans
    cols = shared.columns
    sizes = tuple(int(scans.size if end is None else np.sum(scans < end)) for end in ends)
    if list(sizes) != sorted(sizes):
        raise ValueError(f"prefixes must grow: {sizes}")
    a = _design(cols, terms, scans, shared.sensor_lag_s)  # (2 n_all, m)
    unit_var = np.zeros(2 * scans.size)
    same = noise.pairs[:, 0] == noise.pairs[:, 1]
    for values in noise.pair_cov.values():
        np.add.at(unit_var, noise.pairs[same, 0], values[same])
    if noise.n_thermal > 1:
        unit_var += noise.thermal.var(axis=0, ddof=1)
    model = 60.0 * np.stack([cols["model_xel_arcmin"][scans] + cols["applied_xel_arcmin"][scans],
                             cols["model_el_arcmin"][scans] + cols["applied_el_arcmin"][scans]],
                            axis=1).astype(float)
    y0 = -(noise.quiet_offsets + model).T.reshape(-1)
    return RejectionDesign(a, y0, unit_var, PointingModel(list(terms)).names, sizes)


@dataclass
class RejectionDraws:
    """The robust fit and least squares on every row of some draws of each prefix of a
    design: coefficients ``lsq`` and ``robust`` (prefixes, draws, terms; NaN where the
    fitter would fail: too few observations left), observations ``rejected`` and the used
    ones' mean square residual ``sky_ms`` (prefixes, draws)."""

    draws: np.ndarray
    lsq: np.ndarray
    robust: np.ndarray
    rejected: np.ndarray
    sky_ms: np.ndarray

    @staticmethod
    def concat(parts: Sequence[RejectionDraws]) -> RejectionDraws:
        """Parts of the draws, in draw order (whatever order the parts came in)."""
        parts = sorted(parts, key=lambda p: int(p.draws[0]) if p.draws.size else -1)
        return RejectionDraws(np.concatenate([p.draws for p in parts]),
                              *(np.concatenate([getattr(p, f) for p in parts], axis=1)
                                for f in ("lsq", "robust", "rejected", "sky_ms")))


def rejection_draws(design: RejectionDesign, draws: Sequence[int]) -> RejectionDraws:
    """The robust fit's rejections, by simulation, for draws ``draws`` (of
    :data:`REJECTION_DRAWS`, each the same whichever part computes it) of every prefix of
    ``design``: the noise-free data plus independent Gaussian noise of each row's predicted
    variance, fitted by the fitter's own stages (:mod:`controller.pointing.robust`: LAD, 4x
    the mean absolute deviation, least squares, 3x the rms, least squares) and by least
    squares on every row. A task for the workers (module level, picklable by reference).

    Each draw is fitted prefix after prefix; its LAD starts from its LAD of the prefix
    before (:data:`LAD_BAND_ROWS`), which finds the same exact optimum from small LPs.

    Simulated rather than modelled: truncated-normal moments of the least-squares residuals
    (this function's earlier model) miss the first stage, whose LAD fit passes through
    M observations and leaves the large deterministic residuals of a heated day larger and
    more variable than least squares does. On the 3-hour daytime run (33 observations, ten
    terms) that model predicted 0.30 rejections against the members' 0.90 and W5's sigma
    9.7" against their 13.7"; on the 24-hour run W5 2.82" against 2.43". The same noise
    through the fitter's stages (2000 and 400 draws) gives 0.86 and 13.5", and 2.40".
    Rows are independent here (the jitter's 120 s correlation is shorter than the scan
    spacing; the slow thermal errors enter by their variance): the least-squares part of
    the covariance, with every correlation, is the sandwich of :func:`predict`. The normals
    come from a fixed seed: the same prediction every time."""
    draws = np.asarray(draws, dtype=np.int64)
    n_pre, n_d, m = len(design.sizes), draws.size, design.a.shape[1]
    normals = np.random.default_rng(REJECTION_SEED).standard_normal(
        (REJECTION_DRAWS, design.a.shape[0]))[draws]
    sd = np.sqrt(np.clip(design.unit_var, 0.0, None))
    out = RejectionDraws(draws, np.full((n_pre, n_d, m), np.nan),
                         np.full((n_pre, n_d, m), np.nan), np.zeros((n_pre, n_d)),
                         np.full((n_pre, n_d), np.nan))
    prefixes = []
    for k, n in enumerate(design.sizes):
        rows = design.rows(k)
        a = design.a[rows]
        ys = design.y0[rows] + sd[rows] * normals[:, rows]
        out.lsq[k] = ys @ (a @ np.linalg.pinv(a.T @ a))  # least squares on every row
        prefixes.append((n, a, np.asfortranarray(a), ys))
    for j in range(n_d):
        centre = None
        for k, (n, a, a_f, ys) in enumerate(prefixes):
            y = ys[j]
            eq = Equations(design.names, n, a_f, y, a_f, y, 1e-9 * float(np.abs(y).max()))
            lad = lad_fit(eq, centre, LAD_BAND_ROWS)
            centre = lad
            try:
                used = reject_beyond_mad(eq, lad, LAD_FACTOR)
                used = reject_beyond_rms(eq, least_squares_fit(eq, used).coeffs, used,
                                         RMS_FACTOR)
            except ValueError:
                continue  # too few left: the fitter would fail this member too (robust NaN)
            robust = least_squares_fit(eq, used).coeffs
            out.robust[k, j] = robust
            out.rejected[k, j] = n - int(used.sum())
            res = y - a @ robust
            out.sky_ms[k, j] = float(np.mean(res[:n][used] ** 2 + res[n:][used] ** 2))
    return out


@dataclass
class _Rejection:
    covariance: np.ndarray  # of the robust estimate minus least squares on every row
    mean_shift: np.ndarray  # mean of least squares on every row minus the robust estimate
    n_rejected: float
    sky_rms: float
    variance_error: np.ndarray  # sampling error of the covariance's diagonal
    shift_error: np.ndarray  # sampling error of the mean shift


def _rejection(draws: RejectionDraws, k: int, m: int) -> _Rejection:
    """What the rejections of prefix ``k`` add: the robust estimates' covariance over the
    draws less least squares' (negative where rejecting the noisiest rows makes a term more
    precise: the rejections depend on the noise, so their effect is not independent of
    least squares' estimate); their mean difference, which shifts the bias; the mean number
    of observations rejected and the Sky RMS of the used ones. With the sampling errors of
    the first two from the draws: the diagonal is the mean of x_i = (robust_i - mean)^2 -
    (lsq_i - mean)^2 (times D / (D - 1)), whose standard error is std(x) sqrt(D) / (D - 1);
    the shift's is std(lsq_i - robust_i) / sqrt(D)."""
    ok = np.isfinite(draws.robust[k]).all(axis=1)
    lsq, rob = draws.lsq[k][ok], draws.robust[k][ok]
    d = len(lsq)
    if d < 2:
        return _Rejection(np.zeros((m, m)), np.zeros(m), 0.0, float("nan"), np.zeros(m),
                          np.zeros(m))
    cov = (np.cov(rob, rowvar=False) - np.cov(lsq, rowvar=False)).reshape(m, m)
    x = (rob - rob.mean(axis=0)) ** 2 - (lsq - lsq.mean(axis=0)) ** 2
    return _Rejection(cov, (lsq - rob).mean(axis=0), float(np.mean(draws.rejected[k][ok])),
                      math.sqrt(float(np.mean(draws.sky_ms[k][ok]))),
                      x.std(axis=0, ddof=1) * math.sqrt(d) / (d - 1),
                      (lsq - rob).std(axis=0, ddof=1) / math.sqrt(d))
