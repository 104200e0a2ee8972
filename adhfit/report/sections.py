"""The sections of a report, from the one report.json dictionary, for one curve or a series, least squares
or MCMC: :func:`build_view` returns the :class:`~.view.View` that every writer renders.

Top to bottom: the verdict and values, warnings, results (values, offsets, model), figures, the slip
condition, the curves of a series, the Bayesian fit (MCMC only, :mod:`.sampling`), how the rows were used,
the test set-up, more results, provenance and the solver details (folded away).
"""
from __future__ import annotations

import datetime as _dt
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from . import curves as _curves
from .sampling import convergence_note, mcmc_section, probabilities
from .view import (OFFSET_SENTENCE, Bullets, Figure, Note, Section, Table, View, display, estimate_text, fmt,
                   interval_text, scene_value, seed_text, status_text)

__all__ = ["build_view", "FIGURE_CAPTIONS", "KNOWN_KEYS"]

#: top-level report keys shown in their own sections (anything else goes to "More results")
KNOWN_KEYS = {"method", "slip", "parameters", "offsets", "fits", "correlation_work_of_adhesion_mu_h", "n_points",
              "n_excluded", "excluded", "sigma", "sigma_source", "segments", "warnings", "model_evaluations",
              "histories", "wall_time_s", "provenance", "model", "observables", "diagnostics", "mcmc", "seed",
              "converged", "model_probabilities", "engine_startup_s", "curves"}
METHODS = {"lsq": "least squares (lmfit)", "mcmc": "Bayesian, MCMC (emcee)"}
_STATUS = {"determined": "determined", "lower_bound": "lower bound only", "upper_bound": "upper bound only",
           "undetermined": "not determined", "fixed": "fixed"}
FIGURE_CAPTIONS = {
    "fit.png": "Data, both fitted curves, residuals; fitted values with 95 % intervals in the box",
    "fit.png series": "Every curve (dots) with the shared fit (lines); below, each curve's residuals in units of "
                      "its own noise σ (dashed: ±3), and the contact radius when it was fitted",
    "fit_mcmc.png": "Posterior-predictive band: the model's median and 95 % bands over the data",
    "corner.png": "Posterior of the reported slip condition (red: the least-squares optimum)"}
_ESTIMATE_HEADER = ("quantity", "value", "95 % interval", "std. error", "status", "unit")


def estimate_row(name: str, est: Any) -> tuple[str, ...]:
    """One row of the values table: symbol and name, value, interval, standard error, status, unit."""
    sym, plain, k, unit = display(name, est.get("unit") if isinstance(est, Mapping) else None)
    label = f"{sym}, {plain}"
    if not isinstance(est, Mapping):  # a bare SI value
        return label, fmt(None if est is None else est * k, 5), "", "", "fitted", unit
    status = status_text(est)
    value, se = est.get("value"), est.get("stderr")
    shown = fmt(None if value is None else value * k, 5) if status in ("determined", "fixed") \
        else estimate_text(name, est)
    how = _STATUS.get(status, status)
    if status == "determined" and est.get("ci_method"):
        how += f" (interval: {est['ci_method']})"
    if est.get("note"):
        how += f" ({est['note']})"
    return label, shown, interval_text(name, est, unit=False), fmt(None if se is None else se * k, 2), how, unit


def _series(d: Mapping[str, Any]) -> bool:
    return bool(d.get("curves"))


def _head(d: Mapping[str, Any]) -> tuple[str, tuple[str, ...], tuple[Any, ...]]:
    prov = d.get("provenance") or {}
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    method = METHODS.get(d.get("method"), str(d.get("method")))
    if _series(d):
        n = len(d["curves"])
        title = f"adhfit global fit: {n} curves"
        sub = (f"{n} curves of one membrane, one shared W_ad and μh, offsets per curve; {method}, one joint fit; "
               f"{seed_text(d)}; adhfit {prov.get('adhfit_version')}; generated {now}.",)
    else:
        name = Path(str(prov.get("input") or "")).name or "fit"
        title = f"adhfit fit: {name}"
        sub = (f"{method}; {seed_text(d)}; adhfit {prov.get('adhfit_version')}; generated {now}.",
               f"Input {prov.get('input')}, scene {prov.get('scene_file')}.")
    lines = [f"Slip: {(d.get('slip') or {}).get('verdict')}"]
    lines += [f"{display(k)[0]} = {estimate_text(k, v)}" for k, v in (d.get("parameters") or {}).items()
              if isinstance(v, Mapping)]
    blocks: list[Any] = [Note(tuple(lines), "verdict")]
    bad = convergence_note(d, first=True)
    if bad:
        blocks.append(bad)
    return title, sub, tuple(blocks)


def _warnings(d: Mapping[str, Any]) -> Section:
    warnings = [str(w) for w in d.get("warnings") or []]
    return Section("Warnings", (Bullets(tuple(warnings), "warn"),) if warnings else (Note(("None.",), "ok"),))


def _facts(d: Mapping[str, Any]) -> list[str]:
    facts = []
    model = d.get("model")
    if isinstance(model, Mapping):
        facts.append(f"membrane model: {model.get('membrane')}" + (f" — {model['why']}" if model.get("why") else ""))
    if d.get("observables"):
        facts.append("fitted to: " + ", ".join(str(o).replace("_", " ") for o in d["observables"])
                     + (" of every curve" if _series(d) else ""))
    if d.get("correlation_work_of_adhesion_mu_h") is not None:
        facts.append(f"W_ad–μh correlation: {fmt(d['correlation_work_of_adhesion_mu_h'], 3)}")
    fits, slip = d.get("fits") or {}, (d.get("slip") or {})
    f = fits.get(slip.get("parameters_from") or "") or {}
    if f.get("redchi") is not None and not _series(d):
        facts.append(f"reduced χ² of the reported fit: {fmt(f['redchi'], 4)} ({fmt(f.get('ndata'))} residuals, "
                     f"{fmt(f.get('nvarys'))} parameters)")
    if d.get("sigma") is not None:
        facts.append(f"force noise σ = {fmt(d['sigma'] * 1e3, 3)} mN ({d.get('sigma_source')})")
    if _series(d):
        facts += _curves.series_facts(d)
    return facts


def _results(d: Mapping[str, Any]) -> Section:
    rows = tuple(estimate_row(n, v) for n, v in (d.get("parameters") or {}).items())
    blocks: list[Any] = [Note((_how(d),), "muted"), Table(_ESTIMATE_HEADER, rows, numeric=(1, 2, 3))]
    offsets = {} if _series(d) else (d.get("offsets") or {})
    if offsets:
        blocks.append(Section("Offsets (nuisance parameters)", (
            Table(_ESTIMATE_HEADER, tuple(estimate_row(n, v) for n, v in offsets.items()), numeric=(1, 2, 3)),
            Note((OFFSET_SENTENCE,), "muted"))))
    blocks.append(Bullets(tuple(_facts(d))))
    return Section("Shared values" if _series(d) else "Results", tuple(blocks))


def _how(d: Mapping[str, Any]) -> str:
    if d.get("method") == "mcmc":
        return ("Values are posterior medians ± posterior standard deviations; 95 % intervals are posterior "
                "percentiles (credible intervals).")
    return ("Values ± standard errors (covariance); 95 % intervals from the likelihood profile where it converged, "
            "else from the covariance. The status says how far the data pin each value down.")


def _figures(d: Mapping[str, Any], figures: Sequence[str]) -> Section:
    if not figures:
        return Section("Plots", (Note(("No plot in this report.",), "warn"),))
    cap = FIGURE_CAPTIONS
    return Section("Plots", tuple(Figure(f, cap["fit.png series"] if _series(d) and f == "fit.png"
                                         else cap.get(f, f)) for f in figures))


def _slip(d: Mapping[str, Any]) -> Section:
    slip, fits = d.get("slip") or {}, d.get("fits") or {}
    probs = probabilities(d)
    rows = []
    for s, f in fits.items():
        p = f.get("parameters") or {}
        w, m = p.get("work_of_adhesion"), p.get("mu_h")
        row = [s + (" (reported)" if s == slip.get("parameters_from") else ""), fmt(f.get("chisqr"), 5),
               fmt(f.get("redchi"), 4), fmt(f.get("aic"), 6), fmt(f.get("bic"), 6),
               estimate_text("work_of_adhesion", w) if w else "n/a", estimate_text("mu_h", m) if m else "n/a"]
        rows.append(tuple(row + ([fmt(probs.get(s), 4)] if probs else [])))
    header = ("slip", "χ²", "reduced χ²", "AIC", "BIC", "W_ad", "μh") + (("probability",) if probs else ())
    dbic = slip.get("delta_bic")
    said = (f" ΔBIC = {fmt(dbic, 4)}." if dbic is not None and "ΔBIC" not in str(slip.get("explanation")) else "")
    who = "the series cannot tell" if _series(d) else "the data cannot tell"
    return Section("Slip condition" + (" (one for all curves)" if _series(d) else ""), (
        Note((f"Selected: {slip.get('selected') or 'none (' + who + ')'}. {slip.get('explanation', '')}{said}",)),
        Table(header, tuple(rows), numeric=(1, 2, 3, 4)),
        Note(("The slip condition is decided by comparing the two fits: both share data and parameter count, so "
              "ΔAIC = ΔBIC = Δ(−2 ln L); ΔBIC > 10: decisive (selected); 2–10: favoured, not selected; < 2: no "
              "preference. A single fit's χ² cannot tell." + (" With MCMC, the posterior model probabilities "
                                                              "decide (see the Bayesian fit)." if probs else ""),),
             "muted")))


def _rows(d: Mapping[str, Any]) -> Section:
    seg = d.get("segments") or {}
    facts = [f"{fmt(d.get('n_points'))} rows used, {fmt(d.get('n_excluded') or 0)} lines left out."]
    if "n_loading" in seg:
        facts.append(f"Segments by row order, never by value: loading {fmt(seg.get('n_loading'))} rows, up to row "
                     f"{fmt((seg.get('i_turn') or 0) + 1)} (the largest displacement or pressure); unloading while "
                     f"attached: {fmt(seg.get('n_attached'))} rows.")
        if seg.get("i_jump") is None:
            facts.append("No jump off the substrate was found: every unloading row is modelled as attached.")
        else:
            facts.append(f"Jump off the substrate (pull-off at the turning point) before row {fmt(seg['i_jump'] + 1)}: "
                         f"force jump {fmt((seg.get('jump') or 0) * 1e3, 3)} mN; {fmt(seg.get('n_detached'))} rows "
                         "after it are the free membrane (model force zero).")
        facts += ["Loading rows before contact (δ < 0, or p below the contact pressure) have zero model force; "
                  "unloading rows beyond the model's turning point but before the measured jump get the "
                  "turning-point force (a clamp that keeps the residual continuous).",
                  "The measured pull-off position (midway between the last attached and the first detached row, "
                  "σ = spacing/√12) is one more residual against the model's turning point."]
    if _series(d):
        facts += _curves.rows_facts(d)
    rest = {k: v for k, v in seg.items() if k not in ("i_turn", "i_jump", "jump", "n_loading", "n_attached",
                                                     "n_detached")}
    facts += [f"{k.replace('_', ' ')}: {_plain(v)}" for k, v in rest.items()]
    blocks: list[Any] = [Bullets(tuple(facts))]
    excluded = list(d.get("excluded") or [])
    if excluded:
        blocks += [Note(("Lines left out of the file:",)),
                   Table(("line", "reason"), tuple(_excluded(x) for x in excluded))]
    return Section("How the rows were used", tuple(blocks))


def _excluded(x: Any) -> tuple[str, str]:
    if isinstance(x, (list, tuple)) and len(x) == 2:
        return str(x[0]), str(x[1])
    if isinstance(x, Mapping):
        return str(x.get("line", "")), "; ".join(f"{k}: {v}" for k, v in x.items() if k != "line")
    return "", str(x)


def _plain(v: Any) -> str:
    """Any JSON value as one line of words (never raw JSON)."""
    if isinstance(v, Mapping):
        return "; ".join(f"{str(k).replace('_', ' ')}: {_plain(x)}" for k, x in v.items()) or "none"
    if isinstance(v, (list, tuple)):
        return ", ".join(_plain(x) for x in v) or "none"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return fmt(v, 6)
    return "n/a" if v is None else str(v)


def _scene(d: Mapping[str, Any]) -> Section | None:
    scene = dict((d.get("provenance") or {}).get("scene") or {})
    priors = scene.pop("priors", None)
    if not scene:
        return None
    shown = {k: v for k, v in scene.items() if v is not None or k in ("mu_h", "work_of_adhesion")}
    blocks: list[Any] = [Table(("", "value", "unit"), tuple(scene_value(k, v) for k, v in shown.items()),
                               numeric=(1,))]
    if priors:
        blocks.append(Note((f"Priors from the scene: {_plain(priors)}",)))
    return Section("Test set-up (scene)", tuple(blocks))


_PROV = {"adhfit_version": "adhfit version", "input": "input file", "input_sha256": "input SHA-256",
         "scene_file": "scene file", "method": "method", "seed": "random numbers", "options": "options",
         "backend": "engine backend"}


def _provenance(d: Mapping[str, Any]) -> Section:
    prov = {k: v for k, v in (d.get("provenance") or {}).items() if k != "scene"}
    blocks: list[Any] = []
    if _series(d):
        blocks.append(_curves.inputs_table(prov))
        prov = {k: v for k, v in prov.items() if k not in ("input", "input_sha256", "scene_file")}
    rows = []
    for k in [k for k in _PROV if k in prov] + [k for k in prov if k not in _PROV]:
        v = seed_text(d) if k == "seed" else prov[k]
        v = METHODS.get(v, v) if k == "method" else v
        rows.append((_PROV.get(k, k.replace("_", " ")), _plain(v)))
    blocks.append(Table(("", ""), tuple(rows)))
    cost = (f"{fmt(d.get('model_evaluations'))} model evaluations ({fmt(d.get('histories'))} computed histories) in "
            f"{fmt(d.get('wall_time_s'), 3)} s")
    if d.get("engine_startup_s") is not None:
        cost += f", plus {fmt(d['engine_startup_s'], 3)} s starting the engine (compiled once, then cached)"
    blocks.append(Note((cost + ".",), "muted"))
    return Section("Provenance", tuple(blocks))


def _other(d: Mapping[str, Any]) -> Section | None:
    other = {k: v for k, v in d.items() if k not in KNOWN_KEYS}
    if not other:
        return None
    return Section("More results", (Table(("", ""), tuple((k.replace("_", " "), _plain(v))
                                                          for k, v in other.items())),))


def _solver(d: Mapping[str, Any]) -> Section | None:
    diag = d.get("diagnostics")
    notes = diag if isinstance(diag, (list, tuple)) else (diag or {}).get("notes") or []
    items = tuple(_plain(x) for x in notes)
    rows = tuple((s, "yes" if f.get("success", True) else "NO", str(f.get("message", "")),
                  fmt(f.get("model_evaluations")), fmt(f.get("histories")),
                  "; ".join(str(w) for w in f.get("warnings") or []) or "none")
                 for s, f in (d.get("fits") or {}).items() if isinstance(f, Mapping))
    blocks = ((Bullets(items),) if items else ()) + ((Table(
        ("slip", "converged", "optimiser message", "model evaluations", "histories", "notes"), rows,
        numeric=(3, 4)),) if rows else ())
    if not blocks:
        return None
    n = len(items)
    return Section("Solver details", blocks, folded=f"What the solver did{f' ({n} notes)' if n else ''} — for "
                                                    "checking, not needed to read the results")


def build_view(d: Mapping[str, Any], figures: Sequence[str] = ()) -> View:
    """The whole report of one report.json dictionary ``d``, for one curve or a series, any method.

    Parameters
    ----------
    d : mapping
        The report.json dictionary (:func:`adhfit.report.json_report.report_dict`).
    figures : sequence of str
        The figure files written next to the report (``fit.png``, ``fit_mcmc.png``, ``corner.png``).

    Returns
    -------
    View
    """
    title, sub, head = _head(d)
    parts = [Section("", head), _warnings(d), _results(d), _figures(d, figures), _slip(d),
             _curves.curves_section(d) if _series(d) else None, mcmc_section(d), _rows(d), _scene(d), _other(d),
             _provenance(d), _solver(d),
             Section("", (Note(("Values are in the unit of their column. The fit rests on the membrane model named "
                                "above; λ0 cannot be identified from force curves under the large-stretch model.",),
                               "muted"),))]
    return View(title, sub, tuple(p for p in parts if p is not None))
