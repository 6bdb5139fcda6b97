"""The one interface every physical effect implements.

An effect is configured by parameters (validated from the scenario's ``[[truth.effects]]``
tables), bound to a world with :meth:`Effect.start` (where it draws its random realisation
from its own generator), and then asked, for the state of the antenna and the sky at time t,
for the pointing error it causes: **indicated minus true** (Ghigo's sign), azimuth and
elevation in radians. Effects that vary faster than an integration (wind, servo jitter) set
``per_sample`` and answer :meth:`Effect.sample_error` on arrays of sample times instead.
Effects that act on one polarization channel's beam (squint) answer :meth:`Effect.beam_offset`;
effects that change the world itself (clock, source structure, beam width) do it in
:meth:`Effect.start`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from functools import cache
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from antsim.schema.keys import REQUIRED, Key, read_key

if TYPE_CHECKING:
    from antsim.tomlcheck import Table

__all__ = ["BLOCK_FIELDS", "REQUIRED", "Effect", "Key", "PointingState"]


@dataclass
class PointingState:
    """State of the antenna at one instant (radians, seconds since the epoch).

    ``az_rad``/``el_rad`` are the true direction of the beam (North-based azimuth),
    ``*_rate_rad_s`` the commanded axis rates, ``approach_*`` the sign (+1/-1) of the last
    motion of each axis, ``source`` the name of the source being observed.
    """

    t_s: float
    az_rad: float
    el_rad: float
    az_rate_rad_s: float = 0.0
    el_rate_rad_s: float = 0.0
    approach_az: float = 1.0
    approach_el: float = 1.0
    source: str = ""
    feed_angle_rad: float = 0.0


#: the PointingState fields that carry one value per instant in a block (see block_error)
BLOCK_FIELDS = ("t_s", "az_rad", "el_rad", "az_rate_rad_s", "el_rate_rad_s", "approach_az",
                "approach_el", "feed_angle_rad")


#: the largest magnitude of a parameter whose key gives no bound, by the unit its name
#: ends in (first match): beyond these a value means nothing physical and would only break
#: the simulation (a pointing error of 10^300", a time past the ephemeris, 10^9 gusts)
NAME_BOUNDS: tuple[tuple[str, float], ...] = (
    ("_per_k", 3600.0),        # arcsec per kelvin
    ("_arcsec", 36000.0),      # 10 deg: beyond any telescope's pointing error
    ("_arcmin", 600.0),
    ("_deg", 720.0),
    ("_s_per_day", 3600.0),    # a clock an hour off per day
    ("_per_h", 3600.0),        # one event a second
    ("_s", 1e8),               # about 3 years
    ("_k", 1000.0),
    ("_c", 100.0),
    ("_m_s", 100.0),
)


def name_bound(name: str) -> float | None:
    """The magnitude bound :data:`NAME_BOUNDS` gives parameter ``name`` (None: none)."""
    return next((bound for suffix, bound in NAME_BOUNDS if name.endswith(suffix)), None)


@cache
def _bounded_keys(cls: type[Effect]) -> Mapping[str, Key]:
    """:meth:`Effect.keys`, made once per class (read only: it is shared)."""
    out = {}
    for name, key in cls.PARAMS.items():
        bound = name_bound(name)
        if key.kind == "number" and bound is not None:
            key = replace(key, min=-bound if key.min is None else key.min,
                          max=bound if key.max is None else key.max)
        out[name] = key
    return MappingProxyType(out)


def _instant(value):
    """One instant's field of a block: a number where it is one value (a member block's
    (1,) rows), else the array (members,)."""
    return value.item() if np.ndim(value) and np.size(value) == 1 else value


class Effect:
    """Base class of the physical-effects catalogue."""

    name: ClassVar[str] = ""
    #: TPOINT (or W) terms that express this effect where it has them
    terms: ClassVar[tuple[str, ...]] = ()
    #: a plain explanation of the physical cause
    explanation: ClassVar[str] = ""
    per_sample: ClassVar[bool] = False
    #: the parameters a scenario gives, as declared settings (antsim.schema.keys);
    #: :meth:`keys` adds the bounds :data:`NAME_BOUNDS` gives
    PARAMS: ClassVar[dict[str, Key]] = {}

    def __init__(self, **params: Any):
        unknown = set(params) - set(self.PARAMS)
        if unknown:
            raise TypeError(f"{self.name}: unknown parameter(s) {sorted(unknown)}")
        values = {}
        for key, spec in self.PARAMS.items():
            value = params.get(key, spec.default)
            if value is REQUIRED:
                raise TypeError(f"{self.name}: parameter {key!r} is required")
            values[key] = value
        self.p = values

    # ------------------------------------------------------------------ configuration
    @classmethod
    def keys(cls) -> Mapping[str, Key]:
        """:data:`PARAMS` as the scenario reads them: a number whose key gives no bound on
        a side is bounded there by the unit its name ends in (:data:`NAME_BOUNDS`)."""
        return _bounded_keys(cls)

    @classmethod
    def from_table(cls, table: Table) -> Effect:
        """Build from a scenario table; every bad value is an InputError naming the key."""
        params: dict[str, Any] = {}
        for name, key in cls.keys().items():
            if key.required and name not in table:
                raise table.error(name, "<missing>", "required parameter is missing",
                                  key.doc)
            params[name] = read_key(table, name, key)
        table.finish()
        return cls(**params)

    def params(self) -> dict[str, Any]:
        """Parameters as plain JSON-able values."""
        return {k: (dict(v) if isinstance(v, dict) else v) for k, v in self.p.items()}

    def truth(self) -> dict[str, Any]:
        """This effect's entry in ``truth.json``."""
        return {"effect": self.name, "terms": list(self.terms), "params": self.params()}

    # ------------------------------------------------------------------ runtime
    def start(self, world: Any, rng: np.random.Generator) -> None:
        """Bind to a world (time span, sky, weather) and draw the random realisation."""

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        """Indicated minus true (azimuth, elevation) in radians at ``state``."""
        return 0.0, 0.0

    def block_error(self, state: PointingState) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`pointing_error` at K instants at once, for the antenna's integrations
        computed together: ``state``'s fields are arrays (K,), in time order. The fixed
        point asks several times with the same times and new directions; an effect with a
        state of its own advances it once per set of times. Default: one
        :meth:`pointing_error` per instant; effects that are elementwise in ``state`` use
        :meth:`pointing_error` itself (``block_error = pointing_error``). With a member axis
        (``antsim.plan``) the fields are (K, 1), or (K, members) for the directions and what
        differs between members; the answer then broadcasts to (K, members)."""
        if type(self).pointing_error is Effect.pointing_error:
            return 0.0, 0.0
        fields = [getattr(state, name) for name in BLOCK_FIELDS]
        per_instant = np.broadcast_shapes(*(np.shape(v)[1:] for v in fields))
        errors = []
        for k in range(np.shape(state.t_s)[0]):
            instant = PointingState(**{name: _instant(v[k]) for name, v
                                       in zip(BLOCK_FIELDS, fields, strict=True)})
            errors.append([np.broadcast_to(e, per_instant)
                           for e in self.pointing_error(instant)])
        errors = np.array(errors)
        return errors[:, 0], errors[:, 1]

    def sample_error(self, t_s: np.ndarray, el_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """Per-sample indicated minus true (azimuth, elevation) in radians (``per_sample``)."""
        zero = np.zeros_like(t_s)
        return zero, zero

    def beam_offset(self, channel: str, state: PointingState) -> tuple[float, float]:
        """Offset of one channel's beam from the antenna's pointing, (xel, el) radians."""
        return 0.0, 0.0

    def __repr__(self) -> str:
        body = ", ".join(f"{k}={v!r}" for k, v in self.p.items())
        return f"{type(self).__name__}({body})"
