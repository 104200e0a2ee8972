"""report.html: one self-contained page per fit, to read in a browser or mail to a colleague.

Everything is inside the file: the plots as base64 PNG, the tables, the warnings and the provenance
(adhfit version, input file and its SHA-256, scene, seed, method).  No external CSS, JavaScript,
fonts or images; every piece of text from the data, the scene or the fit is HTML-escaped.

The page is rendered from the report.json dictionary (:func:`adhfit.report.json_report.report_dict`),
so it can also be re-rendered later from a saved report.json::

    import json
    from adhfit.report.html import render_html
    page = render_html(json.load(open("out/report.json")), images={"fit": "out/fit.png"})

Keys it does not know (e.g. those another method adds) are shown in a generic table, never dropped.
"""
from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import json
from pathlib import Path
from typing import Any, Mapping

__all__ = ["render_html", "write_html"]

#: display factor and unit per parameter (SI in the report dict)
_UNITS = {"work_of_adhesion": (1.0, "J/m²", "W_ad"), "mu_h": (1.0, "N/m", "μh"),
          "displacement_offset": (1e6, "µm", "δ_0"), "pressure_offset": (1.0, "Pa", "P_0"),
          "force_offset": (1e3, "mN", "F_0")}
#: top-level report keys this page shows in their own sections
_KNOWN = {"method", "slip", "parameters", "offsets", "fits", "correlation_work_of_adhesion_mu_h",
          "n_points", "n_excluded", "excluded", "sigma", "sigma_source", "segments", "warnings",
          "model_evaluations", "histories", "wall_time_s", "provenance"}

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;max-width:60em;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;border-bottom:1px solid #ccc;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0;font-size:.92em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:left;vertical-align:top}
th{background:#f3f3f3}td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.verdict{font-size:1.1em;padding:.5em .8em;background:#eef5ff;border-left:4px solid #1f77b4}
.warn{background:#fff6e0;border-left:4px solid #e69500;padding:.4em .8em;margin:.3em 0}
.ok{background:#eefaf0;border-left:4px solid #2ca02c;padding:.4em .8em}
.muted{color:#666;font-size:.88em}code,.mono{font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.9em;
word-break:break-all}img{max-width:100%;height:auto;border:1px solid #ddd}
"""


def _e(x: Any) -> str:
    """Escape any value as HTML text."""
    return html.escape("" if x is None else str(x), quote=True)


def _num(x: Any, digits: int = 5) -> str:
    if x is None:
        return "n/a"
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return _e(x)
    return _e(f"{x:.{digits}g}")


def _table(header: list[str], rows: list[list[str]], numeric_from: int = 1) -> str:
    """A table; cells must already be escaped; columns from ``numeric_from`` on align right."""
    head = "".join(f"<th>{h}</th>" for h in header)
    body = "".join("<tr>" + "".join(
        f"<td class=\"num\">{c}</td>" if j >= numeric_from else f"<td>{c}</td>" for j, c in enumerate(r))
        + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _estimate_rows(params: Mapping[str, Any]) -> list[list[str]]:
    rows = []
    for name, e in params.items():
        k, unit, sym = _UNITS.get(name, (1.0, e.get("unit", ""), name))
        scale = (lambda v: None if v is None else v * k)
        ci = e.get("ci95")
        ci_txt = "n/a" if not ci or None in ci else f"[{_num(scale(ci[0]))}, {_num(scale(ci[1]))}]"
        rows.append([f"{_e(sym)} <span class=\"muted\">({_e(name)})</span>", _num(scale(e.get("value"))),
                     _num(scale(e.get("stderr")), 2), ci_txt, _e(e.get("ci_method") or "none"), _e(unit)])
    return rows


def _section_estimates(d: Mapping[str, Any]) -> str:
    params = dict(d.get("parameters", {}))
    params.update(d.get("offsets", {}) or {})
    out = ["<h2>Estimates</h2>",
           _table(["parameter", "value", "std. error", "95 % interval", "interval from", "unit"],
                  _estimate_rows(params))]
    facts = [("W_ad–μh correlation", _num(d.get("correlation_work_of_adhesion_mu_h"), 3)),
             ("force noise σ", f"{_num(None if d.get('sigma') is None else d['sigma'] * 1e3, 4)} mN "
                               f"<span class=\"muted\">({_e(d.get('sigma_source'))})</span>"),
             ("rows used", _e(d.get("n_points"))), ("lines left out", _e(d.get("n_excluded")))]
    out.append("<ul>" + "".join(f"<li>{k}: {v}</li>" for k, v in facts) + "</ul>")
    return "\n".join(out)


def _section_slip(d: Mapping[str, Any]) -> str:
    slip = d.get("slip", {}) or {}
    fits = d.get("fits", {}) or {}
    rows = []
    for s, f in fits.items():
        p = f.get("parameters", {})
        rows.append([_e(s) + (" <b>(reported)</b>" if s == slip.get("parameters_from") else ""),
                     _num(f.get("chisqr")), _num(f.get("redchi"), 4), _num(f.get("aic")), _num(f.get("bic")),
                     _num(p.get("work_of_adhesion", {}).get("value")), _num(p.get("mu_h", {}).get("value")),
                     _e("yes" if f.get("success", True) else "no")])
    return "\n".join([
        "<h2>Slip condition</h2>",
        f"<p>Selected: <b>{_e(slip.get('selected') or 'none (undecided)')}</b>. {_e(slip.get('explanation', ''))}"
        f" ΔBIC = {_num(slip.get('delta_bic'), 4)}, ΔAIC = {_num(slip.get('delta_aic'), 4)}.</p>",
        _table(["slip", "χ²", "reduced χ²", "AIC", "BIC", "W_ad (J/m²)", "μh (N/m)", "converged"], rows),
        "<p class=\"muted\">The slip condition is decided by comparing the two fits (ΔBIC &gt; 10: decisive; "
        "2–10: favoured, not selected; &lt; 2: no preference). A single fit's χ² cannot tell.</p>"])


def _section_warnings(d: Mapping[str, Any]) -> str:
    warnings = list(d.get("warnings", []) or [])
    if not warnings:
        return "<h2>Warnings</h2><p class=\"ok\">None.</p>"
    return "<h2>Warnings</h2>" + "".join(f"<div class=\"warn\">⚠ {_e(w)}</div>" for w in warnings)


def _section_data(d: Mapping[str, Any]) -> str:
    seg = d.get("segments", {}) or {}
    rows = [[_e(k), _e(json.dumps(v, ensure_ascii=False)) if isinstance(v, (dict, list)) else _num(v, 6)]
            for k, v in seg.items()]
    out = ["<h2>How the rows were used</h2>",
           "<p>Segments by row order (loading up to the largest control value, unloading while attached, "
           "after the detachment jump):</p>", _table(["segment key", "value"], rows)]
    excluded = list(d.get("excluded", []) or [])
    if excluded:
        out.append("<p>Lines left out of the file:</p>")
        out.append(_table(["line / reason"], [[_e(x)] for x in excluded], numeric_from=9))
    return "\n".join(out)


def _flat(value: Any) -> str:
    if isinstance(value, (dict, list, tuple)):
        return f"<span class=\"mono\">{_e(json.dumps(value, ensure_ascii=False, default=str))}</span>"
    if isinstance(value, float):
        return _num(value, 8)
    return _e(value)


def _section_provenance(d: Mapping[str, Any]) -> str:
    prov = dict(d.get("provenance", {}) or {})
    scene = prov.pop("scene", None) or {}
    first = ("adhfit_version", "input", "input_sha256", "scene_file", "method", "seed")
    keys = [k for k in first if k in prov] + [k for k in prov if k not in first]
    rows = [[_e(k), f"<span class=\"mono\">{_flat(prov[k])}</span>"] for k in keys]
    out = ["<h2>Provenance</h2>", _table(["", ""], rows, numeric_from=9)]
    if scene:
        out += ["<p>Scene (SI):</p>", _table(["field", "value"], [[_e(k), _flat(v)] for k, v in scene.items()],
                                             numeric_from=9)]
    cost = (f"{_e(d.get('model_evaluations'))} model evaluations ({_e(d.get('histories'))} computed histories) "
            f"in {_num(d.get('wall_time_s'), 3)} s.")
    out.append(f"<p class=\"muted\">{cost}</p>")
    return "\n".join(out)


def _section_other(d: Mapping[str, Any]) -> str:
    other = {k: v for k, v in d.items() if k not in _KNOWN}
    if not other:
        return ""
    rows = [[_e(k), _flat(v)] for k, v in other.items()]
    return "<h2>More results</h2>" + _table(["key", "value"], rows, numeric_from=9)


def _png_bytes(image: Any) -> bytes:
    if isinstance(image, (bytes, bytearray)):
        return bytes(image)
    if hasattr(image, "savefig"):  # a matplotlib Figure
        buf = io.BytesIO()
        image.savefig(buf, format="png", dpi=110)
        return buf.getvalue()
    return Path(image).read_bytes()


def _section_images(images: Mapping[str, Any]) -> str:
    out = []
    for title, image in images.items():
        data = base64.b64encode(_png_bytes(image)).decode("ascii")
        out.append(f"<figure><img alt=\"{_e(title)}\" src=\"data:image/png;base64,{data}\">"
                   f"<figcaption class=\"muted\">{_e(title)}</figcaption></figure>")
    return "\n".join(out)


def _fit_figure(result) -> bytes | None:
    """The fit plot of a FitResult as PNG bytes (None if it cannot be drawn)."""
    try:
        from .fit_plot import plot_fit  # noqa: PLC0415
        ax = plot_fit(result)
    except Exception:  # noqa: BLE001 - a report without its plot beats no report; the page says so
        return None
    fig = ax.figure
    png = _png_bytes(fig)
    import matplotlib.pyplot as plt  # noqa: PLC0415
    plt.close(fig)
    return png


def render_html(result: Any, *, images: Mapping[str, Any] | None = None, title: str | None = None) -> str:
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

    Returns
    -------
    str
        The page (UTF-8 text; no external resources).
    """
    if isinstance(result, Mapping):
        d = dict(result)
        if images is None:
            images = {}
    else:
        from .json_report import report_dict  # noqa: PLC0415
        d = report_dict(result)
        if images is None:
            png = _fit_figure(result)
            images = {"Data, both fitted curves and residuals": png} if png else {}
    prov = d.get("provenance", {}) or {}
    name = Path(str(prov.get("input", "") or "")).name or "fit"
    title = title or f"adhfit fit: {name}"
    slip = d.get("slip", {}) or {}
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    head = (f"<h1>{_e(title)}</h1><p class=\"muted\">Method {_e(d.get('method'))}, adhfit "
            f"{_e(prov.get('adhfit_version'))}, input <code>{_e(prov.get('input'))}</code> (SHA-256 "
            f"<code>{_e(prov.get('input_sha256'))}</code>), seed {_e(prov.get('seed'))}; generated {now}.</p>"
            f"<p class=\"verdict\">Slip: <b>{_e(slip.get('verdict'))}</b></p>")
    figs = _section_images(images) if images else "<p class=\"warn\">No plot in this report.</p>"
    body = [head, _section_estimates(d), "<h2>Plots</h2>", figs, _section_slip(d), _section_warnings(d),
            _section_data(d), _section_other(d), _section_provenance(d),
            "<p class=\"muted\">The model rests on the large-stretch approximation of the membrane (paper eq. 10), "
            "validated at λ0 = 2; λ0 cannot be identified from force curves. Values are in SI unless a unit "
            "says otherwise.</p>"]
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{_e(title)}</title>"
            f"<style>{_CSS}</style></head><body>\n" + "\n".join(b for b in body if b) + "\n</body></html>\n")


def write_html(result: Any, path: str | Path, *, images: Mapping[str, Any] | None = None) -> Path:
    """Write :func:`render_html` to ``path`` (UTF-8); returns the path."""
    path = Path(path)
    path.write_text(render_html(result, images=images), encoding="utf-8")
    return path
