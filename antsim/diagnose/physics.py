"""How a finding is named: its signature in words, the mechanisms it is consistent with,
and what observation would tell apart two candidates these data cannot.

A pure harmonic of an axis angle (:attr:`.candidates.base.Candidate.harmonic`) is named as
the harmonic it is ("dE varies as sin 2A and cos 2A"), with the mechanisms it is consistent
with; none is asserted, since nothing beyond the harmonic (a second axis in a fixed
relation, a phase, a dependence on time, a sensor) tells them apart. Every other candidate's
signature goes beyond a harmonic (a time, a temperature, a source, the direction of the last
slew, a rotator angle, the second-order geometry of both axes), and it names its mechanism.

Two candidates that predict the data equally well differ somewhere else: on the sky where
these data have no observations (their models are evaluated over the whole sky and the
place where they differ most is named), in time (a second night), with the rotator, with
other sources. :func:`tell_apart` says which.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

import numpy as np

from .candidates.base import Candidate
from .data import Observations
from .problem import term_columns

__all__ = ["harmonic_words", "option_columns", "signature_words", "tell_apart"]

_RESULT = {"E": "dE", "A": "dA", "S": "dA cos E", "H": "dH", "D": "dDec", "X": "dH cos Dec"}
_ARGUMENT = {"A": "A", "E": "E", "H": "H", "D": "Dec"}
_HARMONIC = re.compile(r"^H([EASHDX])([SC])([AEHD])(\d*)$")
#: the sky grid :func:`tell_apart` evaluates models on: azimuth step, elevations from, to
#: and step (deg; a pointing run rarely goes below 10 deg)
GRID_AZ_STEP_DEG = 5.0
GRID_EL_DEG = (10.0, 89.0, 2.0)
#: a direction separates two models "much better" than the data do when they differ there
#: by this factor more than anywhere the data were taken
SEPARATES = 2.0


def harmonic_words(names: Sequence[str]) -> str:
    """TPOINT harmonic terms in words: ("HESA2", "HECA2") -> "dE varies as sin 2A and cos
    2A" (several results joined by ";"); "" where a name is not a simple harmonic."""
    by: dict[str, list[str]] = {}
    for name in names:
        m = _HARMONIC.match(name)
        if m is None:
            return ""
        result, fn, arg, n = m.groups()
        k = "" if n in ("", "1") else n
        sep = " " if arg == "D" else ""
        by.setdefault(_RESULT[result], []).append(
            f"{'sin' if fn == 'S' else 'cos'} {k}{sep if k else ''}{_ARGUMENT[arg]}")
    parts = []
    for result, funcs in by.items():
        listed = funcs[0] if len(funcs) == 1 else ", ".join(funcs[:-1]) + " and " + funcs[-1]
        parts.append(f"{result} varies as {listed}")
    return "; ".join(parts)


def signature_words(candidate: Candidate, names: Sequence[str]) -> str:
    """What the finding is, in the data's terms: a harmonic's own (``names``: its terms),
    else the candidate's signature."""
    if candidate.harmonic:
        words = harmonic_words(names)
        if words:
            return words
    return candidate.signature


def option_columns(candidate: Candidate, obs: Observations, theta: Any) -> np.ndarray:
    """A candidate's raw columns (2n, q) at the shape ``theta`` on ``obs`` (the decision's
    form: :meth:`~.candidates.base.Candidate.options` for a nonlinear signature)."""
    if candidate.linear_signature:
        return candidate.columns(obs, theta)[0]
    return next(cols for t, cols, _ in candidate.options(obs) if t == theta)


def _sky(obs: Observations) -> Observations:
    """Observations at every direction of the sky grid (no errors, no time)."""
    az = np.radians(np.arange(0.0, 360.0, GRID_AZ_STEP_DEG))
    el = np.radians(np.arange(*GRID_EL_DEG))
    a, e = (v.ravel() for v in np.meshgrid(az, el))
    zero = np.zeros(a.size)
    return Observations(t_s=zero, az_rad=a, el_rad=e, xel_arcsec=zero, el_arcsec=zero,
                        good=np.ones(a.size, dtype=bool), meta=dict(obs.meta),
                        mount=obs.mount, kind="tpoint")


def _static(candidate: Candidate) -> bool:
    """Whether a candidate's signature depends on the direction alone."""
    return not ({"time", "air_temp_c", "source", "slew_az", "slew_el", "latitude"}
                & set(candidate.needs)) and candidate.name != "feed_offset" \
        and candidate.kind == "offsets"


def tell_apart(obs: Observations, base_terms: Sequence[str],
               models: Sequence[Sequence[tuple[Candidate, Any, Sequence[int] | None]]],
               coefs: Sequence[np.ndarray]) -> str:
    """What observation would tell two models apart: ``models`` the two models' candidate
    shapes beyond the base terms (candidate, shape, the places of the columns fitted among
    the shape's own: None for all), ``coefs`` their fitted coefficients (the base terms'
    first, then each shape's columns in order), both fitted to ``obs``."""
    a, b = ({c for c, _, _ in model} for model in models)
    differ = a ^ b
    words = []
    if any(not c.static and "time" in c.needs for c in differ):
        words.append("a second night (a dependence on time)")
    if any("air_temp_c" in c.needs for c in differ):
        words.append("a night with another temperature history")
    if any(c.name == "feed_offset" for c in differ):
        words.append("other rotator angles")
    if any("source" in c.needs for c in differ):
        words.append("other sources at the same directions")
    if words or not all(_static(c) for c in a | b):
        return "; ".join(words) or "more observations of another kind"
    sky = _sky(obs)
    preds = []
    for model, coef, data in ((models[0], coefs[0], obs), (models[1], coefs[1], obs)):
        out = []
        for where in (data, sky):
            cols = [term_columns(list(base_terms), where)]
            cols += [option_columns(c, where, theta)[:, slice(None) if keep is None
                                                         else list(keep)]
                     for c, theta, keep in model]
            out.append(np.column_stack(cols) @ coef)
        preds.append(out)
    here = _apart(preds[0][0] - preds[1][0])
    there = _apart(preds[0][1] - preds[1][1])
    k = int(np.argmax(there))
    if not there[k] > SEPARATES * max(float(here.max()), 1e-12):
        return ("no direction separates them much better than these data do: more "
                "observations would")
    az, el = math.degrees(sky.az_rad[k]), math.degrees(sky.el_rad[k])
    return (f"observations near azimuth {az:.0f} deg (N = 0, E = 90), elevation {el:.0f} "
            f"deg, where the two predict {there[k]:.2f}\" apart (at most {here.max():.2f}\" "
            "where these data were taken)")


def _apart(d: np.ndarray) -> np.ndarray:
    """Per direction, the length of a difference of predicted errors (2k,) on the sky."""
    k = d.size // 2
    return np.hypot(d[:k], d[k:])
