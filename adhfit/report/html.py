"""report.html: one self-contained page for any fit (one curve or a series, least squares or MCMC), to read
in a browser or mail to a colleague.

The page renders the :class:`~.view.View` of the report.json dictionary (:func:`~.sections.build_view`),
the same sections as report.md.  Everything is inside the file (figures as base64 PNG; no external CSS,
JavaScript, fonts or images); every piece of text is HTML-escaped; diagnostics are folded away.  A saved
report.json renders again::

    import json
    from adhfit.report.html import render_html
    page = render_html(json.load(open("out/report.json")), images={"fit.png": "out/fit.png"})
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .files import write_text
from .html_parts import details, e, figure, page, table
from .sections import METHODS, build_view, estimate_row
from .view import Bullets, Figure, Note, Section, Table, View, display, estimate_text, seed_text

__all__ = ["render_html", "write_html", "fit_summary_html", "render_view"]

_TONES = {"ok": "ok", "warn": "warn", "bad": "bad", "verdict": "verdict", "muted": "muted"}
_HEADER = ("quantity", "value", "95 % interval", "std. error", "status", "unit")


def _lines(n: Note) -> str:
    return "<br>".join(e(x) for x in n.lines)


def _note(n: Note) -> str:
    cls = f" class=\"{_TONES[n.tone]}\"" if n.tone in _TONES else ""
    if n.tone == "verdict":  # the slip verdict and the values, in bold
        first, *rest = n.lines
        return f"<p{cls}><b>{e(first)}</b>" + "".join(f"<br>{e(x)}" for x in rest) + "</p>"
    if n.tone == "bad":
        return f"<p{cls}><b>{_lines(n)}</b></p>"
    return f"<p{cls}>{_lines(n)}</p>"


def _table(t: Table) -> str:
    rows = [[e(c) for c in r] for r in t.rows]
    for k in t.flagged:
        rows[k] = [f"<b class=\"status-failed\">{c}</b>" if j in (1, len(rows[k]) - 1) else c
                   for j, c in enumerate(rows[k])]
    return table([e(h) for h in t.header] if any(t.header) else [], rows, numeric=t.numeric)


def _block(b: Any, level: int, images: Mapping[str, Any]) -> str:
    if isinstance(b, Section):
        return _section(b, level + 1, images)
    if isinstance(b, Note):
        return _note(b)
    if isinstance(b, Bullets):
        if b.tone == "warn":
            return "".join(f"<div class=\"warn\">⚠ {e(x)}</div>" for x in b.items)
        cls = " class=\"muted\"" if b.tone == "muted" else ""
        return f"<ul{cls}>" + "".join(f"<li>{e(x)}</li>" for x in b.items) + "</ul>"
    if isinstance(b, Table):
        return _table(b)
    if isinstance(b, Figure):
        img = images.get(b.name)
        return figure(b.name, img, b.caption) if img is not None else ""
    raise TypeError(f"not a report block: {b!r}")


def _section(s: Section, level: int, images: Mapping[str, Any]) -> str:
    h = min(level, 4)
    body = "".join(_block(b, level, images) for b in s.blocks)
    if s.folded:
        body = details(e(s.folded), body)
    return (f"<h{h}>{e(s.title)}</h{h}>" if s.title else "") + body


def render_view(view: View, images: Mapping[str, Any] | None = None) -> str:
    """A :class:`~.view.View` as a self-contained page; ``images``: figure name -> PNG (bytes, path, Figure)."""
    images = images or {}
    head = f"<h1>{e(view.title)}</h1><p class=\"muted\">" + "<br>".join(e(x) for x in view.subtitle) + "</p>"
    body = [head] + [_section(s, 2, images) for s in view.sections]
    wide = any(isinstance(b, Table) and len(b.header) > 8 for s in view.sections for b in _walk(s))
    return page(view.title, (["<style>body{max-width:80em}</style>"] if wide else []) + body)


def _walk(s: Section):
    for b in s.blocks:
        yield from (_walk(b) if isinstance(b, Section) else (b,))


def render_html(result: Any, *, images: Mapping[str, Any] | None = None, title: str | None = None,
                extra: Mapping[str, Any] | None = None) -> str:
    """The report of any fit as a self-contained HTML page.

    Parameters
    ----------
    result : FitResult or mapping
        A :class:`~adhfit.fitting.result.FitResult`, or its report.json dictionary.
    images : mapping name -> PNG, optional
        Figures to embed (PNG bytes, a path to a PNG file, or a matplotlib Figure), by file name
        (``fit.png``, ``fit_mcmc.png``, ``corner.png``).  Default: the fit plot drawn from a FitResult;
        none for a dictionary.
    title : str, optional
        Page title; default from the input file name (one curve) or the number of curves.
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
    view = build_view(d, figures=tuple(images))
    if title:
        view = View(title, view.subtitle, view.sections)
    return render_view(view, images)


def _fit_figure(result: Any) -> bytes | None:
    """The fit plot of a FitResult as PNG bytes (None if it cannot be drawn)."""
    try:
        import io  # noqa: PLC0415
        from .fit_plot import plot_fit  # noqa: PLC0415
        buf = io.BytesIO()
        plot_fit(result, path=buf)
    except Exception:  # noqa: BLE001 - a report without its plot beats no report; the page says so
        return None
    return buf.getvalue()


def write_html(result: Any, path: str | Path, *, images: Mapping[str, Any] | None = None,
               extra: Mapping[str, Any] | None = None) -> Path:
    """Write :func:`render_html` to ``path`` atomically (UTF-8); returns the path."""
    return write_text(path, render_html(result, images=images, extra=extra))


def fit_summary_html(d: Mapping[str, Any]) -> str:
    """A compact HTML block of a fit (notebooks: ``FitResult._repr_html_``): verdict, values table, warnings."""
    rows = [[e(c) for c in estimate_row(n, v)]
            for n, v in {**(d.get("parameters") or {}), **(d.get("offsets") or {})}.items()]
    warn = "".join(f"<div class=\"warn\">⚠ {e(w)}</div>" for w in d.get("warnings") or [])
    values = "; ".join(f"{display(k)[0]} = {estimate_text(k, v)}" for k, v in (d.get("parameters") or {}).items()
                       if isinstance(v, Mapping))
    return (f"<div><b>adhfit fit</b> ({e(METHODS.get(d.get('method'), d.get('method')))}; {e(seed_text(d))}) — "
            f"slip: <b>{e((d.get('slip') or {}).get('verdict'))}</b><br>{e(values)}"
            + table([e(h) for h in _HEADER], rows, numeric=(1, 2, 3)) + warn + "</div>")
