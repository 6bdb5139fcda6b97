"""What every candidate is: the base class and its test against the current model, and the
helpers the families share (time grid, Sun elevations, p-values with the look-elsewhere
correction). The package docstring says what a candidate knows."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import scipy.linalg
from astropy.time import Time, TimeDelta

from controller.astro.ephemeris import Ephemeris
from controller.astro.site import Site
from controller.units import ARCSEC_PER_RAD

from .. import pvalues
from ..data import Observations
from ..factors import kept_sun_grid, remade_when_read
from ..linalg import gram_solve, lstsq, qt_dot
from ..problem import Problem
from ..shapefit import ABSORBED_WHOLE_1MR2, GRAM_1MR2_MIN, shape_fit

__all__ = ["DISTINGUISH_R", "Candidate", "TestResult", "nyholt_gram", "nyholt_trials",
           "p_value", "periodic_interp", "source_rates_arcsec_s", "stacked", "sun_el_grid_deg",
           "time_grid", "with_trials"]

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
    #: raw (2n, q) columns at the best theta (read as ``columns``)
    _columns: np.ndarray | None = None
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
    #: the other values of a family's parameter that were tested (a harmonic family's other
    #: orders n), with their own p-values: the selection reports those the data cannot tell
    #: from the best as alternatives
    siblings: list[TestResult] = field(default_factory=list)
    #: the effective number of trials as a function of the chi^2 decrease, for a family
    #: whose look-elsewhere factor depends on the level (a change at an unknown time);
    #: None: ``trials`` at every level
    trials_at: Callable[[float], float] | None = None
    #: makes ``columns`` again when they are read, for a test that did not keep them
    _remake: Callable[[], np.ndarray] | None = field(default=None, repr=False)
    #: the columns' least-squares coefficients on the model over ``mask`` and the model's
    #: Gram there, both in the coordinates of the model's basis over its used scans (R
    #: times the coefficients, R^-T A^T A R^-1), where the test formed them
    _on_model: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)

    @property
    def columns(self) -> np.ndarray | None:
        """Raw (2n, q) columns at the best theta. Made again from the candidate each time
        they are read when the test did not keep them: every candidate's result holds
        columns, and all of them were 0.5 GB at 200,000 scans, but few are read."""
        if self._columns is None and self._remake is not None:
            return self._remake()
        return self._columns

    @columns.setter
    def columns(self, value: np.ndarray | None) -> None:
        self._columns, self._remake = value, None

    def critical_chi2(self, level: float) -> float:
        """The chi^2 decrease whose p-value, look-elsewhere effect included, is ``level``
        (known noise): the candidate's detection threshold at that level."""
        if self.trials_at is None:
            return float(pvalues.chi2_isf(level / max(self.trials, 1.0), self.dof))
        lo, hi = 0.0, 400.0  # with_trials(sf(c), trials(c)) falls as c grows
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if with_trials(pvalues.chi2_sf(mid, self.dof), self.trials_at(mid)) > level:
                lo = mid
            else:
                hi = mid
        return hi

    @property
    def name(self) -> str:
        return self.candidate.name

    @property
    def testable(self) -> bool:
        return self.dof > 0 and np.isfinite(self.delta_chi2)


# ---------------------------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------------------------
def stacked(xel: np.ndarray | None, el: np.ndarray | None, n: int) -> np.ndarray:
    x = np.zeros(n) if xel is None else np.asarray(xel, float)
    e = np.zeros(n) if el is None else np.asarray(el, float)
    return np.concatenate([x, e])


def source_rates_arcsec_s(obs: Observations) -> tuple[np.ndarray, np.ndarray]:
    """Apparent motion of a fixed source at (A, E): (dA/dt cos E, dE/dt), arcsec per s; on
    an equatorial mount's axes (H, Dec): (dH/dt cos Dec, 0), the hour angle growing at the
    sidereal rate."""
    if obs.mount == "equatorial":
        return (SIDEREAL_RATE_RAD_S * np.cos(obs.el_rad) * ARCSEC_PER_RAD,
                np.zeros(obs.n))
    phi = obs.latitude_rad
    a, e = obs.az_rad, obs.el_rad
    d_e = SIDEREAL_RATE_RAD_S * math.cos(phi) * np.sin(a)
    d_a = SIDEREAL_RATE_RAD_S * (math.sin(phi) - math.cos(phi) * np.cos(a) * np.tan(e))
    return d_a * np.cos(e) * ARCSEC_PER_RAD, d_e * ARCSEC_PER_RAD


def time_grid(obs: Observations) -> np.ndarray:
    end = float(np.nanmax(obs.t_s)) if obs.n else 0.0
    return np.arange(-SPINUP_S, end + 2 * GRID_STEP_S, GRID_STEP_S)


def periodic_interp(t_grid: np.ndarray, t: np.ndarray, v: np.ndarray) -> np.ndarray:
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


def sun_el_grid_deg(obs: Observations, t_grid: np.ndarray) -> np.ndarray:
    """Sun elevation (deg) on the grid: from the site and epoch when the recordings name them
    (ephemeris), else from the recorded Sun elevations (a day repeats); kept by site, epoch
    and grid (:func:`.factors.kept_sun_grid`)."""
    meta = obs.meta
    key = (meta.get("epoch_utc"), meta.get("latitude_deg"), meta.get("longitude_deg"),
           float(t_grid[0]), float(t_grid[-1]), t_grid.size)
    return kept_sun_grid(key, lambda: _sun_el_grid_deg(obs, t_grid))


def _sun_el_grid_deg(obs: Observations, t_grid: np.ndarray) -> np.ndarray:
    """:func:`sun_el_grid_deg`, made."""
    meta = obs.meta
    out = None
    if all(k in meta for k in ("epoch_utc", "latitude_deg", "longitude_deg")):
        try:
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
        out = periodic_interp(t_grid, obs.t_s[ok], obs.sun_el_deg[ok])
    return out


def nyholt_trials(cols: np.ndarray, overwrite: bool = False) -> float:
    """Effective number of independent tests among correlated 1-column tests (Nyholt 2004);
    ``overwrite``: ``cols`` may be normalized in place (no copy of them)."""
    m = cols.shape[1]
    if m <= 1:
        return 1.0
    norms = np.linalg.norm(cols, axis=0)
    ok = norms > 0
    if overwrite and ok.all():
        c = cols
        c /= norms
    else:
        c = cols[:, ok] / norms[ok]
    return _nyholt(np.linalg.eigvalsh(c.T @ c), int(ok.sum()))


def nyholt_gram(gram: np.ndarray) -> float:
    """:func:`nyholt_trials` of columns given by their Gram matrix (inner products)."""
    d = np.diag(gram)
    ok = d > 0
    s = np.sqrt(d[ok])
    return _nyholt(np.linalg.eigvalsh(gram[np.ix_(ok, ok)] / np.outer(s, s)), int(ok.sum()))


def _nyholt(lam: np.ndarray, m: int) -> float:
    """Nyholt's effective number of tests from the eigenvalues ``lam`` of the ``m`` tests'
    correlation matrix."""
    return float(max(1.0, 1.0 + (m - 1) * (1.0 - np.var(lam, ddof=1) / m))) if m > 1 else 1.0


def _grid_trials(problem: Problem, grid: np.ndarray, qgrid: list[np.ndarray | None]) -> float:
    """:func:`nyholt_trials` of the 1-column shapes projected off the model over its used
    scans, from ``grid`` (their whitened columns there, or projected ones where ``qgrid``
    holds None) and ``qgrid`` (q^T of each): the Gram of the projections is
    grid^T grid - QX^T QX, without a projection per shape. A shape the model absorbs whole
    (ABSORBED_WHOLE_1MR2: its projection is rounding) is no trial, as a zero column is not;
    where a shape is within GRAM_1MR2_MIN of the model (the difference would lose digits),
    the grid is projected explicitly instead."""
    if all(g is None for g in qgrid):
        return nyholt_trials(grid, overwrite=True)
    m = next(g.size for g in qgrid if g is not None)
    qx = np.column_stack([np.zeros(m) if g is None else g for g in qgrid])
    xx = grid.T @ grid
    gram = xx - qx.T @ qx
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(np.diag(xx) > 0, np.diag(gram) / np.diag(xx), 1.0)
    shapes = np.flatnonzero(ratio >= ABSORBED_WHOLE_1MR2)
    if (ratio[shapes] >= GRAM_1MR2_MIN).all():
        return nyholt_gram(gram[np.ix_(shapes, shapes)])
    grid = grid[:, shapes] - problem.basis() @ qx[:, shapes]
    return nyholt_trials(grid, overwrite=True)


def with_trials(p: float, trials: float) -> float:
    """Probability that the best of ``trials`` independent tests reaches p (Sidak)."""
    if trials <= 1.0:
        return float(p)
    if p < 1e-12:
        return float(min(1.0, trials * p))
    return float(min(1.0, -np.expm1(trials * np.log1p(-min(p, 1.0 - 1e-16)))))


def p_value(problem: Problem, dchi2: float, q: int, current_chi2: float | None = None,
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
# The base class
# ---------------------------------------------------------------------------------------------
class Candidate(ABC):
    """The candidate interface, whole: every attribute and method the selection, the
    cross-validated stage, the model update and the blind harness read of a candidate is
    declared here, with the default a family overrides (or NotImplementedError where a
    family must say it). A candidate is a description and its functions: it keeps nothing
    between calls (what is worth keeping for speed, :mod:`..factors` keeps).

    Description: ``name``, ``effect`` (the simulator effect, ``"terms"`` for pointing terms,
    None), ``title``, ``terms``, ``signature``, ``explanation``, ``params_doc``, ``kind``
    (``"offsets"``: a signature in the pointing errors; ``"channel"``: a test on other
    recorded quantities), ``linear_signature``, ``needs``, ``needs_simulation``,
    ``mounts``, ``static``, ``amplitude_param``, ``blind_exclusion``; :meth:`describe`.

    Selection: :meth:`applicable`; :meth:`test` (the added-variable test against the current
    model, its nonlinear parameters searched over :meth:`thetas` and :meth:`refine`d,
    :meth:`linear_test` per shape, :meth:`finish` for the parameters and the model terms it
    is confused with); :meth:`columns` (an offsets candidate's signature as regressors);
    :meth:`params_from`; :meth:`label`; :meth:`cv_thetas` (the cross-validated stage's
    shapes).

    Model update: :meth:`effect_from_params` (the simulator effect's parameters).

    Blind harness: :meth:`draw_shape`, :meth:`unit_signal`, :meth:`effect_params`,
    :meth:`nonlinear_part`, :meth:`signal_power`, :meth:`hidden_amplitude`,
    :meth:`hidden_label`, :meth:`threshold_sigma` (channel candidates).
    """

    name: str = ""
    effect: str | None = None  # simulator effect (antsim.world.effects.EFFECTS) or None
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
    #: its signature depends on the direction only (a pointing-model term): an observatory
    #: that fitted its model has the part the model's terms can take in the model in use
    static: bool = False
    needs_simulation: bool = False
    #: the mounts whose recordings it is tried on (its signature is written on their axes)
    mounts: tuple[str, ...] = ("altaz",)
    #: its signature is linear in its parameters at each shape: :meth:`columns` gives it
    #: (False: a nonlinear signature, fitted by its own :meth:`test`)
    linear_signature: bool = True

    def applicable(self, obs: Observations, known_noise: bool) -> bool:
        if obs.mount not in self.mounts:
            return False
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
    @abstractmethod
    def columns(self, obs: Observations, theta: Any = None) -> tuple[np.ndarray, tuple[str, ...]]:
        """The signature at shape ``theta`` as raw columns (2n, q): the error (indicated
        minus true, arcsec) per unit of each linear parameter, xel rows then el rows; and
        the parameters' names (NotImplementedError where the signature is not linear in
        the parameters or not in the offsets: ``linear_signature``, ``kind``)."""

    def thetas(self, obs: Observations) -> list[Any]:
        """The shapes (values of the nonlinear parameters) :meth:`test` tries."""
        return [None]

    def cv_thetas(self, problem) -> list[Any]:
        """The shapes the cross-validated stage (:mod:`..crossval`) compares: all of them
        unless there is one per scan (a step's change time)."""
        return self.thetas(problem.obs)

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
        thetas = self.thetas(obs)
        # the 1-column shapes whitened over the current model's scans (``perp``'s), for the
        # trials: filled in place (one copy of them, not a list and its stacked copy), each
        # with q^T x (q the model's basis there; zero for a column projected off it already)
        grid = np.empty((z_perp.size, len(thetas))) if len(thetas) > 1 else None
        qgrid: list[np.ndarray | None] = []
        tested: dict[Any, float] = {}  # each theta -> its delta chi^2 (refine starts there)
        for theta in thetas:
            cols, names = self.columns(obs, theta)
            res, xu, qxu = self._linear_xp(problem, cols, names, theta)
            tested[theta] = res.delta_chi2
            if cols.shape[1] == 1 and grid is not None:
                grid[:, len(qgrid)] = xu[:, 0] if xu is not None \
                    else perp(problem.cand(cols))[:, 0]
                qgrid.append(None if qxu is None else qxu[:, 0])
            if best is None or res.delta_chi2 > best.delta_chi2:
                best = res
            del cols, xu
        assert best is not None
        best = self.refine(problem, perp, z_perp, best, tested)
        best.trials = _grid_trials(problem, grid[:, :len(qgrid)], qgrid) \
            if len(qgrid) > 1 else 1.0
        del grid
        best.p = with_trials(p_value(problem, best.delta_chi2, best.dof, best.chi2_now,
                                     best.mask), best.trials)
        if best.dof > 0:
            self.finish(problem, best)
        return best

    def refine(self, problem: Problem, perp, z_perp, best: TestResult,
               grid: dict[Any, float]) -> TestResult:
        """The best result refined beyond the grid of :meth:`thetas` (``grid``: each theta
        tested -> its delta chi^2); the grid's best as it is by default."""
        return best

    def linear_test(self, problem: Problem, perp, z_perp, cols: np.ndarray,
                names: tuple[str, ...], theta: Any) -> TestResult:
        """chi^2 decrease from adding raw ``cols`` (scaled here by the offset scale), on the
        scans a model with the candidate keeps (``perp``, ``z_perp``: unused, the test
        projects over those scans)."""
        return self._linear_xp(problem, cols, names, theta)[0]

    def _linear_xp(self, problem: Problem, cols: np.ndarray, names: tuple[str, ...],
                   theta: Any) -> tuple[TestResult, np.ndarray | None, np.ndarray | None]:
        """:meth:`linear_test`, the candidate's columns whitened over the model's used scans and
        q^T of them (q the model's basis there; None: the columns are projected off it
        already), or (None, None) where they were not formed there. From the model's cached
        basis by inner products (:func:`.shapefit.shape_fit`) where it serves, else by
        explicit projections (:meth:`_linear_explicit`)."""
        raw = cols
        sf = shape_fit(problem, raw)
        res = None if sf is None else self._from_shape_fit(problem, sf, raw, names, theta)
        if res is not None:
            k = raw.shape[1]
            return res, sf.x[:, :k], sf.qx[:, :k]
        res, xp = self._linear_explicit(problem, raw, problem.cand(raw), names, theta)
        return res, xp if np.array_equal(res.mask, problem.used) else None, None

    def _from_shape_fit(self, problem: Problem, sf, raw: np.ndarray, names: tuple[str, ...],
                        theta: Any) -> TestResult | None:
        """:meth:`_linear_explicit`'s result from :func:`.shapefit.shape_fit`'s inner products
        over the same scans (the same least-squares problem); None where a column kept is
        within GRAM_1MR2_MIN of the model's span or the kept ones' Gram is ill-conditioned
        (the explicit path then serves)."""
        k = raw.shape[1]
        j = slice(0, k) if problem.unscaled else slice(k, 2 * k)  # the raw signature's
        full_sq, left_sq = sf.full_sq[j], np.diag(sf.gram)[j]
        if not (full_sq > 0).all():
            return None
        one_minus_r2 = left_sq / full_sq
        keep = one_minus_r2 > ABSORBED_1MR2
        absorbed = tuple(n for n, kp in zip(names, keep, strict=True) if not kp)
        if not keep.any():
            return TestResult(self, 0.0, 0, 1.0, 1.0, theta, None, names, absorbed=absorbed,
                              mask=sf.mask, _remake=self._remaker(problem, theta, raw, raw=True))
        ratio = np.diag(sf.gram)[:k] / sf.full_sq[:k]
        if min(one_minus_r2[keep].min(), ratio[keep].min()) < GRAM_1MR2_MIN:
            return None
        kept = np.flatnonzero(keep)
        if keep.all() and sf.coef.size == k:  # the mask's last fit solved this problem
            coef, cov = sf.coef, sf.cov
        else:
            solved = gram_solve(sf.gram[np.ix_(kept, kept)], sf.rhs[kept])
            if solved is None:
                return None
            coef, cov = solved
        r = np.sqrt(np.clip(1.0 - one_minus_r2[keep], 0.0, 1.0))
        return TestResult(self, float(sf.rhs[kept] @ coef), kept.size, 1.0, 1.0, theta, None,
                          tuple(n for n, kp in zip(names, keep, strict=True) if kp), coef,
                          cov, absorbed=absorbed, r_model=float(r.max()), mask=sf.mask,
                          chi2_now=float(sf.chi2_now),
                          _remake=self._remaker(problem, theta, raw, keep, raw=True),
                          _on_model=(sf.on_model[:, kept], sf.model_gram))

    def _linear_explicit(self, problem: Problem, raw: np.ndarray, cols: np.ndarray,
                         names: tuple[str, ...], theta: Any) -> tuple[TestResult, np.ndarray]:
        """:meth:`linear_test` by explicit projections (the reference :meth:`_from_shape_fit`
        is tested against, and the path where it does not serve), and the candidate's
        columns whitened and projected off the model over the scans it kept (2 n_kept, q)."""
        fitted_mask = problem.mask_fit(cols)
        mask, last = fitted_mask.mask, fitted_mask.last
        perp, z_perp = problem.perp_for(mask)
        # the mask's last fit projected the columns already (the same projection)
        xp = perp(cols) if last is None else last.x_perp
        # degeneracy with the model is a property of the signature itself (before the
        # per-source offset scale): judge absorption and correlation on the raw columns
        if problem.unscaled:
            full = np.linalg.norm(problem.whiten(raw, mask) if last is None else last.x, axis=0)
            left = np.linalg.norm(xp, axis=0)
        elif last is not None:  # the model's cached factor over the mask: whiten raw once
            xr = problem.whiten(raw, mask)
            q = problem.basis(mask)
            full = np.linalg.norm(xr, axis=0)
            left = np.linalg.norm(xr - q @ qt_dot(q, xr), axis=0)  # what perp(raw) computes
            del xr
        else:
            full = np.linalg.norm(problem.whiten(raw, mask), axis=0)
            left = np.linalg.norm(perp(raw), axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            one_minus_r2 = np.where(full > 0, (left / full) ** 2, 0.0)
        keep = one_minus_r2 > ABSORBED_1MR2
        absorbed = tuple(n for n, k in zip(names, keep, strict=True) if not k)
        if not keep.any():
            return TestResult(self, 0.0, 0, 1.0, 1.0, theta, None, names, absorbed=absorbed,
                              mask=mask, _remake=self._remaker(problem, theta, cols)), xp
        if last is not None and keep.all():  # the mask's last fit solved this problem
            xk, coef, cov = xp, last.fit.coef[-xp.shape[1]:], last.fit.cov
        else:
            xk = xp[:, keep]
            coef, cov = lstsq(xk, z_perp)
        fitted = xk @ coef
        r = np.sqrt(np.clip(1.0 - one_minus_r2[keep], 0.0, 1.0))
        return TestResult(self, float(fitted @ fitted), int(keep.sum()), 1.0, 1.0, theta,
                          None, tuple(n for n, k in zip(names, keep, strict=True) if k),
                          coef, cov, absorbed=absorbed, r_model=float(r.max()), mask=mask,
                          chi2_now=float(z_perp @ z_perp),
                          _remake=self._remaker(problem, theta, cols, keep)), xp

    def _remaker(self, problem: Problem, theta: Any, cols: np.ndarray,
                 keep: np.ndarray | None = None, raw: bool = False
                 ) -> Callable[[], np.ndarray]:
        """The candidate columns ``cols`` (scaled, 2n x q; the ``keep`` ones) made again from
        :meth:`columns` at ``theta`` when a result's columns are read
        (:func:`..factors.remade_when_read`). ``raw``: ``cols`` are the raw columns (their
        fingerprint scales their rows as :meth:`Problem.cand` does)."""
        scale = np.concatenate([problem.offset_scale, problem.offset_scale]) if raw else None
        return remade_when_read(
            lambda: problem.cand(self.columns(problem.obs, theta)[0]), cols, keep, scale,
            f"{self.name}: columns at {theta!r} are not the tested ones")

    def finish(self, problem: Problem, res: TestResult) -> None:
        """Parameters, and the model terms the candidate is most correlated with."""
        if problem.pred.known_noise:
            cov = res.cov
        else:
            cov = res.cov  # whitened units: the per-axis scale is already the noise
        res.params, res.amplitude, res.amplitude_sigma = self.params_from(
            problem.obs, res.theta, res.coef, cov, res.comp_names)
        if res.r_model <= 0.5:
            return
        r = problem.current_r(problem.used) if res._on_model is not None else None
        if r is not None:  # from the shape test's inner products: no columns again
            on_model, gram = res._on_model
            beta = scipy.linalg.solve_triangular(r, on_model)
            norms = np.sqrt(np.clip(np.einsum("ij,ik,kj->j", r, gram, r), 0.0, None))
        else:
            cols = res.columns  # read once (may be made again)
            if cols is None or not cols.size:
                return
            x = problem.whiten(cols, res.mask)
            beta = problem.coef_on_current(x, res.mask)
            if beta is None:
                a = problem.whiten(problem.current_columns(), res.mask)
                beta, _ = lstsq(a, x)
                norms = np.linalg.norm(a, axis=0)
            else:  # the whitened model's column norms are its R's (Q is orthonormal)
                norms = problem.current_norms(res.mask)
        contrib = np.abs(beta) * norms[:, None]
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
        """The simulator effect's parameters of a drawn shape at ``amplitude``."""
        raise NotImplementedError

    def effect_from_params(self, params: dict[str, Any]) -> dict[str, Any] | None:
        """The simulator effect's parameters from a finding's ``params`` (None: the
        candidate names no simulator effect, or its terms say it)."""
        return None

    def threshold_sigma(self, pred, used: np.ndarray) -> float:
        """A channel candidate's standard error at the predicted noise, for the blind
        harness's detection threshold."""
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
                "blind": self.blind_exclusion or "drawn", "mounts": list(self.mounts)}
