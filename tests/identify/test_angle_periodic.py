"""Angle-periodic torque seen in the angle domain: a ripple faster than the torque equation's low-pass (and
than the logger's Nyquist frequency in time) is found with its period count, its row means agree with
quadrature, and the report says when a log cannot show a ripple."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify import diagnose
from ocp.identify.angle import angle_limits, interval_ripple
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.synthetic_rig import RigSpec, generate

RIPPLE = {"tau_sin": 0.002, "tau_cos": -0.001, "periods": 48.0}


def test_a_ripple_beyond_the_low_pass_of_a_slow_logger_is_found(rig: MotorParams) -> None:
    """48 periods/rev logged at 200 Hz: beyond the low-pass on most rows (the code before this test filtered
    it out and said nothing); found with its count and amplitude, and the same rig without it stays clean."""
    spec = RigSpec(effects={"cogging": RIPPLE}, seconds=1.5, seed=12, rate=200.0)
    res = diagnose(DCMotorPlant(rig), generate(rig, spec))
    assert res.verdict == ["cogging"]
    assert res.angle_periodic is not None and res.angle_periodic["periods"] == 48
    assert res.angle_periodic["angle"] == "logged" and "cannot show it" not in res.angle_periodic["note"]
    # found on the slow rows, though beyond the count this log resolves on half its moving rows (said, with how
    # much faster a logger would resolve them all)
    reach = res.angle_periodic["max_resolved_periods"]
    assert reach < 48 and f"more than {reach} periods/rev" in res.angle_periodic["note"]
    top = res.ranking[0]
    assert top.name == "cogging" and top.parameters["periods"] == 48
    amp = math.hypot(top.parameters["tau_sin"], top.parameters["tau_cos"])
    assert amp == pytest.approx(math.hypot(RIPPLE["tau_sin"], RIPPLE["tau_cos"]), rel=0.25)
    clean = diagnose(DCMotorPlant(rig), generate(rig, RigSpec(seconds=1.5, seed=12, rate=200.0)))
    assert clean.verdict == []


@pytest.mark.parametrize("triangle", [False, True])
def test_row_means_of_the_ripple_agree_with_quadrature(triangle: bool) -> None:
    """Closed-form row means (box over k -> k+1, or triangle over k-1 -> k+1) against a 2000-point midpoint
    rule on the linearly interpolated angle, slow rows and rows moving several periods per sample alike."""
    rng = np.random.default_rng(3)
    theta = np.cumsum(np.concatenate([[0.0], rng.uniform(-0.3, 0.9, 40), np.full(5, 1e-9)]))
    n = 17
    got_s, got_c = interval_ripple(theta, n, triangle)
    u = (np.arange(2000) + 0.5) / 2000

    def mean_over(k: int, weight: np.ndarray) -> complex:
        th = theta[k] + (theta[k + 1] - theta[k]) * u
        return complex(np.mean(weight * np.exp(1j * n * th)))

    for k in range(theta.size - 1):
        # triangle: rising over k-1 -> k (the first row: over its own interval), falling over k -> k+1
        want = mean_over(max(k - 1, 0), u) + mean_over(k, 1.0 - u) if triangle else mean_over(k, np.ones_like(u))
        assert got_s[k] == pytest.approx(want.imag, abs=1e-6)
        assert got_c[k] == pytest.approx(want.real, abs=1e-6)


def test_the_report_says_when_a_log_cannot_show_the_ripple() -> None:
    fast = np.arange(500) * 0.2  # 0.2 rad per sample: 64 periods/rev turn 2 periods per sample
    lim = angle_limits(fast, 64, logged=True)
    assert lim["rows_resolved"] == 0.0 and "cannot show it" in str(lim["note"])
    assert lim["max_resolved_periods"] == 15  # pi / 0.2
    # 64 periods/rev need a step under pi / 64 rad: 0.2 / (pi / 64) = 4.07 times faster sampling
    assert "more than 15 periods/rev" in str(lim["note"]) and "4.1 times faster" in str(lim["note"])
    slow = angle_limits(np.arange(500) * 0.01, 64, logged=False)
    assert slow["rows_resolved"] == 1.0 and "integrated from the speed" in str(slow["note"])
    assert "cannot show it" not in str(slow["note"]) and "times faster" not in str(slow["note"])  # (64 resolved)
