"""`antsim demo [--out DIR]`: the teaching walk-through, from a cold start to a closed loop.

Five chapters, each printed to stdout as it runs and collected into ``DIR/demo.html``:

1. A cold start (:mod:`.cold_start`): with no pointing model the 45-ft's azimuth encoder
   offset (the 1990 report's W6 = 12.24') is 12.24' cos E on the sky: inside the 11' beam
   for Cassiopeia A high in the sky, beyond it for a source rising at 20 deg, which the first
   scan misses; the controller's wide search finds it and the next scan is centred.
2. The first campaign (:mod:`.first_campaign`): 24 hours of five-point scans from that cold
   start.
3. The fit (:mod:`.the_fit`): the 1990 report's ten-term model recovers the injected
   coefficients.
4. Closing the loop (:mod:`.closed_loop`): a second (12-hour) campaign with the fitted model
   points to the accuracy the fit promised.
5. A hidden effect (:mod:`.hidden_effect`): a third campaign on an antenna with an uneven
   azimuth track (a term the ten-term model does not have); ``antsim diagnose`` is asked to
   find it.

:mod:`.walkthrough` tells them in order and writes the page; :mod:`.story` is how a chapter
is told (paragraphs, figures, tables, commands to try) and :mod:`.campaign` what the
chapters share (a campaign written as ``antsim run`` writes it, the pulls of a fit). The
chapters never import one another: what one needs of an earlier one the walk-through hands
it. Every campaign is written under ``DIR/1-first-campaign`` etc., with the scenario files
used, and every chapter prints the command that repeats its step into ``DIR/yours/``.

May import any part of antsim (it is a command); only :mod:`antsim.cli` imports it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from antsim.bundled import find
from controller.errors import InputError

from .walkthrough import run_demo

__all__ = ["configure", "main", "run_demo"]


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", default="antsim-demo",
                        help="output directory (default: ./antsim-demo); an earlier demo's "
                             "directory is overwritten, any other non-empty one refused")
    parser.add_argument("--scenario", default="ghigo1990",
                        help="the 1990 scenario: a name or a TOML file (default: ghigo1990, "
                             "the one that comes with antsim)")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar, or none (default: a bar on a terminal, a line "
                             "every few seconds to stderr off one)")
    parser.epilog = ("Runs three campaigns (24 h, 12 h, 24 h of simulated time) and one "
                     "antsim diagnose, and prints its own wall time at the end. Writes "
                     "DIR/demo.html, DIR/demo.json (the numbers quoted) and DIR/figures/; "
                     "the commands it prints to try write into DIR/yours/.")


def main(args: argparse.Namespace) -> int:
    from antsim.outdir import LOCK_NAME, held_output_dir
    from antsim.progress import Progress

    scenario_path = find(args.scenario, field="--scenario")
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise InputError("command line", "--out", args.out, "exists and is not a directory")
    if Path(args.out).is_dir() and not (Path(args.out) / "demo.html").exists() and any(
            p.name != LOCK_NAME for p in Path(args.out).iterdir()):
        raise InputError("command line", "--out", args.out,
                         "is not empty and holds no earlier demo", "choose a new directory")
    with held_output_dir(args.out, "--out", "antsim demo") as out, \
            Progress("demo", args.progress) as progress:
        run_demo(out, scenario_path, echo=progress.write, on_chapter=progress.stage)
    return 0
