"""Row-order segments of a measured curve: the end of loading and a detected detachment jump.

The end of loading is the largest control value (first occurrence); the jump is found by a threshold
on the force steps (:func:`detect_jump`).  The fit no longer relies on the jump detector (the model's
free split decides which rows are detached, see :mod:`.model`); it remains a first guess for reports
and the container of the fixed split the second fit stage uses.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Segments", "segment", "detect_jump", "JUMP_FRACTION", "JUMP_NOISE"]

#: a jump must exceed this fraction of the most negative force ...
JUMP_FRACTION = 0.3
#: ... and this many robust standard deviations of the row-to-row force changes
JUMP_NOISE = 6.0




@dataclass(frozen=True)
class Segments:
    """Row-order segments of a measured curve.

    Attributes
    ----------
    n : int
        Number of rows.
    i_turn : int
        Last loading row (largest control value, first occurrence).
    i_jump : int or None
        First row after the detachment jump (model force zero from here on); ``None`` when the data
        end before pull-off.
    jump : float
        Size of the detected jump, N (0 when none).
    """

    n: int
    i_turn: int
    i_jump: int | None
    jump: float = 0.0

    def _mask(self, lo: int, hi: int) -> np.ndarray:
        m = np.zeros(self.n, bool)
        m[lo:hi] = True
        return m

    @property
    def loading(self) -> np.ndarray:
        """Boolean mask of the loading rows (the turning row included)."""
        return self._mask(0, self.i_turn + 1)

    @property
    def attached(self) -> np.ndarray:
        """Boolean mask of the unloading rows before the detachment jump."""
        return self._mask(self.i_turn + 1, self.n if self.i_jump is None else self.i_jump)

    @property
    def detached(self) -> np.ndarray:
        """Boolean mask of the rows after the jump (free membrane)."""
        return self._mask(self.n if self.i_jump is None else self.i_jump, self.n)

    def split_before(self, j: int, force: np.ndarray) -> Segments:
        """The same curve with the detachment fixed before row ``j`` (the jump: the force step there)."""
        f = np.asarray(force, float)
        return Segments(n=self.n, i_turn=self.i_turn, i_jump=j, jump=float(abs(f[j] - f[j - 1])))

    def as_dict(self) -> dict:
        return {"i_turn": self.i_turn, "i_jump": self.i_jump, "jump": self.jump,
                "n_loading": int(self.loading.sum()), "n_attached": int(self.attached.sum()),
                "n_detached": int(self.detached.sum())}


def detect_jump(force: np.ndarray, i_turn: int) -> tuple[int | None, float]:
    """First row after the detachment jump, and the jump's size (N).

    The jump is the largest rise of the force between consecutive rows after the most negative force
    of the unloading rows.  It is accepted only if it exceeds ``JUMP_FRACTION`` of that force and
    ``JUMP_NOISE`` robust standard deviations (median absolute deviation) of the row-to-row changes,
    and if the force after it is closer to zero than to the force before it.

    Returns
    -------
    (i_jump, size) : (int or None, float)
        ``(None, 0.0)`` when the data end before pull-off.
    """
    f = np.asarray(force, float)
    i_min = i_turn + int(np.argmin(f[i_turn:]))
    if f[i_min] >= 0.0 or i_min >= f.size - 1:
        return None, 0.0
    steps = np.diff(f[i_min:])
    k = int(np.argmax(steps))
    size = float(steps[k])
    all_steps = np.diff(f[i_turn:])
    noise = 1.4826 * float(np.median(np.abs(all_steps - np.median(all_steps))))
    before, after = f[i_min + k], float(np.median(f[i_min + k + 1:]))
    if size > JUMP_FRACTION * abs(f[i_min]) and size > JUMP_NOISE * noise \
            and abs(after) < 0.5 * abs(before):
        return i_min + k + 1, size
    return None, 0.0


def segment(curve) -> Segments:
    """Segment a :class:`~adhfit.data.Curve` by row order (loading, attached, detached)."""
    i_jump, size = detect_jump(curve.force, curve.i_turn)
    return Segments(n=len(curve.x), i_turn=int(curve.i_turn), i_jump=i_jump, jump=size)
