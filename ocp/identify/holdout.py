"""Which rows a diagnosis fits on and which it holds out (module doc of :mod:`.diagnose`, step 2).

Every ``every``-th segment of ``segment_s`` seconds is held out (a sweep: every ``every``-th row), and under
cross-validation each class of segments in turn. The rows of a clipped current (:mod:`.clipping`) are in neither:
its readings there are the sensor's range, not the armature's current, and a free run scored on them, or an
equation fitted to them, would blame the model for the sensor. Where so few rows are left that neither a noise level
nor a held-out score can be measured, :func:`usable` says so instead of a verdict.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocp.errors import LogError
from ocp.identify.clipping import clipped, widened
from ocp.logs import Log, LogKind

#: the rows either side of a clipped current's that are left out too (the current sensor's lag, read at up to two
#: samples by :func:`.predict.read_current`)
CLIP_MARGIN = 2
#: the fewest rows the equations are fitted on, and held out on (:func:`usable`): a noise level is the standard
#: deviation of the training residuals and the score a mean over the held-out rows, each within about
#: ``1 / sqrt(2 n)`` of its value from ``n`` rows (13 % at 30)
MIN_ROWS = 30


@dataclass(frozen=True)
class Split:
    """Training and held-out masks (N,); ``folds``: cross-validation's held-out masks (empty: one split)."""

    train: np.ndarray
    test: np.ndarray
    folds: tuple[np.ndarray, ...] = ()


def split(log: Log, segment_s: float, every: int, cross: bool = False) -> Split:
    """Every ``every``-th segment (row for sweeps) held out; ``cross``: and as folds, each class in turn; a clipped
    current's rows in none (module doc)."""
    length = 1 if log.kind is LogKind.STEADY_STATE else max(2, round(segment_s / log.dt))
    cls = (np.arange(log.n) // length) % every
    cls[widened(clipped(log.current), CLIP_MARGIN)] = every  # (no class)
    test = cls == every - 1
    return Split((cls < every) & ~test, test, tuple(cls == k for k in range(every)) if cross else ())


def usable(train: np.ndarray, test: np.ndarray, edge: np.ndarray, current: np.ndarray,
           margin: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The training and held-out masks (M,) without the rows ``edge`` (M,) (the low-passes' transients at the ends)
    and a clipped ``current``'s (M,) [A] with ``margin`` rows either side (their transient), and those rows (M,).
    Raises :class:`ocp.errors.LogError` where fewer than :data:`MIN_ROWS` are left in either mask (a 50 Hz PRBS log
    clipped on a quarter of its rows kept none, and its noise levels came out NaN: proving ground 23018, clipped at
    45 % of its peak by ``bench/clipped_current.py``)."""
    at_range = clipped(current)
    cut = edge | widened(at_range, margin)
    train, test = train & ~cut, test & ~cut
    fit, held = int(train.sum()), int(test.sum())
    if min(fit, held) >= MIN_ROWS:
        return train, test, cut
    n = int(at_range.sum())
    why = (f"the current is clipped at its sensor's range on {n} of {current.size} rows; those rows and the "
           "low-pass's transient around them are left out" if n else
           "the low-passes' start-up and run-out transients are left out")
    raise LogError("current" if n else "t",
                   f"{why}, and {fit} rows remain to fit on and {held} to hold out, fewer than {MIN_ROWS}: nothing "
                   "can be checked (" + ("a current sensor ranged above the reversal spikes, or " if n else "")
                   + "a longer log)")
