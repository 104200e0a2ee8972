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

__all__ = ["jit", "core_hash", "KEYED_ON_CORE"]

_CORE = Path(__file__).resolve().parent


def core_hash() -> str:
    """SHA-256 over the names and contents of every ``adhfit/core/*.py`` (the cache key)."""
    h = hashlib.sha256()
    for path in sorted(_CORE.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _install() -> bool:
    """Put :class:`_CoreLocator` first among numba's cache locators; False where this numba lacks
    the (private) hooks, and then each kernel is cached on its own file as numba does by default."""
    base = getattr(caching, "InTreeCacheLocator", None) or getattr(caching, "_InTreeCacheLocator", None)
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    classes = getattr(impl, "_locator_classes", None)
    if base is None or not isinstance(classes, list):
        return False

    class _CoreLocator(base):
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

    if not any(c.__name__ == "_CoreLocator" for c in classes):
        classes.insert(0, _CoreLocator)
    return True


#: whether every kernel is keyed on :func:`core_hash` (numba's private cache hooks were found)
KEYED_ON_CORE = _install()

#: the decorator of every kernel: cached, no GIL, numpy's error model (division by zero gives inf
#: or NaN instead of raising, as in numpy)
jit = njit(cache=True, nogil=True, error_model="numpy")
