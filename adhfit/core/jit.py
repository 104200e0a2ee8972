"""The engines' numba decorator, with one cache key per engine folder (``adhfit/core``, ``adhfit/exact``).

numba caches each compiled function next to its module (``__pycache__``) and, by default, reloads it
while that one source file is unchanged. A kernel that calls functions of another module embeds their
machine code, so after an edit of the callee's module it would load a stale copy. Here every kernel
of a registered folder is keyed on a hash of all of that folder's ``*.py``: any edit recompiles its
kernels, and an unchanged tree loads everything from the cache (a new process then starts in well
under a second instead of compiling for a minute).  ``adhfit/core`` is registered here,
``adhfit/exact`` by :mod:`adhfit.exact.jit`.
"""
from __future__ import annotations

import hashlib
from pathlib import Path

from numba import njit
from numba.core import caching

__all__ = ["jit", "core_hash", "tree_hash", "key_on_tree", "KEYED_ON_CORE", "CompileWatch"]

_CORE = Path(__file__).resolve().parent
#: registered folder -> its hash, computed once per process (None until first asked)
_TREES: dict[Path, str | None] = {}


def tree_hash(folder: Path) -> str:
    """SHA-256 over the names and contents of every ``*.py`` of ``folder`` (a cache key)."""
    h = hashlib.sha256()
    for path in sorted(Path(folder).glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def core_hash() -> str:
    """The cache key of ``adhfit/core``: :func:`tree_hash` of it."""
    return tree_hash(_CORE)


def _install() -> bool:
    """Put :class:`_TreeLocator` first among numba's cache locators; False where this numba lacks
    the (private) hooks, and then each kernel is cached on its own file as numba does by default."""
    base = getattr(caching, "InTreeCacheLocator", None) or getattr(caching, "_InTreeCacheLocator", None)
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    classes = getattr(impl, "_locator_classes", None)
    if base is None or not isinstance(classes, list):
        return False

    class _TreeLocator(base):
        """numba's in-tree cache locator with the source stamp replaced by its folder's hash."""

        def get_source_stamp(self):
            folder = Path(self._py_file).resolve().parent
            if _TREES.get(folder) is None:
                _TREES[folder] = tree_hash(folder)
            return _TREES[folder]

        @classmethod
        def from_function(cls, py_func, py_file):
            if Path(py_file).resolve().parent not in _TREES:
                return None
            return super().from_function(py_func, py_file)

    if not any(c.__name__ == "_TreeLocator" for c in classes):
        classes.insert(0, _TreeLocator)
    return True


def key_on_tree(folder: Path) -> bool:
    """Key every kernel defined in ``folder`` on :func:`tree_hash` of it; False where numba's cache
    hooks are missing (each kernel is then cached on its own file)."""
    _TREES.setdefault(Path(folder).resolve(), None)
    return _INSTALLED


_INSTALLED = _install()

#: whether every kernel of ``adhfit/core`` is keyed on :func:`core_hash`
KEYED_ON_CORE = key_on_tree(_CORE)

#: the decorator of every kernel: cached, no GIL, numpy's error model (division by zero gives inf
#: or NaN instead of raising, as in numpy)
jit = njit(cache=True, nogil=True, error_model="numpy")


class CompileWatch:
    """Which kernel numba is compiling now, from its ``numba:compile`` events (numba's event API): for a
    progress display while the engine compiles (:mod:`adhfit.cli.engine`).

    Parameters
    ----------
    prefix : str
        Only kernels of modules whose name starts with it are named (numba's own helpers, compiled
        inside them, keep the name of the kernel that needs them).
    stack : list, optional
        Where the names of the kernels being compiled are kept (innermost last).
    """

    def __init__(self, prefix: str = "adhfit.", stack: list | None = None) -> None:
        self.prefix = prefix
        self._stack = [] if stack is None else stack
        self._listener = None

    @property
    def current(self) -> str:
        """``module.function`` (the module's last name) of the kernel compiling now; "" when none."""
        stack = self._stack
        return stack[-1] if stack else ""

    def start(self) -> None:
        from numba.core import event  # noqa: PLC0415
        stack, prefix = self._stack, self.prefix

        class Listener(event.Listener):
            def on_start(self, ev) -> None:
                fn = getattr(ev.data.get("dispatcher"), "py_func", None)
                name = getattr(fn, "__module__", "") or ""
                if name.startswith(prefix):
                    stack.append(f"{name.rsplit('.', 1)[-1]}.{fn.__name__}")
                else:
                    stack.append(stack[-1] if stack else "")

            def on_end(self, ev) -> None:
                if stack:
                    stack.pop()
        self._listener = Listener()
        event.register("numba:compile", self._listener)

    def stop(self) -> None:
        if self._listener is not None:
            from numba.core import event  # noqa: PLC0415
            event.unregister("numba:compile", self._listener)
            self._listener = None
