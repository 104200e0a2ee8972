"""Which curves a batch fits, with which scene and into which folder (docs/contracts.md A7).

Which files
    Every argument is a curve file or a folder.  A folder stands for every curve file below it (the
    patterns of :func:`adhfit.readers.folder_patterns`: ``*.csv``, ``*.tsv``, LabVIEW ``*.lvm``, Excel
    ``*.xlsx``; recursively, sorted; hidden files and folders and the output directory are skipped).  A file there that cannot be fitted (unreadable, a pipe, a broken link, a
    link pointing outside the folder) is a job with a ``problem``: a failed row that says why.

Which scene (when ``--scene`` is not given)
    Each curve uses the nearest ``scene.toml``: in its own folder, else in the parent folders up to the
    folder given on the command line (for a file argument: its own folder only).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

from ..errors import InputError
from ..readers import folder_patterns

__all__ = ["Job", "discover", "is_batch", "single_scene", "SCENE_NAME", "CURVE_PATTERNS"]

SCENE_NAME = "scene.toml"
#: the files a folder stands for, from the one list of formats (readers.FORMATS); a folder of other
#: .txt files is common, so .txt is read when named but not collected
CURVE_PATTERNS = folder_patterns()


@dataclass(frozen=True)
class Job:
    """One curve of a batch: the data file, its scene (None: not found) and its output folder."""

    data: Path
    scene: Path | None
    out: Path
    scene_note: str = ""
    #: why the file cannot be fitted, found before any fit (an unreadable file, a link out of the folder)
    problem: str = ""


def is_batch(data: Iterable[Path]) -> bool:
    """True for several arguments or any folder."""
    data = list(data)
    return len(data) != 1 or Path(data[0]).is_dir()


def _skip(path: Path, root: Path, outdir: Path | None) -> bool:
    rel = path.relative_to(root).parts
    if any(part.startswith(".") for part in rel):
        return True
    if outdir is not None:
        try:
            path.resolve().relative_to(outdir.resolve())
            return True
        except ValueError:
            pass
    return False


def _nearest_scene(csv_path: Path, root: Path) -> Path | None:
    folder = csv_path.parent
    root = root.resolve()
    while True:
        candidate = folder / SCENE_NAME
        if candidate.is_file():
            return candidate
        if folder.resolve() == root or folder.resolve() == folder.resolve().parent:
            return None
        folder = folder.parent


def _found(folder: Path, outdir: Path | None) -> list[Path]:
    """The curve files below ``folder``: anything but a folder (a link, a pipe: listed, and judged by
    :func:`_problem`)."""
    return sorted(f for pattern in CURVE_PATTERNS for f in folder.rglob(pattern)
                  if (f.is_symlink() or not f.is_dir()) and not _skip(f, folder, outdir))


def _problem(f: Path, root: Path | None) -> str:
    """Why ``f`` cannot be fitted, or ``""``.  ``root``: the folder it was found in (None: given by name,
    where a link is the user's own choice)."""
    if f.is_symlink():
        target = Path(os.path.realpath(f))
        if not target.exists():
            return f"a broken symbolic link (to {target}); remove it or point it at a curve file"
        if root is not None and not target.is_relative_to(root.resolve()):
            return (f"a symbolic link to {target}, outside the folder {root} given; links out of the folder "
                    "are not followed: copy the file into the folder, or name it on the command line")
    if not f.is_file():
        return "not a regular file; give a curve file"
    if not os.access(f, os.R_OK):
        return "cannot be read (permission denied); make it readable (chmod +r) or move it out of the folder"
    return ""


def discover(paths: Iterable[str | Path], *, scene: str | Path | None = None,
             outdir: str | Path | None = None) -> list[Job]:
    """The curves to fit, each with its scene and output folder (rules in the module docstring).

    A file that cannot be fitted (unreadable, a broken link, a link pointing out of the folder given)
    is a job with a ``problem``: a failed row, never the end of the run.

    Raises
    ------
    InputError
        A path that does not exist, or no CSV file at all.
    """
    found: list[tuple[Path, Path, bool]] = []  # (csv, the root it was found under, found in a folder?)
    outdir = None if outdir is None else Path(outdir)
    for raw in paths:
        p = Path(raw)
        if p.is_dir():
            found += [(f, p, True) for f in _found(p, outdir)]
        elif p.is_file():
            found.append((p, p.parent, False))
        else:
            raise InputError("DATA", str(p), "an existing CSV file or folder")
    if not found:
        raise InputError("DATA", " ".join(map(str, paths)), "files or folders holding at least one curve file (" + ", ".join(CURVE_PATTERNS) + ")")
    seen, unique = set(), []
    for f, root, in_folder in found:
        key = Path(os.path.realpath(f))
        if key not in seen:
            seen.add(key)
            unique.append((f, root, in_folder))
    base = Path(os.path.commonpath([str(r.resolve()) for _, r, _ in unique]))
    out = Path(outdir) if outdir is not None else Path("adhfit_fit")
    jobs = []
    for f, root, in_folder in unique:
        # the file's place below the folder given (a link's own name, not its target's)
        rel = (root.resolve() / f.relative_to(root)).relative_to(base).with_suffix("")
        if scene is not None:
            sc, note = Path(scene), "--scene"
        else:
            sc = _nearest_scene(f, root)
            note = "nearest scene.toml" if sc else (f"no {SCENE_NAME} next to the file or in a parent folder "
                                                     f"up to {root}; give --scene")
        jobs.append(Job(data=f, scene=sc, out=out / rel, scene_note=note,
                        problem=_problem(f, root if in_folder else None)))
    return jobs


def single_scene(data: str | Path) -> Path:
    """The scene of a single-curve fit without ``--scene``: ``scene.toml`` next to the data file."""
    candidate = Path(data).parent / SCENE_NAME
    if not candidate.is_file():
        raise InputError("--scene", None, f"a scene file: give --scene SCENE.toml or put {SCENE_NAME} next to "
                                          f"{data}")
    return candidate
