"""TPOINT's vocabulary for a model written to a file, and the sign convention of any model.

antsim fits in several vocabularies: the 1990 report's W1..W10 (Ghigo 1990, NRAO EDIR 288,
section II), katpoint's P1..P22, Wright's a(i), b(i) (BIMA memo 23, here A1..A7, B1..B7),
Crane's C1..C11 (NRAO Engineering Memo 147) and TPOINT's own names. Those sources write
"indicated minus true"; TPOINT writes the correction, true (observed) = raw (encoder) +
correction. A model file is read by other software, so :func:`in_tpoint_terms` writes every
term that is one TPOINT term up to sign (:data:`~controller.pointing.terms.GHIGO_EQUIVALENTS`,
``KATPOINT_EQUIVALENTS``, ``WRIGHT_EQUIVALENTS``, tested column by column) under TPOINT's name
with TPOINT's sign, and says in a comment on its line which term it was:

    W1 = -IE, W4 = TF, W5 = TX, W6 = IA, W9 = NPAE, W10 = CA; fitted on their own, W2 = HECA,
    W3 = -HESA, W7 = -HSCASE, W8 = HSSASE; tied as the report ties them (W2 = W8, W3 = -W7),
    the azimuth axis's tilt W2 = W8 = AN and W3 = -W7 = -AW (TPOINT's terms at its azimuth
    A_T = 180 deg - A_N: AN > 0 the pole north of the zenith, AW > 0 west of it).

The model points exactly as before (each renamed column is the old one times its sign). Terms
with no TPOINT twin (Crane's, katpoint's scale factors P9, P12) keep their names.
The sign of any model in words is :func:`controller.pointing.signs.sign_convention`.
"""

from __future__ import annotations

import numpy as np

from .signs import INDICATED_MINUS_TRUE, UNITS, sign_convention
from .terms import (
    GHIGO_EQUIVALENTS,
    GHIGO_TILT,
    KATPOINT_EQUIVALENTS,
    WRIGHT_EQUIVALENTS,
    get_term,
)
from .tpoint import TPointModel

__all__ = ["TPOINT_EQUIVALENTS", "in_tpoint_terms"]

#: term -> (TPOINT's term, sign): term = sign * TPOINT's coefficient
TPOINT_EQUIVALENTS: dict[str, tuple[str, float]] = {
    **GHIGO_EQUIVALENTS, **KATPOINT_EQUIVALENTS, **WRIGHT_EQUIVALENTS}

def in_tpoint_terms(model: TPointModel) -> TPointModel:
    """``model`` with every term TPOINT has under TPOINT's name and sign (its sigma, fixed
    and parallel flags kept), a comment on each renamed line saying what it was, and the
    units and sign in the file's header comments. A pair the report ties (W2 = W8, or
    W3 = -W7, to the last digit written and neither with a sigma) becomes AN or AW."""
    names = list(model.names)
    values = np.asarray(model.values_arcsec, dtype=float)
    ties = _ties(model)
    out_names: list = []
    out_values, keep, notes = [], [], []
    taken = set(names) - set(TPOINT_EQUIVALENTS)
    for i, name in enumerate(names):
        if name in ties:
            tilt, sign = ties[name]
            if tilt in taken:
                continue  # its partner came first
            out_names.append(tilt)
            out_values.append(sign * values[i])
            (first, s1), (second, s2) = GHIGO_TILT[tilt]
            notes.append(f"{first} = {'-' if s1 * s2 < 0 else ''}{second} = "
                         f"{'-' if s1 < 0 else ''}{tilt}: tilt of the azimuth axis, tied")
            keep.append(i)
            taken.add(tilt)
            continue
        twin, sign = TPOINT_EQUIVALENTS.get(name, (name, 1.0))
        if twin in taken and twin != name:
            twin, sign = name, 1.0  # TPOINT's name is already used: keep this one's
        taken.add(twin)
        # a term kept as it is stays the model's own object (Crane's C terms, an equatorial
        # model's, have no name that get_term knows)
        out_names.append(model.terms[i] if twin == name else twin)
        out_values.append(sign * values[i])
        notes.append("" if twin == name else
                     f"{name} = {'-' if sign < 0 else ''}{twin} ({get_term(name).description})")
        keep.append(i)
    written = [getattr(t, "name", t) for t in out_names]
    comments = (f"! Units: {UNITS}. Sign: {sign_convention(written)}.",)
    was = [names[i] for i, note in zip(keep, notes, strict=True) if note]
    renamed = [label for pattern, label in INDICATED_MINUS_TRUE
               if any(pattern.match(n) for n in was)]
    if renamed:
        comments += (f"! Renamed from {', '.join(renamed)}, which write indicated minus true: "
                     "each line says from what.",)
    return TPointModel(out_names, out_values, model.name,
                       sigma_arcsec=[model.sigma_arcsec[i] for i in keep],
                       fixed=[model.fixed[i] for i in keep],
                       parallel=[model.parallel[i] for i in keep],
                       caption=model.caption, parameters=model.parameters,
                       comments=comments, notes=notes)


def _ties(model: TPointModel) -> dict[str, tuple[str, float]]:
    """W term -> (TPOINT's tilt, sign) for each pair of ``model`` tied as the
    report ties them: equal values (to the 1e-4" a .mod file prints) with no sigma."""
    index = {n: i for i, n in enumerate(model.names)}
    out = {}
    for tilt, ((first, s1), (second, s2)) in GHIGO_TILT.items():
        if first not in index or second not in index:
            continue
        i, j = index[first], index[second]
        a, b = s1 * model.values_arcsec[i], s2 * model.values_arcsec[j]
        if abs(a - b) < 5e-5 and np.isnan(model.sigma_arcsec[i]) \
                and np.isnan(model.sigma_arcsec[j]) and model.fixed[i] == model.fixed[j]:
            out[first] = (tilt, s1)
            out[second] = (tilt, s2)
    return out
