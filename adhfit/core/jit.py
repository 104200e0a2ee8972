"""The engine's numba decorator, with one cache key for the whole of ``adhfit/core``.

numba caches each compiled function next to its module (``core/__pycache__``) and, by default,
reloads it while that one source file is unchanged. A kernel that calls functions of another module
embeds their machine code, so after an edit of the callee's module it would load a stale copy. Here
every kernel of ``core/`` is keyed on a hash of all of ``core/*.py``: any edit recompiles them all,
and an unchanged tree loads everything from the cache (a new process then starts in well under a
second instead of compiling for a minute).
"""
from __future__ import annotations

import hashlib
from pathlib import Path

from numba import njit
from numba.core import caching

__all__ = ["jit", "core_hash"]

_CORE = Path(__file__).resolve().parent


def core_hash() -> str:
    """SHA-256 over the names and contents of every ``adhfit/core/*.py`` (the cache key)."""
    h = hashlib.sha256()
    for path in sorted(_CORE.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


_BASE = getattr(caching, "InTreeCacheLocator", None) or getattr(caching, "_InTreeCacheLocator")
_IMPL = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")


class _CoreLocator(_BASE):
    """numba's in-tree cache locator with the source stamp replaced by :func:`core_hash`."""

    _stamp: str | None = None

    def get_source_stamp(self):
        if _CoreLocator._stamp is None:
            _CoreLocator._stamp = core_hash()
        return _CoreLocator._stamp

    @classmethod
    def from_function(cls, py_func, py_file):
        if Path(py_file).resolve().parent != _CORE:
            return None
        return super().from_function(py_func, py_file)


if _CoreLocator not in _IMPL._locator_classes:
    _IMPL._locator_classes.insert(0, _CoreLocator)

#: the decorator of every kernel: cached, no GIL, numpy's error model (division by zero gives inf
#: or NaN instead of raising, as in numpy)
jit = njit(cache=True, nogil=True, error_model="numpy")
