"""The controller driving the simulated antenna: scans, reduction, scheduling, recordings."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from antsim.scenario import load_scenario
from antsim.simulate.runner import run_campaign, simulate
from antsim.world.atmosphere import AtmosphereConfig
from controller.pointing.model import PointingModel
from controller.program.recordings import COLUMN_NAMES, read_pointing_data, read_recordings
from controller.scans.config import SkyConfig

ROOT = Path(__file__).resolve().parents[3]
GHIGO = ROOT / "scenarios" / "ghigo1990.toml"


@pytest.fixture(scope="module")
def ghigo():
    return load_scenario(GHIGO)


def quiet(scenario, hours: float, truth: PointingModel, estimator: str = "clark"):
    """A noise-free, effect-free, transparent-sky version of ``scenario``."""
    channels = tuple(replace(c, gain_fluctuation=0.0) for c in scenario.receiver.channels)
    receiver = replace(scenario.receiver, gain_fluctuation=0.0, bandwidth_mhz=1e12,
                       channels=channels)
    scan = replace(scenario.controller.scan, estimator=estimator)
    scheduler = replace(scenario.controller.scheduler, min_revisit_s=300.0)
    controller = replace(scenario.controller, model=PointingModel(), scan=scan,
                         scheduler=scheduler, duration_s=hours * 3600.0, sky=None)
    return replace(scenario, duration_s=hours * 3600.0, effects=(), receiver=receiver,
                   atmosphere=AtmosphereConfig(zenith_opacity=0.0, temperature_k=270.0),
                   truth_model=truth, controller=controller)


@pytest.mark.parametrize("estimator", ["clark", "lsq"])
def test_noise_free_scans_reduce_to_the_injected_offset(ghigo, estimator):
    # injected errors constant on the sky: 2' of collimation (W10: dA cos E = W10, so
    # xel = 2') and 3' of elevation encoder offset (W1); point sources only, so the reduction
    # must return them exactly
    truth = PointingModel(["W10", "W1"], [120.0, 180.0], name="test")
    sc = quiet(ghigo, 3.0, truth, estimator)
    sources = [s for s in sc.sources if s.size_arcmin == 0.0]
    sc = replace(sc, sources=tuple(sources),
                 controller=replace(sc.controller, sources=tuple(
                     c for c in sc.controller.sources if c.name in {s.name for s in sources})))
    result = simulate(sc, seed=5)
    avg = [r for r in result.rows if r["polarization"] == "AVG"]
    assert len(avg) >= 20
    for r in avg:
        assert r["good"]
        # 0.005' = 0.3": the world solves B + d(B) = encoder exactly and both estimators are
        # exact for a point source on the nominal grid. What remains is second-order geometry
        # of the 2-3' offsets, measured at up to 0.25": the collimation, defined at the
        # beam's elevation 3' below the source, is seen from the source as 2' cos E_source /
        # cos E_beam, a cross-elevation offset x moves the elevation by ~x^2/2 tan E (0.08"
        # seen with the collimation alone), and the gain changes while the source rises
        assert r["xel_arcmin"] == pytest.approx(2.0, abs=0.005)
        assert r["el_arcmin"] == pytest.approx(3.0, abs=0.005)
        # the amplitude is the source's peak antenna temperature: flux x gain x efficiency
        flux = next(s.flux_jy for s in sc.sources if s.name == r["source"])
        eff = float(np.interp(r["el_deg"], sc.beam.efficiency_el_deg, sc.beam.efficiency))
        peak = flux * sc.beam.gain_k_per_jy * eff
        # the az scan runs at the el offset of 3': the peak is attenuated by the beam there
        attenuation = math.exp(-4 * math.log(2) * (3.0 / 11.0) ** 2)
        assert r["xel_amp_k"] == pytest.approx(peak * attenuation, rel=2e-3)


@pytest.mark.parametrize("estimator", ["clark", "lsq"])
def test_azimuth_steps_follow_the_sky_elevation_up_to_the_zenith(ghigo, estimator):
    # the model in use moves the encoder 11' above the source (true elevation error 12'):
    # azimuth steps divided by the cosine of the encoder's elevation would scale the cross-
    # elevation grid by 1 + 11' tan E (1.8% at 80 deg, 0.018' on the 1' offset), and steps
    # computed at the move's start rather than the integration's middle by ~0.7% near the
    # zenith, where cos E changes by ~3% a minute. Both are gone: every scan to 85 deg is
    # exact to the 0.005' of the point-source test. Exact means to second order too: the
    # 1' collimation (W10 sec E in dA, E the beam's elevation, 1' below the source) is seen from
    # the source as 1' cos(E_source) / cos(E_beam), 0.2" less at 85 deg (measured errors
    # then at most 0.11" in cross-elevation and 0.18" in elevation, both estimators)
    truth = PointingModel(["W10", "W1"], [60.0, 720.0], name="test")
    sc = quiet(ghigo, 12.0, truth, estimator)
    sources = [s for s in sc.sources if s.size_arcmin == 0.0]
    controller = replace(sc.controller, model=PointingModel(["W1"], [660.0], name="in use"),
                         sources=tuple(c for c in sc.controller.sources
                                       if c.name in {s.name for s in sources}))
    sc = replace(sc, sources=tuple(sources), controller=controller)
    avg = [r for r in simulate(sc, seed=5).rows if r["polarization"] == "AVG"]
    assert max(r["el_deg"] for r in avg) > 80.0
    el = np.radians([r["el_deg"] for r in avg])
    xel = np.cos(el) / np.cos(el - np.radians(1.0 / 60.0))
    error = np.array([[r["xel_arcmin"] for r in avg] - xel,
                      [r["el_arcmin"] - 1.0 for r in avg]])
    assert np.abs(error).max() < 0.005, np.abs(error).max(axis=1)


@pytest.mark.parametrize(("estimator", "use_size"),
                         [("clark", False), ("clark", True), ("lsq", True)])
def test_extended_sources_and_the_width_the_reduction_assumes(ghigo, estimator, use_size):
    # a source of Gaussian FWHM s seen with the 11' beam is a Gaussian of width
    # sqrt(11^2 + s^2): Clark's method with the beam's width shrinks its offsets by
    # 11^2/(11^2 + s^2) (0.91 for Cas A and Tau A, docs/physics.md); with the width the
    # catalogued size gives (use_source_size) both estimators are exact. 1' and 1.5' are
    # injected: the shrinkage is then 0.09-0.2', the tolerance of 0.005' (0.3") holds the
    # second-order geometry (measured 0.003' at most for Clark)
    truth = PointingModel(["W10", "W1"], [60.0, 90.0], name="test")
    sc = quiet(ghigo, 3.0, truth, estimator)
    sources = [s for s in sc.sources if s.size_arcmin > 0.0]
    controller = replace(sc.controller, scan=replace(sc.controller.scan, use_source_size=use_size),
                         sources=tuple(c for c in sc.controller.sources
                                       if c.name in {s.name for s in sources}))
    sc = replace(sc, sources=tuple(sources), controller=controller)
    result = simulate(sc, seed=5)
    size = {s.name: s.size_arcmin for s in sources}
    avg = [r for r in result.rows if r["polarization"] == "AVG"]
    assert len(avg) >= 10 and sum(size[r["source"]] >= 3.0 for r in avg) >= 3
    for r in avg:
        assert r["good"]
        shrink = 1.0 if use_size else 11.0**2 / (11.0**2 + size[r["source"]] ** 2)
        assert r["xel_arcmin"] == pytest.approx(1.0 * shrink, abs=0.005)
        assert r["el_arcmin"] == pytest.approx(1.5 * shrink, abs=0.005)


@pytest.mark.parametrize("knows_sky", [False, True])
def test_sky_drift_in_time_and_the_a_priori_atmosphere(ghigo, knows_sky):
    # a thick sky (tau = 0.05) brightens by ~0.1 K per integration under a source rising at
    # 15 deg: Clark's straight baseline through the +-4D points removes the emission's slope
    # across the elevation scan but not its drift in time, so the offsets are biased by
    # ~4.8' d / A (several arcmin for a 1 K source). Subtracting the emission the controller
    # predicts from its a-priori atmosphere (equal to the world's here) removes it: the
    # offsets are exact to the 0.005' of the point-source test
    truth = PointingModel(["W10", "W1"], [60.0, 90.0], name="test")
    sc = quiet(ghigo, 3.0, truth, "clark")
    sources = [s for s in sc.sources if s.size_arcmin == 0.0]
    atmosphere = AtmosphereConfig(zenith_opacity=0.05, temperature_k=270.0)
    sky = SkyConfig(zenith_opacity=0.05, t_atm_k=270.0) if knows_sky else None
    controller = replace(sc.controller, sky=sky, sources=tuple(
        c for c in sc.controller.sources if c.name in {s.name for s in sources}))
    sc = replace(sc, sources=tuple(sources), controller=controller, atmosphere=atmosphere)
    result = simulate(sc, seed=5)
    avg = [r for r in result.rows if r["polarization"] == "AVG"]
    assert len(avg) >= 10 and min(r["el_deg"] for r in avg) < 25.0
    error = np.array([[r["xel_arcmin"] - 1.0, r["el_arcmin"] - 1.5] for r in avg])
    if knows_sky:
        assert np.abs(error).max() < 0.005
    else:
        assert np.abs(error[:, 1]).max() > 0.05


def test_a_cold_start_searches_across_and_keeps_an_azimuth_offset(ghigo):
    """No model, the 1990 truth (Table 3 on the report's functions): 3C84 rising at 22 deg is
    8.6' away across (the 12.24' azimuth encoder offset W6 is 11.4' cos E there, less the
    collimation and axis terms) and 3' in elevation, so the first scan misses. The wide
    search's elevation half passes the source 9' to the side: only its cross-elevation offset
    is adopted, and the scan after it is centred to within half a beam in both axes (had the
    search's elevation been adopted it would have been ~6' wrong: ``max_cross_offset_beams =
    0.5``). The scenario keeps the
    correction as an azimuth offset (``search.correction = "encoders"``): Cygnus A at 78 deg
    then gets it times cos E, and no search; the default keeps it constant on the sky."""
    import simpy

    from antsim.world.world import World
    from controller.program.campaign import ControlProgram

    cold = ghigo.with_controller_model(PointingModel("none"))
    env = simpy.Environment()
    program = ControlProgram(cold.controller, World(cold, env, cold.seed).antenna)
    target = {t.name: t for t in program.targets}
    first = env.run(until=env.process(program.observe(env, target["3C84"])))
    row = first.rows[-1]
    assert first.searches == 1 and 20.0 < row["el_deg"] < 24.0
    truth = cold.truth_model.offset_rad(math.radians(row["az_deg"]), math.radians(row["el_deg"]))
    true_xel = truth[0] * math.cos(math.radians(row["el_deg"])) * 3437.75
    assert true_xel > 8.0 and abs(truth[1] * 3437.75) < 4.0
    assert row["applied_el_arcmin"] == 0.0  # the search's elevation was not trusted
    # 1' tolerance: the wide search's 5 s integrations on its 14' grid
    assert row["applied_xel_arcmin"] == pytest.approx(true_xel, abs=1.0)
    assert abs(row["xel_arcmin"]) < 5.5 and abs(row["el_arcmin"]) < 5.5 and row["good"]
    d_az = program.running_correction_arcmin[0]
    assert d_az == pytest.approx(row["applied_xel_arcmin"] / math.cos(math.radians(22.0)),
                                 rel=0.02)
    t0 = env.now
    second = env.run(until=env.process(program.observe(env, target["Cygnus A"])))
    row2 = second.rows[-1]
    assert second.searches == 0 and row2["el_deg"] > 70.0
    # applied as the trajectory is made, before the slew: the azimuth offset times cos E of
    # the source then (within a degree of the row's elevation: 0.2' at 78 deg)
    applied = program.correction_arcmin(target["Cygnus A"], t0)
    assert row2["applied_xel_arcmin"] == applied[0] and row2["applied_el_arcmin"] == 0.0
    assert applied[0] == pytest.approx(d_az * math.cos(math.radians(row2["el_deg"])), abs=0.2)
    assert cold.controller.search.correction == "encoders"  # the scenario's choice
    # the default keeps the correction constant on the sky: Cygnus A gets 3C84's offset
    sky = replace(cold.controller, search=replace(cold.controller.search, correction="sky"))
    env = simpy.Environment()
    program = ControlProgram(sky, World(cold, env, cold.seed).antenna)
    first = env.run(until=env.process(program.observe(env, target["3C84"])))
    second = env.run(until=env.process(program.observe(env, target["Cygnus A"])))
    assert second.rows[-1]["applied_xel_arcmin"] == first.rows[-1]["applied_xel_arcmin"] > 8.0
    # and without the cross-offset limit the search's elevation, measured 9' aside, is
    # adopted: more than 3' from the true elevation error (6' at seed 1)
    every = replace(cold.controller, search=replace(cold.controller.search,
                                                    max_cross_offset_beams=None))
    env = simpy.Environment()
    program = ControlProgram(every, World(cold, env, cold.seed).antenna)
    row = env.run(until=env.process(program.observe(env, target["3C84"]))).rows[-1]
    true_el = cold.truth_model.offset_rad(math.radians(row["az_deg"]),
                                          math.radians(row["el_deg"]))[1] * 3437.75
    assert abs(row["applied_el_arcmin"] - true_el) > 3.0


def test_ghigo1990_gives_about_300_scans_over_all_sources(ghigo):
    result = simulate(ghigo)
    avg = [r for r in result.rows if r["polarization"] == "AVG"]
    assert 250 <= len(avg) <= 350
    assert {r["source"] for r in avg} == {s.name for s in ghigo.sources}
    # scans are spread over the sky: every quadrant of azimuth is visited, low and high
    az = np.array([r["az_deg"] for r in avg])
    el = np.array([r["el_deg"] for r in avg])
    for lo in (0, 90, 180, 270):
        assert np.any((az >= lo) & (az < lo + 90))
    assert el.min() < 20 and el.max() > 60
    # by day and by night
    sun = np.array([r["sun_el_deg"] for r in avg])
    assert (sun > 0).sum() > 60 and (sun < -12).sum() > 60
    # three rows per scan: XR, XL and their average
    pols = [r["polarization"] for r in result.rows]
    assert pols.count("XR") == pols.count("XL") == pols.count("AVG")


def test_recent_history_is_the_same_as_scanning_it_all():
    """The spread policy's memory is bisected and each source's last time kept (a month's
    history made the scans quadratic); they must give exactly what scanning the history
    gives, boundaries included."""
    from controller.program.constraints import History

    rng = np.random.default_rng(5)
    memory_s = 6 * 3600.0
    history = History()
    for t, name in zip(np.cumsum(rng.choice([0.0, 250.0, 0.1, memory_s], size=400)),
                       rng.choice(["a", "b", "c"], size=400, p=[0.6, 0.39, 0.01]), strict=True):
        history.add(float(t), str(name), 0.0, 45.0)
    # now at, just after and between the observation times, so t_s - t == memory_s occurs
    for now in [t + memory_s for t in history.t_s[::7]] + [0.0, history.t_s[-1] + 1e6]:
        plain = [i for i, t in enumerate(history.t_s) if now - t <= memory_s]
        assert list(history.recent(now, memory_s)) == plain
    history.add(history.t_s[-1] - 10.0, "b", 0.0, 45.0)  # out of order: no bisection
    now = history.t_s[-1] + memory_s
    assert not history.in_time_order
    assert list(history.recent(now, memory_s)) == [
        i for i, t in enumerate(history.t_s) if now - t <= memory_s]
    # each source's last time is that of its latest entry (not the largest time), also in
    # a history made from lists
    copy = History(list(history.t_s), list(history.names), list(history.az_deg),
                   list(history.el_deg))
    assert not copy.in_time_order
    for name in ("a", "b", "c", "never"):
        latest = [t for t, n in zip(history.t_s, history.names, strict=True) if n == name]
        assert history.last_time(name) == copy.last_time(name) == (
            latest[-1] if latest else None)


def test_night_window_keeps_the_sun_down(ghigo):
    sched = replace(ghigo.controller.scheduler, window="night")
    sc = replace(ghigo, controller=replace(ghigo.controller, scheduler=sched))
    result = simulate(sc)
    sun = np.array([r["sun_el_deg"] for r in result.rows])
    assert len(sun) > 0
    # the scan starts at night; it lasts about 4 minutes, in which the Sun rises < 1 deg
    assert sun.max() < -11.0


def test_recordings_round_trip(ghigo, tmp_path):
    sc = replace(ghigo, duration_s=2 * 3600.0,
                 controller=replace(ghigo.controller, duration_s=2 * 3600.0))
    result = run_campaign(sc, tmp_path, show_progress=False)
    table = read_recordings(tmp_path / "recordings.ecsv")
    assert tuple(table.colnames) == COLUMN_NAMES
    assert len(table) == len(result.rows)
    for i, row in enumerate(result.rows):
        for name in COLUMN_NAMES:
            value = table[name][i]
            if isinstance(row[name], float):
                assert float(value) == row[name] or (math.isnan(row[name])
                                                     and math.isnan(float(value)))
            else:
                assert value == row[name]
    assert table["xel_arcmin"].unit == "arcmin"
    meta = table.meta
    assert meta["scenario"] == "ghigo1990" and meta["seed"] == sc.seed
    assert meta["model"]["name"] == "ghigo10"
    assert meta["model"]["terms_arcsec"]["W6"] == pytest.approx(720.0)
    assert meta["model"]["w_terms"] == "Ghigo 1990 (NRAO EDIR 288) section II"
    assert meta["step_arcmin"] == 7.0 and meta["beam_hpbw_arcmin"] == 11.0
    # total pointing error = measured + model in use + applied correction
    data = read_pointing_data(tmp_path / "recordings.ecsv")
    avg = [r for r in result.rows if r["polarization"] == "AVG" and r["good"]]
    expected_el = [60 * (r["el_arcmin"] + r["model_el_arcmin"] + r["applied_el_arcmin"])
                   for r in avg]
    assert np.allclose(data.el_arcsec, expected_el)


def test_resume_after_a_torn_write_is_byte_identical(ghigo, tmp_path):
    sc = replace(ghigo, duration_s=2 * 3600.0,
                 controller=replace(ghigo.controller, duration_s=2 * 3600.0))
    full = tmp_path / "full"
    run_campaign(sc, full, show_progress=False)
    reference = (full / "recordings.ecsv").read_bytes()
    names_line = reference.index(b"\nscan ") + 1
    header_end = reference.index(b"\n", names_line) + 1  # first byte of the first data row
    body_lines = reference[header_end:].count(b"\n")
    assert body_lines > 20
    rng = np.random.default_rng(7)
    # cut the file anywhere: inside the header, mid-line, exactly at a line end
    cuts = [header_end - 5, header_end + 10, reference.index(b"\n", header_end + 2000) + 1,
            *rng.integers(header_end, len(reference) - 1, size=3)]
    for cut in cuts:
        part = tmp_path / f"cut{cut}"
        part.mkdir()
        (part / "recordings.ecsv").write_bytes(reference[:cut])
        if cut < header_end:
            # a torn header is not this run's header: resuming refuses, it does not guess
            from controller.errors import InputError

            with pytest.raises(InputError):
                run_campaign(sc, part, resume=True, show_progress=False)
            continue
        # what is on disk is readable up to the last complete row
        table = read_recordings(part / "recordings.ecsv")
        assert len(table) == reference[header_end:cut].count(b"\n")
        run_campaign(sc, part, resume=True, show_progress=False)
        assert (part / "recordings.ecsv").read_bytes() == reference


def test_resume_refuses_another_runs_file(ghigo, tmp_path):
    from controller.program.recordings import ResumeMismatchError

    sc = replace(ghigo, duration_s=1 * 3600.0,
                 controller=replace(ghigo.controller, duration_s=1 * 3600.0))
    run_campaign(sc, tmp_path, seed=1, show_progress=False)
    text = (tmp_path / "recordings.ecsv").read_text()
    # same header (same seed), but a tampered data row
    lines = text.splitlines(keepends=True)
    lines[-1] = lines[-1].replace("AVG", "XR", 1)
    (tmp_path / "recordings.ecsv").write_text("".join(lines))
    with pytest.raises(ResumeMismatchError):
        run_campaign(sc, tmp_path, seed=1, resume=True, show_progress=False)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_a_killed_run_leaves_a_readable_file_and_resumes(tmp_path):
    """Kill ``antsim run`` for real while it writes, then resume it."""
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "antsim", "run", str(GHIGO), "--out", str(out),
           "--no-progress"]
    env = dict(os.environ, PYTHONHASHSEED="0")
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    target = out / "recordings.ecsv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if target.exists() and target.stat().st_size > 30_000:
            proc.send_signal(signal.SIGKILL)
            break
        time.sleep(0.002)
    proc.wait()
    if proc.returncode == 0:
        pytest.skip("the run finished before it could be killed (machine too fast)")
    table = read_recordings(target)
    assert len(table) > 0
    resumed = subprocess.run([*cmd, "--resume"], capture_output=True, env=env, check=False)
    assert resumed.returncode == 0, resumed.stderr.decode()
    fresh = tmp_path / "fresh"
    subprocess.run([sys.executable, "-m", "antsim", "run", str(GHIGO), "--out", str(fresh),
                    "--no-progress"], check=True, capture_output=True, env=env)
    assert target.read_bytes() == (fresh / "recordings.ecsv").read_bytes()
