"""report.md: the report of any fit as Markdown, rendered from the :class:`~.view.View` of its report.json
dictionary (:func:`~.sections.build_view`), the same sections as report.html.

Every piece of text is escaped (:func:`md_escape`): a file name holding a backtick, a bracket, a pipe or
HTML shows as text, never as markup, a link or a table cell boundary.
"""
from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .files import relative_link, write_text
from .sections import build_view
from .view import Bullets, Figure, Note, Section, Table, View

__all__ = ["md_escape", "render_markdown", "write_markdown"]

#: CommonMark/GFM punctuation that can start markup anywhere in a line (a backslash makes it literal); an
#: underscore only where it is not between two letters or digits (inside a word it is never emphasis: W_ad)
_MARKUP = re.compile(r"([\\`*{}\[\]<>|~!#&]|(?<![^\W_])_|_(?![^\W_]))")
#: what starts a list, a quote or a heading underline at the start of a paragraph
_START = re.compile(r"^(\s*)(?:([-+=])|(\d+)([.)]))(?=\s|$)")


def md_escape(text: Any, *, line_start: bool = False) -> str:
    """``text`` as literal Markdown text on one line: markup characters backslash-escaped, line breaks
    made spaces; at the start of a line (``line_start``) a list marker is escaped too (``1\\.``, ``\\-``)."""
    s = _MARKUP.sub(r"\\\1", " ".join(str(text).splitlines()))
    if not line_start:
        return s
    return _START.sub(lambda m: m.group(1) + (f"\\{m.group(2)}" if m.group(2) else f"{m.group(3)}\\{m.group(4)}"), s)


def _table(t: Table) -> list[str]:
    head = t.header if any(t.header) else ("",) * len(t.header)
    align = ["---:" if j in t.numeric else "---" for j in range(len(head))]
    rows = [[md_escape(c) for c in r] for r in t.rows]
    for k in t.flagged:
        rows[k][0] = f"**{rows[k][0]}** ⚠"
    return (["| " + " | ".join(md_escape(h) for h in head) + " |", "|" + "|".join(align) + "|"]
            + ["| " + " | ".join(r) + " |" for r in rows] + [""])


def _note(n: Note) -> list[str]:
    lines = [md_escape(x, line_start=True) for x in n.lines]
    if n.tone == "bad":
        lines = [f"**{x}**" for x in lines]
    elif n.tone == "verdict":
        lines = [f"**{lines[0]}**", *lines[1:]]
    elif n.tone == "muted":
        lines = [f"*{x}*" for x in lines]
    return ["  \n".join(lines), ""]


def _block(b: Any, level: int) -> list[str]:
    if isinstance(b, Section):
        return _section(b, level + 1)
    if isinstance(b, Note):
        return _note(b)
    if isinstance(b, Bullets):
        mark = "- ⚠ " if b.tone == "warn" else "- "
        return [mark + md_escape(x, line_start=True) for x in b.items] + [""]
    if isinstance(b, Table):
        return _table(b)
    if isinstance(b, Figure):
        return [f"![{md_escape(b.caption)}]({relative_link(b.name, '.')})", "", f"*{md_escape(b.caption)}*", ""]
    raise TypeError(f"not a report block: {b!r}")


def _section(s: Section, level: int) -> list[str]:
    out = [f"{'#' * level} {md_escape(s.title)}", ""] if s.title else []
    if s.folded:
        out += [f"*{md_escape(s.folded)}*", ""]
    for b in s.blocks:
        out += _block(b, level)
    return out


def render_view(view: View) -> str:
    """A :class:`~.view.View` as Markdown text."""
    out = [f"# {md_escape(view.title)}", "", "  \n".join(md_escape(x, line_start=True) for x in view.subtitle), ""]
    for s in view.sections:
        out += _section(s, 2)
    return "\n".join(out).rstrip() + "\n"


def render_markdown(result: Any, figures: Sequence[str] = ()) -> str:
    """report.md of a :class:`~adhfit.fitting.result.FitResult` or of its report.json dictionary.

    Parameters
    ----------
    result : FitResult or mapping
    figures : sequence of str
        Figure files next to report.md (``fit.png``, ...), shown as images.

    Returns
    -------
    str
    """
    if not isinstance(result, Mapping):
        from .json_report import report_dict  # noqa: PLC0415
        result = report_dict(result)
    return render_view(build_view(result, figures))


def write_markdown(result: Any, path: str | Path, figures: Sequence[str] = ()) -> Path:
    """Write :func:`render_markdown` to ``path`` atomically; returns the path."""
    return write_text(path, render_markdown(result, figures))
