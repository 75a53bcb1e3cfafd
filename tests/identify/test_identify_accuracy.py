"""Model-check accuracy on effects below the differentiated speed's noise: the torque equation is judged by
the speed error it causes (:func:`ocp.identify.regression.speed_view`), its weight floored at what a free run
can show (:func:`ocp.identify.regression.visible_torque`), and proving-ground logs of the classes this fixed
(seeds from the tuning range 1000..1099; the benchmark reports 0..199)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify import diagnose
from ocp.identify.explain import explain
from ocp.identify.regression import Signals, speed_view, visible_torque
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def test_speed_view_has_unit_dc_gain_and_the_rotors_squared_roll_off() -> None:
    """Closed form: forward-backward first order, |H(w)|^2 = 1 / (1 + (w tau)^2) (away from the ends)."""
    dt, tau, n = 1e-3, 0.05, 40_000
    t = np.arange(n) * dt
    assert np.allclose(speed_view(np.full(n, 3.0), dt, tau)[n // 4:3 * n // 4], 3.0, rtol=1e-9)
    for f in (2.0, 10.0, 40.0):
        w = 2 * math.pi * f
        y = speed_view(np.sin(w * t), dt, tau)[n // 4:3 * n // 4]
        a = math.exp(-dt / tau)  # the discrete filter's exact gain at this frequency
        h2 = (1 - a) ** 2 / abs(1 - a * np.exp(-1j * w * dt)) ** 2
        assert np.sqrt(2 * np.mean(y * y)) == pytest.approx(h2, rel=2e-3)
        assert h2 == pytest.approx(1 / (1 + (w * tau) ** 2), rel=0.05)  # the rotor's, sampled


def test_speed_view_keeps_a_narrow_columns_tails_out_of_the_subnormal_range() -> None:
    """A hat column (nonzero on 200 of 20,000 rows) seen through the plain forward-backward filter
    (:func:`ocp.filters.filtfilt`, itself held to scipy's in ``tests/test_filters.py``) leaves tails decaying through
    the subnormal range (slow arithmetic); :func:`speed_view` gives the same view to within 1e-146 of the column's peak
    without one subnormal value, column by column as for each alone, and a zero column stays zero."""
    from ocp.filters import filtfilt

    dt, tau, n = 1e-3, 0.005, 20_000
    hat = np.clip(1.0 - np.abs(np.arange(n) - 5_000.0) / 100.0, 0.0, None) * 3e-3  # [N m]
    y = np.column_stack([hat, np.zeros(n), np.roll(hat, 9_000)])
    a = math.exp(-dt / tau)
    plain = filtfilt([1.0 - a], [1.0, -a], y)
    tiny = np.finfo(float).tiny

    def subnormal(x: np.ndarray) -> int:
        return int(np.sum((x != 0) & (np.abs(x) < tiny)))

    assert subnormal(plain) > 1000  # (the case this guards against)
    view = speed_view(y, dt, tau)
    assert view.shape == y.shape and view.flags.c_contiguous
    assert subnormal(view) == 0
    assert np.max(np.abs(view - plain)) <= 1e-146 * np.max(np.abs(hat))
    assert np.all(view[:, 1] == 0.0)
    assert np.array_equal(view[:, 0], speed_view(hat, dt, tau))


def test_visible_torque_is_the_steady_state_sensitivity(rig: MotorParams) -> None:
    """Oracle: solve the steady state (k_t i = B w + c_tau w^2 + dtau, V = R i + k_e w) with and without a
    small torque error dtau and compare the speed and current shifts with the noise levels."""
    w0 = 80.0
    s = Signals(*(np.full(10, w0),) * 2, *(np.ones(10),) * 2, np.full(10, w0), np.ones(10), np.ones(10),
                np.ones(10), None, np.arange(10.0), 1e-3)

    def steady(v: float, dtau: float) -> tuple[float, float]:
        def f(w: float) -> float:  # eq. dc_mechanical at w' = 0 with i from eq. dc_electrical at i' = 0
            return rig.k_t * (v - rig.k_e * w) / rig.R - rig.B * w - rig.c_tau * w * w - dtau
        lo, hi = 0.0, v / rig.k_e
        for _ in range(200):
            lo, hi = ((lo + hi) / 2, hi) if f((lo + hi) / 2) > 0 else (lo, (lo + hi) / 2)
        return lo, (v - rig.k_e * lo) / rig.R

    v = rig.R * (rig.B * w0 + rig.c_tau * w0 * w0) / rig.k_t + rig.k_e * w0
    dtau = 1e-6
    (wa, ia), (wb, ib) = steady(v, 0.0), steady(v, dtau)
    noise = {"omega": 0.5, "current": 1e3, "thrust": 1e3}  # the speed channel decides
    assert visible_torque(rig, s, noise) == pytest.approx(0.5 * dtau / abs(wb - wa), rel=0.02)
    noise = {"omega": 1e3, "current": 0.01, "thrust": 1e3}  # the current channel decides
    assert visible_torque(rig, s, noise) == pytest.approx(0.01 * dtau / abs(ib - ia), rel=0.02)


def test_a_challengers_out_of_range_fit_is_words_not_a_crash(rig: MotorParams) -> None:
    text = explain("stribeck", {"tau_s": 1e6, "omega_s": 3.0}, rig, None, None)  # type: ignore[arg-type]
    assert "outside its physical range" in text and "tau_s" in text


@pytest.mark.parametrize("seed", [1001, 1020, 1091, 1022])
def test_proving_ground_effects_below_the_derivative_noise(seed: int) -> None:
    """Coulomb friction on a 500 Hz staircase sweep (0.065 N m under 0.08 N m of differentiated-speed noise),
    drag asymmetry under PI tracking, Stribeck friction on a 100 Hz ramp, and a clean 10 kHz log (no false
    alarm): each verdict exactly right."""
    case = make_case(seed)
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert set(res.verdict) == set(case.expected), (case.kind, case.excitations, res.verdict)
