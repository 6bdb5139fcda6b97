"""Radio sources fixed on the sky: positions in FK4 (B1950), FK5 or ICRS, and the 1990 run's
catalogue."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from .values import finite_fields

__all__ = ["GHIGO1990_SOURCES", "FixedSource", "dec_dms_to_deg", "ra_hms_to_deg"]

_SUPPORTED_FRAMES = ("fk4", "fk5", "icrs")


_SEXAGESIMAL = re.compile(
    r"^\s*([+-]?)\s*(\d+(?:\.\d*)?)\s*[hd:\s]\s*(\d+(?:\.\d*)?)\s*[m:'\s]\s*"
    r"(\d+(?:\.\d*)?)\s*[s\"]?\s*$"
)


def _parse_sexagesimal(text: str, what: str, example: str) -> tuple[float, float, float, float]:
    match = _SEXAGESIMAL.match(str(text))
    if match is None:
        raise ValueError(f"{what} {text!r} is not sexagesimal; write it like {example!r}.")
    sign = -1.0 if match.group(1) == "-" else 1.0
    return sign, float(match.group(2)), float(match.group(3)), float(match.group(4))


def ra_hms_to_deg(text: str) -> float:
    """Right ascension ``"03h16m29.57s"`` (or ``"03:16:29.57"``, ``"03 16 29.57"``) in degrees."""
    sign, hours, minutes, seconds = _parse_sexagesimal(text, "right ascension", "03h16m29.57s")
    if sign < 0 or hours >= 24.0 or minutes >= 60.0 or seconds >= 60.0:
        raise ValueError(f"right ascension {text!r} is out of range; use 00h00m00s..23h59m59.9s.")
    return 15.0 * (hours + minutes / 60.0 + seconds / 3600.0)


def dec_dms_to_deg(text: str) -> float:
    """Declination ``"+41d19m51.9s"`` (or ``"-05:25:16"``, ``"-05 25 16"``) in degrees; the
    sign applies to the whole angle, so ``"-00d30m00s"`` is -0.5."""
    sign, degrees, minutes, seconds = _parse_sexagesimal(text, "declination", "+41d19m51.9s")
    value = sign * (degrees + minutes / 60.0 + seconds / 3600.0)
    if minutes >= 60.0 or seconds >= 60.0 or abs(value) > 90.0:
        raise ValueError(f"declination {text!r} is out of range; use -90d..+90d.")
    return value


@dataclass(frozen=True)
class FixedSource:
    """A source fixed on the sky (no proper motion or parallax: radio sources).

    ``ra_deg``, ``dec_deg`` in degrees in ``frame``: ``"fk4"`` (default; equinox B1950 unless
    ``equinox`` is given), ``"fk5"`` (equinox J2000 unless given) or ``"icrs"``. ``obstime``
    (FK4 only) is the epoch at which an FK4 position was determined; the default is astropy's,
    the equinox (B1950). FK4 rotates slowly relative to inertial frames (Aoki et al. 1983), so
    the same B1950 numbers taken as "observed in 1990" land ~0.1-0.2 arcsec elsewhere.
    Equinox and obstime are strings astropy ``Time`` understands ("B1950", "J2000",
    "1990-02-08").
    """

    name: str
    ra_deg: float
    dec_deg: float
    frame: str = "fk4"
    equinox: str | None = None
    obstime: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError(
                f"source name {self.name!r} is not usable; give every source a non-empty name."
            )
        frame = str(self.frame).strip().lower()
        if frame not in _SUPPORTED_FRAMES:
            raise ValueError(
                f"source {self.name!r}: frame {self.frame!r} is not supported; use 'fk4' "
                "(B1950), 'fk5' (J2000) or 'icrs'."
            )
        object.__setattr__(self, "frame", frame)
        finite_fields(self, f"source {self.name!r}", "ra_deg", "dec_deg")
        if not 0.0 <= self.ra_deg < 360.0:
            raise ValueError(
                f"source {self.name!r}: ra_deg = {self.ra_deg} is outside 0..360; give the "
                "right ascension in degrees (hours times 15)."
            )
        if not -90.0 <= self.dec_deg <= 90.0:
            raise ValueError(
                f"source {self.name!r}: dec_deg = {self.dec_deg} is outside -90..90; give the "
                "declination in degrees."
            )
        if frame == "icrs" and (self.equinox is not None or self.obstime is not None):
            raise ValueError(
                f"source {self.name!r}: ICRS has no equinox or obstime; leave them unset or "
                "use frame 'fk4'/'fk5'."
            )
        if frame == "fk5" and self.obstime is not None:
            raise ValueError(
                f"source {self.name!r}: obstime only matters for FK4; leave it unset for FK5."
            )

    @classmethod
    def from_sexagesimal(cls, name: str, ra: str, dec: str, frame: str = "fk4",
                         **kwargs: Any) -> FixedSource:
        """A source from ``"03h16m29.57s"``, ``"+41d19m51.9s"`` style strings."""
        return cls(name, ra_hms_to_deg(ra), dec_dms_to_deg(dec), frame, **kwargs)


#: The 8 sources of the Ghigo 8-9 February 1990 run at the report's Table 1 positions (B1950
#: FK4, to 0.1 s of right ascension and 1" of declination).
GHIGO1990_SOURCES: tuple[FixedSource, ...] = tuple(
    FixedSource.from_sexagesimal(name, ra, dec, "fk4")
    for name, ra, dec in (
        ("3C84", "03h16m29.6s", "+41d19m52s"),
        ("Taurus A", "05h31m31.0s", "+21d59m00s"),
        ("Orion A", "05h32m49.0s", "-05d25m15s"),
        ("3C273", "12h26m33.3s", "+02d19m43s"),
        ("Virgo A", "12h28m17.6s", "+12d40m02s"),
        ("W31", "18h06m25.6s", "-20d19m36s"),
        ("Cygnus A", "19h57m44.4s", "+40d35m46s"),
        ("Cassiopeia A", "23h21m09.0s", "+58d32m30s"),
    )
)
