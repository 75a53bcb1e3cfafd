"""Optimisation results: the answer of :func:`ocp.optimize.solve.optimize` and its parts (types only).

Built by :mod:`ocp.optimize.solution` (an optimised answer) and :mod:`ocp.reference.fallback_answer` (the
analytic fallback); checked by :mod:`ocp.optimize.verify`; written as JSON by :func:`ocp.encoding.jsonable`.
Every numeric field carries its unit in its metadata (``unit``; ``1`` for a pure number), from which the
service generates its documented response models (:mod:`service.schemas`).

The records also read like the mappings they replace (``result.verification["path_ok"]``,
``result.solver.get("iterations")``): an unset optional field (``None``) reads as absent.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from ocp.encoding import jsonable


def info(unit: str, doc: str, **extra: Any) -> dict[str, Any]:
    """Field metadata: its SI unit (``1``: dimensionless, ``""``: not a number) and one line of doc."""
    return {"unit": unit, "doc": doc, **extra}


class Source(StrEnum):
    """Who answered: the solver, or the analytic fallback (with the reason)."""

    OPTIMIZED = "optimized"
    ANALYTIC_FALLBACK = "analytic-fallback"


class Status(StrEnum):
    """IPOPT's return status of the (last) solve; ``fallback`` for an analytic answer."""

    SOLVE_SUCCEEDED = "Solve_Succeeded"
    SOLVED_TO_ACCEPTABLE_LEVEL = "Solved_To_Acceptable_Level"
    FEASIBLE_POINT_FOUND = "Feasible_Point_Found"
    INFEASIBLE_PROBLEM_DETECTED = "Infeasible_Problem_Detected"
    SEARCH_DIRECTION_BECOMES_TOO_SMALL = "Search_Direction_Becomes_Too_Small"
    DIVERGING_ITERATES = "Diverging_Iterates"
    USER_REQUESTED_STOP = "User_Requested_Stop"
    MAXIMUM_ITERATIONS_EXCEEDED = "Maximum_Iterations_Exceeded"
    MAXIMUM_CPUTIME_EXCEEDED = "Maximum_CpuTime_Exceeded"
    MAXIMUM_WALLTIME_EXCEEDED = "Maximum_WallTime_Exceeded"
    RESTORATION_FAILED = "Restoration_Failed"
    ERROR_IN_STEP_COMPUTATION = "Error_In_Step_Computation"
    NOT_ENOUGH_DEGREES_OF_FREEDOM = "Not_Enough_Degrees_Of_Freedom"
    INVALID_PROBLEM_DEFINITION = "Invalid_Problem_Definition"
    INVALID_OPTION = "Invalid_Option"
    INVALID_NUMBER_DETECTED = "Invalid_Number_Detected"
    UNRECOVERABLE_EXCEPTION = "Unrecoverable_Exception"
    NONIPOPT_EXCEPTION_THROWN = "NonIpopt_Exception_Thrown"
    INSUFFICIENT_MEMORY = "Insufficient_Memory"
    INTERNAL_ERROR = "Internal_Error"
    UNKNOWN = "unknown"
    FALLBACK = "fallback"

    @classmethod
    def parse(cls, status: str) -> Status:
        """The member of IPOPT's ``return_status`` string (``unknown`` for one this list does not know)."""
        try:
            return cls(status)
        except ValueError:
            return cls.UNKNOWN

    @property
    def stopped_by_time(self) -> bool:
        """IPOPT stopped at a wall-time or CPU-time limit (its own or the deadline callback's)."""
        return self in (Status.USER_REQUESTED_STOP, Status.MAXIMUM_CPUTIME_EXCEEDED, Status.MAXIMUM_WALLTIME_EXCEEDED)


class SolverProgram(StrEnum):
    """Which program produced an optimised answer: the flat B-spline program in the speed
    (:mod:`ocp.optimize.flat`, the fast path) or the Radau collocation program (the reference and fallback)."""

    FLAT = "flat"
    RADAU = "radau"


class Record:
    """Read access by name for a result record (dataclass): ``r["x"]``, ``r.get("x")``, ``"x" in r``."""

    def _names(self) -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(self))  # type: ignore[arg-type]

    def __getitem__(self, key: str) -> Any:
        if key not in self._names():
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default: Any = None) -> Any:
        value = getattr(self, key, None) if key in self._names() else None
        return default if value is None else value

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and key in self._names() and getattr(self, key) is not None

    def keys(self) -> Iterator[str]:
        return (k for k in self._names() if getattr(self, k) is not None)


@dataclass
class SolverStats(Record):
    """How the answer was computed; times add up over the back-off rounds (the build happens in the first)."""

    status: Status = field(default=Status.UNKNOWN, metadata=info("", "return status of the last solve (IPOPT's "
                                                                 "vocabulary; the flat program's SQP uses the same "
                                                                 "words)"))
    method: str = field(default="ipopt", metadata=info(
        "", "NLP solver of the last solve: ipopt, or sqp (the flat program's first try: its own SQP, QPs by DAQP)"))
    compiled: bool = field(default=False, metadata=info(
        "", "the SQP evaluated its functions compiled to C (a program solved often; ocp.optimize.native_nlp)"))
    program: SolverProgram = field(default=SolverProgram.RADAU, metadata=info(
        "", "the program that produced the answer: flat (B-spline in the speed) or radau (collocation)"))
    flat_attempt_s: float = field(default=0.0, metadata=info(
        "s", "time spent on a flat program attempt that did not answer (then the Radau program did)"))
    iterations: int = field(default=0, metadata=info("1", "NLP solver iterations over every solve (SQP and IPOPT)"))
    objective: float = field(default=float("nan"), metadata=info("1", "objective of the last solve (scaled)"))
    constraint_violation: float = field(default=0.0, metadata=info("1", "largest scaled collocation residual"))
    setup_time_s: float = field(default=0.0, metadata=info("s", "mission to problem data"))
    build_time_s: float = field(default=0.0, metadata=info("s", "building the program (0 when cached)"))
    solve_time_s: float = field(default=0.0, metadata=info("s", "NLP solver wall time"))
    verify_time_s: float = field(default=0.0, metadata=info("s", "simulation and packaging"))
    backoff_rounds: int = field(default=0, metadata=info("1", "re-solves with limits backed off between nodes"))
    limit_backoff: float = field(default=1.0, metadata=info("1", "smallest bound / limit after the back-off"))
    backoff_intervals: int = field(default=0, metadata=info("1", "collocation intervals whose bounds were backed off"))
    warm_start: bool = field(default=False, metadata=info("", "the first solve started from the program's last "
                                                          "solution (ocp.optimize.warm)"))


@dataclass(frozen=True)
class MeshStep(Record):
    """One mesh of a min-time refinement."""

    intervals: int = field(metadata=info("1", "collocation intervals over all phases"))
    min_time_s: float = field(metadata=info("s", "verified duration on this mesh"))


_TORQUE = ("max_abs_torque", "torque_margin")
_MIN_TIME = ("min_time_s", "min_time_error_bound_s", "min_time_converged", "min_time_mesh", "min_time_note",
             "analytic_min_time_s")


@dataclass
class Verification(Record):
    """A-posteriori check of the answer: its command simulated on the mission's plant (ocp.optimize.verify).

    The torque fields are set for the torque channel only, the min-time fields for a min-time mission only
    (:func:`ocp.optimize.min_time.summary`); unset ones are left out of the JSON form.
    """

    thrust_rms_error: float = field(metadata=info("N", "RMS of simulated - planned thrust"))
    thrust_max_error: float = field(metadata=info("N", "largest |simulated - planned thrust|"))
    tracking_rms_error: float = field(metadata=info("N", "RMS of returned - desired thrust"))
    max_abs_current: float = field(metadata=info("A", "peak |current| (torque channel: DC equivalent)"))
    max_abs_voltage: float = field(metadata=info("V", "peak |voltage| (torque channel: DC equivalent)"))
    max_abs_speed: float = field(metadata=info("rad/s", "peak |speed|"))
    current_margin: float = field(metadata=info("A", "current limit - peak |current|"))
    voltage_margin: float = field(metadata=info("V", "voltage limit - peak |voltage|"))
    path_ok: bool = field(metadata=info("", "the simulated response keeps every limit between the samples too"))
    max_abs_torque: float | None = field(default=None, metadata=info("N m", "peak |torque| (torque channel)"))
    torque_margin: float | None = field(default=None, metadata=info("N m", "torque limit - peak (torque channel)"))
    min_time_s: float | None = field(default=None, metadata=info("s", "finest verified duration (min-time)"))
    min_time_error_bound_s: float | None = field(default=None, metadata=info(
        "s", "the last mesh doubling's change of the duration (min-time)"))
    min_time_converged: bool | None = field(default=None, metadata=info("", "the last change is within tolerance"))
    min_time_mesh: list[MeshStep] | None = field(default=None, metadata=info("", "every mesh solved (min-time)"))
    min_time_note: str | None = field(default=None, metadata=info("", "why it is not a converged minimum"))
    analytic_min_time_s: float | None = field(default=None, metadata=info(
        "s", "half the period of the fastest A sin^(2q+1) within the same limits (min-time)"))

    def __json__(self) -> dict[str, Any]:
        torque = self.max_abs_torque is not None
        min_time = self.min_time_note is not None
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if (f.name not in _TORQUE or torque) and (f.name not in _MIN_TIME or min_time)}


@dataclass(frozen=True)
class Crossing(Record):
    """A reversal of the returned thrust."""

    t: float = field(metadata=info("s", "time of the sign change"))
    exponent: float = field(metadata=info("1", "local exponent g: |F| ~ |t - t_s|^g"))
    sign_change: bool = field(default=True, metadata=info("", "the thrust changes sign"))
    current: float | None = field(default=None, metadata=info("A", "planned current at the crossing"))
    voltage: float | None = field(default=None, metadata=info("V", "planned input at the crossing"))


#: the answer's arrays (shape (N,) on ``t``; the command on its own knots ``command_t``): unit and doc
ARRAYS: dict[str, tuple[str, str]] = {
    "t": ("s", "output times"),
    "thrust": ("N", "thrust of the simulated response"),
    "thrust_desired": ("N", "desired thrust at the (retimed) output times"),
    "omega": ("rad/s", "rotor speed"),
    "theta": ("rad", "rotor angle"),
    "current": ("A", "armature current (torque channel: DC equivalent)"),
    "voltage": ("V", "armature voltage (torque channel: DC equivalent)"),
    "torque": ("rad/s^2", "normalised torque input tau/J (torque channel only)"),
    "command_t": ("s", "knots of the held command"),
    "command": ("V or rad/s^2", "plant input held from each knot on"),
}


#: the comparison table's columns (:mod:`ocp.optimize.compare`) besides ``label``: unit and doc (the Section V
#: loop's only for a voltage plant)
COMPARE_FIGURES: dict[str, tuple[str, str]] = {
    "duration_s": ("s", "length of the shape"),
    "peak_current_a": ("A", "peak |current| of the ideal feedforward; null: unbounded"),
    "peak_voltage_v": ("V", "peak |voltage| of the ideal feedforward; null: unbounded"),
    "energy_j": ("J", "electrical energy of the ideal feedforward; null: unbounded"),
    "thrust_rms_error_n": ("N", "RMS of the shape's thrust - the desired thrust"),
    "crossing_exponents": ("1", "local thrust exponent g at each reversal"),
    "within_limits": ("", "the ideal feedforward keeps the current and voltage limits"),
    "loop_thrust_rms_n": ("N", "Section V closed loop: thrust RMS error"),
    "loop_speed_rms_rad_s": ("rad/s", "Section V closed loop: speed RMS error"),
    "loop_local_speed_error_rad_s": ("rad/s", "Section V closed loop: speed error around the reversals"),
    "loop_peak_voltage_v": ("V", "Section V closed loop: peak |voltage|"),
    "loop_peak_current_a": ("A", "Section V closed loop: peak |current|"),
}
COMPARE_CURVES = ("t", "thrust", "omega", "current", "voltage")  # each candidate's arrays: s, N, rad/s, A, V


@dataclass
class OptimizeResult:
    """A reference and how it was obtained. Arrays have shape (N,) on ``t`` [s], SI units (:data:`ARRAYS`).

    Attributes:
        source: who answered; status: IPOPT's return status or ``fallback``
        reason: why the fallback was used ("" when optimised)
        crossings: at each reversal of the returned thrust
        stretch: per phase, achieved duration / desired duration
        total_time_s: wall time of the whole call [s]
        fine: the simulated response on the integration grid (t, omega, current, voltage[, torque]), shapes (K,):
            what the limits are checked on between the output samples; not serialised
    """

    name: str
    source: Source
    status: Status
    reason: str
    arrays: dict[str, np.ndarray]
    crossings: list[Crossing]
    stretch: list[float]
    verification: Verification
    solver: SolverStats = field(default_factory=SolverStats)
    total_time_s: float = 0.0
    fine: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def path_ok(self) -> bool:
        return bool(self.verification.path_ok)

    @property
    def solve_time_s(self) -> float:
        return float(self.solver.solve_time_s)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (:func:`ocp.encoding.jsonable`): the CLI's ``--json`` and the service's answer."""
        out: dict[str, Any] = {
            "name": self.name, "source": self.source, "status": self.status, "reason": self.reason,
            "solve_time_s": self.solve_time_s, "total_time_s": self.total_time_s,
            "iterations": self.solver.iterations, "solver": self.solver, "verification": self.verification,
            "crossings": self.crossings, "stretch": self.stretch,
        }
        out.update({k: np.asarray(v, float) for k, v in self.arrays.items()})
        return dict(jsonable(out))


@dataclass
class Unsolved:
    """A solve that gave no usable optimised answer: why, and the solver's report (the caller falls back)."""

    reason: str
    solver: SolverStats = field(default_factory=SolverStats)
    source: str = "unsolved"
