"""Monte Carlo members on a shared schedule, vectorized across members.

When the pointing is good the controller's schedule does not depend on the noise: the
scheduler is deterministic, every scan is detected, and which source is observed when, every
slew, offset and integration, and the encoder commands are the same for every member of an
ensemble. :func:`record_schedule` runs the deterministic ("quiet") simulation once with the
antenna's recorder attached and keeps, per integration, the sample times, the encoder command
per sample, the antenna's state at the middle and the true paths of the sources near the beam.

:class:`MemberEngine` then re-simulates only what is random, for a block of members at once,
through the world's own physics (:meth:`antsim.world.world.World.sample_blocks` with a member axis,
a scan's integrations at a time):

* shared (from the quiet run): schedule, encoder commands, source paths (ephemeris and
  refraction), beam, atmosphere, and every effect whose realisation draws no random numbers
  (geometry, sunset drift, squint, ...: an instance started once);
* per member, drawn from the member's own seed exactly as a :class:`~antsim.world.world.World` would
  draw them (same component generators, same order): the receiver's gain fluctuations and
  radiometer noise, the tracking jitter and its gusts, the random parts of the thermal model
  (cloud modulation, lateral forcing) and the weather's wander that drives it; each as one
  array with a member axis (the OU processes and the thermal grids carry it);
* vectorized across members: the pointing solve, the beam response, the sky emission, the
  receiver, then :func:`controller.scans.scan.reduce_sources` on every scan of every member at once;
  each member is then fitted with :func:`controller.pointing.fitting.fit_model` as fit A.

Where the physics does not allow a shared schedule the member is simulated in full
(:func:`antsim.simulate.runner.simulate`) instead: a member one of whose scans the controller
would not detect (a gust, a low S/N: with searching enabled it searches, which changes every
later time and adopts a correction); whole variants when the deterministic run itself searched
(a cold start: where the controller points then depends on the noise), when the running
correction follows each scan (``search.update_gain`` > 0), or when an effect's random
realisation has no member axis (see :attr:`MemberEngine.unshareable`). The weather's wander
shifts a real member's refraction correction and its true refraction by the same arcseconds and
its timing by milliseconds; the shared schedule keeps the quiet run's, which changes no
pointing error. Where the controller corrects no refraction from the weather (the 1990
scenario: its model's W5 carries it), a member's true refraction follows its own weather
alone: the shared paths are shifted by the refraction's change with the member's temperature,
to first order in the wander, at each integration's start (the world takes the weather once per
track: within 0.1" at 10 deg, :class:`_RefractionWander`).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from antsim.simulate.runner import simulate
from antsim.world.effects import EFFECTS, PointingState
from antsim.world.effects.base import BLOCK_FIELDS
from antsim.world.effects.thermal import OUProcess
from antsim.world.effects.tracking import TrackingJitter
from antsim.world.receiver import Receiver
from antsim.world.world import World, component_rng, weather_model
from controller.astro.refraction import refraction_rad
from controller.astro.site import Weather
from controller.pointing.fitting import fit_model
from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask
from controller.scans.scan import channel_average, reduce_sources
from controller.units import ARCSEC_PER_RAD

from ..scenario import EffectSpec, Scenario
from .schedule import (
    QUIET_PARAMS,
    SharedSchedule,
    quiet_scenario,
    record_schedule,
)

__all__ = [
    "MemberEngine",
    "MemberResults",
    "SharedSchedule",
    "fit_rows",
    "member_seed",
    "quiet_scenario",
    "record_schedule",
]

#: the observatory's fit: fit A (XR+XL averaged, filtered, robust)
FIT_A = VARIANTS[0]


def member_seed(plan_seed: int, member: int) -> int:
    """The seed of ensemble member ``member``: numpy's SeedSequence of the plan seed with the
    member index as spawn key (independent streams whatever the block, worker or engine)."""
    seq = np.random.SeedSequence(int(plan_seed), spawn_key=(int(member),))
    return int(seq.generate_state(1, dtype=np.uint64)[0])


# ---------------------------------------------------------------------------------------------
# members with a member axis
# ---------------------------------------------------------------------------------------------
class _MemberDraws:
    """Stands in for a numpy Generator with a member axis: a call for draws of shape
    (*lead, members, last) takes each member's next ``prod(lead) * last`` standard normals
    from that member's own generator, in the order its world would ask for them (the
    member axis is the second to last of every draw: (n, members, 2) for the jitter,
    (K, n, members, 2) for K integrations at once, (K, 2, n, members, channels) for the
    receiver's gain and radiometer draws of K integrations). numpy's normal
    stream does not depend on how it is cut into calls, so drawing ahead in chunks changes no
    value, and the draws need not know the schedule's length (it may still be arriving).
    ``generators`` None: every draw is zero (the quiet members)."""

    CHUNK = 8192

    def __init__(self, generators: Sequence[np.random.Generator] | None):
        self.generators = generators
        self._buffer = np.empty((len(generators or ()), 0))  # (members, drawn ahead)
        self._used = 0

    def standard_normal(self, shape) -> np.ndarray:
        if self.generators is None:
            return np.zeros(shape)
        *lead, members, last = shape
        if members != len(self.generators):
            raise RuntimeError(f"draws for {members} members asked of {len(self.generators)}")
        count = math.prod(lead) * last
        used = self._used
        if used + count > self._buffer.shape[1]:  # every member takes the same count
            ahead = max(count, self.CHUNK)
            self._buffer = np.concatenate(
                [self._buffer[:, used:],
                 np.stack([g.standard_normal(ahead) for g in self.generators])], axis=1)
            used = 0
        self._used = used + count
        block = self._buffer[:, used:used + count]
        return np.moveaxis(block.reshape(members, *lead, last), 0, -2).copy()  # C order


class _MemberGusts:
    """The gusts of every member (each drawn at its own jitter's start), looked up per
    integration: displacement (n, members, 2) rad, as each member's
    :meth:`TrackingJitter.gusts_rad` gives it."""

    def __init__(self, effects: Sequence[TrackingJitter]):
        starts = [e.gust_start_s for e in effects]
        order = np.argsort(np.concatenate(starts), kind="stable")
        self.start_s = np.concatenate(starts)[order]
        self.member = np.concatenate([np.full(s.size, j) for j, s in enumerate(starts)]
                                     ).astype(np.int64)[order]
        self.rad = np.concatenate([e.gust_rad for e in effects])[order]
        self.n_members = len(effects)
        self.duration_s = effects[0].p["gust_duration_s"]

    def __call__(self, t_s: np.ndarray) -> np.ndarray:
        out = np.zeros((t_s.size, self.n_members, 2))
        first = np.searchsorted(self.start_s, t_s[0] - self.duration_s)
        last = np.searchsorted(self.start_s, t_s[-1], side="right")
        for g in range(first, last):  # a member's gusts in its own (time) order
            phase = (t_s - self.start_s[g]) / self.duration_s
            inside = (phase >= 0.0) & (phase <= 1.0)
            out[inside, self.member[g]] += np.sin(np.pi * phase[inside])[:, None] ** 2 \
                * self.rad[g]
        return out


class _MemberView:
    """What an effect's ``start`` may ask of a world, for one member: the reference world's
    sky, beam and Sun; this member's weather; no clock changes (the schedule has them)."""

    def __init__(self, reference: World, weather):
        self._reference = reference
        self.weather = weather

    def __getattr__(self, name: str):
        return getattr(self._reference, name)

    def air_temperature_c(self, t_s) -> np.ndarray:
        return self.weather.air_temperature_c(t_s)

    def set_clock_error(self, error_s) -> None:
        """The clock error is in the shared encoder commands already."""


class _MemberJitter(TrackingJitter):
    """Tracking jitter with a member axis: the OU process draws each member's own normals
    and the gusts are each member's own (:class:`_MemberGusts`)."""

    def set_members(self, process: OUProcess, gusts: _MemberGusts) -> None:
        self.process = process
        self._gusts = gusts
        self.gust_start_s = gusts.start_s

    def gusts_rad(self, t_s: np.ndarray) -> np.ndarray:
        return self._gusts(t_s)


class _MemberWorld(World):
    """The parts of a :class:`World` that :meth:`World.sample_blocks` uses, with a member
    axis; deliberately not built by ``World.__init__``: sky, beam and atmosphere are the
    reference world's."""

    def __init__(self, reference: World, slow: list, fast: list, receiver: Receiver):
        self.scenario = reference.scenario
        self.frame = reference.frame  # the mount's axes (an equatorial mount's HA and Dec)
        self.sky = reference.sky
        self.beam = reference.beam
        self.atmosphere = reference.atmosphere
        self.slow_effects = slow
        self.fast_effects = fast
        self.receiver = receiver


class _Nudge:
    """A per-sample pointing error, constant per member: ``xel_rad``/``el_rad`` (members,)
    on the sky (for the linear response of the offsets)."""

    per_sample = True

    def __init__(self, xel_rad: np.ndarray, el_rad: np.ndarray):
        self.xel_rad = xel_rad
        self.el_rad = el_rad

    def sample_error(self, t_s: np.ndarray, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """Azimuth and elevation errors (rad), shape (*t_s.shape, members)."""
        shape = (*t_s.shape, self.el_rad.size)
        return (np.broadcast_to(self.xel_rad / np.cos(el_rad), shape),
                np.broadcast_to(self.el_rad, shape))


def _stack(instances: list) -> Any:
    """One instance whose random arrays carry a leading member axis (others kept)."""
    out = copy.copy(instances[0])
    for key, value in vars(instances[0]).items():
        if isinstance(value, np.ndarray) and value.ndim >= 1:
            arrays = [vars(x)[key] for x in instances]
            if any(a.shape != value.shape or not np.array_equal(a, value) for a in arrays[1:]):
                setattr(out, key, np.stack(arrays))
    return out


def _differs(a, b) -> bool:
    """Whether two started instances of an effect hold different realisations (arrays or
    numbers drawn in ``start``)."""
    for key, value in vars(a).items():
        other = vars(b).get(key)
        if isinstance(value, np.ndarray):
            if not isinstance(other, np.ndarray) or other.shape != value.shape \
                    or not np.array_equal(other, value, equal_nan=True):
                return True
        elif isinstance(value, int | float) and not isinstance(value, bool) \
                and value != other and not (value != value and other != other):
            return True
    return False


@dataclass
class MemberResults:
    """Fit A of each member (arrays over members, terms in fit order, arcsec)."""

    members: np.ndarray
    values: np.ndarray
    sigma_tpoint: np.ndarray
    sigma_honest: np.ndarray
    sky_rms: np.ndarray
    n_used: np.ndarray
    full: np.ndarray  # simulated in full (not on the shared schedule)
    failed: np.ndarray  # fit A impossible (too few observations)

    @classmethod
    def empty(cls, n_terms: int) -> MemberResults:
        return cls(np.zeros(0, dtype=np.int64), np.zeros((0, n_terms)), np.zeros((0, n_terms)),
                   np.zeros((0, n_terms)), np.zeros(0), np.zeros(0, dtype=np.int64),
                   np.zeros(0, dtype=bool), np.zeros(0, dtype=bool))

    @classmethod
    def concat(cls, parts: Sequence[MemberResults]) -> MemberResults:
        """Joined and sorted by member index."""
        joined = {f: np.concatenate([getattr(p, f) for p in parts])
                  for f in ("members", "values", "sigma_tpoint", "sigma_honest", "sky_rms",
                            "n_used", "full", "failed")}
        order = np.argsort(joined["members"], kind="stable")
        return cls(**{k: v[order] for k, v in joined.items()})


def fit_rows(columns: dict[str, np.ndarray], terms: Sequence[str], name: str,
             sensor_lag_s: float = 0.0):
    """Fit A of recording columns (None when too few observations); thermal terms read the
    structure temperatures, corrected for the sensors' response time ``sensor_lag_s``."""
    mask = variant_mask(columns, FIT_A)
    n = int(mask.sum())
    if n == 0 or 2 * n <= len(terms):
        return None
    try:
        return fit_model(pointing_data(columns, mask, sensor_lag_s), terms,
                         robust=FIT_A.filtered, name=name)
    except ValueError:
        return None


class _RefractionWander:
    """The change of each member's true refraction from the quiet run's (rad), its air
    temperature wandering from the quiet run's by dT: dR/dT dT, dR/dT from ERFA's refraction
    (a central difference of 1 K) at the quiet weather of the integration's start."""

    #: half the temperature step of the central difference (K)
    HALF_STEP_K = 0.5

    def __init__(self, reference: World, weathers: Sequence):
        self.reference = reference
        self.weathers = weathers

    def delta_rad(self, t0_s: np.ndarray, el_rad: np.ndarray) -> np.ndarray:
        """(K, n, members) for integrations starting at ``t0_s`` (K,) whose sources are at
        ``el_rad`` (K, n) (radians)."""
        quiet = self.reference.weather
        frequency = self.reference.sky.frequency_ghz
        d_t = np.stack([w.air_temperature_c(t0_s) for w in self.weathers], axis=-1) \
            - quiet.air_temperature_c(t0_s)[:, None]  # (K, members)
        slope = np.empty(el_rad.shape)
        h = self.HALF_STEP_K
        for k, t in enumerate(t0_s.tolist()):
            r = quiet.reading(t)
            up, down = (refraction_rad(el_rad[k], Weather(r.temperature_c + d, r.pressure_hpa,
                                                          r.relative_humidity),
                                       frequency_ghz=frequency) for d in (h, -h))
            slope[k] = (np.asarray(up) - np.asarray(down)) / (2.0 * h)
        return slope[..., None] * d_t[:, None, :]


class _MemberRun:
    """Members integrating a schedule in time order (the slow errors' fixed point and the
    OU processes carry from one integration to the next). Integrations are queued and
    computed in blocks, as the antenna computes its own (:meth:`World.sample_blocks` with a
    member axis): consecutive integrations of one length that see the same sources."""

    #: at most this many integrations per block (a few scans; memory stays small)
    MAX_BLOCK = 64

    def __init__(self, world: _MemberWorld, n_members: int, channels: tuple[str, ...],
                 refraction: _RefractionWander | None = None):
        self.world = world
        self.channels = channels
        self.refraction = refraction
        self.error = (np.zeros(n_members), np.zeros(n_members))
        self._empty = np.zeros((0, n_members, len(channels)))
        self.power: list[np.ndarray] = []
        self.std: list[np.ndarray] = []
        self._queue: list[tuple] = []

    def integrate(self, t: np.ndarray, enc_az: np.ndarray, enc_el: np.ndarray,
                  state: PointingState, paths: list) -> None:
        """One integration of the schedule (a :class:`SharedSchedule` entry), computed with
        the rest of its block."""
        key = (t.size, tuple(i for i, _, _ in paths))
        if self._queue and (self._queue[0][0] != key or len(self._queue) >= self.MAX_BLOCK):
            self._flush()
        self._queue.append((key, t, enc_az, enc_el, state, paths))

    def _flush(self) -> None:
        block, self._queue = self._queue, []
        if not block:
            return
        t = np.stack([b[1] for b in block])
        paths = [(i, np.stack([b[5][j][1] for b in block])[..., None],
                  np.stack([b[5][j][2] for b in block])[..., None])
                 for j, (i, _, _) in enumerate(block[0][5])]
        if self.refraction is not None:  # each member's own refraction
            paths = [(i, az, el + self.refraction.delta_rad(t[:, 0], el[..., 0]))
                     for i, az, el in paths]
        samples, self.error = self.world.sample_blocks(
            t, np.stack([b[2] for b in block])[..., None],
            np.stack([b[3] for b in block])[..., None], [b[4] for b in block], paths,
            self.error, self.channels)  # samples (K, n, members, channels)
        self.power.extend(samples.mean(axis=1))
        self.std.extend(samples.std(axis=1, ddof=1) if t.shape[1] > 1
                        else np.zeros((t.shape[0], *samples.shape[2:])))

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean power and sample std (K), shape (integrations, members, channels)."""
        self._flush()
        if not self.power:
            return self._empty, self._empty
        return np.stack(self.power), np.stack(self.std)


@dataclass
class MemberEngine:
    """Simulates members of one variant on its shared schedule.

    ``scenario`` is the variant as observed (with its noise), ``shared`` the schedule of its
    quiet run and ``reference`` a world of the quiet scenario (sky, beam, atmosphere, Sun).
    ``unshareable`` explains why the members cannot share the schedule (empty if they can).
    """

    scenario: Scenario
    shared: SharedSchedule
    reference: World
    terms: tuple[str, ...]
    fit_name: str
    unshareable: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._kinds: list[tuple[str, int, EffectSpec]] = []
        c = self.scenario.controller
        if self.shared.searches:
            self.unshareable.append(
                f"the deterministic run searched {self.shared.searches} times for its sources "
                "(cold start or large errors): where the controller points then depends on the "
                "noise")
        if c.search.update_gain > 0:
            self.unshareable.append(
                f"controller.search.update_gain = {c.search.update_gain:g}: the running "
                "correction follows each measured offset, so where the controller points "
                "depends on the noise")
        lengths = {t.size for t in self.shared.t}
        if len(lengths) > 1 and not self.unshareable:
            self.unshareable.append("integrations of different lengths in the schedule")
        self._classify()

    # ------------------------------------------------------------------ effects
    def _view(self, seed: int, quiet: bool = False) -> _MemberView:
        """What member ``seed``'s effects see of the world (``quiet``: no weather wander)."""
        if quiet:
            return _MemberView(self.reference, self.reference.weather)
        return _MemberView(self.reference, weather_model(self.scenario,
                                                         component_rng(seed, "weather")))

    def _started(self, index: int, spec: EffectSpec, seed: int, view: _MemberView):
        effect = EFFECTS[spec.name](**spec.params)
        effect.start(view, component_rng(seed, f"effect:{index}:{effect.name}"))
        return effect

    def _classify(self) -> None:
        """Each effect: ``shared`` (no random realisation), ``member`` (a random realisation
        stacked along a member axis), ``jitter``, or a reason the schedule cannot be shared."""
        probes = (self._view(1), self._view(2))
        state = PointingState(t_s=0.5 * self.shared.duration_s, az_rad=np.array([1.0, 1.1]),
                              el_rad=np.array([0.5, 0.6]))
        # a block of 3 integrations of 2 members, as World.sample_blocks asks it (rates,
        # approach and feed angle at their defaults)
        defaults = PointingState(t_s=0.0, az_rad=0.0, el_rad=0.0)
        block = PointingState(**{f: np.full((3, 1), float(getattr(defaults, f)))
                                 for f in BLOCK_FIELDS})
        block.t_s = state.t_s + np.array([[0.0], [15.0], [30.0]])
        block.az_rad = np.array([[1.0, 1.1], [1.01, 1.11], [1.02, 1.12]])
        block.el_rad = np.array([[0.5, 0.6], [0.51, 0.61], [0.52, 0.62]])
        for i, spec in enumerate(self.scenario.effects, start=1):
            cls = EFFECTS[spec.name]
            if cls.per_sample:
                if cls is TrackingJitter:
                    self._kinds.append(("jitter", i, spec))
                else:
                    self.unshareable.append(f"effect {spec.name} varies per sample and has no "
                                            "member axis")
                continue
            a, b = (self._started(i, spec, s, v) for s, v in zip((1, 2), probes, strict=True))
            kind = "member" if _differs(a, b) else "shared"
            effect = _stack([a, b]) if kind == "member" else a
            try:
                d_az, d_el = effect.pointing_error(replace(state))
                np.broadcast_shapes(np.shape(d_az), np.shape(d_el), (2,))
                b_az, b_el = effect.block_error(replace(block))
                if np.broadcast_shapes(np.shape(b_az), np.shape(b_el), (3, 2)) != (3, 2):
                    raise ValueError("block errors of the wrong shape")
                per_sample = PointingState(**{f: getattr(block, f)[:, None]
                                              for f in BLOCK_FIELDS})
                for ch in self.shared.channels:
                    effect.beam_offset(ch, replace(state))
                    effect.beam_offset(ch, per_sample)
            except Exception as err:  # an effect written for scalars only
                self.unshareable.append(f"effect {spec.name} does not accept a member axis "
                                        f"({type(err).__name__})")
                continue
            self._kinds.append((kind, i, spec))

    # ------------------------------------------------------------------ simulation
    def _effects(self, seeds: Sequence[int], quiet: bool, slow_only: bool = False
                 ) -> tuple[list, list]:
        """Slow and fast effects of the members ``seeds`` with a member axis."""
        views = [self._view(s, quiet) for s in seeds]
        slow: list = [self.reference.geometry]
        fast: list = []
        for kind, i, spec in self._kinds:
            params = {**spec.params, **(QUIET_PARAMS.get(spec.name, {}) if quiet else {})}
            spec_m = EffectSpec(spec.name, params)
            if kind == "shared":
                slow.append(self._started(i, spec_m, seeds[0], views[0]))
            elif kind == "member":
                slow.append(_stack([self._started(i, spec_m, s, v)
                                    for s, v in zip(seeds, views, strict=True)]))
            elif not slow_only:  # tracking jitter: each member's generator continues after
                members, generators = [], []  # its start (the gusts) with the OU draws
                for s, v in zip(seeds, views, strict=True):
                    rng = component_rng(s, f"effect:{i}:{spec.name}")
                    effect = TrackingJitter(**params)
                    effect.start(v, rng)
                    members.append(effect)
                    generators.append(rng)
                jitter = _MemberJitter(**params)
                jitter.start(views[0], np.random.default_rng(0))
                jitter.set_members(
                    OUProcess(_MemberDraws(None if quiet else generators),
                              np.ones((len(seeds), 2)), jitter.p["timescale_s"]),
                    _MemberGusts(members))
                fast.append(jitter)
        return slow, fast

    def _receiver(self, seeds: Sequence[int], quiet: bool) -> Receiver:
        """The receiver of the members ``seeds``, each drawing from its own generator."""
        cfg = self.scenario.receiver
        draws = _MemberDraws(None if quiet else [component_rng(s, "receiver") for s in seeds])
        receiver = Receiver(cfg, draws)
        rms = np.array([cfg.gain_fluctuation if c.gain_fluctuation is None else
                        c.gain_fluctuation for c in cfg.channels])
        receiver._gain = OUProcess(draws, np.tile(0.0 * rms if quiet else rms, (len(seeds), 1)),
                                   cfg.gain_timescale_s)
        return receiver

    def member_run(self, seeds: Sequence[int] | None, *, nudges: tuple | None = None,
                   quiet: bool = False) -> _MemberRun:
        """The members of the given seeds, ready to integrate the schedule in time order.
        ``quiet``: every random part off (the deterministic simulation, with one member per
        ``nudges`` entry); ``nudges``: (xel_rad, el_rad) arrays (members,) of constant extra
        pointing error."""
        n_members = len(seeds) if seeds is not None else len(nudges[0])
        if quiet:
            seeds = [0] * n_members
        slow, fast = self._effects(seeds, quiet)
        if nudges is not None:
            fast.append(_Nudge(*nudges))
        world = _MemberWorld(self.reference, slow, fast, self._receiver(seeds, quiet))
        refraction = None
        if not quiet and self.scenario.controller.refraction != "weather":
            refraction = _RefractionWander(self.reference,
                                           [self._view(s).weather for s in seeds])
        return _MemberRun(world, n_members, self.shared.channels, refraction)

    def simulate(self, seeds: Sequence[int] | None, *, nudges: tuple | None = None,
                 quiet: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Mean power and sample std (K) of every integration, shape (integrations, members,
        channels), for members of the given seeds (``nudges``, ``quiet``: see
        :meth:`member_run`)."""
        sh = self.shared
        run = self.member_run(seeds, nudges=nudges, quiet=quiet)
        for k in range(sh.n_integrations):
            run.integrate(sh.t[k], sh.enc_az[k], sh.enc_el[k], sh.state[k], sh.paths[k])
        return run.result()

    def slow_errors(self, seeds: Sequence[int], quiet: bool = False) -> np.ndarray:
        """The slowly varying pointing errors of members ``seeds`` at every integration, on
        the sky: (members, integrations, 2) xel and el (arcsec), indicated - true."""
        sh = self.shared
        n_members = len(seeds)
        slow, _ = self._effects(seeds, quiet, slow_only=True)
        world = _MemberWorld(self.reference, slow, [], None)
        out = np.empty((n_members, sh.n_integrations, 2))
        error = (np.zeros(n_members), np.zeros(n_members))
        for k in range(sh.n_integrations):
            mid = sh.t[k].size // 2
            state = replace(sh.state[k])
            error = world.solve_pointing(sh.enc_az[k][mid], sh.enc_el[k][mid], state, error)
            out[:, k, 0] = error[0] * np.cos(state.el_rad) * ARCSEC_PER_RAD
            out[:, k, 1] = error[1] * ARCSEC_PER_RAD
        return out

    # ------------------------------------------------------------------ reduction and fits
    def scan_powers(self, power: np.ndarray, std: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Powers, std and times arranged as (members, scans, axes, channels + AVG, 5)."""
        idx = self.shared.scan_int
        p = np.moveaxis(power[idx], (3, 4), (0, 3))  # (M, scans, axes, ch, 5)
        s = np.moveaxis(std[idx], (3, 4), (0, 3))
        if self.shared.scan_sky_k is not None:  # the controller's sky subtraction
            p = p - self.shared.scan_sky_k
        p_avg, s_avg = channel_average(p, s, axis=3)
        p = np.concatenate([p, p_avg[:, :, :, None]], axis=3)
        s = np.concatenate([s, s_avg[:, :, :, None]], axis=3)
        times = np.broadcast_to(self.shared.scan_times[None, :, :, None, :], p.shape)
        return p, s, times

    def reduce(self, power: np.ndarray, std: np.ndarray):
        """The controller's reduction of every scan of every member (AxisReduction of shape
        (members, scans, axes, channels + AVG))."""
        p, s, times = self.scan_powers(power, std)
        return reduce_sources(p, s, times, self.scenario.controller.scan, self.scan_widths, 1)

    @cached_property
    def scan_widths(self) -> np.ndarray:
        """The width (FWHM, arcmin) the controller assumes for each recorded scan."""
        c = self.scenario.controller
        return np.array([c.reduction_width_arcmin(name) for name in self.shared.sources])

    def diverges(self, reduced) -> np.ndarray:
        """Members the controller would search for a scan of (their schedule then differs)."""
        flags = np.asarray(reduced.flags)[..., -1]  # AVG
        missed = (flags != 0).any(axis=(1, 2))
        search = self.scenario.controller.search
        return missed if search.enabled else np.zeros_like(missed)

    def member_columns(self, reduced, m: int) -> dict[str, np.ndarray]:
        """Recording columns of member ``m`` for fit A (AVG rows)."""
        cols = dict(self.shared.columns)
        off = np.asarray(reduced.offset_arcmin)[m, :, :, -1]
        flags = np.asarray(reduced.flags)[m, :, :, -1]
        cols["xel_arcmin"] = off[:, 0]
        cols["el_arcmin"] = off[:, 1]
        cols["good"] = (flags == 0).all(axis=1)
        return cols

    def run_block(self, members: Sequence[int], seeds: Sequence[int]
                  ) -> tuple[MemberResults, list[int]]:
        """Fit A of the members on the shared schedule; also the members to simulate in full."""
        power, std = self.simulate(seeds)
        reduced = self.reduce(power, std)
        diverged = self.diverges(reduced)
        keep = [m for m in range(len(members)) if not diverged[m]]
        results = _results([members[m] for m in keep],
                           [fit_rows(self.member_columns(reduced, m), self.terms, self.fit_name,
                                     self.shared.sensor_lag_s)
                            for m in keep], len(self.terms), full=False)
        return results, [members[m] for m in range(len(members)) if diverged[m]]


def _results(members: Sequence[int], fits: Sequence, n_terms: int, full: bool) -> MemberResults:
    n = len(members)
    out = MemberResults(np.asarray(members, dtype=np.int64), np.full((n, n_terms), np.nan),
                        np.full((n, n_terms), np.nan), np.full((n, n_terms), np.nan),
                        np.full(n, np.nan), np.zeros(n, dtype=np.int64),
                        np.full(n, full, dtype=bool), np.zeros(n, dtype=bool))
    for j, fit in enumerate(fits):
        if fit is None:
            out.failed[j] = True
            continue
        out.values[j] = fit.values_arcsec
        out.sigma_tpoint[j] = fit.sigma_arcsec
        out.sigma_honest[j] = fit.sigma_honest_arcsec
        out.sky_rms[j] = fit.sky_rms_arcsec
        out.n_used[j] = fit.n_used
    return out


def full_member(scenario: Scenario, member: int, seed: int, terms: Sequence[str],
                fit_name: str) -> MemberResults:
    """A member simulated in full (its own schedule) and fitted as fit A."""
    run = simulate(scenario, seed=seed)
    cols = {k: np.asarray(v) for k, v in _columns(run.rows).items()}
    return _results([member], [fit_rows(cols, terms, fit_name,
                                        scenario.controller.structure_lag_s)],
                    len(terms), full=True)


def _columns(rows: list[dict]) -> dict[str, np.ndarray]:
    return columns(rows)
