"""Exact feed-forward of a shaped speed: shaping coordinate -> speed derivatives -> thrust, current, voltage.

The shaper moves ``eta`` with ``omega = eta^m`` (``m`` odd: 1 or 3). Near a zero of ``eta`` crossed with
``eta' != 0`` the speed goes as ``s^m`` and the thrust ``c_f omega|omega|`` as ``sign(s)|s|^(2m)``: the
thrust exponent is ``g = 2m`` by construction (2: bounded commands; 6: current and voltage vanish at
the reversal and stay continuous, as in :func:`ocp.optimize.solve.crossing_order`).

Every function works on floats or numpy arrays of any one shape; units: omega [rad/s], omega' [rad/s^2],
omega'' [rad/s^3], thrust [N], current [A], voltage [V].
"""

from __future__ import annotations

from typing import Any

from ocp.model.params import MotorParams

Num = Any  # float or numpy array


def speed_derivatives(eta: Num, eta1: Num, eta2: Num, m: int) -> tuple[Num, Num, Num]:
    """(omega, omega', omega'') of ``omega = eta^m`` for m in {1, 3}, by the chain rule."""
    if m == 1:
        return eta, eta1, eta2
    e2 = eta * eta
    return e2 * eta, 3.0 * e2 * eta1, 6.0 * eta * eta1 * eta1 + 3.0 * e2 * eta2


def target_coordinate(thrust: Num, c_f: float, m: int) -> Num:
    """``eta`` whose speed produces ``thrust`` statically: ``sign(F) (|F|/c_f)^(1/(2m))`` (Fig. 1 inverse)."""
    mag = (abs(thrust) / c_f) ** (0.5 / m)
    return mag * (thrust > 0) - mag * (thrust < 0)


class Inverse:
    """Plant inverse of paper eqs. current_reference / voltage_reference with the rig's coefficients."""

    __slots__ = ("a1", "a2", "a3", "b1", "b2", "b3", "b4", "b5", "c_f")

    def __init__(self, params: MotorParams) -> None:
        self.a1, self.a2, self.a3 = params.current_coefficients
        self.b1, self.b2, self.b3, self.b4, self.b5 = params.voltage_coefficients
        self.c_f = params.c_f

    def thrust(self, w: Num) -> Num:
        # eq:thrust_model  F = c_f w|w|
        return self.c_f * w * abs(w)

    def current(self, w: Num, w1: Num) -> Num:
        # eq:current_reference  i_d = a1 w' + a2 w + a3 w|w|
        return self.a1 * w1 + self.a2 * w + self.a3 * w * abs(w)

    def voltage(self, w: Num, w1: Num, w2: Num) -> Num:
        # eq:voltage_reference  V_d = b1 w'' + b2 w' + b3 w + b4 w|w| + b5 |w| w'
        aw = abs(w)
        return self.b1 * w2 + self.b2 * w1 + self.b3 * w + self.b4 * w * aw + self.b5 * aw * w1
