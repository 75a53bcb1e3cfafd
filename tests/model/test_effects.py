"""Effect catalogue: numpy and CasADi backends agree, phase-sign form matches the smooth one, the
parameter-file format round-trips, and bad names/values are errors naming the key."""

from __future__ import annotations

import json
import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from ocp.errors import ParameterError
from ocp.model.effects import CATALOGUE, InputDelay, load_plant, make_effect, plant_to_mapping
from ocp.model.params import MotorParams, load_params
from ocp.model.plant import CASADI, NUMPY, DCMotorPlant
from ocp.model.stateful_effects import Cogging
from ocp.simulate.open_loop import simulate_zoh

#: a non-trivial value for every fitted parameter (SI)
VALUES = {
    "coulomb_friction": {"tau_c": 0.003}, "stribeck": {"tau_s": 0.006, "omega_s": 3.0},
    "drag_asymmetry": {"dc_tau": 0.8e-6}, "thrust_asymmetry": {"dc_f": 0.3e-4}, "force_offset": {"f0": 0.03},
    "voltage_deadband": {"v_db": 0.4}, "brush_drop": {"v_b": 0.3}, "current_offset": {"i0": 0.03},
    "input_delay": {"delay": 0.004}, "thrust_lag": {"tau": 0.03},
    "cogging": {"tau_sin": 0.003, "periods": 2.0, "tau_cos2": -0.001, "tau_sin3": 0.0005},
}


def test_every_catalogue_effect_has_test_values() -> None:
    assert set(VALUES) == set(CATALOGUE)


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_numpy_and_casadi_backends_agree(name: str, rig: MotorParams) -> None:
    plant = DCMotorPlant(rig, (make_effect(name, VALUES[name]),))
    n = len(plant.state_names)
    rng = np.random.default_rng(3)
    x0 = np.concatenate([[23.0, 0.2], 0.01 * rng.standard_normal(n - 2)])
    xs, us = ca.SX.sym("x", n), ca.SX.sym("u")
    f = ca.Function("f", [xs, us], [ca.vertcat(*plant.rhs([xs[m] for m in range(n)], us, CASADI)),
                                    plant.thrust([xs[m] for m in range(n)], CASADI)])
    dx_ca, thr_ca = f(x0, 2.5)
    np.testing.assert_allclose(np.asarray(dx_ca).ravel(), plant.rhs(list(x0), 2.5, NUMPY), rtol=1e-12, atol=1e-9)
    assert float(thr_ca) == pytest.approx(float(plant.thrust(list(x0))), rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("name", ["coulomb_friction", "stribeck", "drag_asymmetry", "thrust_asymmetry"])
@pytest.mark.parametrize("w", [-40.0, 40.0])
def test_phase_sign_form_matches_smooth_form_away_from_zero(name: str, w: float) -> None:
    eff = make_effect(name, VALUES[name])
    sgn = math.copysign(1.0, w)
    assert eff.load_torque(w, NUMPY, sgn) == pytest.approx(eff.load_torque(w, NUMPY, None), rel=1e-9, abs=1e-15)
    assert eff.thrust(0.1, w, NUMPY, sgn) == pytest.approx(eff.thrust(0.1, w, NUMPY, None), rel=1e-9)


@pytest.mark.parametrize("delta", [1.0, 0.5])
@pytest.mark.parametrize("w", [-30.0, -5.0, 2.0, 12.0])
def test_stribeck_decay_exponent_follows_its_closed_form_beyond_the_smoothing(delta: float, w: float) -> None:
    """Oracle, closed form: ``tau_s exp(-|w / omega_s|^delta) tanh(w / omega_eps)``, to the stated bound: the
    smoothed power's exponent is too large by under ``delta e^2 / (2 |r|^(2 - delta))`` (``e = omega_eps /
    omega_s``, ``r = w / omega_s``; here 0.02 at 2 rad/s, 0.0003 at 30)."""
    eff = make_effect("stribeck", {"tau_s": 0.006, "omega_s": 3.0, "delta": delta})
    r, e = abs(w) / 3.0, 0.5 / 3.0
    exact = 0.006 * math.exp(-(r**delta)) * math.tanh(w / 0.5)
    ratio = float(eff.load_torque(w, NUMPY, None)) / exact
    assert math.exp(-delta * e * e / (2 * r ** (2 - delta))) <= ratio < 1.0
    gauss = make_effect("stribeck", {"tau_s": 0.006, "omega_s": 3.0})  # the default: the Gaussian, unsmoothed
    assert float(gauss.load_torque(w, NUMPY, None)) == 0.006 * math.exp(-((w / 3.0) ** 2)) * math.tanh(w / 0.5)


@pytest.mark.parametrize("delta", [1.0, 0.5, 0.25])
def test_stribeck_decay_is_differentiable_through_zero_speed(delta: float) -> None:
    """The optimiser differentiates the torque at reversals: CasADi's derivative at and around w = 0 is finite and
    matches central finite differences of the numpy torque (an unsmoothed ``|w|^0.5`` has an infinite one)."""
    eff = make_effect("stribeck", {"tau_s": 0.006, "omega_s": 3.0, "delta": delta})
    w = ca.SX.sym("w")
    d = ca.Function("d", [w], [ca.jacobian(eff.load_torque(w, CASADI, None), w)])
    for w0 in (0.0, 1e-3, -0.3, 2.0):
        h = 1e-6
        fd = (float(eff.load_torque(w0 + h, NUMPY, None)) - float(eff.load_torque(w0 - h, NUMPY, None))) / (2 * h)
        assert math.isfinite(float(d(w0)))
        assert float(d(w0)) == pytest.approx(fd, rel=1e-5, abs=1e-9)


def test_cogging_harmonics_follow_their_fourier_series() -> None:
    """The ripple at h = 1, 2, 3 times its count against the series written out, at angles over a revolution; the
    fundamental alone (harmonics at their default 0) is the plain sine, and only non-zero harmonics are listed."""
    c = make_effect("cogging", {"tau_sin": 0.004, "tau_cos": -0.002, "periods": 7.0, "tau_sin2": 0.0015,
                                "tau_cos2": 0.0005, "tau_cos3": -0.0008})
    assert isinstance(c, Cogging)
    theta = np.linspace(0.0, 2 * np.pi, 97)
    want = (0.004 * np.sin(7 * theta) - 0.002 * np.cos(7 * theta) + 0.0015 * np.sin(14 * theta)
            + 0.0005 * np.cos(14 * theta) - 0.0008 * np.cos(21 * theta))
    got = np.array([c.bind([th]).load_torque(3.0, NUMPY, None) for th in theta])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-15)
    plain = make_effect("cogging", {"tau_sin": 0.004, "periods": 7.0})
    assert isinstance(plain, Cogging)
    assert [h for h, *_ in plain.harmonics()] == [1] and [h for h, *_ in c.harmonics()] == [1, 2, 3]
    np.testing.assert_array_equal([plain.bind([th]).load_torque(3.0, NUMPY, None) for th in theta],
                                  0.004 * np.sin(7 * theta))
    assert c.describe().endswith("; 7 periods per revolution, amplitude 0.00447 N m; its 2x harmonic 0.00158 N m; "
                                 "its 3x harmonic 0.0008 N m.")  # hypot of each pair
    assert plain.describe().endswith("; 7 periods per revolution, amplitude 0.004 N m.")


def test_input_delay_delays_a_slow_sine(rig: MotorParams) -> None:
    """Pade(2) of a 5 ms delay: a 2 Hz voltage reaches the armature 5 ms late (to 1 % of its amplitude)."""
    eff = InputDelay(delay=0.005)
    t = np.arange(0.0, 1.0, 1e-4)
    v = np.sin(2 * np.pi * 2.0 * t)
    z = eff.observe(t, v, v, v, None)
    out = np.array([eff.bound_drive_voltage(tuple(z[:, k]), v[k]) for k in range(t.size)])  # (bind's tuple)
    late = t > 0.2
    np.testing.assert_allclose(out[late], np.sin(2 * np.pi * 2.0 * (t[late] - 0.005)), atol=0.01)


def test_stateful_effects_grow_the_state_and_simulate(rig: MotorParams) -> None:
    plant = load_plant({**rig.model_dump(), "effects": {"thrust_lag": {"tau": 0.03}, "input_delay": {"delay": 0.003}}})
    assert plant.state_names == ("omega", "current", "thrust_lag.thrust", "input_delay.z1", "input_delay.z2")
    t = np.arange(0.0, 0.6, 1e-3)
    sim = simulate_zoh(plant, t, np.full_like(t, 3.0), [0.0] * 5)
    static = rig.c_f * sim.state("omega") ** 2
    assert sim.thrust[-1] == pytest.approx(static[-1], rel=1e-3)  # settled: lag state = static thrust
    assert np.max(static[:100] - sim.thrust[:100]) > 0.01  # while spinning up it lags


def test_parameter_file_round_trip(tmp_path: Path, rig: MotorParams) -> None:
    plant = DCMotorPlant(rig, tuple(make_effect(n, v) for n, v in VALUES.items()))
    path = tmp_path / "cal.json"
    path.write_text(json.dumps(plant_to_mapping(plant, name="cal")), encoding="utf-8")
    back = load_plant(path)
    assert back == plant
    assert load_params(path) == rig  # the constants alone still load as plain MotorParams


@pytest.mark.parametrize(("block", "key"), [
    ({"coulomb_frictin": {"tau_c": 0.1}}, "effects.coulomb_frictin"),
    ({"coulomb_friction": {"tauc": 0.1}}, "effects.coulomb_friction.tauc"),
    ({"coulomb_friction": {"tau_c": "big"}}, "effects.coulomb_friction.tau_c"),
    ({"thrust_lag": {"tau": -1.0}}, "thrust_lag.tau"),
    ({"stribeck": {"tau_s": 0.006, "omega_s": 3.0, "delta": 9.0}}, "effects.stribeck.delta"),
    ([1, 2], "effects"),
    ({"coulomb_friction": 3}, "effects.coulomb_friction"),
    ({"coulomb_friction": "ab"}, "effects.coulomb_friction"),
])
def test_bad_effect_blocks_name_the_key(block: object, key: str, rig: MotorParams) -> None:
    with pytest.raises(ParameterError) as err:
        load_plant({**rig.model_dump(), "effects": block})
    assert err.value.field == key


def test_preset_loads_as_plant_without_effects(rig: MotorParams) -> None:
    plant = load_plant("paper-rig")
    assert plant.params == rig and plant.effects == ()


def test_a_gap_dead_band_passes_nothing_inside_and_the_whole_command_beyond() -> None:
    """The gap form (``gap = 1``) against the hard gap it smooths (``V if |V| >= v_db else 0``), on both backends;
    the shifted default unchanged (``V - v_db tanh(V / v_db)``); any other form refused, naming the key."""
    gap, shift = make_effect("voltage_deadband", {"v_db": 2.0, "gap": 1.0}), make_effect("voltage_deadband",
                                                                                           {"v_db": 2.0})
    v = np.array([-3.0, -2.2, -1.8, 0.0, 0.5, 1.8, 2.2, 3.0])
    hard = np.where(np.abs(v) >= 2.0, v, 0.0)
    assert np.allclose(gap.drive_voltage(v, 0.0, NUMPY), hard, atol=0.04 * np.abs(v).max())
    xs = ca.SX.sym("v")
    f = ca.Function("f", [xs], [gap.drive_voltage(xs, 0.0, CASADI)])
    assert np.allclose([float(f(x)) for x in v], gap.drive_voltage(v, 0.0, NUMPY))
    assert np.allclose(shift.drive_voltage(v, 0.0, NUMPY), v - 2.0 * np.tanh(v / 2.0))
    with pytest.raises(ParameterError) as err:
        make_effect("voltage_deadband", {"v_db": 2.0, "gap": 0.5})
    assert "voltage_deadband.gap" in str(err.value)
