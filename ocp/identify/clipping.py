"""A channel clipped at its sensor's range: an ADC's full scale, a Hall sensor's saturation (issue #11: logs from
rigs this project did not build).

A current sensor ranged for the stall current clips the spikes of a hard reversal; the clipped rows are no armature
current the equations can use, and the torque residual they leave at every reversal was named an angle ripple, a
dead band or a ``J`` error (blind rig, ``bench/blind_check.py``, seeds 0..199: its current ADC clips on 30 logs, and
six of the seven false ripples were among them; five are detected here, and four of those are now right).

A clipped channel piles up at its extreme value: rows at exactly its top (or bottom) value, many more of them than
rows just below it, where a channel that merely peaks touches its extreme once, or sits just under it as often as
on it. Those rows, and the low-pass's transient around them, are left out of every equation; ``diagnose`` says so
among the blind spots.
"""

from __future__ import annotations

import numpy as np

from ocp.identify.columns import runs

#: at least this many consecutive rows at the extreme value (a clipped spike stays beyond the range for a while; a
#: coarsely quantised peak of a slow log touched its top level at most twice in a row on the proving ground's 1,000
#: logs, seed 114: four rows at 100 Hz, none of them clipped)
CLIP_RUN = 3
#: ... and this many times the rows near it (within :data:`NEAR` of the channel's range, or 2.5 quantisation steps,
#: whichever is wider) that are not at it: a pile-up
PILE_UP = 3.0
NEAR = 0.01


def clipped(x: np.ndarray) -> np.ndarray:
    """Rows (N,) of ``x`` (N,) that sit at its top or bottom value where the channel piles up there (module doc)."""
    out = np.zeros(x.size, dtype=bool)
    ok = np.isfinite(x)
    levels = np.unique(x[ok])
    if ok.sum() < 10 * CLIP_RUN or levels.size < 3:
        return out
    top, bottom = float(levels[-1]), float(levels[0])
    near = max(NEAR * (top - bottom), 2.5 * float(np.median(np.diff(levels))))  # (quantisation: the step)
    for ext in (top, bottom):
        at = x == ext
        below = ok & ~at & (np.abs(x - ext) < near)
        if max((b - a for a, b in runs(at)), default=0) >= CLIP_RUN and at.sum() >= PILE_UP * below.sum():
            out |= at
    return out


def widened(mask: np.ndarray, rows: int) -> np.ndarray:
    """``mask`` (N,) with ``rows`` rows on either side of each set row set too."""
    if rows <= 0 or not mask.any():
        return mask.copy()
    return np.convolve(mask.astype(float), np.ones(2 * rows + 1), mode="same") > 0.5


def clip_spot(current: np.ndarray) -> dict[str, object] | None:
    """The blind-spot entry (:func:`.coverage.blind_spots`' form) for a clipped ``current`` (N,) [A], or None."""
    m = clipped(current)
    if not m.any():
        return None
    level = float(np.max(np.abs(current[m])))
    return {"gap": "clipped_current", "hidden": [], "design": False,
            "text": f"the current is clipped at {level:.4g} A on {int(m.sum())} rows ({100 * m.mean():.2g} % of the "
                    "log: the sensor's range); those rows, and the low-pass's transient around them, are left out of "
                    "every equation (a sensor with a wider range shows them)"}
