"""Harmonic pointing errors written as an amplitude and a phase, and the feed offset.

Each harmonic effect is a pair of TPOINT harmonic terms (``H`` + result letter + ``S``/``C``
factor, see :mod:`controller.pointing.terms`) that share an argument, parametrised by an amplitude
``a`` (arcsec) and a phase ``phi`` (deg). The effect is the correction (TPOINT's sign: true =
indicated + correction), in the axis of the result letter (dA for ``A``, dE for ``E``),

    a sin(nX + phi) = a cos(phi) sin nX + a sin(phi) cos nX,

with ``X`` the elevation or ``A_N - 180 deg``, the azimuth counted from South through West,
in which these effects' phases are given. TPOINT's harmonic generator uses its own azimuth
``A_T = 180 deg - A_N`` (South = 0, East = 90) and negates ``A`` results
(:mod:`controller.pointing.terms`); since sin nX = -sin nA_T and cos nX = cos nA_T for every
n, the pair's coefficients are ``s_sin a cos(phi)`` and ``s_cos a sin(phi)`` with the signs
``signs`` below: (-1, +1) for an elevation result (HESA2 = -a cos phi), (+1, -1) for an
azimuth result (dA = -c cos nA_T: HACA = -a sin phi), (+1, +1) for the elevation harmonics.
The error the antenna makes (indicated minus true) is minus the correction, as for every
geometric effect.

| effect | terms | physical cause |
|---|---|---|
| ``az_track_2a`` | HESA2, HECA2 | an uneven azimuth track nods the elevation axis, 2/turn |
| ``az_track_3a`` | HESA3, HECA3 | the same, three times per turn |
| ``az_runout_1a`` | HASA, HACA | azimuth encoder mounted off the axis (runout): once per turn |
| ``az_runout_2a`` | HASA2, HACA2 | an elliptical azimuth encoder or gear: twice per turn |
| ``el_nod_1a`` | HESA, HECA | elevation nod once per turn (a bent track or a tilted bearing race) |
| ``el_eccentricity`` | HESE, HECE | elevation encoder off its axis: once per elevation turn |
| ``el_eccentricity_2e`` | HESE2, HECE2 | elliptical elevation encoder or gear: twice per turn |

The feed offset (Fomalont 1973): a feed displaced from the focus by ``offset_arcsec`` (on the
sky) at position angle ``angle_deg`` (C7) relative to the feed angle f moves the beam by
``(xel, el) = offset * (cos(f - C7), sin(f - C7))``. With a fixed feed this is a collimation
pair (CA and IE); with a rotating feed (a Nasmyth rotator) it turns with f. Fomalont's own,
more general form (``form = "fomalont"``) gives each axis its own amplitude and phase:
``xel = C6 cos(f - C7)``, ``el = D6 cos(f - D7)`` (``offset_arcsec`` = C6, ``angle_deg`` = C7,
``el_offset_arcsec`` = D6, ``el_angle_deg`` = D7); the rigid displacement is D6 = C6,
D7 = C7 + 90 deg. Either is linear in cos f and sin f: the feed terms HSCF, HSSF, HECF, HESF
of the term library (:meth:`FeedOffset.coefficients`; HSCF and HSSF are dA cos E = -c cos f,
-c sin f, HECF and HESF are dE = +c cos f, +c sin f).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

from controller.pointing.model import PointingModel
from controller.units import RAD_PER_ARCSEC

from .base import Effect, Key, PointingState

__all__ = [
    "HARMONIC_EFFECTS",
    "AzimuthRunout1A",
    "AzimuthRunout2A",
    "AzimuthTrack2A",
    "AzimuthTrack3A",
    "ElevationEccentricity",
    "ElevationEccentricity2E",
    "ElevationNod1A",
    "FeedOffset",
    "HarmonicEffect",
]


class HarmonicEffect(Effect):
    """A pair of harmonic terms as amplitude (arcsec) and phase (deg); see the module."""

    sin_term: ClassVar[str] = ""
    cos_term: ClassVar[str] = ""
    #: TPOINT coefficient of (sin_term, cos_term) per unit of the correction's sine and cosine
    #: parts, a cos(phi) and a sin(phi) (see the module docstring; tested against the terms)
    signs: ClassVar[tuple[float, float]] = (1.0, 1.0)
    PARAMS: ClassVar[dict[str, Key]] = {
        "amplitude_arcsec": Key(0.0, "amplitude of the harmonic (arcsec)"),
        "phase_deg": Key(0.0, "phase: the correction is a sin(nX + phase), X = E or the "
                         "azimuth A - 180 deg (South = 0, West = 90)"),
    }

    def __init__(self, **params: Any):
        super().__init__(**params)
        self.model = PointingModel(self.terms, list(self.coefficients().values()),
                                   name=self.name)

    @property
    def terms(self) -> tuple[str, ...]:  # type: ignore[override]
        return (self.sin_term, self.cos_term)

    def coefficients(self) -> dict[str, float]:
        """TPOINT coefficients (arcsec) of the sine and cosine terms."""
        a = float(self.p["amplitude_arcsec"])
        phi = math.radians(float(self.p["phase_deg"]))
        s_sin, s_cos = self.signs
        return {self.sin_term: s_sin * a * math.cos(phi),
                self.cos_term: s_cos * a * math.sin(phi)}

    @classmethod
    def amplitude_phase(cls, sin_coeff: float, cos_coeff: float) -> tuple[float, float]:
        """Inverse of :meth:`coefficients`: (amplitude arcsec >= 0, phase deg in [0, 360))."""
        s_sin, s_cos = cls.signs
        return math.hypot(sin_coeff, cos_coeff), math.degrees(
            math.atan2(s_cos * cos_coeff, s_sin * sin_coeff)) % 360.0

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        return self.model.offset_scalar_rad(state.az_rad, state.el_rad)

    block_error = pointing_error  # offset_scalar_rad is elementwise on arrays


class AzimuthTrack2A(HarmonicEffect):
    name: ClassVar[str] = "az_track_2a"
    sin_term: ClassVar[str] = "HESA2"
    cos_term: ClassVar[str] = "HECA2"
    signs: ClassVar[tuple[float, float]] = (-1.0, 1.0)
    explanation: ClassVar[str] = (
        "the azimuth track (the rail the wheels run on) is uneven: as the antenna turns, the "
        "elevation axis rocks, twice per turn, so elevation errors vary as sin 2A and cos 2A"
    )


class AzimuthTrack3A(HarmonicEffect):
    name: ClassVar[str] = "az_track_3a"
    sin_term: ClassVar[str] = "HESA3"
    cos_term: ClassVar[str] = "HECA3"
    signs: ClassVar[tuple[float, float]] = (-1.0, 1.0)
    explanation: ClassVar[str] = (
        "the azimuth track is uneven with three high points per turn: elevation errors vary "
        "as sin 3A and cos 3A"
    )


class AzimuthRunout1A(HarmonicEffect):
    name: ClassVar[str] = "az_runout_1a"
    sin_term: ClassVar[str] = "HASA"
    cos_term: ClassVar[str] = "HACA"
    signs: ClassVar[tuple[float, float]] = (1.0, -1.0)
    explanation: ClassVar[str] = (
        "the azimuth encoder is not centred on the axis (runout): the azimuth reading is off "
        "by an amount that varies once per turn, sin A and cos A"
    )


class AzimuthRunout2A(HarmonicEffect):
    name: ClassVar[str] = "az_runout_2a"
    sin_term: ClassVar[str] = "HASA2"
    cos_term: ClassVar[str] = "HACA2"
    signs: ClassVar[tuple[float, float]] = (1.0, -1.0)
    explanation: ClassVar[str] = (
        "the azimuth encoder (or its gear) is elliptical: the azimuth reading is off by an "
        "amount that varies twice per turn, sin 2A and cos 2A"
    )


class ElevationNod1A(HarmonicEffect):
    name: ClassVar[str] = "el_nod_1a"
    sin_term: ClassVar[str] = "HESA"
    cos_term: ClassVar[str] = "HECA"
    signs: ClassVar[tuple[float, float]] = (-1.0, 1.0)
    explanation: ClassVar[str] = (
        "the elevation axis nods once per azimuth turn (a bent track or a tilted bearing "
        "race): elevation errors vary as sin A and cos A without the azimuth part of a tilt"
    )


class ElevationEccentricity(HarmonicEffect):
    name: ClassVar[str] = "el_eccentricity"
    sin_term: ClassVar[str] = "HESE"
    cos_term: ClassVar[str] = "HECE"
    explanation: ClassVar[str] = (
        "the elevation encoder is not centred on its axis: the elevation reading is off by an "
        "amount that varies once per turn of the elevation axis, sin E and cos E"
    )


class ElevationEccentricity2E(HarmonicEffect):
    name: ClassVar[str] = "el_eccentricity_2e"
    sin_term: ClassVar[str] = "HESE2"
    cos_term: ClassVar[str] = "HECE2"
    explanation: ClassVar[str] = (
        "the elevation encoder (or its gear) is elliptical: the elevation reading is off by "
        "an amount that varies twice per turn of the elevation axis, sin 2E and cos 2E"
    )


class FeedOffset(Effect):
    """A feed displaced from the focus; see the module docstring (Fomalont 1973)."""

    name: ClassVar[str] = "feed_offset"
    terms: ClassVar[tuple[str, ...]] = ("CA", "IE")
    explanation: ClassVar[str] = (
        "the feed is displaced from the focus, so the beam points off the optical axis in a "
        "fixed direction relative to the feed: a collimation error that turns with the feed "
        "angle"
    )
    FORMS: ClassVar[tuple[str, ...]] = ("rigid", "fomalont")
    PARAMS: ClassVar[dict[str, Key]] = {
        "offset_arcsec": Key(0.0, "beam displacement on the sky (arcsec)", min=0.0),
        "angle_deg": Key(0.0, "direction C7 relative to the feed angle (deg)"),
        "form": Key("rigid", "'rigid' (a displaced feed) or 'fomalont' (C6, C7, D6, D7)",
                    kind="string", choices=FORMS),
        "el_offset_arcsec": Key(0.0, "form 'fomalont': elevation amplitude D6 (arcsec)",
                                min=0.0),
        "el_angle_deg": Key(0.0, "form 'fomalont': elevation phase D7 (deg)"),
    }
    FEED_TERMS: ClassVar[tuple[str, ...]] = ("HSCF", "HSSF", "HECF", "HESF")

    def _fomalont(self) -> tuple[float, float, float, float]:
        """(C6, C7, D6, D7), arcsec and radians, whatever the form."""
        c6, c7 = self.p["offset_arcsec"], math.radians(self.p["angle_deg"])
        if self.p.get("form", "rigid") == "fomalont":
            return c6, c7, self.p["el_offset_arcsec"], math.radians(self.p["el_angle_deg"])
        return c6, c7, c6, c7 + 0.5 * math.pi

    def coefficients(self) -> dict[str, float]:
        """The feed terms' TPOINT-sign coefficients (arcsec). The correction is minus the
        error; HSCF and HSSF are dA cos E = -c cos f, -c sin f and HECF and HESF are
        dE = +c cos f, +c sin f, so HSCF = C6 cos C7, HSSF = C6 sin C7, HECF = -D6 cos D7,
        HESF = -D6 sin D7."""
        c6, c7, d6, d7 = self._fomalont()
        return {"HSCF": c6 * math.cos(c7), "HSSF": c6 * math.sin(c7),
                "HECF": -d6 * math.cos(d7), "HESF": -d6 * math.sin(d7)}

    def truth(self) -> dict[str, Any]:
        out = super().truth()
        if self.p.get("form", "rigid") == "fomalont":
            out["terms"] = list(self.FEED_TERMS)
            out["coefficients_arcsec"] = self.coefficients()
        return out

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        if self.p.get("form", "rigid") == "fomalont":
            c6, c7, d6, d7 = self._fomalont()
            f = state.feed_angle_rad
            return (c6 * RAD_PER_ARCSEC * math.cos(f - c7) / math.cos(state.el_rad),
                    d6 * RAD_PER_ARCSEC * math.cos(f - d7))
        r = self.p["offset_arcsec"] * RAD_PER_ARCSEC
        ang = state.feed_angle_rad - math.radians(self.p["angle_deg"])
        return r * math.cos(ang) / math.cos(state.el_rad), r * math.sin(ang)


#: the harmonic effects, in the order of the module's table
HARMONIC_EFFECTS: tuple[type[HarmonicEffect], ...] = (
    AzimuthTrack2A, AzimuthTrack3A, AzimuthRunout1A, AzimuthRunout2A, ElevationNod1A,
    ElevationEccentricity, ElevationEccentricity2E,
)
