"""Which rows a diagnosis fits on and which it holds out (module doc of :mod:`.diagnose`, step 2).

Every ``every``-th segment of ``segment_s`` seconds is held out (a sweep: every ``every``-th row), and under
cross-validation each class of segments in turn. The rows of a clipped current (:mod:`.clipping`) are in neither:
its readings there are the sensor's range, not the armature's current, and a free run scored on them, or an
equation fitted to them, would blame the model for the sensor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocp.identify.clipping import clipped, widened
from ocp.logs import Log, LogKind

#: the rows either side of a clipped current's that are left out too (the current sensor's lag, read at up to two
#: samples by :func:`.predict.read_current`)
CLIP_MARGIN = 2


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
