"""HTML building blocks shared by report.html, summary.html and the notebook view: escaping, tables,
generic rendering of nested values (tables, never raw JSON), the stylesheet and embedded images."""
from __future__ import annotations

import base64
import html
import io
import math
from pathlib import Path
from typing import Any, Mapping

__all__ = ["CSS", "e", "num", "table", "value_html", "png_bytes", "figure", "page", "details"]

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;max-width:62em;margin:1.5em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.45em;margin-bottom:.2em}h2{font-size:1.15em;border-bottom:1px solid #ccc;margin-top:1.5em}
h3{font-size:1em;margin:1em 0 .3em}
table{border-collapse:collapse;margin:.4em 0;font-size:.92em}
th,td{border:1px solid #d4d4d4;padding:.25em .6em;text-align:left;vertical-align:top}
th{background:#f3f3f3;font-weight:600}td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
table.inner{margin:0;font-size:1em}table.inner td,table.inner th{border:none;border-bottom:1px solid #eee;padding:.1em .5em}
.verdict{font-size:1.08em;padding:.5em .8em;background:#eef5ff;border-left:4px solid #1f77b4}
.warn{background:#fff6e0;border-left:4px solid #e69500;padding:.4em .8em;margin:.3em 0}
.bad{background:#fdecea;border-left:4px solid #d62728;padding:.4em .8em;margin:.3em 0}
.ok{background:#eefaf0;border-left:4px solid #2ca02c;padding:.4em .8em}
.muted{color:#666;font-size:.88em}code,.mono{font-family:ui-monospace,Menlo,Consolas,monospace;font-size:.88em;
word-break:break-all}img{max-width:100%;height:auto;border:1px solid #ddd}
figure{margin:.8em 0}details{margin:.6em 0}summary{cursor:pointer;font-weight:600}
.status-determined{color:#2a7a2a}.status-lower_bound,.status-upper_bound{color:#a36100}
.status-undetermined,.status-failed{color:#b00}
"""


def e(x: Any) -> str:
    """Escape any value as HTML text (``None`` is empty)."""
    return html.escape("" if x is None else str(x), quote=True)


def num(x: Any, digits: int = 4) -> str:
    """A number as escaped text with ``digits`` significant digits; ``n/a`` when missing or not finite."""
    if x is None:
        return "n/a"
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return e(x)
    if isinstance(x, float) and not math.isfinite(x):
        return "n/a"
    if isinstance(x, int) or (isinstance(x, float) and x.is_integer() and abs(x) < 1e7 and digits >= 3):
        return e(f"{int(x)}")
    return e(f"{x:.{digits}g}")


def table(header: list[str], rows: list[list[str]], numeric: tuple[int, ...] = (), cls: str = "") -> str:
    """A table; ``header`` and cells must already be HTML; columns in ``numeric`` align right."""
    head = "".join(f"<th>{h}</th>" for h in header) if header else ""
    body = "".join("<tr>" + "".join(
        f"<td class=\"num\">{c}</td>" if j in numeric else f"<td>{c}</td>" for j, c in enumerate(r))
        + "</tr>" for r in rows)
    return (f"<table{' class=' + chr(34) + cls + chr(34) if cls else ''}>"
            + (f"<tr>{head}</tr>" if head else "") + f"{body}</table>")


def _label(key: Any) -> str:
    return e(str(key).replace("_", " "))


def value_html(v: Any, depth: int = 0) -> str:
    """Any JSON value as readable HTML: dicts as key/value tables, lists of dicts as tables, lists of
    numbers or words as a comma list; never a raw JSON string."""
    if isinstance(v, Mapping):
        if not v:
            return "<span class=\"muted\">none</span>"
        if depth > 3:
            return e(", ".join(f"{k}: {x}" for k, x in v.items()))
        rows = [[_label(k), value_html(x, depth + 1)] for k, x in v.items()]
        return table([], rows, cls="inner")
    if isinstance(v, (list, tuple)):
        if not v:
            return "<span class=\"muted\">none</span>"
        if all(isinstance(x, Mapping) for x in v) and depth <= 3:
            keys = list(dict.fromkeys(k for x in v for k in x))
            rows = [[value_html(x.get(k), depth + 1) for k in keys] for x in v]
            return table([_label(k) for k in keys], rows, cls="inner")
        if all(not isinstance(x, (Mapping, list, tuple)) for x in v):
            return ", ".join(value_html(x, depth + 1) for x in v)
        return "<br>".join(value_html(x, depth + 1) for x in v)
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return num(v, 6)
    if v is None:
        return "<span class=\"muted\">n/a</span>"
    return e(v)


def png_bytes(image: Any) -> bytes:
    """PNG bytes of ``image``: bytes, a path to a PNG file, or a matplotlib Figure."""
    if isinstance(image, (bytes, bytearray)):
        return bytes(image)
    if hasattr(image, "savefig"):
        buf = io.BytesIO()
        image.savefig(buf, format="png", dpi=110)
        return buf.getvalue()
    return Path(image).read_bytes()


def figure(title: str, image: Any, caption: str = "") -> str:
    """An embedded (base64) PNG with its caption."""
    data = base64.b64encode(png_bytes(image)).decode("ascii")
    return (f"<figure><img alt=\"{e(title)}\" src=\"data:image/png;base64,{data}\">"
            f"<figcaption class=\"muted\">{e(caption or title)}</figcaption></figure>")


def details(summary: str, body: str, open_: bool = False) -> str:
    """A collapsed section (``<details>``); ``summary`` is HTML."""
    return f"<details{' open' if open_ else ''}><summary>{summary}</summary>{body}</details>"


def page(title: str, body: list[str]) -> str:
    """A self-contained HTML page (no external resources)."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{e(title)}</title>"
            f"<style>{CSS}</style></head><body>\n" + "\n".join(b for b in body if b) + "\n</body></html>\n")
