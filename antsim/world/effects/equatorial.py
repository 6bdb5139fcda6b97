"""Effects of an equatorial (polar) mount's structure, in hour angle and declination.

On an equatorial mount the world solves the pointing errors on the mount's own axes:
:class:`~.base.PointingState` ``az_rad``/``el_rad`` hold the hour angle (positive West) and
the declination there (:mod:`antsim.world.world`). The effects here are pairs of terms of
TPOINT's equatorial harmonic generator (:mod:`controller.pointing.equatorial`: ``HHSHCD`` is
the correction dH = +c sin H cos(dec)), written, like the alt-az harmonics
(:mod:`.harmonics`), as an amplitude and a phase; their model is bound to the mount's
latitude when the effect starts. Scenarios refuse them on an alt-az mount.

**Polar-drive torsion under the dish's imbalance** (``polar_torsion``). A hypothesis for
the 140-ft's excess right-ascension scatter (Crane 1981, summary item 3: "the rms error in
right ascension is twice as large ... as if the pointing equation used does not describe
the pointing"); the memo names no cause. The dish turns about the declination axis and is
balanced about it by ballast (the 140-ft's reflector carries 35 t of concrete ballast and
5 t of balancing blocks; NRAO's technical description of the 140-ft). When the balance is
off by a moment m d (a receiver, the subreflector or its backup structure changed: the memo's
sections I and V list such changes), the dish's centre of mass lies a distance d from the
declination axis, at an angle psi from the boresight towards the dish's north (increasing
declination). Its component perpendicular to the polar axis is d cos(dec + psi), and gravity
pulls on it with a torque about the polar axis

    tau = m g d cos(phi) cos(dec + psi) sin H      (in the sense of increasing H),

phi the latitude (derivation: the torque about the polar axis p of a weight at r is
m g cos(phi) times r's East-West component, and the hour circle's East component is -sin H).
The hour-angle drive (the 140-ft's 84-ft polar gear sector and its pinions, the yoke) holds
the dish against it and winds up by tau / K: the dish turns further towards the horizon than
the encoder reads,

    dH (indicated - true) = -W cos(dec + psi) sin H,   x = dH cos(dec),

W = m g d cos(phi) / K, the windup at the largest torque (``amplitude_arcsec``, arcsec of
hour angle), psi = ``phase_deg``. As a correction (TPOINT's sign) this is
HHSHCD = W cos(psi), HHSHSD = -W sin(psi). The same imbalance twists the declination drive
by a torque proportional to cos(psi) (sin(phi) cos(dec) - cos(phi) cos H sin(dec)) -
sin(psi) sin(E): for an imbalance along the boresight (psi = 0) exactly the tube-flexure
function that Crane's C11 carries, so the declination axis stays "well behaved" (summary
item 3); the effect leaves the declination drive out (stiff, or in C11). Crane's eleven
terms have x = sin H (C2) but not sin H cos^2(dec): an unbalanced dish leaves a pattern in
right ascension that no C can take.
"""

from __future__ import annotations

from typing import Any, ClassVar

from controller.pointing.equatorial import equatorial_model

from .base import Effect, Key
from .harmonics import HarmonicEffect

__all__ = ["EQUATORIAL_HARMONIC_EFFECTS", "EquatorialHarmonicEffect", "PolarTorsion"]


class EquatorialHarmonicEffect(HarmonicEffect):
    """A pair of equatorial harmonic terms as amplitude (arcsec) and phase (deg), see
    :class:`~.harmonics.HarmonicEffect`; the model is built when the effect starts, at the
    mount's latitude (its terms are those of :mod:`controller.pointing.equatorial`)."""

    def __init__(self, **params: Any):
        Effect.__init__(self, **params)
        self.model = None  # bound to the mount in start()

    def start(self, world, rng) -> None:
        if world.frame.is_altaz:
            raise ValueError(f"effect {self.name} models an equatorial mount")
        self.model = equatorial_model(self.terms, world.frame.latitude_deg,
                                      list(self.coefficients().values()), name=self.name)

    def truth(self) -> dict[str, Any]:
        out = super().truth()
        out["coefficients_arcsec"] = self.coefficients()
        return out


class PolarTorsion(EquatorialHarmonicEffect):
    """The hour-angle drive wound up by the dish's imbalance (module docstring)."""

    name: ClassVar[str] = "polar_torsion"
    #: the pair's terms: "sin_term" takes a cos(phase), "cos_term" a sin(phase) (the
    #: harmonic pair's convention), here the cos(dec) and sin(dec) parts
    sin_term: ClassVar[str] = "HHSHCD"
    cos_term: ClassVar[str] = "HHSHSD"
    signs: ClassVar[tuple[float, float]] = (1.0, -1.0)
    explanation: ClassVar[str] = (
        "the dish is out of balance about the declination axis: gravity's torque about the "
        "polar axis, proportional to cos(dec + psi) sin H, winds up the hour-angle drive, so "
        "the dish turns further towards the horizon than the encoder reads"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "amplitude_arcsec": Key(0.0, "hour-angle windup at the largest torque, W (arcsec "
                                     "of hour angle)"),
        "phase_deg": Key(0.0, "direction psi of the dish's centre of mass from the "
                              "boresight towards the dish's north (deg)"),
    }


#: the equatorial harmonic effects
EQUATORIAL_HARMONIC_EFFECTS: tuple[type[EquatorialHarmonicEffect], ...] = (PolarTorsion,)
