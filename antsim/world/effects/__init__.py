"""The catalogue of physical effects, all behind one interface (:class:`Effect`).

One family per module: :mod:`.base` (the interface), :mod:`.geometric` (pointing-model
terms), :mod:`.harmonics` (harmonic errors, the feed offset), :mod:`.thermal` (solar heating,
sunset drift), :mod:`.drifts` (temperature drift), :mod:`.tracking` (wind and servo jitter),
:mod:`.dynamics` (clock, servo lag, backlash), :mod:`.steps` (a change at one instant),
:mod:`.optics` (squint, beam width, source structure, refraction anomaly, exact tilt and
collimation), :mod:`.equatorial` (an equatorial mount's structure: the polar drive's
torsion). :data:`EFFECTS` names them as scenarios do.
"""

from __future__ import annotations

from .base import Effect, Key, PointingState
from .drifts import TemperatureDrift
from .dynamics import Backlash, ClockError, ServoLag
from .equatorial import EQUATORIAL_HARMONIC_EFFECTS
from .geometric import GeometricEffect, TermsEffect
from .harmonics import HARMONIC_EFFECTS, FeedOffset
from .optics import (
    BeamWidthError,
    ExactTiltCollimation,
    PolarizationSquint,
    RefractionAnomaly,
    SourceStructure,
)
from .steps import Step
from .thermal import SunsetDrift, ThermalEffect
from .tracking import TrackingJitter

__all__ = ["EFFECTS", "Effect", "GeometricEffect", "Key", "PointingState"]

#: effect name (as written in scenarios) -> class
EFFECTS: dict[str, type[Effect]] = {
    cls.name: cls
    for cls in (
        TermsEffect,
        ThermalEffect,
        SunsetDrift,
        TrackingJitter,
        ClockError,
        ServoLag,
        Backlash,
        PolarizationSquint,
        BeamWidthError,
        SourceStructure,
        RefractionAnomaly,
        ExactTiltCollimation,
        *HARMONIC_EFFECTS,
        *EQUATORIAL_HARMONIC_EFFECTS,
        FeedOffset,
        TemperatureDrift,
        Step,
    )
}
