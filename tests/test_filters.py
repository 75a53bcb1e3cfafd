"""ocp.filters against scipy.signal (the oracle): the IIR recursion from rest and from a steady state, zero-phase
filtering with odd padding, the Butterworth design and the zero-order-hold transfer functions."""

from __future__ import annotations

from typing import Literal

import numpy as np
import pytest
from scipy import signal

from ocp.filters import butter2, filtfilt, iir, zoh_transfer


def _close(a: np.ndarray, b: np.ndarray, rel: float) -> bool:
    return bool(np.max(np.abs(a - b)) <= rel * np.max(np.abs(b)))


@pytest.mark.parametrize("wn", [0.02, 0.2, 0.8])
def test_the_butterworth_design_and_its_filters_match_scipy(wn: float) -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(3000, 3)).cumsum(axis=0)  # (a random walk: low frequencies dominate, as in a log)
    b, a = butter2(wn)
    b0, a0 = signal.butter(2, wn)
    assert np.allclose(b, b0, rtol=1e-13, atol=0) and np.allclose(a, a0, rtol=1e-13, atol=1e-15)
    assert _close(iir(b, a, x), signal.lfilter(b, a, x, axis=0), 1e-12)
    zi = signal.lfilter_zi(b, a)[:, None] * x[0]
    assert _close(iir(b, a, x, start=x[0]), signal.lfilter(b, a, x, axis=0, zi=zi)[0], 1e-12)
    for padlen in (0, 9):
        assert _close(filtfilt(b, a, x, padlen=padlen), signal.filtfilt(b, a, x, axis=0, padlen=padlen), 1e-12)
    one = filtfilt(b, a, x[:, 1], padlen=9)
    assert one.shape == (3000,) and _close(one, signal.filtfilt(b, a, x[:, 1], padlen=9), 1e-12)


def test_first_order_lags_as_the_identification_uses_them() -> None:
    """The armature's lag from rest (a delayed input: b0 = 0), a sensor's filter from the steady state at each
    segment's first row (a scalar or one start per column), the speed view's forward-backward pass."""
    rng = np.random.default_rng(2)
    x = rng.normal(size=(500, 4))
    p = 0.8
    assert _close(iir([0.0, 1 - p], [1.0, -p], x), signal.lfilter([0.0, 1 - p], [1.0, -p], x, axis=0), 1e-13)
    a = 1.0 / 1.7
    want = signal.lfilter([a], [1.0, a - 1.0], x.T, axis=1, zi=(1.0 - a) * x.T[:, :1])[0].T
    assert _close(iir([a], [1.0, a - 1.0], x, start=x[0]), want, 1e-13)
    assert _close(iir([a], [1.0, a - 1.0], x[:, 2], start=float(x[0, 2])), want[:, 2], 1e-13)
    q = np.exp(-0.1)
    assert _close(filtfilt([1 - q], [1.0, -q], x), signal.filtfilt([1 - q], [1.0, -q], x, axis=0, padlen=0), 1e-13)


def test_the_backward_pass_is_the_filter_run_on_the_reversed_record() -> None:
    """``iir(..., backward=True)`` (an upper triangular solve) against ``lfilter`` on ``x[::-1]``, reversed back, from
    rest and from the steady state at the last row; and on a record shorter than the filter's order."""
    rng = np.random.default_rng(3)
    x = rng.normal(size=(400, 2))
    b, a = [0.2, 0.3, -0.1], [1.0, -0.5, 0.1]
    rev = signal.lfilter(b, a, x[::-1], axis=0)[::-1]
    assert _close(iir(b, a, x, backward=True), rev, 1e-13)
    zi = signal.lfilter_zi(b, a)[:, None] * x[-1]
    assert _close(iir(b, a, x, start=x[-1], backward=True), signal.lfilter(b, a, x[::-1], axis=0, zi=zi)[0][::-1],
                  1e-13)
    short = x[:1]
    want = signal.lfilter(b, a, short, axis=0, zi=signal.lfilter_zi(b, a)[:, None] * short[0])[0]
    assert _close(iir(b, a, short, start=short[0], backward=True), want, 1e-13)


def test_a_constant_from_its_steady_state_stays_constant() -> None:
    """Closed form: from the steady state of a constant, every output is the DC gain times it."""
    b, a = butter2(0.1)
    assert np.allclose(iir(b, a, np.full(50, 2.5), start=2.5), 2.5, rtol=1e-12)
    assert np.allclose(iir([0.3, 0.1], [1.0, -0.5], np.full(20, 1.0), start=1.0), 0.4 / 0.5, rtol=1e-12)


@pytest.mark.parametrize("delay", [2e-4, 3e-3])
def test_zero_order_hold_transfer_functions_match_cont2discrete_and_ss2tf(delay: float) -> None:
    """The input delay's Pade states (ocp.model.stateful_effects) and a thrust lag's one state."""
    dt = 1e-3
    for a, b in ((np.array([[0.0, 1.0], [-12.0 / delay**2, -6.0 / delay]]), np.array([0.0, 1.0])),
                 (np.array([[-1.0 / delay]]), np.array([1.0 / delay]))):
        n = a.shape[0]
        ad, bd, *_ = signal.cont2discrete((a, b.reshape(n, 1), np.eye(n), np.zeros((n, 1))), dt, method="zoh")
        for j, (num, den) in enumerate(zoh_transfer(a, b, dt)):
            num0, den0 = signal.ss2tf(ad, bd, np.eye(n)[j:j + 1], np.zeros((1, 1)))
            assert np.allclose(num, np.squeeze(num0), rtol=1e-9, atol=1e-12 * np.max(np.abs(num0)))
            assert np.allclose(den, den0, rtol=1e-12, atol=1e-15)


def test_a_pad_as_long_as_the_record_is_refused() -> None:
    with pytest.raises(ValueError, match="padlen"):
        filtfilt([1.0], [1.0, -0.5], np.ones(5), padlen=5)
    with pytest.raises(ValueError, match="cut-off"):
        butter2(1.0)


@pytest.mark.parametrize("order", ["C", "F"])
def test_the_input_is_left_alone_unless_it_may_be_overwritten(order: Literal["C", "F"]) -> None:
    """``iir``/``filtfilt`` without ``overwrite`` never change ``x`` (a first-order filter, all its numerator's later
    taps zero, is the case that filters in place); with it, the same result, ``x``'s buffer reused where its columns
    are contiguous."""
    x = np.asarray(np.random.default_rng(5).standard_normal((400, 3)), order=order)
    keep = x.copy()
    q = 0.93
    want = signal.filtfilt([1 - q], [1.0, -q], x, axis=0, padlen=0)
    assert _close(filtfilt([1 - q], [1.0, -q], x), want, 1e-13) and np.array_equal(x, keep)
    assert _close(iir([1 - q], [1.0, -q], x, start=x[0]), signal.lfilter([1 - q], [1.0, -q], x, axis=0,
                                                                            zi=signal.lfilter_zi([1 - q], [1.0, -q])
                                                                            * x[:1])[0], 1e-13)
    assert np.array_equal(x, keep)
    got = filtfilt([1 - q], [1.0, -q], x, overwrite=True)
    assert _close(got, want, 1e-13)
    assert np.shares_memory(got, x) == (order == "F")
    one = keep[:, 0].copy()
    assert _close(filtfilt([1 - q], [1.0, -q], one, overwrite=True), want[:, 0], 1e-13)
