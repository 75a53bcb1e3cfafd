"""One timed call of an NLP solver (CasADi's IPOPT, or the flat program's own SQP, :class:`ocp.optimize.sqp.Solver`,
which reports its stats in IPOPT's words) and what a program reads from it."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Call:
    """One call of an NLP solver (IPOPT or the own SQP): the solver, its solution and stats, the return status,
    whether it succeeded (or stopped at IPOPT's acceptable level) and the wall time [s]."""

    solver: Any  # ca.Function (IPOPT) or ocp.optimize.sqp.Solver: called with the NLP's arguments, has stats()
    sol: dict[str, Any]
    stats: dict[str, Any]
    status: str
    success: bool
    seconds: float

    @property
    def iterations(self) -> int:
        return int(self.stats.get("iter_count", -1))


def call(solver: Any, args: dict[str, Any]) -> Call:
    """Call ``solver`` with ``args`` (x0, p, bounds, ...) and time it."""
    t0 = time.perf_counter()
    sol = solver(**args)
    seconds = time.perf_counter() - t0
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    return Call(solver, sol, stats, status, bool(stats.get("success", False)) or status == "Solved_To_Acceptable_Level",
                seconds)
