"""What the fitter reads: pointing data, and what it needs of a model.

:class:`PointingData` holds the measured total pointing errors at known true positions.
:class:`LinearModel` is the part of a pointing model the fitter uses (its terms' design
matrix, and a copy with new coefficients); :class:`~controller.pointing.model.PointingModel`
is the implementation. The fitter names this protocol rather than the class so that the model
can fit itself (:meth:`~controller.pointing.model.PointingModel.fit`) without the two
modules importing each other.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

__all__ = ["LinearModel", "PointingData", "require_pointing_data"]


class LinearModel(Protocol):
    """A named, ordered set of linear pointing terms with coefficients (arcsec)."""

    name: str

    @property
    def names(self) -> tuple[str, ...]: ...

    @property
    def values_arcsec(self) -> np.ndarray: ...

    def design_matrix(self, az_rad, el_rad, feed_rad=None,
                      aux=None) -> tuple[np.ndarray, np.ndarray]:
        """TPOINT-sign correction basis ``(dA, dE)`` per radian, each of shape (N, M)."""
        ...

    def with_values(self, values_arcsec, name: str | None = None) -> LinearModel:
        """A copy with new coefficients."""
        ...


def _float_vector(value: Any, name: str) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name} must be numbers; {err}") from None
    arr = np.atleast_1d(arr)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional; it has shape {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name} has {int(bad.sum())} value(s) that are NaN or infinite "
            f"(first at index {first})"
        )
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class PointingData:
    """Measured total pointing errors at known true positions (one row per observation).

    ``az_rad``, ``el_rad``: observed (true) azimuth (North = 0, East = pi/2) and elevation,
    radians. ``xel_arcsec``, ``el_arcsec``: total pointing error, "indicated minus true",
    cross-elevation (dA cos E) and elevation, arcsec. ``weight_xel``, ``weight_el``: optional
    1/sigma^2 weights (1/arcsec^2), used only by
    :func:`~controller.pointing.fitting.fit_model` with ``weighted=True``.
    ``t_s``: optional observation times (s); with them the honest error bars allow for
    residuals correlated in time (see :func:`~controller.pointing.fitting.fit_model`). ``feed_rad``:
    optional feed (rotator) angle of each observation (rad), the regressor of feed terms such as
    ``HSCF``. ``aux``: optional recorded quantities of each observation for thermal terms
    (:mod:`controller.pointing.thermal`): name -> (value for the cross-elevation row, value for
    the elevation row), e.g. a structure temperature read during each half of the cross scan
    (C). For an equatorial mount ``az_rad``/``el_rad`` hold hour angle and declination and
    ``xel_arcsec`` the cross-declination error dH cos(dec) (see
    :mod:`controller.pointing.equatorial`).

    The arrays are validated on construction (1-D, same length, finite, |el| <= pi/2,
    positive weights) and stored as read-only copies.
    """

    az_rad: np.ndarray
    el_rad: np.ndarray
    xel_arcsec: np.ndarray
    el_arcsec: np.ndarray
    weight_xel: np.ndarray | None = None
    weight_el: np.ndarray | None = None
    t_s: np.ndarray | None = None
    feed_rad: np.ndarray | None = None
    aux: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None

    def __post_init__(self) -> None:
        names = ("az_rad", "el_rad", "xel_arcsec", "el_arcsec")
        arrays = {n: _float_vector(getattr(self, n), n) for n in names}
        if (self.weight_xel is None) != (self.weight_el is None):
            raise ValueError("give both weight_xel and weight_el, or neither")
        if self.weight_xel is not None:
            for n in ("weight_xel", "weight_el"):
                w = _float_vector(getattr(self, n), n)
                if (w <= 0).any():
                    first = int(np.flatnonzero(w <= 0)[0])
                    raise ValueError(
                        f"{n} must be positive (1/sigma^2); index {first} is {w[first]}"
                    )
                arrays[n] = w
        if self.t_s is not None:
            arrays["t_s"] = _float_vector(self.t_s, "t_s")
        if self.feed_rad is not None:
            arrays["feed_rad"] = _float_vector(self.feed_rad, "feed_rad")
        aux = None
        if self.aux is not None:
            aux = {}
            for name, pair in self.aux.items():
                if len(pair) != 2:
                    raise ValueError(f"aux[{name!r}] must be a pair (cross-elevation rows, "
                                     "elevation rows)")
                aux[name] = tuple(_float_vector(v, f"aux[{name!r}]") for v in pair)
                arrays[f"aux[{name!r}]"] = aux[name][0]
                arrays[f"aux[{name!r}] (elevation)"] = aux[name][1]
        lengths = {n: a.size for n, a in arrays.items()}
        if len(set(lengths.values())) > 1:
            detail = ", ".join(f"{n} {k}" for n, k in lengths.items())
            raise ValueError(f"pointing data arrays differ in length: {detail}")
        el = arrays["el_rad"]
        # 1e-12 rad of slack: an elevation of exactly 90 deg converted from degrees may land
        # a rounding error above pi/2.
        outside = np.abs(el) > math.pi / 2 + 1e-12
        if outside.any():
            first = int(np.flatnonzero(outside)[0])
            raise ValueError(
                f"el_rad must lie within +-pi/2 radians; index {first} is {el[first]:.6g} "
                "(degrees given where radians are expected?)"
            )
        for n, a in arrays.items():
            if not n.startswith("aux["):
                object.__setattr__(self, n, a)
        object.__setattr__(self, "aux", aux)

    def __len__(self) -> int:
        return int(self.az_rad.size)

    @property
    def weighted(self) -> bool:
        """Whether weights are present."""
        return self.weight_xel is not None

    def select(self, mask) -> PointingData:
        """A new ``PointingData`` holding the observations where ``mask`` is true."""
        keep = np.asarray(mask, dtype=bool)
        if keep.shape != self.az_rad.shape:
            raise ValueError(f"mask has shape {keep.shape}, the data {self.az_rad.shape}")
        return PointingData(
            self.az_rad[keep], self.el_rad[keep], self.xel_arcsec[keep], self.el_arcsec[keep],
            None if self.weight_xel is None else self.weight_xel[keep],
            None if self.weight_el is None else self.weight_el[keep],
            None if self.t_s is None else self.t_s[keep],
            None if self.feed_rad is None else self.feed_rad[keep],
            None if self.aux is None else {n: (x[keep], e[keep]) for n, (x, e) in
                                           self.aux.items()},
        )


def require_pointing_data(data: object) -> None:
    """TypeError unless ``data`` is a :class:`PointingData`."""
    if not isinstance(data, PointingData):
        raise TypeError(f"data must be a PointingData, not {type(data).__name__}")
