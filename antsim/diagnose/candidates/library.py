"""The library: every candidate, DESIGN section 5's signature table first, as data.

Each row names the simulator effect it reproduces, its title, signature and the physical
cause; :data:`CANDIDATES` is the library in the order the selection tries them, and
:func:`candidate` looks one up by name.
"""

from __future__ import annotations

from .base import Candidate
from .changes import StepCandidate
from .dynamics import BacklashCandidate, ClockCandidate, ServoLagCandidate
from .optics import BeamWidthCandidate, ExactTiltCandidate, SourceCandidate, SquintCandidate
from .terms import FeedOffsetCandidate, HarmonicFamilyCandidate, TermsCandidate
from .thermal import SunsetCandidate, SunsetTransientCandidate, TemperatureCandidate

__all__ = ["CANDIDATES", "candidate"]


def _harmonic(name: str, title: str, signature: str) -> TermsCandidate:
    from antsim.world.effects import EFFECTS

    cls = EFFECTS[name]
    return TermsCandidate(name, (cls.sin_term, cls.cos_term), title, signature,
                          cls.explanation, effect=name, signs=cls.signs)


IN_SPAN = "already in the 45-ft's ten-term model (W terms), so invisible with that baseline"

#: DESIGN's signature table, harmonic rows: simulator effect, title, signature
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

#: the rows of DESIGN's signature table that name two orders at once (one finding each:
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
    return lib


CANDIDATES: tuple[Candidate, ...] = tuple(_library())


def candidate(name: str) -> Candidate:
    """The library's candidate called ``name`` (KeyError naming the choices)."""
    for c in CANDIDATES:
        if c.name == name:
            return c
    raise KeyError(f"unknown candidate {name!r}; known: {', '.join(c.name for c in CANDIDATES)}")
