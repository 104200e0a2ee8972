"""report.html: one self-contained page per fit, to read in a browser or mail to a colleague.

Everything is inside the file: the plots as base64 PNG, the tables, the warnings and the provenance
(adhfit version, input file and its SHA-256, scene, seed, method).  No external CSS, JavaScript,
fonts or images; every piece of text from the data, the scene or the fit is HTML-escaped; every
number carries its unit; nested results are tables, never raw JSON.

The page is rendered from the report.json dictionary (:func:`adhfit.report.json_report.report_dict`),
so it can also be re-rendered later from a saved report.json::

    import json
    from adhfit.report.html import render_html
    page = render_html(json.load(open("out/report.json")), images={"fit": "out/fit.png"})

Keys it does not know (e.g. those another method adds) are shown in a "More results" table, never
dropped.
"""
from __future__ import annotations

import datetime as _dt
from pathlib import Path
from typing import Any, Mapping

from .html_mcmc import section_mcmc, section_solver_details
from .html_parts import e, figure, num, page, table, value_html
from .text import display, estimate_text, interval_text, scene_value, seed_text, status_text

__all__ = ["render_html", "write_html", "fit_summary_html"]

#: top-level report keys this page shows in their own sections
_KNOWN = {"method", "slip", "parameters", "offsets", "fits", "correlation_work_of_adhesion_mu_h",
          "n_points", "n_excluded", "excluded", "sigma", "sigma_source", "segments", "warnings",
          "model_evaluations", "histories", "wall_time_s", "provenance", "model", "observables",
          "diagnostics", "mcmc", "seed", "converged", "model_probabilities", "engine_startup_s"}
_METHOD = {"lsq": "least squares (lmfit)", "mcmc": "Bayesian, MCMC (emcee)"}
_STATUS = {"determined": "determined", "lower_bound": "lower bound only", "upper_bound": "upper bound only",
           "undetermined": "not determined"}


def _estimate_row(name: str, est: Any) -> list[str]:
    sym, plain, k, unit = display(name, est.get("unit") if isinstance(est, Mapping) else None)
    label = f"<b>{e(sym)}</b> <span class=\"muted\">{e(plain)}</span>"
    if not isinstance(est, Mapping):  # a bare SI value (offsets)
        return [label, num(None if est is None else est * k, 5), "", "", "fitted", e(unit)]
    status = status_text(est)
    value = est.get("value")
    se = est.get("stderr")
    shown = num(None if value is None else value * k, 5) if status == "determined" else e(estimate_text(name, est))
    how = _STATUS.get(status, status)
    if status == "determined" and est.get("ci_method"):
        how += f" <span class=\"muted\">(interval: {e(est['ci_method'])})</span>"
    return [label, shown, e(interval_text(name, est, unit=False)),
            num(None if se is None else se * k, 2), f"<span class=\"status-{e(status)}\">{how}</span>", e(unit)]


def _section_estimates(d: Mapping[str, Any]) -> str:
    rows = [_estimate_row(n, v) for n, v in (d.get("parameters") or {}).items()]
    out = ["<h2>Results</h2>",
           table(["quantity", "value", "95 % interval", "std. error", "status", "unit"], rows, numeric=(1, 2, 3))]
    offsets = d.get("offsets") or {}
    if offsets:
        out += ["<h3>Offsets (nuisance parameters, added to the measured values)</h3>",
                table(["quantity", "value", "95 % interval", "std. error", "status", "unit"],
                      [_estimate_row(n, v) for n, v in offsets.items()], numeric=(1, 2, 3))]
    facts = []
    model = d.get("model")
    if isinstance(model, Mapping):
        facts.append(f"membrane model: <b>{e(model.get('membrane'))}</b>"
                     + (f" — {e(model['why'])}" if model.get("why") else ""))
    if d.get("observables"):
        facts.append("fitted to: " + ", ".join(e(str(o).replace("_", " ")) for o in d["observables"]))
    if d.get("correlation_work_of_adhesion_mu_h") is not None:
        facts.append(f"W_ad–μh correlation: {num(d['correlation_work_of_adhesion_mu_h'], 3)}")
    if d.get("sigma") is not None:
        facts.append(f"force noise σ = {num(d['sigma'] * 1e3, 3)} mN "
                     f"<span class=\"muted\">({e(d.get('sigma_source'))})</span>")
    out.append("<ul>" + "".join(f"<li>{f}</li>" for f in facts) + "</ul>")
    return "\n".join(out)


def _section_slip(d: Mapping[str, Any]) -> str:
    slip, fits = d.get("slip") or {}, d.get("fits") or {}
    rows = []
    for s, f in fits.items():
        p = f.get("parameters") or {}
        w, m = (p.get("work_of_adhesion") or {}), (p.get("mu_h") or {})
        rows.append([e(s) + (" <b>(reported)</b>" if s == slip.get("parameters_from") else ""),
                     num(f.get("redchi"), 4), num(f.get("aic"), 6), num(f.get("bic"), 6),
                     e(estimate_text("work_of_adhesion", w)) if w else "n/a",
                     e(estimate_text("mu_h", m)) if m else "n/a"])
    dbic = slip.get("delta_bic")
    return "\n".join([
        "<h2>Slip condition</h2>",
        f"<p>Selected: <b>{e(slip.get('selected') or 'none (the data cannot tell)')}</b>. "
        f"{e(slip.get('explanation', ''))}"
        + (f" ΔBIC = {num(dbic, 3)}." if dbic is not None and "ΔBIC" not in str(slip.get("explanation")) else "")
        + "</p>",
        table(["slip", "reduced χ²", "AIC", "BIC", "W_ad", "μh"], rows, numeric=(1, 2, 3)),
        "<p class=\"muted\">The slip condition is decided by comparing the two fits (ΔBIC &gt; 10: decisive; "
        "2–10: favoured, not selected; &lt; 2: no preference). A single fit's χ² cannot tell.</p>"])


def _section_warnings(d: Mapping[str, Any]) -> str:
    warnings = list(d.get("warnings") or [])
    if not warnings:
        return "<h2>Warnings</h2><p class=\"ok\">None.</p>"
    return "<h2>Warnings</h2>" + "".join(f"<div class=\"warn\">⚠ {e(w)}</div>" for w in warnings)


def _section_rows(d: Mapping[str, Any]) -> str:
    seg = d.get("segments") or {}
    facts = [f"{num(d.get('n_points'))} rows used, {num(d.get('n_excluded') or 0)} lines left out."]
    if "n_loading" in seg:
        facts.append(f"Loading: {num(seg.get('n_loading'))} rows, up to row {num((seg.get('i_turn') or 0) + 1)} "
                     "(the largest displacement or pressure).")
        facts.append(f"Unloading while attached: {num(seg.get('n_attached'))} rows.")
        if seg.get("i_jump") is None:
            facts.append("No jump off the substrate was found: every unloading row is modelled as attached.")
        else:
            facts.append(f"Jump off the substrate (pull-off at the turning point) before row "
                         f"{num(seg['i_jump'] + 1)}: force jump {num((seg.get('jump') or 0) * 1e3, 3)} mN; "
                         f"{num(seg.get('n_detached'))} rows after it are the free membrane (force zero).")
    known = {"i_turn", "i_jump", "jump", "n_loading", "n_attached", "n_detached"}
    rest = {k: v for k, v in seg.items() if k not in known}
    out = ["<h2>How the rows were used</h2>", "<ul>" + "".join(f"<li>{e(f)}</li>" for f in facts) + "</ul>"]
    if rest:
        out.append(value_html(rest))
    excluded = list(d.get("excluded") or [])
    if excluded:
        out += ["<p>Lines left out of the file:</p>", value_html(excluded) if isinstance(excluded[0], Mapping)
                else table(["line", "reason"], [_excluded_row(x) for x in excluded])]
    return "\n".join(out)


def _excluded_row(x: Any) -> list[str]:
    if isinstance(x, (list, tuple)) and len(x) == 2:
        return [e(x[0]), e(x[1])]
    return ["", e(x)]


def _section_scene(d: Mapping[str, Any]) -> str:
    scene = dict((d.get("provenance") or {}).get("scene") or {})
    priors = scene.pop("priors", None)
    if not scene:
        return ""
    shown = {k: v for k, v in scene.items() if v is not None or k in ("mu_h", "work_of_adhesion")}
    rows = [[e(lbl), e(val), e(unit)] for lbl, val, unit in (scene_value(k, v) for k, v in shown.items())]
    out = ["<h2>Test set-up (scene)</h2>", table(["", "value", "unit"], rows, numeric=(1,))]
    if priors:
        out.append("<p>Priors from the scene:</p>" + value_html(priors))
    return "\n".join(out)


def _section_provenance(d: Mapping[str, Any]) -> str:
    prov = {k: v for k, v in (d.get("provenance") or {}).items() if k != "scene"}
    labels = {"adhfit_version": "adhfit version", "input": "input file", "input_sha256": "input SHA-256",
              "scene_file": "scene file", "method": "method", "seed": "random numbers", "options": "options",
              "backend": "engine backend"}
    rows = []
    for k in [k for k in labels if k in prov] + [k for k in prov if k not in labels]:
        v = seed_text(d) if k == "seed" else prov[k]
        v = _METHOD.get(v, v) if k == "method" else v
        cell = f"<code>{e(v)}</code>" if k in ("input", "input_sha256", "scene_file") else value_html(v)
        rows.append([e(labels.get(k, k.replace("_", " "))), cell])
    t = d.get("wall_time_s")
    cost = (f"{num(d.get('model_evaluations'))} model evaluations ({num(d.get('histories'))} computed "
            f"histories) in {num(t, 3)} s")
    if d.get("engine_startup_s") is not None:
        cost += f", plus {num(d['engine_startup_s'], 3)} s starting the engine (compiled once, then cached)"
    return "\n".join(["<h2>Provenance</h2>", table([], rows), f"<p class=\"muted\">{e(cost)}.</p>"])


def _section_other(d: Mapping[str, Any]) -> str:
    other = {k: v for k, v in d.items() if k not in _KNOWN}
    if not other:
        return ""
    return "<h2>More results</h2>" + table(["", ""], [[e(k.replace("_", " ")), value_html(v)]
                                                      for k, v in other.items()])


def _fit_figure(result) -> bytes | None:
    """The fit plot of a FitResult as PNG bytes (None if it cannot be drawn)."""
    try:
        import io  # noqa: PLC0415
        from .fit_plot import plot_fit  # noqa: PLC0415
        buf = io.BytesIO()
        plot_fit(result, path=buf)
    except Exception:  # noqa: BLE001 - a report without its plot beats no report; the page says so
        return None
    return buf.getvalue()


_CAPTIONS = {"fit.png": "Data, both fitted curves, residuals; fitted values with 95 % intervals in the box",
             "fit_mcmc.png": "Posterior-predictive band: the model's median and 95 % bands over the data",
             "corner.png": "Posterior of the reported slip condition (red: the least-squares optimum)"}


def _head(d: Mapping[str, Any], title: str) -> str:
    prov = d.get("provenance") or {}
    slip = d.get("slip") or {}
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = [f"{e(k)}: <b>{e(estimate_text(k, v))}</b>" for k, v in (d.get("parameters") or {}).items()
             if isinstance(v, Mapping)]
    return (f"<h1>{e(title)}</h1><p class=\"muted\">{e(_METHOD.get(d.get('method'), d.get('method')))}; "
            f"{e(seed_text(d))}; adhfit {e(prov.get('adhfit_version'))}; generated {now}.<br>Input "
            f"<code>{e(prov.get('input'))}</code>, scene <code>{e(prov.get('scene_file'))}</code>.</p>"
            f"<p class=\"verdict\">Slip: <b>{e(slip.get('verdict'))}</b><br>" + "<br>".join(
                lines).replace("work_of_adhesion:", "W_ad =").replace("mu_h:", "μh =") + "</p>"
            + ("<p class=\"bad\"><b>The MCMC run has not converged</b>: do not trust these values and intervals "
               "(see the convergence diagnostics below).</p>" if d.get("method") == "mcmc"
               and d.get("converged", (d.get("mcmc") or {}).get("converged")) is False else ""))


def render_html(result: Any, *, images: Mapping[str, Any] | None = None, title: str | None = None,
                extra: Mapping[str, Any] | None = None) -> str:
    """The report of one fit as a self-contained HTML page.

    Parameters
    ----------
    result : FitResult or dict
        A :class:`~adhfit.fitting.result.FitResult`, or its report.json dictionary.
    images : mapping title -> PNG, optional
        Plots to embed (PNG bytes, a path to a PNG file, or a matplotlib Figure).  Default: the fit plot
        drawn from a FitResult; none for a dictionary.
    title : str, optional
        Page title; default: "adhfit fit: <input file name>".
    extra : mapping, optional
        More report keys (e.g. ``engine_startup_s``).

    Returns
    -------
    str
        The page (UTF-8 text; no external resources).
    """
    if isinstance(result, Mapping):
        d = dict(result)
        images = {} if images is None else images
    else:
        from .json_report import report_dict  # noqa: PLC0415
        d = report_dict(result)
        if images is None:
            png = _fit_figure(result)
            images = {"fit.png": png} if png else {}
    d.update(extra or {})
    name = Path(str((d.get("provenance") or {}).get("input", "") or "")).name or "fit"
    title = title or f"adhfit fit: {name}"
    figs = "".join(figure(t, img, _CAPTIONS.get(str(t), str(t))) for t, img in (images or {}).items())
    body = [_head(d, title), _section_warnings(d), _section_estimates(d), "<h2>Plots</h2>",
            figs or "<p class=\"warn\">No plot in this report.</p>", _section_slip(d), section_mcmc(d),
            _section_rows(d), _section_scene(d), _section_other(d), _section_provenance(d),
            section_solver_details(d),
            "<p class=\"muted\">Values are in the unit of their column. The fit rests on the membrane model "
            "named above; λ0 cannot be identified from force curves under the large-stretch model.</p>"]
    return page(title, body)


def write_html(result: Any, path: str | Path, *, images: Mapping[str, Any] | None = None,
               extra: Mapping[str, Any] | None = None) -> Path:
    """Write :func:`render_html` to ``path`` (UTF-8); returns the path."""
    path = Path(path)
    path.write_text(render_html(result, images=images, extra=extra), encoding="utf-8")
    return path


def fit_summary_html(d: Mapping[str, Any]) -> str:
    """A compact HTML block of a fit (for notebooks: ``FitResult._repr_html_``): verdict, results table,
    warnings."""
    rows = [_estimate_row(n, v) for n, v in {**(d.get("parameters") or {}), **(d.get("offsets") or {})}.items()]
    warn = "".join(f"<div class=\"warn\">⚠ {e(w)}</div>" for w in d.get("warnings") or [])
    return (f"<div><b>adhfit fit</b> ({e(_METHOD.get(d.get('method'), d.get('method')))}; "
            f"{e(seed_text(d))}) — slip: <b>{e((d.get('slip') or {}).get('verdict'))}</b>"
            + table(["quantity", "value", "95 % interval", "std. error", "status", "unit"], rows, numeric=(1, 2, 3))
            + warn + "</div>")
