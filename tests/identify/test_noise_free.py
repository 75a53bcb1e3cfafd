"""Model-exact logs without noise (sessions 63-64: a user who simulates the plant first; issue #11).

The catalogue's own ZOH run of ``tests/identify/test_one_command.py``'s plant, logged without noise, is diagnosed
against that very plant, so the right verdict is the empty one. What the equations then hold is the method's own error
(derivative filters, the integrator, sub-sample timing), and their noise units are themselves made of it: each
equation's level is what the richest fit (every effect) leaves on the training rows
(:func:`ocp.identify.regression.build`), the torque equation's floored by the channels' noise read from their second
differences (:func:`ocp.identify.predict.noise_levels`: here the signals' own curvature). Session 63 counted an
equation's held-out error under :data:`ocp.identify.evidence.RESOLVED` noise units at it where an effect's fall is
judged; that fixed the +-6 V square wave (a Stribeck band and a ripple were named on falls from 0.137 to 0.04 noise
units), but not where the part of the method's error effects absorb is above that level: a step down from 6 to 2 V
named a current offset and a Stribeck band (torque equation at 12.2 noise units). Session 64 asks of each adopted
effect whether it takes more of the log's held-out error than the same model takes of the nominal plant's own
noise-free replica of the log (:func:`ocp.identify.replica.artifacts`): what it takes there is the method's error under
this command. The step down is clean so (its current offset was the method's, and without it nothing is adopted).

Session 65 fixed the thrust map's method error (:func:`ocp.identify.columns.speed_square`: the low-passed thrust is
compared with the low-pass of ``c_f w|w|``, no longer with ``c_f`` times the square of the low-passed speed, whose
difference did not fall with the sample time). The 1 Hz sine, whose Stribeck band had taken 0.026 of the log against
0.021 of the replica, is clean since; so are a step from rest after 500 rows (a current offset before) and after 200
(a force offset until session 64's replica check set it aside).

Not fixed (a strict expected failure, measured): the 0/6 V square's drag asymmetry (torque equation 2.0 -> 0.74 noise
units) is taken for the method's, but a ripple is then named, and the replica's ripple (its period count picked from
the replica's own spectrum) takes less of the replica than the log's of the log (2.66 against 3.29 squared noise
units). The sine is still aligned 0.53 samples late (0.94 applied) on this exact log. With the loggers' noise at a
tenth of the usual level every command here is clean.
"""

from __future__ import annotations

import numpy as np
import pytest

from bench.modelcheck import case_log, noise_free
from ocp.identify import diagnose
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.identify.test_one_command import P, step_log
from tests.proving_ground import make_case

N = 3000
T = np.arange(N) * 1e-3


def test_a_noise_free_square_wave_is_clean() -> None:
    u = 6.0 * np.sign(np.sin(2 * np.pi * 2.0 * T) + 1e-9)
    assert diagnose(DCMotorPlant(P), step_log(u, 0.0)).verdict == []


def test_a_noise_free_step_down_is_clean() -> None:
    """Session 63 named a current offset and a Stribeck band here; session 64 set the current offset aside (it took
    no more of the log's held-out error than of the nominal plant's replica). Since session 74 nothing is adopted at
    all: the settled speed repeats, most of its second differences are zero, and its noise level is their RMS
    (:func:`ocp.identify.noise_level.sensor_noise`), no longer the floor of 1e-6 of its peak."""
    d = diagnose(DCMotorPlant(P), step_log(np.where(np.arange(N) < 1500, 6.0, 2.0), 0.0))
    assert d.verdict == [] and d.explanations == [] and d.to_dict()["message"] == "nothing missing"


def test_an_effect_the_replica_takes_as_much_of_is_set_aside_and_said() -> None:
    """The 1 Hz sine's Stribeck band takes no more of the log's held-out error than of the nominal plant's replica
    (:func:`ocp.identify.replica.artifacts`): it is the method's error under this command, not named, and the answer
    says so."""
    d = diagnose(DCMotorPlant(P), step_log(6.0 * np.sin(2 * np.pi * 1.0 * T), 0.0))
    assert d.verdict == [] and [e.split(":")[0] for e in d.explanations] == ["stribeck is not named"]
    assert d.to_dict()["message"] == "nothing missing; " + d.explanations[0]


@pytest.mark.xfail(strict=True, reason="session 64: the replica's ripple is not the log's (module doc)")
def test_a_noise_free_square_from_zero_whose_method_error_effects_absorb_is_clean() -> None:
    assert diagnose(DCMotorPlant(P), step_log(np.where(np.sin(2 * np.pi * 2.0 * T) > 0, 6.0, 0.0), 0.0)).verdict == []


@pytest.mark.parametrize("u", [6.0 * np.sin(2 * np.pi * 1.0 * T), np.where(np.arange(N) >= 500, 6.0, 0.0)],
                         ids=["sine", "step-after-500-rows"])
def test_noise_free_commands_the_thrust_maps_method_error_spoilt_are_clean(u: np.ndarray) -> None:
    """Named a Stribeck band and a current offset until session 64 (module doc)."""
    assert diagnose(DCMotorPlant(P), step_log(u, 0.0)).verdict == []


def test_a_constant_under_the_floor_is_still_named() -> None:
    """Proving-ground 150 without noise (``bench/modelcheck.py --noise-free``: a 10 kHz log, cogging and ``B`` drawn
    off): ``B`` takes the torque equation from 0.05 noise units to 0. The floor is an effect's; a constant's
    materiality is the tolerance, and with the floor on it too ``B`` went unnamed. Until session 65 the thrust map's
    method error held that equation at 1.10 noise units, above the floor, which let a constant win at all; with it
    gone every equation is at its noise after the ripple, and ``B`` wins by halving the torque equation's error
    (:func:`ocp.identify.select._halves`), as an effect may."""
    case = noise_free(make_case(150))
    assert case.expected == {"cogging", "param:B"}
    assert diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case)).verdict == ["cogging", "param:B"]
