"""The catalogue of physical effects, all behind one interface (:class:`Effect`)."""

from __future__ import annotations

from .base import Effect, Param, PointingState
from .drifts import TemperatureDrift
from .dynamics import Backlash, ClockError, ServoLag
from .geometric import GeometricEffect, TermsEffect
from .harmonics import HARMONIC_EFFECTS, FeedOffset
from .optics import (
    BeamWidthError,
    ExactTiltCollimation,
    PolarizationSquint,
    RefractionAnomaly,
    SourceStructure,
)
from .thermal import SunsetDrift, ThermalEffect
from .tracking import TrackingJitter

__all__ = ["EFFECTS", "Effect", "GeometricEffect", "Param", "PointingState"]

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
        FeedOffset,
        TemperatureDrift,
    )
}
