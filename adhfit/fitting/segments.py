"""Row-order segments of a measured curve: the end of loading and a detected detachment jump.

The end of loading is the largest control value (first occurrence); the jump is found by a threshold
on the force steps (:func:`detect_jump`).  The fit no longer relies on the jump detector (the model's
free split decides which rows are detached, see :mod:`.model`); it remains a first guess for reports
and the container of the fixed split the second fit stage uses.

A dense log (a 100 Hz machine writes 10^4-10^6 rows a test) is averaged in bins of consecutive rows
before a fit (:func:`thin`), each segment apart.  The model is smooth on the scale of a bin, so the
bins' means carry the rows' information on every fitted parameter (for a model linear across a bin,
exactly: the mean is the sufficient statistic) at the cost of a ~2,000-row fit; what a bin cannot
carry, the loading end and the pull-off gap, is kept from the rows as read (:class:`adhfit.data.Binning`).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

__all__ = ["Segments", "segment", "detect_jump", "thin", "JUMP_FRACTION", "JUMP_NOISE", "THIN_ABOVE", "THIN_BINS"]

#: a jump must exceed this fraction of the most negative force ...
JUMP_FRACTION = 0.3
#: ... and this many robust standard deviations of the row-to-row force changes
JUMP_NOISE = 6.0
#: curves with more rows than this are averaged in bins of consecutive rows before a fit ...
THIN_ABOVE = 6000
#: ... about this many bins (every bin holds k or k + 1 rows, k >= 3: variances within 4/3 of each other)
THIN_BINS = 2000


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
    """Segment a :class:`~adhfit.data.Curve` by row order (loading, attached, detached).

    A thinned curve keeps the jump found on its rows as read (:func:`thin`: no bin straddles it).
    """
    binning = getattr(curve, "binning", None)
    if binning is not None:
        j = binning.i_jump
        size = 0.0 if j is None else float(abs(curve.force[j] - curve.force[j - 1]))
        return Segments(n=len(curve.x), i_turn=int(curve.i_turn), i_jump=j, jump=size)
    i_jump, size = detect_jump(curve.force, curve.i_turn)
    return Segments(n=len(curve.x), i_turn=int(curve.i_turn), i_jump=i_jump, jump=size)


def _bin_means(a: np.ndarray | None, starts: np.ndarray, size: np.ndarray) -> np.ndarray | None:
    """Mean of each bin of consecutive rows (NaN-aware: a bin without a finite value is NaN)."""
    if a is None:
        return None
    a = np.asarray(a, float)
    finite = np.isfinite(a)
    if finite.all():
        return np.add.reduceat(a, starts) / size
    count = np.add.reduceat(finite.astype(float), starts)
    total = np.add.reduceat(np.where(finite, a, 0.0), starts)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1.0), np.nan)


def thin(curve, *, above: int = THIN_ABOVE, bins: int = THIN_BINS):
    """Average a dense curve in bins of consecutive rows; ``(curve, None)`` when it has ``above`` rows or fewer.

    The loading rows, the unloading rows before the detected jump and the rows after it are binned
    apart (k or k + 1 rows a bin, k = rows // ``bins``), so no bin mixes an attached and a detached
    membrane.  Control, force, time and contact radius become their bin means (rows in bins are
    nearly equal in number: their variances are within (k + 1)/k); a drift in row order uses each
    bin's mean row.  The loading end and the pull-off gap are kept from the rows as read
    (:class:`adhfit.data.Binning`): the model loads to the largest measured control value and the
    censored pull-off term brackets the turning point between two rows as read.

    Returns
    -------
    (curve, note) : (adhfit.data.Curve, str or None)
        The thinned curve, and the sentence for the report.
    """
    from ..data import Binning  # noqa: PLC0415
    n = len(curve.x)
    if n <= above or curve.binning is not None:
        return curve, None
    k = max(3, n // bins)
    seg = segment(curve)
    cuts = sorted({0, seg.i_turn + 1, n if seg.i_jump is None else seg.i_jump, n})
    starts, first_bin = [], {}
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        nb = max(1, (hi - lo) // k)
        first_bin[lo] = len(starts)
        starts.extend(lo + (np.arange(nb) * (hi - lo)) // nb)
    starts = np.asarray(starts, int)
    size = np.diff(np.append(starts, n))
    row = starts + (size - 1) / 2.0
    i_turn = first_bin[seg.i_turn + 1] - 1 if seg.i_turn + 1 < n else len(starts) - 1
    x = np.asarray(curve.x, float)
    i_jump = gap = None
    if seg.i_jump is not None:
        i_jump, gap = first_bin[seg.i_jump], (float(x[seg.i_jump - 1]), float(x[seg.i_jump]))
    binning = Binning(rows=n, size=size, row=row, x_max=float(x[seg.i_turn]), i_jump=i_jump, gap=gap)
    thinned = dataclasses.replace(
        curve, x=_bin_means(x, starts, size), force=_bin_means(curve.force, starts, size),
        line=np.asarray(curve.line)[starts], i_turn=i_turn, time=_bin_means(curve.time, starts, size),
        contact_radius=_bin_means(curve.contact_radius, starts, size), binning=binning)
    note = (f"{n:,} rows fitted as {len(starts):,} bins of {size.min()}-{size.max()} consecutive rows (their "
            "means; loading, attached and detached rows binned apart, the loading end and the pull-off gap kept "
            "from the rows as read): the bins carry the rows' information on W_ad and μh at a fraction of the cost; "
            "residuals, noise levels and plots are per bin")
    return thinned, note
