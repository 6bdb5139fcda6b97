"""Model it: findings -> updated scenario and pointing model; re-simulate; before/after.

* The updated scenario is the scenario's own text with one ``[[truth.effects]]`` table
  appended per finding (the simulator effect with its fitted parameters); it loads with
  :func:`antsim.scenario.load_scenario` like any scenario.
* The updated pointing model is the baseline terms refitted together with the findings plus
  the findings' own TPOINT terms (effects that are not pointing terms, such as a drift in
  time, stay out of it: the report says so).
* Re-simulation runs the updated scenario with fresh seeds and compares, scan by scan, the
  recorded residuals of the baseline fit with the simulated ones (a paired two-sample chi^2
  test with the simulations' own scatter and time correlation), before (the original
  scenario) and after (the updated one), and also the two residual distributions
  (two-sample Kolmogorov-Smirnov per axis).
* Plots: residuals before and after (:mod:`antsim.figures.diagnose`), before only when
  nothing was found; on an equatorial mount a figure against its own axes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import ks_2samp

from antsim.figures.diagnose import Residuals, before_after_figures, before_figures
from antsim.figures.style import Canvas, figure_file
from antsim.scenario import EffectSpec, load_scenario
from antsim.world.effects import EFFECTS
from controller.pointing.data import PointingData
from controller.pointing.fitting import fit_model
from controller.pointing.modelio import model_to_json, write_model_file
from controller.pointing.tpoint import TPointModel

from .baseline import SimulatedBaseline
from .candidates.terms import TermsCandidate
from .core import Diagnosis, Finding, plain
from .linalg import lstsq
from .problem import Problem
from .report import write_diagnose_report

__all__ = ["effect_specs", "resimulate", "updated_scenario_text", "write_outputs"]


def _effect_params(finding: Finding, scenario=None) -> tuple[str, dict[str, Any]] | None:
    """The simulator effect name and parameters of a finding (None if it has none)."""
    r = finding.result
    c = r.candidate
    p = r.params
    if c.name == "thermal_sensors":  # temperatures, not an effect's parameters
        return None
    if isinstance(c, TermsCandidate):
        terms = dict(p.get("terms_arcsec", {}))
        if c.effect != "terms" and c.pair:
            cls = EFFECTS[c.effect]
            s = terms.get(cls.sin_term, 0.0)
            co = terms.get(cls.cos_term, 0.0)
            amp, phase = cls.amplitude_phase(s, co)
            return c.effect, {"amplitude_arcsec": amp, "phase_deg": phase}
        return "terms", {"terms_arcsec": terms}
    out = c.effect_from_params(p)
    if out is None:
        return None
    if c.name == "source_structure" and scenario is not None:
        sizes = {s.name: s.size_arcmin for s in scenario.sources}
        out["size_arcmin"] = float(sizes.get(p["source"], p.get("size_arcmin", 0.0)))
    return c.effect, out


def effect_specs(diag: Diagnosis, scenario=None):
    """EffectSpec of every finding that has a simulator effect."""
    specs = []
    for f in diag.findings:
        got = _effect_params(f, scenario)
        if got is None:
            continue
        name, params = got
        if name == "terms":
            specs.append(EffectSpec("terms", {"terms_arcsec": params["terms_arcsec"]}))
            continue
        effect = EFFECTS[name](**params)  # validates names and values
        specs.append(EffectSpec(name, effect.params()))
    return specs


def _toml_value(v: Any) -> str:
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(float(v))


def updated_scenario_text(scenario, diag: Diagnosis) -> str:
    """The scenario's text with the findings appended as ``[[truth.effects]]`` tables."""
    lines = [scenario.text.rstrip("\n"), "",
             "# ---- added by antsim diagnose: the physics the scenario left out, with the "
             "fitted parameters ----"]
    for f, spec in zip([f for f in diag.findings if _effect_params(f, scenario)],
                       effect_specs(diag, scenario), strict=True):
        lines.append(f"# {f.result.candidate.title}: {f.step.significance:.1f} sigma")
        lines.append("[[truth.effects]]")
        lines.append(f"effect = {json.dumps(spec.name)}")
        if spec.name == "terms":
            for term, value in spec.params["terms_arcsec"].items():
                lines.append(f"{term} = {_toml_value(value)}")
        else:
            for key, value in spec.params.items():
                lines.append(f"{key} = {_toml_value(value)}")
        lines.append("")
    return "\n".join(lines).rstrip("\n") + "\n"


def _paired_test(diag: Diagnosis, pred) -> dict[str, Any]:
    """Recorded baseline-fit residuals against a prediction, scan by scan (chi^2 per axis of
    the GLS-whitened differences) — the two samples are the recordings and the simulations."""
    obs = diag.obs
    prob = Problem(obs, pred, diag.problem.base_terms, offset_scale=diag.problem.offset_scale)
    prob.update_outliers()
    gof = prob.gof()
    return {axis: {"chi2": v["chi2"], "dof": v["dof"], "ratio": v["ratio"], "p": v["p"]}
            for axis, v in gof.items()}


def _ks(diag: Diagnosis, baseline) -> dict[str, Any]:
    """Two-sample Kolmogorov-Smirnov test per axis: the recorded residuals of the baseline
    fit against all the simulations' residuals."""
    obs = diag.obs
    good = obs.good
    data = PointingData(obs.az_rad[good], obs.el_rad[good], obs.xel_arcsec[good],
                        obs.el_arcsec[good])
    fit = fit_model(data, obs.terms(diag.problem.base_terms), robust=True)
    used = np.asarray(fit.used)
    rec = (np.asarray(fit.residual_xel_arcsec)[used], np.asarray(fit.residual_el_arcsec)[used])
    out = {}
    for axis, name in ((0, "xel"), (1, "el")):
        sims = np.concatenate([p.res[:, axis] for p in baseline.products])
        sims = sims[np.isfinite(sims)]
        ks = ks_2samp(rec[axis], sims)
        out[name] = {"statistic": float(ks.statistic), "p": float(ks.pvalue)}
    return out


def resimulate(diag: Diagnosis, scenario, n_sims: int = 4, cache_dir=None,
               use_cache: bool = True, jobs: int = 1) -> dict[str, Any]:
    """Simulate the updated scenario and test recorded against simulated residuals, before
    (the scenario as given) and after (with the findings)."""
    specs = effect_specs(diag, scenario)
    updated = scenario.with_effects(tuple(scenario.effects) + tuple(specs))
    model = diag.obs.model_in_use if diag.obs.model_in_use is not None else None
    seed = diag.obs.meta.get("seed")
    avoid = [] if seed is None else [int(seed)]
    after = SimulatedBaseline(updated, diag.problem.base_terms, n_sims, avoid_seeds=avoid,
                              cache_dir=cache_dir, use_cache=use_cache, jobs=jobs, model=model)
    before = diag.sim_baseline
    out: dict[str, Any] = {"n_sims": n_sims, "effects": [s.name for s in specs]}
    if before is not None:
        out["before"] = {"paired": _paired_test(diag, before.predict(diag.obs)),
                         "ks": _ks(diag, before)}
    out["after"] = {"paired": _paired_test(diag, after.predict(diag.obs)),
                    "ks": _ks(diag, after)}
    out["_baseline"] = after
    return out


def residuals_before_after(diag: Diagnosis):
    """What the figures draw: the good scans' positions and the residuals (arcsec) of the
    baseline (before) and of the baseline with every finding (after), each an unweighted
    least-squares fit over the diagnosis's used scans, the residuals its Sky RMS
    (``summary``) is the rms of: the figures print the diagnosis's own numbers. Returns
    (data, before, after) as :class:`antsim.figures.diagnose.Residuals`."""
    p = diag.problem
    obs = diag.obs
    good = obs.good
    rows = p.rows()
    used = p.used[good]
    aux = None if obs.structure is None else {k: (x[good], e[good]) for k, (x, e) in
                                               obs.structure.items()}
    data = PointingData(obs.az_rad[good], obs.el_rad[good], obs.xel_arcsec[good],
                        obs.el_arcsec[good], t_s=obs.t_s[good], aux=aux)
    after_names = [*p.base_terms, *(f.effect for f in diag.findings)]
    out = []
    for names, cols, key in ((list(p.base_terms), p.base, "before"),
                             (after_names, p.current_columns(), "after")):
        coef, _ = lstsq(cols[rows], p.y_raw[rows])
        r = (p.y_raw - cols @ coef).reshape(2, -1)[:, good]
        out.append(Residuals(names, r[0], r[1], used, diag.summary[f"sky_rms_{key}_arcsec"]))
    return data, out[0], out[1]


def _equatorial_plot(before, after, data, path: Path, caption: str):
    """Residuals against the equatorial mount's axes and time (the shared figures draw an
    alt-az sky); ``after`` None: before only."""
    offsets = ("cross-declination", "declination")
    positions = (("hour angle (h, West +)", np.degrees(data.az_rad) / 15.0),
                 ("declination (deg)", np.degrees(data.el_rad)))
    series = [("baseline", before)] + ([("with findings", after)] if after is not None else [])
    with Canvas(13.0, 7.0) as fig:
        axes = fig.subplots(2, 3)
        fig.subplots_adjust(left=0.06, right=0.99, bottom=0.08, top=0.92, hspace=0.3,
                            wspace=0.25)
        for row, axis in enumerate(offsets):
            for col, (xlab, x) in enumerate((*positions,
                                             ("time (h)", np.asarray(data.t_s) / 3600.0))):
                ax = axes[row, col]
                for name, res in series:
                    r = res.residual_xel_arcsec if row == 0 else res.residual_el_arcsec
                    ax.plot(x, r, ".", ms=4, alpha=0.6,
                            label=f"{name} ({res.sky_rms_arcsec:.2f}\")")
                ax.axhline(0.0, color="k", lw=0.5)
                ax.set_xlabel(xlab)
                ax.set_ylabel(f"{axis} residual (arcsec)")
            axes[row, 0].legend(fontsize=8)
        title = ("Residuals before and after modelling the findings" if after is not None
                 else "Residuals of the baseline (nothing found)")
        return figure_file(fig, path, title, caption, ("png",))


def plots(diag: Diagnosis, out_dir: Path) -> list:
    """Residual plots into ``out_dir``: before and after the findings, or before only (with
    a caption saying nothing was found and what was tested); returns their
    :class:`antsim.figures.style.FigureFile` s."""
    data, before, after = residuals_before_after(diag)
    nothing = diag.nothing_found_words() if not diag.findings else ""
    if diag.obs.mount == "equatorial":  # the shared figures draw an alt-az sky
        return [_equatorial_plot(
            before, after if diag.findings else None, data, out_dir / "diagnose_residuals.png",
            nothing or "Residuals of the baseline (before) and with the findings (after) "
                       "against hour angle, declination and time.")]
    if not diag.findings:
        return before_figures(before, data, out_dir, label="diagnose",
                              before_name="baseline", nothing_found=nothing)
    return before_after_figures(before, after, data, out_dir, label="diagnose",
                                before_name="baseline", after_name="with findings")


def write_outputs(diag: Diagnosis, out_dir: str | Path, scenario=None, resim: int = 0,
                  cache_dir=None, use_cache: bool = True, jobs: int = 1) -> dict[str, Any]:
    """Write the report (diagnose.json, diagnose.txt, report.html), the updated model and
    scenario, plots; optionally re-simulate."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Any] = {}
    model = diag.updated_model()
    write_model_file(TPointModel.from_model(
        model, caption=f"{model.name} (antsim diagnose)", n_obs=int(diag.problem.used.sum()),
        sky_rms_arcsec=diag.summary["sky_rms_after_arcsec"]), out / "model_updated.dat")
    (out / "model_updated.json").write_text(json.dumps(model_to_json(model), indent=2) + "\n",
                                            encoding="utf-8")
    written["model"] = ["model_updated.dat", "model_updated.json"]
    nonterm = [f.effect for f in diag.findings
               if not isinstance(f.result.candidate, TermsCandidate)]
    if nonterm:
        written["not_in_model"] = (f"{', '.join(nonterm)} cannot be written as pointing-model "
                                   "terms (they depend on time, source, polarization or the "
                                   "beam); they are in the updated scenario")
    if any(f.result.candidate.name == "thermal_sensors" for f in diag.findings):
        written["not_in_scenario"] = ("thermal (the structure sensors' terms) is in the updated "
                                      "model, not in the updated scenario: six coefficients do "
                                      "not give the structure's heating (a thermal effect's "
                                      "forcing and time constants)")
    if scenario is not None:
        text = updated_scenario_text(scenario, diag)
        path = out / "scenario_updated.toml"
        path.write_text(text, encoding="utf-8")
        load_scenario(path)  # it must load like any scenario
        written["scenario"] = path.name
        if resim > 0 and diag.findings:
            res = resimulate(diag, scenario, resim, cache_dir, use_cache, jobs)
            res.pop("_baseline", None)
            written["resimulation"] = plain(res)
    figures = plots(diag, out)
    written["plots"] = [f.path.name for f in figures]
    written["report"] = "report.html"
    doc = diag.to_json()
    doc["outputs"] = plain(written)
    (out / "diagnose.json").write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    text = diag.text()
    if "resimulation" in written:
        text += "\n" + resimulation_words(written["resimulation"])
    (out / "diagnose.txt").write_text(text + "\n", encoding="utf-8")
    write_diagnose_report(doc, text, figures, out, recordings=str(diag.obs.path),
                          axes=diag.axes_label(),
                          nothing_found="" if diag.findings else diag.nothing_found_words())
    return written


def resimulation_words(res: dict[str, Any]) -> str:
    lines = [f"re-simulation with the findings ({res['n_sims']} seeds): recorded against "
             "simulated residuals, scan by scan (chi2/dof, p) and as distributions (KS p)"]
    for when in ("before", "after"):
        if when not in res:
            continue
        parts = []
        for axis in ("xel", "el"):
            pr = res[when]["paired"][axis]
            ks = res[when]["ks"][axis]
            parts.append(f"{axis} {pr['chi2'] / pr['dof']:.2f} (p = {_p(pr['p'])}), KS p = "
                         f"{_p(ks['p'])}")
        lines.append(f"  {when}: " + "; ".join(parts))
    return "\n".join(lines)


def _p(p: float | None) -> str:
    if p is None or not math.isfinite(p):
        return "n/a"
    return f"{p:.2g}" if p >= 1e-4 else "<1e-4"
