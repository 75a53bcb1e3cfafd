"""A free run reads the rotor angle from the log (issue #11, session 39).

A ripple's torque depends on the rotor angle to a fraction of its period. A free run that integrated its own angle
from its own speed lost the phase within a segment, so a plant with the rig's true ripple predicted the log worse
than one without (``fit`` then "refined" the ripple into nonsense and the error did not fall: the mission's "add it,
refit and watch the error fall" failed for this effect). The angle is a measured state
(:attr:`ocp.model.stateful_effects.StatefulBase.measured`): the free run sets it from the log at every sample.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify.candidates import candidate
from ocp.identify.fit import FitOptions, fit
from ocp.identify.predict import measured_states
from ocp.model.effects import Cogging, InputDelay
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.simulate.zoh import segment_simulator
from tests.proving_ground import make_case


def test_a_read_state_is_set_from_its_input_at_every_sample(rig: MotorParams) -> None:
    """Oracle, self-consistency: feeding the simulator's own angle at each sample's start as the read input gives
    its trajectory back; an angle shifted by a quarter period gives another speed. Only the angle is read."""
    plant = DCMotorPlant(rig, (InputDelay(delay=0.004), Cogging(tau_sin=0.02, tau_cos=0.01, periods=6.0)))
    assert measured_states(plant) == (4,)  # omega, current, the delay's two states, the angle
    length, segs, per, dt = 40, 2, 4, 2e-3
    x0 = np.array([[30.0, -20.0], [0.5, -0.4], [0.0, 0.0], [0.0, 0.0], [0.3, 2.0]])
    u = np.concatenate([np.full(length - 1, 3.0), np.linspace(-4.0, 4.0, length - 1)])[None, :]
    free = np.asarray(segment_simulator(plant, per, length, segs)(x0, u, dt / per))
    starts = np.concatenate([np.concatenate([x0[4, b:b + 1], free[4, b * (length - 1):(b + 1) * (length - 1) - 1]])
                             for b in range(segs)])
    sim = segment_simulator(plant, per, length, segs, (4,))
    np.testing.assert_allclose(np.asarray(sim(x0, np.vstack([u, starts]), dt / per)), free, rtol=1e-12, atol=1e-12)
    shifted = np.asarray(sim(x0, np.vstack([u, starts + math.pi / 12]), dt / per))
    assert np.max(np.abs(shifted[0] - free[0])) > 0.01
    # the segments run by CasADi's threads: bitwise the serial run's numbers (each segment's arithmetic is its own)
    threaded = segment_simulator(plant, per, length, segs, (4,), workers=2)
    assert threaded is not sim
    assert np.array_equal(np.asarray(threaded(x0, np.vstack([u, starts]), dt / per)),
                          np.asarray(sim(x0, np.vstack([u, starts]), dt / per)))


def test_refitting_a_ripple_makes_the_free_run_error_fall(monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving-ground draw ``make_case(42066, "one")`` (a sine ripple of 10 periods/rev, amplitude 47.5 mN m, on a
    2 kHz encoder log): ``fit`` adding the ripple to the nominal plant takes the count ``diagnose`` finds (not the
    catalogue's default 2), halves the free run's speed error and finds the amplitude within 10 %. With the angle
    simulated instead of read, the same fit's speed error does not fall."""
    case = make_case(42066, "one")
    truth = case.truth.effects["cogging"]
    assert truth["periods"] == 10.0 and "theta" in case.columns
    plant, log = DCMotorPlant(MotorParams(**case.nominal)), case_log(case)
    res = fit(plant, log, ["cogging"])
    assert res.adopted and res.note is None
    ripple = next(e for e in res.plant.effects if isinstance(e, Cogging))
    assert ripple.periods == 10.0
    assert res.after["omega"] < 0.6 * res.before["omega"]
    assert math.hypot(ripple.tau_sin, ripple.tau_cos) == pytest.approx(truth["amplitude"], rel=0.1)
    monkeypatch.setattr(Cogging, "measured", False)
    unread = fit(plant, log, ["cogging"])
    assert unread.after["omega"] > 0.9 * unread.before["omega"]


def test_a_ripple_the_plant_has_keeps_its_count() -> None:
    """A parameter file's (or a diagnosis's) count is kept: the ripple is refitted at 7 periods/rev, not searched."""
    case = make_case(42066, "one")
    plant = DCMotorPlant(MotorParams(**case.nominal), (Cogging(periods=7.0),))
    res = fit(plant, case_log(case), ["cogging"], FitOptions(refine=False))
    assert next(e for e in res.plant.effects if isinstance(e, Cogging)).periods == 7.0


def test_a_large_motors_ripple_is_fitted_beyond_the_catalogues_box() -> None:
    """Proving-ground draw ``make_case(42416, "one")``: a 240 mN m ripple of 20 periods/rev on a 500 Hz encoder log.
    The catalogue's box (0.1 N m, a small motor's) held ``fit`` at 0.1 on each coefficient; reaching the motor's
    peak torque in the log, the amplitude is found within 20 % and the speed error more than halves."""
    case = make_case(42416, "one")
    truth = case.truth.effects["cogging"]
    assert truth["periods"] == 20.0 and truth["amplitude"] > 0.2
    res = fit(DCMotorPlant(MotorParams(**case.nominal)), case_log(case), ["cogging"])
    ripple = next(e for e in res.plant.effects if isinstance(e, Cogging))
    assert math.hypot(ripple.tau_sin, ripple.tau_cos) == pytest.approx(truth["amplitude"], rel=0.2)
    assert res.after["omega"] < 0.5 * res.before["omega"]


def test_only_torque_valued_boxes_reach_the_peak_torque(rig: MotorParams) -> None:
    """Oracle, the catalogue's boxes: widened to +-0.7 N m for the ripple's coefficients and Stribeck's level (units
    N m), not for its band (rad/s); a box wider than the peak torque, or none given, is the catalogue's."""
    plant = DCMotorPlant(rig)
    lo, hi = candidate("cogging").bounds(plant, 0.7)
    assert np.all(lo == -0.7) and np.all(hi == 0.7)
    lo, hi = candidate("stribeck").bounds(plant, 0.7)
    assert list(candidate("stribeck").keys) == ["tau_s", "omega_s"]
    assert lo.tolist() == [0.0, 0.3] and hi.tolist() == [0.7, 30.0]
    assert candidate("cogging").bounds(plant, 0.01)[1].tolist() == candidate("cogging").bounds(plant)[1].tolist() \
        == [0.1] * 6
