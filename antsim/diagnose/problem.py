"""The whitened least-squares problem every test in diagnosis is posed on.

Data: the total pointing errors (indicated minus true, arcsec) of the used scans, stacked as
``[xel; el]`` (2n rows), minus the systematic residual the baseline predicts, divided by the
noise it predicts per scan and axis. Regressors are stacked and whitened the same way. With
the right noise model the residual of a correct model is white with unit variance, so adding
q columns that describe nothing changes chi^2 by a chi^2_q variable: every test below is a
chi^2 (known noise, from simulation) or F (noise estimated from the data) test on that.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from controller.pointing.model import PointingModel
from controller.pointing.terms import basis_columns

from . import pvalues
from .data import Observations
from .linalg import (
    economic_qr,
    gram_solve,
    heldout_lstsq,
    lstsq,
    near_rows,
    qt_dot,
    rows_fortran,
    shape_products,
    take_rows_fortran,
)

__all__ = ["Prediction", "Problem", "ShapeFit", "term_columns"]

#: a scan whose whitened residual on either axis exceeds this is an outlier (gusts)
OUTLIER_Z = 4.0


@dataclass(frozen=True)
class Prediction:
    """What the baseline predicts per observation: systematic residual and noise (arcsec).

    ``kind`` is ``"simulated"`` (from simulations of the scenario: mean residual and scatter
    per scan) or ``"white"`` (no simulation: zero systematic, one noise level per axis
    estimated from the data, so tests become F tests). ``pol_*`` and ``width_*`` predict the
    XR - XL offset difference and the measured beam width (arcmin) in the same way.
    """

    kind: str
    sys_xel: np.ndarray
    sys_el: np.ndarray
    sig_xel: np.ndarray
    sig_el: np.ndarray
    pol_mean: np.ndarray | None = None  # (n, 2)
    pol_sig: np.ndarray | None = None  # (n, 2)
    width_mean: np.ndarray | None = None  # (n, 2)
    width_sig: np.ndarray | None = None  # (n, 2)
    matched: np.ndarray | None = None
    n_sims: int = 0
    description: str = ""
    #: noise correlation in time per axis: ((weight, tau_s), ...) (empty: none)
    corr_xel: tuple[tuple[float, float], ...] = ()
    corr_el: tuple[tuple[float, float], ...] = ()

    @property
    def known_noise(self) -> bool:
        return self.kind == "simulated"


def term_columns(terms: Sequence[str], obs: Observations) -> np.ndarray:
    """Error-convention columns (2n, m) of TPOINT/W terms: the error (indicated - true,
    arcsec) each term makes per arcsec of coefficient, xel rows then el rows (on an
    equatorial mount's recordings: its equatorial terms, cross-declination and declination
    rows; thermal terms per unit of the observations' structure temperature differences)."""
    if not terms:
        return np.zeros((2 * obs.n, 0))
    n = obs.n
    out = np.empty((2 * n, len(terms)))  # -[dA cos E; dE], filled a column at a time
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        model = PointingModel(obs.terms(terms))  # the terms by name, each once
        for j, (col_az, col_el) in enumerate(basis_columns(
                model.terms, obs.az_rad, obs.el_rad, aux=obs.structure, cos_el=obs.cos_el)):
            np.multiply(col_az, obs.cos_el, out=out[:n, j])
            out[n:, j] = col_el
    return np.negative(out, out=out)


@dataclass
class LinearFit:
    coef: np.ndarray
    chi2: float
    resid: np.ndarray  # standardized residual (r / sigma) over all 2n rows, unused included
    cov: np.ndarray  # covariance of coef in units of the whitened noise (sigma^2 = 1)
    wres: np.ndarray | None = None  # decorrelated residual over the used rows [xel; el]
    n_used: int = 0


def correlation_matrix(t_s: np.ndarray, model: tuple[tuple[float, float], ...]) -> np.ndarray:
    """Correlation of the noise between scans at times ``t_s`` (s): 1 on the diagonal and
    sum_m w_m exp(-|dt| / tau_m) off it (``model`` = ((w_m, tau_m), ...), sum w_m < 1)."""
    n = t_s.size
    r = np.zeros((n, n))
    if model:
        dt = np.abs(t_s[:, None] - t_s[None, :])
        for wgt, tau in model:
            r += wgt * np.exp(-dt / tau)
    r[np.diag_indices(n)] = 1.0
    return r


#: sets of scans whose row indices and weights whitening keeps (each 2 n_used indices and
#: weights: 6 MB at 200,000 scans)
VIEW_CACHE = 4

#: the bound on the memory cached projectors hold (their bases; see Problem.perp_for): one
#: factor of the model over its used scans and its projectors at 200,000 scans (49 MiB),
#: what the shape tests read (Problem.shape_fit corrects it by rows for other scan sets)
PERP_CACHE_BYTES = 64 * 2**20


#: :meth:`Problem.shape_fit` corrects the model's fit over its used scans by at most this
#: many rows (another set of scans); beyond, the explicit path factors the model over it
ROW_UPDATE_MAX = 4096

#: the least 1 - R^2 of a column on the model at which :meth:`Problem.shape_fit` takes its
#: norm off the model from x^T x - (q^T x)^T (q^T x): the difference loses log10(1 / (1 -
#: R^2)) of the 16 digits, here at most 5 (11 kept: relative error about 2.2e-16 / (1 -
#: R^2) <= 2.2e-11, far below the 6 significant digits diagnose prints); closer columns
#: take the explicit projection
GRAM_1MR2_MIN = 1e-5

#: a candidate whose every (raw) column has a 1 - R^2 on the model below this is absorbed
#: whole (four decades below the candidates' ABSORBED_1MR2, beyond the Gram's rounding): it
#: tests nothing (0 parameters, as the explicit path finds), so no figure depends on its
#: fit, and :meth:`Problem.shape_fit` gives it the mask of the model alone (the explicit
#: path's fits the columns' parts off the model, at most 1e-5 of them: the same scans but
#: where a residual lies within about 1e-3 of OUTLIER_Z)
ABSORBED_WHOLE_1MR2 = 1e-10


class Problem:
    """Whitened data and base design; fits models of base + extra columns on the used scans.

    Whitening is generalized least squares: per axis, the residuals of the used scans divided
    by their predicted noise have the correlation :func:`correlation_matrix` of the
    prediction's model (identity when the noise is white), and ``T(v)`` maps raw (2n, k)
    columns to ``L^-1 (v / sigma)`` over the used scans (L the Cholesky factor), so that
    every chi^2 below is a sum of independent unit-variance terms.
    """

    def __init__(self, obs: Observations, pred: Prediction, base_terms: Sequence[str],
                 base_columns: np.ndarray | None = None, offset_scale: np.ndarray | None = None):
        self.obs = obs
        #: how much of a pointing error each scan's measured offset shows (a partly
        #: resolved source shows theta_b^2 / (theta_b^2 + theta_s^2) of it, Clark 1968)
        self.f = np.ones(obs.n) if offset_scale is None else np.asarray(offset_scale, float)
        self._perps: dict[bytes, tuple] = {}
        self._perp_bytes: dict[bytes, int] = {}
        self._chol: dict[bytes, tuple] = {}
        self._views: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
        self._w: tuple[bytes, np.ndarray] | None = None
        self._stacked: tuple[int, np.ndarray] | None = None
        self.pred = pred
        self.base_terms = tuple(base_terms)
        n = obs.n
        self.n = n
        self.y = np.concatenate([obs.xel_arcsec - pred.sys_xel, obs.el_arcsec - pred.sys_el])
        self.y_raw = np.concatenate([obs.xel_arcsec, obs.el_arcsec])
        self.base = term_columns(self.base_terms, obs) if base_columns is None else base_columns
        finite = np.isfinite(self.base).all(axis=1)
        ok = obs.good & finite[:n] & finite[n:] & np.isfinite(self.y[:n]) \
            & np.isfinite(self.y[n:])
        self.valid = ok
        self.sigma = np.concatenate([pred.sig_xel, pred.sig_el]).astype(float)
        self.scale = np.ones(2)  # per-axis noise scale (estimated when the noise is unknown)
        self.used = ok.copy()
        self.extra: list[np.ndarray] = []  # accepted columns (raw, error convention)
        self.extra_names: list[str] = []
        # the last fit of the current model and the last raw residuals of it or of it plus
        # given columns, by what they depend on: outlier updates, goodness of fit, Sky RMS
        # and the summary ask for the same fits again (each a QR of 2 n_used rows)
        self._fit_memo: tuple | None = None
        self._raw_memo: list[tuple] = []
        self._cv_memo: tuple | None = None  # the current model's last held-out chi^2

    # ------------------------------------------------------------------ candidates
    @property
    def unscaled(self) -> bool:
        """Whether every scan shows all of a pointing error (offset scale 1): candidate
        columns are then the raw columns."""
        return bool(np.all(self.f == 1.0))

    def cand(self, columns: np.ndarray) -> np.ndarray:
        """Candidate columns as the recordings show them (scaled by the offset scale)."""
        f2 = np.concatenate([self.f, self.f])
        return columns * f2[:, None] if columns.ndim == 2 else columns * f2

    # ------------------------------------------------------------------ whitening
    @property
    def w(self) -> np.ndarray:
        """1 / (predicted noise) per row (2n), arcsec^-1 (read-only; formed once per noise
        scale, not per call: whitening asks for it thousands of times)."""
        key = self.scale.tobytes()
        if self._w is None or self._w[0] != key:
            s = self.sigma * np.repeat(self.scale, self.n)
            with np.errstate(divide="ignore"):
                w = np.where(s > 0, 1.0 / s, 0.0)
            w.flags.writeable = False
            self._w = (key, w)
        return self._w[1]

    def rows(self, used: np.ndarray | None = None) -> np.ndarray:
        used = self.used if used is None else used
        return np.concatenate([used, used])

    def _factors(self, used: np.ndarray):
        key = used.tobytes()
        hit = self._chol.get(key)
        if hit is None:
            out = []
            models = (self.pred.corr_xel, self.pred.corr_el)
            t = self.obs.t_s[used]
            for model in models:
                if model:
                    c = scipy.linalg.cholesky(correlation_matrix(t, model), lower=True)
                    # the inverse factor once per set of scans: whitening is then one
                    # matrix product (many small triangular solves cost more in overhead)
                    out.append(scipy.linalg.solve_triangular(c, np.eye(c.shape[0]),
                                                             lower=True))
                else:
                    out.append(None)
            hit = tuple(out)
            if len(self._chol) > 256:
                self._chol.clear()
            self._chol[key] = hit
        return hit

    def T(self, v: np.ndarray, used: np.ndarray | None = None,
          fortran: bool = False) -> np.ndarray:
        """Whiten raw rows ``v`` (2n,) or (2n, k) over the used scans: (2 n_used[, k]);
        ``fortran``: a (2 n_used, k) result in Fortran order where the noise is white (what
        LAPACK factors without a copy)."""
        used = self.used if used is None else used
        factors = self._factors(used)
        if all(f is None for f in factors):  # white: the used rows times their weights
            idx, wu = self._view(used)
            if idx.size == v.shape[0]:  # every row: the product alone, no gather
                return np.multiply(v, wu if v.ndim == 1 else wu[:, None],
                                   order="F" if fortran else "C")
            if fortran and v.ndim == 2:
                return take_rows_fortran(v, idx, wu)
            out = v.take(idx, axis=0)
            out *= wu if v.ndim == 1 else wu[:, None]
            return out
        flat = v.ndim == 1
        vv = v[:, None] if flat else v
        w = self.w
        n = self.n
        parts = []
        for axis, factor in enumerate(factors):
            sl = slice(axis * n, (axis + 1) * n)
            x = vv[sl][used] * w[sl][used][:, None]
            if factor is not None:
                x = factor @ x
            parts.append(x)
        out = np.vstack(parts)
        return out[:, 0] if flat else out

    def weights(self, used: np.ndarray | None = None) -> np.ndarray:
        """The weights (1 / predicted noise) of the rows [xel; el] of the scans ``used``
        (default: the model's): white noise's whitening is the rows times these (kept,
        read-only)."""
        return self._view(self.used if used is None else used)[1]

    def _view(self, used: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(indices, weights) of the rows [xel; el] of the scans ``used``, kept for the last
        few sets of scans (one boolean selection and stacking per set, not per call)."""
        key = used.tobytes() + self.scale.tobytes()
        hit = self._views.get(key)
        if hit is None:
            idx = np.flatnonzero(self.rows(used))
            hit = (idx, self.w[idx])
            if len(self._views) >= VIEW_CACHE:
                self._views.pop(next(iter(self._views)))
            self._views[key] = hit
        return hit

    def current_columns(self) -> np.ndarray:
        """The current model's raw columns (2n, m): the base, then the accepted ones (stacked
        once per model, not per call: 200,000 scans and 13 columns are 42 MB)."""
        if not self.extra:
            return self.base
        if self._stacked is None or self._stacked[0] != len(self.extra):
            whole = np.column_stack([self.base, *self.extra])
            # the base and the accepted columns as views of the whole: the model's columns
            # held once, not twice
            k = self.base.shape[1]
            self.base = whole[:, :k]
            for i, part in enumerate(self.extra):
                self.extra[i] = whole[:, k:k + part.shape[1]]
                k += part.shape[1]
            self._stacked = (len(self.extra), whole)
        return self._stacked[1]

    def add(self, name: str, extra: np.ndarray, comp_names: Sequence[str]) -> np.ndarray:
        """Add a finding's raw columns ``extra`` (2n, q) to the model, named
        ``name:component``; returns the model's columns before it (kept: the finding's
        fitted signal is taken off them)."""
        before = self.current_columns()
        # the factors and projectors cached are of the model without it: never asked again
        self._perps.clear()
        self._perp_bytes.clear()
        self.extra.append(extra)
        self.extra_names.extend(f"{name}:{n}" for n in comp_names)
        return before

    @property
    def current_names(self) -> list[str]:
        return [*self.base_terms, *self.extra_names]

    # ------------------------------------------------------------------ fitting
    def fit(self, columns: np.ndarray, used: np.ndarray | None = None) -> LinearFit:
        """Generalized least squares of the data on ``columns`` over the used scans (the
        current model's columns themselves over the model's scans: :meth:`fit_current`,
        the same fit, kept; treat it as read-only)."""
        if used is None and columns is self.current_columns():
            return self.fit_current()
        return self._fit(columns, self.used if used is None else used)

    def _fit(self, columns: np.ndarray, used: np.ndarray) -> LinearFit:
        """:meth:`fit`, made."""
        a = self.T(columns, used)
        z = self.T(self.y, used)
        coef, cov = lstsq(a, z)
        wres = z - a @ coef
        resid = (self.y - columns @ coef) * self.w
        return LinearFit(coef=coef, chi2=float(wres @ wres), resid=resid, cov=cov, wres=wres,
                         n_used=int(used.sum()))

    def fit_current(self, used: np.ndarray | None = None) -> LinearFit:
        """:meth:`fit` of the current model (the last one kept: the same fit is not made
        twice; treat it as read-only)."""
        used = self.used if used is None else used
        key = (used.tobytes(), self.scale.tobytes(), len(self.extra))
        if self._fit_memo is None or self._fit_memo[0] != key:
            self._fit_memo = (key, self._fit(self.current_columns(), used))
        return self._fit_memo[1]

    def _current_qr(self, used: np.ndarray):
        """(q, r, q^T z, z, z projected off q) of the whitened current model over the scans
        ``used`` (z the whitened data), cached with the projectors; None when its columns
        are not independent there (the callers then fit the whole design)."""
        key = b"qr" + used.tobytes() + bytes([len(self.extra)])
        hit = self._cached(key)
        if hit is None:
            q, r = economic_qr(self.T(self.current_columns(), used, fortran=True), overwrite=True)
            d = np.abs(np.diag(r))
            full = bool(d.size) and d.min() > 1e-10 * max(float(d.max()), 1e-300)
            if full:
                z = self.T(self.y, used)
                qz = q.T @ z
                hit = (q, r, qz, z, z - q @ qz)
            else:
                hit = ()
            self._cache(key, hit, 8 * (q.size + 2 * q.shape[0]) if full else 0)
        return hit or None

    def current_r(self, used: np.ndarray) -> np.ndarray | None:
        """The R factor (m, m) of the whitened current model over the scans ``used`` (its
        cached QR), or None when the model's columns are not independent there."""
        qr = self._current_qr(used)
        return None if qr is None else qr[1]

    def coef_on_current(self, x: np.ndarray, used: np.ndarray) -> np.ndarray | None:
        """Least-squares coefficients of whitened columns ``x`` (2 n_used, k) on the whitened
        current model over ``used``, from its cached QR (R^-1 Q^T x); None when the model's
        columns are dependent there."""
        qr = self._current_qr(used)
        if qr is None:
            return None
        return scipy.linalg.solve_triangular(qr[1], qr[0].T @ x)

    def current_norms(self, used: np.ndarray) -> np.ndarray:
        """Norms of the whitened current model's columns over ``used`` (from its cached R;
        the model's columns must be independent there)."""
        return np.linalg.norm(self._current_qr(used)[1], axis=0)

    def fit_added(self, extra: np.ndarray, used: np.ndarray | None = None) -> LinearFit:
        """:meth:`fit` of the current model plus raw columns ``extra`` (2n, q) by
        Frisch-Waugh-Lovell: the current model is factored once per set of scans (QR) and only
        ``extra``, projected off it, is solved for; the same least-squares problem (the
        residual is the same projection, to float rounding), without a factorization of the
        whole design per call. ``cov`` is the extra columns' block only."""
        return self._added(extra, self.used if used is None else used)[0]

    def _added(self, extra: np.ndarray, used: np.ndarray, valid_only: bool = False
               ) -> tuple[LinearFit, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
        """:meth:`fit_added` and, when the model's cached QR served, the whitened ``extra``,
        it projected off the model and the projected data (x, x_perp, z_perp).
        ``valid_only``: ``resid`` only where the scans are valid (NaN elsewhere), the used
        rows' from the fit's own residual where the noise is white (what outlier masks
        need, without a product of the whole design over all rows)."""
        qr = self._current_qr(used)
        if qr is None:
            f = self.fit(np.column_stack([self.current_columns(), extra]), used)
            m = self.current_columns().shape[1]
            f.cov = f.cov[m:, m:]
            return f, None
        q, r, qz, _, zp = qr
        x = self.T(extra, used)
        qx = q.T @ x
        xp = x - q @ qx
        coef_x, cov = lstsq(xp, zp)
        coef_a = scipy.linalg.solve_triangular(r, qz - qx @ coef_x)
        wres = zp - xp @ coef_x
        if valid_only and self.white(used):
            # white: the used rows' whitened residual is the standardized residual
            resid = np.full(2 * self.n, np.nan)
            resid[self._view(used)[0]] = wres
            rest = np.flatnonzero(self.rows(self.valid & ~used))
            resid[rest] = (self.y[rest] - self.current_columns()[rest] @ coef_a
                           - extra[rest] @ coef_x) * self.w[rest]
        else:
            resid = (self.y - self.current_columns() @ coef_a - extra @ coef_x) * self.w
        return (LinearFit(coef=np.concatenate([coef_a, coef_x]), chi2=float(wres @ wres),
                          resid=resid, cov=cov, wres=wres, n_used=int(used.sum())),
                (x, xp, zp))

    def shape_fit(self, raw: np.ndarray) -> ShapeFit | None:
        """:meth:`mask_fit` of the candidate's columns (raw ``raw`` (2n, k), scaled by
        :meth:`cand`) and the fit over the mask it returns, from
        one pass over the model's cached basis over its used scans U (``q^T x``), not two
        factors and projections: the same masks and numbers to rounding, or None where the
        explicit path must serve (correlated noise, dependent model columns, an
        ill-conditioned candidate Gram, more than :data:`ROW_UPDATE_MAX` rows between U and
        a scan set tried; the caller refuses columns within :data:`GRAM_1MR2_MIN` of the
        span). The mask's fits leave out the columns within :data:`ABSORBED_WHOLE_1MR2` of
        the model's span (the explicit path fits their rounding-level remainder).

        Algebra (white noise: whitening is a weight per row). With the model in its basis
        q = A_U R^-1 and x the whitened columns over U, every row i of the valid scans has
        model coordinates g_i (q_i on U, a_i R^-1 elsewhere), the data's residual e_i of the
        model's fit over U (z_perp on U) and the columns' part p_i = x_i - g_i^T q^T x left by
        that fit. Over U, sum g g^T = I, sum g p^T = 0, sum g e = 0, sum p e = x^T z_perp and
        sum p p^T = x^T x - (q^T x)^T (q^T x) (Frisch-Waugh-Lovell from inner products); over
        any other set of scans S these sums change by the rows S adds and removes, so the fit
        of model + columns over S is a small (m + k) system. Its residuals on U are
        z_perp_i - x_i c - q_i d (d the change of the model's coordinates): |q_i d| <= |q_i|
        |d|, so only rows whose z_perp_i - x_i c lies within that of OUTLIER_Z can fall on
        the other side; those rows are computed exactly, and the mask is the same set.
        Where the offset scale is not 1 the raw columns' norms and norms off the model come
        beside (the signature's, for absorption): x is then [scaled, raw]."""
        used = self.used
        qr = self._current_qr(used) if self.white(used) else None
        if qr is None:
            return None
        q, _, _, _, zp = qr
        rn_max, idx_o, g_o, e_o, zz, uscan, oscan = self._shape_base(used, qr)
        k = raw.shape[1]
        scaled = not self.unscaled
        idx, wu = self._view(used)
        f2u = np.concatenate([self.f[uscan]] * 2) if scaled else None
        # whitened over U in Fortran order, the rows gathered once: the scaled columns
        # (raw times the offset scale, as cand() makes them) then the raw ones; the one
        # pass over the model's basis and x's inner products made as it is (shape_products)
        x, qx, xx, xz = shape_products(raw, idx, wu, f2u, q, zp)
        x_o = raw[idx_o]
        if scaled:
            x_o = np.column_stack([x_o * self.f[idx_o % self.n][:, None], x_o])
        x_o = x_o * self.w[idx_o][:, None]
        gram = xx - qx.T @ qx
        d = np.diag(xx)
        if not np.isfinite(xx).all() or not (d > 0).all():
            return None
        ratio = np.diag(gram) / d  # 1 - R^2 of each column on the model
        if ratio[x.shape[1] - k:].max() < ABSORBED_WHOLE_1MR2:
            fitted = np.arange(0)  # a signature the model absorbs whole: the model alone
        else:
            # the columns the model leaves a part of: one off it by rounding only (a
            # signature partly absorbed, e.g. by an accepted term) is not fitted, as a
            # signature absorbed whole is not (its direction would be rounding)
            fitted = np.flatnonzero(ratio[:k] >= ABSORBED_WHOLE_1MR2)
        # the fitted columns of x and q^T x (a view where they are the first ones)
        cols = fitted if 0 < fitted.size < k else slice(0, fitted.size)
        p_o = x_o - g_o @ qx
        m = self.current_columns().shape[1] + k
        nu, no = uscan.size, oscan.size

        def fit(scans: np.ndarray):
            rm = np.searchsorted(uscan, np.flatnonzero(used & ~scans))
            ad = np.flatnonzero(scans[oscan])
            if 2 * (rm.size + ad.size) > ROW_UPDATE_MAX:
                return None
            out = _rows_fit(q, x, qx, zp, gram, xz, xx, zz, g_o, p_o, x_o, e_o,
                            np.concatenate([rm, rm + nu]), np.concatenate([ad, ad + no]),
                            fitted)
            if out is None:
                return None
            schur, rhs, chi2_now, fullsq, coef, cov, b, model, on_model = out
            # the standardized residuals of model + columns on the used scans' rows are
            # z_perp - x c - q d; |q_i d| <= max_i |q_i| |d| = bound, so only rows whose
            # |z_perp - x c| exceeds OUTLIER_Z - bound can exceed OUTLIER_Z (a margin of
            # 1e-9 of both for rounding): those are computed exactly
            dv = b - qx[:, cols] @ coef
            bound = rn_max * float(np.linalg.norm(dv)) * (1 + 1e-9) + 1e-9
            near, u_near = near_rows(x, cols, coef, zp, OUTLIER_Z - bound)
            out_u = near[np.abs(u_near - q[near] @ dv) > OUTLIER_Z]
            out_o = np.flatnonzero(~(np.abs(e_o - g_o @ b - p_o[:, cols] @ coef)
                                     <= OUTLIER_Z))
            keep = self.valid.copy()
            keep[uscan[out_u % nu]] = False
            keep[oscan[out_o % no]] = False
            return keep, ShapeFit(scans, schur, rhs, chi2_now, fullsq, coef, cov, x, qx,
                                  model, on_model)

        # mask_fit's iterations: from every valid scan, twice
        scans = self.valid
        for _ in range(2):
            out = fit(scans)
            if out is None:
                return None
            keep, res = out
            if keep.sum() < max(m, 3) or np.array_equal(keep, scans):
                return res
            # the model's own scans as one array, not a copy per result (most candidates
            # keep them: a mask of n bytes each, held by every result of the round)
            scans = used if np.array_equal(keep, used) else keep
        out = fit(scans)
        return None if out is None else out[1]

    def _shape_base(self, used: np.ndarray, qr: tuple):
        """What :meth:`shape_fit` keeps per model and used scans: the largest row norm of
        the model's basis q, the rows of the valid scans outside ``used`` (indices into 2n, the
        model's coordinates there and the data's residual of the model's fit over
        ``used``), ||z_perp||^2, and the scans of both sets."""
        key = b"sb" + used.tobytes() + bytes([len(self.extra)])
        hit = self._cached(key)
        if hit is None:
            q, r, qz, _, zp = qr
            rn_max = float(np.sqrt(np.einsum("ij,ij->i", q, q).max())) if q.size else 0.0
            other = self.valid & ~used
            idx_o = np.flatnonzero(self.rows(other))
            a_o = self.current_columns()[idx_o] * self.w[idx_o][:, None]
            g_o = scipy.linalg.solve_triangular(r, a_o.T, trans="T").T
            e_o = self.y[idx_o] * self.w[idx_o] - g_o @ qz
            hit = (rn_max, idx_o, g_o, e_o, float(zp @ zp), np.flatnonzero(used),
                   np.flatnonzero(other))
            self._cache(key, hit, 8 * zp.size)
        return hit

    def _cache(self, key: bytes, value, size: int) -> None:
        """Keep ``value`` among the cached projectors and factors: at most 64 of them and
        PERP_CACHE_BYTES together (each holds a basis, 2 n_used x k floats: 200,000 scans
        and 20 terms are 64 MB), the least recently used let go first, but never those over
        the model's used scans (its factor, projector and :meth:`shape_fit`'s rows), which
        every shape test reads (a model larger than the bound would be factored again per
        shape)."""
        used = self.used.tobytes() + bytes([len(self.extra)])
        pinned = {used, b"qr" + used, b"sb" + used}
        while len(self._perps) > 64 or sum(self._perp_bytes.values()) + size \
                > PERP_CACHE_BYTES:
            old = next((k for k in self._perps if k not in pinned), None)
            if old is None:
                break
            # a projector over the same scans holds the factor's basis (counted once, with
            # the factor): it goes with it
            for k in (old, old[2:]) if old.startswith(b"qr") else (old,):
                self._perps.pop(k, None)
                self._perp_bytes.pop(k, None)
        self._perps[key] = value
        self._perp_bytes[key] = size

    def _cached(self, key: bytes):
        """The cached projector or factor ``key`` (None if not held), now the most recently
        used."""
        hit = self._perps.pop(key, None)
        if hit is not None:
            self._perps[key] = hit
            self._perp_bytes[key] = self._perp_bytes.pop(key)
        return hit

    def mask_for(self, extra: np.ndarray, iterations: int = 2) -> np.ndarray:
        """The scans a model of the current columns plus raw ``extra`` (2n, q) keeps
        (standardized residual <= OUTLIER_Z on both axes), starting from every valid scan: a
        candidate that explains scans the current model rejects gets them back."""
        return self.mask_fit(extra, iterations)[0]

    def mask_fit(self, extra: np.ndarray, iterations: int = 2):
        """:meth:`mask_for` and, when its last fit was over the scans it returns (the mask
        settled) and the model's cached QR served, that fit: (LinearFit, (x, x_perp,
        z_perp)) as :meth:`_added` gives them, else None."""
        used = self.valid.copy()
        m = self.current_columns().shape[1] + extra.shape[1]
        last = None
        for _ in range(iterations):
            f, parts = self._added(extra, used, valid_only=True)
            last = (f, parts) if parts is not None else None
            r = np.abs(f.resid)
            keep = self.valid & (r[: self.n] <= OUTLIER_Z) & (r[self.n:] <= OUTLIER_Z)
            if keep.sum() < max(m, 3) or np.array_equal(keep, used):
                return used, last
            used = keep
        return used, None

    def update_outliers(self, iterations: int = 2) -> None:
        """Reject scans whose standardized residual exceeds OUTLIER_Z on either axis (and,
        with unknown noise, re-estimate each axis' noise scale from the kept scans)."""
        for _ in range(iterations):
            f = self.fit_current()
            if not self.pred.known_noise:
                self._rescale(f)
                f = self.fit_current()
            r = np.abs(f.resid)
            keep = self.valid & (r[: self.n] <= OUTLIER_Z) & (r[self.n:] <= OUTLIER_Z)
            if keep.sum() < max(self.current_columns().shape[1], 3):
                break
            if np.array_equal(keep, self.used):
                break
            self.used = keep
        if not self.pred.known_noise:
            self._rescale(self.fit_current())
        self._perps.clear()
        self._perp_bytes.clear()

    def _rescale(self, f: LinearFit) -> None:
        """Per-axis noise scale from the residual rms, corrected for the fitted columns."""
        n_used = f.n_used
        m = self.current_columns().shape[1]
        dof = max(2 * n_used - m, 1)
        factor = 2 * n_used / dof
        for axis in range(2):
            part = f.wres[axis * n_used:(axis + 1) * n_used]
            ms = float(np.mean(part**2)) * factor if part.size else 1.0
            if ms > 0:
                self.scale[axis] *= math.sqrt(ms)
        self._perps.clear()
        self._perp_bytes.clear()

    # ------------------------------------------------------------------ tests
    def white(self, used: np.ndarray | None = None) -> bool:
        """Whether whitening over the used scans is a weight per row (no correlated noise):
        a whitened column is then the raw column times :attr:`w` on the used rows."""
        return all(f is None for f in self._factors(self.used if used is None else used))

    def basis(self, used: np.ndarray | None = None) -> np.ndarray:
        """An orthonormal basis (2 n_used, rank) of the whitened current model over the used
        scans (what :meth:`projector` projects out)."""
        used = self.used if used is None else used
        qr = self._current_qr(used)
        if qr is not None:  # independent columns: the cached factor's basis, all of it
            return qr[0]
        a = self.T(self.current_columns(), used)
        q, r = economic_qr(a)
        d = np.abs(np.diag(r))
        return q[:, d > 1e-10 * max(float(d.max()) if d.size else 0.0, 1e-300)]

    def projector(self, used: np.ndarray | None = None):
        """A function raw v (2n, k) -> P_perp T(v): whitened over the used scans, with the
        current model projected out."""
        used = self.used if used is None else used
        q = self.basis(used)

        def perp(v: np.ndarray) -> np.ndarray:
            vr = self.T(v, used)  # a new array: the model's part taken off in place
            vr -= q @ qt_dot(q, vr)
            return vr

        return perp

    def perp_for(self, used: np.ndarray):
        """Cached projector of the current model over the scans ``used`` and the projected
        data: (perp, z_perp)."""
        key = used.tobytes() + bytes([len(self.extra)])
        hit = self._cached(key)
        if hit is None:
            perp = self.projector(used)
            qr = self._current_qr(used)
            hit = (perp, qr[4] if qr is not None else perp(self.y[:, None])[:, 0])
            # the basis is shared with the cached factors when the model's columns are
            # independent there (already counted)
            m = 1 if qr is not None else self.current_columns().shape[1] + 1
            self._cache(key, hit, 8 * hit[1].size * m)
        return hit

    def gof(self) -> dict[str, dict[str, float]]:
        """Per-axis goodness of fit of the current model against the predicted noise:
        rms of the decorrelated residual (1 when the noise is as predicted), chi^2, dof, p."""
        f = self.fit_current()
        n_used = f.n_used
        m = self.current_columns().shape[1]
        out = {}
        for axis, name in ((0, "xel"), (1, "el")):
            part = f.wres[axis * n_used:(axis + 1) * n_used]
            dof = max(n_used - m / 2.0, 1.0)
            chi2 = float(part @ part)
            p = float(pvalues.chi2_sf(chi2, dof)) if self.pred.known_noise else float("nan")
            out[name] = {"ratio": math.sqrt(chi2 / dof), "chi2": chi2, "dof": dof, "p": p,
                         "n": n_used}
        return out

    def matches_noise(self, level: float = 0.05) -> bool:
        """Whether both axes' residuals are consistent with the predicted noise."""
        if not self.pred.known_noise:
            return False
        return all(v["p"] > level for v in self.gof().values())

    def sky_rms(self, columns: np.ndarray | None = None, used: np.ndarray | None = None) -> float:
        """TPOINT Sky RMS (arcsec) of the raw total errors after an unweighted fit of
        ``columns`` (default: the current model) over the used scans."""
        return sky_of(self.raw_residuals(columns, used))

    def sky_rms_added(self, extra: np.ndarray) -> float:
        """:meth:`sky_rms` of the current model plus raw columns ``extra`` (2n, q)."""
        return sky_of(self.raw_residuals(extra=extra))

    def raw_residuals(self, columns: np.ndarray | None = None,
                      used: np.ndarray | None = None, extra: np.ndarray | None = None
                      ) -> np.ndarray:
        """(2, n_used) raw residuals (arcsec; cross-axis, then along the second axis) of the
        used scans after an unweighted fit of ``columns`` (default: the current model, plus
        ``extra`` when given). Those of the current model (plus ``extra``) are kept for the
        next call: treat them as read-only."""
        used = self.used if used is None else used
        key = None
        if columns is None or columns is self.current_columns():
            # the same fit when the scans, the model and the added columns are the same (a
            # finding's columns compared by value: a result may make them again when read)
            key = (used.tobytes(), len(self.extra), extra)
            for old, r in self._raw_memo:
                if old[:2] == key[:2] and (old[2] is extra or (
                        extra is not None and old[2] is not None
                        and np.array_equal(old[2], extra))):
                    return r
            columns = self.current_columns()
            if extra is not None:
                columns = np.column_stack([columns, extra])
        rows = self.rows(used)
        coef, _ = lstsq(columns[rows], self.y_raw[rows])
        r = (self.y_raw - columns @ coef).reshape(2, -1)[:, used]
        if key is not None:  # the last two: the Sky RMS before and after a finding
            self._raw_memo = [*self._raw_memo[-1:], (key, r)]
        return r

    def cv_chi2(self, columns: np.ndarray | tuple[np.ndarray, ...], folds: np.ndarray,
                refit=None, used: np.ndarray | None = None) -> float:
        """Held-out chi^2: each fold predicted from a fit to the others (whitened units).
        ``columns``: raw (2n, k), or its column blocks (stacked only where the noise is not
        white or ``refit`` is given). ``refit(train_mask) -> columns`` re-derives nonlinear
        shapes on the training data."""
        used = self.used if used is None else used
        blocks = columns if isinstance(columns, tuple) else (columns,)
        if refit is None and self.white(used):
            lab = folds[used]
            if blocks[0] is self.current_columns() and len(blocks) == 1:
                # the current model's: its cached factor over ``used`` (what the finding's
                # simplest form projects with next), and the figure kept (a simpler
                # equivalent is checked over the same scans)
                key = (used.tobytes(), self.scale.tobytes(), len(self.extra), folds)
                memo = self._cv_memo
                if memo is not None and memo[0][:3] == key[:3] and memo[0][3] is folds:
                    return memo[1]
                qr = self._current_qr(used)
                r = None if qr is None else heldout_lstsq(
                    None, qr[3], np.concatenate([lab, lab]), (qr[0], np.abs(np.diag(qr[1]))))
                if r is not None:
                    self._cv_memo = (key, float(r @ r))
                    return self._cv_memo[1]
            else:
                # whitened in Fortran order and factored in place: one copy of the design
                # (and none of the blocks stacked)
                r = heldout_lstsq(self._whitened_fortran(blocks, used), self.T(self.y, used),
                                  np.concatenate([lab, lab]), overwrite=True)
                if r is not None:
                    return float(r @ r)
        columns = np.column_stack(blocks) if len(blocks) > 1 else blocks[0]
        total = 0.0
        for k in np.unique(folds[used]):
            test = used & (folds == k)
            train = used & (folds != k)
            cols = columns if refit is None else refit(train)
            f = self.fit(cols, train)
            r = self.T(self.y - cols @ f.coef, test)
            total += float(r @ r)
        return total

    def _whitened_fortran(self, blocks: tuple[np.ndarray, ...], used: np.ndarray
                          ) -> np.ndarray:
        """:meth:`T` of the column blocks side by side (white noise), in Fortran order, each
        block gathered into the one array (the same numbers as whitening them stacked)."""
        if len(blocks) == 1:
            return self.T(blocks[0], used, fortran=True)
        idx, wu = self._view(used)
        out = np.empty((idx.size, sum(b.shape[1] for b in blocks)), order="F")
        j = 0
        for b in blocks:
            take_rows_fortran(b, idx, wu, out[:, j:j + b.shape[1]])
            j += b.shape[1]
        return out

    def cv_sky_rms(self, columns: np.ndarray, folds: np.ndarray) -> float:
        """Held-out Sky RMS (arcsec): raw residuals of each fold predicted from an
        unweighted fit to the others."""
        return heldout_sky_rms(self.heldout_residuals(columns, folds))

    def heldout_residuals(self, columns: np.ndarray, folds: np.ndarray) -> np.ndarray:
        """(2, n_used) raw residuals (arcsec) of each fold's used scans predicted from an
        unweighted fit to the other folds."""
        lab = folds[self.used]
        rows = self.rows(self.used)
        r = heldout_lstsq(rows_fortran(columns, rows), self.y_raw[rows],
                          np.concatenate([lab, lab]), overwrite=True)
        if r is not None:  # in the order of the loop below: fold by fold, each in time
            return r.reshape(2, -1)[:, np.argsort(lab, kind="stable")]
        parts = []
        for k in np.unique(folds[self.used]):
            test = self.used & (folds == k)
            train = self.used & (folds != k)
            rows = self.rows(train)
            coef, _ = lstsq(columns[rows], self.y_raw[rows])
            parts.append((self.y_raw - columns @ coef).reshape(2, -1)[:, test])
        return np.concatenate(parts, axis=1) if parts else np.zeros((2, 0))


def sky_of(r: np.ndarray) -> float:
    """Sky RMS (arcsec) of (2, n) in-sample raw residuals (:meth:`Problem.raw_residuals`)."""
    return math.sqrt(float(np.mean(r[0] ** 2 + r[1] ** 2)))


def heldout_sky_rms(r: np.ndarray) -> float:
    """Sky RMS (arcsec) of (2, n) held-out residuals (:meth:`Problem.heldout_residuals`)."""
    return math.sqrt(float(np.sum(r**2)) / max(r.shape[1], 1))


@dataclass
class ShapeFit:
    """:meth:`Problem.shape_fit`: the scans a model with the candidate keeps and, over them,
    the candidate's columns (then ``raw``'s) projected off the model as inner products."""

    mask: np.ndarray
    gram: np.ndarray  # (kk, kk) X_perp^T X_perp over ``mask``
    rhs: np.ndarray  # (kk,) X_perp^T z_perp over ``mask``
    chi2_now: float  # z_perp^T z_perp over ``mask`` (the model alone)
    full_sq: np.ndarray  # (kk,) squared norms of the whitened columns over ``mask``
    #: the candidate's coefficients over ``mask``, of the columns the model leaves a part of
    #: (ABSORBED_WHOLE_1MR2; none: the model absorbs its signature whole)
    coef: np.ndarray
    cov: np.ndarray  # (k, k) their covariance (whitened units)
    x: np.ndarray  # (2 n_used, kk) the whitened columns over the model's used scans
    qx: np.ndarray  # (m, kk) q^T x there (q the model's basis)
    #: (m, m) the whitened model's Gram over ``mask`` in q's coordinates (R^-T A^T A R^-1,
    #: R the model's factor over its used scans; the identity over them)
    model_gram: np.ndarray
    #: (m, kk) the columns' least-squares coefficients on the model over ``mask``, in q's
    #: coordinates (R times the model's coefficients; q^T x over the used scans)
    on_model: np.ndarray


def _rows_fit(q, x, qx, zp, gram, xz, xx, zz, g_o, p_o, x_o, e_o, rm, ad, fitted):
    """:meth:`Problem.shape_fit`'s fit over the used scans less the rows ``rm`` (positions
    on them) plus the rows ``ad`` (positions among the other valid rows): the sums over the
    used scans corrected by those rows, the model's block eliminated. None where the rows
    removed carry half of some direction of the model, or :func:`gram_solve` refuses the
    columns ``fitted``. Returns (Schur complement, its right-hand side, chi^2 of the model
    alone, squared column norms, the ``fitted`` columns' coefficients and covariance, the
    model's change of coordinates, the model's Gram and the columns' least-squares
    coefficients on the model, both in its coordinates over U)."""
    m, kk = q.shape[1], x.shape[1]
    full_sq = np.diag(xx).copy()
    if rm.size or ad.size:
        q_rm = q[rm]
        g = np.vstack([q_rm, g_o[ad]])
        p = np.vstack([x[rm] - q_rm @ qx, p_o[ad]])
        e = np.concatenate([zp[rm], e_o[ad]])
        s = np.concatenate([-np.ones(rm.size), np.ones(ad.size)])
        gs = g.T * s
        w, v = np.linalg.eigh(np.eye(m) + gs @ g)
        if w[0] < 0.5:
            return None
        ps = p.T * s
        cgp = gs @ p
        model = (v * w) @ v.T
        sg = (v / w) @ (v.T @ np.column_stack([cgp, gs @ e]))
        schur = gram + ps @ p - cgp.T @ sg[:, :kk]
        rhs = xz + ps @ e - cgp.T @ sg[:, kk]
        chi2_now = zz + float((e * s) @ e) - float((gs @ e) @ sg[:, kk])
        full_sq += np.vstack([x[rm], x_o[ad]]).T ** 2 @ s
    else:
        sg = np.zeros((m, kk + 1))
        schur, rhs, chi2_now, model = gram, xz, zz, np.eye(m)
    solved = gram_solve(schur[np.ix_(fitted, fitted)], rhs[fitted])
    if solved is None:
        return None
    coef, cov = solved
    return (schur, rhs, chi2_now, full_sq, coef, cov, sg[:, kk] - sg[:, fitted] @ coef, model,
            qx + sg[:, :kk])


def folds_for(obs: Observations, k: int = 5) -> np.ndarray:
    """Held-out folds: whole nights when the data span more than a day and a half, else k
    folds interleaved in time order (deterministic)."""
    nights = _night_folds(obs)
    if nights is not None:
        return nights
    n = obs.n
    order = np.argsort(obs.t_s, kind="stable")
    folds = np.empty(n, dtype=int)
    folds[order] = np.arange(n) % k
    return folds


def folds_words(obs: Observations, k: int = 5) -> str:
    """What :func:`folds_for` holds out, in words."""
    if _night_folds(obs) is not None:
        return "nights held out in turn"
    return f"{k}-fold cross-validation interleaved in time"


def _night_folds(obs: Observations) -> np.ndarray | None:
    """One fold per local day (noon to noon) when the data span more than a day and a
    half, else None."""
    if obs.has_time and np.ptp(obs.t_s) > 1.5 * 86400.0:
        lon = float(obs.meta.get("longitude_deg", 0.0))
        local_day = np.floor((obs.t_s / 3600.0 + lon / 15.0 - 12.0) / 24.0)
        _, folds = np.unique(local_day, return_inverse=True)
        if folds.max() >= 1:
            return folds
    return None
