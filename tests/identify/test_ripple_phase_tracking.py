"""A ripple along an angle integrated from a noisy speed: its phase tracked knot by knot (issue #11, session 10).

Proving-ground tuning draw ``make_case(1182)`` (a tuning seed, not one of the reported 0..199): a 17.6 s, 200 Hz log
with a tachometer (no angle column) and a 3-periods/rev torque ripple. The angle integrated from the speed drifts
as a random walk (the ripple's phase by ~6 rad over the log), so one phase over the whole log explained 3 % of the
torque residual held out and the ripple was not named. Tracked between knots a drift variance apart (one amplitude,
the phase fitted per knot on training rows), it explains ~40 % and is named at its period count.
"""

from __future__ import annotations

import numpy as np

from ocp.identify import diagnose
from ocp.identify.angle import DRIFT_SPAN, drift_windows, track_phase
from ocp.identify.noise_level import white_noise
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def test_a_ripple_on_a_tachometer_log_is_named() -> None:
    case = make_case(1182)
    assert case.expected == {"cogging"} and case.logger.speed == "tacho" and "theta" not in case.columns
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"])
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert res.verdict == ["cogging"]
    assert res.angle_periodic is not None and res.angle_periodic["periods"] == 3


def test_drift_windows_and_phase_tracking() -> None:
    rng = np.random.default_rng(3)
    dt, m = 0.005, 3000
    t = np.arange(m) * dt
    assert drift_windows(t, 3, 0.01, dt).shape == (m, 1)  # drift within one phase: one column of ones
    h = drift_windows(t, 3, 3.5, dt)  # 0.55 rad^2/s over 15 s: pieces of at least DRIFT_SPAN
    assert 2 < h.shape[1] <= 1 + int(t[-1] / DRIFT_SPAN) and np.allclose(h.sum(axis=1), 1.0)
    assert abs(white_noise(np.sin(t) + 0.2 * rng.standard_normal(m)) - 0.2) < 0.02  # white noise, not the sine
    theta = 40.0 * t  # the integrated angle; the true one drifts from it by a slow phase
    drift = 2.0 * np.sin(2 * np.pi * t / t[-1])
    z = np.exp(3j * theta)
    resid = 0.1 * np.cos(3 * theta + drift) + 0.01 * rng.standard_normal(m)
    train = (np.arange(m) // 100) % 3 != 2
    turned = z * track_phase(z, h, resid, train)
    one = np.linalg.lstsq(np.column_stack([z.real, z.imag]), resid, rcond=None)[1][0]
    tracked = np.linalg.lstsq(np.column_stack([turned.real, turned.imag]), resid, rcond=None)[1][0]
    assert tracked < 0.2 * one  # one phase leaves most of the ripple; tracked, little of it
