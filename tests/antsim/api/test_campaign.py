"""antsim/api/campaign.py: ``antsim.run_campaign`` holds the numbers the files of ``antsim run``
hold for the same scenario and seed, writes the command's bytes with ``out=``, closes the
loop with a fit to the byte of ``--model model.dat``, and draws the report's figures in
memory."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest

import antsim
from controller.errors import InputError

from .conftest import command, command_error


def _files(directory: Path) -> dict[str, bytes]:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*"))
            if p.is_file() and p.name != ".antsim.lock"}


@pytest.fixture(scope="module")
def campaign(short_path):
    """The same campaign in memory (nothing written)."""
    return antsim.run_campaign(short_path)


def test_a_campaign_holds_what_the_commands_files_hold(campaign, command_run):
    assert json.dumps(campaign.fit_json(), indent=2) + "\n" == \
        (command_run / "fit.json").read_text(encoding="utf-8")
    assert json.dumps(campaign.fit_variants_json(), indent=2) + "\n" == \
        (command_run / "fit_variants.json").read_text(encoding="utf-8")
    assert json.dumps(campaign.truth, indent=2) + "\n" == \
        (command_run / "truth.json").read_text(encoding="utf-8")
    assert campaign.tables == (command_run / "fit.txt").read_text(encoding="utf-8")
    assert campaign.out is None and campaign.recordings_path is None
    # the Quantities are the documents' numbers, in arcsec
    saved = json.loads((command_run / "fit.json").read_text(encoding="utf-8"))
    fit = campaign.fit
    assert fit.values.unit == u.arcsec and fit.sky_rms.unit == u.arcsec
    assert list(fit.names) == list(saved["terms"])
    for name, value in zip(fit.names, fit.values, strict=True):
        assert value.to_value(u.arcsec) == saved["terms"][name]["value_arcsec"], name
    assert fit.sky_rms.to_value(u.arcsec) == pytest.approx(saved["sky_rms_arcsec"], abs=1e-9)
    rows = campaign.recordings()
    assert len(rows) == len(campaign.run.rows) and "xel_arcmin" in rows.colnames


def test_with_out_it_writes_the_commands_bytes(short_path, command_run, tmp_path):
    written = antsim.run_campaign(short_path, out=tmp_path / "api")
    assert written.out == tmp_path / "api"
    assert _files(tmp_path / "api") == _files(command_run)
    status, printed, _ = command(["run", str(short_path), "--out", str(tmp_path / "cli"),
                                  "--no-progress"])
    assert status == 0
    assert printed.replace(str(tmp_path / "cli"), "DIR") == \
        written.summary.replace(str(tmp_path / "api"), "DIR") + "\n"


def test_the_loop_closed_with_a_fit_is_the_commands_with_its_model_file(
        campaign, short_path, command_run, tmp_path):
    status, _, err = command(["run", str(short_path), "--seed", "2", "--model",
                              str(command_run / "model.dat"), "--out", str(tmp_path / "cli"),
                              "--no-report", "--no-progress"])
    assert status == 0, err
    closed = antsim.run_campaign(short_path, seed=2, model=campaign.fit,
                                 out=tmp_path / "api", report=False)
    assert _files(tmp_path / "api") == _files(tmp_path / "cli")
    assert closed.model_in_use == "ghigo1990 seed 1: fit A"
    # how the model in use pointed: what fit.txt's line says, as a Quantity
    assert closed.in_use.line()[:1].upper() + closed.in_use.line()[1:] in \
        (tmp_path / "cli" / "fit.txt").read_text(encoding="utf-8")
    assert closed.in_use_sky_rms.to_value(u.arcsec) == closed.in_use.sky_rms_arcsec


def test_pulls_are_fit_minus_recoverable_truth_over_sigma(campaign):
    truth = campaign.truth["recoverable"]["terms"]
    table = campaign.pulls()
    assert list(table["term"]) == list(campaign.fit.names)
    saved = campaign.fit_json()["terms"]
    for row in table:
        name = row["term"]
        value = saved[name]["value_arcsec"]
        expected = truth[name]["value_arcsec"]
        assert row["truth"].to_value(u.arcsec) == expected
        assert row["fit_minus_truth"].to_value(u.arcsec) == pytest.approx(value - expected)
        sigma = saved[name]["sigma_arcsec"]
        assert row["pull"] == pytest.approx((value - expected) / sigma)


def test_the_report_figures_are_drawn_in_memory(campaign, command_run, tmp_path, monkeypatch):
    """The figures are the report's (the same files' names and, saved as the report saves
    them, the same PNG bytes), and drawing them writes nothing."""
    from antsim.figures.style import FIG_DPI

    monkeypatch.chdir(tmp_path)
    figures = campaign.figures()
    assert list(tmp_path.iterdir()) == []
    on_disk = {p.stem: p for p in (command_run / "figures").glob("*.png")}
    assert set(figures) == set(on_disk)
    for name in ("fig1_sky", "fig3_residuals", "fig8_coefficients"):
        png = io.BytesIO()
        figures[name].savefig(png, format="png", dpi=FIG_DPI, metadata={"Software": "antsim"},
                              pil_kwargs={"compress_level": 3})
        assert png.getvalue() == on_disk[name].read_bytes(), name
    assert campaign.plot_sky() is figures["fig1_sky"]
    assert campaign.plot("against_truth") is figures["fig8_coefficients"]
    assert campaign.plot_residuals()._suptitle.get_text().startswith("Fig. 3a-d")
    with pytest.raises(ValueError, match="has no figure 'nothing'; it has fig1_sky"):
        campaign.plot("nothing")


def test_a_campaign_shows_a_short_table(campaign):
    fit = campaign.products.fit_a
    html, text = campaign._repr_html_(), repr(campaign)
    for shown in (html, text):
        assert f"{fit.sky_rms_arcsec:.1f}" in shown and "ghigo1990" in shown
        assert f"{fit.n_used} of {fit.n_input}" in shown
    assert html.count("<tr>") == len(campaign._table().rows) + 1
    fit_html = campaign.fit._repr_html_()
    assert all(f"{v:.2f}" in fit_html for v in fit.values_arcsec)


@pytest.mark.parametrize(("kwargs", "options"), [
    ({"seed": -1}, ["--seed", "-1"]),
    ({"model": "nonesuch"}, ["--model", "nonesuch"]),
    ({"model": " "}, ["--model", " "]),
    ({"model": "{run}/recordings.ecsv"}, ["--model", "{run}/recordings.ecsv"]),
    ({"out": "{run}"}, ["--out", "{run}"]),
])
def test_bad_input_is_the_commands_line(kwargs, options, short_path, command_run, tmp_path):
    """The same InputError line as the command's, and nothing written."""
    def filled(text):
        return text.replace("{run}", str(command_run))

    options = [filled(o) for o in options]
    if "--out" not in options:
        options += ["--out", str(tmp_path / "never")]
    line = command_error(["run", str(short_path), *options, "--no-progress"])
    with pytest.raises(InputError) as err:
        antsim.run_campaign(short_path, **{k: filled(str(v)) if k != "seed" else v
                                           for k, v in kwargs.items()})
    assert str(err.value) == line
    assert not (tmp_path / "never").exists()


def test_an_unknown_scenario_is_the_commands_line():
    line = command_error(["run", "no-such-scenario", "--out", "x", "--no-progress"])
    with pytest.raises(InputError) as err:
        antsim.run_campaign("no-such-scenario")
    assert str(err.value) == line


def test_fits_of_every_variant(campaign):
    fits = campaign.fits
    assert set(fits) == set(campaign.products.fits)
    for name, fit in fits.items():
        if fit is not None:
            assert np.array_equal(fit.values.to_value(u.arcsec),
                                  campaign.products.fits[name].values_arcsec)
            assert math.isfinite(fit.sky_rms.to_value(u.arcsec))
