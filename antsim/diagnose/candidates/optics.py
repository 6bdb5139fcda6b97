"""Candidates of the optics and the sources: a source's structure, an exact (large) tilt
and collimation, polarization squint, a beam width error.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np
from scipy import optimize

from antsim.world.effects.optics import (
    BeamWidthError,
    ExactTiltCollimation,
    PolarizationSquint,
    SourceStructure,
    TiltedSky,
)
from controller.units import ARCSEC_PER_RAD, RAD_PER_ARCMIN

from .. import pvalues
from ..data import Observations
from ..linalg import lstsq
from ..problem import term_columns
from .base import (
    Candidate,
    TestResult,
    p_value,
    stacked,
    with_trials,
)

__all__ = ['BeamWidthCandidate', 'ExactTiltCandidate', 'SourceCandidate', 'SquintCandidate']


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

    mounts = ("altaz", "equatorial")

    def __init__(self):
        self.explanation = SourceStructure.explanation

    def thetas(self, obs):
        names, counts = obs.good_sources
        return [str(s) for s, c in zip(names, counts, strict=True) if c >= self.MIN_SCANS]

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and len(self.thetas(obs)) >= 2

    def columns(self, obs, theta=None):
        ind = (obs.source == theta).astype(float)
        return np.column_stack([stacked(ind, None, obs.n), stacked(None, ind, obs.n)]), \
            ("xel_arcsec", "el_arcsec")

    def test(self, problem, perp, z_perp, chi2_now):
        res = super().test(problem, perp, z_perp, chi2_now)
        res.trials = float(len(self.thetas(problem.obs)))
        res.p = with_trials(p_value(problem, res.delta_chi2, res.dof, res.chi2_now, res.mask),
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
                       "(tests/end_to_end/test_diagnose_sim.py, benchmarks/blind.py --tilt)")
    linear_signature = False
    #: the chi^2 decrease of this 3-parameter even (quadratic) family is referred to chi^2_6,
    #: the dimension of the space of quadratic forms its signature spans (conservative)
    REFERENCE_DOF = 6
    STARTS = ((1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 0, -1), (0, 1, -1),
              (1, 1, 0), (1, -1, 0))
    #: above this many scans the starts are tried on a subsample of about this many (every
    #: k-th scan) and only the best is refined on all of them
    SEARCH_SCANS = 10_000

    def __init__(self):
        self.explanation = ExactTiltCollimation.explanation

    @staticmethod
    def linear_terms(theta: Sequence[float]) -> np.ndarray:
        """AN, AW, CA (arcsec) of the small-angle limit (ExactTiltCollimation's docstring):
        TPOINT's, AN the tilt's north component, AW minus its east one."""
        tn, te, c = (float(v) * 60.0 for v in theta)
        return np.array([tn, -te, -c])

    @staticmethod
    def _sky_error(sky, theta: Sequence[float]) -> np.ndarray:
        """Error (2k,) arcsec of an exact tilt (north, east components) and collimation,
        arcmin, at the directions ``sky`` (:class:`~antsim.world.effects.optics.TiltedSky`)."""
        tn, te, c = (float(v) for v in theta)
        d_az, d_el = sky.errors_rad(math.hypot(tn, te) * RAD_PER_ARCMIN, math.atan2(te, tn),
                                    c * RAD_PER_ARCMIN)
        k = d_az.size
        out = np.empty(2 * k)  # [d_az cos E, d_el] arcsec, made in place
        np.multiply(d_az, sky.cos_el, out=out[:k])
        out[:k] *= ARCSEC_PER_RAD
        np.multiply(d_el, ARCSEC_PER_RAD, out=out[k:])
        return out

    def columns(self, obs, theta=None):
        raise NotImplementedError(f"{self.name}: its signature is not linear in its "
                                  "parameters (its own test fits it)")

    def error(self, obs: Observations, theta: Sequence[float]) -> np.ndarray:
        """Error (2n,) arcsec of an exact tilt (north, east components) and collimation,
        arcmin."""
        return self._sky_error(TiltedSky(obs.az_rad, obs.el_rad), theta)

    def _shown(self, problem, rows: np.ndarray | None, lin: np.ndarray):
        """theta -> the error as the recordings show it on the scans ``rows`` (every scan if
        None; both axes, (2k,) arcsec): the model in use carries the linear part (else the
        scans would miss the source), so the recordings show the linear part whole and the
        rest scaled by each source's offset scale. ``lin``: the AN, AW, CA columns of every
        scan (:func:`term_columns`, made once a test)."""
        obs = problem.obs
        f2 = np.concatenate([problem.offset_scale, problem.offset_scale])
        if rows is None:
            sky, lin_cols = TiltedSky(obs.az_rad, obs.el_rad), lin
        else:
            sky = TiltedSky(obs.az_rad[rows], obs.el_rad[rows])
            both = np.concatenate([rows, rows + obs.n])
            lin_cols, f2 = lin[both], f2[both]

        def err(theta):
            out = self._sky_error(sky, theta)  # raw, then lin + f2 (raw - lin) in place
            lin = lin_cols @ self.linear_terms(theta)
            out -= lin
            out *= f2
            out += lin
            return out

        k = sky.cos_el.size
        made = []  # the Jacobian's constant share and scale, made at its first use

        def jac_rows(theta):
            """d err / d theta, one row (2k,) per parameter, arcsec per arcmin: analytic."""
            if not made:
                # d err / d theta = lin' + f2 (raw' - lin'): the linear part's constant share
                made.extend(((1.0 - f2) * (lin_cols * self.linear_terms((1.0, 1.0, 1.0))).T,
                             sky.cos_el * (ARCSEC_PER_RAD * RAD_PER_ARCMIN)))
            lin_rows, scale_az = made
            d_az, d_el = sky.derivatives_rad(*(float(v) * RAD_PER_ARCMIN for v in theta))
            rows = np.empty_like(lin_rows)
            np.multiply(d_az, scale_az, out=rows[:, :k])
            np.multiply(d_el, ARCSEC_PER_RAD * RAD_PER_ARCMIN, out=rows[:, k:])
            rows *= f2
            rows += lin_rows
            return rows

        err.jac_rows = jac_rows
        return err

    def _fit(self, problem, used: np.ndarray, starts,
             lin: np.ndarray) -> tuple[np.ndarray, float, float, Any]:
        """The best of ``starts`` refined by Levenberg-Marquardt on the scans ``used``:
        (theta, chi^2 left, chi^2 now, (err, proj, z_perp, jac) of those scans); ``lin`` as
        :meth:`_shown`'s; ``jac``: the projected error's Jacobian at theta (columns
        ``proj(row)`` of ``err.jac_rows(theta)``), which least_squares evaluates at its
        solution, or None where no start improved on theta = 0."""
        rows = np.flatnonzero(used)
        err = self._shown(problem, rows, lin)
        proj, z_perp = _projection(problem, used, rows)

        def resid(theta):
            return z_perp - proj(err(theta))

        def resid_jac(theta):
            rows = err.jac_rows(theta)
            out = np.empty((rows.shape[1], rows.shape[0]))
            for j, row in enumerate(rows):
                out[:, j] = proj(row)
            return np.negative(out, out=out)

        base = float(z_perp @ z_perp)
        best_x, best_c, best_jac = np.zeros(3), base, None
        for x0 in starts:
            try:
                sol = optimize.least_squares(resid, x0, jac=resid_jac, method="lm",
                                             x_scale=30.0, max_nfev=200)
            except ValueError:
                continue
            cost = float(sol.fun @ sol.fun)
            if cost < best_c:
                # sol.jac is resid_jac(sol.x): the covariance's Jacobian, not made again
                best_c, best_x, best_jac = cost, sol.x, sol.jac
        return best_x, best_c, base, (err, proj, z_perp, best_jac)

    def test(self, problem, perp, z_perp, chi2_now):
        obs = problem.obs
        used = problem.used
        perp, _ = problem.perp_for(used)
        starts = [np.array(start, float) * 40.0 for start in self.STARTS]
        n_used = int(used.sum())
        lin = term_columns(("AN", "AW", "CA"), obs)
        if n_used > self.SEARCH_SCANS:
            # many scans: the starts on every k-th of them, the best refined on all (each
            # start's search is some 40 evaluations of the error, each reading every scan)
            sub = np.zeros_like(used)
            sub[np.flatnonzero(used)[:: -(-n_used // self.SEARCH_SCANS)]] = True
            x, left, now, _ = self._fit(problem, sub, starts, lin)
            if left < now:
                starts = [x]
        best_x, best_c, base, (err, proj, z_perp, jac) = self._fit(problem, used, starts, lin)
        dchi2 = max(base - best_c, 0.0)
        # covariance from the Jacobian at the optimum (least_squares' is resid_jac's: minus)
        _, cov = lstsq(np.column_stack([proj(row) for row in err.jac_rows(best_x)])
                        if jac is None else np.negative(jac, order="C"), z_perp)
        cols = self._shown(problem, None, lin)(best_x)[:, None]
        res = TestResult(self, dchi2, self.REFERENCE_DOF, 1.0, 1.0, tuple(best_x), cols,
                         ("exact",), np.array([1.0]), cov, mask=used.copy(),
                         chi2_now=base)
        res.p = p_value(problem, dchi2, self.REFERENCE_DOF, base)
        # correlation of the nonlinear part (the error minus its best linear AN/AW/CA fit)
        beta, _ = lstsq(lin, cols[:, 0])
        quad = (cols[:, 0] - lin @ beta)[:, None]
        xp = perp(quad)
        full = np.linalg.norm(problem.whiten(quad))
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
        beta, _ = lstsq(lin, signal)
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


def _projection(problem, used: np.ndarray, rows: np.ndarray):
    """(proj, z_perp) over the scans ``used`` (``rows`` their indices): proj maps raw values
    (2k,) on those scans, xel rows then el rows, to the whitened residual with the current
    model projected out (the problem's ``perp`` without the unused rows); z_perp the data's."""
    perp, z_perp = problem.perp_for(used)
    both = np.concatenate([rows, rows + problem.n])
    if problem.white(used):  # whitening is a weight per row: only the used rows
        w = problem.row_weights[both]
        q = problem.basis(used)

        def proj(v):
            if v.ndim == 2:  # column by column: a matrix product with an inner dimension
                # of ~10 was 10-20 times slower than these under load (OpenBLAS threads)
                return np.column_stack([proj(col) for col in v.T])
            wv = w * v
            wv -= q @ (q.T @ wv)
            return wv

        return proj, z_perp

    def proj(v):
        full = np.zeros((2 * problem.n, *v.shape[1:]))
        full[both] = v
        return perp(full[:, None])[:, 0] if v.ndim == 1 else perp(full)

    return proj, z_perp


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

    mounts = ("altaz", "equatorial")

    def __init__(self):
        self.explanation = PolarizationSquint.explanation

    def columns(self, obs, theta=None):
        raise NotImplementedError(f"{self.name}: tested on the XR - XL offsets, not the "
                                  "pointing errors")

    def test(self, problem, perp=None, z_perp=None, chi2_now=None):
        obs, pred = problem.obs, problem.pred
        d = np.column_stack([obs.pol_xel_arcsec, obs.pol_el_arcsec]) - pred.pol_mean
        ok = problem.valid & np.isfinite(d).all(axis=1)
        if ok.sum() < 3:
            return TestResult(self, 0.0, 0, 1.0, 1.0)
        d = d[ok]
        f = problem.offset_scale[ok][:, None]
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

    mounts = ("altaz", "equatorial")

    def __init__(self):
        self.explanation = BeamWidthError.explanation

    def applicable(self, obs, known_noise):
        return super().applicable(obs, known_noise) and "beam_hpbw_arcmin" in obs.meta

    def columns(self, obs, theta=None):
        raise NotImplementedError(f"{self.name}: tested on the measured beam widths, not the "
                                  "pointing errors")

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
