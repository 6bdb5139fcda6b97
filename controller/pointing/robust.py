"""The fit of a pointing model: the Ghigo/Payne robust procedure with TPOINT's statistics.

Signs. The data are total pointing errors, "indicated minus true" (Ghigo's and katpoint's
sign): ``xel = dA cos E`` and ``el = dE`` at the true (observed) position. A model's TPOINT
correction is minus that, so with ``Ba, Be = PointingModel.design_matrix(az, el)`` the
equations are the stacked rows ``-xel = (Ba cos E) @ c`` and ``-el = Be @ c`` (c in arcsec).
A fitted model's :meth:`~controller.pointing.model.PointingModel.offset_rad` reproduces the
data.

Procedure (``robust=True``), the stages of the 1990 report (Ghigo 1990, section III: "first
if they exceed 4 times the mean absolute deviation from a least absolute deviation fit, and
second, if they exceed 3 times the rms deviation to a least squares fit. A final least
squares fit uses only the filtered data"), one function each:

1. :func:`lad_fit`: least-absolute-deviation fit of every observation;
2. :func:`reject_beyond_mad`: reject observations whose xel or el residual exceeds
   ``lad_factor`` (4) times the mean absolute residual of that axis;
3. :func:`least_squares_fit` on the rest;
4. :func:`reject_beyond_rms`: reject beyond ``rms_factor`` (3) times that axis' rms;
5. :func:`least_squares_fit`, the final fit.

``robust=False`` is stage 5 alone on everything (the report's fit F; TPOINT's own fit). The
means and rms are taken over the observations still in use; rejected observations stay
rejected. No threshold goes below 1e-9 of the largest |datum|, so rounding noise in
noise-free data is never "rejected".

Statistics (TPOINT's, verified on the MMT data in ``examples/README.md``), over
the N used observations and the M fitted terms:

* Sky RMS = sqrt(mean(xel_res^2 + el_res^2)); xel and el rms separately;
* sigma_j = sqrt(diag((A^T A)^-1))_j * Sky RMS;
* Popn SD = Sky RMS * sqrt(N / (N - M)).

With ``weighted=True`` the rows are scaled by sqrt(weight) (weights are 1/sigma^2 in
1/arcsec^2), A^T A becomes the weighted normal matrix A^T W A, and sigma is scaled by the
weighted rms sqrt(mean(w_xel xel_res^2 + w_el el_res^2)) instead of the Sky RMS, so that
multiplying every weight by a constant changes nothing and unit weights give the unweighted
result. Sky RMS, the axis rms and Popn SD stay the plain (unweighted) figures in arcsec.
The robust rejection thresholds then apply to the weighted (normalised) residuals.

The linear algebra (QR with rank analysis, LAD by linear programming) is in
:mod:`controller.pointing.solvers`; the honest error bars in
:mod:`controller.pointing.jackknife`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from .data import LinearModel, PointingData, require_pointing_data
from .jackknife import (
    BLOCK_PHASES,
    BLOCK_S,
    JackknifeResult,
    Rejection,
    cluster_jackknife,
    within_rms,
)
from .result import FitResult, readonly
from .solvers import (
    LadBlock,
    Rank,
    Solution,
    independent_columns,
    lad_blocks,
    least_squares,
    matvec,
)

__all__ = ["CORRELATION_WARNING_LEVEL", "Equations", "fit_terms", "fit_terms_before_after",
           "lad_fit", "least_squares_fit", "reject_beyond_mad", "reject_beyond_rms"]

#: the 1990 report's rejection thresholds (Ghigo 1990, section III): an observation goes when
#: an axis' residual exceeds LAD_FACTOR times that axis' mean absolute deviation from the LAD
#: fit, then RMS_FACTOR times the rms of a least-squares fit to the rest
LAD_FACTOR = 4.0
RMS_FACTOR = 3.0

#: |correlation| above which TPOINT warns that two terms "cannot reliably be distinguished".
CORRELATION_WARNING_LEVEL = 0.95


#: the largest term basis (per radian) a fit takes: beyond it a term is at its singularity
#: (cot E at E = 0.2", tan E within 0.2" of the zenith) and its column would swamp the solver
MAX_BASIS = 1e6

@dataclass(frozen=True)
class Equations:
    """The stacked equations of a fit: ``design`` (2N x M, the xel rows then the el rows,
    TPOINT-sign correction per arcsec of coefficient) and ``target`` (minus the errors);
    ``a_w``, ``y_w`` the same rows scaled by sqrt(weight) when weighted (else the same
    arrays); ``floor`` the smallest rejection threshold (1e-9 of the largest |datum|)."""

    names: tuple[str, ...]
    n: int
    design: np.ndarray
    target: np.ndarray
    a_w: np.ndarray
    y_w: np.ndarray
    floor: float

    @classmethod
    def of(cls, data: PointingData, start: LinearModel, weighted: bool) -> Equations:
        names = start.names
        n, m = len(data), len(names)
        cos_el = np.cos(data.el_rad)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # checked below
            basis_az, basis_el = start.design_matrix(data.az_rad, data.el_rad, data.feed_rad,
                                                         data.aux)
        design = np.empty((2 * n, m), order="F")  # column-major, as LAPACK works on it
        np.multiply(basis_az, cos_el[:, None], out=design[:n])
        design[n:] = basis_el
        with np.errstate(invalid="ignore"):
            singular = ~(np.abs(design) <= MAX_BASIS)  # NaN and infinity included
        if singular.any():
            row, col = np.argwhere(singular)[0]
            obs = row % n
            raise ValueError(
                f"term {names[col]} is infinite at observation {obs} (elevation "
                f"{math.degrees(data.el_rad[obs]):.4g} deg); remove the term or the observation"
            )
        return cls._of_design(data, names, design, weighted)

    @classmethod
    def _of_design(cls, data: PointingData, names: Sequence[str], design: np.ndarray,
                   weighted: bool) -> Equations:
        n = len(data)
        target = -np.concatenate([data.xel_arcsec, data.el_arcsec])
        if weighted:
            root_w = np.sqrt(np.concatenate([data.weight_xel, data.weight_el]))
            a_w = np.asfortranarray(design * root_w[:, None])
            y_w = target * root_w
        else:
            a_w, y_w = design, target
        # Rounding noise must not count as an outlier: on noise-free data the residuals are
        # ~1e-13 and a threshold of 4x their mean would reject at random. No threshold goes
        # below 1e-9 of the largest |datum| (1e-9" on errors of an arcsec).
        floor = 1e-9 * float(np.abs(y_w).max())
        return cls(tuple(names), n, design, target, a_w, y_w, floor)

    def select(self, keep: np.ndarray, data: PointingData, weighted: bool = False
               ) -> Equations:
        """The equations of ``data``, the observations ``keep`` (boolean, one per observation
        of these equations) of this one's: the design's rows taken, not evaluated again (the
        same numbers: each row is its observation's alone)."""
        rows = np.concatenate([keep, keep])
        if int(keep.sum()) != len(data):
            raise ValueError(f"{int(keep.sum())} observations kept, the data hold {len(data)}")
        design = np.empty((2 * len(data), len(self.names)), order="F")  # as of() makes it
        for j in range(design.shape[1]):
            np.compress(rows, self.design[:, j], out=design[:, j])
        return self._of_design(data, self.names, design, weighted)

    def for_data(self, data: PointingData, weighted: bool = False) -> Equations:
        """The equations of other data at the same observations (the same design)."""
        if len(data) != self.n:
            raise ValueError(f"{len(data)} observations, the design has {self.n}")
        return self._of_design(data, self.names, self.design, weighted)

    def abs_residuals(self, coeffs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """|weighted residual| of every observation, xel and el, for coefficients ``coeffs``."""
        r = self.y_w - matvec(self.a_w, coeffs)
        return np.abs(r[:self.n]), np.abs(r[self.n:])


# ---------------------------------------------------------------------------------------------
# the stages of the 1990 report
# ---------------------------------------------------------------------------------------------
def lad_fit(eq: Equations, centre: np.ndarray | None = None,
            band_rows: int | None = None) -> np.ndarray:
    """Stage 1: least-absolute-deviation coefficients of every observation (0 for terms the
    data cannot determine). ``centre``: an estimate of them, one per term, where the search
    starts, with ``band_rows`` rows about it in the first LP (:func:`solvers._lad_dense`:
    the same optimum, found sooner from a close centre)."""
    return _lad_stage(eq, centre=centre, band_rows=band_rows).coeffs


@dataclass(frozen=True)
class _LadFit:
    """Stage 1's coefficients, the design's rank analysis and the LAD's blocks (what a fit of
    the same design to other data can take from it)."""

    coeffs: np.ndarray
    rank: Rank
    blocks: list[LadBlock | None]


def _lad_stage(eq: Equations, prior: _LadFit | None = None,
               centre: np.ndarray | None = None, band_rows: int | None = None) -> _LadFit:
    """:func:`lad_fit`; ``prior``: that of the same design (``eq.a_w``) fitted to other data,
    whose rank analysis is this one's and whose blocks of unchanged data are not solved
    again; ``centre``: an estimate of the coefficients, one per term (the LAD of a larger
    set of observations), where the LAD's search starts, ``band_rows`` rows about it in the
    first LP (:func:`solvers._lad_dense`)."""
    rank = prior.rank if prior is not None else independent_columns(eq.a_w, eq.names)
    coeffs = np.zeros(len(eq.names))
    blocks: list[LadBlock | None] = []
    if rank.kept:
        k = list(rank.kept)
        coeffs[k], blocks = lad_blocks(eq.a_w[:, k], eq.y_w, eq.n,
                                        None if prior is None else prior.blocks,
                                        None if centre is None else centre[k], band_rows)
    return _LadFit(coeffs, rank, blocks)


def reject_beyond_mad(eq: Equations, coeffs: np.ndarray, factor: float) -> np.ndarray:
    """Stage 2: the observations whose xel and el residuals both lie within ``factor`` times
    that axis' mean absolute residual (the mean absolute deviation) of the LAD fit."""
    abs_x, abs_e = eq.abs_residuals(coeffs)
    used = np.ones(eq.n, dtype=bool)
    used &= ((abs_x <= max(factor * abs_x.mean(), eq.floor))
             & (abs_e <= max(factor * abs_e.mean(), eq.floor)))
    _check_enough(used, len(eq.names),
                  "rejecting beyond lad_factor x the mean absolute deviation")
    return used


def least_squares_fit(eq: Equations, used: np.ndarray) -> Solution:
    """Stages 3 and 5: least squares on the observations ``used``."""
    rows = np.concatenate([used, used])
    return least_squares(eq.a_w[rows], eq.y_w[rows], eq.names)


def reject_beyond_rms(eq: Equations, coeffs: np.ndarray, used: np.ndarray,
                      factor: float) -> np.ndarray:
    """Stage 4: of the observations ``used``, those whose residuals lie within ``factor``
    times that axis' rms of the least-squares fit ``coeffs``."""
    used = within_rms(*eq.abs_residuals(coeffs), used, factor, eq.floor)
    _check_enough(used, len(eq.names), "rejecting beyond rms_factor x the rms")
    return used


def _check_enough(used: np.ndarray, m: int, stage: str) -> None:
    k = int(used.sum())
    if k < m:
        raise ValueError(
            f"only {k} observations remain after {stage}, fewer than the {m} terms; "
            "the data are too few or too discrepant for this model"
        )


# ---------------------------------------------------------------------------------------------
# the fit
# ---------------------------------------------------------------------------------------------
def fit_terms(data: PointingData, start: LinearModel, *, robust: bool = True,
              weighted: bool = False, lad_factor: float = LAD_FACTOR,
              rms_factor: float = RMS_FACTOR,
              block_s: float = BLOCK_S, block_phases: int = BLOCK_PHASES) -> FitResult:
    """Fit the terms of ``start`` (its coefficients are not used) to ``data``: the stages of
    the module docstring, then the statistics; ``result.model`` is ``start`` with the fitted
    coefficients. The options are those of :func:`controller.pointing.fitting.fit_model`."""
    require_pointing_data(data)
    _check_options(data, start, weighted, lad_factor, rms_factor, block_phases)
    eq = Equations.of(data, start, weighted)
    return _fit_equations(data, start, eq, robust=robust, weighted=weighted,
                          lad_factor=lad_factor, rms_factor=rms_factor, block_s=block_s,
                          block_phases=block_phases)[0]


def fit_terms_before_after(data: PointingData, start: LinearModel, minus_xel_arcsec: np.ndarray,
                           minus_el_arcsec: np.ndarray, windows: Sequence[np.ndarray] = ()
                           ) -> list[tuple[FitResult, FitResult] | ValueError]:
    """The robust, unweighted :func:`fit_terms` of ``data`` and of ``data`` less a signal
    (``minus_*_arcsec``, one per observation), then the same of each of ``windows`` (boolean
    masks of the observations): a list of (before, after) pairs, or the ValueError that
    :func:`fit_terms` raises for one.

    As separate calls give them, but one design (a window's are its rows) and one rank
    analysis for before and after, an axis' LAD block that the signal leaves unchanged
    solved once, and a window's LAD started from the whole's (the exact optimum either way;
    its rounding, ~1e-13 relative, depends on the start)."""
    require_pointing_data(data)
    options = {"robust": True, "weighted": False, "lad_factor": LAD_FACTOR,
               "rms_factor": RMS_FACTOR, "block_s": BLOCK_S, "block_phases": BLOCK_PHASES}
    try:
        whole = Equations.of(data, start, False)
    except ValueError:  # a term infinite at an observation: each window's fit sees its own
        whole = None
    out: list[tuple[FitResult, FitResult] | ValueError] = []
    centres: tuple[np.ndarray | None, ...] = (None, None)
    for keep in (None, *windows):
        part = data if keep is None else data.select(keep)
        minus = (minus_xel_arcsec, minus_el_arcsec) if keep is None else (
            minus_xel_arcsec[keep], minus_el_arcsec[keep])
        after = dataclasses.replace(part, xel_arcsec=part.xel_arcsec - minus[0],
                                    el_arcsec=part.el_arcsec - minus[1])
        try:
            _check_options(part, start, False, LAD_FACTOR, RMS_FACTOR, BLOCK_PHASES)
            eq = Equations.of(part, start, False) if whole is None else (
                whole if keep is None else whole.select(keep, part))
            first, lad = _fit_equations(part, start, eq, centre=centres[0], **options)
            second, lad_after = _fit_equations(after, start, eq.for_data(after), prior=lad,
                                               centre=centres[1], **options)
        except ValueError as err:
            out.append(err)
            continue
        out.append((first, second))
        if keep is None:
            centres = (lad.coeffs, lad_after.coeffs)
    return out


def _fit_equations(data: PointingData, start: LinearModel, eq: Equations, *, robust: bool,
                   weighted: bool, lad_factor: float, rms_factor: float, block_s: float,
                   block_phases: int, prior: _LadFit | None = None,
                   centre: np.ndarray | None = None) -> tuple[FitResult, _LadFit | None]:
    """:func:`fit_terms` of the equations ``eq`` of ``data``, and its LAD stage (``prior``,
    ``centre``: :func:`_lad_stage`'s)."""
    used = np.ones(eq.n, dtype=bool)
    rejection = None
    lad = None
    if robust:
        lad = _lad_stage(eq, prior, centre)
        used = reject_beyond_mad(eq, lad.coeffs, lad_factor)
        kept_lad = used.copy()
        used = reject_beyond_rms(eq, least_squares_fit(eq, used).coeffs, used, rms_factor)
        rejection = Rejection(kept_lad, rms_factor, eq.floor, eq.y_w)
    sol = least_squares_fit(eq, used)
    return _result(data, start, eq, sol, used, rejection, robust=robust, weighted=weighted,
                   block_s=block_s, block_phases=block_phases), lad


def _check_options(data: PointingData, start: LinearModel, weighted: bool, lad_factor: float,
                   rms_factor: float, block_phases: int) -> None:
    m, n = len(start.names), len(data)
    if m == 0:
        raise ValueError("no terms to fit: give at least one pointing term")
    if n == 0:
        raise ValueError("there are no observations to fit")
    for label, factor in (("lad_factor", lad_factor), ("rms_factor", rms_factor)):
        if not (math.isfinite(factor) and factor > 0):
            raise ValueError(f"{label} must be a positive number, not {factor!r}")
    if isinstance(block_phases, bool) or not isinstance(block_phases, int) or block_phases < 1:
        raise ValueError(f"block_phases must be a whole number >= 1, not {block_phases!r}")
    if weighted and not data.weighted:
        raise ValueError("weighted=True needs weight_xel and weight_el in the data")
    if n < m:
        raise ValueError(f"{n} observations cannot determine {m} terms; observe more positions")


def _result(data: PointingData, start: LinearModel, eq: Equations, sol: Solution,
            used: np.ndarray, rejection: Rejection | None, *, robust: bool, weighted: bool,
            block_s: float, block_phases: int) -> FitResult:
    """The final fit's residuals of every observation, TPOINT's statistics over the used
    ones, the honest error bars (computed on first use) and the warnings."""
    n, m, names = eq.n, len(eq.names), eq.names
    coeffs = sol.coeffs
    fitted = matvec(eq.design, coeffs)  # TPOINT correction rows; the fitted error is minus this
    res_x = data.xel_arcsec + fitted[:n]
    res_e = data.el_arcsec + fitted[n:]

    n_used = int(used.sum())
    n_fitted = len(sol.rank.kept)
    ux, ue = res_x[used], res_e[used]
    sky = math.sqrt(float(np.mean(ux**2 + ue**2)))
    xel_rms = math.sqrt(float(np.mean(ux**2)))
    el_rms = math.sqrt(float(np.mean(ue**2)))
    if weighted:
        scale = math.sqrt(float(np.mean(data.weight_xel[used] * ux**2
                                        + data.weight_el[used] * ue**2)))
    else:
        scale = sky
    popn = sky * math.sqrt(n_used / (n_used - n_fitted)) if n_used > n_fitted else float("nan")
    sigma = np.sqrt(np.diag(sol.cov_unscaled)) * scale
    honest_source = partial(_honest, eq.a_w, eq.y_w, coeffs.copy(), used,
                            list(sol.rank.kept), n, data.t_s, block_s, rejection, block_phases)
    with np.errstate(invalid="ignore", divide="ignore"):
        sd = np.sqrt(np.diag(sol.cov_unscaled))
        corr = sol.cov_unscaled / np.outer(sd, sd)

    return FitResult(
        model=start.with_values(coeffs, name=start.name),
        sigma_arcsec=readonly(sigma),
        n_input=n,
        n_used=n_used,
        n_rejected=n - n_used,
        used=readonly(used),
        residual_xel_arcsec=readonly(res_x),
        residual_el_arcsec=readonly(res_e),
        sky_rms_arcsec=sky,
        xel_rms_arcsec=xel_rms,
        el_rms_arcsec=el_rms,
        popn_sd_arcsec=popn,
        condition_number=sol.condition_number,
        correlation=readonly(corr),
        unconstrained=tuple(names[j] for j in range(m) if j not in sol.rank.kept),
        warnings=_warnings(names, sol, corr),
        robust=robust,
        weighted=weighted,
        n_fitted=n_fitted,
        sigma_scale=scale,
        honest_block_s=block_s if data.t_s is not None else None,
        honest_source=honest_source,
    )


def _honest(a_w: np.ndarray, y_w: np.ndarray, coeffs: np.ndarray, used: np.ndarray,
            kept: list[int], n: int, t_s: np.ndarray | None, block_s: float,
            rejection: Rejection | None, phases: int) -> JackknifeResult:
    """:func:`cluster_jackknife` of the fit ``coeffs`` of the weighted equations ``a_w``,
    ``y_w``: its residuals made when the honest error bars are first asked for (most fits
    never ask: a matrix-vector product of the whole design saved)."""
    return cluster_jackknife(a_w, y_w - matvec(a_w, coeffs), used, kept, n, t_s, block_s,
                             rejection, phases)


def _warnings(names: Sequence[str], sol: Solution, corr: np.ndarray) -> tuple[str, ...]:
    """The terms the data cannot determine, and TPOINT's warning for each pair of terms that
    "cannot reliably be distinguished"."""
    m = len(names)
    messages = [
        f"{names[j]} cannot be determined from these data ({reason}); it was not fitted and "
        "is reported as 0 with no sigma"
        for j, reason in sorted(sol.rank.reasons.items())
    ]
    for i in range(m):
        for j in range(i + 1, m):
            r = corr[i, j]
            if math.isfinite(r) and abs(r) > CORRELATION_WARNING_LEVEL:
                messages.append(
                    f"{names[i]} and {names[j]} cannot reliably be distinguished (r = {r:.2f})"
                )
    return tuple(messages)
