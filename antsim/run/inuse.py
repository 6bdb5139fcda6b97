"""How well the pointing model in use pointed: the closed loop's one number.

A campaign observed with a model measures, in every good scan, the pointing error that model
left: the measured correction plus any correction the controller added on top of the model
(a search's encoder offset; :mod:`controller.program.recordings`). Its Sky RMS is what a
model fitted from an earlier campaign promised with that fit's Sky RMS (its residuals); the
ratio of the two says whether the loop closed.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Pointing", "pointing_errors", "pointing_in_use"]


@dataclass(frozen=True)
class Pointing:
    """The pointing error left by the model in use (arcsec) over ``n`` good scans, and the
    fit the model came from (its Sky RMS and observations, None when unknown)."""

    model: str
    n: int
    sky_rms_arcsec: float
    xel_rms_arcsec: float
    el_rms_arcsec: float
    fit_sky_rms_arcsec: float | None = None
    fit_observations: int | None = None

    @property
    def ratio(self) -> float | None:
        """Sky RMS with the model in use over the Sky RMS of the fit it came from."""
        fit = self.fit_sky_rms_arcsec
        return self.sky_rms_arcsec / fit if fit else None

    def line(self) -> str:
        """One line for a person: the rms, and against the fit's when it is known."""
        text = (f"pointing with the model in use ({self.model}): Sky RMS "
                f"{self.sky_rms_arcsec:.1f}\" (xel {self.xel_rms_arcsec:.1f}\", el "
                f"{self.el_rms_arcsec:.1f}\") on {self.n} good scans")
        if self.ratio is not None:
            text += (f", {self.ratio:.2f} times the {self.fit_sky_rms_arcsec:.1f}\" of the fit "
                     f"it came from" + (f" ({self.fit_observations} points)"
                                        if self.fit_observations else ""))
        return text

    def to_json(self) -> dict[str, Any]:
        return {"model": self.model, "n_scans": self.n, "sky_rms_arcsec": self.sky_rms_arcsec,
                "xel_rms_arcsec": self.xel_rms_arcsec, "el_rms_arcsec": self.el_rms_arcsec,
                "fit_sky_rms_arcsec": self.fit_sky_rms_arcsec,
                "fit_observations": self.fit_observations, "ratio": self.ratio}


def pointing_errors(rows: Iterable[Mapping[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """(xel, el) arcsec: the pointing error the model in use left in each good scan of
    ``rows`` (the averaged polarization; the recordings' offsets are arcmin)."""
    good = [r for r in rows if r["polarization"] == "AVG" and r["good"]]
    xel = 60.0 * np.array([r["xel_arcmin"] + r["applied_xel_arcmin"] for r in good])
    el = 60.0 * np.array([r["el_arcmin"] + r["applied_el_arcmin"] for r in good])
    return xel, el


def pointing_in_use(rows: Iterable[Mapping[str, Any]], model) -> Pointing | None:
    """The pointing error left by ``model`` (the model in use) in the good scans of ``rows``
    (:func:`pointing_errors`); None without any. The fit it came from is read from ``model``
    when it carries one (a ``model.dat`` or a ``fit.json`` loaded by
    :func:`controller.pointing.modelio.load_model`)."""
    xel, el = pointing_errors(rows)
    if not xel.size:
        return None
    return Pointing(model=str(model.name), n=int(xel.size),
                    sky_rms_arcsec=math.sqrt(float(np.mean(xel ** 2 + el ** 2))),
                    xel_rms_arcsec=math.sqrt(float(np.mean(xel ** 2))),
                    el_rms_arcsec=math.sqrt(float(np.mean(el ** 2))),
                    fit_sky_rms_arcsec=getattr(model, "fit_sky_rms_arcsec", None),
                    fit_observations=getattr(model, "fit_observations", None))
