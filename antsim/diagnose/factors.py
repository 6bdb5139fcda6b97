"""The model's factorizations, made once and kept: all that diagnose holds in memory for speed.

Every statistic of diagnosis (:mod:`.problem`, :mod:`.select`, :mod:`.crossval`, the
candidates) is posed on the whitened current model over some set of scans, and the same
factorizations are asked for again and again within a round of the selection (each a QR of
2 n_used rows: the costly step at 200,000 scans). :class:`ModelFactors` makes them for one
:class:`~.problem.Problem` and keeps them:

* whitening per set of scans: with correlated noise the inverse Cholesky factor of each
  axis' correlation (:meth:`ModelFactors.noise_factors`), with white noise the rows'
  indices and weights (:meth:`ModelFactors.rows_and_weights`);
* the QR of the whitened current model over a set of scans (:class:`ModelQR`), the
  projector that takes the model out of whitened columns (:class:`Projection`), and what
  the shape test (:mod:`.shapefit`) needs of the valid scans outside the model's
  (:class:`OtherRows`);
* the current model's last fit.

The memory policy, all of it: the factors and projectors are held in one cache bounded by
:data:`FACTOR_CACHE_BYTES` and :data:`FACTOR_CACHE_ENTRIES`, the least recently used let go
first but never those over the model's own used scans (every shape test reads them); the
whole cache is dropped when the model, its used scans or the noise scale change (the
problem says so: :meth:`ModelFactors.clear`). The Sun's elevations on a time grid (an
ephemeris over the campaign: the thermal candidates and the location ask for the same grid
many times) are kept by content in :data:`SUN_GRIDS`. A candidate's test result does not hold
its columns but makes them again when they are read (:func:`remade_when_read`). Nothing else
in diagnose caches between calls.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol

import numpy as np
import scipy.linalg

from .data import Observations
from .linalg import economic_qr, qt_dot

__all__ = ["FACTOR_CACHE_BYTES", "FACTOR_CACHE_ENTRIES", "SUN_GRIDS", "BoundedCache",
           "ModelFactors", "ModelQR", "OtherRows", "Projection", "correlation_matrix",
           "kept_sun_grid", "remade_when_read"]

#: the bound on the memory the cached factors and projectors hold (their bases): one factor
#: of the model over its used scans and its projector at 200,000 scans (49 MiB), what the
#: shape tests read
FACTOR_CACHE_BYTES = 64 * 2**20
#: and on their number (a factor over a few scans is small, but each is a QR to keep)
FACTOR_CACHE_ENTRIES = 64
#: sets of scans whose correlated-noise factors are kept (each n_used^2 floats per axis:
#: correlated noise is a scenario's prediction, a few thousand scans at most)
NOISE_FACTOR_SETS = 256
#: sets of scans whose row indices and weights are kept (each 2 n_used indices and weights:
#: 6 MB at 200,000 scans)
ROW_VIEW_SETS = 4
#: the bound on the Sun grids kept (8 bytes a minute: a year is 4 MiB)
SUN_GRID_BYTES = 64 * 2**20


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


class BoundedCache:
    """Values by key, at most ``max_entries`` of them and ``max_bytes`` together (each
    value's size given when it is kept), the least recently used let go first; keys for
    which ``pinned(key)`` holds are never let go (they may exceed the bound)."""

    def __init__(self, max_bytes: int, max_entries: int,
                 pinned: Callable[[Hashable], bool] = lambda key: False):
        self.max_bytes, self.max_entries, self.pinned = max_bytes, max_entries, pinned
        self._values: OrderedDict[Hashable, tuple[Any, int]] = OrderedDict()

    def get(self, key: Hashable) -> Any:
        """The value kept for ``key`` (None if none), now the most recently used."""
        hit = self._values.get(key)
        if hit is None:
            return None
        self._values.move_to_end(key)
        return hit[0]

    def put(self, key: Hashable, value: Any, size: int,
            goes_with: Callable[[Hashable], list[Hashable]] = lambda key: []) -> None:
        """Keep ``value`` (``size`` bytes) for ``key``, letting the least recently used
        others go to make room (and, with each, the keys ``goes_with`` names)."""
        while len(self._values) > self.max_entries or self.nbytes + size > self.max_bytes:
            old = next((k for k in self._values if not self.pinned(k)), None)
            if old is None:
                break
            for k in (old, *goes_with(old)):
                self._values.pop(k, None)
        self._values[key] = (value, size)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._values

    def keys(self) -> list[Hashable]:
        """The keys kept, least recently used first."""
        return list(self._values)

    @property
    def nbytes(self) -> int:
        """The bytes kept."""
        return sum(size for _, size in self._values.values())

    def clear(self) -> None:
        self._values.clear()


#: the Sun's elevations (deg) on a campaign's time grid, by site, epoch and grid
SUN_GRIDS = BoundedCache(SUN_GRID_BYTES, 64)


class ModelQR(NamedTuple):
    """The QR of the whitened current model over a set of scans and the whitened data there
    (2 n_used rows)."""

    q: np.ndarray  # (2 n_used, m) orthonormal basis
    r: np.ndarray  # (m, m) upper triangular
    qz: np.ndarray  # (m,) q^T z
    z: np.ndarray  # (2 n_used,) the whitened data
    z_perp: np.ndarray  # (2 n_used,) z with the model projected out


class Projection(NamedTuple):
    """The current model taken out over a set of scans: ``perp(v)`` maps raw columns (2n, k)
    to whitened ones with the model projected out; ``z_perp`` is the data's."""

    perp: Callable[[np.ndarray], np.ndarray]
    z_perp: np.ndarray


@dataclass(frozen=True)
class OtherRows:
    """What :func:`.shapefit.shape_fit` needs of the valid scans outside the model's used
    ones U, with the model fitted over U."""

    rn_max: float  # the largest row norm of the model's basis q over U
    idx: np.ndarray  # the other scans' rows (indices into the 2n rows)
    coords: np.ndarray  # (rows, m) the model's coordinates there (a_i R^-1)
    resid: np.ndarray  # the data's whitened residual there of the model's fit over U
    chi2_now: float  # ||z_perp||^2 over U
    used_scans: np.ndarray  # the scans of U (indices)
    other_scans: np.ndarray  # the other valid scans (indices)


class Problem(Protocol):
    """What the factors read of the problem they serve (:class:`.problem.Problem`)."""

    obs: Observations
    pred: Any  # the baseline's prediction (its noise correlation models)
    extra: list[np.ndarray]
    used: np.ndarray
    valid: np.ndarray
    scale: np.ndarray
    y: np.ndarray
    row_weights: np.ndarray

    def whiten(self, v: np.ndarray, used: np.ndarray | None = None,
               fortran: bool = False) -> np.ndarray: ...

    def current_columns(self) -> np.ndarray: ...

    def rows(self, used: np.ndarray | None = None) -> np.ndarray: ...


class ModelFactors:
    """The factorizations of one problem's current model, made on request and kept (see the
    module docstring). The problem calls :meth:`clear` when its model, its used scans or
    its noise scale change."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self.cache = BoundedCache(FACTOR_CACHE_BYTES, FACTOR_CACHE_ENTRIES, self._pinned)
        self._noise: dict[bytes, tuple[np.ndarray | None, np.ndarray | None]] = {}
        self._views: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
        self._fit: tuple[tuple, Any] | None = None

    def clear(self) -> None:
        """Drop the factors and projectors and the kept fit (the model, its scans or the
        noise scale changed)."""
        self.cache.clear()

    def _key(self, kind: str, used: np.ndarray) -> tuple[str, bytes, int]:
        return kind, used.tobytes(), len(self.problem.extra)

    def _pinned(self, key: Hashable) -> bool:
        """Whether ``key`` is over the model's used scans (never let go)."""
        return key[1:] == self._key("", self.problem.used)[1:]

    @staticmethod
    def _goes_with(key: Hashable) -> list[Hashable]:
        """A factor's projector over the same scans holds its basis (counted once, with the
        factor): it goes with it."""
        return [("projection", *key[1:])] if key[0] == "qr" else []

    def _kept(self, key: tuple, make: Callable[[], tuple[Any, int]]) -> Any:
        hit = self.cache.get(key)
        if hit is None:
            hit, size = make()
            self.cache.put(key, hit, size, self._goes_with)
        return hit

    # ------------------------------------------------------------------ whitening
    def noise_factors(self, used: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Per axis, the inverse Cholesky factor of the noise correlation over the scans
        ``used`` (None where that axis' noise is white)."""
        key = used.tobytes()
        hit = self._noise.get(key)
        if hit is None:
            p = self.problem
            t = p.obs.t_s[used]
            out = []
            for model in (p.pred.corr_xel, p.pred.corr_el):
                if model:
                    c = scipy.linalg.cholesky(correlation_matrix(t, model), lower=True)
                    # the inverse factor once per set of scans: whitening is then one
                    # matrix product (many small triangular solves cost more in overhead)
                    out.append(scipy.linalg.solve_triangular(c, np.eye(c.shape[0]),
                                                             lower=True))
                else:
                    out.append(None)
            hit = (out[0], out[1])
            if len(self._noise) > NOISE_FACTOR_SETS:
                self._noise.clear()
            self._noise[key] = hit
        return hit

    def rows_and_weights(self, used: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(indices, weights) of the rows [xel; el] of the scans ``used`` (one boolean
        selection and stacking per set of scans and noise scale, not per call)."""
        p = self.problem
        key = used.tobytes() + p.scale.tobytes()
        hit = self._views.get(key)
        if hit is None:
            idx = np.flatnonzero(p.rows(used))
            hit = (idx, p.row_weights[idx])
            if len(self._views) >= ROW_VIEW_SETS:
                self._views.pop(next(iter(self._views)))
            self._views[key] = hit
        return hit

    # ------------------------------------------------------------------ the model
    def current_fit(self, used: np.ndarray, make: Callable[[], Any]) -> Any:
        """The current model's fit over ``used``, ``make()`` once per model, scans and
        noise scale (outlier updates, goodness of fit and the summary ask for it again)."""
        p = self.problem
        key = (used.tobytes(), p.scale.tobytes(), len(p.extra))
        if self._fit is None or self._fit[0] != key:
            self._fit = (key, make())
        return self._fit[1]

    def qr(self, used: np.ndarray) -> ModelQR | None:
        """The QR of the whitened current model over the scans ``used`` (None when its
        columns are not independent there: the callers then fit the whole design)."""
        def make():
            p = self.problem
            q, r = economic_qr(p.whiten(p.current_columns(), used, fortran=True), overwrite=True)
            d = np.abs(np.diag(r))
            if not (d.size and d.min() > 1e-10 * max(float(d.max()), 1e-300)):
                return (), 0
            z = p.whiten(p.y, used)
            qz = q.T @ z
            return ModelQR(q, r, qz, z, z - q @ qz), 8 * (q.size + 2 * q.shape[0])

        return self._kept(self._key("qr", used), make) or None

    def basis(self, used: np.ndarray) -> np.ndarray:
        """An orthonormal basis (2 n_used, rank) of the whitened current model over the
        scans ``used``: the kept QR's where the model's columns are independent there."""
        qr = self.qr(used)
        if qr is not None:
            return qr.q
        p = self.problem
        q, r = economic_qr(p.whiten(p.current_columns(), used))
        d = np.abs(np.diag(r))
        return q[:, d > 1e-10 * max(float(d.max()) if d.size else 0.0, 1e-300)]

    def projector(self, used: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        """A function raw v (2n, k) -> the whitened v over the scans ``used`` with the
        current model projected out."""
        p = self.problem
        q = self.basis(used)

        def perp(v: np.ndarray) -> np.ndarray:
            vr = p.whiten(v, used)  # a new array: the model's part taken off in place
            vr -= q @ qt_dot(q, vr)
            return vr

        return perp

    def projection(self, used: np.ndarray) -> Projection:
        """The projector over the scans ``used`` and the data projected (kept)."""
        def make():
            perp = self.projector(used)
            qr = self.qr(used)
            z_perp = qr.z_perp if qr is not None else perp(self.problem.y[:, None])[:, 0]
            # the basis is the kept factor's where the model's columns are independent
            # there (counted with it)
            m = 1 if qr is not None else self.problem.current_columns().shape[1] + 1
            return Projection(perp, z_perp), 8 * z_perp.size * m

        return self._kept(self._key("projection", used), make)

    def other_rows(self, used: np.ndarray, qr: ModelQR) -> OtherRows:
        """:class:`OtherRows` of the model fitted over the scans ``used`` (its QR ``qr``)."""
        def make():
            p = self.problem
            q, r, qz, zp = qr.q, qr.r, qr.qz, qr.z_perp
            rn_max = float(np.sqrt(np.einsum("ij,ij->i", q, q).max())) if q.size else 0.0
            other = p.valid & ~used
            idx = np.flatnonzero(p.rows(other))
            a = p.current_columns()[idx] * p.row_weights[idx][:, None]
            coords = scipy.linalg.solve_triangular(r, a.T, trans="T").T
            resid = p.y[idx] * p.row_weights[idx] - coords @ qz
            return OtherRows(rn_max, idx, coords, resid, float(zp @ zp), np.flatnonzero(used),
                             np.flatnonzero(other)), 8 * zp.size

        return self._kept(self._key("other_rows", used), make)


def remade_when_read(make: Callable[[], np.ndarray], cols: np.ndarray,
                     keep: np.ndarray | None, scale: np.ndarray | None, refusal: str
                     ) -> Callable[[], np.ndarray]:
    """A function that makes columns ``cols`` (2n, q) again with ``make()`` (the ``keep``
    ones), in place of holding them: every candidate's test result has columns (at 200,000
    scans all of a round's were 0.5 GB) and few are read. The columns made again are checked
    against a fingerprint of ``cols`` (a row in 64; ``scale``: their rows scaled by it, as
    ``make`` scales them), RuntimeError(``refusal``) where they differ."""
    rows = slice(None, None, max(1, cols.shape[0] // 64))
    # not ``cols``: the point is to free it
    mark = cols[rows] * scale[rows][:, None] if scale is not None else cols[rows].copy()
    shape = cols.shape

    def remake() -> np.ndarray:
        again = make()
        if again.shape != shape or not np.array_equal(again[rows], mark, equal_nan=True):
            raise RuntimeError(refusal)
        return again if keep is None or keep.all() else again[:, keep]

    return remake


def kept_sun_grid(key: Hashable, make: Callable[[], np.ndarray]) -> np.ndarray:
    """The Sun's elevations ``make()`` on a time grid, kept by ``key`` (:data:`SUN_GRIDS`)."""
    hit = SUN_GRIDS.get(key)
    if hit is None:
        hit = make()
        SUN_GRIDS.put(key, hit, hit.nbytes)
    return hit
