"""The proving ground's steady-state sweeps (:mod:`tests.proving_ground.sweeps`): each row is the rig's settled point
by the rig's own formulas, and a label is kept only where the sweep shows it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.proving_ground.cases import draw_motor
from tests.proving_ground.physics import drive_voltage, load_torque, quasi_static_thrust
from tests.proving_ground.sweeps import (
    SWEEP_CONSTANTS,
    SWEEP_EFFECTS,
    Esc,
    make_sweep,
    rows,
    settle,
)


@pytest.mark.parametrize("effects", [{}, {"coulomb_friction": {"tau_c": 0.01}},
                                     {"stribeck": {"tau_s": 0.02, "omega_s": 20.0}},
                                     {"brush_drop": {"v_b": 0.8}, "voltage_deadband": {"v_db": 0.5}}])
def test_a_settled_point_balances_the_rigs_equations(effects: dict[str, dict[str, float]]) -> None:
    """Oracle, the rig's equations at rest (di/dt = dw/dt = 0): the motor's torque equals the load torque and the
    armature's voltage its drops, at every moving point; a point at rest has its motor torque within the friction."""
    t, _ = draw_motor(np.random.default_rng(3))
    t = replace(t, effects=effects)
    tau, vb = load_torque(t), t.e("brush_drop", "v_b")
    for v in np.linspace(-0.9, 0.9, 41) * t.v_max:
        w, i = settle(t, float(v))
        if w == 0.0:
            assert abs(t.k * i) <= t.e("coulomb_friction", "tau_c") + t.e("stribeck", "tau_s")
            continue
        assert t.k * i == pytest.approx(tau(w, 0.0), rel=1e-9, abs=1e-12)
        assert drive_voltage(t, float(v)) - vb * np.sign(i) == pytest.approx(t.R * i + t.k * w, rel=1e-9, abs=1e-9)


def test_rows_are_what_the_sensors_read() -> None:
    t, _ = draw_motor(np.random.default_rng(5))
    t = replace(t, effects={"current_offset": {"i0": 0.05}, "force_offset": {"f0": -0.2}})
    v = np.array([0.5 * t.v_max])
    r = rows(t, v)
    w, i = settle(t, float(v[0]))
    np.testing.assert_allclose(r[:, 0], [v[0], i + 0.05, w, quasi_static_thrust(t, w) - 0.2])


def test_draws_are_deterministic_and_labelled_within_the_catalogue_a_sweep_can_show() -> None:
    a, b = make_sweep(17), make_sweep(17)
    assert a.expected == b.expected and all(np.array_equal(a.columns[k], b.columns[k]) for k in a.columns)
    labels = set().union(*(make_sweep(s).expected for s in range(40)))
    assert labels <= set(SWEEP_EFFECTS) | {f"param:{c}" for c in SWEEP_CONSTANTS}
    assert len(labels) >= 8  # (effects and constants both drawn)


def test_through_an_esc_the_supply_delivers_the_armatures_power_over_its_efficiency() -> None:
    """Oracle, the drive's power balance: supply current times the supply voltage equals the armature's input power
    ``V_a i`` (its dead zone applied) over the efficiency, plus the idle power; the command is the pulse width."""
    t, _ = draw_motor(np.random.default_rng(9))
    t = replace(t, effects={"voltage_deadband": {"v_db": 0.3}})
    esc = Esc(0.9, 1.5)
    v = np.array([-0.6, 0.4]) * t.v_max
    r = rows(t, v, esc)
    for k, vk in enumerate(v):
        i = settle(t, float(vk))[1]
        assert r[0, k] == pytest.approx(1500.0 + 400.0 * vk / t.v_max)
        assert r[1, k] * t.v_max == pytest.approx(drive_voltage(t, float(vk)) * i / 0.9 + 1.5, rel=1e-12)

