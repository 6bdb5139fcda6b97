"""The azimuth of a TPOINT file, end to end, on files whose true azimuths are known.

TPOINT writes its terms in its own azimuth, South = 0, East = 90 (A_T = 180 deg - A_N: the
mirror image of the North-based azimuth, not a half turn of it; TPOINT routine tptPterms,
note 8; Bisque's TPoint manual, appendix "The Pointing Terms"), and takes a data file's
azimuth North-based. A synthetic file is written here from known North-based azimuths with a
known physical error (the azimuth axis's pole tilted towards a known azimuth, computed with
a rotation, and an elevation nod three times a turn in TPOINT's own azimuth), then read and
fitted as a user would: the fit must give TPOINT's coefficients with TPOINT's meaning (AN > 0:
the pole north of the zenith; AW > 0: west of it), and the tilt's direction comes back.
antsim's terms are TPOINT's at A_T = 180 deg - A_N on any data, so the same holds for
North-based CSV measurements, for the simulated telescope's recordings (a tilt the world
makes with a rotation) and for those recordings written as a TPOINT file; a TPOINT file's
stars keep their true azimuth (docs/inputs.md, "The azimuth of a TPOINT file").
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.pointing.fitting import fit_model
from controller.program.inputs import read_pointing_file

RNG = np.random.default_rng(44)  # positions only: the errors are exact, no noise
N = 80
TRUE_AZ_DEG = RNG.uniform(0.0, 360.0, N)
TRUE_EL_DEG = RNG.uniform(15.0, 80.0, N)
TILT_ARCSEC = 60.0
TILT_TOWARDS_DEG = 30.0  # the pole of the azimuth axis leans towards azimuth 30 (N = 0, E = 90)
NOD_ARCSEC = 8.0  # TPOINT's HESA3: dE = +8" sin 3 A_T, A_T = 180 deg - A_N
TERMS = ["IA", "IE", "AN", "AW", "HESA3", "HECA3"]


def _encoder_positions() -> tuple[np.ndarray, np.ndarray]:
    """Encoder (raw) azimuth and elevation (deg) that put the beam on the true positions, of
    a mount whose azimuth axis is tilted (a rotation taking the true vertical to the pole),
    plus the elevation nod."""
    tau = math.radians(TILT_ARCSEC / 3600.0)
    phi = math.radians(TILT_TOWARDS_DEG)
    pole = np.array([math.sin(tau) * math.cos(phi), math.sin(tau) * math.sin(phi),
                     math.cos(tau)])  # (north, east, up)
    axis = np.cross(pole, [0.0, 0.0, 1.0])
    axis /= np.linalg.norm(axis)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                  [-axis[1], axis[0], 0.0]])
    rotation = np.eye(3) + math.sin(tau) * k + (1.0 - math.cos(tau)) * k @ k  # pole -> up
    a, e = np.radians(TRUE_AZ_DEG), np.radians(TRUE_EL_DEG)
    mount = rotation @ np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    raw_az = np.degrees(np.arctan2(mount[1], mount[0])) % 360.0
    raw_el = np.degrees(np.arcsin(mount[2]))
    a_t = np.radians(180.0 - TRUE_AZ_DEG)  # TPOINT's own azimuth
    raw_el = raw_el - NOD_ARCSEC / 3600.0 * np.sin(3.0 * a_t)  # true = raw + correction
    return raw_az, raw_el


def _tpoint_file(tmp_path, az_of=lambda a: a) -> str:
    raw_az, raw_el = _encoder_positions()
    lines = ["synthetic run, North-based azimuths", ": ALTAZ", "+38 25 48.00"]
    lines += [f"{az_of(TRUE_AZ_DEG[i]) % 360.0:.8f} {TRUE_EL_DEG[i]:.8f} "
              f"{az_of(raw_az[i]) % 360.0:.8f} {raw_el[i]:.8f}" for i in range(N)]
    path = tmp_path / "synthetic.dat"
    path.write_text("\n".join([*lines, "END"]) + "\n", encoding="utf-8")
    return str(path)


def _fit(path: str) -> dict[str, float]:
    data = read_pointing_file(path).pointing_data()
    return fit_model(data, TERMS, robust=False).model.as_dict()


def test_a_tpoint_file_is_fitted_as_tpoint_fits_it(tmp_path):
    """AN = tilt cos(towards), AW = -tilt sin(towards) (pole north, west positive), HESA3 the
    nod; the pole's azimuth comes back from AN and AW. The tolerance: the small-angle terms
    leave the tilt's second order, (60")^2 / 206265" ~ 0.02", and 8 decimals of a degree
    are 0.00004"."""
    fit = _fit(_tpoint_file(tmp_path))
    towards = math.radians(TILT_TOWARDS_DEG)
    assert fit["AN"] == pytest.approx(TILT_ARCSEC * math.cos(towards), abs=0.05)
    assert fit["AW"] == pytest.approx(-TILT_ARCSEC * math.sin(towards), abs=0.05)
    assert fit["HESA3"] == pytest.approx(NOD_ARCSEC, abs=0.05)
    assert fit["HECA3"] == pytest.approx(0.0, abs=0.05)
    assert math.degrees(math.atan2(-fit["AW"], fit["AN"])) == pytest.approx(TILT_TOWARDS_DEG,
                                                                            abs=0.1)


def test_a_file_written_south_zero_east_ninety_is_a_mirror_image(tmp_path):
    """The MMT's files are written as 180 deg - A_N ("South = 0, East = 90"): read as TPOINT
    reads a file (North-based) they are the telescope mirrored north-south: AN changes sign,
    AW and the nod (sin 3A) do not."""
    fit = _fit(_tpoint_file(tmp_path, az_of=lambda a: 180.0 - a))
    towards = math.radians(TILT_TOWARDS_DEG)
    assert fit["AN"] == pytest.approx(-TILT_ARCSEC * math.cos(towards), abs=0.05)
    assert fit["AW"] == pytest.approx(-TILT_ARCSEC * math.sin(towards), abs=0.05)
    assert fit["HESA3"] == pytest.approx(NOD_ARCSEC, abs=0.05)


def test_antsims_azimuth_of_a_tpoint_file_is_the_true_one(tmp_path):
    """What diagnose's exact tilt (tilt_az_deg) and its "towards the north" groups read."""
    data = read_pointing_file(_tpoint_file(tmp_path)).pointing_data()
    np.testing.assert_allclose(np.degrees(data.az_rad) % 360.0, TRUE_AZ_DEG % 360.0,
                               atol=1e-6)


def test_north_based_measurements_give_tpoints_coefficients(tmp_path):
    """The same telescope measured as CSV (North-based, indicated minus true): the same
    coefficients as the TPOINT file's, the tolerance the first test's."""
    raw_az, raw_el = _encoder_positions()
    d_az = (raw_az - TRUE_AZ_DEG + 180.0) % 360.0 - 180.0
    rows = [f"{TRUE_AZ_DEG[i]:.8f},{TRUE_EL_DEG[i]:.8f},"
            f"{d_az[i] * 3600.0 * math.cos(math.radians(TRUE_EL_DEG[i])):.5f},"
            f"{(raw_el[i] - TRUE_EL_DEG[i]) * 3600.0:.5f}" for i in range(N)]
    path = tmp_path / "synthetic.csv"
    path.write_text("# sign: indicated-minus-true\naz_deg,el_deg,d_xel_arcsec,d_el_arcsec\n"
                    + "\n".join(rows) + "\n", encoding="utf-8")
    fit = _fit(str(path))
    towards = math.radians(TILT_TOWARDS_DEG)
    assert fit["AN"] == pytest.approx(TILT_ARCSEC * math.cos(towards), abs=0.05)
    assert fit["AW"] == pytest.approx(-TILT_ARCSEC * math.sin(towards), abs=0.05)
    assert fit["HESA3"] == pytest.approx(NOD_ARCSEC, abs=0.05)
    assert fit["HECA3"] == pytest.approx(0.0, abs=0.05)


#: the simulated telescope's tilt: 1' towards azimuth 30 deg (N = 0, E = 90)
WORLD_TILT_ARCMIN = 1.0


def test_a_tilt_the_world_makes_comes_back_with_tpoints_signs(quiet_path, tmp_path):
    """The noise-free test world (tests/data/scenarios/quiet.toml, three hours, its extended
    source made a point) with its azimuth axis tilted by a rotation (the effect
    exact_tilt_collimation: 1' towards azimuth 30 deg), observed by antsim's own campaign:
    its recordings, and the same recordings written as a TPOINT data file, both give AN =
    +tilt cos 30, AW = -tilt sin 30. Tolerance 0.3": the second order of a 1' tilt is
    (60")^2 / 206265" tan E < 0.1" below 80 deg, and the noise-free reduction leaves
    ~0.1" (the residual rms is checked too)."""
    from antsim.scenario import load_scenario
    from antsim.simulate.runner import run_campaign
    from controller.pointing.tpoint import RunParameters, TPointData, write_tpoint
    from tests.conftest import edit_text

    text = edit_text(quiet_path.read_text(encoding="utf-8"), (
        ("duration_h = 1.0", "duration_h = 3.0"),
        ("size_arcmin = 3.46", "size_arcmin = 0.0"),
        ("[controller]", '[[truth.effects]]\neffect = "exact_tilt_collimation"\n'
                         f"tilt_arcmin = {WORLD_TILT_ARCMIN}\ntilt_az_deg = 30.0\n\n"
                         "[controller]")))
    scenario_path = tmp_path / "tilted.toml"
    scenario_path.write_text(text, encoding="utf-8")
    run_campaign(load_scenario(scenario_path), tmp_path / "run", show_progress=False)
    recordings = read_pointing_file(str(tmp_path / "run" / "recordings.ecsv")).pointing_data()
    assert recordings.az_rad.size >= 20
    az, el = np.degrees(recordings.az_rad), np.degrees(recordings.el_rad)
    exported = tmp_path / "recordings.dat"
    write_tpoint(TPointData.from_azel(
        "antsim recordings", RunParameters(38.43), az, el,
        az + recordings.xel_arcsec / 3600.0 / np.cos(recordings.el_rad),
        el + recordings.el_arcsec / 3600.0), exported)
    tilt = 60.0 * WORLD_TILT_ARCMIN
    towards = math.radians(30.0)
    for data in (recordings, read_pointing_file(str(exported)).pointing_data()):
        result = fit_model(data, ["IA", "IE", "AN", "AW"], robust=False)
        assert result.sky_rms_arcsec < 0.3
        assert result.model["AN"] == pytest.approx(tilt * math.cos(towards), abs=0.3)
        assert result.model["AW"] == pytest.approx(-tilt * math.sin(towards), abs=0.3)
