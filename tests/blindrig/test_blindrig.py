"""Self-checks of the blind rig's simulator against independent oracles (closed forms, matrix exponential)."""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

from blindrig.draw import EFFECTS, PARAMS, draw_case
from blindrig.excite import Excitation, make_excitation
from blindrig.logger import LoggerConfig, run_log
from blindrig.rig import Rig, RigTruth, stiffness_step


def _motor(**kw: float) -> RigTruth:
    """A 12 V hobby motor: R 0.5 ohm, L 0.25 mH, k 0.01, J 2e-6 (tau_m 10 ms), B 1e-6, c_tau 1e-8."""
    base = dict(V_supply=12.0, R=0.5, L=2.5e-4, k=0.01, J=2e-6, B=1e-6, c_tau=1e-8, c_tau_rev=1e-8,
                c_f=2e-6, c_f_rev=2e-6, w_smooth=2.0)
    base.update(kw)
    return RigTruth(**base)


def test_steady_state_matches_quadratic_closed_form() -> None:
    """Constant 9 V: speed and current settle at the root of c w^2 + (B + k^2/R) w - k V/R = 0."""
    p = _motor()
    rig = Rig(p, h_max=2e-4)
    for _ in range(100):
        rig.advance(9.0, 0.01)
    roots = np.roots([p.c_tau, p.B + p.k**2 / p.R, -p.k * 9.0 / p.R])
    w_ss = float(roots[roots > 0][0])
    assert rig.w == pytest.approx(w_ss, rel=1e-6)
    assert rig.i == pytest.approx((9.0 - p.k * w_ss) / p.R, rel=1e-5)
    assert rig.thrust() == pytest.approx(p.c_f * w_ss**2, rel=1e-5)


def test_linear_step_response_matches_matrix_exponential() -> None:
    """c_tau = 0: the rig is linear; a 6 V step from rest must follow expm of the 2-state system."""
    p = _motor(c_tau=0.0, c_tau_rev=0.0, L=2e-3)  # L/R = 4 ms, comparable to tau_m: strongly coupled
    A = np.array([[-p.R / p.L, -p.k / p.L, 6.0 / p.L], [p.k / p.J, -p.B / p.J, 0.0], [0.0, 0.0, 0.0]])
    rig = Rig(p, h_max=1e-4)
    dt = 1e-3
    err = 0.0
    for n in range(1, 80):
        rig.advance(6.0, dt)
        x = expm(A * n * dt) @ np.array([0.0, 0.0, 1.0])
        err = max(err, abs(rig.w - x[1]) / 600.0, abs(rig.i - x[0]) / 12.0)
    assert err < 1e-3


def test_quadratic_drag_free_decay() -> None:
    """k -> 0, B = 0: J dw/dt = -c w|w| gives w = w0 / (1 + c w0 t / J)."""
    p = _motor(k=1e-12, B=0.0, c_tau=5e-8, c_tau_rev=5e-8)
    rig = Rig(p, h_max=1e-4)
    rig.w = 1000.0
    rig.advance(0.0, 0.2)
    assert rig.w == pytest.approx(1000.0 / (1.0 + 5e-8 * 1000.0 * 0.2 / 2e-6), rel=1e-5)


def test_reverse_coefficients_used_in_reverse() -> None:
    """Reverse rotation uses the reverse drag and thrust coefficients (steady -9 V vs closed form)."""
    p = _motor(c_tau_rev=2e-8, c_f_rev=1e-6)
    rig = Rig(p, h_max=2e-4)
    for _ in range(100):
        rig.advance(-9.0, 0.01)
    roots = np.roots([2e-8, p.B + p.k**2 / p.R, -p.k * 9.0 / p.R])
    w_ss = -float(roots[roots > 0][0])
    assert rig.w == pytest.approx(w_ss, rel=1e-6)
    assert rig.thrust() == pytest.approx(-1e-6 * w_ss**2, rel=1e-5)


def test_thrust_lag_is_first_order() -> None:
    """Huge inertia holds the speed; the lagged thrust rises as 1 - exp(-t/tau)."""
    p = _motor(J=1e3, thrust_tau=0.05)
    rig = Rig(p, h_max=1e-3)
    rig.w = 500.0
    rig.advance(0.0, 0.03)
    assert rig.F == pytest.approx(p.c_f * 500.0**2 * (1 - math.exp(-0.03 / 0.05)), rel=2e-3)


def test_coulomb_friction_holds_below_breakaway_and_brush_drop_lowers_current() -> None:
    """A torque k u/R below tau_c keeps the rotor (near) still; a brush drop V_b removes V_b/R of current."""
    p = _motor(tau_coulomb=0.05)  # stall torque at 1 V: 0.02 N m < 0.05
    rig = Rig(p, h_max=1e-4)
    for _ in range(50):
        rig.advance(1.0, 0.01)
    assert abs(rig.w) < 3 * p.w_smooth
    q = _motor(J=1e3, V_brush=0.8, i_brush=0.05)
    rig = Rig(q, h_max=1e-4)
    rig.advance(4.0, 0.05)  # rotor held still by the inertia: i = (4 - 0.8) / R
    assert rig.i == pytest.approx((4.0 - 0.8) / q.R, rel=1e-4)


def test_cogging_mean_is_zero_and_ripple_is_angle_periodic() -> None:
    """At a held speed the cogging torque averages out over a revolution; in a run it makes a ripple at N/rev."""
    p = _motor(cog_amp=0.01, cog_N=6, c_tau=0.0, c_tau_rev=0.0, B=0.0)
    rig = Rig(p, h_max=2e-5)
    for _ in range(40):
        rig.advance(6.0, 0.005)
    th, w = [], []
    for _ in range(4000):
        rig.advance(6.0, 2e-5)
        th.append(rig.th)
        w.append(rig.w)
    spec = np.abs(np.fft.rfft(np.asarray(w) - np.mean(w)))
    freqs = np.fft.rfftfreq(len(w), 2e-5)
    f_cog = 6 * np.mean(w) / (2 * math.pi)
    assert abs(freqs[np.argmax(spec)] - f_cog) < 2 * freqs[1]


def _cfg(n: int, skew: int = 0, **kw: float | str) -> LoggerConfig:
    """A quiet 1 kHz logger with a tachometer."""
    base = dict(rate=1000.0, n=n, skew=skew, jitter=0.0, speed_sensor="tacho", columns="both", tach_noise=0.0,
                tach_filter=0.0, cpr=4096, diff_window=1, cur_noise=1e-9, cur_filter=0.0, cur_bits=16,
                cur_range=30.0, cur_offset=0.0, thr_noise=1e-9, thr_bits=24, thr_range=5.0, thr_offset=0.0,
                thr_filter=0.0, pi_kp=0.0, pi_ki=0.0)
    base.update(kw)
    return LoggerConfig(**base)


def _step_exc(n: int, at: int, v: float) -> Excitation:
    cmd = np.where(np.arange(n) >= at, v, 0.0)
    return Excitation("steps", ["steps"], np.zeros(n, bool), cmd, np.zeros(n), False)


@pytest.mark.parametrize(("skew", "delay_rows"), [(0, 0), (2, 0), (1, 5)])
def test_command_reaches_motor_after_skew_plus_delay(skew: int, delay_rows: int) -> None:
    """The command logged at row 20 acts on the motor from row 20 + skew + delay."""
    p = _motor(delay=delay_rows / 1000.0)
    cols = run_log(p, _cfg(60, skew), _step_exc(60, 20, 5.0), 1e-4, np.random.default_rng(0))
    first = int(np.argmax(cols["u_motor"] != 0.0))
    assert first == 20 + skew + delay_rows
    assert cols["voltage"][20] == 5.0 and cols["voltage"][19] == 0.0


def test_encoder_speed_and_theta_track_truth() -> None:
    """Differentiated encoder counts average to the true speed; theta is within a count of the true angle."""
    p = _motor()
    cfg = _cfg(800, speed_sensor="encoder", cpr=1024, diff_window=4)
    cols = run_log(p, cfg, _step_exc(800, 0, 8.0), 1e-4, np.random.default_rng(1))
    late = slice(400, 800)
    assert np.mean(cols["omega"][late]) == pytest.approx(np.mean(cols["true_w"][late]), rel=2e-3)
    th_true = np.concatenate([[0.0], np.cumsum(cols["true_w"][:-1] * 1e-3)])
    assert np.max(np.abs(cols["theta"] - th_true)) < 0.05 * np.max(th_true)


def test_halving_the_substep_barely_changes_a_log_with_effects() -> None:
    """Friction, Stribeck, cogging, brush drop, lag under an open-loop chirp: h -> h/2 changes the speed by
    < 0.3 % of top speed and the current by < 0.2 % of stall, and h/2 -> h/4 changes them less (convergence).

    (Closed loop on encoder counts is excluded on purpose: a count flipping one row earlier is a discrete
    event of the logger, not integration error.)
    """
    case = draw_case(3)
    sc = case.meta["scales"]
    p = replace(case.truth, tau_coulomb=0.05 * sc["T_top"], tau_stribeck=0.05 * sc["T_top"],
                w_stribeck=0.03 * sc["w_top"], cog_amp=0.02 * sc["T_stall"], cog_N=7, V_brush=0.2,
                i_brush=0.02 * sc["I_stall"], thrust_tau=0.05)
    cfg = replace(case.cfg, n=1500, speed_sensor="tacho")
    exc = make_excitation(np.random.default_rng(1), 1500, 1.0 / cfg.rate, p.V_supply, sc["w_top"], sc["tau_eff"],
                          True, "chirp")
    h = stiffness_step(p, sc["w_top"])
    runs = [run_log(p, cfg, exc, hh, np.random.default_rng(5), 0.3) for hh in (h, h / 2, h / 4)]
    dw1, dw2 = (float(np.max(np.abs(runs[j]["true_w"] - runs[j + 1]["true_w"]))) for j in (0, 1))
    di1, di2 = (float(np.max(np.abs(runs[j]["true_i"] - runs[j + 1]["true_i"]))) for j in (0, 1))
    assert dw1 < 3e-3 * sc["w_top"] and di1 < 2e-3 * sc["I_stall"]
    assert dw2 < 0.7 * dw1 and di2 < 0.7 * di1
    assert np.max(np.abs(runs[0]["true_w"])) > 0.3 * sc["w_top"]  # the rotor actually moved


def test_draws_are_deterministic_and_within_brief_ranges() -> None:
    """Same seed, same case; constants in range; nominal file within 3 % except the one wrong constant."""
    allowed = set(EFFECTS) | {f"param:{q}" for q in PARAMS}
    for seed in range(40):
        c, d = draw_case(seed), draw_case(seed)
        assert c.labels == d.labels and c.nominal == d.nominal
        assert set(c.labels) <= allowed
        p = c.truth
        assert 3.7 <= p.V_supply <= 48 and 0.05 <= p.R <= 10 and 0.002 <= p.k <= 0.1 and 1e-7 <= p.J <= 1e-3
        assert 5e-5 <= p.L / p.R <= 5e-3
        true = {"J": p.J, "B": p.B, "c_tau": p.c_tau, "c_f": p.c_f, "k_t": p.k, "k_e": p.k, "R": p.R, "L": p.L}
        for key, val in c.nominal.items():
            rel = abs(val / true[key] - 1.0)
            wrong = f"param:{key}" in c.labels or (key in ("k_t", "k_e") and "param:k" in c.labels)
            assert (0.15 - 1e-9 <= rel <= 0.5 + 1e-9) if wrong else rel <= 0.03 + 1e-9
