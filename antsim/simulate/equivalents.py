"""What a fit of pointing terms makes of the world's effects: the recoverable truth.

A campaign's fit does not recover the mount's terms alone. The atmosphere's refraction the
control program leaves uncorrected (the 1990 program carried it in W5, docs/physics.md,
Refraction), the Sun's heating and the repeatable irregularities (encoders, gears, track)
are systematic errors too, and a least-squares fit of the terms gives each of them a share:
its projection on the terms at the good averaged rows (:func:`equivalent_arcsec`). The
recoverable truth (:func:`recoverable_truth`) is the mount's terms plus those shares, the
value a fit is judged against (``truth.json``'s ``recoverable``, docs/contract.md). All
values arcsec, indicated minus true, as the 1990 report writes them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from controller.astro.refraction import refraction_rad
from controller.astro.site import Weather
from controller.pointing.model import PointingModel
from controller.units import ARCSEC_PER_RAD

__all__ = ["RECOVERABLE_ABOUT", "RecoverableTruth", "equivalent_arcsec",
           "heating_equivalent_arcsec", "pattern_equivalent_arcsec", "recoverable_truth",
           "refraction_arcsec", "refraction_equivalent_arcsec"]

#: what the recoverable truth holds, in one line (truth.json, the run report, the demo)
RECOVERABLE_ABOUT = ("the recoverable truth: the mount's terms plus what the fit makes of the "
                     "uncorrected refraction, the heating and the repeatable irregularities "
                     "at the campaign's good scans")


def _good(rows: Sequence[Mapping]) -> list[Mapping]:
    return [r for r in rows if r["polarization"] == "AVG" and r["good"]]


def refraction_arcsec(rows: Sequence[Mapping], frequency_ghz: float,
                      relative_humidity: float | None = None) -> np.ndarray:
    """The atmosphere's refraction (arcsec, elevation increase) at each row's elevation and
    recorded weather (``relative_humidity`` instead of the recorded one when given)."""
    out = []
    for r in rows:
        humidity = r["humidity"] if relative_humidity is None else relative_humidity
        weather = Weather(float(r["air_temp_c"]), float(r["pressure_hpa"]), float(humidity))
        out.append(float(refraction_rad(np.radians(float(r["el_deg"])), weather,
                                        frequency_ghz=frequency_ghz)))
    return np.array(out) * ARCSEC_PER_RAD


def equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str], xel_arcsec: np.ndarray,
                      el_arcsec: np.ndarray) -> dict[str, float]:
    """What a least-squares fit of ``terms`` to the good averaged rows makes of errors
    ``xel_arcsec`` (dA cos E) and ``el_arcsec`` (dE) at them (indicated minus true, one
    value per good row): the terms' share of a systematic error."""
    good = _good(rows)
    az = np.radians([float(r["az_deg"]) for r in good])
    el = np.radians([float(r["el_deg"]) for r in good])
    model = PointingModel(list(terms))
    basis_az, basis_el = model.design_matrix(az, el)
    # the W's sign (indicated minus true) is minus TPOINT's basis; both axes of the fit
    design = -np.vstack([basis_az * np.cos(el)[:, None], basis_el])
    target = np.concatenate([xel_arcsec, el_arcsec])
    values, *_ = np.linalg.lstsq(design, target, rcond=None)
    return dict(zip(model.names, (float(v) for v in values), strict=True))


def refraction_equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str],
                                 frequency_ghz: float,
                                 relative_humidity: float | None = None) -> dict[str, float]:
    """What a least-squares fit of ``terms`` to the good averaged rows makes of the
    atmosphere's refraction alone (arcsec per term, indicated minus true: the control
    program points at unrefracted positions, so the encoders read the refraction more)."""
    good = _good(rows)
    d_el = refraction_arcsec(good, frequency_ghz, relative_humidity)
    return equivalent_arcsec(rows, terms, np.zeros(d_el.size), d_el)


def pattern_equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str],
                              world) -> dict[str, float]:
    """What the fit makes of the world's repeatable irregularities (encoders, gears, track)
    at the good rows' positions: the bias a fixed pattern gives the terms on this schedule
    (zero without the effect)."""
    effect = next((e for e in world.effects if e.name == "irregularities"), None)
    good = _good(rows)
    if effect is None:
        return dict.fromkeys(terms, 0.0)
    xel, d_el = effect.errors_arcsec(np.radians([float(r["az_deg"]) for r in good]),
                                     np.radians([float(r["el_deg"]) for r in good]))
    return equivalent_arcsec(rows, terms, xel, d_el)


def heating_equivalent_arcsec(rows: Sequence[Mapping], terms: Sequence[str],
                              world) -> dict[str, float]:
    """What the fit makes of the Sun's heating at the good rows' times and positions: the
    pedestal's tilt as the world has it, the feed legs and the yoke at their equilibrium for
    pointing there (their time constants, 17-55 min, are long beside a scan, short beside
    the day, so this is the shift a day's fit shares; zero without the effect)."""
    effect = next((e for e in world.effects if e.name == "thermal"), None)
    good = _good(rows)
    if effect is None or not hasattr(effect, "equilibrium_errors_arcsec"):
        return dict.fromkeys(terms, 0.0)
    xel, d_el = effect.equilibrium_errors_arcsec(
        np.array([float(r["t_s"]) for r in good]),
        np.radians([float(r["az_deg"]) for r in good]),
        np.radians([float(r["el_deg"]) for r in good]))
    return equivalent_arcsec(rows, terms, np.asarray(xel), np.asarray(d_el))


@dataclass(frozen=True)
class RecoverableTruth:
    """The recoverable truth per fitted term (arcsec) and its parts: ``mount`` (the injected
    term, zero for a term the mount has not), ``refraction`` (the share of the refraction
    the controller leaves uncorrected), ``heating`` and ``irregularities``."""

    mount: dict[str, float]
    refraction: dict[str, float]
    heating: dict[str, float]
    irregularities: dict[str, float]

    @property
    def value(self) -> dict[str, float]:
        """The recoverable value per term: the sum of the parts (arcsec)."""
        return {n: self.mount[n] + self.refraction[n] + self.heating[n]
                + self.irregularities[n] for n in self.mount}

    def as_json(self) -> dict:
        """``truth.json``'s ``recoverable`` object (docs/contract.md)."""
        value = self.value
        return {"about": RECOVERABLE_ABOUT,
                "terms": {n: {"value_arcsec": value[n], "mount_arcsec": self.mount[n],
                              "refraction_arcsec": self.refraction[n],
                              "heating_arcsec": self.heating[n],
                              "irregularities_arcsec": self.irregularities[n]}
                          for n in value}}


def uncorrected_refraction_scale(controller, world) -> float:
    """The fraction of the formula's refraction (at the recorded weather) the controller
    leaves in the pointing: the world's whole refraction (its ``refraction_scale``) when it
    corrects none, the anomaly's excess over the formula when it corrects some (a standard
    atmosphere's mismatch with the day's weather is not counted)."""
    scale = float(world.sky.refraction_scale)
    return scale if controller.refraction == "none" else scale - 1.0


def recoverable_truth(rows: Sequence[Mapping], scenario, world) -> RecoverableTruth | None:
    """What the campaign's fit of its terms (the controller's ``fit_spec``, terms held fixed
    left out) should recover from ``rows``: the mount's terms plus the fit's shares of the
    world's uncorrected refraction, heating and irregularities (a mount term the fit has
    not is not projected on the fitted ones). None where this projection does not apply: an
    equatorial mount, optical pointing, fitted terms of the feed angle or of recorded
    temperatures (the projection is of position alone), or no good scan."""
    c = scenario.controller
    if c.mount != "altaz" or c.method != "five_point" or not _good(rows):
        return None
    fixed = {name for name, _ in c.fit_fixed}
    terms = [n for n in c.fit_spec()[0] if n not in fixed]
    fitted = PointingModel(terms)
    if fitted.needs_feed or fitted.regressors:
        return None
    injected = scenario.truth_model.as_dict()
    mount = {n: float(injected.get(n, 0.0)) for n in terms}
    scale = uncorrected_refraction_scale(c, world)
    refraction = dict.fromkeys(terms, 0.0)
    if scale:
        refraction = {n: scale * v for n, v in
                      refraction_equivalent_arcsec(rows, terms, world.sky.frequency_ghz).items()}
    return RecoverableTruth(mount=mount, refraction=refraction,
                            heating=heating_equivalent_arcsec(rows, terms, world),
                            irregularities=pattern_equivalent_arcsec(rows, terms, world))
