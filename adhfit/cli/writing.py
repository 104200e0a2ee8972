"""The output folder (checked before any work) and the summary lines the command line prints; the
reports themselves are written by :func:`adhfit.report.write`."""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import InputError

__all__ = ["check_output_dir", "writable_folder", "os_error_words", "summary_text", "estimate_line", "exit_status",
           "EXIT_MISFIT"]

#: ``adhfit fit``'s exit status when the reports are written but the model does not describe the data
#: (the first warning says why and names the likely causes: a unit, a scene setting, the slip condition)
EXIT_MISFIT = 5


def exit_status(result) -> int:
    """0, or :data:`EXIT_MISFIT` when the reported fit does not describe the data."""
    return EXIT_MISFIT if result.fits[result.reported_slip].misfit else 0


def check_output_dir(path: Path) -> Path:
    """Make sure ``path`` can hold the reports *before* any work, without creating it yet.

    Raises
    ------
    InputError
        ``path`` is an existing file, lies under a file, or its nearest existing folder is not writable.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError("-o/--output", str(path), "a folder (it is an existing file)",
                         "Give another name, or remove the file.")
    parent = next((q for q in [path, *path.parents] if q.exists()), Path("."))
    if not parent.is_dir():
        raise InputError("-o/--output", str(path), "a folder path", f"{parent} is a file, not a folder.")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError("-o/--output", str(path), "a folder you can write to",
                         f"{parent} is not writable; choose another folder, or change its permissions.")
    try:
        _probe(path)
    except OSError as err:  # e.g. /proc or a read-only mount, which os.access does not see
        raise InputError("-o/--output", str(path), "a folder you can write to",
                         os_error_words(err, path) + ".") from None
    return path


def _probe(path: Path) -> None:
    """Create ``path`` and a file in it, then remove what was created: the folder is left as found."""
    missing = [q for q in [path, *path.parents] if not q.exists()]
    created = []
    try:
        for q in reversed(missing):
            try:
                q.mkdir()
            except FileExistsError:  # made by another process meanwhile: not ours to remove
                continue
            created.append(q)
        probe = path / f".adhfit-write-test-{os.getpid()}"
        probe.touch()
        probe.unlink()
    finally:
        for q in reversed(created):
            try:
                q.rmdir()
            except OSError:
                pass


def os_error_words(err: OSError, path: str | Path | None = None) -> str:
    """One sentence for a failed write: the path, what went wrong in words, and the fix (no errno)."""
    import errno  # noqa: PLC0415
    where = path if path is not None else (err.filename or "the output folder")
    why = {errno.EACCES: "permission denied", errno.EPERM: "permission denied",
           errno.EROFS: "the file system is read-only", errno.ENOSPC: "the disk is full",
           errno.EDQUOT: "the disk quota is used up", errno.ENOTDIR: "a part of the path is a file, not a folder",
           errno.EEXIST: "a file of that name is in the way", errno.ENAMETOOLONG: "the name is too long"}
    reason = why.get(err.errno, (err.strerror or type(err).__name__).lower())
    fix = ("free some space, or choose another folder with -o" if err.errno in (errno.ENOSPC, errno.EDQUOT)
           else "choose another folder with -o, or fix the folder's permissions")
    return f"cannot write {where}: {reason}; {fix}"


def writable_folder(path: str | Path) -> Path:
    """Create the output folder ``path`` (and its parents) now, or say in one line why not.

    Raises
    ------
    InputError
        The folder cannot be created or written (the message names the path and the fix).
    """
    path = check_output_dir(Path(path))
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError("-o/--output", str(path), "a folder you can write to", os_error_words(err, path) + ".") from None
    return path


def estimate_line(name: str, e) -> str:
    """One line per estimate, honest about one-sided and undetermined parameters."""
    d = e if isinstance(e, dict) else e.as_dict()
    from ..report.view import estimate_text  # noqa: PLC0415
    return f"{name} = {estimate_text(name, d)}"


def summary_text(result, out: Path) -> str:
    """The lines ``adhfit fit`` prints: the slip verdict, the membrane model, the estimates, the cost."""
    d = result.as_dict()
    lines = [f"slip: {d['slip'].get('verdict')}"]
    if d.get("model"):
        lines.append(f"membrane: {d['model']['membrane']} ({d['model']['why']})")
    shown = dict(d.get("parameters", {}))
    for name, e in shown.items():
        lines.append(estimate_line(name, e))
    for w in d.get("warnings", []) or []:  # a fit that did not converge is said on the command line too
        if w.startswith(("The fit did not converge", "MCMC NOT CONVERGED")) or \
                "The model does not describe these data" in w or "The model may not describe these data" in w:
            lines.append(f"WARNING: {w}")
    n_warn = len(d.get("warnings", []) or [])
    lines.append(f"{n_warn} warning(s); {d.get('model_evaluations')} model evaluations, "
                 f"{result.wall_time:.1f} s; wrote {out}/report.json, report.md, report.html"
                 + ("" if not (out / "fit.png").exists() else ", fit.png"))
    return "\n".join(lines)
