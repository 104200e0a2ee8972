"""One line before a large curve file is read (a dense log can take seconds to parse), in a pipe too."""
from __future__ import annotations

import sys
from pathlib import Path

from .engine import elapsed

__all__ = ["reading", "BIG_FILE"]

#: a curve file at least this large (bytes: ~200,000 rows of two columns) is announced before it is read
BIG_FILE = 8 * 2**20


def reading(path, *, quiet: bool = False):
    """Say that a large curve file is being read (one line, in a pipe too; a running clock on a terminal)."""
    p = Path(path)
    size = p.stat().st_size if p.is_file() else 0
    if quiet or size < BIG_FILE:
        return elapsed("", enabled=False)
    print(f"adhfit: reading {p.name} ({size / 2**20:.0f} MiB; a dense log is fitted as ~2,000 bins of "
          "consecutive rows)…", file=sys.stderr, flush=True)
    return elapsed(f"reading {p.name}")
