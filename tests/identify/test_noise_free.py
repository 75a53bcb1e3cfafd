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

Not fixed (strict expected failures, measured): the 0/6 V square's drag asymmetry (torque equation 2.0 -> 0.74 noise
units) is taken for the method's, but a ripple is then named, and the replica's ripple (its period count picked from
the replica's own spectrum) takes less of the replica than the log's of the log (2.66 against 3.29 squared noise
units); the 1 Hz sine is aligned 0.53 samples late (0.94 applied) on this exact log, so the replica, run under the
shifted command, is not the log (its armature equation at 1.6 noise units, the log's at 1,039), and the Stribeck band
takes 0.026 of the log against 0.021 of it. Nor, outside these tests, a step from rest (0 -> 6 V after 200 rows): a
force offset of -2.3e-5 N is named noise-free (the thrust equation low-passes ``c_f w|w|`` and the thrust alike; the
square of a low-pass is not the low-pass of the square, and over a spin-up that bias is one-signed). With the loggers'
noise at a tenth of the usual level every command here is clean.
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
    """Session 63 named a current offset and a Stribeck band here; the current offset takes no more of the log's
    held-out error than of the nominal plant's replica (:func:`ocp.identify.replica.artifacts`), and without it
    nothing is adopted; the answer says so."""
    d = diagnose(DCMotorPlant(P), step_log(np.where(np.arange(N) < 1500, 6.0, 2.0), 0.0))
    assert d.verdict == [] and [e.split(":")[0] for e in d.explanations] == ["current_offset is not named"]
    assert d.to_dict()["message"] == "nothing missing; " + d.explanations[0]


@pytest.mark.xfail(strict=True, reason="session 64: the replica's ripple is not the log's; the sine's alignment is "
                                       "off by a sample on an exact log (module doc)")
@pytest.mark.parametrize("u", [np.where(np.sin(2 * np.pi * 2.0 * T) > 0, 6.0, 0.0),
                               6.0 * np.sin(2 * np.pi * 1.0 * T)], ids=["square-0-6", "sine"])
def test_noise_free_commands_whose_method_error_effects_absorb_are_clean(u: np.ndarray) -> None:
    assert diagnose(DCMotorPlant(P), step_log(u, 0.0)).verdict == []


def test_a_constant_under_the_floor_is_still_named() -> None:
    """Proving-ground 150 without noise (``bench/modelcheck.py --noise-free``: a 10 kHz log, cogging and ``B`` drawn
    off): ``B`` takes the torque equation from 0.05 noise units to 0. The floor is an effect's; a constant's
    materiality is the tolerance, and with the floor on it too ``B`` went unnamed."""
    case = noise_free(make_case(150))
    assert case.expected == {"cogging", "param:B"}
    assert diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case)).verdict == ["cogging", "param:B"]
