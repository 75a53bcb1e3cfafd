"""thrustshape's core: optimal thrust references for bidirectional propellers (``F = c_f w|w|``).

The public API, in the order data flows through it::

    params = load_params("paper-rig")                       # ocp.model: motor constants, effects, plants
    mission = load_mission("examples/reversal.json")        # ocp.optimize.mission: what a user asks for
    result = optimize_reference(mission)                    # ocp.optimize: collocation, or the fallback
    result.to_dict()                                        # ocp.encoding: one JSON spelling
    compare(mission); simulate_open_loop(plant, t, u, x0); diagnose(plant, log)

Names are imported on first use (PEP 562), so ``import ocp`` (and the CLI's ``--help``) loads nothing heavy.
A public name never shadows a subpackage: the optimiser's entry point is ``optimize_reference`` (the
service's operation of the same name; ``from ocp.optimize import optimize`` is the same function), the
closed-form reference ``analytic_reference`` and the open-loop simulation ``simulate_open_loop``.
"""

from __future__ import annotations

import importlib
from typing import Any

#: public name -> the module that defines it
_EXPORTS: dict[str, str] = {
    # model
    "MotorParams": "ocp.model.params", "load_params": "ocp.model.params",
    "load_plant": "ocp.model.effects", "PlantKind": "ocp.model.factory", "make_plant": "ocp.model.factory",
    "DCMotorPlant": "ocp.model.plant", "TorquePlant": "ocp.model.plant", "DriveBounds": "ocp.model.plant",
    "equilibrium": "ocp.model.equilibrium",
    # reference (closed forms and the fallback)
    "SinProfile": "ocp.reference.analytic", "analytic_reference": "ocp.reference.analytic",
    "design_sin": "ocp.reference.fallback", "analytic_fallback": "ocp.reference.fallback_answer",
    # optimise
    "Mission": "ocp.optimize.mission", "load_mission": "ocp.optimize.mission",
    "mission_from_mapping": "ocp.optimize.mission",
    "optimize_reference": "ocp.optimize.solve", "SolveContext": "ocp.optimize.collocation",
    "OptimizeResult": "ocp.optimize.result", "Source": "ocp.optimize.result", "Status": "ocp.optimize.result",
    "SolverStats": "ocp.optimize.result", "Verification": "ocp.optimize.result", "Crossing": "ocp.optimize.result",
    "compare": "ocp.optimize.compare", "CompareResult": "ocp.optimize.compare",
    # simulate
    "simulate_open_loop": "ocp.simulate.open_loop", "track": "ocp.simulate.closed_loop",
    # identify
    "check": "ocp.identify", "diagnose": "ocp.identify", "fit": "ocp.identify",
    # output and errors
    "jsonable": "ocp.encoding",
    "ThrustshapeError": "ocp.errors", "ParameterError": "ocp.errors", "MissionError": "ocp.errors",
    "InfeasibleError": "ocp.errors", "SolverError": "ocp.errors",
}

#: public names that differ from the defining module's
_ALIASES = {"optimize_reference": "optimize", "analytic_reference": "reference", "simulate_open_loop": "simulate"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'ocp' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), _ALIASES.get(name, name))
    globals()[name] = value  # imported once
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
