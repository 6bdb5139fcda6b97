"""Shared by the tests of antsim plan: plan files of the 1990 scenario cut to 3 hours
(``SHORT_EDITS``, about 30 scans), the member engine without the mount's irregularities, one
``antsim plan --out DIR`` run, and JSON documents compared to rounding."""

from __future__ import annotations

import math

import pytest

from antsim.cli import main as cli_main

PLAN = """name = "short"
scenario = "{scenario}"
seed = 7
members = {members}
block_members = {block}
{extra}
[[variants]]
name = "as run"
{variant}
"""


@pytest.fixture
def short_path(write_scenario, short_ghigo_text):
    return write_scenario(short_ghigo_text, name="short.toml")


@pytest.fixture
def write_plan(tmp_path, short_path):
    def write(members: int = 4, block: int = 2, variant: str = "", extra: str = "",
              more: str = "", name: str = "plan.toml"):
        text = PLAN.format(scenario=short_path.as_posix(), members=members, block=block,
                           variant=variant, extra=extra) + more
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path

    return write


@pytest.fixture(scope="module")
def smooth_engine(tmp_path_factory, short_ghigo_text):
    """The member engine of the 3-hour scenario without the mount's repeatable
    irregularities: on a 3-hour, five-source schedule their large fixed residuals make the
    robust fit's rejections, not the noise, most of the members' scatter, which the
    prediction's Gaussian rejection draws underestimate (W1, W2, W4 by 40-55% with them:
    docs/physics.md, The night residual)."""
    from tests.conftest import NOISE_ONLY, edit_text, member_engine

    smooth = edit_text(short_ghigo_text, [e for e in NOISE_ONLY
                                          if e[0].startswith(("az_", "el_enc", "track_"))])
    return member_engine(smooth, tmp_path_factory.mktemp("smooth"))


@pytest.fixture(scope="module")
def plan_out(tmp_path_factory, short_ghigo_text):
    """``antsim plan PLAN --workers 1 --no-answers --out DIR`` of 6 members in blocks of 2:
    (plan file, DIR)."""
    base = tmp_path_factory.mktemp("plan_out")
    scenario = base / "short.toml"
    scenario.write_text(short_ghigo_text, encoding="utf-8")
    path = base / "plan.toml"
    path.write_text(PLAN.format(scenario=scenario.as_posix(), members=6, block=2, variant="",
                                extra=""), encoding="utf-8")
    out = base / "out"
    assert cli_main(["plan", str(path), "--workers", "1", "--no-answers", "--no-progress",
                     "--out", str(out)]) == 0
    return path, out


def assert_docs_close(a, b, rtol: float, path: str = "") -> None:
    """Two JSON documents alike: the same keys, strings and integers; floats within rtol."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for key in a:
            assert_docs_close(a[key], b[key], rtol, f"{path}.{key}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_docs_close(x, y, rtol, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert a == b or (math.isnan(a) and math.isnan(b)) or math.isclose(
            a, b, rel_tol=rtol, abs_tol=0.0), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"
