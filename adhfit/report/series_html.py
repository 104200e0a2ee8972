"""report.html of a global (series) fit: one self-contained page, like the single-curve report.

What a person looks for first: the shared W_ad and μh with their intervals and status, the slip
verdict, then whether every curve agrees (a per-curve table: its scene, its own χ², its pull on the
shared values, its flags, what it contributes) and the figure with every curve, the shared fit and
its residuals.  Rendered from the report.json dictionary; the figure is embedded as base64 PNG.
"""
from __future__ import annotations

import datetime as _dt
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .html import _estimate_row, _section_other, _section_warnings
from .html_mcmc import section_mcmc, section_solver_details
from .html_parts import e, figure, num, page, table, value_html
from .series_text import (
    CURVE_HEADER,
    SLIP_HEADER,
    curve_label,
    curve_legend,
    curve_rows,
    slip_rows,
    width_comparison,
)
from .text import display, estimate_text, seed_text

__all__ = ["render_series_html", "write_series_html"]

_METHOD = {"lsq": "least squares (lmfit), one joint fit", "mcmc": "Bayesian, MCMC (emcee) on the joint posterior"}
_KNOWN = {"method", "slip", "parameters", "offsets", "fits", "correlation_work_of_adhesion_mu_h", "n_points",
          "n_excluded", "excluded", "sigma", "sigma_source", "segments", "warnings", "model_evaluations",
          "histories", "wall_time_s", "provenance", "model", "observables", "diagnostics", "mcmc", "seed",
          "converged", "model_probabilities", "engine_startup_s", "curves"}


def _head(d: Mapping[str, Any], title: str) -> str:
    prov = d.get("provenance") or {}
    slip = d.get("slip") or {}
    now = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    names = {"work_of_adhesion": "W_ad", "mu_h": "μh"}
    lines = [f"{names.get(k, k)} = <b>{e(estimate_text(k, v))}</b>"
             + f" <span class=\"status-{e(v.get('status'))}\">({e(str(v.get('status')).replace('_', ' '))})</span>"
             for k, v in (d.get("parameters") or {}).items() if isinstance(v, Mapping)]
    n = len(d.get("curves") or [])
    bad = d.get("method") == "mcmc" and d.get("converged", (d.get("mcmc") or {}).get("converged")) is False
    return (f"<h1>{e(title)}</h1><p class=\"muted\">{n} curves of one membrane, one shared W_ad and μh, offsets "
            f"per curve; {e(_METHOD.get(d.get('method'), d.get('method')))}; {e(seed_text(d))}; adhfit "
            f"{e(prov.get('adhfit_version'))}; generated {now}.</p>"
            f"<p class=\"verdict\">Slip: <b>{e(slip.get('verdict'))}</b><br>" + "<br>".join(lines) + "</p>"
            + ("<p class=\"bad\"><b>The MCMC run has not converged</b>: do not trust these values and intervals "
               "(see the convergence diagnostics below).</p>" if bad else ""))


def _section_shared(d: Mapping[str, Any]) -> str:
    rows = [_estimate_row(n, v) for n, v in (d.get("parameters") or {}).items()]
    facts = []
    if d.get("observables"):
        facts.append("fitted to: " + ", ".join(e(str(o).replace("_", " ")) for o in d["observables"])
                     + " of every curve")
    if d.get("correlation_work_of_adhesion_mu_h") is not None:
        facts.append(f"W_ad–μh correlation: {num(d['correlation_work_of_adhesion_mu_h'], 3)}")
    width = width_comparison(d)
    if width:
        facts.append(e(width))
    given = ((d.get("provenance") or {}).get("options") or {}).get("sigma") is not None
    facts.append("noise: one σ per curve and observable, " + ("given" if given else "estimated from each curve's "
                 "residuals") + " (the force noise of each curve is in the Curves table)")
    return "\n".join(["<h2>Shared values</h2>",
                      table(["quantity", "value", "95 % interval", "std. error", "status", "unit"], rows,
                            numeric=(1, 2, 3)),
                      "<ul>" + "".join(f"<li>{f}</li>" for f in facts) + "</ul>"])


def _section_slip(d: Mapping[str, Any]) -> str:
    slip = d.get("slip") or {}
    body = [[e(c) for c in r] for r in slip_rows(d)]
    how = ("posterior model probabilities of the joint fit (equal prior odds; selected at ≥ 0.95)"
           if d.get("method") == "mcmc" else
           "ΔBIC of the joint fits (> 10: decisive; 2–10: favoured, not selected; < 2: no preference)")
    dbic = slip.get("delta_bic")
    return "\n".join([
        "<h2>Slip condition (one for all curves)</h2>",
        f"<p>Selected: <b>{e(slip.get('selected') or 'none (the series cannot tell)')}</b>. "
        f"{e(slip.get('explanation', ''))}"
        + (f" ΔBIC of the joint least-squares fits = {num(dbic, 4)}." if dbic is not None
           and "ΔBIC" not in str(slip.get("explanation")) else "") + "</p>",
        table(SLIP_HEADER[:len(body[0])] if body else SLIP_HEADER, body, numeric=(1, 2, 5)),
        f"<p class=\"muted\">Decided by the {e(how)}; every curve is fitted under the same condition.</p>"])


def _section_curves(d: Mapping[str, Any]) -> str:
    rows = []
    for r, c in zip(curve_rows(d), d.get("curves") or []):
        cells = [e(x) for x in r]
        cells[1] = f"{cells[1]}<br><span class=\"muted\" style=\"white-space:nowrap\">{cells.pop(2)}</span>"
        if c.get("flags"):
            cells[-1] = f"<b class=\"status-failed\">{cells[-1]}</b>"
        rows.append(cells)
    flagged = [c for c in d.get("curves") or [] if c.get("flags")]
    head = ("<p class=\"ok\">Every curve agrees with the shared fit.</p>" if not flagged else
            f"<p class=\"bad\"><b>{len(flagged)} curve(s) flagged</b>: "
            + ", ".join(e(curve_label(c.get('file'))) for c in flagged) + ". See the warnings.</p>")
    return "\n".join(["<h2>Curves</h2>", head, table(["#", "curve, scene", *CURVE_HEADER[3:]], rows, numeric=tuple(range(2, 11))),
                      "<ul class=\"muted\">" + "".join(f"<li>{e(x)}</li>" for x in curve_legend()) + "</ul>",
                      _offsets_table(d), _radius_table(d)])


def _offsets_table(d: Mapping[str, Any]) -> str:
    rows, names = [], []
    for k, c in enumerate(d.get("curves") or []):
        offs = c.get("offsets") or {}
        names = list(dict.fromkeys([*names, *offs]))
        rows.append((k, offs))
    if not names:
        return ""
    head = [e(f"{display(n)[0]} ({display(n)[1]})") for n in names]
    body = []
    for k, offs in rows:
        cells = [str(k + 1)]
        for n in names:
            o = offs.get(n)
            cells.append("n/a" if not isinstance(o, Mapping) else
                         e(estimate_text(n, o)) if o.get("note") is None else e(o["note"]))
        body.append(cells)
    return ("<h3>Offsets per curve (added to the measured values)</h3>"
            + table(["#"] + head, body, numeric=(0,)))


def _radius_table(d: Mapping[str, Any]) -> str:
    body = []
    for k, c in enumerate(d.get("curves") or []):
        cr = c.get("contact_radius")
        if not cr:
            continue
        body.append([str(k + 1), num(cr.get("n_used")), num(cr.get("n_zero_not_in_contact")), num(cr.get("n_missing")),
                     num((cr.get("sigma") or 0) * 1e6, 3), num(cr.get("redchi"), 3)])
    if not body:
        return ""
    return ("<h3>Contact radius</h3>"
            + table(["#", "rows used", "of them 0 (not in contact)", "rows missing (skipped)", "noise σ_a (µm)",
                     "χ²/n"], body, numeric=(0, 1, 2, 3, 4, 5)))


def _section_provenance(d: Mapping[str, Any]) -> str:
    prov = d.get("provenance") or {}
    files = prov.get("input") or []
    shas = prov.get("input_sha256") or [None] * len(files)
    scenes = prov.get("scene_file") or [None] * len(files)
    body = [[str(k + 1), f"<code>{e(f)}</code>", f"<code>{e(s)}</code>", f"<code>{e(sc)}</code>"]
            for k, (f, s, sc) in enumerate(zip(files, shas, scenes))]
    rest = {k: v for k, v in prov.items() if k not in ("input", "input_sha256", "scene_file", "scene")}
    rest["seed"] = seed_text(d)
    rest["method"] = _METHOD.get(rest.get("method"), rest.get("method"))
    cost = (f"{num(d.get('model_evaluations'))} model evaluations ({num(d.get('histories'))} computed histories) "
            f"in {num(d.get('wall_time_s'), 3)} s")
    return "\n".join(["<h2>Provenance</h2>", table(["#", "input file", "SHA-256", "scene file"], body),
                      table([], [[e(k.replace("_", " ")), value_html(v)] for k, v in rest.items()]),
                      f"<p class=\"muted\">{e(cost)}.</p>"])


def render_series_html(d: Mapping[str, Any], *, images: Mapping[str, Any] | None = None,
                       title: str | None = None) -> str:
    """The report of a global fit as a self-contained HTML page.

    Parameters
    ----------
    d : mapping
        The report.json dictionary (``FitResult.as_dict()`` with ``curves``).
    images : mapping caption -> PNG, optional
        Figures to embed (bytes, a PNG path or a matplotlib Figure).
    title : str, optional

    Returns
    -------
    str
    """
    n = len(d.get("curves") or [])
    title = title or f"adhfit global fit: {n} curves"
    figs = "".join(figure(str(t), img, str(t)) for t, img in (images or {}).items())
    body = [_head(d, title), _section_warnings(d), _section_shared(d), _section_slip(d), "<h2>Figure</h2>",
            figs or "<p class=\"warn\">No figure in this report.</p>", _section_curves(d), section_mcmc(d),
            _section_other({k: v for k, v in d.items() if k not in _KNOWN}), _section_provenance(d),
            section_solver_details(d)]
    return page(title, ["<style>body{max-width:78em}</style>", *body])  # the curves table is wide


def write_series_html(result, path: str | Path, *, images: Mapping[str, Any] | None = None) -> Path:
    """Write the page of ``result`` (a FitResult with ``curves`` or its dictionary) to ``path``."""
    d = result if isinstance(result, Mapping) else result.as_dict()
    path = Path(path)
    path.write_text(render_series_html(d, images=images), encoding="utf-8")
    return path
