"""Changes at one instant: a step (changepoint) in either axis at an unknown time.

The azimuth or the elevation zero point changes between two scans and stays changed (an
encoder slip, a moved subreflector or feed, a re-levelling; docs/physics.md's "a step
at an unknown time"). Every gap between consecutive scans (with at least ``MIN_SIDE`` scans
on each side) on either axis is one trial; all are tested at once, vectorized (one
projection of every step column), and the look-elsewhere effect is paid with the effective
number of independent trials among them (Nyholt 2004, as for the drifts' time constants).
The time is located with its uncertainty: every change time whose chi^2 decrease lies
within the 95% point of chi^2_1 (3.84) of the best (a profile-likelihood interval).

The test: the largest chi^2 decrease over every change time of either axis, each a
one-parameter added-variable test. Its null distribution is that of the maximum of a
chi^2_1 process along the sequence of change times, whose tail the tube formula bounds
(Davies 1987, Biometrika 74, 33, for one parameter): P(max > u) <= k P(chi^2_1 > u) +
(L / pi) exp(-u / 2), with k = 2 ends (one per axis) and L the length of the curve the
unit-normalized projected step columns trace on the sphere (the sum of the angles between
neighbours). Nyholt's eigenvalue count, right for the drifts' few time constants, is five
times too conservative here; the tube formula, 1.5-2 times (a Monte Carlo of the maximum
on the 1990 campaign's 282 scans: 0.0065 against 0.0117 at u = 16, 0.0010 against 0.0016
at u = 20; tests/antsim/diagnose/test_diagnose.py checks it on a smaller design).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from antsim.world.effects.steps import Step

from .. import pvalues
from ..problem import Problem
from .base import Candidate, TestResult, p_value, stacked, with_trials

__all__ = ["StepCandidate", "curve_length", "tube_trials"]

#: chi^2_1's 95% point: the profile-likelihood interval of the change time
PROFILE_95 = 3.841458820694124


def curve_length(xp: np.ndarray, split: int) -> float:
    """Length (radians) of the curve the unit-normalized columns of ``xp`` trace, in order,
    as two curves: columns [0, split) and [split, end)."""
    return sum(_arc_length(np.einsum("ij,ij->j", part, part),
                           np.einsum("ij,ij->j", part[:, 1:], part[:, :-1]))
               for part in (xp[:, :split], xp[:, split:]))


def _arc_length(norm2: np.ndarray, dots: np.ndarray) -> float:
    """Length (radians) of the curve of unit vectors from vectors of squared norms
    ``norm2`` whose neighbours' inner products are ``dots`` (one fewer)."""
    if norm2.size < 2:
        return 0.0
    cos = np.abs(dots) / np.sqrt(norm2[1:] * norm2[:-1])
    return float(np.arccos(np.clip(cos, 0.0, 1.0)).sum())


def _as_slice(index: np.ndarray) -> np.ndarray | slice:
    """``index`` (ascending integers) as the slice it equals where it is a run of
    consecutive ones: rows taken as a view, not gathered into a copy (the same numbers)."""
    if index.size and index[-1] - index[0] == index.size - 1 and bool(
            np.all(index[1:] > index[:-1])):
        return slice(int(index[0]), int(index[-1]) + 1)
    return index


def _rows_dot(sq: np.ndarray, qc: np.ndarray, a: np.ndarray | slice,
              b: np.ndarray | slice) -> np.ndarray:
    """The inner products of step columns ``a`` and ``b`` (a < b, one axis) from their
    squared norms ``sq`` and their model parts ``qc`` (:meth:`StepCandidate._all_stats`)."""
    return sq[b] - np.einsum("ij,ij->i", qc[a], qc[b])


def tube_trials(u: float, length: float, ends: int) -> float:
    """The tube formula's bound on P(max of a chi^2_1 process > u) over curves of total
    ``length`` with ``ends`` ends, as a number of trials: bound / P(chi^2_1 > u) (>= 1)."""
    sf = float(pvalues.chi2_sf(u, 1))
    if sf <= 0.0:  # far in the tail: the ratio's limit, L sqrt(u / (2 pi)) / ... + ends
        return ends + length / math.pi * math.sqrt(math.pi * u / 2.0)
    return max(1.0, (ends * sf + length / math.pi * math.exp(-u / 2.0)) / sf)


class StepCandidate(Candidate):
    name = "step"
    effect = "step"
    title = "step (a change at an unknown time)"
    signature = ("the azimuth or the elevation zero point jumps between two scans and stays "
                 "changed (a changepoint at an unknown time, not a drift)")
    params_doc: ClassVar[dict[str, str]] = {
        "axis": "az (azimuth zero point: xel ~ cos E) or el (elevation zero point)",
        "t_s": "time of the change (s after the start: midway between two scans)",
        "t_low_s": "earliest change time within the 95% interval (s)",
        "t_high_s": "latest change time within the 95% interval (s)",
        "step_arcsec": "size of the change (arcsec of azimuth or of elevation)"}
    amplitude_param = "step_arcsec"
    needs = ("time",)
    AXES = ("az", "el")
    #: scans required on each side of a change
    MIN_SIDE = 3

    def __init__(self):
        self.explanation = Step.explanation

    def change_times(self, obs) -> np.ndarray:
        """Candidate change times (s): midway between consecutive distinct scan times, with
        ``MIN_SIDE`` good scans on each side."""
        t = np.unique(obs.t_s[obs.good])
        if t.size < 2 * self.MIN_SIDE:
            return np.zeros(0)
        mid = 0.5 * (t[1:] + t[:-1])
        return mid[self.MIN_SIDE - 1: t.size - self.MIN_SIDE]

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and self.change_times(obs).size > 0

    def thetas(self, obs):
        return [(axis, float(t)) for axis in self.AXES for t in self.change_times(obs)]

    def _theta(self, times: np.ndarray, k: int) -> tuple[str, float]:
        """``thetas(obs)[k]`` from ``change_times(obs)``: the tests need one or two of them,
        not the list (two tuples a scan: 35 MB at 200,000 scans)."""
        return self.AXES[k // times.size], float(times[k % times.size])

    def _all_columns(self, obs) -> np.ndarray:
        """Every step column (2n, 2 m): azimuth steps at each change time, then elevation."""
        times = self.change_times(obs)
        after = (obs.t_s[:, None] > times[None, :]).astype(float)
        zero = np.zeros_like(after)
        az = np.vstack([after * np.cos(obs.el_rad)[:, None], zero])
        el = np.vstack([zero, after])
        return np.hstack([az, el])

    def columns(self, obs, theta=None):
        axis, t0 = theta
        after = (obs.t_s > t0).astype(float)
        if axis == "az":
            return stacked(after * np.cos(obs.el_rad), None, obs.n)[:, None], ("az_arcsec",)
        return stacked(None, after, obs.n)[:, None], ("el_arcsec",)

    def _all_stats(self, problem: Problem, perp, z_perp):
        """Of every step column (:meth:`_all_columns`, whitened and projected): the inner
        products with ``z_perp``, the squared norms, and a function giving the inner
        products of columns ``a`` and ``b`` (index arrays). Where the noise is white (a
        weight per row), from running sums over the scans in time order, O(n k) for n scans
        and k model columns instead of the O(n m) columns for m change times: a step column
        c_j is the scans after its time, so c_a.c_b = |c_b|^2 for a < b of one axis, and
        projecting out the model's orthonormal basis Q subtracts (Q'c_a).(Q'c_b). With
        correlated noise (a scenario's prediction: a few thousand scans), the columns."""
        obs = problem.obs
        used = problem.used
        if not problem.white(used):
            xp = perp(problem.cand(self._all_columns(obs)))
            return (xp.T @ z_perp, np.einsum("ij,ij->j", xp, xp),
                    lambda a, b: np.einsum("ij,ij->j", xp[:, a], xp[:, b]))
        q = problem.basis(used)
        times = self.change_times(obs)
        n, n_used = obs.n, int(used.sum())
        t = obs.t_s[used]
        order = np.argsort(t, kind="stable")
        start = np.searchsorted(t[order], times, side="right")  # first scan after each time

        past = start >= n_used  # no scan after the time (the last ones)

        at = np.where(past, 0, start)

        def after(x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
            """Sums of ``x`` (n_used, in time order) over the scans after each time."""
            out = np.take(np.cumsum(x[::-1])[::-1], at, out=out)
            out[past] = 0.0
            return out

        cz, sq = [], []
        # filled in place, an axis at a time: no copy of the n x k sums beside them
        qc_all = np.empty((2 * times.size, q.shape[1]))
        qz = q.T @ z_perp
        for axis in range(2):
            rows = slice(axis * n_used, (axis + 1) * n_used)
            g = problem.offset_scale[used] * problem.row_weights[axis * n:(axis + 1) * n][used]
            if axis == 0:  # an azimuth step shows as dA cos E in cross-elevation
                g = g * np.cos(obs.el_rad[used])
            g = g[order]
            qc = qc_all[axis * times.size:(axis + 1) * times.size]
            q_axis = q[rows]
            # a column at a time (the same sums: a cumulative sum runs down each column
            # alone): no n x k products, reversed sums and gathered copies beside ``qc``
            for j in range(q.shape[1]):
                after(g * q_axis[order, j], out=qc[:, j])
            sq.append(after(g * g))
            cz.append(after(g * z_perp[rows][order]) - qc @ qz)
        sq_all = np.concatenate(sq)
        norm2 = sq_all - np.einsum("ij,ij->i", qc_all, qc_all)
        return (np.concatenate(cz), norm2,
                lambda a, b: _rows_dot(sq_all, qc_all, _as_slice(a), _as_slice(b)))

    def _gains(self, problem: Problem, perp, z_perp):
        """The chi^2 decrease of each step column (0 where the model absorbs it), which
        columns count (``ok``), their squared norms and the inner-product function of
        :meth:`_all_stats`."""
        xz, norm2, dot = self._all_stats(problem, perp, z_perp)
        ok = norm2 > 1e-9 * max(float(norm2.max()), 1e-300)
        return np.where(ok, xz ** 2 / np.where(ok, norm2, 1.0), 0.0), ok, norm2, dot

    def cv_thetas(self, problem: Problem):
        """The most likely change time of each axis (the largest chi^2 decrease): held-out
        fits at every gap between scans would refit the model once per scan (n^2: hours
        for 200,000 scans)."""
        gain = self._gains(problem, *problem.perp_for(problem.used))[0]
        times = self.change_times(problem.obs)
        m = times.size
        return [self._theta(times, int(np.argmax(gain[:m]))),
                self._theta(times, m + int(np.argmax(gain[m:])))]

    def test(self, problem: Problem, perp, z_perp, chi2_now) -> TestResult:
        obs = problem.obs
        times = self.change_times(obs)
        gain, ok, norm2, dot = self._gains(problem, perp, z_perp)
        best = int(np.argmax(gain))
        theta = self._theta(times, best)
        cols, names = self.columns(obs, theta)
        res = self.linear_test(problem, perp, z_perp, cols, names, theta)
        if not res.testable:
            return res
        m = times.size
        length = 0.0
        for axis in (slice(0, m), slice(m, 2 * m)):  # the kept columns' two curves
            k = np.flatnonzero(ok[axis]) + axis.start
            length += _arc_length(norm2[k], dot(k[:-1], k[1:]))
        res.trials_at = lambda u, _l=length: tube_trials(u, _l, ends=2)
        res.trials = res.trials_at(res.delta_chi2)
        res.p = with_trials(p_value(problem, res.delta_chi2, res.dof, res.chi2_now, res.mask),
                            res.trials)
        # the profile over the change time on the chosen axis: a 95% interval
        axis_gain = gain[:m] if best < m else gain[m:]
        inside = times[axis_gain >= axis_gain.max() - PROFILE_95]
        res.theta = (*theta, float(inside.min()), float(inside.max()))
        self.finish(problem, res)
        return res

    def params_from(self, obs, theta, coef, cov, names):
        axis, t0, lo, hi = theta if len(theta) == 4 else (*theta, theta[1], theta[1])
        step = float(coef[0])
        return ({"axis": axis, "t_s": float(t0), "t_low_s": float(lo), "t_high_s": float(hi),
                 "step_arcsec": step}, step, math.sqrt(max(float(cov[0, 0]), 0.0)))

    def label(self, theta: Any) -> str:
        return f"{self.name}[{theta[0]}]"

    # -- blind harness ------------------------------------------------------------------------
    def draw_shape(self, rng, obs):
        times = self.change_times(obs)
        lo, hi = np.quantile(times, [0.1, 0.9])
        return {"axis": str(rng.choice(self.AXES)), "t_s": float(rng.uniform(lo, hi)),
                "sign": float(rng.choice([-1.0, 1.0]))}

    def unit_signal(self, obs, shape):
        return shape["sign"] * self.columns(obs, (shape["axis"], shape["t_s"]))[0][:, 0]

    def effect_params(self, shape, amplitude):
        size = float(shape["sign"] * amplitude)
        return {"t_s": float(shape["t_s"]), "az_arcsec": size if shape["axis"] == "az" else 0.0,
                "el_arcsec": size if shape["axis"] == "el" else 0.0}

    def hidden_amplitude(self, params):
        return float(params["az_arcsec"] or params["el_arcsec"])

    def hidden_label(self, params):
        return f"{self.name}[{'az' if params['az_arcsec'] else 'el'}]"

    def effect_from_params(self, params):
        size = params["step_arcsec"]
        return {"t_s": params["t_s"], "az_arcsec": size if params["axis"] == "az" else 0.0,
                "el_arcsec": size if params["axis"] == "el" else 0.0}
