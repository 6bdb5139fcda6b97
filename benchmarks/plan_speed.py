"""How long ``antsim plan ghigo1990_whatif`` takes, and whether its numbers are the reference's.

    python benchmarks/plan_speed.py [--workers N] [--out DIR]
                                    [--reference benchmarks/data/ghigo1990_whatif_plan.json]

Runs the command as a user would (``python -m antsim plan ghigo1990_whatif --out DIR``, a
process of its own, the machine's cores unless ``--workers``), prints its wall time against
the target (60 s on two cores), then compares every number of its ``plan.json`` that is an
answer or a table entry with the reference file, the ``plan.json`` that the command wrote
before the answering stage was rebuilt (kept in ``benchmarks/data/``).

Each number must lie within its Monte Carlo error of the reference: three standard errors of
the difference of two independent estimates, ``3 sqrt(e_ref^2 + e_new^2)``, where

* a Monte Carlo sigma or bias of the members has the error the table states
  (``sigma_mc_error_arcsec`` = sigma / sqrt(2 (N - 1)), ``bias_error_arcsec`` =
  sigma / sqrt(N));
* a predicted sigma or bias (a variant's, each point of a duration curve, each source list
  checked) has the error ``plan.json`` states beside it (``sigma_fisher_error_arcsec`` and
  ``bias_predicted_error_arcsec`` in a variant's table, ``sigma_error_arcsec`` and
  ``bias_error_arcsec`` in an answer): the sampling error of its two simulated parts, the
  robust fit's rejections (64 draws of the predicted noise) and the random slow errors (128
  or 256 draws), see :mod:`antsim.plan.fisher`. The reference file predates those fields; it was
  made by the same estimators with the same number of draws, so its error is taken as the
  new run's.

A number with no stated error (a count of scans, a source list, the pairs that cannot be
separated) must be equal. A duration answer may differ only where the target lies within the
error of the curve at every count between the two answers. Exit status 1 when a number is
outside its error (the wall time is reported, not judged: the machine is shared).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "benchmarks" / "data" / "ghigo1990_whatif_plan.json"
#: the target: the whole command on two cores
TARGET_S = 60.0
#: standard errors of the difference allowed
K_SIGMA = 3.0


def run(out: Path, workers: int | None) -> float:
    """Wall time (s) of ``antsim plan ghigo1990_whatif --out OUT`` in a process of its own."""
    cmd = [sys.executable, "-m", "antsim", "plan", "ghigo1990_whatif", "--out", str(out),
           "--no-progress"]
    if workers is not None:
        cmd += ["--workers", str(workers)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def _tolerance(*errors: float | None) -> float:
    """K_SIGMA standard errors of the difference of independent estimates (0 with none)."""
    known = [e for e in errors if e is not None]
    return K_SIGMA * math.sqrt(sum(e * e for e in known)) if known else 0.0


def _within(ref: float | None, new: float | None, tol: float) -> bool:
    if ref is None or new is None:
        return ref is None and new is None
    return abs(new - ref) <= tol + 1e-9 * max(abs(ref), 1.0)  # plus rounding


def comparisons(ref: dict, new: dict) -> Iterator[tuple[str, object, object, float, bool]]:
    """(what, reference, new, tolerance, within it) for every number compared."""
    for pr, pn in zip(ref["plans"], new["plans"], strict=True):
        v = pr["name"]
        yield f"{v}: scans", pr["n_scans"], pn["n_scans"], 0.0, pr["n_scans"] == pn["n_scans"]
        for name, tr in pr["terms"].items():
            tn = pn["terms"][name]
            e = tn.get("sigma_fisher_error_arcsec")
            tol = _tolerance(tr.get("sigma_fisher_error_arcsec", e), e)
            yield (f"{v}: {name} sigma predicted", tr["sigma_fisher_arcsec"],
                   tn["sigma_fisher_arcsec"], tol,
                   _within(tr["sigma_fisher_arcsec"], tn["sigma_fisher_arcsec"], tol))
            e = tn.get("bias_predicted_error_arcsec")
            tol = _tolerance(tr.get("bias_predicted_error_arcsec", e), e)
            yield (f"{v}: {name} bias predicted", tr["bias_predicted_arcsec"],
                   tn["bias_predicted_arcsec"], tol,
                   _within(tr["bias_predicted_arcsec"], tn["bias_predicted_arcsec"], tol))
            tol = _tolerance(tr["sigma_mc_error_arcsec"], tn["sigma_mc_error_arcsec"])
            yield (f"{v}: {name} sigma Monte Carlo", tr["sigma_mc_arcsec"], tn["sigma_mc_arcsec"],
                   tol, _within(tr["sigma_mc_arcsec"], tn["sigma_mc_arcsec"], tol))
            tol = _tolerance(tr["bias_error_arcsec"], tn["bias_error_arcsec"])
            yield (f"{v}: {name} bias Monte Carlo", tr["bias_arcsec"], tn["bias_arcsec"], tol,
                   _within(tr["bias_arcsec"], tn["bias_arcsec"], tol))
        pairs_r = sorted(tuple(c["terms"]) for c in pr["cannot_separate"])
        pairs_n = sorted(tuple(c["terms"]) for c in pn["cannot_separate"])
        yield f"{v}: cannot separate", pairs_r, pairs_n, 0.0, pairs_r == pairs_n
    for qr, qn in zip(ref["answers"]["duration"], new["answers"]["duration"], strict=True):
        yield from _duration(qr, qn)
    for qr, qn in zip(ref["answers"]["sources"], new["answers"]["sources"], strict=True):
        yield from _sources(qr, qn)
    for qr, qn in zip(ref["answers"]["coverage"], new["answers"]["coverage"], strict=True):
        yield (f"coverage {qr['based_on']}: days", qr["answer_days"], qn["answer_days"], 0.0,
               qr["answer_days"] == qn["answer_days"])


def _duration(qr: dict, qn: dict) -> Iterator[tuple[str, object, object, float, bool]]:
    what = f"duration {qr['based_on']}"
    tols: dict[int, dict[str, float]] = {}
    for cr, cn in zip(qr["curve"], qn["curve"], strict=True):
        c = cr["count"]
        yield f"{what}: scans after {c}", cr["n_scans"], cn["n_scans"], 0.0, \
            cr["n_scans"] == cn["n_scans"]
        tols[c] = {}
        for term, sr in cr["sigma_arcsec"].items():
            sn = cn["sigma_arcsec"][term]
            e = cn.get("sigma_error_arcsec", {}).get(term)
            tol = _tolerance(cr.get("sigma_error_arcsec", {}).get(term, e), e)
            tols[c][term] = tol
            yield f"{what}: {term} sigma after {c}", sr, sn, tol, _within(sr, sn, tol)
            br, bn = cr["bias_predicted_arcsec"][term], cn["bias_predicted_arcsec"][term]
            e = cn.get("bias_error_arcsec", {}).get(term)
            tol = _tolerance(cr.get("bias_error_arcsec", {}).get(term, e), e)
            yield f"{what}: {term} bias after {c}", br, bn, tol, _within(br, bn, tol)
    ar = qr["answer"]["count"] if qr["reached"] else None
    an = qn["answer"]["count"] if qn["reached"] else None
    ok = ar == an
    if not ok and ar is not None and an is not None:  # the target within the curve's error
        targets = qr["targets_arcsec"]
        ok = all(abs(p["sigma_arcsec"][t] - targets[t]) <= tols[p["count"]][t]
                 for p in qn["curve"] if min(ar, an) <= p["count"] < max(ar, an)
                 for t in targets)
    yield f"{what}: answer ({qr['unit']}s)", ar, an, 0.0, ok


def _sources(qr: dict, qn: dict) -> Iterator[tuple[str, object, object, float, bool]]:
    what = f"sources {qr['based_on']}"
    best_r = qr["best"]["sources"] if qr["best"] else None
    best_n = qn["best"]["sources"] if qn["best"] else None
    yield f"{what}: best list", best_r, best_n, 0.0, best_r == best_n
    for cr, cn in zip(qr["checked"], qn["checked"], strict=True):
        label = f"{what} [{', '.join(cr['sources'])}]"
        yield f"{label}: same list", cr["sources"], cn["sources"], 0.0, \
            cr["sources"] == cn["sources"]
        if not cr["feasible"]:
            continue
        yield f"{label}: scans", cr["n_scans"], cn["n_scans"], 0.0, \
            cr["n_scans"] == cn["n_scans"]
        for term, sr in cr["sigma_arcsec"].items():
            e = cn.get("sigma_error_arcsec", {}).get(term)
            tol = _tolerance(cr.get("sigma_error_arcsec", {}).get(term, e), e)
            sn = cn["sigma_arcsec"][term]
            yield f"{label}: {term} sigma", sr, sn, tol, _within(sr, sn, tol)


def _show(x: object) -> str:
    if isinstance(x, float):
        return f"{x:.3f}"
    if isinstance(x, list | tuple):
        return "[" + ", ".join(str(i) if not isinstance(i, tuple) else "/".join(i)
                               for i in x) + "]"
    return str(x)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=None,
                        help="the command's --workers (default: the machine's cores)")
    parser.add_argument("--out", default=None, help="keep the command's output here")
    parser.add_argument("--reference", default=str(REFERENCE))
    parser.add_argument("--all", action="store_true", help="print every comparison")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.out) if args.out else Path(tmp) / "whatif"
        wall = run(out, args.workers)
        new = json.loads((out / "plan.json").read_text(encoding="utf-8"))
    ref = json.loads(Path(args.reference).read_text(encoding="utf-8"))
    rows = list(comparisons(ref, new))
    bad = [r for r in rows if not r[4]]
    worst = max((abs(r[2] - r[1]) / r[3] * K_SIGMA for r in rows
                 if isinstance(r[1], float) and isinstance(r[2], float) and r[3] > 0),
                default=0.0)
    cores = args.workers if args.workers is not None else os.cpu_count()
    print(f"antsim plan ghigo1990_whatif: {wall:.1f} s wall with {cores} worker(s) "
          f"(target {TARGET_S:.0f} s on two cores)")
    print(f"{len(rows)} numbers compared with {Path(args.reference).name}; "
          f"{len(rows) - len(bad)} within {K_SIGMA:g} standard errors of the difference; "
          f"the largest difference {worst:.2f} standard errors")
    for what, r, n, tol, ok in (rows if args.all else bad):
        print(f"  {'ok ' if ok else 'OUT'} {what}: reference {_show(r)}, now {_show(n)}"
              + (f" (+- {tol:.3f})" if tol else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
