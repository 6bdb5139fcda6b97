"""Geometric pointing errors expressed by linear pointing-model terms."""

from __future__ import annotations

from typing import Any, ClassVar

from controller.pointing.equatorial import equatorial_model
from controller.pointing.model import PointingModel
from controller.pointing.terms import TermError, get_term

from .base import Effect, Key, PointingState, name_bound

__all__ = ["GeometricEffect", "TermsEffect"]


class GeometricEffect(Effect):
    """Mount geometry as a pointing model: the encoders read true + ``model.offset``.

    The model is evaluated at the true position (the convention TPOINT fits use), so the
    controller's fitted model of the same terms reproduces it exactly.
    """

    name: ClassVar[str] = "geometric"
    explanation: ClassVar[str] = (
        "fixed mechanical misalignments of the mount: encoder zero points, collimation, "
        "axis non-perpendicularity and tilt, gravitational sag"
    )

    def __init__(self, model: PointingModel):
        self.model = model
        self.p = {"model": model.name, "terms_arcsec": model.as_dict()}

    @property
    def terms(self) -> tuple[str, ...]:  # type: ignore[override]
        return self.model.names

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        if self.model.needs_feed:  # feed terms (HSCF...) turn with the feed angle
            return self.model.offset_scalar_rad(state.az_rad, state.el_rad,
                                                state.feed_angle_rad)
        return self.model.offset_scalar_rad(state.az_rad, state.el_rad)

    block_error = pointing_error  # offset_scalar_rad is elementwise on arrays


class TermsEffect(GeometricEffect):
    """Extra geometric terms by name, e.g. ``HESA2 = 6.0`` (arcsec, TPOINT sign).

    On an equatorial mount the names are TPOINT's equatorial terms (``HHSHCD``, ``NP``...,
    :mod:`controller.pointing.equatorial`), bound to the mount's latitude when the effect
    starts (a name both vocabularies know, such as TF, means the mount's)."""

    name: ClassVar[str] = "terms"
    explanation: ClassVar[str] = "additional geometric terms given by their TPOINT names"
    PARAMS: ClassVar[dict[str, Key]] = {}
    #: each term's value, by the term's name (any number of them)
    TERM: ClassVar[Key] = Key(0.0, "the value of a pointing term, by its name (TPOINT's, or "
                              "the mount's equatorial terms)", min=-name_bound("_arcsec"),
                              max=name_bound("_arcsec"), unit="arcsec")

    def __init__(self, terms_arcsec: dict[str, float] | None = None, **named: Any):
        values = dict(terms_arcsec or {})
        values.update(named)
        self.values_arcsec = {str(k).upper(): float(v) for k, v in values.items()}
        try:
            model = PointingModel(list(values), list(values.values()), name="terms")
        except TermError:  # an equatorial mount's terms: bound in start()
            model = None
        self.model = model
        self.p = {"model": "terms", "terms_arcsec": dict(self.values_arcsec)}

    @property
    def terms(self) -> tuple[str, ...]:  # type: ignore[override]
        return tuple(self.values_arcsec)

    def start(self, world, rng) -> None:
        if not world.frame.is_altaz:
            self.model = equatorial_model(list(self.values_arcsec), world.frame.latitude_deg,
                                          list(self.values_arcsec.values()), name="terms")
        elif self.model is None:
            raise TermError(f"effect terms: {', '.join(self.values_arcsec)} are not all "
                            "alt-az pointing terms")

    @classmethod
    def from_table(cls, table, lookup=get_term):
        """``lookup(name)`` resolves a term name (an equatorial mount's: its own vocabulary
        at the site's latitude)."""
        values = {}
        for key in table:
            if key == "effect":
                continue
            try:
                lookup(key)
            except TermError as err:
                raise table.error(key, table.raw(key), "not a pointing term", str(err)) from None
            if key.upper() in values:
                raise table.error(key, table.raw(key), f"gives the term {key.upper()} again",
                                  "give each term once")
            values[key.upper()] = table.number(key, min=cls.TERM.min, max=cls.TERM.max)
        if not values:
            raise table.error("effect", "terms", "lists no terms", "add e.g. HESA2 = 6.0 (arcsec)")
        table.finish()
        return cls(values)
