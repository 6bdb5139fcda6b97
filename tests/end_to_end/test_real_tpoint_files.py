"""Every real pointing run the project may read goes through the front door, and reads the
same with the comments observatories append to records. The runs live in the shared
folder beside the repository (``shared/data/real``, or ``ANTSIM_REAL_DATA``); the tests skip
without them."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from controller.pointing.tpoint import parse_tpoint
from controller.program.inputs import read_pointing_file

REPO = Path(__file__).resolve().parents[2]


def _real_folder() -> Path | None:
    given = os.environ.get("ANTSIM_REAL_DATA")
    for folder in ([Path(given)] if given else
                   [REPO.parent / "shared" / "data" / "real",
                    REPO.parent.parent / "shared" / "data" / "real"]):
        if (folder / "README.md").is_file():
            return folder
    return None


REAL = _real_folder()
#: the runs of the folder's README the tests may read (its last paragraph keeps others apart)
RUNS = ("auxtel_20200315.dat", "mmt_20210821_k_and_e.dat", "mmt_20230702.dat",
        "mmt_20230924.dat", "mmt_20250326.dat", "rts2_gpoint_altaz.dat")

pytestmark = pytest.mark.skipif(REAL is None, reason="the real runs are not next to the "
                                "repository (set ANTSIM_REAL_DATA)")


@pytest.mark.parametrize("name", RUNS)
def test_a_real_run_reads_through_the_front_door(name):
    file = read_pointing_file(REAL / name)
    assert file.kind == "tpoint" and file.tpoint.coordinates == "azel"
    points = file.pointing_data()
    assert len(points) == len(file.tpoint) > 40
    assert np.isfinite(points.xel_arcsec).all() and np.isfinite(points.el_arcsec).all()


@pytest.mark.parametrize("name", RUNS)
def test_a_real_run_reads_the_same_with_comments_after_its_records(name):
    text = (REAL / name).read_text(encoding="utf-8")
    plain = parse_tpoint(text, source=name)
    lines = text.splitlines()
    for i in plain.line_numbers - 1:
        lines[i] = f"{lines[i]} ; [{i:04d}] AT_O_{i:06d}"
    commented = parse_tpoint("\n".join(lines) + "\n", source=name)
    for field in ("lon_obs_deg", "lat_obs_deg", "lon_raw_deg", "lat_raw_deg"):
        np.testing.assert_array_equal(getattr(commented, field), getattr(plain, field))
