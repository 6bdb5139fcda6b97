"""Figures (antsim.figures): every figure of a run is written, sane and not blank; the same
inputs give the same bytes (PNG and SVG); the APIs for diagnose (before/after) and plan
(comparison) work and refuse bad input; the user's matplotlib style does not leak in.

The run here is the 1990 scenario cut to 3 hours (``SHORT_EDITS`` in conftest): about 30
scans, enough for fit A, too few for the night fit E (so a missing variant is exercised too).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from antsim.documents import GHIGO1990
from antsim.figures import run as figures
from antsim.figures.charts import comparison_figure
from antsim.figures.diagnose import before_after_figures
from antsim.run.outputs import run_fits
from antsim.scenario import load_scenario
from antsim.simulate.runner import simulate
from controller.pointing.fitting import fit_model
from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask

#: a figure below this many bytes is an empty canvas or a lone title (an 800x600 PNG holding
#: only axes and a title compresses to ~8 kB); above the upper bound it would bloat the
#: report (every figure here is 20-160 kB at 100 dpi)
MIN_BYTES, MAX_BYTES = 10_000, 2_000_000
#: standard deviation of the grey level (0..1) below which a figure counts as blank: a
#: white canvas gives 0; our figures give 0.08-0.2 (dark text, lines and markers on white)
MIN_PIXEL_STD = 0.03
#: ... and the share of non-white pixels below which it counts as blank
MIN_INK_FRACTION = 0.01

EXPECTED = {"fig1_sky", "fig2_total_errors", "fig3_residuals", "fig4_amplitude",
            "fig5_residual_quiver", "fig6_residual_histograms", "fig7_residuals_time",
            "fig8_coefficients", "fig9_term_sigmas", "fig10_fit_rms"}


def png_stats(path: Path) -> tuple[float, float]:
    """(std of the grey level, fraction of non-white pixels) of a PNG, decoded by
    matplotlib (pyplot not needed)."""
    import matplotlib.image

    img = matplotlib.image.imread(str(path))
    grey = img[..., :3].mean(axis=-1)
    return float(grey.std()), float((grey < 0.98).mean())


def assert_sane_png(path: Path) -> None:
    assert path.exists(), f"{path} was not written"
    size = path.stat().st_size
    assert MIN_BYTES < size < MAX_BYTES, f"{path.name}: {size} bytes"
    assert path.read_bytes().startswith(b"\x89PNG\r\n\x1a\n"), f"{path.name} is not a PNG"
    std, ink = png_stats(path)
    assert std > MIN_PIXEL_STD and ink > MIN_INK_FRACTION, \
        f"{path.name} looks blank (grey std {std:.4f}, ink {ink:.4f})"


@pytest.fixture(scope="module")
def short_run(short_ghigo_text, tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "short.toml"
    path.write_text(short_ghigo_text, encoding="utf-8")
    result = simulate(load_scenario(path))
    fits = run_fits(result)
    truth = {k: v["value_arcsec"] for k, v in result.truth["terms"].items()}
    return result, fits, truth


@pytest.fixture(scope="module")
def run_figs(short_run, tmp_path_factory):
    result, fits, truth = short_run
    out = tmp_path_factory.mktemp("figs")
    return figures.run_figures(result.rows, fits, out, truth_arcsec=truth, name="short",
                               el_limit_deg=10.0,
                               reference_rms=dict(GHIGO1990.table2))


def test_run_figures_are_written_sane_and_not_blank(run_figs, short_run):
    _, fits, _ = short_run
    assert fits["A"] is not None and fits["E"] is None  # the premise of this module
    assert {f.path.stem for f in run_figs} == EXPECTED
    for f in run_figs:
        assert_sane_png(f.path)
        assert f.title and f.caption, f"{f.path.name} has no title or caption"


def test_blank_detector_can_fail(tmp_path):
    """The non-blank check must reject a blank canvas and a figure of bare axes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 6), dpi=100)
    FigureCanvasAgg(fig)
    fig.savefig(tmp_path / "blank.png")
    std, ink = png_stats(tmp_path / "blank.png")
    assert std < MIN_PIXEL_STD and ink < MIN_INK_FRACTION
    with pytest.raises(AssertionError):
        assert_sane_png(tmp_path / "blank.png")


def test_same_inputs_give_identical_png_and_svg_bytes(short_run, tmp_path):
    result, fits, truth = short_run
    outs = []
    for name in ("one", "two"):
        files = figures.run_figures(result.rows, fits, tmp_path / name, truth_arcsec=truth,
                                    formats=("png", "svg"))
        outs.append({p.name: p.read_bytes() for f in files for p in (f.path, *f.extra)})
    assert len(outs[0]) == 2 * len(EXPECTED)
    assert outs[0].keys() == outs[1].keys()
    for name in outs[0]:
        assert outs[0][name] == outs[1][name], f"{name} differs between two renderings"
    svg = outs[0]["fig1_sky.svg"].decode("utf-8")
    assert "<dc:date>" not in svg  # no timestamp in the SVG metadata


def test_user_style_does_not_leak_in_or_out(tmp_path):
    """A user's rcParams change neither the bytes nor survive a figure."""
    import matplotlib

    plain = figures.sky_distribution_figure([10.0, 200.0], [30.0, 60.0], tmp_path / "a.png")
    with matplotlib.rc_context({"font.size": 20.0, "axes.facecolor": "black"}):
        styled = figures.sky_distribution_figure([10.0, 200.0], [30.0, 60.0],
                                                 tmp_path / "b.png")
        assert matplotlib.rcParams["font.size"] == 20.0
    assert plain.path.read_bytes() == styled.path.read_bytes()


def test_pyplot_is_never_imported(tmp_path):
    """The figures use the Agg canvas directly: no pyplot, no GUI backend, no global state."""
    code = ("import sys; from antsim.figures import run as figures; "
            "figures.sky_distribution_figure([1.0], [45.0], sys.argv[1]); "
            "print('matplotlib.pyplot' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "probe.png")],
                         capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.strip() == "False"


def test_figures_without_fit_a(short_run, tmp_path):
    """Too few observations for fit A: the figures that need it are left out, no crash."""
    result, fits, _ = short_run
    files = figures.run_figures(result.rows, {k: None for k in fits}, tmp_path)
    assert {f.path.stem for f in files} == {"fig1_sky", "fig2_total_errors", "fig4_amplitude"}
    for f in files:
        assert_sane_png(f.path)


def _fit_a_data(result):
    cols = columns(result.rows)
    return pointing_data(cols, variant_mask(cols, VARIANTS[0]))


def test_before_after_figures(short_run, tmp_path):
    result, fits, _ = short_run
    data = _fit_a_data(result)
    after = fits["A"]
    before = fit_model(data, [n for n in after.names if n not in ("W6", "W10")], robust=True)
    # without the azimuth encoder offset W6 (12') and the collimation W10 (sec E in dA, which
    # mimics a constant over the few hours' elevations) the other azimuth terms absorb part
    # of it, not all
    assert before.sky_rms_arcsec > 1.5 * after.sky_rms_arcsec
    files = before_after_figures(before, after, data, tmp_path, "diag",
                                         before_name="without W6, W10",
                                         after_name="with W6, W10")
    assert [f.path.name for f in files] == ["diag_residuals.png", "diag_histograms.png",
                                            "diag_quiver.png"]
    for f in files:
        assert_sane_png(f.path)
    # the Sky RMS at the precision diagnose's text prints it
    assert f"{before.sky_rms_arcsec:.2f}\"" in files[0].title
    assert f"{after.sky_rms_arcsec:.2f}\"" in files[0].title


def test_before_after_refuses_mismatched_data(short_run, tmp_path):
    result, fits, _ = short_run
    data = _fit_a_data(result)
    shorter = data.select(np.arange(len(data)) > 0)
    with pytest.raises(ValueError, match="pass the PointingData the fit was made from"):
        before_after_figures(fits["A"], fits["A"], shorter, tmp_path)


def test_comparison_figure_for_plans(tmp_path):
    values = {"plan night only": {"W1": 40.0, "W6": 12.0, "W9": 6.0},
              "plan 24 h": {"W1": 30.0, "W6": 9.0, "W9": float("nan")},
              "plan day": {"W1": 50.0, "W6": 0.0}}
    f = comparison_figure(values, tmp_path / "plans.png", title="sigma per term",
                                  ylabel="sigma (arcsec)", xlabel="term", log=True)
    assert_sane_png(f.path)
    with pytest.raises(ValueError, match="at least one series"):
        comparison_figure({}, tmp_path / "x.png", title="t", ylabel="y")
    with pytest.raises(ValueError, match="unknown figure format"):
        comparison_figure(values, tmp_path / "y.png", title="t", ylabel="y",
                                  formats=("png", "gif"))


def test_amplitude_figure_without_the_strong_sources(tmp_path):
    """A run that never observed Cas A or Cyg A (the 140-ft's and BIMA's scenarios): the
    figure says so, draws no empty legend and warns nothing."""
    import warnings

    el = np.array([20.0, 40.0, 60.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        drawn = figures.amplitude_figure(el, np.array([1.0, 1.1, 1.05]),
                                         np.array(["3C 84", "3C 84", "3C 286"]),
                                         tmp_path / "fig4.png")
    assert_sane_png(drawn.path)


def test_amplitude_figure_follows_the_report_gain_curve(short_run):
    """Fig. 4's premise: the strong sources' amplitudes, normalised above 30 deg, follow the
    section V curve. Tolerances: the median deviation within 2% (pointing errors during the
    scan cost ~1%: a 30" error takes 1% off an 11' beam's peak; extinction at tau 0.01 takes
    2.5% more at 15 deg than at 30 deg); every point within 10% (a 90" gust during the scan
    costs 5%, plus gain fluctuations). A figure normalised wrongly or a curve in the wrong
    units misses by far more."""
    result, _, _ = short_run
    obs = figures._Observations.from_rows(result.rows)
    for name in figures.STRONG_SOURCES:
        sel = (obs.source == name) & obs.good
        assert sel.sum() >= 3, f"too few scans of {name} in the short run"
        ref = np.median(obs.amp_k[sel & (obs.el_deg > 30)]) if (sel & (obs.el_deg > 30)).any() \
            else None
        if ref is None:
            continue
        rel = obs.amp_k[sel] / ref
        expected = figures._gain_curve(obs.el_deg[sel], figures.REPORT_GAIN_CURVE)
        deviation = np.abs(rel - expected)
        assert np.median(deviation) < 0.02 and deviation.max() < 0.10, (name, rel, expected)
