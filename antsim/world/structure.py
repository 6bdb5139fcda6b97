"""How the 45-ft's structure turns temperature differences into pointing errors.

Differential expansion of two members of a structure (steel: 12e-6 per kelvin) moves or turns
what they carry. The geometry below is that of a prime-focus alt-azimuth antenna of 13.7 m
(the 1990 report's "45-foot (13.7 m)"); every other dimension is an assumption
(``docs/physics.md`` gives each with its range), and the pointing per kelvin follows from it:

* **feed legs** (a quadripod from the rim to the prime focus): one leg longer by ``dL``
  pushes the feed away from its foot, ``dL / (2 sin phi)`` across the axis (``phi`` the
  legs' angle from the axis: the two opposite legs are a bipod), and the beam moves the
  other way by the beam deviation factor (Ruze 1965, Lo's form with ``kappa = 0.36``) over
  the focal length. The upper leg longer than the lower (with the dish at the horizon)
  raises the beam: ``dE = -alpha L BDF / (2 F sin phi)`` per kelvin; the right leg (towards
  increasing azimuth) longer moves it right: ``dA cos E`` the same per kelvin;
* **yoke arms bowing**: an arm of height ``H`` and depth ``w`` whose front face is warmer
  than its back bends with a curvature ``alpha dT / w``; its top, which holds the elevation
  bearing and encoder, turns back by ``alpha H dT / w`` and the beam rises with it:
  ``dE = -alpha H / w`` per kelvin of front-minus-back;
* **yoke arms rolling the elevation axis**: the right arm longer by ``alpha H dT`` tilts the
  elevation axis by that over the arms' separation ``S``, right end up: the beam moves left by
  that times ``sin E``, ``dA cos E = +alpha H / S sin E`` per kelvin of right-minus-left
  (the shape of W9, the axes' non-perpendicularity);
* **pedestal tilt**: a cylinder of height ``P`` and diameter ``Dp`` warmer on one side by
  ``dT`` leans away from it by ``alpha P dT / Dp`` (beam theory for a thin-walled tube whose
  temperature goes as the cosine around it), an azimuth-axis tilt.

Signs are the report's, indicated minus true. Published coefficients to compare with: the
JCMT (15 m) corrects its elevation by 6.5" +- 0.6" per kelvin of front-minus-back leg
difference, expects 2.4" per kelvin of roll of the elevation axis from side-to-side
differences and about 3" per kelvin of linear gradient across its primary (JCMT pointing
error budget, JAC Pointing Note 6.1, citing MT282).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from controller.units import ARCSEC_PER_RAD

__all__ = ["JCMT_ARCSEC_PER_K", "STEEL_EXPANSION_PER_K", "Structure", "beam_deviation_factor"]

#: linear expansion of structural steel (1/K)
STEEL_EXPANSION_PER_K = 12e-6
#: Lo's constant in the beam deviation factor of a paraboloid (Ruze 1965)
BDF_KAPPA = 0.36
#: the JCMT's published coefficients (arcsec per kelvin): elevation per kelvin of its legs'
#: front-minus-back difference (empirical, 6.5 +- 0.6), roll of the elevation axis per
#: kelvin side to side, and pointing per kelvin of linear gradient across the primary
JCMT_ARCSEC_PER_K = {"legs_front_back": 6.5, "yoke_roll": 2.4, "dish_gradient": 3.0}


def beam_deviation_factor(diameter_m: float, focal_length_m: float,
                          kappa: float = BDF_KAPPA) -> float:
    """How far the beam of a paraboloid turns per angle its feed is displaced by (as seen
    from the vertex): ``(1 + kappa (D/4F)^2) / (1 + (D/4F)^2)`` (Ruze 1965): 0.82 at
    F/D = 0.4."""
    q = (diameter_m / (4.0 * focal_length_m)) ** 2
    return (1.0 + kappa * q) / (1.0 + q)


@dataclass(frozen=True)
class Structure:
    """The dimensions of the antenna (m) and its steel's expansion (1/K); the pointing per
    kelvin of each member pair follows (arcsec per kelvin, indicated minus true)."""

    diameter_m: float = 13.7
    focal_length_m: float = 5.5
    yoke_height_m: float = 3.0
    yoke_depth_m: float = 1.0
    yoke_separation_m: float = 4.0
    pedestal_height_m: float = 5.0
    pedestal_diameter_m: float = 2.5
    expansion_per_k: float = STEEL_EXPANSION_PER_K

    # ------------------------------------------------------------------ the feed legs
    @property
    def rim_depth_m(self) -> float:
        """Depth of the paraboloid at its rim (m): R^2 / 4F."""
        return (0.5 * self.diameter_m) ** 2 / (4.0 * self.focal_length_m)

    @property
    def leg_angle_rad(self) -> float:
        """The feed legs' angle from the axis (rad): from the rim (R, R^2/4F) to the focus."""
        return math.atan2(0.5 * self.diameter_m, self.focal_length_m - self.rim_depth_m)

    @property
    def leg_length_m(self) -> float:
        """Length of a feed leg from the rim to the focus (m)."""
        return math.hypot(0.5 * self.diameter_m, self.focal_length_m - self.rim_depth_m)

    @property
    def leg_arcsec_per_k(self) -> float:
        """Beam movement per kelvin of a leg over its opposite (arcsec, in the direction of
        the warmer leg's foot: the beam turns towards it, so the error is minus this)."""
        shift_m = self.expansion_per_k * self.leg_length_m / (2.0 * math.sin(self.leg_angle_rad))
        bdf = beam_deviation_factor(self.diameter_m, self.focal_length_m)
        return bdf * shift_m / self.focal_length_m * ARCSEC_PER_RAD

    @property
    def legs_el_arcsec_per_k(self) -> float:
        """dE per kelvin of the upper leg over the lower (arcsec/K): the beam rises."""
        return -self.leg_arcsec_per_k

    @property
    def legs_xel_arcsec_per_k(self) -> float:
        """dA cos E per kelvin of the right leg over the left (arcsec/K)."""
        return -self.leg_arcsec_per_k

    # ------------------------------------------------------------------ the yoke
    @property
    def yoke_bow_arcsec_per_k(self) -> float:
        """dE per kelvin of the arms' front face over their back face (arcsec/K)."""
        return -self.expansion_per_k * self.yoke_height_m / self.yoke_depth_m * ARCSEC_PER_RAD

    @property
    def yoke_roll_arcsec_per_k(self) -> float:
        """dA cos E / sin E per kelvin of the right arm over the left (arcsec/K)."""
        return self.expansion_per_k * self.yoke_height_m / self.yoke_separation_m \
            * ARCSEC_PER_RAD

    # ------------------------------------------------------------------ the pedestal
    @property
    def pedestal_tilt_arcsec_per_k(self) -> float:
        """Tilt of the azimuth axis away from the warmer side per kelvin across the
        pedestal (arcsec/K)."""
        return self.expansion_per_k * self.pedestal_height_m / self.pedestal_diameter_m \
            * ARCSEC_PER_RAD

    def coefficients(self) -> dict[str, float]:
        """Every pair's pointing per kelvin (arcsec/K), by the pair's name."""
        return {"legs_el": self.legs_el_arcsec_per_k, "legs_xel": self.legs_xel_arcsec_per_k,
                "yoke_bow": self.yoke_bow_arcsec_per_k,
                "yoke_roll": self.yoke_roll_arcsec_per_k,
                "pedestal_tilt": self.pedestal_tilt_arcsec_per_k}
