"""What ``antsim diagnose --out DIR`` writes, on arcsecond data (the MMT example, 80 stars,
Sky RMS ~0.9") and on a 45-ft run's recordings (the 1990 scenario cut to 3 hours, seed 1:
33 scans, Sky RMS ~59", nothing found):

* plots scaled to the residuals' spread: histogram bins and the sky map's key (the fixed 10"
  bins and 60" key of before drew one bar and no visible arrow on the MMT file);
* a before-only plot, captioned with what was tested, when nothing is found;
* report.html whose numbers are diagnose.json's and diagnose.txt's (one source), figures
  embedded byte for byte, rendering in a browser;
* model_updated.dat in TPOINT's vocabulary, read back by ``antsim run --model``.
"""

from __future__ import annotations

import json
import math
import re
from html import escape as html_escape
from pathlib import Path

import numpy as np
import pytest

from antsim.cli import main
from antsim.diagnose import diagnose, load_observations
from antsim.diagnose.modelit import residuals_before_after, write_outputs
from antsim.diagnose.report import FINDINGS_HEADER, RMS_HEADER
from antsim.figures.charts import histogram_edges, spread_arcsec
from controller.pointing.modelio import load_model
from tests.antsim.figures.test_figures import assert_sane_png
from tests.antsim.run.test_report_page import (
    _embedded,
    assert_renders_in_a_browser,
    needs_chromium,
    read_page,
)

REPO = Path(__file__).resolve().parents[2]
MMT = REPO / "examples" / "mmt_20210821_k_and_e.dat"
PLOTS = ["diagnose_residuals.png", "diagnose_histograms.png", "diagnose_quiver.png"]


def _diagnosed(path: Path, out: Path):
    diag = diagnose(load_observations(str(path)))
    write_outputs(diag, out)
    return diag, out


@pytest.fixture(scope="module")
def mmt(tmp_path_factory):
    """The MMT example diagnosed (four findings) with its outputs."""
    return _diagnosed(MMT, tmp_path_factory.mktemp("mmt"))


@pytest.fixture(scope="module")
def short_run(tmp_path_factory, short_ghigo_text) -> tuple[Path, Path]:
    """(scenario, run directory) of the 1990 scenario cut to 3 hours, seed 1."""
    base = tmp_path_factory.mktemp("run45")
    scenario = base / "short.toml"
    scenario.write_text(short_ghigo_text, encoding="utf-8")
    assert main(["run", str(scenario), "--out", str(base / "run"), "--no-report",
                 "--no-progress"]) == 0
    return scenario, base / "run"


@pytest.fixture(scope="module")
def ft45(short_run, tmp_path_factory):
    """The 45-ft run's recordings diagnosed without a scenario (nothing found)."""
    return _diagnosed(short_run[1] / "recordings.ecsv", tmp_path_factory.mktemp("diag45"))


def _used_before(diag) -> tuple[np.ndarray, np.ndarray]:
    _, before, _ = residuals_before_after(diag)
    return before.residual_xel_arcsec[before.used], before.residual_el_arcsec[before.used]


@pytest.mark.parametrize("case", ["mmt", "ft45"])
def test_plots_are_scaled_to_the_residuals(case, request):
    """The bin width the histogram's caption states and the quiver key follow the spread
    s of the baseline's residuals: bins a 1-2-5 number in (s/6.25, s/2.5], the key in
    (0.8 s, 2 s] (:func:`antsim.figures.charts.nice_step` rounds down by at most 2.5);
    every residual inside the drawn range, at least 6 non-empty bins per axis (the old
    fixed 10" bins give 1 on the MMT residuals, the old 60" key is 100 s there)."""
    diag, out = request.getfixturevalue(case)
    xel, el = _used_before(diag)
    s = spread_arcsec(xel, el)
    captions = read_page(out / "report.html").captions
    width = float(re.search(r'Bins of ([0-9.]+)"', captions[PLOTS[1]]).group(1))
    assert s / 6.25 < width <= s / 2.5
    edges = histogram_edges(np.concatenate([xel, el]), width)
    for v in (xel, el):
        counts = np.histogram(v, edges)[0]
        assert counts.sum() == v.size  # the axis covers every residual
        assert np.count_nonzero(counts) >= 6
    key, drawn = re.search(r'([0-9.]+)" of residual is drawn as ([0-9.]+)\N{DEGREE SIGN}',
                           captions[PLOTS[2]]).groups()
    assert 0.8 * s < float(key) <= 2.0 * s and float(drawn) == 6.0


def test_the_scales_differ_as_the_spreads_do(mmt, ft45):
    """Arcsecond and arcminute data get bins ~60 times apart (their spreads' ratio)."""
    widths = [float(re.search(r'Bins of ([0-9.]+)"',
                              read_page(out / "report.html").captions[PLOTS[1]]).group(1))
              for _, out in (mmt, ft45)]
    spreads = [spread_arcsec(*_used_before(d)) for d, _ in (mmt, ft45)]
    assert spreads[1] / spreads[0] > 20
    # each width within a factor 2.5 of its spread / 2.5: the ratios within 2.5^2
    assert 1 / 6.25 < (widths[1] / widths[0]) / (spreads[1] / spreads[0]) < 6.25


@pytest.mark.parametrize("case", ["mmt", "ft45"])
def test_figures_draw_the_residuals_the_text_reports(case, request):
    """One source: the residuals drawn are those whose rms diagnose.txt prints (Sky RMS and
    per axis, before and after), and the figures' titles print the same Sky RMS."""
    diag, out = request.getfixturevalue(case)
    _, before, after = residuals_before_after(diag)
    s = diag.summary
    for r, key in ((before, "before"), (after, "after")):
        x, e = r.residual_xel_arcsec[r.used], r.residual_el_arcsec[r.used]
        assert math.isclose(math.sqrt(np.mean(x * x + e * e)), s[f"sky_rms_{key}_arcsec"],
                            rel_tol=1e-9)
        assert np.allclose([math.sqrt(np.mean(x * x)), math.sqrt(np.mean(e * e))],
                           s[f"axis_rms_{key}_arcsec"], rtol=1e-9)
    text = (out / "diagnose.txt").read_text()
    b, a = re.search(r'Sky RMS in-sample ([0-9.]+)" -> ([0-9.]+)"', text).groups()
    captions = read_page(out / "report.html").captions  # the figures' titles and captions
    assert f"sky rms {b}\"" in captions[PLOTS[0]]
    if diag.findings:
        assert f"sky rms {b}\" \N{RIGHTWARDS ARROW} {a}\"" in captions[PLOTS[0]]


def test_nothing_found_draws_the_baseline_and_says_what_was_tested(ft45):
    diag, out = ft45
    doc = json.loads((out / "diagnose.json").read_text())
    assert doc["findings"] == [] and doc["outputs"]["plots"] == PLOTS
    assert len(doc["tested"]) >= 10
    captions = read_page(out / "report.html").captions
    for name in PLOTS:
        assert_sane_png(out / name)
        caption = captions[name]
        assert "nothing found" in caption.lower() or "nothing beyond" in caption
        assert f"tested {len(doc['tested'])} candidate effects" in caption
        assert all(t in caption for t in doc["tested"])
    assert diag.nothing_found_words() in (out / "diagnose.txt").read_text()


@pytest.mark.parametrize("case", ["mmt", "ft45"])
def test_report_page_numbers_are_the_json_numbers(case, request):
    _, out = request.getfixturevalue(case)
    doc = json.loads((out / "diagnose.json").read_text())
    page = read_page(out / "report.html")
    html = (out / "report.html").read_text()
    findings = page.tables.get("Findings, best first (arcsec)")
    if doc["findings"]:
        assert findings[0] == list(FINDINGS_HEADER)
        assert [r[1:6] for r in findings[1:]] == [
            [f["effect"], " ".join(f["terms"]), f"{f['significance']:.1f}",
             f"{f['sky_rms_before_arcsec']:.2f}", f"{f['sky_rms_after_arcsec']:.2f}"]
            for f in doc["findings"]]
    else:
        assert findings is None
    s = doc["summary"]
    rms = next(v for k, v in page.tables.items() if k.startswith("Residuals before"))
    assert rms[0] == list(RMS_HEADER)
    assert rms[1][1:] == [f"{s['sky_rms_before_arcsec']:.2f}", f"{s['sky_rms_after_arcsec']:.2f}"]
    assert rms[2][1:] == [f"{s['cv_sky_rms_before_arcsec']:.2f}",
                          f"{s['cv_sky_rms_after_arcsec']:.2f}"]
    assert [r[1:] for r in rms[3:]] == [
        [f"{s[f'{cv}axis_rms_before_arcsec'][k]:.1f}", f"{s[f'{cv}axis_rms_after_arcsec'][k]:.1f}"]
        for k in range(2) for cv in ("", "cv_")]
    text = (out / "diagnose.txt").read_text()
    assert html_escape(text.rstrip("\n")) in html  # ... and the page holds diagnose.txt whole
    embedded = _embedded(html)
    assert set(embedded) == set(doc["outputs"]["plots"])
    for name, data in embedded.items():
        assert data == (out / name).read_bytes()


def test_model_updated_in_tpoint_terms_round_trips_through_run(ft45, short_run, capsys):
    """The 45-ft baseline is the report's W1..W10: model_updated.dat writes TPOINT's names
    and signs (the W names in comments), states units and sign, points as the diagnosis's
    model does (to the file's 1e-4" rounding), and ``antsim run --model`` reads it and
    reports the pointing against the fit it came from (the T record's Sky RMS and count)."""
    diag, out = ft45
    path = out / "model_updated.dat"
    text = path.read_text()
    assert "! Units: arcsec. Sign: TPOINT's" in text
    names = load_model(path).names
    assert not any(n.startswith("W") for n in names) and {"IE", "IA", "CA", "TF"} <= set(names)
    assert "! W1 = -IE" in text
    az = np.radians(np.linspace(0.0, 350.0, 36))
    el = np.radians(np.linspace(20.0, 85.0, 36))
    got = np.array(load_model(path).offset_rad(az, el))
    want = np.array(diag.updated_model().offset_rad(az, el))
    # ten terms rounded to 5e-5" each, columns at most cot 20 deg = 2.7: < 1.5e-3"
    assert np.max(np.abs(got - want)) * 206264.806 < 1.5e-3
    scenario, _ = short_run
    capsys.readouterr()
    assert main(["run", str(scenario), "--out", str(out / "closed"), "--model", str(path),
                 "--no-report", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    s = diag.summary
    assert f"{s['sky_rms_after_arcsec']:.1f}\" of the fit it came from ({s['n_used']} points)" \
        in printed


@needs_chromium
def test_diagnose_page_in_a_headless_browser(mmt, tmp_path):
    _, out = mmt
    assert_renders_in_a_browser(out / "report.html", tmp_path, len(PLOTS))
