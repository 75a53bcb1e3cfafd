"""One timed call of a CasADi NLP solver (IPOPT) and what a program reads from it."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import casadi as ca


@dataclass(frozen=True)
class Call:
    """One call of a CasADi NLP solver (IPOPT): the solver, its solution and stats, the return status,
    whether it succeeded (or stopped at IPOPT's acceptable level) and the wall time [s]."""

    solver: ca.Function
    sol: dict[str, Any]
    stats: dict[str, Any]
    status: str
    success: bool
    seconds: float

    @property
    def iterations(self) -> int:
        return int(self.stats.get("iter_count", -1))


def call(solver: ca.Function, args: dict[str, Any]) -> Call:
    """Call ``solver`` with ``args`` (x0, p, bounds, ...) and time it."""
    t0 = time.perf_counter()
    sol = solver(**args)
    seconds = time.perf_counter() - t0
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    return Call(solver, sol, stats, status, bool(stats.get("success", False)) or status == "Solved_To_Acceptable_Level",
                seconds)
