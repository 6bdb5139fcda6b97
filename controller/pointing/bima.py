"""BIMA memo 23's pointing model (Wright 1992): the 7 + 7 linear terms of its equations (1) and
(2), and what an azimuth-axis tilt and a collimation error make of them.

The memo's fitting equations (1) and (2) are all in the TPOINT vocabulary (``bima14`` in
:data:`controller.pointing.model.NAMED_MODELS`), azimuth error as dA cos E and elevation error:

| memo term | dA cos E (eq. 1) | TPOINT | memo term | dE (eq. 2) | TPOINT |
|---|---|---|---|---|---|
| encoder offset | cos E | IA | encoder offset | 1 | IE |
| tilt | sin E sin A | HSSASE | tilt | sin A | HESA |
| tilt | sin E cos A | HSCASE | tilt | cos A | HECA |
| collimation | 1 | CA | sag | sin E | HESE |
| axis alignment | sin E | NPAE | gravity | cos E | HECE |
| 2Az | cos E sin 2A | HASA2 | 2Az | sin 2A | HESA2 |
| 2Az | cos E cos 2A | HACA2 | 2Az | cos 2A | HECA2 |

(TPOINT's harmonic generator evaluates azimuth at ``A_H = -A_N`` and negates dA and dA cos E
results (:mod:`controller.pointing.terms`), so some coefficients are minus the memo's North-based
ones: for a correction written with North-based azimuth, HSSASE, HASA2, HECA and HECA2 keep the
memo's sign and HSCASE, HACA2, HESA and HESA2 change it; the fitted space is the same.)
"""

from __future__ import annotations

import math

__all__ = ["BIMA_TERMS", "tilt_collimation_equivalents"]

#: the memo's 7 azimuth and 7 elevation terms, in TPOINT's names
BIMA_TERMS = ("IA", "HSSASE", "HSCASE", "CA", "NPAE", "HASA2", "HACA2",
              "IE", "HESA", "HECA", "HESE", "HECE", "HESA2", "HECA2")


def tilt_collimation_equivalents(tilt_arcmin: float, tilt_az_deg: float,
                                 collimation_arcmin: float) -> dict[str, float]:
    """The linear (small-angle) BIMA-term coefficients, arcsec in TPOINT's sign, of an
    azimuth-axis tilt ``tilt_arcmin`` towards azimuth ``tilt_az_deg`` (N = 0) and a
    collimation error ``collimation_arcmin`` (the simulator's ``exact_tilt_collimation``):
    with AN = -tilt cos(az_t), AW = tilt sin(az_t), CA = -collimation, the memo's separate
    azimuth and elevation tilt terms are HSSASE = HECA = AN, HSCASE = -AW, HESA = AW (TPOINT's
    harmonic signs, :mod:`controller.pointing.terms`; tested against AN and AW)."""
    tilt = tilt_arcmin * 60.0
    phi = math.radians(tilt_az_deg)
    an = -tilt * math.cos(phi)
    aw = tilt * math.sin(phi)
    return {"HSSASE": an, "HECA": an, "HSCASE": -aw, "HESA": aw,
            "CA": -collimation_arcmin * 60.0}
