"""Streaming shaper (ocp.stream) on an impedance-like reference with many linear crossings, checked
against oracles it does not share code with: the test's own DC-motor model integrated by scipy's Radau,
its own log-log fit of the local exponent, the closed-form steady state."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize_scalar

from ocp.errors import MissionError
from ocp.gallery.interaction import InteractionSetup, Law, interaction_reference
from ocp.model.params import MotorParams
from ocp.stream import StreamShaper, shape_profile, stream_options
from ocp.stream.blend import blend_profile
from ocp.stream.preview import Hold, design

AMPLITUDE = 0.4  # N
CURRENT, VOLTAGE = 1.0, 12.0


@pytest.fixture(scope="module")
def impedance() -> tuple[np.ndarray, np.ndarray]:
    """Section IV-B impedance reference, 10 s at 1 kHz, scaled to +-0.4 N (19 linear crossings)."""
    ref = interaction_reference(Law.IMPEDANCE, InteractionSetup(duration=10.0), rate=1000.0)
    return ref.t, ref.x2d / np.max(np.abs(ref.x2d)) * AMPLITUDE


def motor_thrust(p: MotorParams, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The test's own DC motor (J w' = k_t i - B w - c_tau w|w|, L i' = V - R i - k_e w) under the voltage
    samples ``v`` joined by a cubic spline (smooth, so Radau is not stopped at a kink every sample), from
    rest; thrust c_f w|w| on ``t``."""
    spline = CubicSpline(t, v)

    def rhs(tt: float, x: np.ndarray) -> list[float]:
        vv = float(spline(tt))
        w, i = x
        return [(p.k_t * i - p.B * w - p.c_tau * w * abs(w)) / p.J, (vv - p.R * i - p.k_e * w) / p.L]

    def jac(tt: float, x: np.ndarray) -> list[list[float]]:
        w = x[0]
        return [[-(p.B + 2.0 * p.c_tau * abs(w)) / p.J, p.k_t / p.J], [-p.k_e / p.L, -p.R / p.L]]

    sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0], method="Radau", t_eval=t, jac=jac, rtol=1e-6, atol=1e-7)
    assert sol.success
    return p.c_f * sol.y[0] * np.abs(sol.y[0])


def exponent(t: np.ndarray, f: np.ndarray, t_guess: float, half_window: float) -> float:
    """Own fit of g in |f| ~ |t - t_s|^g on |t - t_s| <= half_window, t_s refined within a sample."""
    dt = t[1] - t[0]

    def fit(ts: float) -> tuple[float, float]:
        s = np.abs(t - ts)
        m = (s > 0.5 * dt) & (s <= half_window)
        x, y = np.log(s[m]), np.log(np.abs(f[m]))
        g, c = np.polyfit(x, y, 1)
        return float(np.sum((y - g * x - c) ** 2)), float(g)

    res = minimize_scalar(lambda ts: fit(ts)[0], bounds=(t_guess - dt, t_guess + dt), method="bounded")
    return fit(float(res.x))[1]


def reversals(t: np.ndarray, f: np.ndarray) -> list[float]:
    k = np.flatnonzero(f[:-1] * f[1:] < 0)
    return [float(t[j] - f[j] * (t[j + 1] - t[j]) / (f[j + 1] - f[j])) for j in k]


@pytest.mark.slow
@pytest.mark.parametrize(("regularity", "g"), [("bounded", 2.0), ("continuous-voltage", 6.0)])
def test_impedance_stream_limits_reproduction_and_crossings(rig: MotorParams, impedance: tuple, regularity: str,
                                                            g: float) -> None:
    t, f = impedance
    opts = stream_options(current=CURRENT, voltage=VOLTAGE, regularity=regularity, delay=0.1)
    out = shape_profile(rig, opts, t, f)
    # limits held at every sample
    assert np.max(np.abs(out.current)) <= CURRENT
    assert np.max(np.abs(out.voltage)) <= VOLTAGE
    # an independent simulation under the returned voltage reproduces the returned thrust (1 % RMS of A)
    sim = motor_thrust(rig, t, out.voltage)
    assert np.sqrt(np.mean((sim - out.thrust) ** 2)) <= 0.01 * AMPLITUDE
    # every reversal of the output has the requested exponent (own fit on +-10 ms)
    desired_reversals = [tc for tc in reversals(t, f) if tc + opts.delay < t[-1] - 0.05]
    shaped = reversals(t, out.thrust)
    assert len(shaped) >= len(desired_reversals) >= 15
    fitted = [exponent(t, out.thrust, tc, 0.010) for tc in shaped if 0.02 < tc < t[-1] - 0.02]
    assert len(fitted) == len(shaped)
    assert np.all(np.abs(np.array(fitted) - g) <= 0.2), fitted
    # each desired reversal, delayed by the look-ahead, has a shaped reversal close to it
    for tc in desired_reversals:
        assert min(abs(s - (tc + opts.delay)) for s in shaped) < 0.03
    # tracking the delayed desired thrust as closely as the limits allow (regression guard, README figures)
    assert out.tracking_rms() <= 0.05 * AMPLITUDE


def test_output_is_causal_and_delayed(rig: MotorParams, impedance: tuple) -> None:
    t, f = impedance
    t, f = t[:1500], f[:1500]
    opts = stream_options(current=CURRENT, voltage=VOLTAGE, delay=0.08)
    a = shape_profile(rig, opts, t, f)
    g = f.copy()
    g[1000:] = -g[1000:] * 3.0  # a different future
    b = shape_profile(rig, opts, t, g)
    np.testing.assert_array_equal(a.voltage[:1000], b.voltage[:1000])
    assert np.max(np.abs(a.voltage[1000:] - b.voltage[1000:])) > 0.1
    # the output at t tracks the desired thrust at t - delay (zero before the stream)
    np.testing.assert_array_equal(a.desired[80:], f[:-80])
    assert np.all(a.desired[:80] == 0.0)


def test_steady_state_matches_motor_equilibrium(rig: MotorParams) -> None:
    """Constant desired thrust: the shaper settles on it with the motor's closed-form equilibrium i, V."""
    opts = stream_options(current=CURRENT, voltage=VOLTAGE, regularity="continuous-voltage", delay=0.05)
    t = np.arange(3000) * opts.dt
    out = shape_profile(rig, opts, t, np.full(t.size, 0.3))
    w = np.sqrt(0.3 / rig.c_f)
    i_ss = (rig.B * w + rig.c_tau * w * w) / rig.k_t
    assert out.thrust[-1] == pytest.approx(0.3, rel=1e-6)
    assert out.current[-1] == pytest.approx(i_ss, rel=1e-5)
    assert out.voltage[-1] == pytest.approx(rig.R * i_ss + rig.k_e * w, rel=1e-5)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_preview_gains_hold_a_constant_reference(hold: Hold) -> None:
    """For r constant the law v = -K z + F.r must keep z = (r, 0, ...) at rest: sum F = K[0]."""
    g = design(hold, 0.001, 20.0, 100)
    assert float(np.sum(g.F)) == pytest.approx(float(g.K[0]), rel=1e-9)
    closed = g.A - np.outer(g.B, g.K)
    assert np.max(np.abs(np.linalg.eigvals(closed))) < 1.0


def test_blend_alternative_is_causal_but_breaks_the_limits(rig: MotorParams, impedance: tuple) -> None:
    """The analytic-blend alternative (README table): causal, flat crossings, but no bound on i and V."""
    t, f = impedance
    opts = stream_options(current=CURRENT, voltage=VOLTAGE, delay=0.1)
    full = blend_profile(rig, opts, t, f)
    part = blend_profile(rig, opts, t[:5000], f[:5000])
    np.testing.assert_allclose(part.voltage[:-3], full.voltage[:4997], rtol=0, atol=1e-12)
    assert np.max(np.abs(full.current)) > 2.0 * CURRENT


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"delay": 0.1005}, "delay"),
    ({"delay": 2.0}, "delay"),
    ({"regularity": "c1-voltage"}, "regularity"),
    ({"regularity": "smooth"}, "regularity"),
    ({"current": -1.0}, "current"),
    ({"extra": 1}, "extra"),
])
def test_bad_options_name_the_field(kwargs: dict, field: str) -> None:
    base = {"current": 1.0, "voltage": 12.0}
    with pytest.raises(MissionError) as err:
        stream_options(**{**base, **kwargs})
    assert err.value.field == field


def test_bad_samples_name_the_field(rig: MotorParams) -> None:
    sh = StreamShaper(rig, stream_options(current=1.0, voltage=12.0, delay=0.05))
    sh.push(0.0, 0.1)
    with pytest.raises(MissionError) as err:
        sh.push(0.001, float("nan"))
    assert err.value.field == "thrust"
    with pytest.raises(MissionError) as err:
        sh.push(0.0015, 0.1)
    assert err.value.field == "t"
    sh.push(0.001, 0.1)  # a rejected sample leaves the stream where it was
