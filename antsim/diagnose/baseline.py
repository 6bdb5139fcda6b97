"""The baseline: what the user believes, and the noise it predicts.

Rules: the pointing-model terms are those of ``--model`` when given; else, with a
scenario, the scenario's ``controller.fit_model`` (or the terms of its model in use); else the
model in the recordings' metadata; else, for a TPOINT file, TPOINT's eight terms IA IE NPAE CA
AN AW TF TX. Recordings of an equatorial mount take their terms from TPOINT's equatorial
vocabulary (``--model crane1981``, ``crane11``, or IH,ID,NP,...; default ``crane11``, as
``antsim fit``).

With a scenario the noise is predicted by simulating it: ``n_sims`` campaigns with seeds other
than the recordings' are run, each is fitted with the baseline terms, and for every recorded
scan the simulations' scans of the same source at the same time (the schedule is
deterministic) give the predicted systematic residual (their mean: thermal, reduction and
structure effects the model does not describe but the scenario does) and the noise (their
scatter, shrunk towards a running mean in time so that a few simulations suffice). The
simulations are cached on disk, keyed by the scenario's text, the seeds, the terms and the
software version; each file holds that key and a digest of its content, recomputed when it is
read, so that a file antsim did not write (damaged, edited, renamed) is simulated again with a
note rather than used (docs/caches.md). Without a scenario the noise is white with one level
per axis, estimated from the data.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import warnings
import zlib
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from zipfile import BadZipFile

import numpy as np
from scipy.optimize import nnls

import controller
from antsim.simulate.runner import recording_meta, simulate
from controller.errors import InputError, Note
from controller.pointing.data import PointingData
from controller.pointing.equatorial import (
    EQUATORIAL_MODELS,
    equatorial_terms,
    is_equatorial_term,
    load_equatorial_model,
)
from controller.pointing.fitting import fit_model
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.pointing.modelio import load_model
from controller.pointing.terms import TermError, get_term, is_term_name

from .._version import __version__
from ..simulate.streaming import release_prestarted
from .data import Observations, from_columns, from_rows
from .fastsim import shared_schedule_columns
from .problem import Prediction

__all__ = ["BaselineSpec", "SimulatedBaseline", "resolve_baseline", "white_prediction"]

#: bump when the cached simulation products change meaning
CACHE_VERSION = 3
#: two scans match when they observe the same source within this time (s)
MATCH_TOLERANCE_S = 150.0
#: prior weight (in scans' worth of degrees of freedom) of the running-mean noise level
SHRINK_DOF = 10.0
#: running-mean half width in time for the noise level (s)
NOISE_BANDWIDTH_S = 5400.0
DEFAULT_SIMS = 8
SEED_BASE = 7_000_001
#: lag bins (s) and exponential time constants (s) of the noise-correlation model
CORR_BINS = ((1.0, 450.0), (450.0, 900.0), (900.0, 1800.0), (1800.0, 3600.0),
             (3600.0, 7200.0), (7200.0, 14400.0))
CORR_TAUS_S = (150.0, 600.0, 2400.0, 9600.0)


@dataclass(frozen=True)
class BaselineSpec:
    """The baseline model's terms and where they come from (a sentence)."""

    terms: tuple[str, ...]
    origin: str
    scenario: object | None = None  # antsim.scenario.Scenario
    model_in_use: PointingModel | None = None


def parse_model_option(spec: str, obs: Observations | None = None
                       ) -> tuple[tuple[str, ...], str]:
    """``--model``: a named model, a ``.mod``/JSON model file, or comma-separated terms (on
    an equatorial mount's recordings ``obs``, of its equatorial vocabulary)."""
    if obs is not None and obs.mount == "equatorial":
        return _parse_equatorial_model(spec, obs)
    if spec in NAMED_MODELS:
        return NAMED_MODELS[spec], f"the named model {spec}"
    path = Path(spec)
    if path.is_file():
        model = load_model(path)
        return model.names, f"the terms of {path}"
    names = tuple(t.strip().upper() for t in spec.split(",") if t.strip())
    bad = [n for n in names if not is_term_name(n)]
    if not names or bad:
        raise InputError("command line", "--model", spec,
                         "is neither a named model, a model file nor a list of known terms",
                         f"named models: {', '.join(sorted(NAMED_MODELS))}; or e.g. "
                         "IA,IE,NPAE,CA,AN,AW,TF,TX")
    return names, "the terms given with --model"


def _parse_equatorial_model(spec: str, obs: Observations) -> tuple[tuple[str, ...], str]:
    if spec in EQUATORIAL_MODELS:
        return EQUATORIAL_MODELS[spec], f"the named equatorial model {spec}"
    if Path(spec).is_file():
        model = load_equatorial_model(spec, math.degrees(obs.latitude_rad))
        return model.names, f"the terms of {spec}"
    names = tuple(t.strip().upper() for t in spec.split(",") if t.strip())
    if not names or not all(is_equatorial_term(n) for n in names):
        raise InputError("command line", "--model", spec,
                         "is neither a named equatorial model, a model file nor a list of "
                         "equatorial terms (these recordings are from an equatorial mount)",
                         f"equatorial models: {', '.join(sorted(EQUATORIAL_MODELS))}; or e.g. "
                         "IH,ID,CH,NP,MA,ME,TF")
    return names, "the terms given with --model"


def resolve_baseline(obs: Observations, scenario=None, model: str | None = None) -> BaselineSpec:
    """The baseline terms by the rules in the module docstring."""
    in_use = obs.model_in_use
    if scenario is not None:
        in_use = scenario.controller.model
    if model:
        terms, origin = parse_model_option(model, obs)
    elif scenario is not None:
        c = scenario.controller
        if c.fit_terms:
            terms = tuple(c.fit_terms)
            origin = f"scenario {scenario.name}'s fit model ({c.fit_model_name or 'custom'})"
        elif len(c.model.names):
            terms = tuple(c.model.names)
            origin = f"scenario {scenario.name}'s model in use ({c.model.name})"
        else:
            terms, origin = NAMED_MODELS["tpoint8"], "TPOINT's eight terms (scenario has none)"
    elif obs.model_in_use is not None and len(obs.model_in_use.names):
        terms = tuple(obs.model_in_use.names)
        for named in _named_models(obs):  # metadata may have sorted the names
            if named and set(named) == set(terms):
                terms = tuple(named)
        origin = f"the model in the recordings' metadata ({obs.model_in_use.name})"
    elif obs.mount == "equatorial":
        terms = EQUATORIAL_MODELS["crane11"]
        origin = "the equatorial model crane11 (IH ID CH NP MA ME TF FO DAF TX HCES)"
    else:
        terms = NAMED_MODELS["tpoint8"]
        origin = "TPOINT's eight terms IA IE NPAE CA AN AW TF TX"
    feed_terms = [t for t in terms if _needs_feed_angle(t)]
    if feed_terms:
        raise InputError(obs.path, "baseline terms", " ".join(feed_terms),
                         "diagnose does not use feed-angle terms in its baseline yet",
                         "give --model with the terms without them (e.g. --model ghigo10): "
                         "its feed_offset candidate then looks for the feed terms")
    return BaselineSpec(tuple(terms), origin, scenario, in_use)


def _named_models(obs: Observations):
    """The named models' term lists in the recordings' vocabulary."""
    if obs.mount == "equatorial":
        return EQUATORIAL_MODELS.values()
    return NAMED_MODELS.values()


def _needs_feed_angle(name: str) -> bool:
    try:
        term = get_term(name)
    except TermError:
        return False  # reported where the terms are fitted
    return any(arg == "F" for _, _, factors in term.components for _, arg, _ in factors)


# ---------------------------------------------------------------------------------------------
# White noise (no simulation)
# ---------------------------------------------------------------------------------------------
def white_prediction(obs: Observations, why: str = "") -> Prediction:
    """Zero systematic residual and unit noise (each axis' level is estimated in the fit);
    ``why``: words for the description (why no simulation predicts it)."""
    n = obs.n
    ones = np.ones(n)
    hpbw = float(obs.meta.get("beam_hpbw_arcmin", np.nan))
    width_mean = np.full((n, 2), hpbw) if np.isfinite(hpbw) else None
    return Prediction(kind="white", sys_xel=np.zeros(n), sys_el=np.zeros(n), sig_xel=ones,
                      sig_el=ones.copy(), pol_mean=np.zeros((n, 2)), pol_sig=None,
                      width_mean=width_mean, width_sig=None,
                      description="white noise, one level per axis estimated from the data"
                      + (f" ({why})" if why else ""))


# ---------------------------------------------------------------------------------------------
# Simulated prediction
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SimProducts:
    """What one baseline simulation contributes (per scan of that simulation)."""

    t_s: np.ndarray
    source: np.ndarray
    res: np.ndarray  # (n, 2) residual of the baseline fit, NaN where not used
    pol: np.ndarray  # (n, 2) XR - XL, NaN where missing
    width: np.ndarray  # (n, 2) measured FWHM (arcmin), NaN where not good
    az_rad: np.ndarray
    el_rad: np.ndarray


def _products(obs: Observations, terms: Sequence) -> SimProducts:
    """One simulation's products; ``terms``: names or Term objects (an equatorial mount's)."""
    good = obs.good
    data = PointingData(obs.az_rad[good], obs.el_rad[good], obs.xel_arcsec[good],
                        obs.el_arcsec[good])
    fit = fit_model(data, list(terms), robust=True)
    # residuals of every good scan (outliers are clipped when the simulations are combined)
    res = np.full((obs.n, 2), np.nan)
    idx = np.flatnonzero(good)
    res[idx, 0] = np.asarray(fit.residual_xel_arcsec)
    res[idx, 1] = np.asarray(fit.residual_el_arcsec)
    pol = np.column_stack([obs.pol_xel_arcsec, obs.pol_el_arcsec]) \
        if obs.pol_xel_arcsec is not None else np.full((obs.n, 2), np.nan)
    width = np.column_stack([obs.width_xel_arcmin, obs.width_el_arcmin]) \
        if obs.width_xel_arcmin is not None else np.full((obs.n, 2), np.nan)
    width = np.where(good[:, None], width, np.nan)
    return SimProducts(obs.t_s.copy(), obs.source.copy(), res, pol, width, obs.az_rad.copy(),
                       obs.el_rad.copy())


def _simulate_rows(args):
    """Worker: one baseline simulation (top level so that a process pool can run it)."""
    scenario, seed = args
    result = simulate(scenario, seed)
    return result.rows, recording_meta(scenario, seed, result.model)


_FINGERPRINT: str | None = None


def code_fingerprint() -> str:
    """A hash of the source that makes a simulation (the simulator and the controller; not
    diagnosis, plans, figures, reports or the command line), so that cached simulations are
    redone when that code changes."""
    global _FINGERPRINT
    if _FINGERPRINT is None:
        h = hashlib.sha256()
        roots = [Path(__file__).resolve().parents[1], Path(controller.__file__).resolve().parent]
        skip_dirs = {"diagnose", "commands", "plan", "figures"}
        skip_files = {"report.py", "outputs.py", "cli.py", "__main__.py"}
        for root in roots:
            for path in sorted(root.rglob("*.py")):
                rel = path.relative_to(root).parts
                if skip_dirs & set(rel[:-1]) or path.name in skip_files:
                    continue
                h.update(path.name.encode())
                h.update(path.read_bytes())
        _FINGERPRINT = h.hexdigest()[:16]
    return _FINGERPRINT


def default_cache_dir() -> Path:
    env = os.environ.get("ANTSIM_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "antsim"


#: a cached simulation larger than this (unpacked) is not one antsim wrote: a campaign of
#: 200,000 scans takes 66 MB
MAX_CACHE_BYTES = 256 * 2**20
#: the arrays of a cached simulation, in the order of its digest
_CACHED = ("t_s", "source", "res", "pol", "width", "az_rad", "el_rad")


def _cached_arrays(prod: SimProducts) -> dict[str, np.ndarray]:
    return {"t_s": prod.t_s, "source": prod.source.astype("U64"), "res": prod.res,
            "pol": prod.pol, "width": prod.width, "az_rad": prod.az_rad,
            "el_rad": prod.el_rad}


def _digest(key: str, arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 of the inputs' key and every array (dtype, shape and bytes)."""
    h = hashlib.sha256(key.encode())
    for name in _CACHED:
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name} {a.dtype.str} {a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _why(err: Exception) -> str:
    return str(err) if isinstance(err, ValueError) and str(err) else type(err).__name__


def _read_cached(path: Path, key: str) -> SimProducts:
    """A cached simulation's products, checked against what wrote them: the inputs' key and
    the digest of the content, recomputed (ValueError saying what does not match). Data
    only: ``allow_pickle=False``."""
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
        if not hasattr(z, "files"):
            raise ValueError("not an archive of arrays")
        size = sum(info.file_size for info in z.zip.infolist())
        if size > MAX_CACHE_BYTES:  # read before its arrays are: no memory taken
            raise ValueError(f"it unpacks to {size} bytes")
        missing = [k for k in ("key", "digest", *_CACHED) if k not in z.files]
        if missing:
            raise ValueError(f"no {missing[0]}")
        if str(z["key"][()]) != key:
            raise ValueError("made from other inputs")
        arrays = {k: z[k] for k in _CACHED}
        if _digest(key, arrays) != str(z["digest"][()]):
            raise ValueError("its digest does not match its content")
    return SimProducts(arrays["t_s"], arrays["source"].astype(str), arrays["res"],
                       arrays["pol"], arrays["width"], arrays["az_rad"], arrays["el_rad"])


class SimulatedBaseline:
    """Simulations of the baseline scenario and the per-scan predictions they give."""

    def __init__(self, scenario, terms: Sequence[str], n_sims: int = DEFAULT_SIMS,
                 avoid_seeds: Sequence[int] = (), cache_dir: str | Path | None = None,
                 use_cache: bool = True, jobs: int = 1, model: PointingModel | None = None):
        if n_sims < 2:
            raise InputError("command line", "--sims", n_sims, "needs at least 2 simulations")
        self.scenario = scenario if model is None else scenario.with_controller_model(model)
        self.terms = tuple(terms)
        self.mount = scenario.mount.kind
        #: the terms each simulation is fitted with (an equatorial mount's own vocabulary)
        self.fit_terms = self.terms
        if self.mount == "equatorial":
            self.fit_terms = equatorial_terms(self.terms, scenario.site.latitude_deg)
        seeds = []
        k = 0
        avoid = {int(s) for s in avoid_seeds}
        while len(seeds) < n_sims:
            if SEED_BASE + k not in avoid:
                seeds.append(SEED_BASE + k)
            k += 1
        self.seeds = tuple(seeds)
        self.cache_dir = Path(cache_dir) if cache_dir is not None else default_cache_dir()
        self.use_cache = use_cache
        self.jobs = max(1, int(jobs))
        self.products = self._load_or_run()
        self.corr = self._correlation()

    # ------------------------------------------------------------------ simulations
    def _key(self, seed: int) -> str:
        c = self.scenario.controller
        blob = json.dumps({
            "v": CACHE_VERSION, "software": __version__, "code": code_fingerprint(),
            "text": self.scenario.text,
            "effects": [[e.name, sorted(e.params.items(), key=str)]
                        for e in self.scenario.effects],
            "model": c.model.as_dict(), "terms": self.terms, "seed": seed,
            "duration": self.scenario.duration_s,
        }, sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()[:24]

    def _load_or_run(self) -> list[SimProducts]:
        out: dict[int, SimProducts] = {}
        todo = []
        refused: list[tuple[Path, str]] = []
        for seed in self.seeds:
            key = self._key(seed)
            path = self.cache_dir / f"baseline-{key}.npz"
            if self.use_cache and path.exists():
                try:
                    out[seed] = _read_cached(path, key)
                    continue
                except (OSError, KeyError, ValueError, EOFError, BadZipFile, zlib.error) as err:
                    # not what antsim wrote for these inputs (a torn write, a disk error, an
                    # edit): never used, simulated again and rewritten
                    refused.append((path, _why(err)))
            todo.append(seed)
        if refused:
            path, why = refused[0]
            more = f" and {len(refused) - 1} more" if len(refused) > 1 else ""
            warnings.warn(Note(f"the cached baseline simulation {path}{more} was not written "
                               f"by antsim for this scenario and seed ({why}); simulated "
                               "again"), stacklevel=3)
        if not todo or self.scenario.controller.method != "five_point":
            release_prestarted()  # no members to stream (antsim diagnose started one)
        else:
            shared = shared_schedule_columns(self.scenario, todo, self.jobs)
            for seed, cols in shared.items():
                prod = _products(from_columns(cols), self.fit_terms)
                out[seed] = prod
                if self.use_cache:
                    self._save(seed, prod)
            todo = [s for s in todo if s not in out]
        if todo:
            args = [(self.scenario, s) for s in todo]
            if self.jobs > 1 and len(todo) > 1:
                with ProcessPoolExecutor(max_workers=min(self.jobs, len(todo))) as pool:
                    results = list(pool.map(_simulate_rows, args))
            else:
                results = [_simulate_rows(a) for a in args]
            for seed, (rows, meta) in zip(todo, results, strict=True):
                prod = _products(from_rows(rows, meta), self.fit_terms)
                out[seed] = prod
                if self.use_cache:
                    self._save(seed, prod)
        return [out[s] for s in self.seeds]

    def _save(self, seed: int, prod: SimProducts) -> None:
        key = self._key(seed)
        path = self.cache_dir / f"baseline-{key}.npz"
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        arrays = _cached_arrays(prod)
        try:
            self.cache_dir.mkdir(parents=True, exist_ok=True)
            # a new file of our own (no link followed), renamed over any old one
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL
                         | getattr(os, "O_NOFOLLOW", 0), 0o644)
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, key=np.array(key), digest=np.array(_digest(key, arrays)),
                         **arrays)
            os.replace(tmp, path)
        except OSError:
            tmp.unlink(missing_ok=True)  # a read-only or full cache only costs time

    # ------------------------------------------------------------------ prediction
    def matches(self, obs: Observations) -> np.ndarray:
        """Index (K, n) of each simulation's scan matching each observation (-1: none)."""
        k_sims = len(self.products)
        idx = np.full((k_sims, obs.n), -1, dtype=int)
        if obs.source is None:
            return idx
        for k, prod in enumerate(self.products):
            for src in np.unique(obs.source):
                mine = np.flatnonzero(obs.source == src)
                theirs = np.flatnonzero(prod.source == src)
                if theirs.size == 0:
                    continue
                order = theirs[np.argsort(prod.t_s[theirs])]
                ts = prod.t_s[order]
                pos = np.clip(np.searchsorted(ts, obs.t_s[mine]), 1, max(ts.size - 1, 1))
                left = np.clip(pos - 1, 0, ts.size - 1)
                right = np.clip(pos, 0, ts.size - 1)
                pick = np.where(np.abs(ts[left] - obs.t_s[mine])
                                <= np.abs(ts[right] - obs.t_s[mine]), left, right)
                ok = np.abs(ts[pick] - obs.t_s[mine]) <= MATCH_TOLERANCE_S
                idx[k, mine[ok]] = order[pick[ok]]
        return idx

    def predict(self, obs: Observations) -> Prediction:
        idx = self.matches(obs)
        matched_any = (idx >= 0).any(axis=0)
        res = self._gather(idx, "res")  # (K, n, 2)
        sys, sig, count = _mean_and_sigma(res, obs.t_s)
        # observations no simulation matched: no systematic prediction, inflated noise
        rms_sys = np.sqrt(np.nanmean(sys**2, axis=0)) if np.isfinite(sys).any() else np.zeros(2)
        lonely = count < 1
        sys = np.where(lonely[:, None], 0.0, sys)
        sig = np.where(lonely[:, None], np.sqrt(sig**2 + rms_sys**2), sig)
        total_sig = sig * np.sqrt(1.0 + 1.0 / np.maximum(count, 1))[:, None]
        pol_mean, pol_sig, pc = _mean_and_sigma(self._gather(idx, "pol"), obs.t_s)
        pol_sig = pol_sig * np.sqrt(1.0 + 1.0 / np.maximum(pc, 1))[:, None]
        w_mean, w_sig, wc = _mean_and_sigma(self._gather(idx, "width"), obs.t_s)
        w_sig = w_sig * np.sqrt(1.0 + 1.0 / np.maximum(wc, 1))[:, None]
        desc = (f"simulation of the scenario: {len(self.products)} seeds, "
                f"{int(matched_any.sum())} of {obs.n} scans matched; correlation of "
                f"successive scans {self.corr_at(300.0)[0]:.2f} (xel), "
                f"{self.corr_at(300.0)[1]:.2f} (el)")
        return Prediction(kind="simulated", sys_xel=sys[:, 0], sys_el=sys[:, 1],
                          sig_xel=total_sig[:, 0], sig_el=total_sig[:, 1],
                          pol_mean=np.where(pc[:, None] >= 1, pol_mean, 0.0), pol_sig=pol_sig,
                          width_mean=w_mean, width_sig=w_sig, matched=matched_any,
                          n_sims=len(self.products), description=desc,
                          corr_xel=self.corr[0], corr_el=self.corr[1])

    def corr_at(self, dt_s: float) -> tuple[float, float]:
        """The noise correlation model at lag ``dt_s`` (xel, el)."""
        return tuple(sum(w * math.exp(-dt_s / tau) for w, tau in m) for m in self.corr)

    def _correlation(self):
        """Per axis, the correlation in time of the noise: the simulations' deviations from
        their mean, paired within each simulation and binned by lag, fitted by a sum of
        exponentials with non-negative weights (positive definite by construction)."""
        ref = self.products[0]
        geo = Observations(t_s=ref.t_s, az_rad=ref.az_rad, el_rad=ref.el_rad,
                           xel_arcsec=np.zeros(ref.t_s.size), el_arcsec=np.zeros(ref.t_s.size),
                           good=np.isfinite(ref.res).all(axis=1), source=ref.source)
        idx = self.matches(geo)
        values = self._gather(idx, "res")
        mean, sig, _ = _mean_and_sigma(values, geo.t_s)
        k = values.shape[0]
        z = (values - mean[None]) / sig[None]
        t = geo.t_s
        dt = np.abs(t[:, None] - t[None, :])
        off = ~np.eye(t.size, dtype=bool)
        out = []
        for axis in range(2):
            zz = np.nan_to_num(z[:, :, axis])
            ok = np.isfinite(z[:, :, axis]).astype(float)
            prod = np.einsum("ki,kj->ij", zz, zz)
            cnt = np.einsum("ki,kj->ij", ok, ok)
            centres, values_b, weights = [], [], []
            for lo, hi in CORR_BINS:
                sel = off & (dt > lo) & (dt <= hi)
                c = float(cnt[sel].sum())
                if c < 50:
                    continue
                centres.append(float(np.sum(dt[sel] * cnt[sel]) / c))
                values_b.append(float(prod[sel].sum() / c) * k / (k - 1))
                weights.append(math.sqrt(c))
            if not centres:
                out.append(())
                continue
            taus = np.array(CORR_TAUS_S)
            a = np.exp(-np.array(centres)[:, None] / taus[None, :]) * np.array(weights)[:, None]
            b = np.array(values_b) * np.array(weights)
            wts, _ = nnls(a, b)
            total = wts.sum()
            if total > 0.9:
                wts *= 0.9 / total
            out.append(tuple((float(w), float(tau)) for w, tau in zip(wts, taus, strict=True)
                             if w > 1e-3))
        return tuple(out)

    def _gather(self, idx: np.ndarray, what: str) -> np.ndarray:
        k_sims, n = idx.shape
        out = np.full((k_sims, n, 2), np.nan)
        for k, prod in enumerate(self.products):
            ok = idx[k] >= 0
            out[k, ok] = getattr(prod, what)[idx[k, ok]]
        return out

    def reference_observations(self) -> Observations:
        """The first simulation's scans as geometry (for detection thresholds)."""
        p = self.products[0]
        good = np.isfinite(p.res).all(axis=1)
        n = p.t_s.size
        return Observations(t_s=p.t_s, az_rad=p.az_rad, el_rad=p.el_rad,
                            xel_arcsec=np.zeros(n), el_arcsec=np.zeros(n), good=good,
                            source=p.source, kind="ecsv", path="<baseline simulation>",
                            mount=self.mount)


def _mean_and_sigma(values: np.ndarray, t_s: np.ndarray, clip: float = 4.0):
    """Per observation (axis last): mean over simulations, a noise sigma shrunk towards a
    running mean in time, and the number of simulations that contributed. Values more than
    ``clip`` sigma from the mean (gusts) are dropped and the estimates redone."""
    values = np.array(values, dtype=float)
    for _ in range(2):
        mean, sigma, _count = _mean_and_sigma_once(values, t_s)
        with np.errstate(invalid="ignore"):
            bad = np.abs(values - mean[None]) > clip * sigma[None]
        if not bad.any():
            break
        values[bad] = np.nan
    return _mean_and_sigma_once(values, t_s)


def _mean_and_sigma_once(values: np.ndarray, t_s: np.ndarray):
    count = np.isfinite(values).sum(axis=0).min(axis=1)  # (n,)
    c = np.isfinite(values).sum(axis=0)  # (n, 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(c > 0, np.nansum(values, axis=0) / np.maximum(c, 1), np.nan)
        dev2 = np.nansum((values - mean[None]) ** 2, axis=0)  # (n, 2)
    dof = np.maximum(c - 1, 0).astype(float)
    var = np.where(dof > 0, dev2 / np.maximum(dof, 1), np.nan)
    smooth = np.empty_like(mean)
    order = np.argsort(t_s)
    ts = t_s[order]
    for axis in range(2):
        v = var[order, axis]
        d = dof[order, axis]
        ok = np.isfinite(v) & (d > 0)
        if not ok.any():
            smooth[:, axis] = np.nan
            continue
        # running mean of the per-scan variances, weighted by their degrees of freedom
        wt = np.exp(-0.5 * ((ts[:, None] - ts[None, ok]) / NOISE_BANDWIDTH_S) ** 2) * d[ok]
        s = (wt @ v[ok]) / np.maximum(wt.sum(axis=1), 1e-300)
        smooth[order, axis] = s
    var_i = np.where(dof > 0, (SHRINK_DOF * smooth + dof * np.nan_to_num(var)) /
                     (SHRINK_DOF + dof), smooth)
    # a quantity no simulation has (the XR - XL offsets of a one-channel receiver) stays NaN
    fill = np.nanmedian(var_i) if np.isfinite(var_i).any() else np.nan
    sigma = np.sqrt(np.where(np.isfinite(var_i), var_i, fill))
    mean = np.where(np.isfinite(mean), mean, 0.0)
    return mean, sigma, count


def offset_scale(obs: Observations, scenario=None) -> np.ndarray:
    """Per scan, the fraction of a pointing error its measured offset shows.

    The reduction assumes a Gaussian of width s_a (the nominal beam, or the beam widened by
    the catalogued source size when the controller uses it); a source of size s_s seen with
    the true beam s_b gives a Gaussian of width sqrt(s_b^2 + s_s^2), and the five-point
    estimate of its offset is s_a^2 / (s_b^2 + s_s^2) of the true one (0.91 for Taurus A and
    Cassiopeia A reduced with the 11' beam, docs/physics.md). With a scenario the sizes are
    the scenario's; without one they come from the widths the recordings measured per source.
    """
    n = obs.n
    if obs.source is None:
        return np.ones(n)
    out = np.ones(n)
    if scenario is not None:
        beam = float(scenario.beam.hpbw_arcmin)
        for s in scenario.sources:
            assumed = scenario.controller.reduction_width_arcmin(s.name)
            out[obs.source == s.name] = assumed**2 / (beam**2 + float(s.size_arcmin) ** 2)
        return out
    hpbw = obs.meta.get("beam_hpbw_arcmin")
    if hpbw is None or obs.width_xel_arcmin is None:
        return out
    assumed_width = obs.meta.get("reduction_width_arcmin") or {}
    for src in np.unique(obs.source):
        m = (obs.source == src) & obs.good
        w2 = np.concatenate([obs.width_xel_arcmin[m], obs.width_el_arcmin[m]]) ** 2
        w2 = w2[np.isfinite(w2)]
        if w2.size >= 3:
            assumed = float(assumed_width.get(str(src), hpbw))
            out[obs.source == src] = min(1.0, assumed**2 / float(np.median(w2)))
    return out
