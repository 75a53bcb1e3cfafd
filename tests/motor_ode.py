"""The DC motor with its propeller written out in NumPy for scipy's integrators: an oracle independent of the
plant's CasADi expressions. State ``x = (w [rad/s], i [A])``, input ``v`` [V] (held: scipy's ``args``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

Rhs = Callable[[float, Any, float], list[float]]


def dc_motor_ode(p: Any) -> tuple[Rhs, Callable[[float, Any, float], list[list[float]]]]:
    """Right-hand side and its Jacobian for the constants ``p`` (``MotorParams``)."""
    def rhs(_t: float, z: Any, v: float) -> list[float]:
        w, i = z
        # eq. dc_mechanical, eq. dc_electrical
        return [(p.k_t * i - p.B * w - p.c_tau * w * abs(w)) / p.J, (v - p.R * i - p.k_e * w) / p.L]

    def jac(_t: float, z: Any, v: float) -> list[list[float]]:
        w = z[0]
        return [[-(p.B + 2.0 * p.c_tau * abs(w)) / p.J, p.k_t / p.J], [-p.k_e / p.L, -p.R / p.L]]

    return rhs, jac
