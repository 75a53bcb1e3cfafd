"""The nominal plant's noise-free replica of a log, and the effects that take no more of a log than of it
(:mod:`ocp.identify.replica`).

Oracle: a linear plant (drag ``c_tau`` at 1e-15, nil beside the rest) under a held command is propagated exactly,
sample to sample, by the matrix exponential of its state matrix augmented with the held input and the angle
(eq. dc_mechanical, eq. dc_electrical); the replica's integrator is RK4 on sub-steps and shares nothing with it. It
agrees to 1e-4 of each channel's range (RK4's truncation over the 0.2 ms armature time constant: 4e-5 A of 12 A after
a step).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from ocp.identify import diagnose
from ocp.identify.replica import replica
from ocp.logs import Log, log_from_arrays
from ocp.model.effects import make_effect
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.simulate.open_loop import simulate_zoh
from tests.identify.test_one_command import P

LINEAR = MotorParams(J=1e-5, B=1e-5, c_tau=1e-15, c_f=2e-6, k_t=0.01, k_e=0.01, R=0.5, L=1e-4)


def exact(p: MotorParams, t: np.ndarray, u: np.ndarray, w0: float, i0: float) -> np.ndarray:
    """(3, N) speed [rad/s], current [A], angle from 0 [rad] of the linear plant ``p`` under ``u`` (N,) [V] held
    on each sample interval of ``t`` (N,) [s], by the augmented matrix exponential."""
    a = np.zeros((4, 4))
    a[0, :3] = (-p.B / p.J, p.k_t / p.J, 0.0)  # eq. dc_mechanical
    a[1, :4] = (-p.k_e / p.L, -p.R / p.L, 0.0, 1.0 / p.L)  # eq. dc_electrical
    a[2, 0] = 1.0
    x, out = np.array([w0, i0, 0.0, u[0]]), [np.array([w0, i0, 0.0])]
    for k in range(t.size - 1):
        x[3] = u[k]
        x = expm(a * (t[k + 1] - t[k])) @ x
        out.append(x[:3].copy())
    return np.array(out).T


def logged(p: MotorParams, u: np.ndarray, dt: float, theta: bool) -> tuple[np.ndarray, Log]:
    t = np.arange(u.size) * dt
    w0 = p.k_t * u[0] / (p.B * p.R + p.k_t * p.k_e)  # (from the steady state of the first command: an encoder's
    w, i, th = exact(p, t, u, w0, p.B * w0 / p.k_t)  # differenced first speed is then the true one, as the replica's)
    f = p.c_f * w * np.abs(w)
    log = log_from_arrays(t, u, i, f, theta=th + 1.0) if theta else log_from_arrays(t, u, i, f, omega=w)
    return np.vstack([w, i, th + 1.0]), log


@pytest.mark.parametrize("theta", [False, True], ids=["tachometer", "encoder"])
def test_the_replica_is_the_plant_run_under_the_held_command(theta: bool) -> None:
    u = np.where(np.arange(400) % 100 < 50, 6.0, -2.0)
    truth, log = logged(LINEAR, u, 1e-3, theta)
    r = replica(DCMotorPlant(LINEAR), log)
    assert np.allclose(r.current, truth[1], rtol=0, atol=1e-4 * np.max(np.abs(truth[1])))
    assert np.allclose(r.thrust, LINEAR.c_f * truth[0] * np.abs(truth[0]), rtol=2e-4, atol=1e-12)
    if theta:  # the speed the log differentiated from its angle, differentiated so again
        assert r.theta is not None
        assert np.allclose(r.theta, truth[2], rtol=0, atol=1e-4 * np.ptp(truth[2]))
        assert np.allclose(r.omega, np.gradient(r.theta, log.t))
    else:
        assert r.theta is None
        assert np.allclose(r.omega, truth[0], rtol=0, atol=1e-4 * np.max(np.abs(truth[0])))


@pytest.mark.parametrize(("effect", "values"), [("coulomb_friction", {"tau_c": 2e-3}),
                                                ("current_offset", {"i0": 0.05})])
def test_a_missing_effect_on_a_noise_free_log_is_not_the_methods(effect: str, values: dict[str, float]) -> None:
    """A noise-free log of the plant WITH the effect, diagnosed against the plant without it: the effect takes far
    more of the log's held-out error than of the nominal replica's, is not taken for the method's, and is named."""
    n = 3000
    t = np.arange(n) * 1e-3
    u = 6.0 * np.sign(np.sin(2 * np.pi * 2.0 * t) + 1e-9)
    true = DCMotorPlant(P, (make_effect(effect, values),))
    x = np.asarray(simulate_zoh(true, t, u, [0.0, 0.0]).x)
    i = x[1] + values.get("i0", 0.0)  # (a current sensor's offset is in what it logs)
    log = log_from_arrays(t, u, i, P.c_f * x[0] * np.abs(x[0]), omega=x[0])
    assert diagnose(DCMotorPlant(P), log).verdict == [effect]
