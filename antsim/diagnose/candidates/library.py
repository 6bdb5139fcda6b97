"""The library: every candidate, docs/physics.md's signature table first, as data.

Each row names the simulator effect it reproduces, its title, signature and the physical
cause; :data:`CANDIDATES` is the library in the order the selection tries them, and
:func:`candidate` looks one up by name. An equatorial mount's rows (its TPOINT terms, the
polar drive's torsion, harmonic families in hour angle and declination) come last; each
candidate is tried only on recordings of the mounts it names (``Candidate.mounts``).
"""

from __future__ import annotations

from antsim.world.effects import EFFECTS

from .base import Candidate
from .changes import StepCandidate
from .dynamics import BacklashCandidate, ClockCandidate, ServoLagCandidate
from .optics import BeamWidthCandidate, ExactTiltCandidate, SourceCandidate, SquintCandidate
from .terms import FeedOffsetCandidate, HarmonicFamilyCandidate, TermsCandidate
from .thermal import (
    SensorTermsCandidate,
    SunsetCandidate,
    SunsetTransientCandidate,
    TemperatureCandidate,
)

__all__ = ["CANDIDATES", "candidate"]


def _harmonic(name: str, title: str, signature: str,
              mounts: tuple[str, ...] = ("altaz",)) -> TermsCandidate:
    cls = EFFECTS[name]
    return TermsCandidate(name, (cls.sin_term, cls.cos_term), title, signature,
                          cls.explanation, effect=name, signs=cls.signs, mounts=mounts)


IN_SPAN = "already in the 45-ft's ten-term model (W terms), so invisible with that baseline"

#: docs/physics.md's signature table, harmonic rows: simulator effect, title, signature
HARMONIC_ROWS = (
    ("az_track_2a", "azimuth track unevenness (twice per turn)",
     "dE ~ sin 2A, cos 2A (BIMA memo 23 saw 6\" rms)"),
    ("az_track_3a", "azimuth track unevenness (three times per turn)", "dE ~ sin 3A, cos 3A"),
    ("az_runout_1a", "azimuth encoder runout (once per turn)", "dA ~ sin A, cos A"),
    ("az_runout_2a", "azimuth encoder runout (twice per turn)", "dA ~ sin 2A, cos 2A"),
    ("el_nod_1a", "elevation nod (once per azimuth turn)", "dE ~ sin A, cos A"),
    ("el_eccentricity", "elevation encoder eccentricity (once per turn)", "dE ~ sin E, cos E"),
    ("el_eccentricity_2e", "elevation encoder eccentricity (twice per turn)",
     "dE ~ sin 2E, cos 2E"),
)

#: the rows of docs/physics.md's signature table that name two orders at once (one finding each:
#: an encoder both eccentric and elliptical, a track with two and three high points)
TWO_ORDER_ROWS = (
    ("az_runout_1a_2a", ("HASA", "HACA", "HASA2", "HACA2"),
     "azimuth encoder runout (once and twice per turn)", "dA ~ sin A, cos A, sin 2A, cos 2A",
     "the azimuth encoder (or its gear) is both off-centre and elliptical: the azimuth "
     "reading is off by an amount that varies once and twice per turn"),
    ("az_track_2a_3a", ("HESA2", "HECA2", "HESA3", "HECA3"),
     "azimuth track unevenness (twice and three times per turn)",
     "dE ~ sin 2A, cos 2A, sin 3A, cos 3A",
     "the azimuth track has two and three high points per turn: the whole mount nods in "
     "elevation as it rolls over them"),
)

#: TPOINT's harmonic generator as families with an unknown number of cycles n per turn:
#: name, result (E: dE, A: dA, S: dA cos E), argument (A or E), orders, title, signature,
#: physical cause
HARMONIC_FAMILIES = (
    ("el_periodic_el", "E", "E", range(3, 9),
     "periodic elevation error along the elevation axis (n cycles per turn)",
     "dE ~ sin nE, cos nE (n = 3..8)",
     "a gear, encoder or lookup-table error that repeats n times per turn of the elevation "
     "axis (e.g. an optics collimation table sampled in elevation)"),
    ("xel_periodic_el", "S", "E", range(1, 9),
     "cross-elevation error varying with elevation (n cycles per turn)",
     "dA cos E ~ sin nE, cos nE (n = 1..8)",
     "a collimation that changes with elevation: the optics (secondary, feed or instrument) "
     "shift sideways as the tube tips"),
    ("el_periodic_az", "E", "A", range(4, 9),
     "azimuth track unevenness of higher order (n cycles per turn)",
     "dE ~ sin nA, cos nA (n = 4..8)",
     "the azimuth track has n high points per turn (segments, joints of the rail)"),
    ("az_periodic_az", "A", "A", range(3, 9),
     "azimuth encoder or gear periodic error of higher order (n cycles per turn)",
     "dA ~ sin nA, cos nA (n = 3..8)",
     "an azimuth encoder, pinion or bull-gear error that repeats n times per turn"),
)


EQUATORIAL = ("equatorial",)

#: an equatorial mount's rows (TPOINT's equatorial vocabulary, controller.pointing.equatorial;
#: x = dH cos(dec), the cross-declination error): the simulator effect's harmonic pairs
EQUATORIAL_HARMONIC_ROWS = (
    ("polar_torsion", "polar-drive torsion under the dish's imbalance",
     "x ~ sin H cos(dec) cos(dec + psi): dH ~ sin H cos(dec), sin H sin(dec) (HHSHCD, "
     "HHSHSD)"),
)

#: an equatorial mount's geometry and flexure as TPOINT terms: name, terms, title, signature,
#: physical cause, whether the two terms are one harmonic pair (amplitude and phase)
EQUATORIAL_TERM_ROWS = (
    ("ha_index", ("IH",), "hour-angle encoder zero", "dH constant (x ~ cos dec)",
     "the hour-angle encoder's zero point (or the program's sidereal time) is off", False),
    ("dec_index", ("ID",), "declination encoder zero", "dDec constant",
     "the declination encoder's zero point is off", False),
    ("ew_collimation", ("CH",), "east-west collimation", "x constant (dH ~ sec dec)",
     "the beam is not perpendicular to the declination axis", False),
    ("ha_dec_nonperpendicularity", ("NP",), "polar and declination axes not perpendicular",
     "x ~ sin dec (dH ~ tan dec)",
     "the declination axis is not perpendicular to the polar axis", False),
    ("polar_axis_misalignment", ("MA", "ME"), "polar axis misaligned",
     "dH ~ cos H tan dec, sin H tan dec; dDec ~ sin H, cos H",
     "the polar axis does not point at the pole: to its left or right (MA) or above or "
     "below it (ME)", False),
    ("tube_flexure", ("TF",), "tube flexure", "sin Z law on both axes (TF)",
     "the tube (dish and feed support) bends under its own weight, most when horizontal",
     False),
    ("refraction_tan_z", ("TX",), "refraction error or tan Z flexure",
     "tan Z law on both axes (TX)",
     "the refraction the controller corrects differs from the refraction present, or the "
     "tube bends as tan Z", False),
    ("fork_flexure", ("FO",), "fork (yoke) flexure", "dDec ~ cos H",
     "the yoke's arms bend under the dish's weight as the polar axis turns", False),
    ("dec_axis_flexure", ("DAF",), "declination-axis flexure",
     "dH ~ cos(phi) cos H + sin(phi) tan dec",
     "the declination shaft bends under the weight it carries (on a counterweighted mount, "
     "the tube and its counterweight)", False),
    ("ha_encoder_eccentricity", ("HCES", "HCEC"), "hour-angle encoder eccentricity",
     "dH ~ sin H, cos H",
     "the hour-angle encoder (or the polar gear) is off the polar axis: the reading is off "
     "by an amount that varies once per turn", True),
    ("dec_encoder_eccentricity", ("DCES", "DCEC"), "declination encoder eccentricity",
     "dDec ~ sin dec, cos dec",
     "the declination encoder (or its gear) is off the declination axis: once per turn",
     True),
)

#: an equatorial mount's harmonic families (as HARMONIC_FAMILIES below; result H: dH,
#: D: dDec, X: dH cos dec; argument H: hour angle, D: declination)
EQUATORIAL_FAMILIES = (
    ("ha_periodic_ha", "H", "H", range(2, 9),
     "periodic hour-angle error along the polar axis (n cycles per turn)",
     "dH ~ sin nH, cos nH (n = 2..8)",
     "a polar gear, pinion or encoder error that repeats n times per turn of the polar axis"),
    ("dec_periodic_ha", "D", "H", range(1, 9),
     "declination error varying with hour angle (n cycles per turn)",
     "dDec ~ sin nH, cos nH (n = 1..8)",
     "the declination axis nods as the polar axis turns: a bent polar shaft, an uneven "
     "bearing or a yoke that flexes"),
    ("dec_periodic_dec", "D", "D", range(2, 9),
     "periodic declination error along the declination axis (n cycles per turn)",
     "dDec ~ sin n dec, cos n dec (n = 2..8)",
     "a declination gear or encoder error that repeats n times per turn of the declination "
     "axis"),
    ("xdec_periodic_dec", "X", "D", range(1, 9),
     "cross-declination error varying with declination (n cycles per turn)",
     "dH cos dec ~ sin n dec, cos n dec (n = 1..8)",
     "a collimation that changes with declination: the optics shift sideways as the dish "
     "turns about the declination axis"),
)


def _equatorial_rows() -> list[Candidate]:
    lib: list[Candidate] = [_harmonic(*row, mounts=EQUATORIAL)
                            for row in EQUATORIAL_HARMONIC_ROWS]
    lib += [TermsCandidate(name, terms, title, signature, cause, pair=pair, mounts=EQUATORIAL)
            for name, terms, title, signature, cause, pair in EQUATORIAL_TERM_ROWS]
    lib += [HarmonicFamilyCandidate(*row, mounts=EQUATORIAL) for row in EQUATORIAL_FAMILIES]
    return lib


def _library() -> list[Candidate]:
    lib: list[Candidate] = [_harmonic(*row) for row in HARMONIC_ROWS]
    lib += [TermsCandidate(name, terms, title, signature, cause, pair=False)
            for name, terms, title, signature, cause in TWO_ORDER_ROWS]
    lib += [
        TermsCandidate("gravity", ("TF",), "gravitational sag", "dE ~ cos E",
                       "the tube (dish and feed support) bends under its own weight, most "
                       "when horizontal", pair=False, blind_exclusion=IN_SPAN + " (W4)"),
        TermsCandidate("refraction", ("TX",), "refraction error", "dE ~ cot E",
                       "the refraction the controller corrects differs from the refraction "
                       "present (wrong weather data or formula)", pair=False,
                       blind_exclusion=IN_SPAN + " (W5)"),
        TermsCandidate("encoder_zero", ("IA", "IE"), "encoder zero points",
                       "dA constant, dE constant",
                       "the encoders' zero points are off", pair=False,
                       blind_exclusion=IN_SPAN + " (W1, W6)"),
        TermsCandidate("collimation", ("CA",), "collimation error", "dA ~ sec E (xel constant)",
                       "the beam is not perpendicular to the elevation axis", pair=False,
                       blind_exclusion=IN_SPAN + " (W10)"),
        TermsCandidate("non_perpendicularity", ("NPAE",), "axis non-perpendicularity",
                       "dA ~ tan E", "the elevation axis is not perpendicular to the azimuth "
                       "axis", pair=False, blind_exclusion=IN_SPAN + " (W9)"),
        TermsCandidate("azimuth_axis_tilt", ("AN", "AW"), "azimuth axis tilt",
                       "dE ~ cos A, sin A; dA ~ tan E sin A, tan E cos A",
                       "the azimuth axis is not vertical", pair=False,
                       blind_exclusion=IN_SPAN + " (W2, W3, W7, W8)"),
    ]
    lib += [HarmonicFamilyCandidate(*row) for row in HARMONIC_FAMILIES]
    lib += [
        FeedOffsetCandidate(),
        SunsetCandidate(),
        SunsetTransientCandidate(),
        TemperatureCandidate(),
        SensorTermsCandidate(),
        StepCandidate(),
        ClockCandidate(),
        ServoLagCandidate(),
        BacklashCandidate(),
        SquintCandidate(),
        SourceCandidate(),
        BeamWidthCandidate(),
        ExactTiltCandidate(),
    ]
    for c in lib:
        if isinstance(c, TermsCandidate) and c.name in ("el_nod_1a",):
            c.blind_exclusion = IN_SPAN + " (W2, W3)"
    return lib + _equatorial_rows()


CANDIDATES: tuple[Candidate, ...] = tuple(_library())


def candidate(name: str) -> Candidate:
    """The library's candidate called ``name`` (KeyError naming the choices)."""
    for c in CANDIDATES:
        if c.name == name:
            return c
    raise KeyError(f"unknown candidate {name!r}; known: {', '.join(c.name for c in CANDIDATES)}")
