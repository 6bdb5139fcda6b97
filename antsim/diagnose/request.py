"""A diagnosis as a user asks for one, on the command line (``antsim diagnose``) or in
Python (:func:`antsim.api.diagnose_model`): the options checked, the scenario read and
matched to the recordings' mount, the recordings read, :func:`~.core.diagnose` run, and with
an output directory the files of :func:`~.modelit.write_outputs`. Every refusal is the
command's one :class:`~controller.errors.InputError` line, naming the option as the command
line has it. Nothing here decides a finding: it calls what does.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fnmatch import fnmatch
from pathlib import Path
from typing import Any

from antsim.bundled import find
from antsim.options import MAX_SIMULATIONS, check_count, check_processes
from antsim.progress import Progress
from antsim.scenario import load_scenario
from antsim.simulate.streaming import prestart
from controller.errors import InputError
from controller.program.recordings import recorded_mount

from . import diagnose, load_observations
from .core import Diagnosis
from .modelit import write_outputs

__all__ = ["OUTPUTS", "Asked", "check_options", "diagnose_file", "read_scenario",
           "refuse_links"]

#: the files diagnose writes into --out (and its figures, diagnose*.png)
OUTPUTS = ("diagnose.json", "diagnose.txt", "report.html", "model_updated.dat",
           "model_updated.json", "scenario_updated.toml")


@dataclass
class Asked:
    """A diagnosis made (:class:`~.core.Diagnosis`) and, with an output directory, what
    :func:`~.modelit.write_outputs` wrote (its ``outputs`` document, None without one)."""

    diagnosis: Diagnosis
    written: dict[str, Any] | None = None


def check_options(jobs: int, sims: int, resimulate: int | None, model: str | None) -> None:
    """``--jobs``, ``--sims``, ``--resimulate`` within their limits and ``--model`` not
    empty, else one InputError line."""
    check_processes(jobs, "--jobs")
    check_count(sims, "--sims", 2, MAX_SIMULATIONS, "each is a campaign simulated")
    if resimulate is not None:
        check_count(resimulate, "--resimulate", 0, MAX_SIMULATIONS,
                    "each is a campaign simulated")
    if model is not None and not model.strip():  # not "no model": said so
        raise InputError("command line", "--model", model, "is empty",
                         "give a named model, a model file or T1,T2,...")


def refuse_links(out: Path) -> None:
    """A symbolic link where diagnose writes one of its files would be written through
    (its target overwritten): refused before anything runs."""
    links = sorted(p.name for p in out.iterdir() if p.is_symlink() and (
        p.name in OUTPUTS or fnmatch(p.name, "diagnose*.png")))
    if links:
        raise InputError("command line", "--out", str(out),
                         f"holds {' '.join(links)} as a symbolic link: diagnose writes its "
                         "outputs there and does not write through a link",
                         "remove the link, or write into another directory")


def read_scenario(spec: str, recordings: str | Path, jobs: int):
    """The scenario ``spec`` (a name or a TOML file) that should explain ``recordings``,
    refused when the recordings name another mount; its quiet campaign started on a second
    process where ``jobs`` allow (:func:`antsim.simulate.streaming.prestart`)."""
    scenario = load_scenario(find(spec, field="--scenario"))
    mount = recorded_mount(recordings)
    if mount is not None and mount != scenario.mount.kind:  # before 7 s of simulation
        raise InputError(str(recordings), "mount", mount,
                         f"the recordings' mount; --scenario {spec} is an "
                         f"{scenario.mount.kind} mount's",
                         "diagnose them with a scenario of their own telescope")
    if Path(recordings).is_file():
        # a cold baseline's quiet campaign starts now, on the second core, while this
        # process imports the analysis and reads the recordings (antsim.simulate.streaming)
        prestart(jobs, scenario)
    return scenario


def diagnose_file(recordings: str | Path, scenario=None, *, scenario_spec: str | None = None,
                  model: str | None = None, mount: str | None = None,
                  csv_options: Sequence[str] = (), sims: int = 8, jobs: int = 1,
                  cache_dir: str | Path | None = None, use_cache: bool = True,
                  out: Path | None = None, resimulate: int | None = None,
                  progress: Progress | None = None,
                  note: Callable[[str], None] | None = None) -> Asked:
    """Diagnose the file ``recordings`` against ``scenario`` (:func:`read_scenario` of
    ``scenario_spec``, or None) as ``antsim diagnose`` does, and with ``out`` (a directory
    the caller holds, :func:`refuse_links` checked) write its files, re-simulating
    ``resimulate`` times (None: 4). ``note``: told each of the reader's notes;
    ``progress``: the command's, told each stage."""
    progress = progress if progress is not None else Progress("diagnose", False)
    progress.stage("reading the recordings")
    obs = load_observations(recordings, mount=mount, csv_options=list(csv_options))
    for line in obs.meta.get("notes", ()):
        if note is not None:
            note(line)
    if scenario is not None and (obs.kind == "tpoint" or not obs.has_time):
        raise InputError(str(recordings), "--scenario", scenario_spec,
                         f"{'a TPOINT data file' if obs.kind == 'tpoint' else 'a file'} "
                         "without times has nothing to simulate against",
                         "diagnose it without --scenario")
    progress.stage("the noise the scenario predicts (simulations) and the candidate "
                   "effects" if scenario is not None else "testing the candidate effects")
    try:
        diag = diagnose(obs, scenario, model, n_sims=sims, cache_dir=cache_dir,
                        use_cache=use_cache, jobs=jobs)
    except ValueError as err:
        if isinstance(err, InputError):
            raise
        raise InputError(str(recordings), "observations", obs.n, str(err)) from None
    if out is None:
        return Asked(diag)
    resim = 4 if resimulate is None else resimulate
    progress.stage("writing the outputs" + (f" and re-simulating {resim} times"
                                            if scenario and resim else ""))
    written = write_outputs(diag, out, scenario, resim if scenario else 0,
                            cache_dir=cache_dir, use_cache=use_cache, jobs=jobs)
    return Asked(diag, written)
