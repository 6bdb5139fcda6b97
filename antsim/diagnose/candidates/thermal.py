"""Thermal candidates: an elevation drift that follows the sunset with a lag, one that
follows the air temperature, and the thermal deformation as structure temperature sensors see
it (recordings of an antenna with sensors).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from antsim.world.effects.drifts import TemperatureDrift, structure_temperature_c
from antsim.world.effects.heating import ThermalEffect
from antsim.world.effects.thermal import (
    SunsetDrift,
    since_sunset,
    sunset_level,
    transient_level,
)
from controller.pointing.model import PointingModel
from controller.pointing.thermal import SENSOR_FAMILY

from ..data import Observations
from ..linalg import lstsq
from ..problem import Problem
from .base import (
    GRID_STEP_S,
    Candidate,
    TestResult,
    periodic_interp,
    stacked,
    sun_el_grid_deg,
    time_grid,
)
from .terms import TermsCandidate

__all__ = ['SensorTermsCandidate', 'SunsetCandidate', 'SunsetTransientCandidate',
           'TemperatureCandidate']

#: the time-constant searches' tolerance in log theta: 1% of tau, some 20 times finer than
#: tau's own standard error (Fomalont's drift, 16 seeds: 22-31% of tau,
#: docs/results/blind_fomalont.txt); 1e-3 took 68 tests at 200,000 scans where this takes
#: 51, for time constants that moved by under 1% of their sigma
XATOL_LOG_THETA = 1e-2


#: the golden section's step, a fraction of the bracket's wider side
_GOLDEN = 0.5 * (3.0 - math.sqrt(5.0))


def _next_point(a: float | None, x: float, b: float | None, values: dict[float, float],
                widths: list[float]) -> float:
    """The next log theta to test: the vertex of the parabola through the best point ``x``
    and its tested neighbours ``a`` < x < ``b`` (None: x is a bound) in ``values`` (delta
    chi^2, maximized), at least XATOL_LOG_THETA from each; a golden-section step into the
    wider side where there is no such vertex or the bracket (``widths``, its width at each
    step) has not halved in two steps (Brent's safeguard)."""
    tol = XATOL_LOG_THETA
    left = x - a if a is not None else 0.0
    right = b - x if b is not None else 0.0
    u = None
    if a is not None and b is not None and (len(widths) < 3 or widths[-1] <= 0.5 * widths[-3]):
        fa, fx, fb = -values[a], -values[x], -values[b]
        r = (x - a) * (fx - fb)
        q = (x - b) * (fx - fa)
        den = 2.0 * (q - r)
        if den != 0.0:
            v = x - ((x - b) * q - (x - a) * r) / den
            if a < v < b:
                u = v
    if u is None:  # the golden section of the wider side
        u = x + _GOLDEN * right if right >= left else x - _GOLDEN * left
    # into a side wider than XATOL_LOG_THETA, at least that far from x and from its end
    if u < x and left > tol:
        return max(min(u, x - tol), min(a + tol, x - tol))
    if u > x and right > tol:
        return min(max(u, x + tol), max(b - tol, x + tol))
    return x + tol if right > tol else x - tol


class _LaggedCandidate(Candidate):
    """An effect with one time constant ``tau_s`` (a lag or a relaxation): the blind
    harness draws tau log-uniformly between 30 min and 3 h, with either sign."""

    def _refine_log_theta(self, problem: Problem, perp, z_perp, best: TestResult,
                          grid: dict[Any, float], log_lo: float, log_hi: float,
                          end: float | None = None) -> TestResult:
        """The time constant between exp(log_lo) and exp(log_hi) that fits best (a search
        in log theta to XATOL_LOG_THETA), or ``best`` if that fits better.

        ``end`` (log_lo or log_hi, where the grid's best is its first or last point): the
        bound past the grid. Where the fit there is at least as good as at the grid's best
        and XATOL_LOG_THETA inside it, the optimum of a unimodal decrease lies within that
        tolerance of the bound, and the bound is the answer (two tests).

        Otherwise the search starts from what the grid found (``grid``: each time constant
        of the grid tested this round -> its delta chi^2): the best point and its
        neighbours bracket the optimum, and
        each step tests the vertex of the parabola through the best point and the nearest
        tested ones on either side (kept XATOL_LOG_THETA from each; the bracket's wider side
        by the golden section where a parabola does not narrow it), until both lie within
        XATOL_LOG_THETA of the best: a unimodal optimum is then within that tolerance of it,
        the bounded search's stopping rule. That took 3-7 tests where scipy's bounded search
        (which ignores the grid's tests) took 6-7 (tests/antsim/diagnose/test_memory.py; 1-4 against
        7-10 at 200,000 scans); the time constants found move by under 1% of tau, 3% of
        their sigma (docs/results/blind_fomalont.txt)."""
        obs = problem.obs
        tested: dict[float, TestResult] = {}  # log theta -> its test here
        values: dict[float, float] = {}  # log theta -> delta chi^2

        def run(log_theta: float) -> TestResult:
            theta = math.exp(log_theta)
            res = self.linear_test(problem, perp, z_perp, *self.columns(obs, theta), theta)
            tested[log_theta], values[log_theta] = res, res.delta_chi2
            return res

        if end is not None:
            inside = end + (XATOL_LOG_THETA if end == log_lo else -XATOL_LOG_THETA)
            at_end, near = run(end), run(inside)
            if at_end.delta_chi2 >= max(near.delta_chi2, best.delta_chi2):
                return at_end
        # the grid's tests bracketing the search (theta > 0) and its best
        for theta, dchi2 in grid.items():
            if theta > 0 and log_lo - 1e-12 <= math.log(theta) <= log_hi + 1e-12:
                values.setdefault(math.log(theta), dchi2)
        for bound in (log_lo, log_hi):  # a bound the grid did not test: tested
            if not any(abs(x - bound) <= 1e-12 for x in values):
                run(bound)
        widths: list[float] = []
        for _ in range(64):  # each step narrows the bracket by XATOL_LOG_THETA at least
            xs = sorted(values)
            i = max(range(len(xs)), key=lambda j: (values[xs[j]], -j))
            x = xs[i]
            a = xs[i - 1] if i > 0 else None
            b = xs[i + 1] if i + 1 < len(xs) else None
            if (a is None or x - a <= XATOL_LOG_THETA * (1 + 1e-9)) and \
                    (b is None or b - x <= XATOL_LOG_THETA * (1 + 1e-9)):
                break
            widths.append((b if b is not None else x) - (a if a is not None else x))
            run(_next_point(a, x, b, values, widths))
        x = max(values, key=values.get)
        res = tested.get(x)
        if res is None:  # a grid point: the test passed in
            return best
        return best if res.delta_chi2 < best.delta_chi2 else res

    TAUS: tuple[float, ...] = ()

    def thetas(self, obs):
        return list(self.TAUS)

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

    #: the simulator effect's ``shape`` (antsim.world.effects.thermal.sunset_level)
    shape = "relaxation"

    def __init__(self):
        super().__init__()
        self.explanation = SunsetDrift.explanation + " (Fomalont 1973: 1' in the 4 h after " \
                                                      "sunset)"

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and (
            obs.sun_el_deg is not None or "epoch_utc" in obs.meta) and np.ptp(obs.t_s) > 4 * 3600

    def level(self, obs: Observations, tau_s: float) -> np.ndarray:
        t = time_grid(obs)
        night = (sun_el_grid_deg(obs, t) < 0.0).astype(float)
        if self.shape == "transient":
            lev = transient_level(since_sunset(night), GRID_STEP_S, tau_s)
        else:
            lev = sunset_level(night, GRID_STEP_S, tau_s, self.shape)
        return np.interp(obs.t_s, t, lev)

    def columns(self, obs, theta=None):
        return stacked(None, self.level(obs, float(theta)), obs.n)[:, None], ("amplitude",)

    def refine(self, problem, perp, z_perp, best, grid):
        if best.dof == 0:
            return best
        obs = problem.obs
        lo, hi = math.log(self.TAUS[0] / 1.5), math.log(self.TAUS[-1] * 1.5)
        i = list(self.TAUS).index(best.theta)
        a = math.log(self.TAUS[max(i - 1, 0)]) if i > 0 else lo
        b = math.log(self.TAUS[min(i + 1, len(self.TAUS) - 1)]) if i < len(self.TAUS) - 1 \
            else hi

        end = lo if i == 0 else hi if i == len(self.TAUS) - 1 else None
        res = self._refine_log_theta(problem, perp, z_perp, best, grid, a, b, end)
        # joint covariance of (amplitude, log tau) from the Jacobian
        tau = float(res.theta)
        h = 0.01
        d = (self.columns(obs, tau * math.exp(h))[0] - self.columns(obs, tau * math.exp(-h))[0]) \
            / (2 * h) * float(res.coef[0])
        perp, z_perp = problem.perp_for(res.mask)
        jac = perp(np.column_stack([res.columns, problem.cand(d)]))
        _, cov2 = lstsq(jac, z_perp)
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
                "tau_s": float(shape["tau_s"]), "shape": self.shape}

    def effect_from_params(self, params: dict[str, Any]) -> dict[str, Any]:
        return {"amplitude_arcsec": params["amplitude_arcsec"], "tau_s": params["tau_s"],
                "shape": self.shape}

    def hidden_label(self, params: dict[str, Any]) -> str:
        return self.name


class SunsetTransientCandidate(SunsetCandidate):
    """A change the evening sets off and that dies away: ``a exp(-(t - t_set) / tau)`` after
    each sunset (the simulator's sunset drift with ``shape = "transient"``)."""

    name = "sunset_transient"
    title = "a transient after sunset"
    signature = ("elevation residuals that jump at sunset and die away as exp(-t/tau), back "
                 "to the daytime level within a few tau")
    params_doc: ClassVar[dict[str, str]] = {
        "amplitude_arcsec": "elevation change at sunset (arcsec)",
        "tau_s": "time constant of its decay (s)"}
    shape = "transient"
    TAUS = (600.0, 900.0, 1200.0, 1800.0, 2400.0, 3600.0, 4800.0, 6000.0, 7200.0, 9000.0,
            10800.0)

    def __init__(self):
        super().__init__()
        self.explanation = ("at sunset the structure's sunlit side starts to cool before the "
                            "rest: a temperature difference appears and dies away as the "
                            "structure settles, and the elevation error with it")


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
        super().__init__()
        self.explanation = TemperatureDrift.explanation

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and np.ptp(obs.t_s) > 4 * 3600 and \
            float(np.nanstd(obs.air_temp_c)) > 0.3

    def structure(self, obs: Observations, tau_s: float) -> tuple[np.ndarray, float]:
        t = time_grid(obs)
        ts = np.interp(obs.t_s, t, structure_temperature_c(t, self._air(obs, t), tau_s))
        return ts, float(np.mean(ts[obs.good]) if obs.good.any() else 0.0)

    @staticmethod
    def _air(obs: Observations, t: np.ndarray) -> np.ndarray:
        """The air temperature (C) on the time grid ``t``."""
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
            air = periodic_interp(t, obs.t_s[ok], obs.air_temp_c[ok])
        return air

    def columns(self, obs, theta=None):
        ts, mean = self.structure(obs, float(theta))
        return stacked(None, ts - mean, obs.n)[:, None], ("arcsec_per_k",)

    def refine(self, problem, perp, z_perp, best, grid):
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

            res = self._refine_log_theta(problem, perp, z_perp, best, grid, a, b,
                                         b if i + 1 == len(taus) else None)
        tau = float(res.theta)
        if tau > 0:
            h = 0.01
            d = (self.columns(obs, tau * math.exp(h))[0]
                 - self.columns(obs, tau * math.exp(-h))[0]) / (2 * h) * float(res.coef[0])
            perp, z_perp = problem.perp_for(res.mask)
            jac = perp(np.column_stack([res.columns, problem.cand(d)]))
            _, res.cov = lstsq(jac, z_perp)

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


class SensorTermsCandidate(TermsCandidate):
    """The thermal deformation, linear in the recorded structure temperature differences:
    the six pair terms of :mod:`controller.pointing.thermal` (fit T's candidates), tested
    together. Applicable to recordings with every sensor those terms read (an antenna with
    structure temperature sensors). It names the thermal effect and its terms; it adds no
    simulator effect (the structure's heating is not recovered from six coefficients:
    ``antsim.diagnose.modelit``)."""

    def __init__(self):
        terms = SENSOR_FAMILY
        super().__init__(
            "thermal_sensors", terms, "thermal deformation seen by the structure sensors",
            "residuals linear in the structure temperature differences: the feed legs' "
            "upper-lower (dE) and right-left (dA cos E), the yoke's bow (dE) and roll, the "
            "pedestal's (an azimuth-axis tilt)",
            ThermalEffect.explanation + "; the structure temperature sensors see it: fit the "
            "thermal terms " + " ".join(terms) + " with the geometric ones (fit T, "
            "'antsim fit --terms ...,TEDFB')",
            effect="thermal", pair=False,
            blind_exclusion="it needs recordings with structure temperatures")

    def applicable(self, obs, known_noise):
        need = PointingModel(list(self.terms)).regressors
        return super().applicable(obs, known_noise) and obs.structure is not None \
            and need <= set(obs.structure)
