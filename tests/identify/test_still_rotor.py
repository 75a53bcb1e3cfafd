"""Logs whose rotor never turns (issue #11: inputs this project did not generate; the blind rig drew two).

A rotor held still under a voltage (a blocked-rotor test, how R and L are often measured) crashed ``diagnose`` with
a ParameterError on the friction grids' smoothing width (scaled by a peak speed of zero, under the catalogue's
range); a log whose command is zero on every row was diagnosed as ``R`` 80 % low at 1e11 noise units. The first is
diagnosed, the second refused naming the command.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.errors import LogError
from ocp.identify import diagnose
from ocp.logs import log_from_arrays
from ocp.model.params import preset
from ocp.model.plant import DCMotorPlant


def _held(voltage: np.ndarray, dt: float = 1e-3) -> tuple:
    """A held rotor's log under ``voltage`` (N,) [V]: the armature's exact first-order current, speed and thrust 0."""
    p = preset("paper-rig")
    a = math.exp(-dt * p.R / p.L)
    i = np.zeros(voltage.size)
    for k in range(1, voltage.size):
        i[k] = a * i[k - 1] + (1.0 - a) * voltage[k - 1] / p.R
    rng = np.random.default_rng(0)
    t = dt * np.arange(voltage.size)
    zero = np.zeros(voltage.size)
    return p, log_from_arrays(t, voltage, i + 1e-3 * rng.standard_normal(i.size), zero, omega=zero)


def test_a_rotor_held_still_is_diagnosed() -> None:
    p, log = _held(np.repeat([0.0, 0.5, -0.5, 1.0, 0.2], 400))
    d = diagnose(DCMotorPlant(p), log)
    assert all(not item.startswith(("coulomb", "stribeck")) for item in d.verdict), d.verdict


def test_a_command_zero_on_every_row_is_refused_naming_it() -> None:
    p, log = _held(np.zeros(2000))
    with pytest.raises(LogError) as err:
        diagnose(DCMotorPlant(p), log)
    assert err.value.field == "voltage" and "zero on every row" in str(err.value)
