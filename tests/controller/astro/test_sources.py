"""Sources' coordinates (controller.astro.sources): sexagesimal text read as the 1990 report's
Table 1 writes it, and refused where it is no angle."""

from __future__ import annotations

import pytest

from controller.astro.sources import GHIGO1990_SOURCES, dec_dms_to_deg, ra_hms_to_deg


def test_sexagesimal_parsing():
    assert ra_hms_to_deg("03h16m29.57s") == pytest.approx(49.1232083333, abs=1e-9)
    assert ra_hms_to_deg("03:16:29.57") == ra_hms_to_deg("03 16 29.57")
    assert dec_dms_to_deg("-05d25m16s") == pytest.approx(-5.4211111111, abs=1e-9)
    assert dec_dms_to_deg("-00d30m00s") == -0.5
    # the 1990 report's Table 1: 3C84 at 03:16:29.6 +41:19:52 (B1950)
    assert GHIGO1990_SOURCES[0].ra_deg == ra_hms_to_deg("03:16:29.6")
    assert GHIGO1990_SOURCES[0].dec_deg == dec_dms_to_deg("+41:19:52")
    for bad in ("3h16", "25h00m00s", "-01h00m00s", "12h61m00s"):
        with pytest.raises(ValueError, match="right ascension"):
            ra_hms_to_deg(bad)
    with pytest.raises(ValueError, match="declination"):
        dec_dms_to_deg("+91d00m00s")
