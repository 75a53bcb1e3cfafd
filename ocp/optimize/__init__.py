"""The optimiser, by role: mission -> problem -> data -> collocation program -> solution -> verification.

:func:`optimize` (:mod:`ocp.optimize.solve`) is the entry point; it is imported on first use, so importing
this package (or :mod:`ocp.optimize.mission` alone) loads no solver.
"""

from __future__ import annotations

from typing import Any

__all__ = ["optimize"]


def __getattr__(name: str) -> Any:
    if name == "optimize":
        from ocp.optimize.solve import optimize

        return optimize
    raise AttributeError(f"module 'ocp.optimize' has no attribute {name!r}")
