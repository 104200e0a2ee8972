"""summary.html of a batch: one page for many curves.

A table of every curve (W_ad and μh with their intervals and status, slip, reduced χ², warnings, a link
to the curve's own report.html), W_ad and μh across curves with their 95 % intervals, and small
multiples of every curve with its fitted model.  It reads what each fit wrote (report.json, and the
thumbnail.png its batch job drew or else plot_data.json, in the curve's folder), so it never re-runs a fit.
"""
from __future__ import annotations

import datetime as _dt
import json
import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from .files import relative_link, write_text
from .html_parts import e, figure, num, page, table
from .plots import file_figure
from .thumbnails import thumbnail_png
from .view import display, estimate_text, interval_text, status_text

__all__ = ["write_summary_html", "render_summary_html", "write_plot_data"]

_PARAMS = ("work_of_adhesion", "mu_h")
#: the small figures of every curve: as many to a row as the page is wide
_GRID_CSS = (".thumbs{display:grid;grid-template-columns:repeat(auto-fill,minmax(250px,1fr));gap:.5em}"
             ".thumbs figure{margin:0}.thumbs img{width:100%}")


def write_plot_data(result: Any, path: str | Path) -> Path | None:
    """Save the data and the reported fit's model curve (SI) for the batch figure; None when the result
    holds no curve."""
    try:
        c = result.curve
        mc = dict(result.fits[result.reported_slip].model_curve)
        d = {"control": c.control, "x": np.asarray(c.x, float).tolist(),
             "force": np.asarray(c.force, float).tolist(),
             "model": {k: np.asarray(mc[k], float).tolist() for k in
                       ("x_loading", "force_loading", "x_unloading", "force_unloading") if k in mc}}
    except (AttributeError, KeyError, TypeError):
        return None
    d = json.loads(json.dumps(d).replace("NaN", "null"))
    return write_text(path, json.dumps(d))


def _load(row: Mapping[str, Any], name: str) -> dict | None:
    folder = row.get("report_dir")
    if not folder or row.get("status") != "ok":
        return None
    try:
        return json.loads((Path(folder) / name).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def _labels(rows: Sequence[Mapping[str, Any]], base: Path) -> list[str]:
    """Short names: the path below the common folder, without ``.csv``; when every file has the same
    name (``*/curve.csv``), its folder."""
    files = [Path(str(r.get("file", ""))) for r in rows]
    rel = []
    for f in files:
        try:
            rel.append(f.resolve().relative_to(base.resolve()).with_suffix(""))
        except ValueError:
            rel.append(Path(f.stem))
    from collections import Counter  # noqa: PLC0415
    shared = Counter(r.name for r in rel)
    return [str(r.parent) if shared[r.name] > 1 and str(r.parent) != "." else str(r) for r in rel]


def _intervals(reports: list[dict | None], name: str):
    """Per curve: value, lower and upper error (nan where missing) and the status."""
    out = []
    for rep in reports:
        est = ((rep or {}).get("parameters") or {}).get(name) or {}
        ci = est.get("ci95") or [None, None]
        v = est.get("value")
        lo, hi = (ci + [None, None])[:2] if isinstance(ci, list) else (None, None)
        out.append((v, lo, hi, status_text(est) if est else "failed"))
    return out


def _across(reports: list[dict | None], labels: list[str]):
    n = len(reports)
    fig, axes = file_figure(1, 2, figsize=(9.0, max(2.2, 0.32 * n + 1.2)), layout="constrained", sharey=True)
    y = np.arange(n)[::-1]
    for ax, name in zip(axes, _PARAMS):
        sym, _, k, unit = display(name)
        for yi, (v, lo, hi, status) in zip(y, _intervals(reports, name)):
            if status == "determined" and v is not None:
                err = [[v - lo if lo is not None else 0.0], [hi - v if hi is not None else 0.0]]
                ax.errorbar([v * k], [yi], xerr=np.array(err) * k, fmt="o", color="#1f77b4", ms=4, capsize=3)
            elif status in ("lower_bound", "upper_bound") and (lo if status == "lower_bound" else hi) is not None:
                b = (lo if status == "lower_bound" else hi) * k
                ax.plot([b], [yi], "|", color="#e69500", ms=10)
                ax.annotate("", xy=(b * (1.25 if status == "lower_bound" else 0.8), yi), xytext=(b, yi),
                            arrowprops={"arrowstyle": "->", "color": "#e69500"})
            else:
                ax.text(0.02, yi, "not determined" if status != "failed" else "failed", va="center",
                        fontsize=7, color="#b00", transform=ax.get_yaxis_transform())
        ax.set_xlabel(f"{sym} ({unit})")
        ax.grid(axis="x", color="0.9")
    axes[0].set_yticks(y, [lbl if len(lbl) < 40 else "…" + lbl[-38:] for lbl in labels], fontsize=7)
    axes[0].set_ylim(-0.7, n - 0.3)
    return fig


def _multiples(rows: Sequence[Mapping[str, Any]], labels: list[str], reports: list[dict | None]) -> str:
    """Every curve's small figure (drawn by its job, :mod:`.thumbnails`) in a grid, captioned with its
    label and the slip condition its values come from."""
    cells = []
    for row, label, rep in zip(rows, labels, reports):
        short = label if len(label) < 34 else "…" + label[-32:]
        png = thumbnail_png(row["report_dir"]) if row.get("status") == "ok" and row.get("report_dir") else None
        if png is None:
            cells.append(f"<figure><div class=\"status-failed\">no fit</div>"
                         f"<figcaption class=\"muted\">{e(short)}</figcaption></figure>")
            continue
        slip = ((rep or {}).get("slip") or {}).get("parameters_from") or ""
        cells.append(figure(label, png, f"{short} · {slip}" if slip else short))
    return f"<div class=\"thumbs\">{''.join(cells)}</div>"


def _row_html(i: int, row: Mapping[str, Any], rep: dict | None, label: str, outdir: Path) -> list[str]:
    link = e(label)
    if row.get("report_dir"):  # relative and URL-encoded: a file name never becomes a scheme or markup
        href = relative_link(Path(str(row["report_dir"])) / "report.html", outdir)
        link = f"<a href=\"{e(href)}\">{e(label)}</a>"
    if row.get("status") != "ok" or rep is None:
        return [str(i), f"{link}<br><span class=\"status-failed\">failed:</span> <span class=\"muted\">"
                f"{e(row.get('error', ''))}</span>", "", "", "", "", "", "", ""]
    params = rep.get("parameters") or {}
    cells = []
    for name in _PARAMS:
        est = params.get(name) or {}
        st = status_text(est)
        k = display(name)[2]
        if st == "determined":
            se = est.get("stderr")
            cells += [num(est["value"] * k) + ("" if se is None else f" ± {num(se * k, 2)}"),
                      e(interval_text(name, est, unit=False))]
        else:
            cells += [f"<span class=\"status-{e(st)}\">{e(estimate_text(name, est))}</span>", ""]
    slip = rep.get("slip") or {}
    fits = rep.get("fits") or {}
    redchi = (fits.get(slip.get("parameters_from") or "") or {}).get("redchi")
    nw = len(rep.get("warnings") or [])
    return [str(i), link, *cells, e(slip.get("verdict", "")), num(redchi, 3),
            f"<b>{nw}</b>" if nw else "0"]


def render_summary_html(rows: Sequence[Mapping[str, Any]], outdir: str | Path) -> str:
    """The batch summary page (self-contained) from the summary.csv rows of a batch."""
    outdir = Path(outdir)
    reports = [_load(r, "report.json") for r in rows]
    files = [Path(str(r.get("file", ""))).resolve() for r in rows]
    base = Path(os.path.commonpath([str(f.parent) for f in files])) if files else Path(".")
    labels = _labels(rows, base)
    ok = sum(1 for r in rows if r.get("status") == "ok")
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    body = [f"<h1>adhfit batch: {len(rows)} curves</h1>",
            f"<p class=\"muted\">{ok} fitted, {len(rows) - ok} failed; files under <code>{e(base)}</code>; "
            f"generated {now}. Values: value ± standard error, and the 95 % interval; a one-sided bound or an "
            "undetermined value says so. The table "
            "<code>summary.csv</code> next to this page holds the same numbers in SI.</p>"]
    hdr = ["#", "curve (link: its report)", "W_ad (J/m²)", "W_ad 95 %", "μh (N/m)", "μh 95 %", "slip",
           "reduced χ²", "warnings"]
    body.append(table(hdr, [_row_html(i + 1, r, rep, lbl, outdir)
                            for i, (r, rep, lbl) in enumerate(zip(rows, reports, labels))], numeric=(0, 2, 3, 4, 5, 7, 8)))
    if rows:
        body.append("<h2>W_ad and μh of every curve with 95 % intervals (an orange arrow: a one-sided bound)</h2>"
                    + figure("values", _across(reports, labels), " "))
        body.append("<h2>Every curve (blue: data) with its reported fit (red)</h2>" + _multiples(rows, labels, reports))
    html = page(f"adhfit batch: {len(rows)} curves", body).replace("max-width:62em", "max-width:80em", 1)
    return html.replace("</style>", _GRID_CSS + "</style>", 1)


def write_summary_html(rows: Sequence[Mapping[str, Any]], outdir: str | Path) -> Path:
    """Write ``outdir/summary.html`` atomically (see :func:`render_summary_html`); returns its path."""
    return write_text(Path(outdir) / "summary.html", render_summary_html(rows, outdir))
