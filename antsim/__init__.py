"""antsim: a simulated radio telescope, and the tool that calibrates its pointing."""

from controller.astro import offline as _offline  # noqa: F401  (no network, before anything touches astropy)

from ._version import __version__

__all__ = ["__version__"]
