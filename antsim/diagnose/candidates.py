"""The library of candidate physical effects: signature, parameters, physical cause, test.

Every row of DESIGN section 5's signature table is here, and the effects that are not
harmonics. Each candidate knows

* its residual **signature** as regressors: columns of the error (indicated minus true,
  arcsec) it makes per unit of its parameters, xel rows then el rows (``kind = "offsets"``);
  or, for the polarization squint and the beam width, a test on other recorded quantities
  (XR - XL offsets, measured widths: ``kind = "channel"``);
* its **parameters**, linear (amplitudes) and nonlinear (time constants, which source, tilt
  direction), the nonlinear ones searched on a grid and refined (the look-elsewhere effect is
  paid with an effective number of independent trials);
* the simulator **effect** that reproduces it (``antsim.effects.EFFECTS``) and its TPOINT
  **terms** where it has them, so that a finding becomes an updated scenario and model;
* a plain **explanation** of the physical cause;
* for the blind harness, how to **draw** random parameters and its **unit signal** (the
  detection threshold is the amplitude whose expected chi^2 decrease equals the critical
  value of its test).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from scipy import optimize

from controller.units import ARCSEC_PER_RAD

from . import pvalues
from .data import Observations
from .problem import Problem, _lstsq, term_columns

__all__ = ["CANDIDATES", "Candidate", "TestResult", "candidate"]

SIDEREAL_RATE_RAD_S = 7.2921158553e-5
GRID_STEP_S = 60.0
SPINUP_S = 86400.0
#: a component this close to the span of the model (1 - R^2) is absorbed by it
ABSORBED_1MR2 = 1e-6
#: TPOINT's level: a candidate this correlated with the model "cannot reliably be
#: distinguished" from it
DISTINGUISH_R = 0.95


@dataclass
class TestResult:
    """The outcome of testing one candidate against the current model."""

    candidate: Candidate
    delta_chi2: float
    dof: int
    trials: float
    p: float  # with the candidate's own look-elsewhere correction
    theta: Any = None
    columns: np.ndarray | None = None  # raw (2n, q) columns at the best theta
    comp_names: tuple[str, ...] = ()
    coef: np.ndarray = field(default_factory=lambda: np.zeros(0))
    cov: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    params: dict[str, Any] = field(default_factory=dict)
    amplitude: float = float("nan")
    amplitude_sigma: float = float("nan")
    absorbed: tuple[str, ...] = ()
    r_model: float = 0.0
    partners: tuple[str, ...] = ()
    refit: Callable[[np.ndarray], np.ndarray] | None = None
    note: str = ""
    mask: np.ndarray | None = None  # the scans this test kept (outliers of model+candidate out)
    chi2_now: float = float("nan")  # chi^2 of the current model on those scans

    @property
    def name(self) -> str:
        return self.candidate.name

    @property
    def testable(self) -> bool:
        return self.dof > 0 and np.isfinite(self.delta_chi2)


# ---------------------------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------------------------
def _wrap(xel: np.ndarray | None, el: np.ndarray | None, n: int) -> np.ndarray:
    x = np.zeros(n) if xel is None else np.asarray(xel, float)
    e = np.zeros(n) if el is None else np.asarray(el, float)
    return np.concatenate([x, e])


def source_rates_arcsec_s(obs: Observations) -> tuple[np.ndarray, np.ndarray]:
    """Apparent motion of a fixed source at (A, E): (dA/dt cos E, dE/dt), arcsec per s."""
    phi = obs.latitude_rad
    a, e = obs.az_rad, obs.el_rad
    d_e = SIDEREAL_RATE_RAD_S * math.cos(phi) * np.sin(a)
    d_a = SIDEREAL_RATE_RAD_S * (math.sin(phi) - math.cos(phi) * np.cos(a) * np.tan(e))
    return d_a * np.cos(e) * ARCSEC_PER_RAD, d_e * ARCSEC_PER_RAD


def obs_key(obs: Observations) -> tuple:
    """A content key for per-observation caches (never ``id``, which Python reuses)."""
    import hashlib

    h = hashlib.blake2b(digest_size=12)
    for arr in (obs.t_s, obs.air_temp_c, obs.sun_el_deg, obs.good):
        if arr is not None:
            h.update(np.ascontiguousarray(arr).tobytes())
    h.update(str(sorted(obs.meta.items())).encode())
    return (obs.n, h.hexdigest(), obs.air_daily_c is not None)


def _grid(obs: Observations) -> np.ndarray:
    end = float(np.nanmax(obs.t_s)) if obs.n else 0.0
    return np.arange(-SPINUP_S, end + 2 * GRID_STEP_S, GRID_STEP_S)


def _periodic_interp(t_grid: np.ndarray, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Interpolate samples (t, v) onto the grid; before the first sample use the values a
    day later (the daily cycle repeats), else hold the first value."""
    order = np.argsort(t)
    t, v = t[order], v[order]
    out = np.interp(t_grid, t, v)
    early = t_grid < t[0]
    shifted = t_grid[early] + 86400.0
    inside = shifted <= t[-1]
    vals = np.interp(shifted, t, v)
    out[early] = np.where(inside, vals, v[0])
    return out


_SUN_CACHE: dict[tuple, np.ndarray] = {}


def sun_el_grid_deg(obs: Observations, t_grid: np.ndarray) -> np.ndarray:
    """Sun elevation (deg) on the grid: from the site and epoch when the recordings name them
    (ephemeris), else from the recorded Sun elevations (a day repeats)."""
    meta = obs.meta
    key = (meta.get("epoch_utc"), meta.get("latitude_deg"), meta.get("longitude_deg"),
           float(t_grid[0]), float(t_grid[-1]), t_grid.size)
    if key in _SUN_CACHE:
        return _SUN_CACHE[key]
    if len(_SUN_CACHE) > 64:
        _SUN_CACHE.clear()
    out = None
    if all(k in meta for k in ("epoch_utc", "latitude_deg", "longitude_deg")):
        try:
            from astropy.time import Time, TimeDelta

            from controller.astro.ephemeris import Ephemeris
            from controller.astro.site import Site

            site = Site(float(meta["latitude_deg"]), float(meta["longitude_deg"]),
                        float(meta.get("height_m", 0.0)))
            epoch = Time(str(meta["epoch_utc"]), scale="utc") + TimeDelta(t_grid[0],
                                                                           format="sec")
            eph = Ephemeris(site, epoch, float(t_grid[-1] - t_grid[0]) + 60.0, ())
            out = np.degrees(eph.sun_altaz_rad(t_grid - t_grid[0])[1])
        except Exception:  # no usable ephemeris: fall back on the recorded column
            out = None
    if out is None:
        if obs.sun_el_deg is None:
            raise ValueError("no Sun elevations")
        ok = np.isfinite(obs.sun_el_deg)
        out = _periodic_interp(t_grid, obs.t_s[ok], obs.sun_el_deg[ok])
    _SUN_CACHE[key] = out
    return out


def _nyholt_trials(cols: np.ndarray) -> float:
    """Effective number of independent tests among correlated 1-column tests (Nyholt 2004)."""
    m = cols.shape[1]
    if m <= 1:
        return 1.0
    norms = np.linalg.norm(cols, axis=0)
    ok = norms > 0
    c = cols[:, ok] / norms[ok]
    lam = np.linalg.eigvalsh(c.T @ c)
    m = int(ok.sum())
    return float(max(1.0, 1.0 + (m - 1) * (1.0 - np.var(lam, ddof=1) / m))) if m > 1 else 1.0


def with_trials(p: float, trials: float) -> float:
    """Probability that the best of ``trials`` independent tests reaches p (Sidak)."""
    if trials <= 1.0:
        return float(p)
    if p < 1e-12:
        return float(min(1.0, trials * p))
    return float(min(1.0, -np.expm1(trials * np.log1p(-min(p, 1.0 - 1e-16)))))


def _pvalue(problem: Problem, dchi2: float, q: int, current_chi2: float | None = None,
            used: np.ndarray | None = None) -> float:
    if q <= 0:
        return 1.0
    if problem.pred.known_noise:
        return float(pvalues.chi2_sf(dchi2, q))
    n_used = int((problem.used if used is None else used).sum())
    m = problem.current_columns().shape[1]
    dof = 2 * n_used - m - q
    if dof <= 0:
        return 1.0
    if current_chi2 is None:
        current_chi2 = problem.fit_current().chi2
    rest = max(current_chi2 - dchi2, 1e-12)
    return float(pvalues.f_sf((dchi2 / q) / (rest / dof), q, dof))


# ---------------------------------------------------------------------------------------------
# Candidates
# ---------------------------------------------------------------------------------------------
class Candidate:
    """Base class; see the module docstring."""

    name: str = ""
    effect: str | None = None  # simulator effect (antsim.effects.EFFECTS) or None
    title: str = ""
    terms: tuple[str, ...] = ()
    signature: str = ""
    explanation: str = ""
    params_doc: ClassVar[dict[str, str]] = {}
    kind: str = "offsets"
    needs: tuple[str, ...] = ()
    amplitude_param: str = ""
    #: why the blind harness must not draw it (None: it may)
    blind_exclusion: str | None = None
    needs_simulation: bool = False

    def applicable(self, obs: Observations, known_noise: bool) -> bool:
        if self.needs_simulation and not known_noise:
            return False
        for need in self.needs:
            if need == "time":
                if not obs.has_time:
                    return False
            elif need == "latitude":
                if not np.isfinite(obs.latitude_rad):
                    return False
            elif not obs.has(need):
                return False
        return True

    # -- offsets candidates -------------------------------------------------------------------
    def columns(self, obs: Observations, theta: Any = None) -> tuple[np.ndarray, tuple[str, ...]]:
        raise NotImplementedError

    def thetas(self, obs: Observations) -> list[Any]:
        return [None]

    def params_from(self, obs: Observations, theta: Any, coef: np.ndarray, cov: np.ndarray,
                    names: tuple[str, ...]) -> tuple[dict[str, Any], float, float]:
        """Effect parameters, amplitude and its sigma from the fitted coefficients."""
        values = dict(zip(names, map(float, coef), strict=True))
        sig = np.sqrt(np.clip(np.diag(cov), 0, None)) if cov.size else np.zeros(0)
        amp = float(np.hypot.reduce(coef)) if coef.size else float("nan")
        amp_sig = float(np.sqrt(np.sum((coef * sig) ** 2)) / amp) if amp > 0 else float("nan")
        return values, amp, amp_sig

    def test(self, problem: Problem, perp, z_perp: np.ndarray, chi2_now: float) -> TestResult:
        """Best chi^2 decrease over the candidate's nonlinear parameters (if any)."""
        obs = problem.obs
        best = None
        grid_cols = []
        for theta in self.thetas(obs):
            cols, names = self.columns(obs, theta)
            res = self._linear(problem, perp, z_perp, cols, names, theta)
            if cols.shape[1] == 1:
                grid_cols.append(perp(problem.cand(cols))[:, 0])
            if best is None or res.delta_chi2 > best.delta_chi2:
                best = res
        assert best is not None
        best = self.refine(problem, perp, z_perp, best)
        best.trials = _nyholt_trials(np.column_stack(grid_cols)) if len(grid_cols) > 1 else 1.0
        best.p = with_trials(_pvalue(problem, best.delta_chi2, best.dof, best.chi2_now,
                                     best.mask), best.trials)
        if best.dof > 0:
            self._finish(problem, best)
        return best

    def refine(self, problem: Problem, perp, z_perp, best: TestResult) -> TestResult:
        return best

    def _linear(self, problem: Problem, perp, z_perp, cols: np.ndarray,
                names: tuple[str, ...], theta: Any) -> TestResult:
        """chi^2 decrease from adding raw ``cols`` (scaled here by the offset scale), on the
        scans a model with the candidate keeps."""
        raw = cols
        cols = problem.cand(cols)
        mask = problem.mask_for(np.column_stack([problem.current_columns(), cols]))
        perp, z_perp = problem.perp_for(mask)
        xp = perp(cols)
        # degeneracy with the model is a property of the signature itself (before the
        # per-source offset scale): judge absorption and correlation on the raw columns
        full = np.linalg.norm(problem.T(raw, mask), axis=0)
        left = np.linalg.norm(perp(raw), axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            one_minus_r2 = np.where(full > 0, (left / full) ** 2, 0.0)
        keep = one_minus_r2 > ABSORBED_1MR2
        absorbed = tuple(n for n, k in zip(names, keep, strict=True) if not k)
        if not keep.any():
            return TestResult(self, 0.0, 0, 1.0, 1.0, theta, cols, names, absorbed=absorbed,
                              mask=mask)
        xk = xp[:, keep]
        coef, cov = _lstsq(xk, z_perp)
        fitted = xk @ coef
        r = np.sqrt(np.clip(1.0 - one_minus_r2[keep], 0.0, 1.0))
        return TestResult(self, float(fitted @ fitted), int(keep.sum()), 1.0, 1.0, theta,
                          cols[:, keep], tuple(n for n, k in zip(names, keep, strict=True)
                                                if k), coef, cov, absorbed=absorbed,
                          r_model=float(r.max()), mask=mask,
                          chi2_now=float(z_perp @ z_perp))

    def _finish(self, problem: Problem, res: TestResult) -> None:
        """Parameters, and the model terms the candidate is most correlated with."""
        if problem.pred.known_noise:
            cov = res.cov
        else:
            cov = res.cov  # whitened units: the per-axis scale is already the noise
        res.params, res.amplitude, res.amplitude_sigma = self.params_from(
            problem.obs, res.theta, res.coef, cov, res.comp_names)
        if res.columns is not None and res.columns.size and res.r_model > 0.5:
            a = problem.T(problem.current_columns(), res.mask)
            x = problem.T(res.columns, res.mask)
            beta, _ = _lstsq(a, x)
            contrib = np.abs(beta) * np.linalg.norm(a, axis=0)[:, None]
            weight = contrib.max(axis=1)
            order = np.argsort(weight)[::-1]
            names = problem.current_names
            top = [names[i] for i in order[:3] if weight[i] > 0.2 * weight[order[0]]]
            res.partners = tuple(top)

    # -- blind harness ------------------------------------------------------------------------
    def draw_shape(self, rng: np.random.Generator, obs: Observations) -> dict[str, Any]:
        """Random shape parameters (everything except the amplitude)."""
        return {}

    def unit_signal(self, obs: Observations, shape: dict[str, Any]) -> np.ndarray:
        """Error (2n,) of the effect at unit amplitude with the given shape."""
        raise NotImplementedError

    def effect_params(self, shape: dict[str, Any], amplitude: float) -> dict[str, Any]:
        raise NotImplementedError

    def nonlinear_part(self, obs: Observations, signal: np.ndarray) -> np.ndarray:
        """The part of a unit signal that is the candidate's own (default: all of it)."""
        return signal

    def signal_power(self, amplitude_ratio: float) -> float:
        """How the signal scales with the amplitude (1: linear)."""
        return amplitude_ratio

    def hidden_amplitude(self, params: dict[str, Any]) -> float:
        return float(params.get(self.amplitude_param, float("nan")))

    def label(self, theta: Any) -> str:
        """The name the blind harness scores (families add their order)."""
        return self.name

    def hidden_label(self, params: dict[str, Any]) -> str:
        return self.name

    def describe(self) -> dict[str, Any]:
        """The library row as plain data (for ``--list`` and the report)."""
        return {"effect": self.effect or self.name, "candidate": self.name, "title": self.title,
                "terms": list(self.terms), "signature": self.signature,
                "parameters": dict(self.params_doc), "explanation": self.explanation,
                "blind": self.blind_exclusion or "drawn"}


class TermsCandidate(Candidate):
    """An effect expressed exactly by TPOINT terms (a harmonic pair or single terms)."""

    def __init__(self, name: str, terms: Sequence[str], title: str, signature: str,
                 explanation: str, effect: str | None = None, pair: bool = True,
                 blind_exclusion: str | None = None, signs: tuple[float, float] = (1.0, 1.0)):
        self.name = name
        self.terms = tuple(terms)
        self.title = title
        self.signature = signature
        self.explanation = explanation
        self.effect = effect or "terms"
        self.pair = pair and len(self.terms) == 2
        self.blind_exclusion = blind_exclusion
        self.amplitude_param = "amplitude_arcsec"
        #: a pair's coefficients per unit of a cos(phase), a sin(phase): the simulator
        #: effect's ``HarmonicEffect.signs`` (its phase is of the physical correction)
        self.signs = (float(signs[0]), float(signs[1]))
        if self.pair:
            sign = ["" if x > 0 else "-" for x in self.signs]
            self.params_doc = {
                "amplitude_arcsec": "amplitude of the harmonic (arcsec)",
                "phase_deg": f"phase: {self.terms[0]} = {sign[0]}a cos(phase), "
                             f"{self.terms[1]} = {sign[1]}a sin(phase)"}
        else:
            self.params_doc = {t: f"TPOINT coefficient of {t} (arcsec)" for t in self.terms}

    def columns(self, obs, theta=None):
        return term_columns(self.terms, obs), self.terms

    def params_from(self, obs, theta, coef, cov, names):
        values = dict(zip(names, map(float, coef), strict=True))
        if self.pair and len(names) == 2:
            s, c = float(coef[0]), float(coef[1])
            amp = math.hypot(s, c)
            grad = np.array([s, c]) / amp if amp > 0 else np.zeros(2)
            amp_sig = float(np.sqrt(grad @ cov @ grad)) if amp > 0 else float("nan")
            phase = math.degrees(math.atan2(self.signs[1] * c, self.signs[0] * s)) % 360.0
            return ({"amplitude_arcsec": amp, "phase_deg": phase, "terms_arcsec": values},
                    amp, amp_sig)
        if len(names) == 1:
            return ({"terms_arcsec": values}, float(coef[0]),
                    float(math.sqrt(max(cov[0, 0], 0.0))))
        return super().params_from(obs, theta, coef, cov, names)

    def draw_shape(self, rng, obs):
        return {"phase_deg": float(rng.uniform(0.0, 360.0))}

    def unit_signal(self, obs, shape):
        cols = term_columns(self.terms, obs)
        if self.pair:
            phi = math.radians(shape["phase_deg"])
            return cols @ np.array([self.signs[0] * math.cos(phi), self.signs[1] * math.sin(phi)])
        return cols[:, 0]

    def effect_params(self, shape, amplitude):
        if self.pair and self.effect != "terms":
            return {"amplitude_arcsec": float(amplitude), "phase_deg": float(shape["phase_deg"])}
        return {"terms_arcsec": {self.terms[0]: float(amplitude)}}

    def model_terms(self, params: dict[str, Any]) -> dict[str, float]:
        return dict(params.get("terms_arcsec", {}))


class HarmonicFamilyCandidate(TermsCandidate):
    """A periodic error with an unknown number of cycles n per turn of an axis: the pair
    ``H<result>S<arg><n>``, ``H<result>C<arg><n>`` of TPOINT's harmonic generator, n searched
    over ``orders`` (the look-elsewhere effect paid as that many trials)."""

    def __init__(self, name: str, result: str, arg: str, orders: Sequence[int], title: str,
                 signature: str, explanation: str):
        self.result, self.arg, self.orders = result, arg, tuple(orders)
        super().__init__(name, (self._pair(self.orders[0])), title, signature, explanation,
                         effect="terms")
        #: the pattern (a finding names its actual terms, e.g. HESE7 HECE7)
        self.terms = (f"H{result}S{arg}n", f"H{result}C{arg}n")
        self.params_doc = {"n": "cycles per turn", "amplitude_arcsec": "amplitude (arcsec)",
                           "phase_deg": "phase: sine term a cos(phase), cosine a sin(phase)"}

    def _pair(self, n: int) -> tuple[str, str]:
        k = "" if n == 1 else str(n)
        return (f"H{self.result}S{self.arg}{k}", f"H{self.result}C{self.arg}{k}")

    def thetas(self, obs):
        return list(self.orders)

    def columns(self, obs, theta=None):
        n = self.orders[0] if theta is None else int(theta)
        pair = self._pair(n)
        return term_columns(pair, obs), pair

    def test(self, problem, perp, z_perp, chi2_now):
        best = None
        for n in self.orders:
            cols, names = self.columns(problem.obs, n)
            res = self._linear(problem, perp, z_perp, cols, names, n)
            if best is None or res.delta_chi2 > best.delta_chi2:
                best = res
        best.trials = float(len(self.orders))
        best.p = with_trials(_pvalue(problem, best.delta_chi2, best.dof, best.chi2_now,
                                     best.mask), best.trials)
        if best.dof > 0:
            self._finish(problem, best)
        return best

    def params_from(self, obs, theta, coef, cov, names):
        params, amp, sig = super().params_from(obs, theta, coef, cov, names)
        params["n"] = int(theta)
        return params, amp, sig

    def label(self, theta: Any) -> str:
        return f"{self.name}[{int(theta)}]"

    def draw_shape(self, rng, obs):
        return {"n": int(rng.choice(self.orders)), "phase_deg": float(rng.uniform(0.0, 360.0))}

    def unit_signal(self, obs, shape):
        cols, _ = self.columns(obs, shape["n"])
        phi = math.radians(shape["phase_deg"])
        return cols @ np.array([math.cos(phi), math.sin(phi)])

    def effect_params(self, shape, amplitude):
        s_term, c_term = self._pair(shape["n"])
        phi = math.radians(shape["phase_deg"])
        return {"terms_arcsec": {s_term: float(amplitude * math.cos(phi)),
                                 c_term: float(amplitude * math.sin(phi))}}

    def hidden_label(self, params: dict[str, Any]) -> str:
        term = next(iter(params["terms_arcsec"]))
        digits = term[len(f"H{self.result}S{self.arg}"):]
        return f"{self.name}[{int(digits) if digits else 1}]"


class _LaggedCandidate(Candidate):
    """An effect with one time constant ``tau_s`` (a lag or a relaxation): the blind
    harness draws tau log-uniformly between 30 min and 3 h, with either sign."""

    def _refine_log_theta(self, problem: Problem, perp, z_perp, best: TestResult,
                          log_lo: float, log_hi: float) -> TestResult:
        """The time constant between exp(log_lo) and exp(log_hi) that fits best (bounded
        search in log theta), or ``best`` if that fits better."""
        obs = problem.obs

        def neg(log_theta: float) -> float:
            cols, names = self.columns(obs, math.exp(log_theta))
            return -self._linear(problem, perp, z_perp, cols, names, None).delta_chi2

        opt = optimize.minimize_scalar(neg, bounds=(log_lo, log_hi), method="bounded",
                                       options={"xatol": 1e-3})
        theta = float(math.exp(opt.x))
        cols, names = self.columns(obs, theta)
        res = self._linear(problem, perp, z_perp, cols, names, theta)
        return best if res.delta_chi2 < best.delta_chi2 else res

    def draw_shape(self, rng, obs):
        return {"tau_s": float(math.exp(rng.uniform(math.log(1800.0), math.log(10800.0)))),
                "sign": float(rng.choice([-1.0, 1.0]))}

    def unit_signal(self, obs, shape):
        return shape.get("sign", 1.0) * self.columns(obs, shape["tau_s"])[0][:, 0]


class SunsetCandidate(_LaggedCandidate):
    name = "sunset_drift"
    effect = "sunset_drift"
    title = "thermal lag after sunset"
    signature = ("elevation residuals that change after sunset as a (1 - exp(-t/tau)) "
                 "relaxation and return after sunrise")
    params_doc: ClassVar[dict[str, str]] = {
        "amplitude_arcsec": "total elevation change after sunset (arcsec)",
        "tau_s": "time constant of the drift (s)"}
    amplitude_param = "amplitude_arcsec"
    needs = ("time",)
    TAUS = (600.0, 900.0, 1200.0, 1800.0, 2400.0, 3600.0, 4800.0, 6000.0, 7200.0, 9000.0,
            10800.0, 14400.0, 18000.0)

    def __init__(self):
        from antsim.world.effects.thermal import SunsetDrift

        self.explanation = SunsetDrift.explanation + " (Fomalont 1973: 1' in the 4 h after " \
                                                      "sunset)"
        self._cache: dict[tuple, np.ndarray] = {}

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and (
            obs.sun_el_deg is not None or "epoch_utc" in obs.meta) and np.ptp(obs.t_s) > 4 * 3600

    def level(self, obs: Observations, tau_s: float) -> np.ndarray:
        from antsim.world.effects.thermal import relax

        t = _grid(obs)
        key = (obs_key(obs), round(tau_s, 3))
        if key not in self._cache:
            if len(self._cache) > 512:
                self._cache.clear()
            night = (sun_el_grid_deg(obs, t) < 0.0).astype(float)
            lev = relax(night, GRID_STEP_S, tau_s, float(night[0]))
            self._cache[key] = np.interp(obs.t_s, t, lev)
        return self._cache[key]

    def thetas(self, obs):
        return list(self.TAUS)

    def columns(self, obs, theta=None):
        return _wrap(None, self.level(obs, float(theta)), obs.n)[:, None], ("amplitude",)

    def refine(self, problem, perp, z_perp, best):
        if best.dof == 0:
            return best
        obs = problem.obs
        lo, hi = math.log(self.TAUS[0] / 1.5), math.log(self.TAUS[-1] * 1.5)
        i = list(self.TAUS).index(best.theta)
        a = math.log(self.TAUS[max(i - 1, 0)]) if i > 0 else lo
        b = math.log(self.TAUS[min(i + 1, len(self.TAUS) - 1)]) if i < len(self.TAUS) - 1 \
            else hi

        res = self._refine_log_theta(problem, perp, z_perp, best, a, b)
        # joint covariance of (amplitude, log tau) from the Jacobian
        tau = float(res.theta)
        h = 0.01
        d = (self.columns(obs, tau * math.exp(h))[0] - self.columns(obs, tau * math.exp(-h))[0]) \
            / (2 * h) * float(res.coef[0])
        perp, z_perp = problem.perp_for(res.mask)
        jac = perp(np.column_stack([res.columns, problem.cand(d)]))
        _, cov2 = _lstsq(jac, z_perp)
        res.cov = cov2
        res.refit = self._refit_factory(problem)
        return res

    def _refit_factory(self, problem: Problem):
        def refit(train: np.ndarray) -> np.ndarray:
            obs = problem.obs
            best, best_tau = -1.0, self.TAUS[0]
            for tau in self.TAUS:
                cols = problem.cand(self.columns(obs, tau)[0])
                full = np.column_stack([problem.current_columns(), cols])
                f = problem.fit(full, train)
                g = problem.fit(problem.current_columns(), train)
                if g.chi2 - f.chi2 > best:
                    best, best_tau = g.chi2 - f.chi2, tau
            return problem.cand(self.columns(obs, best_tau)[0])
        return refit

    def params_from(self, obs, theta, coef, cov, names):
        amp = float(coef[0])
        tau = float(theta)
        sig_amp = math.sqrt(max(cov[0, 0], 0.0))
        sig_tau = tau * math.sqrt(max(cov[1, 1], 0.0)) if cov.shape[0] > 1 else float("nan")
        return ({"amplitude_arcsec": amp, "tau_s": tau, "tau_sigma_s": sig_tau}, amp, sig_amp)

    def effect_params(self, shape, amplitude):
        return {"amplitude_arcsec": float(shape.get("sign", 1.0) * amplitude),
                "tau_s": float(shape["tau_s"])}

    def effect_from_params(self, params: dict[str, Any]) -> dict[str, Any]:
        return {"amplitude_arcsec": params["amplitude_arcsec"], "tau_s": params["tau_s"]}


class TemperatureCandidate(_LaggedCandidate):
    name = "temperature_drift"
    effect = "temperature_drift"
    title = "temperature-driven elevation drift"
    signature = ("elevation residuals proportional to the air temperature, lagged by the "
                 "structure's time constant")
    params_doc: ClassVar[dict[str, str]] = {
        "arcsec_per_k": "elevation error per kelvin of structure temperature",
        "tau_s": "time constant of the structure temperature (s)",
        "reference_c": "structure temperature of zero error (C)"}
    amplitude_param = "arcsec_per_k"
    needs = ("time", "air_temp_c")
    TAUS = (0.0, 600.0, 1200.0, 1800.0, 2700.0, 3600.0, 5400.0, 7200.0, 10800.0, 14400.0,
            21600.0)

    def __init__(self):
        from antsim.world.effects.drifts import TemperatureDrift

        self.explanation = TemperatureDrift.explanation
        self._cache: dict[tuple, tuple[np.ndarray, float]] = {}

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and np.ptp(obs.t_s) > 4 * 3600 and \
            float(np.nanstd(obs.air_temp_c)) > 0.3

    def structure(self, obs: Observations, tau_s: float) -> tuple[np.ndarray, float]:
        from antsim.world.effects.drifts import structure_temperature_c

        key = (obs_key(obs), round(tau_s, 3))
        if key not in self._cache:
            if len(self._cache) > 512:
                self._cache.clear()
            t = _grid(obs)
            ok = np.isfinite(obs.air_temp_c)
            if obs.air_daily_c is not None and np.ptp(obs.t_s[ok]) < 72000.0:
                # a campaign much shorter than a day: the day before follows the scenario's
                # daily curve, shifted to the recorded temperatures
                curve = np.asarray(obs.air_daily_c(t), dtype=float)
                shift = float(np.median(obs.air_temp_c[ok]
                                        - np.asarray(obs.air_daily_c(obs.t_s[ok]))))
                air = np.interp(t, obs.t_s[ok], obs.air_temp_c[ok])
                outside = (t < obs.t_s[ok].min()) | (t > obs.t_s[ok].max())
                air[outside] = curve[outside] + shift
            else:
                air = _periodic_interp(t, obs.t_s[ok], obs.air_temp_c[ok])
            ts = np.interp(obs.t_s, t, structure_temperature_c(t, air, tau_s))
            self._cache[key] = (ts, float(np.mean(ts[obs.good]) if obs.good.any() else 0.0))
        return self._cache[key]

    def thetas(self, obs):
        return list(self.TAUS)

    def columns(self, obs, theta=None):
        ts, mean = self.structure(obs, float(theta))
        return _wrap(None, ts - mean, obs.n)[:, None], ("arcsec_per_k",)

    def refine(self, problem, perp, z_perp, best):
        if best.dof == 0:
            return best
        obs = problem.obs
        taus = list(self.TAUS)
        i = taus.index(best.theta)
        if best.theta == 0.0:
            res = best
        else:
            a = math.log(taus[i - 1]) if taus[i - 1] > 0 else math.log(60.0)
            b = math.log(taus[i + 1]) if i + 1 < len(taus) else math.log(taus[-1] * 1.5)

            res = self._refine_log_theta(problem, perp, z_perp, best, a, b)
        tau = float(res.theta)
        if tau > 0:
            h = 0.01
            d = (self.columns(obs, tau * math.exp(h))[0]
                 - self.columns(obs, tau * math.exp(-h))[0]) / (2 * h) * float(res.coef[0])
            perp, z_perp = problem.perp_for(res.mask)
            jac = perp(np.column_stack([res.columns, problem.cand(d)]))
            _, res.cov = _lstsq(jac, z_perp)

        def refit(train: np.ndarray) -> np.ndarray:
            best_d, best_tau = -1.0, taus[0]
            g = problem.fit(problem.current_columns(), train)
            for t in taus:
                cols = problem.cand(self.columns(obs, t)[0])
                f = problem.fit(np.column_stack([problem.current_columns(), cols]), train)
                if g.chi2 - f.chi2 > best_d:
                    best_d, best_tau = g.chi2 - f.chi2, t
            return problem.cand(self.columns(obs, best_tau)[0])

        res.refit = refit
        return res

    def params_from(self, obs, theta, coef, cov, names):
        k = float(coef[0])
        tau = float(theta)
        _, mean = self.structure(obs, tau)
        sig_tau = tau * math.sqrt(max(cov[1, 1], 0.0)) if cov.shape[0] > 1 else float("nan")
        return ({"arcsec_per_k": k, "tau_s": tau, "tau_sigma_s": sig_tau, "reference_c": mean},
                k, math.sqrt(max(cov[0, 0], 0.0)))

    def effect_params(self, shape, amplitude):
        return {"arcsec_per_k": float(shape.get("sign", 1.0) * amplitude),
                "tau_s": float(shape["tau_s"]), "reference_c": 5.0}

    def effect_from_params(self, params):
        return {"arcsec_per_k": params["arcsec_per_k"], "tau_s": params["tau_s"],
                "reference_c": params["reference_c"]}


class ClockCandidate(Candidate):
    name = "clock_error"
    effect = "clock_error"
    title = "clock (timing) error"
    signature = ("an offset along each source's apparent motion, proportional to its rate "
                 "(sidereal-rate regressor); a drifting clock makes it grow in time")
    params_doc: ClassVar[dict[str, str]] = {"offset_s": "clock reading minus true time (s)",
                  "drift_s_per_day": "clock rate error (s per day)"}
    amplitude_param = "drift_s_per_day"
    needs = ("time", "latitude")

    def __init__(self):
        from antsim.world.effects.dynamics import ClockError

        self.explanation = ClockError.explanation

    def columns(self, obs, theta=None):
        # the antenna points where the source is at its clock's time t + dt, so the measured
        # correction (source minus beam) is -dt times the source's apparent motion
        rx, re_ = source_rates_arcsec_s(obs)
        day = obs.t_s / 86400.0
        cols = -np.column_stack([_wrap(rx, re_, obs.n), _wrap(rx * day, re_ * day, obs.n)])
        return cols, ("offset_s", "drift_s_per_day")

    def params_from(self, obs, theta, coef, cov, names):
        values = dict(zip(names, map(float, coef), strict=True))
        i = names.index("drift_s_per_day") if "drift_s_per_day" in names else None
        amp = values.get("drift_s_per_day", float("nan"))
        sig = math.sqrt(max(cov[i, i], 0.0)) if i is not None else float("nan")
        values.setdefault("offset_s", 0.0)
        return values, amp, sig

    def draw_shape(self, rng, obs):
        return {"sign": float(rng.choice([-1.0, 1.0])),
                "offset_s": float(rng.uniform(-2.0, 2.0))}

    def unit_signal(self, obs, shape):
        return shape["sign"] * self.columns(obs)[0][:, 1]

    def effect_params(self, shape, amplitude):
        return {"offset_s": shape["offset_s"],
                "drift_s_per_day": float(shape["sign"] * amplitude)}

    def effect_from_params(self, params):
        return {"offset_s": params.get("offset_s", 0.0),
                "drift_s_per_day": params.get("drift_s_per_day", 0.0)}


class ServoLagCandidate(Candidate):
    name = "servo_lag"
    effect = "servo_lag"
    title = "servo lag"
    signature = "an error along each axis proportional to that axis' speed (rate regressor)"
    params_doc: ClassVar[dict[str, str]] = {"lag_s": "servo following lag (s)"}
    amplitude_param = "lag_s"
    needs = ("latitude",)
    blind_exclusion = ("while tracking, the axis rates are the source's apparent motion: the "
                       "lag is a rotation about the polar axis that IA and the azimuth-axis "
                       "tilt terms absorb exactly, and it shares its regressor with a clock "
                       "offset")

    def __init__(self):
        from antsim.world.effects.dynamics import ServoLag

        self.explanation = ServoLag.explanation

    def columns(self, obs, theta=None):
        # the axes trail their command: the beam lags the source by lag x rate
        rx, re_ = source_rates_arcsec_s(obs)
        return -_wrap(rx, re_, obs.n)[:, None], ("lag_s",)

    def params_from(self, obs, theta, coef, cov, names):
        return {"lag_s": float(coef[0])}, float(coef[0]), math.sqrt(max(cov[0, 0], 0.0))


class BacklashCandidate(Candidate):
    name = "backlash"
    effect = "backlash"
    title = "gear backlash"
    signature = "an offset whose sign follows the direction of the last slew on each axis"
    params_doc: ClassVar[dict[str, str]] = {
        "az_arcsec": "azimuth dead band, full width (arcsec of azimuth)",
        "el_arcsec": "elevation dead band, full width (arcsec)"}
    amplitude_param = "el_arcsec"
    needs = ("slew_az", "slew_el")
    blind_exclusion = ("the five-point pattern reaches every on-source point from the same "
                       "side (the offsets step upwards), so backlash is a constant offset "
                       "that IA and IE absorb; the slew direction does not reach the offsets")

    def __init__(self):
        from antsim.world.effects.dynamics import Backlash

        self.explanation = Backlash.explanation

    def applicable(self, obs, known_noise):
        if not super().applicable(obs, known_noise):
            return False
        return bool(np.unique(obs.slew_az[np.isfinite(obs.slew_az)]).size > 1
                    or np.unique(obs.slew_el[np.isfinite(obs.slew_el)]).size > 1)

    def columns(self, obs, theta=None):
        sa = np.nan_to_num(obs.slew_az)
        se = np.nan_to_num(obs.slew_el)
        cols = np.column_stack([_wrap(0.5 * sa * np.cos(obs.el_rad), None, obs.n),
                                _wrap(None, 0.5 * se, obs.n)])
        return cols, ("az_arcsec", "el_arcsec")


class SourceCandidate(Candidate):
    name = "source_structure"
    effect = "source_structure"
    title = "source structure (one source's centroid off its catalogue position)"
    signature = "residuals clustered by source: one source's offsets shifted by a constant"
    params_doc: ClassVar[dict[str, str]] = {
        "source": "the source", "xel_arcsec": "centroid offset, cross-elevation",
        "el_arcsec": "centroid offset, elevation",
        "size_arcmin": "Gaussian FWHM of the source from its measured widths"}
    amplitude_param = "offset_arcsec"
    needs = ("source",)
    MIN_SCANS = 4

    def __init__(self):
        from antsim.world.effects.optics import SourceStructure

        self.explanation = SourceStructure.explanation

    def thetas(self, obs):
        names, counts = np.unique(obs.source[obs.good], return_counts=True)
        return [str(s) for s, c in zip(names, counts, strict=True) if c >= self.MIN_SCANS]

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and len(self.thetas(obs)) >= 2

    def columns(self, obs, theta=None):
        ind = (obs.source == theta).astype(float)
        return np.column_stack([_wrap(ind, None, obs.n), _wrap(None, ind, obs.n)]), \
            ("xel_arcsec", "el_arcsec")

    def test(self, problem, perp, z_perp, chi2_now):
        res = super().test(problem, perp, z_perp, chi2_now)
        res.trials = float(len(self.thetas(problem.obs)))
        res.p = with_trials(_pvalue(problem, res.delta_chi2, res.dof, res.chi2_now, res.mask),
                            res.trials)
        return res

    def params_from(self, obs, theta, coef, cov, names):
        values = dict(zip(names, map(float, coef), strict=True))
        x, e = values.get("xel_arcsec", 0.0), values.get("el_arcsec", 0.0)
        amp = math.hypot(x, e)
        g = np.array([x, e])[: len(coef)] / amp if amp > 0 else np.zeros(len(coef))
        sig = float(np.sqrt(g @ cov @ g)) if amp > 0 else float("nan")
        out = {"source": theta, "xel_arcsec": x, "el_arcsec": e, "offset_arcsec": amp}
        if obs.width_xel_arcmin is not None and "beam_hpbw_arcmin" in obs.meta:
            sel = obs.good & (obs.source == theta)
            w = np.nanmean(np.concatenate([obs.width_xel_arcmin[sel], obs.width_el_arcmin[sel]]))
            hp = float(obs.meta["beam_hpbw_arcmin"])
            out["size_arcmin"] = float(math.sqrt(max(w * w - hp * hp, 0.0)))
        return out, amp, sig

    def draw_shape(self, rng, obs):
        names = self.thetas(obs)
        return {"source": str(rng.choice(names)),
                "angle_deg": float(rng.uniform(0.0, 360.0))}

    def unit_signal(self, obs, shape):
        cols, _ = self.columns(obs, shape["source"])
        a = math.radians(shape["angle_deg"])
        return cols @ np.array([math.cos(a), math.sin(a)])

    def effect_params(self, shape, amplitude):
        a = math.radians(shape["angle_deg"])
        return {"source": shape["source"], "xel_arcsec": float(amplitude * math.cos(a)),
                "el_arcsec": float(amplitude * math.sin(a))}

    def hidden_amplitude(self, params):
        return math.hypot(params.get("xel_arcsec", 0.0), params.get("el_arcsec", 0.0))

    def effect_from_params(self, params):
        return {"source": params["source"], "xel_arcsec": params["xel_arcsec"],
                "el_arcsec": params["el_arcsec"]}


class ExactTiltCandidate(Candidate):
    name = "exact_tilt_collimation"
    effect = "exact_tilt_collimation"
    title = "large tilt or collimation: the small-angle model fails"
    terms = ("AN", "AW", "CA")
    signature = ("second-order residuals of a large azimuth-axis tilt or collimation error "
                 "(BIMA memo 23, eqs. 3-4), growing as tan E near the zenith and largest "
                 "near azimuth 90 deg; the linear part is absorbed by AN, AW and CA")
    params_doc: ClassVar[dict[str, str]] = {"tilt_arcmin": "tilt of the azimuth axis (arcmin)",
                  "tilt_az_deg": "azimuth towards which the axis tilts (deg, N = 0)",
                  "collimation_arcmin": "collimation error (arcmin)"}
    amplitude_param = "tilt_arcmin"
    blind_exclusion = ("its signature is quadratic in the tilt: at 3-10 times its detection "
                       "threshold (tilts of 45-80' on the 45-ft's schedule) the second-order "
                       "errors reach 4-12' near the zenith, beyond what a five-point scan "
                       "with 7' steps measures; it is proven separately at 25-40' "
                       "(tests/test_diagnose_sim.py, benchmarks/blind.py --tilt)")
    #: the chi^2 decrease of this 3-parameter even (quadratic) family is referred to chi^2_6,
    #: the dimension of the space of quadratic forms its signature spans (conservative)
    REFERENCE_DOF = 6
    STARTS = ((1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 0, -1), (0, 1, -1),
              (1, 1, 0), (1, -1, 0))

    def __init__(self):
        from antsim.world.effects.optics import ExactTiltCollimation

        self.explanation = ExactTiltCollimation.explanation

    @staticmethod
    def linear_terms(theta: Sequence[float]) -> np.ndarray:
        """AN, AW, CA (arcsec) of the small-angle limit (ExactTiltCollimation's docstring)."""
        tn, te, c = (float(v) * 60.0 for v in theta)
        return np.array([-tn, te, -c])

    def error(self, obs: Observations, theta: Sequence[float]) -> np.ndarray:
        """Error (2n,) arcsec of an exact tilt (north, east components) and collimation,
        arcmin."""
        from antsim.world.effects.optics import ExactTiltCollimation

        tn, te, c = (float(v) for v in theta)
        eff = ExactTiltCollimation(tilt_arcmin=math.hypot(tn, te),
                                   tilt_az_deg=math.degrees(math.atan2(te, tn)),
                                   collimation_arcmin=c)
        az_enc, el_enc = eff.encoder_from_true(obs.az_rad, obs.el_rad)
        d_az = (az_enc - obs.az_rad + math.pi) % (2 * math.pi) - math.pi
        return _wrap(d_az * np.cos(obs.el_rad) * ARCSEC_PER_RAD,
                     (el_enc - obs.el_rad) * ARCSEC_PER_RAD, obs.n)

    def test(self, problem, perp, z_perp, chi2_now):
        obs = problem.obs
        perp, z_perp = problem.perp_for(problem.used)
        f2 = np.concatenate([problem.f, problem.f])
        lin_cols = term_columns(("AN", "AW", "CA"), obs)

        def err(theta):
            # the model in use carries the linear part (else the scans would miss the
            # source): the recordings show the linear part whole and the rest scaled by
            # each source's offset scale
            raw = self.error(obs, theta)
            lin = lin_cols @ self.linear_terms(theta)
            return lin + f2 * (raw - lin)

        def resid(theta):
            return z_perp - perp(err(theta)[:, None])[:, 0]

        base = float(z_perp @ z_perp)
        best_x, best_c = np.zeros(3), base
        for start in self.STARTS:
            for scale in (40.0,):
                x0 = np.array(start, float) * scale
                try:
                    sol = optimize.least_squares(resid, x0, method="lm", x_scale=30.0,
                                                 max_nfev=200)
                except ValueError:
                    continue
                cost = float(sol.fun @ sol.fun)
                if cost < best_c:
                    best_c, best_x = cost, sol.x
        dchi2 = max(base - best_c, 0.0)
        # covariance from the Jacobian at the optimum
        h = 0.5
        jac = np.column_stack([
            perp(((err(best_x + h * e) - err(best_x - h * e)) / (2 * h))[:, None])[:, 0]
            for e in np.eye(3)])
        _, cov = _lstsq(jac, z_perp)
        cols = err(best_x)[:, None]
        res = TestResult(self, dchi2, self.REFERENCE_DOF, 1.0, 1.0, tuple(best_x), cols,
                         ("exact",), np.array([1.0]), cov, mask=problem.used.copy(),
                         chi2_now=base)
        res.p = _pvalue(problem, dchi2, self.REFERENCE_DOF, base)
        # correlation of the nonlinear part (the error minus its best linear AN/AW/CA fit)
        lin = term_columns(("AN", "AW", "CA"), obs)
        beta, _ = _lstsq(lin, cols[:, 0])
        quad = (cols[:, 0] - lin @ beta)[:, None]
        xp = perp(quad)
        full = np.linalg.norm(problem.T(quad))
        res.r_model = float(math.sqrt(max(0.0, 1 - (np.linalg.norm(xp) / full) ** 2))) \
            if full > 0 else 1.0
        res.params, res.amplitude, res.amplitude_sigma = self.params_from(
            obs, res.theta, res.coef, cov, res.comp_names)
        return res

    def params_from(self, obs, theta, coef, cov, names):
        tn, te, c = theta
        tilt = math.hypot(tn, te)
        g = np.array([tn, te, 0.0]) / tilt if tilt > 0 else np.zeros(3)
        sig = float(np.sqrt(g @ cov @ g)) if tilt > 0 else float("nan")
        return ({"tilt_arcmin": tilt, "tilt_az_deg": math.degrees(math.atan2(te, tn)) % 360.0,
                 "collimation_arcmin": float(c),
                 "collimation_sigma_arcmin": float(math.sqrt(max(cov[2, 2], 0.0))),
                 "note": "the signature is even: (tilt, collimation) and their negatives "
                         "fit equally"}, tilt, sig)

    def draw_shape(self, rng, obs):
        v = rng.standard_normal(3)
        v[2] *= 0.5
        v /= np.linalg.norm(v)
        return {"direction": tuple(float(x) for x in v)}

    def unit_signal(self, obs, shape):
        # the signature is quadratic: the signal at 30' along the direction, per 30'^2
        d = np.array(shape["direction"])
        return self.error(obs, 30.0 * d)

    def signal_power(self, amplitude_ratio):
        return amplitude_ratio**2

    def nonlinear_part(self, obs, signal):
        lin = term_columns(("AN", "AW", "CA"), obs)
        beta, _ = _lstsq(lin, signal)
        return signal - lin @ beta

    def effect_params(self, shape, amplitude):
        tn, te, c = (amplitude * x for x in shape["direction"])
        return {"tilt_arcmin": float(math.hypot(tn, te)),
                "tilt_az_deg": float(math.degrees(math.atan2(te, tn)) % 360.0),
                "collimation_arcmin": float(c)}

    def hidden_amplitude(self, params):
        return float(params["tilt_arcmin"])

    def effect_from_params(self, params):
        return {k: params[k] for k in ("tilt_arcmin", "tilt_az_deg", "collimation_arcmin")}


class FeedOffsetCandidate(Candidate):
    name = "feed_offset"
    effect = "feed_offset"
    title = "feed offset"
    terms = ("CA", "IE")
    signature = ("(xel, el) proportional to (cos(f - C7), sin(f - C7)) with f the feed angle "
                 "(Fomalont 1973): a collimation pair that turns with a rotating feed")
    params_doc: ClassVar[dict[str, str]] = {"offset_arcsec": "beam displacement (arcsec)",
                  "angle_deg": "direction C7 relative to the feed angle (deg)"}
    amplitude_param = "offset_arcsec"

    def __init__(self):
        from antsim.world.effects.harmonics import FeedOffset

        self.explanation = FeedOffset.explanation
        self.blind_exclusion = ("with the 45-ft's fixed feed the feed offset is a constant "
                                "collimation pair that CA (W2) and IE (W6) absorb")

    def columns(self, obs, theta=None):
        # the feed (rotator) angle: a TPOINT file's fifth column or the recordings'
        # feed_angle_deg; a fixed feed makes this a collimation pair (CA, IE)
        f = np.radians(obs.rotator_deg) if obs.rotator_deg is not None else np.zeros(obs.n)
        f = np.nan_to_num(f)
        cols = np.column_stack([_wrap(np.cos(f), np.sin(f), obs.n),
                                _wrap(np.sin(f), -np.cos(f), obs.n)])
        return cols, ("a_arcsec", "b_arcsec")

    def params_from(self, obs, theta, coef, cov, names):
        values = dict(zip(names, map(float, coef), strict=True))
        a, b = values.get("a_arcsec", 0.0), values.get("b_arcsec", 0.0)
        r = math.hypot(a, b)
        g = np.array([a, b])[: len(coef)] / r if r > 0 else np.zeros(len(coef))
        return ({"offset_arcsec": r, "angle_deg": math.degrees(math.atan2(b, a)) % 360.0},
                r, float(np.sqrt(g @ cov @ g)) if r > 0 else float("nan"))


class SquintCandidate(Candidate):
    name = "polarization_squint"
    effect = "polarization_squint"
    title = "polarization beam squint"
    kind = "channel"
    signature = "XR and XL offsets differ by a constant vector; their average is unaffected"
    params_doc: ClassVar[dict[str, str]] = {
        "separation_arcsec": "XR beam minus XL beam separation (arcsec)",
        "angle_deg": "direction of the separation, 0 = +xel, 90 = +el"}
    amplitude_param = "separation_arcsec"
    needs = ("pol_xel_arcsec",)

    def __init__(self):
        from antsim.world.effects.optics import PolarizationSquint

        self.explanation = PolarizationSquint.explanation

    def test(self, problem, perp=None, z_perp=None, chi2_now=None):
        obs, pred = problem.obs, problem.pred
        d = np.column_stack([obs.pol_xel_arcsec, obs.pol_el_arcsec]) - pred.pol_mean
        ok = problem.valid & np.isfinite(d).all(axis=1)
        if ok.sum() < 3:
            return TestResult(self, 0.0, 0, 1.0, 1.0)
        d = d[ok]
        f = problem.f[ok][:, None]
        if pred.pol_sig is not None and pred.known_noise:
            sig = pred.pol_sig[ok]
        else:
            sig = np.tile(np.std(d, axis=0, ddof=1), (d.shape[0], 1))
        # reject gross outliers (4 sigma about the median)
        z = np.abs(d - np.median(d, axis=0)) / sig
        keep = (z <= 4.0).all(axis=1)
        d, sig, f = d[keep], sig[keep], f[keep]
        # each scan shows the separation scaled by its source's offset scale
        w = 1.0 / sig**2
        mean = (w * f * d).sum(axis=0) / (w * f * f).sum(axis=0)
        var = 1.0 / (w * f * f).sum(axis=0)
        dchi2 = float(np.sum(mean**2 / var))
        if pred.known_noise:
            p = float(pvalues.chi2_sf(dchi2, 2))
        else:
            p = float(pvalues.f_sf(dchi2 / 2.0, 2, max(d.shape[0] - 1, 1)))
        # XR minus XL measured corrections are minus the beam separation
        sep = -mean
        amp = float(math.hypot(*sep))
        g = sep / amp if amp > 0 else np.zeros(2)
        amp_sig = float(np.sqrt(np.sum(g**2 * var)))
        params = {"separation_arcsec": amp,
                  "angle_deg": math.degrees(math.atan2(sep[1], sep[0])) % 360.0,
                  "xr_minus_xl_xel_arcsec": float(mean[0]), "xr_minus_xl_el_arcsec": float(mean[1])}
        return TestResult(self, dchi2, 2, 1.0, p, params=params, amplitude=amp,
                          amplitude_sigma=amp_sig, coef=mean, cov=np.diag(var))

    def draw_shape(self, rng, obs):
        return {"angle_deg": float(rng.uniform(0.0, 360.0))}

    def threshold_sigma(self, pred, used) -> float:
        """sigma of the separation estimate (arcsec) for the detection threshold."""
        sig = pred.pol_sig[used]
        w = (1.0 / sig**2).sum(axis=0)
        return float(np.sqrt(np.mean(1.0 / w)))

    def effect_params(self, shape, amplitude):
        return {"separation_arcsec": float(amplitude), "angle_deg": shape["angle_deg"]}

    def effect_from_params(self, params):
        return {"separation_arcsec": params["separation_arcsec"],
                "angle_deg": params["angle_deg"]}


class BeamWidthCandidate(Candidate):
    name = "beam_width"
    effect = "beam_width"
    title = "wrong beam width"
    kind = "channel"
    signature = ("measured beam widths differ from those the simulation predicts by one "
                 "factor, and every offset is scaled by its inverse square")
    params_doc: ClassVar[dict[str, str]] = {"scale": "true HPBW / nominal HPBW"}
    amplitude_param = "scale"
    needs_simulation = True
    needs = ("width_xel_arcmin",)

    def __init__(self):
        from antsim.world.effects.optics import BeamWidthError

        self.explanation = BeamWidthError.explanation

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and "beam_hpbw_arcmin" in obs.meta

    def _stats(self, problem):
        obs, pred = problem.obs, problem.pred
        w = np.column_stack([obs.width_xel_arcmin, obs.width_el_arcmin])
        ok = problem.used & np.isfinite(w).all(axis=1) & np.isfinite(pred.width_mean).all(axis=1)
        hp = float(obs.meta["beam_hpbw_arcmin"])
        # w^2 - w_pred^2 = hpbw^2 (f^2 - 1) for every source (sizes add in quadrature)
        d = (w[ok] ** 2 - pred.width_mean[ok] ** 2) / hp**2
        sig = 2.0 * pred.width_mean[ok] * pred.width_sig[ok] / hp**2
        return d.reshape(-1), sig.reshape(-1)

    def test(self, problem, perp=None, z_perp=None, chi2_now=None):
        d, sig = self._stats(problem)
        if d.size < 3:
            return TestResult(self, 0.0, 0, 1.0, 1.0)
        good = np.isfinite(d) & np.isfinite(sig) & (sig > 0)
        d, sig = d[good], sig[good]
        if d.size < 3:
            return TestResult(self, 0.0, 0, 1.0, 1.0)
        z = np.abs(d - np.median(d)) / sig
        keep = z <= 4.0
        d, sig = d[keep], sig[keep]
        w = 1.0 / sig**2
        mean = float((w * d).sum() / w.sum())
        var = float(1.0 / w.sum())
        dchi2 = mean * mean / var
        p = float(pvalues.chi2_sf(dchi2, 1))
        scale = math.sqrt(max(1.0 + mean, 1e-6))
        sig_scale = 0.5 * math.sqrt(var) / scale
        return TestResult(self, dchi2, 1, 1.0, p, params={"scale": scale}, amplitude=scale,
                          amplitude_sigma=sig_scale, coef=np.array([mean]),
                          cov=np.array([[var]]))

    def draw_shape(self, rng, obs):
        return {"sign": float(rng.choice([-1.0, 1.0]))}

    def threshold_sigma(self, pred, used) -> float:
        """sigma of (scale - 1) for the detection threshold."""
        sig = 2.0 * pred.width_sig[used] / pred.width_mean[used]
        w = (1.0 / sig**2).sum()
        return float(0.5 * math.sqrt(1.0 / w))

    def effect_params(self, shape, amplitude):
        return {"scale": float(1.0 + shape["sign"] * amplitude)}

    def hidden_amplitude(self, params):
        return float(params["scale"])

    def effect_from_params(self, params):
        return {"scale": params["scale"]}


# ---------------------------------------------------------------------------------------------
# The library
# ---------------------------------------------------------------------------------------------
def _harmonic(name: str, title: str, signature: str) -> TermsCandidate:
    from antsim.world.effects import EFFECTS

    cls = EFFECTS[name]
    return TermsCandidate(name, (cls.sin_term, cls.cos_term), title, signature,
                          cls.explanation, effect=name, signs=cls.signs)


def _library() -> list[Candidate]:
    in_span = "already in the 45-ft's ten-term model (W terms), so invisible with that baseline"
    lib: list[Candidate] = [
        _harmonic("az_track_2a", "azimuth track unevenness (twice per turn)",
                  "dE ~ sin 2A, cos 2A (BIMA memo 23 saw 6\" rms)"),
        _harmonic("az_track_3a", "azimuth track unevenness (three times per turn)",
                  "dE ~ sin 3A, cos 3A"),
        _harmonic("az_runout_1a", "azimuth encoder runout (once per turn)",
                  "dA ~ sin A, cos A"),
        _harmonic("az_runout_2a", "azimuth encoder runout (twice per turn)",
                  "dA ~ sin 2A, cos 2A"),
        _harmonic("el_nod_1a", "elevation nod (once per azimuth turn)", "dE ~ sin A, cos A"),
        _harmonic("el_eccentricity", "elevation encoder eccentricity (once per turn)",
                  "dE ~ sin E, cos E"),
        _harmonic("el_eccentricity_2e", "elevation encoder eccentricity (twice per turn)",
                  "dE ~ sin 2E, cos 2E"),
        TermsCandidate("gravity", ("TF",), "gravitational sag", "dE ~ cos E",
                       "the tube (dish and feed support) bends under its own weight, most "
                       "when horizontal", pair=False, blind_exclusion=in_span + " (W4)"),
        TermsCandidate("refraction", ("TX",), "refraction error", "dE ~ cot E",
                       "the refraction the controller corrects differs from the refraction "
                       "present (wrong weather data or formula)", pair=False,
                       blind_exclusion=in_span + " (W5)"),
        TermsCandidate("encoder_zero", ("IA", "IE"), "encoder zero points",
                       "dA constant, dE constant",
                       "the encoders' zero points are off", pair=False,
                       blind_exclusion=in_span + " (W1, W6)"),
        TermsCandidate("collimation", ("CA",), "collimation error", "dA ~ sec E (xel constant)",
                       "the beam is not perpendicular to the elevation axis", pair=False,
                       blind_exclusion=in_span + " (W2)"),
        TermsCandidate("non_perpendicularity", ("NPAE",), "axis non-perpendicularity",
                       "dA ~ tan E", "the elevation axis is not perpendicular to the azimuth "
                       "axis", pair=False, blind_exclusion=in_span + " (W3)"),
        TermsCandidate("azimuth_axis_tilt", ("AN", "AW"), "azimuth axis tilt",
                       "dE ~ cos A, sin A; dA ~ tan E sin A, tan E cos A",
                       "the azimuth axis is not vertical", pair=False,
                       blind_exclusion=in_span + " (W7-W10)"),
        HarmonicFamilyCandidate(
            "el_periodic_el", "E", "E", range(3, 9),
            "periodic elevation error along the elevation axis (n cycles per turn)",
            "dE ~ sin nE, cos nE (n = 3..8)",
            "a gear, encoder or lookup-table error that repeats n times per turn of the "
            "elevation axis (e.g. an optics collimation table sampled in elevation)"),
        HarmonicFamilyCandidate(
            "xel_periodic_el", "S", "E", range(1, 7),
            "cross-elevation error varying with elevation (n cycles per turn)",
            "dA cos E ~ sin nE, cos nE (n = 1..6)",
            "a collimation that changes with elevation: the optics (secondary, feed or "
            "instrument) shift sideways as the tube tips"),
        HarmonicFamilyCandidate(
            "el_periodic_az", "E", "A", range(4, 9),
            "azimuth track unevenness of higher order (n cycles per turn)",
            "dE ~ sin nA, cos nA (n = 4..8)",
            "the azimuth track has n high points per turn (segments, joints of the rail)"),
        HarmonicFamilyCandidate(
            "az_periodic_az", "A", "A", range(3, 9),
            "azimuth encoder or gear periodic error of higher order (n cycles per turn)",
            "dA ~ sin nA, cos nA (n = 3..8)",
            "an azimuth encoder, pinion or bull-gear error that repeats n times per turn"),
        FeedOffsetCandidate(),
        SunsetCandidate(),
        TemperatureCandidate(),
        ClockCandidate(),
        ServoLagCandidate(),
        BacklashCandidate(),
        SquintCandidate(),
        SourceCandidate(),
        BeamWidthCandidate(),
        ExactTiltCandidate(),
    ]
    for c in lib:
        if isinstance(c, TermsCandidate) and c.name in ("el_nod_1a",):
            c.blind_exclusion = in_span + " (W7, W8)"
    return lib


CANDIDATES: tuple[Candidate, ...] = tuple(_library())


def candidate(name: str) -> Candidate:
    """The library's candidate called ``name`` (KeyError naming the choices)."""
    for c in CANDIDATES:
        if c.name == name:
            return c
    raise KeyError(f"unknown candidate {name!r}; known: {', '.join(c.name for c in CANDIDATES)}")
