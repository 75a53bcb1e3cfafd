"""Optimisation results: the answer of :func:`ocp.optimize.solve.optimize` and its JSON form (types only).

Built by :mod:`ocp.optimize.solution` (an optimised answer) and :mod:`ocp.reference.fallback_answer` (the
analytic fallback); checked by :mod:`ocp.optimize.verify`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class OptimizeResult:
    """A reference and how it was obtained. Arrays have shape (N,) on ``t`` [s], SI units.

    Attributes:
        source: "optimized" or "analytic-fallback"
        status: IPOPT return status, or "fallback"
        reason: why the fallback was used ("" when optimised)
        arrays: t, thrust, thrust_desired, omega, theta, current, voltage (and ``torque`` for the
            torque plant: normalised input [rad/s^2])
        crossings: [{"t", "exponent", "sign_change"}] at each reversal of the returned thrust
        stretch: per phase, achieved duration / desired duration
        verification: thrust_rms_error, thrust_max_error [N] (simulation vs returned), tracking_rms_error
            [N] (returned vs desired), max_abs_current [A], max_abs_voltage [V], margins, path_ok
        solver: status, iterations, objective, constraint_violation, and times [s]: setup_time_s (mission
            -> problem data), build_time_s (0 when the structure's solver is cached), solve_time_s (IPOPT),
            verify_time_s (simulation and packaging); solve and verify add up over back-off rounds
    """

    name: str
    source: str
    status: str
    reason: str
    arrays: dict[str, np.ndarray]
    crossings: list[dict[str, Any]]
    stretch: list[float]
    verification: dict[str, Any]
    solver: dict[str, Any] = field(default_factory=dict)
    total_time_s: float = 0.0
    #: the simulated response on the integration grid (t, omega, current, voltage[, torque]), shapes (K,):
    #: what the limits are checked on between the output samples; not serialised
    fine: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def path_ok(self) -> bool:
        return bool(self.verification.get("path_ok", False))

    @property
    def solve_time_s(self) -> float:
        return float(self.solver.get("solve_time_s", 0.0))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (no NaN/inf) dict: the CLI's ``--json`` and the service's answer."""
        out: dict[str, Any] = {
            "name": self.name, "source": self.source, "status": self.status, "reason": self.reason,
            "solve_time_s": self.solve_time_s, "total_time_s": self.total_time_s,
            "iterations": self.solver.get("iterations"), "solver": json_ready(self.solver),
            "verification": json_ready(self.verification), "crossings": json_ready(self.crossings),
            "stretch": json_ready(self.stretch),
        }
        for k, v in self.arrays.items():
            out[k] = json_ready(np.asarray(v, float).tolist())
        return out


def json_ready(obj: Any) -> Any:
    """``obj`` with numpy scalars made plain and non-finite floats made ``None`` (strict JSON)."""
    if isinstance(obj, dict):
        return {k: json_ready(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_ready(v) for v in obj]
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


@dataclass(frozen=True)
class Unsolved:
    """A solve that gave no usable optimised answer: why, and the solver's report (the caller falls back)."""

    reason: str
    solver: dict[str, Any] = field(default_factory=dict)
    source: str = "unsolved"
