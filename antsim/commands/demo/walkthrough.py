"""The walk-through told in order: the five chapters, each handed what it needs of the earlier
ones, then ``demo.html`` (every chapter's text, tables and figures) and ``demo.json`` (the
numbers quoted, the commands to try)."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from antsim.outdir import write_file

from . import closed_loop, cold_start, first_campaign, hidden_effect, the_fit
from .story import Story

__all__ = ["run_demo"]


def run_demo(out: Path, scenario_path: Path,
             echo: Callable[[str], None] = print,
             on_chapter: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Tell the story into ``out``; returns the numbers a test or a teacher may want (those
    of ``demo.json``). ``on_chapter`` is told each chapter's title as it starts (the
    command's progress)."""
    from antsim.figures.html import Section, write_report
    from antsim.scenario import load_scenario

    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    figdir = out / "figures"
    story = Story(echo, on_chapter)
    base_text = scenario_path.read_text(encoding="utf-8")
    scenario = load_scenario(scenario_path)
    numbers: dict[str, Any] = {}
    echo(f"antsim demo: the pointing of the NRAO Green Bank 45-ft, 8-9 February 1990 -> {out}")

    numbers.update(cold_start.tell(story, scenario, figdir))
    first, more = first_campaign.tell(story, scenario, scenario_path, out)
    numbers.update(more)
    numbers.update(the_fit.tell(story, first))
    numbers.update(closed_loop.tell(story, base_text, scenario_path, out, first, figdir,
                                    numbers["first_sky_rms_arcsec"]))
    numbers.update(hidden_effect.tell(story, base_text, scenario_path, out,
                                      first.directory / "model.dat", figdir,
                                      numbers["fit_sky_rms_arcsec"]))

    sections = [Section(c.title, c.blocks) for c in story.chapters]
    path = write_report(
        out / "demo.html", "How a radio telescope is pointed: a walk-through with antsim",
        sections, subtitle="The NRAO Green Bank 45-ft at X-band, 8-9 February 1990 "
                           "(simulated): from a cold start to a closed loop")
    numbers["wall_s"] = time.perf_counter() - t0
    numbers["html"] = str(path)
    numbers["chapters"] = [c.title for c in story.chapters]
    numbers["commands"] = list(story.commands)
    write_file(out / "demo.json", json.dumps(numbers, indent=2, default=str) + "\n")
    echo(f"\nwrote {path} ({len(story.chapters)} chapters) and demo.json in "
         f"{numbers['wall_s']:.1f} s")
    return numbers
