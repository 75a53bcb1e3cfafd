"""A thrust lag is a wake's only beyond what logger timing explains (issue #11, session 34).

To first order a first-order lag ``tau`` leaves ``-tau F'`` in the thrust map, and so does a speed read ``tau / dt``
samples late (the ``speed_lag`` nuisance, at most two samples). Where the alignment left a PRBS log's armature
equation with a sub-sample timing error, ``speed_lag`` went to its bound there and the thrust map's disagreement
with it was named ``thrust_lag``, fitted at the grid's shortest time constant under a unit coefficient: 1.5-1.8
samples (proving-ground 14000, a cogging log at 2 kHz, with and without its angle column; 23196 likewise). Of 40
drawn wake lags the shortest, four samples at 50-100 Hz, came out at 3.3-3.9 (:func:`ocp.identify.explain.wake_lag`).
"""

from __future__ import annotations

import sys
from typing import Any

import pytest

from tests.identify.diagnosed import diagnosed


def _diagnose(seed: int, angle: bool, monkeypatch: pytest.MonkeyPatch) -> tuple[Any, list[str], float]:
    """The case, its verdict and the final model's thrust lag in samples (sum of coefficient x tau over dt)."""
    case, res, design, final = diagnosed(seed, angle, monkeypatch)
    lag = sum(design.columns[j].shape * final.coefficient(j) for j in design.index("thrust_lag"))
    return case, res.verdict, lag * case.logger.rate


@pytest.mark.parametrize("angle", [True, False])
def test_a_lag_within_the_speed_sensors_reach_is_no_wake(angle: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    case, verdict, _ = _diagnose(14000, angle, monkeypatch)
    assert case.expected == {"cogging"} and verdict == ["cogging"]


def test_without_the_rule_the_timing_was_named_a_wake(monkeypatch: pytest.MonkeyPatch) -> None:
    """The guard: the same log with every thrust lag let through names one, shorter than two samples."""
    monkeypatch.setattr(sys.modules["ocp.identify.explain"], "wake_lag", lambda design, f: True)
    _, verdict, lag = _diagnose(14000, False, monkeypatch)
    assert "thrust_lag" in verdict and 0.0 < lag < 2.0


def test_a_drawn_wake_of_four_samples_is_still_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """Oracle: the rig's drawn time constant (proving-ground 23042: 50 Hz, a wake of 80 ms = 4 samples)."""
    case, verdict, lag = _diagnose(23042, True, monkeypatch)
    drawn = case.truth.e("thrust_lag", "tau", 0.0) * case.logger.rate
    assert "thrust_lag" in case.expected and sorted(verdict) == sorted(case.expected)
    assert drawn == pytest.approx(4.0, abs=0.2) and lag == pytest.approx(drawn, rel=0.2)
