"""Speed and accuracy of the fast ephemeris (:mod:`controller.astro.ephemeris`).

    python benchmarks/ephemeris.py [--samples N] [--seed S]

Run it as a fresh process: the first figures are one-time costs of a process.

- import: ``import controller`` (its IERS set-up loads astropy.time and erfa) and then
  ``import controller.astro.ephemeris`` (with the site, sources and IERS modules it uses);
- one-time costs the first Ephemeris of a process pays: importing astropy.coordinates,
  reading the bundled IERS tables, and (in "first build") astropy's first FK4 -> ICRS;
- warm builds: 8 sources over 24 h and over 30 days (best of 5);
- evaluation: one ``altaz_rad`` call for 1 source x 15 times (the brief's figure), a scalar
  call, 8 sources x 15 times, ``rates_rad_s`` and ``sun_altaz_rad`` (best of 7 repeats of
  many calls; the machine's cost of one ``np.sin`` on 15 values is printed for scale);
- accuracy: the largest angular separation (arcsec) from exact per-point astropy
  (ICRS -> AltAz, pressure 0) over N random times x all sources for the 1990 day, a 30-day
  span and a 2021 southern site (target 0.1", docs/layout.md), and for the Sun (target ~1").
"""

from __future__ import annotations

import argparse
import sys
import time
import timeit
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

_start = time.perf_counter()
import controller  # noqa: E402, F401  (timed: the package's IERS set-up)

_controller_s = time.perf_counter() - _start
_start = time.perf_counter()
from controller.astro import ephemeris as astro  # noqa: E402  (timed: this module on top)
from controller.astro.site import GREEN_BANK_45FT, Site  # noqa: E402
from controller.astro.sources import GHIGO1990_SOURCES, FixedSource  # noqa: E402

_astro_s = time.perf_counter() - _start

DAY_S = 86400.0
EPOCH_1990 = "1990-02-08T00:00:00"
ARCSEC_PER_RAD = 206264.80624709636


def best_per_call_us(call, number: int, repeat: int = 7) -> float:
    """Best-of-``repeat`` mean time of one call (microseconds)."""
    return min(timeit.repeat(call, number=number, repeat=repeat)) / number * 1e6


def best_s(call, repeat: int = 5) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best


def separation_arcsec(az1, el1, az2, el2) -> np.ndarray:
    def unit(az, el):
        return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])

    chord = np.linalg.norm(unit(az1, el1) - unit(az2, el2), axis=0)
    return 2.0 * np.arcsin(chord / 2.0) * ARCSEC_PER_RAD


def max_error_arcsec(ephemeris: astro.Ephemeris, t_s: np.ndarray) -> float:
    """Largest separation from exact per-point astropy over all sources and ``t_s``."""
    from astropy import units as u
    from astropy.coordinates import AltAz, SkyCoord

    radec = astro.icrs_radec_rad(ephemeris.sources)
    frame = AltAz(obstime=ephemeris.time(t_s)[None, :], location=ephemeris.site.earth_location(),
                  pressure=0 * u.hPa)
    exact = SkyCoord(radec[:, :1] * u.rad, radec[:, 1:] * u.rad, frame="icrs").transform_to(frame)
    az, el = ephemeris.altaz_rad(np.arange(len(ephemeris.sources))[:, None], t_s[None, :])
    return float(separation_arcsec(az, el, exact.az.rad, exact.alt.rad).max())


def max_sun_error_arcsec(ephemeris: astro.Ephemeris, t_s: np.ndarray) -> float:
    from astropy import units as u
    from astropy.coordinates import AltAz, get_body

    times = ephemeris.time(t_s)
    location = ephemeris.site.earth_location()
    exact = get_body("sun", times, location).transform_to(
        AltAz(obstime=times, location=location, pressure=0 * u.hPa)
    )
    az, el = ephemeris.sun_altaz_rad(t_s)
    return float(separation_arcsec(az, el, exact.az.rad, exact.alt.rad).max())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=500,
                        help="random times per accuracy check (default 500)")
    parser.add_argument("--seed", type=int, default=1990, help="seed of the random times")
    args = parser.parse_args(argv)
    sources = GHIGO1990_SOURCES
    site = GREEN_BANK_45FT

    print("controller.astro ephemeris benchmark")
    print(f"  import controller                  {_controller_s * 1e3:8.1f} ms"
          "  (astropy IERS set-up, not this module)")
    print(f"  import controller.astro.ephemeris  {_astro_s * 1e3:8.1f} ms")

    # one-time costs of a process, paid by the first Ephemeris
    start = time.perf_counter()
    import astropy.coordinates  # noqa: F401

    print(f"  import astropy.coordinates         {(time.perf_counter() - start) * 1e3:8.1f} ms"
          "  (one-time, first Ephemeris)")
    start = time.perf_counter()
    from astropy.utils import iers

    iers.earth_orientation_table.get()
    print(f"  read bundled IERS tables           {(time.perf_counter() - start) * 1e3:8.1f} ms"
          "  (one-time, first Ephemeris)")
    start = time.perf_counter()
    day = astro.Ephemeris(site, EPOCH_1990, DAY_S, sources)
    print(f"  first build (8 sources, 24 h)      {(time.perf_counter() - start) * 1e3:8.1f} ms"
          "  (includes astropy's first FK4 -> ICRS transform)")
    build_day = best_s(lambda: astro.Ephemeris(site, EPOCH_1990, DAY_S, sources))
    build_month = best_s(lambda: astro.Ephemeris(site, EPOCH_1990, 30 * DAY_S, sources))
    print(f"  build, 8 sources, 24 h             {build_day * 1e3:8.1f} ms")
    print(f"  build, 8 sources, 30 days          {build_month * 1e3:8.1f} ms")

    t15 = np.linspace(40000.0, 40000.0 + 14 * 15.0, 15)
    all_sources = np.arange(len(sources))[:, None]
    number = 3000
    calls = (
        ("altaz_rad, 1 source x 15 times", lambda: day.altaz_rad(3, t15)),
        ("altaz_rad, scalar", lambda: day.altaz_rad(3, 40000.0)),
        ("altaz_rad, 8 sources x 15 times", lambda: day.altaz_rad(all_sources, t15)),
        ("hadec_rad, 1 source x 15 times", lambda: day.hadec_rad(3, t15)),
        ("rates_rad_s, 1 source x 15 times", lambda: day.rates_rad_s(3, t15)),
        ("sun_altaz_rad, 15 times", lambda: day.sun_altaz_rad(t15)),
        ("np.sin of 15 values (for scale)", lambda: np.sin(t15)),
    )
    for label, call in calls:
        print(f"  {label:34s} {best_per_call_us(call, number):8.1f} us")

    rng = np.random.default_rng(args.seed)
    month = astro.Ephemeris(site, EPOCH_1990, 30 * DAY_S, sources)
    southern = astro.Ephemeris(
        Site(-32.998, 148.263, 415.0, "southern"), "2021-06-01T00:00:00", 2 * DAY_S,
        (FixedSource("3C273 J2000", 187.27791535, 2.05238857, "fk5"),
         FixedSource("south", 120.0, -85.0, "icrs"), sources[2]),
    )
    print(f"accuracy: max separation from exact per-point astropy, {args.samples} random times")
    for label, ephemeris in (("1990, 24 h, 8 sources", day), ("1990, 30 days, 8 sources", month),
                             ("2021, southern site, 3 sources", southern)):
        t = rng.uniform(0.0, ephemeris.duration_s, args.samples)
        print(f"  {label:34s} {max_error_arcsec(ephemeris, t):.2e} arcsec  (target 0.1)")
    t = rng.uniform(0.0, DAY_S, args.samples)
    print(f"  {'Sun, 1990, 24 h':34s} {max_sun_error_arcsec(day, t):.2e} arcsec  (target ~1)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
