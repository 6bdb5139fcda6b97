"""BIMA memo 23's pointing model (Wright 1992): the 7 + 7 linear terms of its equations (1) and
(2), and what an azimuth-axis tilt and a collimation error make of them.

The memo's fitting equations (1) and (2), "indicated minus true", azimuth error as dA cos E:

    daz = a(1) cos(el) + a(2) + a(3) sin(el) + sin(el) (a(4) sin(az) + a(5) cos(az))
          + cos(el) (a(6) sin(2 az) + a(7) cos(2 az))
    del = b(1) + b(2) sin(el) + b(3) cos(el) + b(4) sin(az) + b(5) cos(az) + b(6) sin(2 az)
          + b(7) cot(el)

are the named terms A1..A7, B1..B7 (``wright14``, :mod:`controller.pointing.terms`; the memo's
names: a(1) azimuth encoder + mount offset from the meridian, a(2) collimation, a(3)
elevation-axis misalignment, a(4), a(5) and b(4), b(5) tilt of the azimuth axis, a(6), a(7)
residuals, b(1) elevation encoder offset, b(2), b(3) elevation axis errors, b(6) Fourier
residual, b(7) refraction), and every one coincides with a TPOINT term (``bima14``, in the
memo's order; ``controller.pointing.terms.WRIGHT_EQUIVALENTS``, tested column by column):

| memo | TPOINT | memo | TPOINT |
|---|---|---|---|
| a(1) | IA | b(1) | -IE |
| a(2) | CA | b(2) | -HESE |
| a(3) | NPAE | b(3) | TF |
| a(4) | HSSASE | b(4) | -HESA |
| a(5) | -HSCASE | b(5) | HECA |
| a(6) | -HASA2 | b(6) | HESA2 |
| a(7) | HACA2 | b(7) | TX |
"""

from __future__ import annotations

import math

__all__ = ["BIMA_TERMS", "WRIGHT_TERMS", "tilt_collimation_equivalents"]

#: the memo's 7 azimuth and 7 elevation terms, in TPOINT's names and the memo's order
BIMA_TERMS = ("IA", "CA", "NPAE", "HSSASE", "HSCASE", "HASA2", "HACA2",
              "IE", "HESE", "TF", "HESA", "HECA", "HESA2", "TX")
#: the same, by the memo's names a(1)..a(7), b(1)..b(7)
WRIGHT_TERMS = (*(f"A{i}" for i in range(1, 8)), *(f"B{i}" for i in range(1, 8)))


def tilt_collimation_equivalents(tilt_arcmin: float, tilt_az_deg: float,
                                 collimation_arcmin: float) -> dict[str, float]:
    """The linear (small-angle) BIMA-term coefficients, arcsec in TPOINT's sign, of an
    azimuth-axis tilt ``tilt_arcmin`` towards azimuth ``tilt_az_deg`` (N = 0) and a
    collimation error ``collimation_arcmin`` (the simulator's ``exact_tilt_collimation``):
    with AN = tilt cos(az_t), AW = -tilt sin(az_t) (TPOINT's: AN > 0 the pole north of the
    zenith, AW > 0 west of it), CA = -collimation, the memo's separate
    azimuth and elevation tilt terms are HSSASE = HECA = AN, HSCASE = -AW, HESA = AW (TPOINT's
    harmonic signs, :mod:`controller.pointing.terms`; tested against AN and AW)."""
    tilt = tilt_arcmin * 60.0
    phi = math.radians(tilt_az_deg)
    an = tilt * math.cos(phi)
    aw = -tilt * math.sin(phi)
    return {"HSSASE": an, "HECA": an, "HSCASE": -aw, "HESA": aw,
            "CA": -collimation_arcmin * 60.0}
