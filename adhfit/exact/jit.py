"""The exact membrane's kernels are keyed on one hash of all of ``adhfit/exact`` (the mechanism of
:mod:`adhfit.core.jit`): a kernel embeds the machine code of the kernels it calls from other modules
(``newton`` calls ``kernels``), so an edit of any file must recompile them all."""
from __future__ import annotations

from pathlib import Path

from numba import njit

from ..core.jit import jit, key_on_tree, tree_hash

__all__ = ["jit", "fast_jit", "exact_hash", "KEYED_ON_EXACT"]

#: ``jit`` with the floating-point freedoms that let the compiler fuse and reorder the Runge-Kutta
#: sums (contraction to FMA, reassociation, reciprocals): ~7 % off a shot, results changed at the
#: rounding level only. NaN and inf keep their meaning (no 'nnan'/'ninf'), so the finiteness checks
#: of the callers still see a shot that left the domain.
fast_jit = njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract", "reassoc", "arcp", "nsz"})

_EXACT = Path(__file__).resolve().parent


def exact_hash() -> str:
    """The cache key of ``adhfit/exact``: :func:`adhfit.core.jit.tree_hash` of it."""
    return tree_hash(_EXACT)


#: whether every exact kernel is keyed on :func:`exact_hash`
KEYED_ON_EXACT = key_on_tree(_EXACT)
