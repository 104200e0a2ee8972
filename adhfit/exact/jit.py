"""The exact membrane's numba decorator, with one cache key for the whole of ``adhfit/exact``.

numba reloads a cached kernel while its own source file is unchanged, but a kernel embeds the machine
code of the kernels it calls from other modules (``newton`` calls ``kernels``): after an edit of the
callee's module it would load a stale copy. As :mod:`adhfit.core.jit` does for ``adhfit/core``, every
kernel of ``adhfit/exact`` is keyed here on a hash of all of ``exact/*.py``: any edit recompiles them
all, an unchanged tree loads everything from the cache.
"""
from __future__ import annotations

import hashlib
from pathlib import Path

from numba import njit
from numba.core import caching

__all__ = ["jit", "exact_hash", "KEYED_ON_EXACT"]

_EXACT = Path(__file__).resolve().parent


def exact_hash() -> str:
    """SHA-256 over the names and contents of every ``adhfit/exact/*.py`` (the cache key)."""
    h = hashlib.sha256()
    for path in sorted(_EXACT.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _install() -> bool:
    """Put :class:`_ExactLocator` first among numba's cache locators; False where this numba lacks the
    (private) hooks, and then each kernel is cached on its own file as numba does by default."""
    base = getattr(caching, "InTreeCacheLocator", None) or getattr(caching, "_InTreeCacheLocator", None)
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    classes = getattr(impl, "_locator_classes", None)
    if base is None or not isinstance(classes, list):
        return False

    class _ExactLocator(base):
        """numba's in-tree cache locator with the source stamp replaced by :func:`exact_hash`."""

        _stamp: str | None = None

        def get_source_stamp(self):
            if _ExactLocator._stamp is None:
                _ExactLocator._stamp = exact_hash()
            return _ExactLocator._stamp

        @classmethod
        def from_function(cls, py_func, py_file):
            if Path(py_file).resolve().parent != _EXACT:
                return None
            return super().from_function(py_func, py_file)

    if not any(c.__name__ == "_ExactLocator" for c in classes):
        classes.insert(0, _ExactLocator)
    return True


#: whether every kernel is keyed on :func:`exact_hash` (numba's private cache hooks were found)
KEYED_ON_EXACT = _install()

#: the decorator of every kernel: cached, no GIL, numpy's error model (as before this module)
jit = njit(cache=True, nogil=True, error_model="numpy")
