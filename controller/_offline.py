"""The one place where astropy is told never to reach the network.

IERS tables come from the ``astropy-iers-data`` package. Importing this module is cheap: it
only sets configuration values and does not import astropy.coordinates.
"""

from astropy.utils import iers

iers.conf.auto_download = False
iers.conf.auto_max_age = None
# Dates beyond the bundled tables (future campaigns) fall back to zero corrections with a
# warning instead of an exception; 1990 is well inside IERS-B.
iers.conf.iers_degraded_accuracy = "warn"
