"""Honest error bars for a linear pointing fit: the cluster jackknife and its degrees of freedom.

The fitter's rows are the xel rows of the N observations followed by their el rows; an
observation's two rows always belong to the same cluster. Clusters are single observations,
or the observations within time blocks when the data carry times (see
:func:`controller.pointing.fitting.fit_model`).

Variance: the cluster jackknife (CV3, MacKinnon, Nielsen and Webb 2023)
``V = (G-1)/G sum_g d_g d_g^T`` of the exact leave-one-cluster-out changes
``d_g = -(A^T A - A_g^T A_g)^-1 A_g^T r_g``.

Degrees of freedom. With G ~ 24 one-hour clusters V is itself noisy: a coefficient's error
divided by sqrt(V) then follows a t distribution rather than a normal one, and its spread over
many campaigns is sqrt(nu / (nu - 2)) > 1 even when V is unbiased. nu is the Satterthwaite
value (Bell and McCaffrey 2002; Imbens and Kolesar 2016): V_j is the quadratic form
``e^T W_j W_j^T e`` in the errors e, and for independent errors of per-axis variance Omega
(the working model, from the fit's own xel and el rms)
``nu_j = tr(K_j)^2 / tr(K_j^2)`` with the G x G matrix ``K_j = W_j^T Omega W_j``.
K_j is diagonal plus rank 2k, so both traces are accumulated cluster by cluster in O(G k^2)
per coefficient without forming it (one-observation clusters make G the number of
observations).

Time blocks on several grids. Where the clock puts the block edges is arbitrary, and with
~24 blocks one grid's variance is noisy: over 200 campaigns of ghigo1990 without heating its
effective dof (2 E[V]^2 / Var V) was 9-13. The variance is therefore the mean over
``BLOCK_PHASES`` grids shifted by a quarter block each (overlapping batch means, Meketon and
Schmeiser 1984: the same expectation, a smaller spread): effective dof 12-17 on the same
campaigns. The reported dof is the mean of the grids' Satterthwaite values (15-20 there).
The mean's own Satterthwaite value would be higher still, and the measured effective dof
lie below even the single grid's value (the errors are neither Gaussian nor of one
variance, as the working model assumes), so the t widening keeps the single grid's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["JackknifeResult", "Rejection", "cluster_jackknife", "within_rms"]

#: clusters per batch of the k x k inversions (bounds memory at ~k*k*8 kB per 1000)
_CHUNK = 4096
#: elements of the (blocks, observations) arrays of one batch of rejection replays
_BATCH_ELEMENTS = 2_000_000
#: time-block grids averaged, each shifted by a fraction 1/BLOCK_PHASES of a block
BLOCK_PHASES = 4
#: the time blocks' length (s) by default: residuals correlated over minutes to an hour
#: (thermal drifts) fall in one block (the project's choice: no source report gives one)
BLOCK_S = 3600.0


@dataclass(frozen=True)
class JackknifeResult:
    """Per fitted term (NaN for terms not fitted): the CV3 jackknife standard error
    ``sigma`` (same unit as the coefficients), its Satterthwaite degrees of freedom ``dof``,
    the ``clusters`` used (of the unshifted block grid) and the number of block grids
    (``phases``) whose variances were averaged."""

    sigma: np.ndarray
    dof: np.ndarray
    clusters: int
    phases: int = 1

    @property
    def sigma_t_scaled(self) -> np.ndarray:
        """``sigma * sqrt(dof / (dof - 2))``: the standard deviation of a t variable with
        ``dof`` degrees of freedom in units of sigma, so that (error / this) has unit spread.
        Infinite where dof <= 2 (the t distribution then has no finite variance)."""
        with np.errstate(invalid="ignore", divide="ignore"):  # 0 x inf: NaN, said so
            factor = np.where(self.dof > 2.0, np.sqrt(self.dof / (self.dof - 2.0)), np.inf)
            return np.where(np.isfinite(self.sigma), self.sigma * factor, np.nan)


@dataclass(frozen=True)
class Rejection:
    """The robust fit's last rejection, replayed in every time-block replicate: the
    observations the least-absolute-deviation stage kept (``kept_lad``, (n,) bool), and the
    rejection beyond ``rms_factor`` x each axis' rms (never below ``floor``) before the final
    least squares."""

    kept_lad: np.ndarray
    rms_factor: float
    floor: float
    target: np.ndarray  # (2n,) the fitted quantity (weighted as the design is)


def within_rms(abs_x: np.ndarray, abs_e: np.ndarray, used: np.ndarray, factor: float,
               floor: float) -> np.ndarray:
    """``used`` less the observations whose |residual| on either axis exceeds ``factor`` x
    that axis' rms over ``used`` (a threshold never below ``floor``): the robust fit's last
    rejection. ``used`` and the residuals are (n,) for the fit, or (replicates, n) for the
    jackknife that replays the rejection in every replicate at once (:class:`_Replay`)."""
    if used.ndim == 1:
        limit_x = max(factor * math.sqrt(float(np.mean(abs_x[used] ** 2))), floor)
        limit_e = max(factor * math.sqrt(float(np.mean(abs_e[used] ** 2))), floor)
    else:
        count = used.sum(axis=1, keepdims=True)
        limit_x = np.maximum(factor * np.sqrt(
            np.where(used, abs_x**2, 0.0).sum(axis=1, keepdims=True) / count), floor)
        limit_e = np.maximum(factor * np.sqrt(
            np.where(used, abs_e**2, 0.0).sum(axis=1, keepdims=True) / count), floor)
    return used & (abs_x <= limit_x) & (abs_e <= limit_e)


def cluster_jackknife(a: np.ndarray, r: np.ndarray, used: np.ndarray, kept: list[int],
                      n: int, t_s: np.ndarray | None, block_s: float,
                      rejection: Rejection | None = None,
                      phases: int = BLOCK_PHASES) -> JackknifeResult:
    """Jackknife sigma and dof of the least-squares coefficients of design ``a`` (2n x m,
    xel rows then el rows) with residuals ``r`` (2n,), over the ``used`` observations and the
    fitted (``kept``) columns. Clusters: one per observation when ``t_s`` is None, else the
    observations in each ``block_s`` time block.

    Time blocks: the variance is the mean of the jackknife variances of ``phases`` block
    grids, each shifted by ``block_s / phases`` from the last (the overlapping-batch idea of
    Meketon and Schmeiser 1984): each grid is as honest about correlations shorter than a
    block, and their mean is less noisy than any one. The dof are the mean of the grids'
    Satterthwaite values (see the module docstring for why that is kept).

    ``rejection``: the fit rejected outliers. A fit that keeps only residuals within 3 rms
    varies more than its kept residuals say (the window moves with the data: ~5% in sigma
    for 1990-like data), so with time blocks each grid's variance is scaled by
    :func:`_rejection_factor`, which replays the rejection in every replicate. The dof stay
    those of the linear estimator on the kept observations."""
    m = a.shape[1]
    sigma = np.full(m, np.nan)
    dof = np.full(m, np.nan)
    idx = np.flatnonzero(used)
    if not kept or idx.size <= len(kept):
        return JackknifeResult(sigma, dof, 0)
    if t_s is not None and phases < 1:
        raise ValueError(f"phases must be at least 1, not {phases!r}")
    fitted = a if len(kept) == m else a[:, kept]
    # row-major: the per-observation products below run along rows (the fitter's design is
    # column-major for LAPACK)
    rows_x, rows_e = np.ascontiguousarray(fitted[idx]), np.ascontiguousarray(fitted[n + idx])
    res_x, res_e = r[idx], r[n + idx]
    info = rows_x.T @ rows_x + rows_e.T @ rows_e
    bread = np.linalg.inv(info)  # the kept columns are independent
    # working model of the errors: independent, with each axis' own scatter
    var_x, var_e = float(np.mean(res_x**2)), float(np.mean(res_e**2))
    if var_x + var_e == 0.0:  # noise-free data: nu does not depend on a common scale
        var_x = var_e = 1.0
    a_omega_a = var_x * rows_x.T @ rows_x + var_e * rows_e.T @ rows_e
    if t_s is None:
        g = idx.size
        if g < 2:
            return JackknifeResult(sigma, dof, g)
        cov, nu = _single_observation_pass(rows_x, rows_e, res_x, res_e, info, bread,
                                           a_omega_a, var_x, var_e)
        phases = 1
    else:
        covs, nus, g = [], [], 0
        obs_outer = (rows_x[:, :, None] * rows_x[:, None, :]
                     + rows_e[:, :, None] * rows_e[:, None, :])
        replay = _Replay(fitted, n, rejection) if rejection is not None else None
        for p in range(phases):
            shift_s = p * block_s / phases
            _, cluster = np.unique(np.floor((t_s[idx] - shift_s) / block_s),
                                   return_inverse=True)
            g_p = int(cluster.max()) + 1
            if g_p < 2:
                continue
            cov_p, nu_p = _block_pass(rows_x, rows_e, res_x, res_e, info, bread, a_omega_a,
                                      var_x, var_e, cluster, g_p, obs_outer)
            if replay is not None:
                cov_p = cov_p * _rejection_factor(replay, t_s - shift_s, block_s,
                                                  np.diag(cov_p))
            covs.append(cov_p)
            nus.append(nu_p)
            g = g or g_p  # the unshifted grid's count is the one reported
        if not covs:
            return JackknifeResult(sigma, dof, g_p)
        cov, nu = np.mean(covs, axis=0), np.mean(nus, axis=0)
        phases = len(covs)
    sigma[kept] = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    dof[kept] = nu
    return JackknifeResult(sigma, dof, g, phases)


def _single_observation_pass(rows_x, rows_e, res_x, res_e, info, bread, a_omega_a,
                             var_x: float, var_e: float) -> tuple[np.ndarray, np.ndarray]:
    """CV3 covariance (with its (G-1)/G) and Satterthwaite dof for one-observation
    clusters: the Woodbury fast path, else the general one with each observation alone."""
    g = rows_x.shape[0]
    singles = _single_observation_rows(rows_x, rows_e, bread)
    if singles is None:
        return _block_pass(rows_x, rows_e, res_x, res_e, info, bread, a_omega_a, var_x,
                           var_e, np.arange(g), g)
    k = rows_x.shape[1]
    cov = np.zeros((k, k))
    dofs = _DofSums(bread, a_omega_a)
    bx, be = singles  # a_x^T M_g^-1 and a_e^T M_g^-1 for each observation's M_g
    for lo in range(0, g, _CHUNK):
        s = slice(lo, min(g, lo + _CHUNK))
        delta = -(bx[s] * res_x[s, None] + be[s] * res_e[s, None])
        cov += delta.T @ delta
        dofs.add_single_observations(rows_x[s], rows_e[s], bx[s], be[s], var_x, var_e)
    return cov * (g - 1) / g, dofs.dof()


def _block_pass(rows_x, rows_e, res_x, res_e, info, bread, a_omega_a, var_x: float,
                var_e: float, cluster: np.ndarray, g: int,
                obs_outer: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """CV3 covariance (with its (G-1)/G) and Satterthwaite dof for the ``g`` clusters
    ``cluster`` (per observation, 0..g-1); ``obs_outer``: each observation's A_o^T A_o
    when the caller has them."""
    k = rows_x.shape[1]
    cov = np.zeros((k, k))
    dofs = _DofSums(bread, a_omega_a)
    # per-cluster score A_g^T r_g and information A_g^T A_g
    score = rows_x * res_x[:, None] + rows_e * res_e[:, None]
    score_g = _group_sum(score, cluster, g)
    for lo in range(0, g, _CHUNK):
        hi = min(g, lo + _CHUNK)
        mine = (cluster >= lo) & (cluster < hi)
        c = cluster[mine] - lo
        own = (obs_outer[mine] if obs_outer is not None
               else rows_x[mine, :, None] * rows_x[mine, None, :]
               + rows_e[mine, :, None] * rows_e[mine, None, :])
        info_g = _group_sum(own, c, hi - lo)
        inverse = _invert_stack(info[None] - info_g)  # M_g^-1, M_g = A^T A - A_g^T A_g
        delta = -np.einsum("gij,gj->gi", inverse, score_g[lo:hi])
        cov += delta.T @ delta
        bx = np.einsum("oi,oij->oj", rows_x[mine], inverse[c])
        be = np.einsum("oi,oij->oj", rows_e[mine], inverse[c])
        p, q, d = _cluster_sums(rows_x[mine], rows_e[mine], bx, be, var_x, var_e)
        dofs.add(*(_sum_by(x, c, hi - lo) for x in (p, q, d)))
    return cov * (g - 1) / g, dofs.dof()


def _rejection_factor(replay: _Replay, t_s: np.ndarray, block_s: float,
                      linear_var: np.ndarray) -> float:
    """How much the rejection widens the jackknife variance, one factor for all terms: the
    mean over terms of (jackknife variance with the rejection replayed in each replicate,
    :meth:`_Replay.variance`) / ``linear_var`` (the linear jackknife's, same blocks).

    Why pooled: the replayed variances alone are right on average but jumpy (a point
    crossing the threshold moves a replicate by a step), so their spread across campaigns
    is that of a t variable with a few degrees of freedom and 3 sigma covers less than it
    should. One ratio over all terms keeps each term's linear jackknife (smooth, its dof
    computed) and corrects the common scale. Over seeds 201..400 of ghigo1990 without heating
    the pulls' spread went from 1.03-1.14 to 0.93-1.04 and the fraction within 3 sigma from
    98-100% to 99.5-100% (seeds 1..200, on which the form was chosen: docs/results.md)."""
    replayed = replay.variance(t_s, block_s)
    ok = np.isfinite(replayed) & np.isfinite(linear_var) & (linear_var > 0)
    return float(np.mean(replayed[ok] / linear_var[ok])) if ok.any() else 1.0


class _Replay:
    """The robust fit's last stage, repeated without each time block: least squares on the
    observations the LAD stage kept, rejection beyond ``rms_factor`` x each axis' rms, least
    squares. Normal equations, downdated by the observations each step removes; the
    per-observation products are shared by every block grid."""

    def __init__(self, fitted: np.ndarray, n: int, rejection: Rejection) -> None:
        self.ax, self.ae = fitted[:n], fitted[n:]
        y = rejection.target
        self.yx, self.ye = y[:n], y[n:]
        self.rejection = rejection
        ax, ae = self.ax, self.ae
        self.outer = ax[:, :, None] * ax[:, None, :] + ae[:, :, None] * ae[:, None, :]
        self.rhs = ax * self.yx[:, None] + ae * self.ye[:, None]
        lad = rejection.kept_lad
        self.info1, self.score1 = self.outer[lad].sum(axis=0), self.rhs[lad].sum(axis=0)
        self.full = self._last_stage(lad[None, :], self.info1[None], self.score1[None])[0]

    def variance(self, t_s: np.ndarray, block_s: float) -> np.ndarray:
        """CV3 jackknife variance per term ``(G-1)/G sum_g (b_g - b)^2`` over the
        ``block_s`` time blocks of ``t_s`` (G blocks), b the full fit's last stage and b_g
        the same without block g; all blocks of a batch at once."""
        lad = self.rejection.kept_lad
        n = lad.size
        _, block = np.unique(np.floor(t_s / block_s), return_inverse=True)
        blocks = np.unique(block[lad])
        slot = np.searchsorted(blocks, block[lad])
        info = self.info1[None] - _group_sum(self.outer[lad], slot, blocks.size)
        score = self.score1[None] - _group_sum(self.rhs[lad], slot, blocks.size)
        b = np.empty((blocks.size, self.info1.shape[0]))
        batch = max(1, _BATCH_ELEMENTS // max(n, 1))  # bounds the (batch, n) arrays
        for lo in range(0, blocks.size, batch):
            s = slice(lo, lo + batch)
            first = lad[None, :] & (block[None, :] != blocks[s, None])
            b[s] = self._last_stage(first, info[s], score[s])
        var = ((b - self.full) ** 2).sum(axis=0)
        return var * (blocks.size - 1) / max(blocks.size, 1)

    def _last_stage(self, first: np.ndarray, info: np.ndarray,
                    score: np.ndarray) -> np.ndarray:
        """Solutions after the rms rejection, one per row of ``first`` (the observations
        each replicate starts from) with its normal equations ``info``, ``score``."""
        rej = self.rejection
        b0 = _solve_stack(info, score)
        abs_x = np.abs(self.yx[None, :] - b0 @ self.ax.T)
        abs_e = np.abs(self.ye[None, :] - b0 @ self.ae.T)
        kept = within_rms(abs_x, abs_e, first, rej.rms_factor, rej.floor)
        drop_g, drop_o = np.nonzero(first & ~kept)
        rows = b0.shape[0]
        return _solve_stack(info - _group_sum(self.outer[drop_o], drop_g, rows),
                            score - _group_sum(self.rhs[drop_o], drop_g, rows))


def _solve_stack(info: np.ndarray, score: np.ndarray) -> np.ndarray:
    """Solve a stack of normal equations; a singular one (the block left out alone
    constrained a term) by least squares."""
    try:
        return np.linalg.solve(info, score[..., None])[..., 0]
    except np.linalg.LinAlgError:
        return np.array([np.linalg.lstsq(m, v, rcond=None)[0] for m, v in zip(info, score,
                                                                               strict=True)])


def _single_observation_rows(rows_x: np.ndarray, rows_e: np.ndarray,
                             bread: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``a_x^T M^-1`` and ``a_e^T M^-1`` for each observation, M = A^T A without that
    observation's two rows, by the Woodbury identity: O(N k^2) instead of N k x k inversions.
    ``None`` when an observation alone constrains a term (the general path handles that)."""
    bx, be = rows_x @ bread, rows_e @ bread
    hxx = np.einsum("ij,ij->i", rows_x, bx)
    hxe = np.einsum("ij,ij->i", rows_x, be)
    hee = np.einsum("ij,ij->i", rows_e, be)
    det = (1.0 - hxx) * (1.0 - hee) - hxe**2
    if np.any(det < 1e-12):
        return None
    return (((1.0 - hee) * bx.T + hxe * be.T) / det).T, ((hxe * bx.T + (1.0 - hxx) * be.T) / det).T


def _cluster_sums(rows_x, rows_e, bx, be, var_x: float, var_e: float):
    """Per observation o and coefficient j (arrays (k, observations, k terms) and
    (k, observations)): p = A_o^T b, q = A_o^T Omega b and d = b^T Omega b, with b the
    observation's two entries of column j of M_g^-1-weighted design (``bx``, ``be``)."""
    bxt, bet = bx.T[:, :, None], be.T[:, :, None]
    p = bxt * rows_x[None] + bet * rows_e[None]
    q = var_x * bxt * rows_x[None] + var_e * bet * rows_e[None]
    d = var_x * bx.T**2 + var_e * be.T**2
    return p, q, d


def _sum_by(values: np.ndarray, cluster: np.ndarray, g: int) -> np.ndarray:
    """Sum (k, observations, ...) arrays over the observations of each cluster."""
    return _group_sum(values.swapaxes(0, 1), cluster, g).swapaxes(0, 1)


def _group_sum(values: np.ndarray, labels: np.ndarray, g: int) -> np.ndarray:
    """Sums of the rows of ``values`` with each label 0..g-1 (zeros for a label without
    rows): one sort and ``np.add.reduceat``, several times faster than ``np.add.at``."""
    out = np.zeros((g, *values.shape[1:]))
    if labels.size == 0:
        return out
    order = np.argsort(labels, kind="stable")
    present, starts = np.unique(labels[order], return_index=True)
    out[present] = np.add.reduceat(values[order], starts, axis=0)
    return out


class _DofSums:
    """Accumulates tr K_j and tr K_j^2 for every coefficient j over batches of clusters.

    For cluster g let p_g = A^T b_g, q_g = A^T Omega b_g and d_g = b_g^T Omega b_g, where b_g
    is column j of M_g^-1 A_g^T placed in the cluster's rows. With H the hat matrix,
    K_gh = b_g^T (I-H) Omega (I-H) b_h = delta_gh d_g - p_g.x_h - x_g.p_h + p_g^T C p_h,
    x = (A^T A)^-1 q and C = (A^T A)^-1 (A^T Omega A) (A^T A)^-1; that is K = D + U V^T with
    U = [P, X] and V = [P C - X, -P], so tr K^2 = tr D^2 + 2 tr(D U V^T) + tr((V^T U)^2),
    where V^T U needs only the Gram matrices P^T P, P^T X and X^T X.
    """

    def __init__(self, bread: np.ndarray, a_omega_a: np.ndarray) -> None:
        k = bread.shape[0]
        self.bread = bread
        self.c = bread @ a_omega_a @ bread
        self.tr_k = np.zeros(k)
        self.tr_d2 = np.zeros(k)
        self.tr_duv = np.zeros(k)
        self.pp = np.zeros((k, k, k))
        self.px = np.zeros((k, k, k))
        self.xx = np.zeros((k, k, k))

    def add(self, p: np.ndarray, q: np.ndarray, d: np.ndarray) -> None:
        """``p``, ``q``: (k coefficients, clusters, k terms); ``d``: (k, clusters)."""
        pt = p.transpose(0, 2, 1)
        self._add(d, np.einsum("jga,jga->jg", p @ self.c, p),
                  np.einsum("jga,jga->jg", p, q @ self.bread))
        self._add_grams(pt @ p, pt @ q, q.transpose(0, 2, 1) @ q)

    def add_single_observations(self, rows_x, rows_e, bx, be, var_x: float,
                                var_e: float) -> None:
        """The same for clusters of one observation, whose p and q are combinations of its
        two design rows (``bx``, ``be``: the rows' entries of b for every j): per-row
        scalars and three weighted Gram products instead of (k, observations, k) arrays."""
        def quad(m, u, v):
            return ((u @ m) * v).sum(1)[:, None]

        k = rows_x.shape[1]

        def gram(w, u, v):  # sum_o w[o, j] u_o v_o^T for every j
            return (w.T @ (u[:, :, None] * v[:, None, :]).reshape(len(u), k * k)).reshape(k, k, k)

        bxx, bxe, bee = bx**2, bx * be, be**2
        d = (var_x * bxx + var_e * bee).T
        p_c_p = (bxx * quad(self.c, rows_x, rows_x) + 2.0 * bxe * quad(self.c, rows_x, rows_e)
                 + bee * quad(self.c, rows_e, rows_e)).T
        p_x = (var_x * bxx * quad(self.bread, rows_x, rows_x)
               + (var_x + var_e) * bxe * quad(self.bread, rows_x, rows_e)
               + var_e * bee * quad(self.bread, rows_e, rows_e)).T
        self._add(d, p_c_p, p_x)
        g_xx, g_xe, g_ee = gram(bxx, rows_x, rows_x), gram(bxe, rows_x, rows_e), \
            gram(bee, rows_e, rows_e)
        g_ex = g_xe.transpose(0, 2, 1)
        self._add_grams(g_xx + g_xe + g_ex + g_ee,
                        var_x * g_xx + var_e * g_xe + var_x * g_ex + var_e * g_ee,
                        var_x**2 * g_xx + var_x * var_e * (g_xe + g_ex) + var_e**2 * g_ee)

    def _add(self, d, p_c_p, p_x) -> None:
        """Per (coefficient, cluster): d, p^T C p and p.x."""
        self.tr_k += d.sum(1) - 2.0 * p_x.sum(1) + p_c_p.sum(1)
        self.tr_d2 += (d**2).sum(1)
        self.tr_duv += (d * (p_c_p - 2.0 * p_x)).sum(1)

    def _add_grams(self, pp, pq, qq) -> None:
        """Per coefficient: P^T P, P^T Q and Q^T Q."""
        self.pp += pp
        self.px += pq @ self.bread
        self.xx += self.bread @ qq @ self.bread

    def dof(self) -> np.ndarray:
        c = self.c[None]
        xp = self.px.transpose(0, 2, 1)
        top = np.concatenate([c @ self.pp - xp, c @ self.px - self.xx], axis=2)
        bottom = np.concatenate([-self.pp, -self.px], axis=2)
        vu = np.concatenate([top, bottom], axis=1)
        tr_k2 = self.tr_d2 + 2.0 * self.tr_duv + np.einsum("jab,jba->j", vu, vu)
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.tr_k**2 / tr_k2


def _invert_stack(matrices: np.ndarray) -> np.ndarray:
    """Invert a stack of small matrices; a cluster without which the fit is singular (it
    alone constrains a term) gets the pseudo-inverse (its term then has no finite error)."""
    try:
        return np.linalg.inv(matrices)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(matrices)
