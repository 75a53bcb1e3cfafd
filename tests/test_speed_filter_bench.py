"""``bench/speed_filter.py``'s filter against its closed forms: a first-order low-pass of ``lag`` samples steps as
``1 - (lag / (1 + lag))^n`` and trails a ramp by ``lag`` samples (the lag the bench's tables are in); and one clean
proving-ground draw through the script's own path, unfiltered, stays clean (its table counts it)."""

from __future__ import annotations

import numpy as np
import pytest

from bench.speed_filter import filtered, one, table


@pytest.mark.parametrize("lag", [0.5, 1.0, 3.0])
def test_the_filter_steps_and_trails_a_ramp_as_its_closed_form(lag: float) -> None:
    n = np.arange(400)
    step = filtered(np.where(n > 0, 1.0, 0.0), lag)
    np.testing.assert_allclose(step, 1.0 - (lag / (1.0 + lag)) ** n, rtol=0, atol=1e-12)
    ramp = n.astype(float)
    assert ramp[-1] - filtered(ramp, lag)[-1] == pytest.approx(lag, abs=1e-9)


def test_no_lag_leaves_the_speed_as_logged() -> None:
    w = np.random.default_rng(3).normal(size=50)
    out = filtered(w, 0.0)
    np.testing.assert_array_equal(out, w)
    assert out is not w


def test_an_unfiltered_clean_draw_stays_clean() -> None:
    row = one((3000, 0.0, "clean", None))
    assert row[:3] == (3000, 0.0, []) and row[3] == []
    assert table([row]).splitlines()[1].split()[:3] == ["0", "1/1", "0/1"]
