"""The baseline's simulations on one shared schedule, vectorized across seeds.

The scheduler is deterministic, so every baseline simulation of a well-pointed scenario
observes the same sources at the same times; only the noise differs. :mod:`antsim.plan`'s
:class:`~antsim.simulate.vectorized.MemberEngine` re-simulates just the random parts for all seeds
at once through the world's own physics (see that module for what is shared and what is
drawn per seed). Here its reduced scans become recording columns, one block of rows per
polarization, for :func:`antsim.diagnose.data.from_columns`. A seed whose scan the controller
would miss (it would then search and change its schedule) is left out and simulated in full
by the caller, as is every seed of a scenario whose schedule cannot be shared (the engine
says why).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
import simpy

from antsim.world.world import World
from controller.program.campaign import FWHM_PER_SIGMA

from ..simulate import streaming
from ..simulate.schedule import REFERENCE_SEED, quiet_scenario, record_schedule
from ..simulate.vectorized import MemberEngine

__all__ = ["shared_schedule_columns"]


def shared_schedule_columns(scenario, seeds: Sequence[int], jobs: int = 1
                            ) -> dict[int, dict[str, np.ndarray]]:
    """Recording columns (XR, XL and AVG rows of every scan) of each seed that keeps the
    shared schedule; seeds missing from the result need a full simulation. With ``jobs`` >= 2
    (and two cores) the quiet run is a second process and the members follow it here
    (:mod:`antsim.simulate.streaming`; same numbers)."""
    if not seeds:
        return {}
    quiet = quiet_scenario(scenario)
    shared = power = std = None
    if streaming.stream_available(jobs):
        stream = streaming.take(scenario, REFERENCE_SEED)
        try:
            shared, (power, std) = streaming.stream_members(stream, scenario, seeds)
        except RuntimeError as err:  # the same numbers, only later
            warnings.warn(f"{err}; running the quiet campaign and the baseline's members in "
                          "this process", RuntimeWarning, stacklevel=2)
        finally:
            stream.close()
    if shared is None:
        shared, _ = record_schedule(quiet, seed=REFERENCE_SEED)
    reference = World(quiet, simpy.Environment(), REFERENCE_SEED)
    engine = MemberEngine(scenario, shared, reference, (), "baseline")
    if engine.unshareable:
        return {}
    if power is None:
        power, std = engine.simulate(list(seeds))
    reduced = engine.reduce(power, std)
    diverged = engine.diverges(reduced)
    offset = np.asarray(reduced.offset_arcmin)  # (seeds, scans, axes, channels + AVG)
    flags = np.asarray(reduced.flags)
    width = np.asarray(reduced.width_arcmin) * FWHM_PER_SIGMA
    polarizations = (*shared.channels, "AVG")
    n = len(shared.sources)
    fixed = {name: np.tile(np.asarray(values), len(polarizations))
             for name, values in shared.columns.items()
             if name not in ("xel_arcmin", "el_arcmin", "good", "polarization")}
    fixed["source"] = np.tile(np.asarray(shared.sources), len(polarizations))
    fixed["scan"] = np.tile(np.arange(n), len(polarizations))
    fixed["polarization"] = np.repeat(np.asarray(polarizations), n)
    out = {}
    for m, seed in enumerate(seeds):
        if diverged[m]:
            continue

        def stacked(values, axis, m=m):
            return np.concatenate([values[m, :, axis, c] for c in range(len(polarizations))])

        out[int(seed)] = {
            **fixed,
            "xel_arcmin": stacked(offset, 0), "el_arcmin": stacked(offset, 1),
            "good": (stacked(flags, 0) == 0) & (stacked(flags, 1) == 0),
            "xel_width_arcmin": stacked(width, 0), "el_width_arcmin": stacked(width, 1),
        }
    return out
