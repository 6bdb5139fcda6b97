"""What the chapters share: a campaign written as ``antsim run`` writes it, where the reader's
own repeats go, and how a fit's coefficients are judged against the truth."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["YOURS", "Campaign", "honest_words", "pulls", "run_campaign_like_antsim_run"]

#: the folder of the demo's directory that the "try it yourself" commands write into (the
#: demo's own campaigns are beside it, so that a repeat never meets an earlier run)
YOURS = "yours"


@dataclass(frozen=True)
class Campaign:
    """A campaign of the demo: the run (:class:`antsim.simulate.runner.RunResult`), its
    fits A-F (None where too few observations) and the directory it was written to."""

    result: Any
    fits: dict
    directory: Path


def run_campaign_like_antsim_run(scenario, out: Path, seed: int, model,
                                 report: bool) -> Campaign:
    """Simulate ``scenario`` with ``seed`` and the pointing ``model`` in use, and write it to
    ``out`` as ``antsim run`` does (with its report page if ``report``)."""
    from antsim.run.outputs import run_fits, write_outputs
    from antsim.simulate.runner import run_campaign

    result = run_campaign(scenario, out, seed=seed, model=model, show_progress=False)
    write_outputs(result, report=report)
    return Campaign(result, run_fits(result), out)


def pulls(fit, truth: dict[str, float]) -> dict[str, float]:
    """(fit - truth) / honest sigma per term that has a truth (TPOINT's sigma where there
    is no honest one)."""
    sigma = fit.sigma_honest_arcsec if fit.sigma_honest_arcsec is not None \
        else fit.sigma_arcsec
    return {n: (float(v) - truth[n]) / float(s)
            for n, v, s in zip(fit.names, fit.values_arcsec, sigma, strict=True)
            if n in truth and s > 0}


def honest_words(fit) -> str:
    """The honest sigma of ``fit`` named as every output names it: "honest sigma, a
    jackknife over observations within 3600 s time blocks" (docs/outputs.md)."""
    return f"honest sigma, a jackknife over {fit.honest_clusters_words}"
