"""Candidates that are linear pointing terms: TPOINT's named terms, harmonic pairs and
families of harmonics of higher order, and the feed (rotator) offset.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from antsim.world.effects.harmonics import FeedOffset

from ..problem import term_columns
from .base import (
    Candidate,
    p_value,
    stacked,
    with_trials,
)

__all__ = ['FeedOffsetCandidate', 'HarmonicFamilyCandidate', 'TermsCandidate']


class TermsCandidate(Candidate):
    """An effect expressed exactly by TPOINT terms (a harmonic pair or single terms)."""

    static = True

    def __init__(self, name: str, terms: Sequence[str], title: str, signature: str,
                 explanation: str, effect: str | None = None, pair: bool = True,
                 blind_exclusion: str | None = None, signs: tuple[float, float] = (1.0, 1.0),
                 mounts: tuple[str, ...] = ("altaz",)):
        self.name = name
        #: the vocabulary its terms are in: TPOINT's alt-az one, or its equatorial one
        self.mounts = tuple(mounts)
        self.terms = tuple(terms)
        self.title = title
        self.signature = signature
        self.explanation = explanation
        self.effect = effect or "terms"
        self.pair = pair and len(self.terms) == 2
        self.blind_exclusion = blind_exclusion
        self.amplitude_param = "amplitude_arcsec"
        #: a pair's coefficients per unit of a cos(phase), a sin(phase): the simulator
        #: effect's ``HarmonicEffect.signs`` (its phase is of the physical correction)
        self.signs = (float(signs[0]), float(signs[1]))
        if self.pair:
            sign = ["" if x > 0 else "-" for x in self.signs]
            self.params_doc = {
                "amplitude_arcsec": "amplitude of the harmonic (arcsec)",
                "amplitude_sigma_arcsec": "its standard error (arcsec)",
                "phase_deg": f"phase: {self.terms[0]} = {sign[0]}a cos(phase), "
                             f"{self.terms[1]} = {sign[1]}a sin(phase)"}
        else:
            self.params_doc = {t: f"TPOINT coefficient of {t} (arcsec)" for t in self.terms}

    def columns(self, obs, theta=None):
        return term_columns(self.terms, obs), self.terms

    def params_from(self, obs, theta, coef, cov, names):
        values = dict(zip(names, map(float, coef), strict=True))
        if self.pair and len(names) == 2:
            s, c = float(coef[0]), float(coef[1])
            amp = math.hypot(s, c)
            grad = np.array([s, c]) / amp if amp > 0 else np.zeros(2)
            amp_sig = float(np.sqrt(grad @ cov @ grad)) if amp > 0 else float("nan")
            phase = math.degrees(math.atan2(self.signs[1] * c, self.signs[0] * s)) % 360.0
            return ({"amplitude_arcsec": amp, "amplitude_sigma_arcsec": amp_sig,
                     "phase_deg": phase, "terms_arcsec": values}, amp, amp_sig)
        if len(names) == 1:
            return ({"terms_arcsec": values}, float(coef[0]),
                    float(math.sqrt(max(cov[0, 0], 0.0))))
        _, amp, amp_sig = super().params_from(obs, theta, coef, cov, names)
        return {"amplitude_arcsec": amp, "terms_arcsec": values}, amp, amp_sig

    def draw_shape(self, rng, obs):
        if len(self.terms) > 2:  # several orders at once: a random direction among them
            v = rng.standard_normal(len(self.terms))
            return {"direction": tuple(float(x) for x in v / np.linalg.norm(v))}
        return {"phase_deg": float(rng.uniform(0.0, 360.0))}

    def unit_signal(self, obs, shape):
        cols = term_columns(self.terms, obs)
        if self.pair:
            phi = math.radians(shape["phase_deg"])
            return cols @ np.array([self.signs[0] * math.cos(phi), self.signs[1] * math.sin(phi)])
        if "direction" in shape:
            return cols @ np.array(shape["direction"])
        return cols[:, 0]

    def effect_params(self, shape, amplitude):
        if self.pair and self.effect != "terms":
            return {"amplitude_arcsec": float(amplitude), "phase_deg": float(shape["phase_deg"])}
        if "direction" in shape:
            return {"terms_arcsec": {t: float(amplitude * x) for t, x
                                     in zip(self.terms, shape["direction"], strict=True)}}
        return {"terms_arcsec": {self.terms[0]: float(amplitude)}}

    def hidden_amplitude(self, params):
        if "terms_arcsec" in params and len(self.terms) > 2:
            return float(np.hypot.reduce(list(params["terms_arcsec"].values())))
        return super().hidden_amplitude(params)


class HarmonicFamilyCandidate(TermsCandidate):
    """A periodic error with an unknown number of cycles n per turn of an axis: the pair
    ``H<result>S<arg><n>``, ``H<result>C<arg><n>`` of TPOINT's harmonic generator, n searched
    over ``orders`` (the look-elsewhere effect paid as that many trials)."""

    def __init__(self, name: str, result: str, arg: str, orders: Sequence[int], title: str,
                 signature: str, explanation: str, mounts: tuple[str, ...] = ("altaz",)):
        self.result, self.arg, self.orders = result, arg, tuple(orders)
        super().__init__(name, (self.order_terms(self.orders[0])), title, signature, explanation,
                         effect="terms", mounts=mounts)
        #: the pattern (a finding names its actual terms, e.g. HESE7 HECE7)
        self.terms = (f"H{result}S{arg}n", f"H{result}C{arg}n")
        self.params_doc = {"n": "cycles per turn", "amplitude_arcsec": "amplitude (arcsec)",
                           "phase_deg": "phase: sine term a cos(phase), cosine a sin(phase)"}

    def order_terms(self, n: int) -> tuple[str, str]:
        k = "" if n == 1 else str(n)
        return (f"H{self.result}S{self.arg}{k}", f"H{self.result}C{self.arg}{k}")

    def thetas(self, obs):
        return list(self.orders)

    def columns(self, obs, theta=None):
        n = self.orders[0] if theta is None else int(theta)
        pair = self.order_terms(n)
        return term_columns(pair, obs), pair

    def test(self, problem, perp, z_perp, chi2_now):
        results = []
        for n in self.orders:
            cols, names = self.columns(problem.obs, n)
            results.append(self.linear_test(problem, perp, z_perp, cols, names, n))
        for res in results:
            res.trials = float(len(self.orders))
            res.p = with_trials(p_value(problem, res.delta_chi2, res.dof, res.chi2_now,
                                        res.mask), res.trials)
        best = max(results, key=lambda res: res.delta_chi2)
        best.siblings = [res for res in results if res is not best and res.dof > 0]
        if best.dof > 0:
            self.finish(problem, best)
        return best

    def params_from(self, obs, theta, coef, cov, names):
        params, amp, sig = super().params_from(obs, theta, coef, cov, names)
        params["n"] = int(theta)
        return params, amp, sig

    def label(self, theta: Any) -> str:
        return f"{self.name}[{int(theta)}]"

    def draw_shape(self, rng, obs):
        return {"n": int(rng.choice(self.orders)), "phase_deg": float(rng.uniform(0.0, 360.0))}

    def unit_signal(self, obs, shape):
        cols, _ = self.columns(obs, shape["n"])
        phi = math.radians(shape["phase_deg"])
        return cols @ np.array([math.cos(phi), math.sin(phi)])

    def effect_params(self, shape, amplitude):
        s_term, c_term = self.order_terms(shape["n"])
        phi = math.radians(shape["phase_deg"])
        return {"terms_arcsec": {s_term: float(amplitude * math.cos(phi)),
                                 c_term: float(amplitude * math.sin(phi))}}

    def hidden_label(self, params: dict[str, Any]) -> str:
        term = next(iter(params["terms_arcsec"]))
        digits = term[len(f"H{self.result}S{self.arg}"):]
        return f"{self.name}[{int(digits) if digits else 1}]"


class FeedOffsetCandidate(Candidate):
    name = "feed_offset"
    effect = "feed_offset"
    title = "feed offset"
    terms = ("CA", "IE")
    signature = ("(xel, el) proportional to (cos(f - C7), sin(f - C7)) with f the feed angle "
                 "(Fomalont 1973): a collimation pair that turns with a rotating feed")
    params_doc: ClassVar[dict[str, str]] = {"offset_arcsec": "beam displacement (arcsec)",
                  "angle_deg": "direction C7 relative to the feed angle (deg)"}
    amplitude_param = "offset_arcsec"

    def __init__(self):
        self.explanation = FeedOffset.explanation
        self.blind_exclusion = ("with the 45-ft's fixed feed the feed offset is a constant "
                                "collimation pair that CA (W10) and IE (W1) absorb")

    def columns(self, obs, theta=None):
        # the feed (rotator) angle: a TPOINT file's fifth column or the recordings'
        # feed_angle_deg; a fixed feed makes this a collimation pair (CA, IE)
        f = np.radians(obs.rotator_deg) if obs.rotator_deg is not None else np.zeros(obs.n)
        f = np.nan_to_num(f)
        cols = np.column_stack([stacked(np.cos(f), np.sin(f), obs.n),
                                stacked(np.sin(f), -np.cos(f), obs.n)])
        return cols, ("a_arcsec", "b_arcsec")

    def params_from(self, obs, theta, coef, cov, names):
        values = dict(zip(names, map(float, coef), strict=True))
        a, b = values.get("a_arcsec", 0.0), values.get("b_arcsec", 0.0)
        r = math.hypot(a, b)
        g = np.array([a, b])[: len(coef)] / r if r > 0 else np.zeros(len(coef))
        return ({"offset_arcsec": r, "angle_deg": math.degrees(math.atan2(b, a)) % 360.0},
                r, float(np.sqrt(g @ cov @ g)) if r > 0 else float("nan"))

    def effect_from_params(self, params):
        return {"offset_arcsec": params["offset_arcsec"], "angle_deg": params["angle_deg"]}
