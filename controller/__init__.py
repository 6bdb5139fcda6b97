"""The control program: pointing mathematics, scans, reduction, scheduling, recordings.

It drives an antenna only through :mod:`controller.protocol` and never imports ``antsim``.
"""

from .astro import offline as _offline  # noqa: F401  (astropy IERS auto-download off before any astropy use)
from .errors import InputError
from .pointing.model import NAMED_MODELS, PointingModel
from .pointing.terms import Term, get_term

__all__ = ["NAMED_MODELS", "InputError", "PointingModel", "Term", "get_term"]
