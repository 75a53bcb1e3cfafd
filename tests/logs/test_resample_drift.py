"""A jittered log's resampling grid (the first stamp plus the median step) and how far it runs off the rows, said in
the note (:func:`ocp.logs.timebase.drift`): the median of jittered steps is off by about ``1.25 sigma / sqrt(n)`` of a
step and the grid accumulates it. Oracle: the instants the rows were drawn at (a clock of step ``dt`` and independent
jitter), known here."""

from __future__ import annotations

import numpy as np
import pytest

from ocp.logs.timebase import DRIFT_NOTE, drift, uniform


def _clock(n: int, dt: float, jitter: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(true row instants (n,), their stamps (n,)) [s]: a clock of step ``dt`` from 0.3 s, stamps off by Gaussian
    jitter of ``jitter`` steps (clipped at three)."""
    rng = np.random.default_rng(seed)
    true = 0.3 + np.arange(n) * dt
    return true, true + dt * np.clip(rng.normal(0.0, jitter, n), -3 * jitter, 3 * jitter)


@pytest.mark.parametrize(("n", "jitter", "seed"), [(6000, 0.01, 1), (20000, 0.1, 2), (3000, 0.1, 3)])
def test_the_drift_is_the_grids_distance_from_the_true_rows(n: int, jitter: float, seed: int) -> None:
    """The drift read from the stamps alone is the median grid's worst distance from the rows' true instants, to
    within four times the fitted line's standard error at its ends (``sigma sqrt(4 / n)`` steps, with room)."""
    dt = 1e-3
    true, stamps = _clock(n, dt, jitter, seed)
    h = float(np.median(np.diff(stamps)))
    actual = float(np.max(np.abs(stamps[0] + h * np.arange(n) - true)) / h)  # [median steps], as drift's
    assert drift(stamps, h) == pytest.approx(actual, abs=4 * jitter * np.sqrt(4 / n))


def test_a_dropped_row_keeps_its_place() -> None:
    """Rows missing from a jittered log (steps of two and three): the drift counts their steps, the same as with
    them (within 0.02 steps)."""
    true, stamps = _clock(5000, 2e-3, 0.05, 4)
    keep = np.ones(true.size, dtype=bool)
    keep[[1200, 3100, 3101]] = False
    h = float(np.median(np.diff(stamps)))
    assert drift(stamps[keep], h) == pytest.approx(drift(stamps, h), abs=0.02)


def test_the_note_says_a_drift_and_only_then() -> None:
    """6,000 rows of 1 % jitter (this draw: the median step drifts 0.58 samples): the resampling's note says how far
    and that the noise levels read come out low; 600 rows of another draw of the clock (0.02 samples), no word."""
    _, stamps = _clock(6000, 1e-3, 0.01, 1)
    noise = np.random.default_rng(5).standard_normal(stamps.size)
    _, _, note = uniform(stamps, {"current": noise}, resample=True)
    assert note is not None and "up to 0.58 samples off the time stamps' own rows" in note and "come out low" in note
    short = _clock(600, 1e-3, 0.01, 3)[1]
    assert drift(short, float(np.median(np.diff(short)))) < DRIFT_NOTE
    _, _, quiet = uniform(short, {"current": noise[:600]}, resample=True)
    assert quiet is not None and "off the time stamps" not in quiet
