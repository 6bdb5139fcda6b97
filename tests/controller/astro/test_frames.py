"""The mount frame (controller.astro.frames): an equatorial mount's frame against ERFA, and its
round trips."""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.astro.frames import MountFrame, altaz_to_hadec, hadec_to_altaz

LAT = 38.437611  # the 140-ft (scenarios: SLALIB GBVA140)


def test_frame_matches_erfa_and_round_trips():
    import erfa

    rng = np.random.default_rng(11)
    ha = rng.uniform(-math.pi, math.pi, 500)
    dec = rng.uniform(-1.2, 1.5, 500)
    phi = math.radians(LAT)
    az, el = hadec_to_altaz(ha, dec, phi)
    az_e, el_e = erfa.hd2ae(ha, dec, phi)
    np.testing.assert_allclose(az, az_e, atol=1e-12)
    np.testing.assert_allclose(el, el_e, atol=1e-12)
    ha2, dec2 = altaz_to_hadec(az, el, phi)
    np.testing.assert_allclose((ha2 - ha + math.pi) % (2 * math.pi) - math.pi, 0.0, atol=1e-10)
    np.testing.assert_allclose(dec2, dec, atol=1e-10)
    frame = MountFrame("altaz", LAT)
    assert frame.to_altaz(1.0, 0.5) == (1.0, 0.5)  # identity for an alt-az mount
    with pytest.raises(ValueError, match="mount kind"):
        MountFrame("fork", LAT)
