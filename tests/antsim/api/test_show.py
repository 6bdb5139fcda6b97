"""antsim/api/show.py: angles in and out, a result's text table, figures kept in memory
without pyplot and without a file."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import astropy.units as u
import pytest

from antsim.api.show import arcsec, as_arcsec, table_text
from antsim.figures.html import Table
from controller.errors import InputError


def test_angles_given_and_returned():
    assert as_arcsec(1 * u.arcmin, "f", "x") == pytest.approx(60.0)
    assert as_arcsec(2 * u.deg, "f", "x") == pytest.approx(7200.0)
    assert as_arcsec(66, "f", "x") == 66.0
    for bad, words in ((3 * u.s, "must be one angle"), ([1, 2] * u.arcsec, "must be one angle"),
                       ("66", "must be an angle"), (True, "must be an angle")):
        with pytest.raises(InputError, match=words):
            as_arcsec(bad, "f", "x")
    assert arcsec(None) is None and arcsec(float("nan")) is None
    assert arcsec([1.0, 2.0]).unit == u.arcsec


def test_a_text_table_aligns_numbers_right_at_their_formats():
    table = Table(["term", "value (\")"], [["W1", -1.234], ["W10", 12.5], ["W2", None]],
                  caption="c", column_formats=(None, "+.1f"))
    assert table_text(table).split("\n") == ["c", "term  value (\")", "W1         -1.2",
                                             "W10       +12.5", "W2            -"]


def test_figures_in_memory_need_no_pyplot_and_write_nothing(tmp_path):
    code = textwrap.dedent(f"""
        import os, sys
        os.chdir({str(tmp_path)!r})
        import antsim
        campaign = antsim.run_campaign({str(tmp_path / "short.toml")!r})
        figures = campaign.figures()
        print(len(figures), "matplotlib.pyplot" in sys.modules, sorted(os.listdir(".")))
        print(type(campaign.plot_errors()).__module__)
    """)
    from tests.conftest import REPO, SHORT_EDITS, edit_text

    (tmp_path / "short.toml").write_text(
        edit_text((REPO / "scenarios" / "ghigo1990.toml").read_text(encoding="utf-8"),
                  SHORT_EDITS), encoding="utf-8")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[:2] == ["11 False ['short.toml']", "matplotlib.figure"]
