"""Shared fixtures: scenario files and texts, editing a scenario by string replacement, and a
probe that finds, through the control protocol only, where a noise-free world's beam is.

Scenario variants are made from a base text by explicit ``(old, new)`` replacements; each
``old`` must occur exactly once, so a test shows precisely which edit it depends on and fails
loudly (instead of silently testing something else) when the base scenario changes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
TEST_SCENARIOS = Path(__file__).resolve().parent / "data" / "scenarios"

#: the 1990 scenario cut to its first 3 hours (17:00-20:00 UTC, 8 Feb 1990). Orion A, 3C273
#: and Virgo A do not rise above the 10 deg scheduling limit in that window (the runner
#: refuses such a plan), so the scheduler is given the five sources that do.
SHORT_EDITS = (
    ("duration_h = 24.0", "duration_h = 3.0"),
    ('policy = "spread"',
     'policy = "spread"\nsources = ["3C84", "Taurus A", "W31", "Cygnus A", "Cassiopeia A"]'),
)


#: the 1990 scenario with its residual all noise and none of the physics that leaves
#: systematic errors beyond the ten W's (the mount's repeatable irregularities, the Sun's
#: heating, the atmosphere's refraction beyond W5's cot E, which the controller then
#: corrects from the weather); the night's residual all random as in
#: scenarios/ghigo1990_random_night.toml, and XL's gain as unstable as diagnose's tests were
#: written against (2e-3; the 1990 receiver's is 3e-4, docs/physics.md): a test of diagnose
#: naming an injected effect, or finding nothing, needs a world whose only systematic is the
#: injected one
NOISE_ONLY = (
    ("az_encoder_rms_arcsec = 22.0", "az_encoder_rms_arcsec = 0.0"),
    ("el_encoder_rms_arcsec = 35.0", "el_encoder_rms_arcsec = 0.0"),
    ("track_rms_arcsec = 20.0", "track_rms_arcsec = 0.0"),
    ("absorptivity = 0.35", "absorptivity = 0.0"),
    ('refraction = "none"', 'refraction = "weather"'),
    ("xel_rms_arcsec = 5.0", "xel_rms_arcsec = 19.0"),
    ("el_rms_arcsec = 5.0", "el_rms_arcsec = 28.0"),
    ("timescale_s = 30.0", "timescale_s = 120.0"),
    ('{ name = "XL", tsys_k = 51.75 },',
     '{ name = "XL", tsys_k = 51.75, gain_fluctuation = 2.0e-3 },'),
)


def edit_text(text: str, edits: Iterable[tuple[str, str]]) -> str:
    """``text`` with each ``old`` (which must occur exactly once) replaced by ``new``."""
    for old, new in edits:
        count = text.count(old)
        if count != 1:
            raise AssertionError(f"scenario edit target {old!r} occurs {count} times "
                                 "(expected once): has the base scenario changed?")
        text = text.replace(old, new)
    return text


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def diagnose_cache(request, tmp_path_factory) -> Path:
    """A directory for diagnose's fit cache shared by the tests: pytest's cache (kept between
    runs) or, under ``-p no:cacheprovider``, a temporary one for this run."""
    cache = getattr(request.config, "cache", None)
    if cache is None:
        return tmp_path_factory.mktemp("antsim-diagnose")
    return cache.mkdir("antsim-diagnose")


@pytest.fixture(scope="session")
def ghigo_path() -> Path:
    return REPO / "scenarios" / "ghigo1990.toml"


@pytest.fixture(scope="session")
def ghigo_text(ghigo_path) -> str:
    return ghigo_path.read_text(encoding="utf-8")


@pytest.fixture(scope="session")
def short_ghigo_text(ghigo_text) -> str:
    """The 1990 scenario text shortened to 3 hours (see ``SHORT_EDITS``)."""
    return edit_text(ghigo_text, SHORT_EDITS)


@pytest.fixture(scope="session")
def short_path(tmp_path_factory, short_ghigo_text) -> Path:
    """The 1990 scenario cut to 3 hours, as a file (read only: a test that edits it writes
    its own)."""
    path = tmp_path_factory.mktemp("short_scenario") / "short.toml"
    path.write_text(short_ghigo_text, encoding="utf-8")
    return path


@pytest.fixture(scope="session")
def quiet_path() -> Path:
    """A noise-free, atmosphere-free one-hour test world (see the file's comments)."""
    return TEST_SCENARIOS / "quiet.toml"


@pytest.fixture
def write_scenario(tmp_path):
    """``write_scenario(text, edits=(), name="scenario.toml") -> Path`` in ``tmp_path``."""

    def write(text: str, edits: Iterable[tuple[str, str]] = (),
              name: str = "scenario.toml") -> Path:
        path = tmp_path / name
        path.write_text(edit_text(text, edits), encoding="utf-8")
        return path

    return write


# ---------------------------------------------------------------------------------------------
# probing a noise-free world through the protocol
ARCSEC_PER_RAD = 648000.0 / math.pi


def source_trajectory(world, index: int,
                      offset_rad: Callable | None = None) -> Callable:
    """Trajectory (antenna clock s -> encoder az, el deg) on source ``index``'s true observed
    position, plus ``offset_rad(az_rad, el_rad) -> (d_az, d_el)`` evaluated there if given."""

    def trajectory(t_s):
        az, el = world.sky.observed_altaz_rad(index, np.asarray(t_s, dtype=float),
                                              t_weather_s=0.0)
        if offset_rad is not None:
            d_az, d_el = offset_rad(az, el)
            az, el = az + d_az, el + d_el
        return np.degrees(az) % 360.0, np.degrees(el)

    return trajectory


def probe_beam(world, index: int, trajectory, *, t_track_s: float = 600.0,
               step_arcmin: float = 3.0) -> dict[str, dict]:
    """Where source ``index`` is, per channel, relative to ``trajectory``.

    Drives the world's antenna only through the protocol: track at ``t_track_s``, then for
    each axis 1-s integrations (one sample each) at offsets -step, 0, +step on the sky.
    Azimuth steps are made in encoder azimuth; the sky offset actually obtained is computed
    from the source's true elevation at the sample time (the world's cross-elevation is
    d_az cos E_source). The baseline subtracted is Tsys + sky emission at the source's
    elevation (exact in a world with zero opacity).

    Returns per channel: ``center`` (xel, el) arcsec, the vertex of the parabola through the
    three log powers (exact for a Gaussian of any width); ``nominal`` (xel, el) arcsec, the
    two-point log-ratio offset assuming the scenario's nominal HPBW (what a five-point
    reduction measures); ``peak`` (az, el) the power above baseline at zero offset (K);
    ``powers`` and ``offsets`` (arcsec) per axis; ``times`` (az, el) the true time of the
    zero-offset sample of each axis. Offsets are the encoder (sky) offset from the trajectory
    at which the power peaks: indicated minus true when the trajectory is the true position.
    """
    env, antenna = world.env, world.antenna
    tsys = {c.name: c.tsys_k for c in world.scenario.receiver.channels}
    data: dict[str, list] = {"az": [], "el": []}

    def run():
        if env.now < t_track_s:
            yield env.timeout(t_track_s - env.now)
        yield antenna.track(trajectory)
        for axis in ("az", "el"):
            for n in (-1, 0, 1):
                step_deg = n * step_arcmin / 60.0
                _, el_now = world.sky.observed_altaz_rad(index, np.array([env.now]), 0.0)
                if axis == "az":
                    d_az_deg = step_deg / math.cos(el_now[0])
                    yield antenna.set_offset(d_az_deg, 0.0)
                else:
                    yield antenna.set_offset(0.0, step_deg)
                integ = yield antenna.integrate(1.0)
                t_sample = env.now - 0.5
                _, el_src = world.sky.observed_altaz_rad(index, np.array([t_sample]), 0.0)
                sky_arcsec = (d_az_deg * math.cos(el_src[0]) if axis == "az"
                              else step_deg) * 3600.0
                baseline = float(world.atmosphere.emission_k(el_src[0]))
                data[axis].append((sky_arcsec, {c: integ.power_k[c] - tsys[c] - baseline
                                                for c in integ.power_k}, t_sample))

    env.run(until=env.process(run()))
    k = 4.0 * math.log(2.0) / (world.scenario.beam.hpbw_arcmin * 60.0) ** 2  # per arcsec^2
    out = {}
    for c in world.antenna.channels:
        center, nominal, peak, powers, offsets, times = [], [], [], [], [], []
        for axis in ("az", "el"):
            u = np.array([row[0] for row in data[axis]])
            p = np.array([row[1][c] for row in data[axis]])
            quad, lin, _ = np.polyfit(u, np.log(p), 2)
            center.append(-lin / (2.0 * quad))
            nominal.append(0.5 * (u[2] + u[0])
                           + math.log(p[2] / p[0]) / (2.0 * k * (u[2] - u[0])))
            peak.append(p[1])
            powers.append(p)
            offsets.append(u)
            times.append(data[axis][1][2])
        out[c] = {"center": tuple(center), "nominal": tuple(nominal), "peak": tuple(peak),
                  "powers": powers, "offsets": offsets, "times": tuple(times)}
    return out


@pytest.fixture(scope="session")
def probe():
    """``(probe_beam, source_trajectory)``: see :func:`probe_beam`."""
    return probe_beam, source_trajectory


# ---------------------------------------------------------------------------------------------
# antsim as a user installs it: a wheel, in a fresh virtual environment, outside the clone
class Installed:
    """A fresh virtual environment holding antsim's wheel (``bin``: its scripts). Its
    dependencies are this interpreter's (a ``.pth`` line, which imports nothing of antsim:
    the ``.pth`` files of that folder, such as an editable install's, are not read), so that
    no network and no minute of installing is needed; antsim itself comes from the wheel
    only."""

    def __init__(self, venv: Path, wheel: Path):
        self.venv, self.wheel = venv, wheel
        self.bin = venv / "bin"

    def environ(self, **extra: str) -> dict[str, str]:
        """This process's environment with the venv's ``bin`` first on PATH and no
        PYTHONPATH (plus ``extra``): what a user who installed the wheel has."""
        import os

        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        env["PATH"] = f"{self.bin}{os.pathsep}{env.get('PATH', '')}"
        env["VIRTUAL_ENV"] = str(self.venv)
        env.update(extra)
        return env

    def run(self, command: str, cwd: Path, timeout: float = 300.0, **extra: str):
        """``command`` (a shell line, as a README writes it) in ``cwd`` in
        :meth:`environ`: what a user who installed the wheel runs."""
        import subprocess

        return subprocess.run(["bash", "-c", command], cwd=cwd, env=self.environ(**extra),
                              capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="session")
def built_wheel(tmp_path_factory) -> Path:
    """antsim's wheel, built once per session from this tree (without build isolation, so
    offline: hatchling comes with the test extras)."""
    import subprocess
    import sys

    pytest.importorskip("hatchling", reason="building the wheel needs hatchling (test extras)")
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    "--no-index", "-q", "-w", str(out), str(REPO)], check=True,
                   capture_output=True, text=True)
    (wheel,) = out.glob("antsim-*.whl")
    return wheel


@pytest.fixture(scope="session")
def installed(built_wheel, tmp_path_factory) -> Installed:
    """:class:`Installed`: the wheel in a fresh virtual environment."""
    import subprocess
    import sys
    import sysconfig
    import venv

    root = tmp_path_factory.mktemp("venv")
    venv.create(root, with_pip=False)
    (site,) = (root / "lib").glob("python*/site-packages")
    (site / "_antsim_test_dependencies.pth").write_text(
        sysconfig.get_paths()["purelib"] + "\n" + sysconfig.get_paths()["platlib"] + "\n",
        encoding="utf-8")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(root / "bin" / "python"),
                    "install", "--no-deps", "--no-index", "-q", str(built_wheel)], check=True,
                   capture_output=True, text=True)
    return Installed(root, built_wheel)


def member_engine(scenario_text: str, directory: Path):
    """(scenario, member engine) of a scenario's text: its quiet campaign's shared schedule
    and a reference world, as antsim plan builds them (written to ``directory``)."""
    import simpy

    from antsim.scenario import load_scenario
    from antsim.simulate.vectorized import MemberEngine, quiet_scenario, record_schedule
    from antsim.world.world import World

    path = directory / "scenario.toml"
    path.write_text(scenario_text, encoding="utf-8")
    scenario = load_scenario(path)
    quiet = quiet_scenario(scenario)
    shared, _ = record_schedule(quiet)
    terms, name = scenario.controller.fit_spec()
    return scenario, MemberEngine(scenario, shared, World(quiet, simpy.Environment(), 0),
                                  terms, name)
