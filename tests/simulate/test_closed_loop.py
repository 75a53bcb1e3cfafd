"""Closed-loop simulator of the Section V controller, checked against independent oracles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.errors import MissionError
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.reference.analytic import SinProfile, reference, time_grid
from ocp.simulate.closed_loop import GainUnit, PaperController, lowpass_coefficient, reversal_times, track
from ocp.simulate.open_loop import simulate_zoh


def test_lowpass_step_response_matches_the_closed_form_exponential() -> None:
    """y[k] of the discretised filter equals 1 - exp(-k dt / tau) for a unit step (to rounding)."""
    dt = 1e-3
    for tau in (3e-3, 0.02, 1.0 / (2.0 * math.pi * 15.0)):
        a = lowpass_coefficient(tau, dt)
        y, ys = 0.0, []
        for _ in range(200):
            y += a * (1.0 - y)
            ys.append(y)
        k = np.arange(1, 201)
        np.testing.assert_allclose(ys, 1.0 - np.exp(-k * dt / tau), rtol=0, atol=1e-12)
    assert lowpass_coefficient(0.0, dt) == 1.0


def test_zero_gains_reduce_to_the_open_loop_zoh_simulation(rig: MotorParams) -> None:
    """With every gain zero and quantisation off, the loop is the open-loop ZOH plant under the feedforward.

    Both integrate with 10 RK4 sub-steps per 1 ms sample (max_substep slightly above 0.1 ms so rounding of
    dt cannot make it 11), so they agree to rounding.
    """
    plant = DCMotorPlant(rig)
    t = time_grid(0.5, 1000.0)
    volts = 3.0 + 2.0 * np.sin(2 * np.pi * 3.0 * t)
    ctrl = PaperController(kp=0.0, ki=0.0, kd=0.0, kp_f=0.0, ki_f=0.0, quantise=False, substeps=10)
    res = track(plant, t, np.zeros_like(t), np.zeros_like(t), np.zeros_like(t), ctrl, feedforward=volts, x0=(0.0, 0.0))
    ref = simulate_zoh(plant, t, volts, (0.0, 0.0), max_substep=1.001e-4)
    np.testing.assert_allclose(res.voltage, volts, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.omega, ref.state("omega"), rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.current, ref.state("current"), rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.theta, ref.theta, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.thrust, ref.thrust, rtol=0, atol=1e-12)


def test_exact_midpoint_feedforward_tracks_a_slow_reference(rig: MotorParams) -> None:
    """Quantisation off, exact voltage feedforward sampled mid-interval: the ZOH error is O(dt^2 V'').

    For A sin^5 (T = 4 s, A = 0.4 N) the speed error stays below 1e-4 rad/s (0.0002 % of the 44 rad/s peak).
    """
    plant = DCMotorPlant(rig)
    prof = SinProfile(0.4, 4.0, 2)
    t = time_grid(4.0, 1000.0)
    ref = reference(prof, rig, t)
    ff = reference(prof, rig, t + 0.5e-3).voltage
    res = track(plant, t, ref.thrust, ref.omega, ref.theta, PaperController(quantise=False), feedforward=ff)
    assert np.max(np.abs(res.speed_error)) < 1e-4
    assert res.metrics.thrust_rms < 1e-6


def test_quantisation_and_saturation_are_never_exceeded(rig: MotorParams) -> None:
    """Gains read as volts make the loop saturate hard: |V| <= 12 V and V is a whole number of counts."""
    plant = DCMotorPlant(rig)
    prof = SinProfile(0.59, 1.5, 0)
    t = time_grid(1.5, 1000.0)
    ref = reference(prof, rig, t)
    ctrl = PaperController(gain_unit=GainUnit.VOLTS)
    res = track(plant, t, ref.thrust, ref.omega, ref.theta, ctrl)
    assert res.saturated.any()
    assert np.max(np.abs(res.voltage)) <= 12.0
    counts = res.voltage / ctrl.volts_per_count
    np.testing.assert_allclose(counts, np.round(counts), rtol=0, atol=1e-9)
    assert np.max(np.abs(counts)) <= 2048
    assert ctrl.volts_per_count == pytest.approx(5.86e-3, abs=5e-6)


def test_case_1_reversal_peaks_are_localised(rig: MotorParams) -> None:
    """A sin (linear reversal): local speed error near each reversal is a large share of the speed peak."""
    plant = DCMotorPlant(rig)
    prof = SinProfile(0.59, 1.5, 0)
    t = time_grid(3.0, 1000.0)
    ref = reference(prof, rig, t)
    m = track(plant, t, ref.thrust, ref.omega, ref.theta).metrics
    np.testing.assert_allclose(m.reversal_times, [0.75, 1.5, 2.25], atol=1e-9)
    assert m.local_speed_error > 0.3 * float(np.max(np.abs(ref.omega)))
    assert m.local_speed_error > 2.0 * m.speed_rms


def test_reference_on_another_grid_is_resampled_onto_the_controller_grid(rig: MotorParams) -> None:
    plant = DCMotorPlant(rig)
    t = time_grid(0.2, 2000.0)
    ref = reference(SinProfile(0.3, 1.0, 2), rig, t)
    res = track(plant, t, ref.thrust, ref.omega, ref.theta)
    np.testing.assert_allclose(np.diff(res.t), 1e-3, rtol=1e-9)
    np.testing.assert_allclose(res.thrust_ref, ref.thrust[::2], rtol=0, atol=1e-12)


def test_reversal_times_between_samples_are_interpolated() -> None:
    t = np.linspace(0.0, 1.0, 11)
    f = t - 0.33
    assert reversal_times(t, f) == pytest.approx((0.33,))


def test_bad_input_names_the_field(rig: MotorParams) -> None:
    plant = DCMotorPlant(rig)
    t = time_grid(0.1, 1000.0)
    z = np.zeros_like(t)
    with pytest.raises(MissionError, match="omega_ref"):
        track(plant, t, z, z[:-1], z)
    with pytest.raises(MissionError, match="thrust_ref"):
        track(plant, t, np.full_like(t, np.nan), z, z)
    with pytest.raises(MissionError, match=r"controller\.kp"):
        PaperController(kp=-1.0)
    with pytest.raises(MissionError, match=r"controller\.substeps"):
        PaperController(substeps=0)
