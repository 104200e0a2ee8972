"""Files of a report written safely, and links between them.

Every report file is written atomically (issue 23 item 6): the content goes to a temporary file in the
same folder, then ``os.replace`` puts it in place, so an interrupted run (Ctrl-C, a killed worker) leaves
the old file or the new one, never half of one.  (No ``fsync``: a batch writes five files a curve, and
the rename already guards against interruption; a power cut may still lose the newest file.)  Links built from file names (issue 23 item 7) are relative, URL-encoded and
never carry a scheme (``javascript:``, ``file:``, ``http:``).
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any
from urllib.parse import quote

__all__ = ["write_atomic", "write_text", "write_bytes", "save_figure", "relative_link"]


def write_atomic(path: str | Path, fill: Callable[[IO[bytes]], Any]) -> Path:
    """Write ``path`` atomically: ``fill(f)`` writes into a temporary file of the same folder, which then
    replaces ``path`` (``os.replace``); on any error the temporary file is removed and ``path`` is untouched.

    Parameters
    ----------
    path : path
        The file to write; its folder must exist.
    fill : callable
        Called with the open binary temporary file.

    Returns
    -------
    Path
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            fill(f)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    data = text.encode("utf-8")
    return write_atomic(path, lambda f: f.write(data))


def write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    return write_atomic(path, lambda f: f.write(data))


def save_figure(fig: Any, path: str | Path, **savefig_kw: Any) -> Path:
    """``fig.savefig`` to ``path`` atomically (the format from the file name's suffix, PNG by default)."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    return write_atomic(path, lambda f: fig.savefig(f, format=fmt, **savefig_kw))


def relative_link(target: str | Path, base: str | Path) -> str:
    """A relative, URL-encoded link from folder ``base`` to ``target``, safe in ``href`` and Markdown.

    Every path segment is percent-encoded (``quote(..., safe="")``), so no segment can start a scheme
    (``javascript:`` becomes ``javascript%3A``), a query or a fragment, or break out of an attribute or a
    Markdown link (quotes, brackets, spaces, backticks are all encoded).

    Parameters
    ----------
    target : path
        The file linked to.
    base : path
        The folder of the page that holds the link.

    Returns
    -------
    str
    """
    rel = os.path.relpath(Path(target), Path(base))
    return "/".join(quote(p, safe="") for p in Path(rel).parts)
