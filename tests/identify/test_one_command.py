"""A spin-up under one constant command, model-exact (session 61: found probing inputs users send; issue #11).

The first log a user takes of a new rig is often a single step: the command switched to one voltage at the start and
held. Simulated here by the catalogue's own ZOH integration (:func:`ocp.simulate.open_loop.simulate_zoh`) of the very
plant ``diagnose`` is given, so nothing is missing and the right verdict is the empty one. Without noise it is. With
the loggers' noise at a tenth of a typical level (1 mA, 0.05 rad/s) a current offset of -0.09 A is named (the
regression's held-out score falls 68 % while the free run gets worse, 0.995 -> 1.037 noise units), and at the full
level (10 mA, 0.5 rad/s) a -1 A offset and a 34 % ``c_tau``: under one command the offset is nearly collinear with
``R``, ``k`` and the drag in both equations, and only the spin-up's first rows tell them apart. A step after 25 rows
at rest (6 after the low-passes' start-up cut) is named a 0.6 V dead band (10 % of the step: a gain at the
calibration box's edge; a dead band's column counted the zero command as a second level, and with the rows at rest
counted as "off" a brush drop took its place, so the residual the drop explains is the open question); after 200
rows at rest the step comes back clean at the full level. Noise-free, every one is clean. Strict xfails: a fix
turns them into passes and the marks must go.
"""

from __future__ import annotations

import numpy as np
import pytest

from ocp.identify import diagnose
from ocp.logs import Log, log_from_arrays
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.simulate.open_loop import simulate_zoh

P = MotorParams(J=1e-5, B=1e-5, c_tau=1e-7, c_f=2e-6, k_t=0.01, k_e=0.01, R=0.5, L=1e-4)
#: the loggers' noise at scale 1: current [A], speed [rad/s], thrust [N]
NOISE = (0.01, 0.5, 1e-3)


def _log(u: np.ndarray, scale: float, dt: float = 1e-3) -> Log:
    t = np.arange(u.size) * dt
    x = np.asarray(simulate_zoh(DCMotorPlant(P), t, u, [0.0, 0.0]).x)  # (2, N): speed, current
    w, i = x[0], x[1]
    rng = np.random.default_rng(1)
    si, sw, sf = (scale * s for s in NOISE)
    return log_from_arrays(t, u, i + si * rng.standard_normal(u.size),
                           P.c_f * w * np.abs(w) + sf * rng.standard_normal(u.size),
                           omega=w + sw * rng.standard_normal(u.size))


def test_a_step_after_a_long_rest_is_clean() -> None:
    u = np.where(np.arange(2000) >= 200, 6.0, 0.0)
    assert diagnose(DCMotorPlant(P), _log(u, 1.0)).verdict == []


@pytest.mark.parametrize("rest", [0, 25])
def test_the_noise_free_step_is_clean(rest: int) -> None:
    assert diagnose(DCMotorPlant(P), _log(np.where(np.arange(2000) >= rest, 6.0, 0.0), 0.0)).verdict == []


@pytest.mark.xfail(strict=True, reason="session 61: a model-exact step log under noise gets a false name (a current "
                                       "offset under one command from the start; a dead band after 25 rows at rest)")
@pytest.mark.parametrize(("rest", "scale"), [(0, 0.1), (0, 1.0), (25, 1.0)])
def test_a_noisy_step_is_clean(rest: int, scale: float) -> None:
    assert diagnose(DCMotorPlant(P), _log(np.where(np.arange(2000) >= rest, 6.0, 0.0), scale)).verdict == []
