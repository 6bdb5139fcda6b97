"""The fast ephemeris (controller.astro.ephemeris) against exact per-point astropy: sources
and the Sun, rates, conventions, input checks and offline operation (refraction, the Sun's
rising and setting and the sources' coordinates have files of their own).

Reference positions are astropy's own transforms, computed point by point (vectorized over
times, but each time its own frame) from the source's catalogue frame:
``SkyCoord(FK4).transform_to(ICRS()).transform_to(AltAz(obstime=t, pressure=0))``. The explicit
ICRS step keeps the FK4 position's obstime at B1950; astropy's one-step FK4 -> AltAz silently
takes the AltAz obstime for its intermediate FK4NoETerms frame instead (astropy issue #10456),
which moves the 1990 sources by 0.11-0.19" (pinned by a test below).

Tolerances: 0.1 arcsec for positions (docs/layout.md) with a 1 mas regression guard (both
sides use the same ERFA routines; measured agreement is a few micro-arcseconds); 1 arcsec for
the Sun (it only drives thermal models and day/night splits). Random times come from seeded
numpy Generators.
"""

from __future__ import annotations

import math
import socket
import subprocess
import sys
import urllib.request
from pathlib import Path

import erfa
import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import FK4, FK5, ICRS, AltAz, HADec, SkyCoord, get_body
from astropy.utils import iers
from hypothesis import given, settings
from hypothesis import strategies as st

from controller.astro import ephemeris as astro
from controller.astro.ephemeris import Ephemeris
from controller.astro.refraction import refraction_rad
from controller.astro.site import GREEN_BANK_45FT, Site, Weather
from controller.astro.sources import GHIGO1990_SOURCES, FixedSource

ARCSEC_PER_RAD = 180.0 / math.pi * 3600.0
DAY_S = 86400.0
EPOCH_1990 = "1990-02-08T00:00:00"
#: docs/layout.md's conventions: the vectorized ephemeris must match exact astropy to 0.1"
POSITION_TOLERANCE_ARCSEC = 0.1
#: regression guard: astropy and this module run the same ERFA code; measured ~2e-6"
REGRESSION_TOLERANCE_ARCSEC = 0.001
#: the Sun feeds a thermal model and day/night splits only (brief: about an arcsecond)
SUN_TOLERANCE_ARCSEC = 1.0
REPO = Path(__file__).resolve().parents[3]


# --------------------------------------------------------------------------- helpers
def astropy_frame(source: FixedSource):
    """The astropy frame a FixedSource's numbers are given in (independent of the module)."""
    if source.frame == "icrs":
        return ICRS()
    if source.frame == "fk5":
        return FK5(equinox=source.equinox or "J2000")
    attributes = {"equinox": source.equinox or "B1950"}
    if source.obstime is not None:
        attributes["obstime"] = source.obstime
    return FK4(**attributes)


def reference_icrs(sources) -> SkyCoord:
    """ICRS positions of ``sources``, shape (n, 1), one astropy transform per source."""
    coords = [
        SkyCoord(s.ra_deg * u.deg, s.dec_deg * u.deg, frame=astropy_frame(s)).icrs
        for s in sources
    ]
    return SkyCoord([c.ra for c in coords], [c.dec for c in coords], frame="icrs")[:, None]


def reference_altaz(ephemeris: Ephemeris, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact astropy vacuum az, el (rad) of every source at every time, shape (n, m)."""
    frame = AltAz(obstime=ephemeris.time(t_s)[None, :],
                  location=ephemeris.site.earth_location(), pressure=0 * u.hPa)
    altaz = reference_icrs(ephemeris.sources).transform_to(frame)
    return altaz.az.rad, altaz.alt.rad


def separation_arcsec(az1, el1, az2, el2) -> np.ndarray:
    """Great-circle separation (arcsec) from the chord between unit vectors (exact at small
    angles, no trouble at the zenith where azimuth is ill-defined)."""

    def unit(az, el):
        return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])

    chord = np.linalg.norm(unit(az1, el1) - unit(az2, el2), axis=0)
    return 2.0 * np.arcsin(chord / 2.0) * ARCSEC_PER_RAD


def assert_matches_astropy(ephemeris: Ephemeris, t_s: np.ndarray) -> float:
    index = np.arange(len(ephemeris.sources))[:, None]
    az, el = ephemeris.altaz_rad(index, t_s[None, :])
    ref_az, ref_el = reference_altaz(ephemeris, t_s)
    error = separation_arcsec(az, el, ref_az, ref_el)
    worst = float(error.max())
    assert worst < POSITION_TOLERANCE_ARCSEC, f"max error {worst:.3g} arcsec"
    assert worst < REGRESSION_TOLERANCE_ARCSEC, f"max error {worst:.3g} arcsec (regression)"
    return worst


def transit_times_s(ephemeris: Ephemeris, index: int) -> np.ndarray:
    """Upper transits (hour angle 0 crossing upward) of a source inside the campaign (s)."""
    t = np.arange(0.0, ephemeris.duration_s, 60.0)
    ha, _ = ephemeris.hadec_rad(index, t)
    crossing = np.flatnonzero((ha[:-1] < 0.0) & (ha[1:] >= 0.0))
    # linear interpolation within the minute: good to a fraction of a second
    return t[crossing] - ha[crossing] / (ha[crossing + 1] - ha[crossing]) * 60.0


# --------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def day_1990() -> Ephemeris:
    return Ephemeris(GREEN_BANK_45FT, EPOCH_1990, DAY_S, GHIGO1990_SOURCES)


@pytest.fixture(scope="module")
def month_1990() -> Ephemeris:
    return Ephemeris(GREEN_BANK_45FT, EPOCH_1990, 30.0 * DAY_S, GHIGO1990_SOURCES)


SOUTHERN_SITE = Site(-32.998, 148.263, 415.0, "Parkes-like southern site")
#: the Sun on 2021-06-01 is near RA 69.3 deg, Dec +22.0 deg
SOURCES_2021 = (
    FixedSource("3C273 J2000", 187.27791535, 2.05238857, "fk5"),
    FixedSource("south pole", 120.0, -85.0, "icrs"),
    FixedSource("3 deg from the Sun", 72.5, 22.0, "icrs"),
    FixedSource("overhead at Parkes", 200.0, -33.0, "icrs"),
    GHIGO1990_SOURCES[2],  # Orion A, FK4 B1950
)


# --------------------------------------------------------------------------- positions
def test_1990_day_all_sources_random_times_match_astropy(day_1990):
    rng = np.random.default_rng(1990)
    random_times = rng.uniform(0.0, DAY_S, 200)
    # the middle of grid intervals is where an interpolant is worst
    mid_grid = -day_1990.margin_s + day_1990.grid_step_s * (np.arange(0, 160, 7) + 0.5)
    mid_grid = mid_grid[(mid_grid >= 0.0) & (mid_grid <= DAY_S)]
    assert_matches_astropy(day_1990, np.concatenate([random_times, mid_grid, [0.0, DAY_S]]))


@pytest.mark.parametrize("name", ["Cygnus A", "3C84", "Cassiopeia A", "Virgo A"])
def test_1990_near_transit_matches_astropy(day_1990, name):
    """Around transit; Cygnus A and 3C84 pass 2-3 deg from the zenith at Green Bank, where
    the azimuth swings by minutes of arc per second."""
    index = day_1990.index(name)
    transits = transit_times_s(day_1990, index)
    assert transits.size == 1
    rng = np.random.default_rng(index)
    t = np.clip(transits[0] + np.concatenate([[0.0], rng.uniform(-900.0, 900.0, 60)]), 0, DAY_S)
    az, el = day_1990.altaz_rad(index, t)
    ref_az, ref_el = reference_altaz(day_1990, t)
    error = separation_arcsec(az, el, ref_az[index], ref_el[index])
    assert error.max() < REGRESSION_TOLERANCE_ARCSEC <= POSITION_TOLERANCE_ARCSEC
    if name == "Cygnus A":  # really near the zenith, really fast in azimuth
        assert np.degrees(el.max()) > 87.0
        assert np.degrees(np.abs(day_1990.rates_rad_s(index, transits[0])[0])) > 0.03


def test_30_day_campaign_matches_astropy(month_1990):
    rng = np.random.default_rng(30)
    assert_matches_astropy(month_1990, rng.uniform(0.0, 30.0 * DAY_S, 120))


@pytest.mark.parametrize("grid_step_s", [600.0, astro.MAX_GRID_STEP_S])
def test_2021_southern_site_matches_astropy(grid_step_s):
    ephemeris = Ephemeris(SOUTHERN_SITE, "2021-06-01T00:00:00", 2.0 * DAY_S, SOURCES_2021,
                          grid_step_s=grid_step_s)
    rng = np.random.default_rng(2021)
    assert_matches_astropy(ephemeris, rng.uniform(0.0, 2.0 * DAY_S, 150))


def test_campaign_across_a_leap_second_matches_astropy():
    """UTC gained a leap second at the end of 1990: campaign seconds are SI seconds, so the
    position a day after the epoch is 86400 s of Earth rotation later, not 86401."""
    ephemeris = Ephemeris(GREEN_BANK_45FT, "1990-12-31T12:00:00", DAY_S, GHIGO1990_SOURCES[:3])
    assert ephemeris.time(DAY_S).isot == "1991-01-01T11:59:59.000"
    t = np.concatenate([np.random.default_rng(60).uniform(0.0, DAY_S, 60), [43199.0, 43201.0]])
    assert_matches_astropy(ephemeris, t)


def test_hadec_matches_astropy(day_1990):
    t = np.random.default_rng(7).uniform(0.0, DAY_S, 100)
    ha, dec = day_1990.hadec_rad(np.arange(8)[:, None], t[None, :])
    frame = HADec(obstime=day_1990.time(t)[None, :],
                  location=day_1990.site.earth_location(), pressure=0 * u.hPa)
    ref = reference_icrs(day_1990.sources).transform_to(frame)
    ref_ha = (ref.ha.rad + math.pi) % (2 * math.pi) - math.pi
    # an hour angle error is an arc of size d(HA) cos(Dec) on the sky
    ha_error = np.abs((ha - ref_ha + math.pi) % (2 * math.pi) - math.pi) * np.cos(dec)
    assert (ha_error * ARCSEC_PER_RAD).max() < REGRESSION_TOLERANCE_ARCSEC
    assert (np.abs(dec - ref.dec.rad) * ARCSEC_PER_RAD).max() < REGRESSION_TOLERANCE_ARCSEC
    assert np.all((ha >= -math.pi) & (ha < math.pi))


def test_icrs_conversion_is_astropys(day_1990):
    radec = astro.icrs_radec_rad(GHIGO1990_SOURCES)
    ref = reference_icrs(GHIGO1990_SOURCES)[:, 0]
    assert np.allclose(radec[:, 0], ref.ra.rad, rtol=0, atol=1e-12)
    assert np.allclose(radec[:, 1], ref.dec.rad, rtol=0, atol=1e-12)


def test_fk4_sources_declared_observed_at_the_campaign_match_the_one_step_transform():
    """With ``obstime`` set to the campaign, the brief's literal one-step astropy expression
    ``SkyCoord(FK4(equinox="B1950")).transform_to(AltAz(...))`` is matched to 0.1"."""
    sources = tuple(
        FixedSource(s.name, s.ra_deg, s.dec_deg, "fk4", obstime="1990-02-08T12:00:00")
        for s in GHIGO1990_SOURCES
    )
    ephemeris = Ephemeris(GREEN_BANK_45FT, EPOCH_1990, DAY_S, sources)
    t = np.random.default_rng(4).uniform(0.0, DAY_S, 60)
    frame = AltAz(obstime=ephemeris.time(t)[None, :], location=GREEN_BANK_45FT.earth_location(),
                  pressure=0 * u.hPa)
    fk4 = SkyCoord([s.ra_deg for s in sources] * u.deg, [s.dec_deg for s in sources] * u.deg,
                   frame=FK4(equinox="B1950"))[:, None]
    one_step = fk4.transform_to(frame)
    az, el = ephemeris.altaz_rad(np.arange(8)[:, None], t[None, :])
    error = separation_arcsec(az, el, one_step.az.rad, one_step.alt.rad)
    # what is left is FK4's rotation over the <= 12 h between obstime and the sample
    assert error.max() < POSITION_TOLERANCE_ARCSEC


def test_astropy_one_step_fk4_to_altaz_takes_obstime_from_the_altaz_frame():
    """Pins the astropy behaviour the module documents (issue #10456): the one-step transform
    equals FK4 with obstime = observation time, which differs from B1950 by > 0.1" for Cas A
    in 1990. If astropy changes this, revisit FixedSource.obstime's documentation."""
    when = astro.utc_instant("1990-02-08T06:00:00")
    frame = AltAz(obstime=when, location=GREEN_BANK_45FT.earth_location(), pressure=0 * u.hPa)
    cas = GHIGO1990_SOURCES[-1]
    b1950 = SkyCoord(cas.ra_deg * u.deg, cas.dec_deg * u.deg, frame=FK4(equinox="B1950"))
    at_obstime = SkyCoord(cas.ra_deg * u.deg, cas.dec_deg * u.deg,
                          frame=FK4(equinox="B1950", obstime=when))
    one_step = b1950.transform_to(frame)
    assert one_step.separation(at_obstime.icrs.transform_to(frame)).arcsec < 1e-6
    assert one_step.separation(b1950.icrs.transform_to(frame)).arcsec > POSITION_TOLERANCE_ARCSEC


def test_rates_match_astropy_finite_differences(day_1990):
    """d(az)/dt and d(el)/dt against central differences of exact astropy positions
    (+-1 s: truncation ~1e-13 rad/s); times kept below 80 deg elevation where az is smooth."""
    t = np.random.default_rng(11).uniform(10.0, DAY_S - 10.0, 80)
    index = np.arange(8)[:, None]
    az_rate, el_rate = day_1990.rates_rad_s(index, t[None, :])
    az_plus, el_plus = reference_altaz(day_1990, t + 1.0)
    az_minus, el_minus = reference_altaz(day_1990, t - 1.0)
    ref_az_rate = ((az_plus - az_minus + math.pi) % (2 * math.pi) - math.pi) / 2.0
    ref_el_rate = (el_plus - el_minus) / 2.0
    _, el = day_1990.altaz_rad(index, t[None, :])
    smooth = el < math.radians(80.0)
    # 1e-10 rad/s = 0.02 mas/s, far below anything a servo model notices
    assert np.abs(az_rate - ref_az_rate)[smooth].max() < 1e-10
    assert np.abs(el_rate - ref_el_rate)[smooth].max() < 1e-10
    # a sidereal-rate sanity check that does not depend on astropy: |rate| <= 15"/s / cos el
    assert np.all(np.abs(el_rate) <= astro.SIDEREAL_RATE_RAD_S * 1.001)


def test_sun_matches_astropy_get_body(day_1990):
    t = np.random.default_rng(3).uniform(0.0, DAY_S, 100)
    times = day_1990.time(t)
    location = day_1990.site.earth_location()
    ref = get_body("sun", times, location).transform_to(
        AltAz(obstime=times, location=location, pressure=0 * u.hPa)
    )
    az, el = day_1990.sun_altaz_rad(t)
    error = separation_arcsec(az, el, ref.az.rad, ref.alt.rad)
    assert error.max() < SUN_TOLERANCE_ARCSEC
    assert error.max() < 0.005  # regression guard: measured 0.002" (light time is 0.008")


# --------------------------------------------------------------------------- conventions
def test_azimuth_is_north_based_and_half_open(day_1990):
    index = day_1990.index("Orion A")  # transits south of the zenith at Green Bank
    transit = transit_times_s(day_1990, index)[0]
    az, _ = day_1990.altaz_rad(index, np.array([transit - 3600.0, transit, transit + 3600.0]))
    assert 0.0 < az[0] < math.pi  # rising: east of the meridian
    assert abs(az[1] - math.pi) < 1e-6  # due south at transit
    assert math.pi < az[2] < 2 * math.pi  # setting: west
    # due north with either sign of zero east component stays inside [0, 2 pi)
    north_az, _ = astro._az_el(np.array([-1.0, -1.0, -1.0]), np.array([0.0, -0.0, -1e-30]),
                               np.zeros(3), (3,))
    assert np.all((north_az >= 0.0) & (north_az < 2 * math.pi))


def test_shapes_scalars_and_quantities(day_1990):
    az, el = day_1990.altaz_rad(0, 1000.0)
    assert np.ndim(az) == 0 and isinstance(float(el), float)
    az, el = day_1990.altaz_rad(np.arange(8)[:, None], np.linspace(0, 100, 5))
    assert az.shape == el.shape == (8, 5)
    assert day_1990.altaz_rad(3, np.empty(0))[0].shape == (0,)
    in_minutes = day_1990.altaz_rad(2, 60.0 * u.min)
    assert in_minutes == day_1990.altaz_rad(2, 3600.0)
    assert day_1990.time(3600.0).isot == "1990-02-08T01:00:00.000"
    assert day_1990.time(np.array([0.0, 1.0])).shape == (2,)
    assert day_1990.names[day_1990.index("W31")] == "W31"


@settings(max_examples=60, deadline=None)
@given(t=st.floats(-3600.0, DAY_S + 3600.0), index=st.integers(0, 7))
def test_altaz_is_the_spherical_trig_of_hadec(day_1990, t, index):
    """Property over the whole span (margins included): altaz is erfa.hd2ae of hadec."""
    az, el = day_1990.altaz_rad(index, t)
    ha, dec = day_1990.hadec_rad(index, t)
    ref_az, ref_el = erfa.hd2ae(ha, dec, GREEN_BANK_45FT.latitude_rad)
    assert 0.0 <= az < 2 * math.pi and -math.pi / 2 <= el <= math.pi / 2
    assert separation_arcsec(az, el, ref_az, ref_el) < 1e-6


def test_sun_only_ephemeris():
    ephemeris = Ephemeris(GREEN_BANK_45FT, EPOCH_1990, DAY_S, ())
    assert ephemeris.sun_altaz_rad(np.array([0.0, 43200.0]))[1].shape == (2,)
    with pytest.raises(ValueError, match="0 sources"):
        ephemeris.altaz_rad(0, 0.0)


# --------------------------------------------------------------------------- bad input
#: surface weather for the refraction cases (10 C, 920 hPa, 50 % humidity)
RADIO_WEATHER = Weather(10.0, 920.0, 0.5)


@pytest.mark.parametrize(("build", "message"), [
    (lambda: FixedSource("x", 10.0, 10.0, "galactic"), "frame 'galactic' is not supported"),
    (lambda: FixedSource("x", 400.0, 10.0), "ra_deg = 400.0 is outside 0..360"),
    (lambda: FixedSource("x", 10.0, 10.0, "icrs", equinox="J2000"), "ICRS has no equinox"),
    (lambda: Site(100.0, 0.0, 0.0), "latitude_deg = 100.0 is outside"),
    (lambda: Weather(10.0, 920.0, 50.0), "give a fraction"),
    (lambda: Weather(10.0, float("nan"), 0.5), "not finite"),
    (lambda: Ephemeris(GREEN_BANK_45FT, EPOCH_1990, -1.0, GHIGO1990_SOURCES), "is negative"),
    (lambda: Ephemeris(GREEN_BANK_45FT, "8 Feb 1990", 10.0, ()), "not a time astropy can"),
    (lambda: Ephemeris(GREEN_BANK_45FT, EPOCH_1990, 10.0, (), grid_step_s=7200.0),
     "grid_step_s = 7200.0 is outside"),
    (lambda: Ephemeris((38.4, -79.8, 800.0), EPOCH_1990, 10.0, ()), "must be a controller"),
    (lambda: Ephemeris(GREEN_BANK_45FT, EPOCH_1990, 10.0, GHIGO1990_SOURCES[:1] * 2),
     "names must be unique"),
    (lambda: astro.icrs_radec_rad([FixedSource("x", 1.0, 2.0, "fk4", equinox="whenever")]),
     "not a time astropy understands"),
    (lambda: refraction_rad(0.5, RADIO_WEATHER, frequency_ghz=-8.4), "positive number of GHz"),
    (lambda: refraction_rad(0.5, (10.0, 920.0, 0.5)), "must be a controller.astro.site.Weather"),
])
def test_bad_input_raises_value_error_saying_what_to_do(build, message):
    with pytest.raises(ValueError, match=message) as caught:
        build()
    text = str(caught.value)
    assert "\n" not in text and text.endswith(".")  # one plain sentence


def test_bad_index_and_times(day_1990):
    with pytest.raises(ValueError, match=r"index 8 is out of range.*Ephemeris.index"):
        day_1990.altaz_rad(8, 0.0)
    with pytest.raises(ValueError, match="out of range"):
        day_1990.rates_rad_s(np.array([0, 8]), 0.0)
    with pytest.raises(ValueError, match="must be an integer"):
        day_1990.hadec_rad(1.5, 0.0)
    with pytest.raises(ValueError, match="no source called 'Sun'"):
        day_1990.index("Sun")
    margin = day_1990.margin_s
    day_1990.altaz_rad(0, np.array([-margin, DAY_S + margin]))  # the margin is accepted
    for t in (-margin - 1.0, DAY_S + margin + 1.0, float("nan")):
        with pytest.raises(ValueError, match=r"outside this ephemeris.*longer duration_s"):
            day_1990.altaz_rad(0, np.array([100.0, t]))
    with pytest.raises(ValueError, match="outside this ephemeris"):
        day_1990.sun_altaz_rad(-margin - 1.0)


# --------------------------------------------------------------------------- offline, import
def test_building_an_ephemeris_never_touches_the_network(monkeypatch):
    attempts: list[tuple] = []

    def refuse(*args, **kwargs):
        attempts.append(args)
        raise OSError("network access attempted during a test")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    monkeypatch.setattr(socket, "getaddrinfo", refuse)
    monkeypatch.setattr(urllib.request, "urlopen", refuse)
    # control: the trap does catch astropy's download path
    from astropy.utils.data import download_file

    with pytest.raises(Exception):  # noqa: B017  (whatever astropy wraps the OSError in)
        download_file("https://example.invalid/finals2000A.all", cache=False)
    assert attempts, "the network trap did not fire; this test would prove nothing"
    attempts.clear()

    assert iers.conf.auto_download is False  # set by controller.astro.offline
    # forget the loaded IERS tables so that building re-opens them under the trap
    monkeypatch.setattr(iers.IERS_Auto, "iers_table", None)
    monkeypatch.setattr(iers.IERS_B, "iers_table", None)
    monkeypatch.setattr(astro, "_ICRS_CACHE", {})
    ephemeris = Ephemeris(GREEN_BANK_45FT, "1995-07-01T00:00:00", DAY_S,
                          (FixedSource("offline test", 12.0, 34.0),))
    assert np.isfinite(ephemeris.altaz_rad(0, 3600.0)[0])
    assert attempts == []


def test_import_is_light():
    """Importing controller.astro loads neither astropy.coordinates nor scipy (large parts of
    a second; `antsim --help` should not pay for them) and nothing heavy beyond what
    ``import controller`` already loads (its IERS set-up brings astropy.time and erfa)."""
    code = (
        "import sys; import controller; before = set(sys.modules); "
        "import controller.astro.ephemeris; added = set(sys.modules) - before; "
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy' "
        "or m.startswith('astropy.coordinates'))); "
        "print(sorted(m for m in added if m.split('.')[0] in ('astropy', 'erfa', 'scipy')))"
    )
    result = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                            text=True, check=True)
    heavy_loaded, heavy_added = result.stdout.split("\n")[:2]
    assert heavy_loaded == "[]"
    assert heavy_added == "[]"
    # (the import's time, ~5 ms on a quiet machine, is no test: a busy shared machine took
    # 0.17 s; what makes it light is the absence of the modules above)
