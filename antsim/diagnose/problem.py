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
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from controller.pointing.model import PointingModel
from controller.pointing.terms import basis_columns

from . import pvalues
from .data import Observations
from .factors import ModelFactors, Projection
from .linalg import heldout_lstsq, lstsq, rows_fortran, take_rows_fortran

__all__ = ["OUTLIER_Z", "AddedFit", "LinearFit", "MaskFit", "Prediction", "Problem",
           "folds_for", "folds_words", "heldout_sky_rms", "sky_of", "term_columns"]

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


@dataclass
class AddedFit:
    """:meth:`Problem.fit_added`'s fit and, where the model's kept QR served, the whitened
    added columns ``x``, them projected off the model and the data projected off it (over
    the scans fitted; None otherwise)."""

    fit: LinearFit
    x: np.ndarray | None = None
    x_perp: np.ndarray | None = None
    z_perp: np.ndarray | None = None


@dataclass
class MaskFit:
    """:meth:`Problem.mask_fit`: the scans a model with the added columns keeps and, where
    its last fit was over them and the model's kept QR served, that fit."""

    mask: np.ndarray
    last: AddedFit | None


class Problem:
    """Whitened data and base design; fits models of base + extra columns on the used scans.

    Whitening is generalized least squares: per axis, the residuals of the used scans divided
    by their predicted noise have the correlation :func:`.factors.correlation_matrix` of the
    prediction's model (identity when the noise is white), and ``whiten(v)`` maps raw (2n, k)
    columns to ``L^-1 (v / sigma)`` over the used scans (L the Cholesky factor), so that
    every chi^2 below is a sum of independent unit-variance terms.
    """

    def __init__(self, obs: Observations, pred: Prediction, base_terms: Sequence[str],
                 base_columns: np.ndarray | None = None, offset_scale: np.ndarray | None = None):
        self.obs = obs
        #: how much of a pointing error each scan's measured offset shows (a partly
        #: resolved source shows theta_b^2 / (theta_b^2 + theta_s^2) of it, Clark 1968)
        self.offset_scale = np.ones(obs.n) if offset_scale is None \
            else np.asarray(offset_scale, float)
        #: the factorizations of the current model, made on request and kept
        self.factors = ModelFactors(self)
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

    # ------------------------------------------------------------------ candidates
    @property
    def unscaled(self) -> bool:
        """Whether every scan shows all of a pointing error (offset scale 1): candidate
        columns are then the raw columns."""
        return bool(np.all(self.offset_scale == 1.0))

    def cand(self, columns: np.ndarray) -> np.ndarray:
        """Candidate columns as the recordings show them (scaled by the offset scale)."""
        f2 = np.concatenate([self.offset_scale, self.offset_scale])
        return columns * f2[:, None] if columns.ndim == 2 else columns * f2

    # ------------------------------------------------------------------ whitening
    @property
    def row_weights(self) -> np.ndarray:
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

    def whiten(self, v: np.ndarray, used: np.ndarray | None = None,
               fortran: bool = False) -> np.ndarray:
        """Whiten raw rows ``v`` (2n,) or (2n, k) over the used scans: (2 n_used[, k]);
        ``fortran``: a (2 n_used, k) result in Fortran order where the noise is white (what
        LAPACK factors without a copy)."""
        used = self.used if used is None else used
        factors = self.factors.noise_factors(used)
        if all(f is None for f in factors):  # white: the used rows times their weights
            idx, wu = self.factors.rows_and_weights(used)
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
        w = self.row_weights
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
        return self.factors.rows_and_weights(self.used if used is None else used)[1]

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
        self.factors.clear()  # they were the model's without it
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
        a = self.whiten(columns, used)
        z = self.whiten(self.y, used)
        coef, cov = lstsq(a, z)
        wres = z - a @ coef
        resid = (self.y - columns @ coef) * self.row_weights
        return LinearFit(coef=coef, chi2=float(wres @ wres), resid=resid, cov=cov, wres=wres,
                         n_used=int(used.sum()))

    def fit_current(self, used: np.ndarray | None = None) -> LinearFit:
        """:meth:`fit` of the current model (the last one kept: the same fit is not made
        twice; treat it as read-only)."""
        used = self.used if used is None else used
        return self.factors.current_fit(used, lambda: self._fit(self.current_columns(), used))

    def current_r(self, used: np.ndarray) -> np.ndarray | None:
        """The R factor (m, m) of the whitened current model over the scans ``used`` (its
        cached QR), or None when the model's columns are not independent there."""
        qr = self.factors.qr(used)
        return None if qr is None else qr.r

    def coef_on_current(self, x: np.ndarray, used: np.ndarray) -> np.ndarray | None:
        """Least-squares coefficients of whitened columns ``x`` (2 n_used, k) on the whitened
        current model over ``used``, from its cached QR (R^-1 Q^T x); None when the model's
        columns are dependent there."""
        qr = self.factors.qr(used)
        if qr is None:
            return None
        return scipy.linalg.solve_triangular(qr.r, qr.q.T @ x)

    def current_norms(self, used: np.ndarray) -> np.ndarray:
        """Norms of the whitened current model's columns over ``used`` (from its cached R;
        the model's columns must be independent there)."""
        return np.linalg.norm(self.factors.qr(used).r, axis=0)

    def fit_added(self, extra: np.ndarray, used: np.ndarray | None = None) -> LinearFit:
        """:meth:`fit` of the current model plus raw columns ``extra`` (2n, q) by
        Frisch-Waugh-Lovell: the current model is factored once per set of scans (QR) and only
        ``extra``, projected off it, is solved for; the same least-squares problem (the
        residual is the same projection, to float rounding), without a factorization of the
        whole design per call. ``cov`` is the extra columns' block only."""
        return self._added(extra, self.used if used is None else used).fit

    def _added(self, extra: np.ndarray, used: np.ndarray, valid_only: bool = False
               ) -> AddedFit:
        """:meth:`fit_added` and, when the model's kept QR served, the whitened ``extra``,
        it projected off the model and the projected data. ``valid_only``: ``resid`` only
        where the scans are valid (NaN elsewhere), the used rows' from the fit's own
        residual where the noise is white (what outlier masks need, without a product of
        the whole design over all rows)."""
        qr = self.factors.qr(used)
        if qr is None:
            f = self.fit(np.column_stack([self.current_columns(), extra]), used)
            m = self.current_columns().shape[1]
            f.cov = f.cov[m:, m:]
            return AddedFit(f)
        q, r, qz, zp = qr.q, qr.r, qr.qz, qr.z_perp
        x = self.whiten(extra, used)
        qx = q.T @ x
        xp = x - q @ qx
        coef_x, cov = lstsq(xp, zp)
        coef_a = scipy.linalg.solve_triangular(r, qz - qx @ coef_x)
        wres = zp - xp @ coef_x
        if valid_only and self.white(used):
            # white: the used rows' whitened residual is the standardized residual
            resid = np.full(2 * self.n, np.nan)
            resid[self.factors.rows_and_weights(used)[0]] = wres
            rest = np.flatnonzero(self.rows(self.valid & ~used))
            resid[rest] = (self.y[rest] - self.current_columns()[rest] @ coef_a
                           - extra[rest] @ coef_x) * self.row_weights[rest]
        else:
            resid = (self.y - self.current_columns() @ coef_a - extra @ coef_x) * self.row_weights
        return AddedFit(LinearFit(coef=np.concatenate([coef_a, coef_x]),
                                  chi2=float(wres @ wres), resid=resid, cov=cov, wres=wres,
                                  n_used=int(used.sum())), x, xp, zp)

    def mask_for(self, extra: np.ndarray, iterations: int = 2) -> np.ndarray:
        """The scans a model of the current columns plus raw ``extra`` (2n, q) keeps
        (standardized residual <= OUTLIER_Z on both axes), starting from every valid scan: a
        candidate that explains scans the current model rejects gets them back."""
        return self.mask_fit(extra, iterations).mask

    def mask_fit(self, extra: np.ndarray, iterations: int = 2) -> MaskFit:
        """:meth:`mask_for` and, when its last fit was over the scans it returns (the mask
        settled) and the model's kept QR served, that fit (with the projected columns)."""
        used = self.valid.copy()
        m = self.current_columns().shape[1] + extra.shape[1]
        last = None
        for _ in range(iterations):
            added = self._added(extra, used, valid_only=True)
            last = added if added.x is not None else None
            r = np.abs(added.fit.resid)
            keep = self.valid & (r[: self.n] <= OUTLIER_Z) & (r[self.n:] <= OUTLIER_Z)
            if keep.sum() < max(m, 3) or np.array_equal(keep, used):
                return MaskFit(used, last)
            used = keep
        return MaskFit(used, None)

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
        self.factors.clear()

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
        self.factors.clear()

    # ------------------------------------------------------------------ tests
    def white(self, used: np.ndarray | None = None) -> bool:
        """Whether whitening over the used scans is a weight per row (no correlated noise):
        a whitened column is then the raw column times :attr:`row_weights` on the used rows."""
        return all(f is None for f in
                   self.factors.noise_factors(self.used if used is None else used))

    def basis(self, used: np.ndarray | None = None) -> np.ndarray:
        """An orthonormal basis (2 n_used, rank) of the whitened current model over the used
        scans (what :meth:`projector` projects out)."""
        return self.factors.basis(self.used if used is None else used)

    def projector(self, used: np.ndarray | None = None) -> Callable[[np.ndarray], np.ndarray]:
        """A function raw v (2n, k) -> P_perp whiten(v): whitened over the used scans, with the
        current model projected out."""
        return self.factors.projector(self.used if used is None else used)

    def perp_for(self, used: np.ndarray) -> Projection:
        """The projector of the current model over the scans ``used`` and the projected
        data: (perp, z_perp), kept."""
        return self.factors.projection(used)

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
        ``extra`` when given)."""
        used = self.used if used is None else used
        if columns is None:
            columns = self.current_columns()
            if extra is not None:
                columns = np.column_stack([columns, extra])
        rows = self.rows(used)
        coef, _ = lstsq(columns[rows], self.y_raw[rows])
        return (self.y_raw - columns @ coef).reshape(2, -1)[:, used]

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
                # the current model's: its kept factor over ``used``
                qr = self.factors.qr(used)
                r = None if qr is None else heldout_lstsq(
                    None, qr.z, np.concatenate([lab, lab]), (qr.q, np.abs(np.diag(qr.r))))
                if r is not None:
                    return float(r @ r)
            else:
                # whitened in Fortran order and factored in place: one copy of the design
                # (and none of the blocks stacked)
                r = heldout_lstsq(self._whitened_fortran(blocks, used), self.whiten(self.y, used),
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
            r = self.whiten(self.y - cols @ f.coef, test)
            total += float(r @ r)
        return total

    def _whitened_fortran(self, blocks: tuple[np.ndarray, ...], used: np.ndarray
                          ) -> np.ndarray:
        """:meth:`whiten` of the column blocks side by side (white noise), in Fortran order, each
        block gathered into the one array (the same numbers as whitening them stacked)."""
        if len(blocks) == 1:
            return self.whiten(blocks[0], used, fortran=True)
        idx, wu = self.factors.rows_and_weights(used)
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
