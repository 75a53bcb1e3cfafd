"""Task functions: what runs inside a worker process (or on a Dask worker).

Each takes and returns a JSON-ready dict, re-validates its input (it may come from the job store or a Dask
queue) with the untrusted rule (:func:`untrusted_mission`: ``params`` a preset or a mapping, never a file),
imports the core lazily (the server process never builds a solver) and returns JSON-safe output
(no NaN: non-finite floats become "inf" / "-inf" / null).

:func:`available_tasks` decides at app creation which optional backends exist in this install;
a route whose backend is missing is not registered.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import math
import time
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from pydantic import TypeAdapter

from ocp.errors import MissionError, ThrustshapeError
from service.workers import TaskFn

if TYPE_CHECKING:
    from ocp.optimize.mission import Mission

Payload = dict[str, Any]
KeyFn = Callable[[Payload], Hashable | None]
#: kept between IPOPT's stop and the worker's deadline, for verifying the result (or the in-worker fallback) [s]
SOLVE_MARGIN_S = 1.0
#: the one key of a task's answer that was checked against its public model and rendered to JSON in the worker
RENDERED = "rendered_json"


def untrusted_mission(data: Any) -> Mission:
    """A mission from a request, the job store or a queue, validated as untrusted input: ``params`` may name a
    preset or be a mapping, never a file on this machine; errors are :class:`~ocp.errors.MissionError` naming
    the field (``params``) and the reason."""
    from ocp.optimize.mission import mission_from_mapping

    return mission_from_mapping(data, allow_files=False)


def analytic_reference(payload: Payload) -> Payload:
    """``{"request": SinRequest | DesignRequest, "max_samples": int}`` -> :meth:`Reference.to_dict`
    (+ ``design`` for a design request)."""
    from ocp.model.params import load_params
    from ocp.reference.analytic import reference, time_grid
    from ocp.reference.fallback import design_sin
    from service.schemas import AnalyticRequest, DesignRequest

    req = TypeAdapter(AnalyticRequest).validate_python(payload["request"])
    params = load_params(req.params)
    design = None
    if isinstance(req, DesignRequest):
        d = design_sin(params, req.limits.current, req.limits.voltage, req.regularity,
                       amplitude=req.amplitude, period=req.period)
        prof = d.profile
        design = {"q": int(prof.q), "amplitude": float(prof.amplitude), "period": float(prof.period),
                  "peak_current": float(d.peak_current), "peak_voltage": float(d.peak_voltage)}
    else:
        from ocp.reference.analytic import SinProfile

        prof = SinProfile(req.amplitude, req.period, req.q, req.phase)
    duration = prof.period if req.duration is None else req.duration
    n = duration * req.rate + 1.0
    if not n <= int(payload["max_samples"]):
        raise MissionError("duration" if req.duration is not None else "rate",
                           f"the reference would have {n:.4g} samples; at most {payload['max_samples']} allowed")
    out = reference(prof, params, time_grid(duration, req.rate)).to_dict()
    if design is not None:
        out["design"] = design
    return out


def optimize_mission(payload: Payload) -> Payload:
    """Mission -> :meth:`ocp.optimize.result.OptimizeResult.to_dict` (the solver bounds its own CPU time). A solver
    build is reported to the worker's parent (:func:`service.workers.report_phase`): it survives the deadline."""
    from ocp.optimize.collocation import SolveContext
    from service.workers import report_phase, time_left

    module = importlib.import_module("ocp.optimize.solve")
    left = time_left()  # IPOPT stops early enough to verify and answer before the worker would be killed
    context = SolveContext(deadline=math.inf if left is None else time.perf_counter() + left - SOLVE_MARGIN_S,
                           on_build=report_phase)
    # warm=None: start from the worker's last solution of the same structure when it is plausibly close
    # (repeated requests, batch items; ocp.optimize.warm), else cold
    return module.optimize(untrusted_mission(payload), warm=None, context=context).to_dict()


def _rendered(data: Payload, check: bool = True) -> Payload:
    """``data`` checked against the optimise answer's public model (``check``) and rendered to JSON bytes here,
    in the worker: the server sends or stores the bytes as they are (:func:`service.api.answers.json_answer`,
    :func:`service.jobs.result_text`), its event loop neither unpickles 16,000 numbers nor validates and renders
    them."""
    import pydantic_core

    if check:
        from service.schemas import OptimizePublic

        OptimizePublic.model_validate(data)
    return {RENDERED: pydantic_core.to_json(data)}


def batch_answer(payload: Payload) -> Payload:
    """:func:`optimize_mission` for a stored batch item, its answer rendered to JSON (``{RENDERED: bytes}``)."""
    return _rendered(optimize_mission(payload), check=False)


def optimize_answer(payload: Payload) -> Payload:
    """:func:`optimize_mission`, its answer checked and rendered (``{RENDERED: bytes}``), for the HTTP route."""
    return _rendered(optimize_mission(payload))


def fallback_answer(payload: Payload) -> Payload:
    """:func:`fallback_mission`, its answer checked and rendered (``{RENDERED: bytes}``), for the HTTP route."""
    return _rendered(fallback_mission(payload))


def fallback_mission(payload: Payload) -> Payload:
    """``{"mission": ..., "reason": ...}`` -> the analytic fallback answer (cheap, no IPOPT; within the limits or
    :class:`~ocp.errors.InfeasibleError`)."""
    analytic_fallback = importlib.import_module("ocp.reference.fallback_answer").analytic_fallback
    mission = untrusted_mission(payload["mission"])
    return analytic_fallback(mission, str(payload["reason"])).to_dict()


def compare_mission(payload: Payload) -> Payload:
    """``{"mission": Mission, "qs": [q, ...] | None}`` -> :meth:`ocp.optimize.compare.CompareResult.to_dict`."""
    compare = importlib.import_module("ocp.optimize.compare").compare
    qs = payload.get("qs")
    mission = untrusted_mission(payload["mission"])
    result = compare(mission) if not qs else compare(mission, tuple(int(q) for q in qs))
    return result.to_dict()


def structure_key(payload: Payload) -> str | None:
    """Affinity key of a mission, computed in the parent before it is sent to a worker (about a millisecond, no
    solver built): the collocation structure it is solved with (phases, intervals per phase, input chain, plant
    constants and effects; :class:`ocp.optimize.collocation.Structure`, the key of a worker's program cache).
    Missions with one key are solved by one cached program. Validates with the untrusted rule, so a bad mission
    is refused (:class:`~ocp.errors.MissionError` naming the field) before it takes a worker; ``None`` when the
    structure cannot be told here (the worker then decides)."""
    from ocp.optimize.problem import problem_for

    mission = untrusted_mission(payload)
    try:
        st = problem_for(mission).structure
    except ThrustshapeError:
        raise
    except Exception:  # the worker reports what is wrong, with its own error handling
        return None
    plant = hashlib.sha256(st.plant_key.encode()).hexdigest()[:16]
    return f"{st.n_phases}x{st.intervals}/chain{st.chain}/{plant}"


def affinity_keys(payload: Payload) -> Payload:
    """``{"key": KeyFn, "missions": [...]}`` -> ``{"keys": [{"key": ...} | {"error": [type, field, reason]}]}``:
    each mission's affinity key (e.g. :func:`structure_key`), or the core error that refuses the mission, computed
    in a worker process for a batch runner (the server process computes nothing of a request)."""
    key: KeyFn = payload["key"]
    out: list[Payload] = []
    for mission in payload["missions"]:
        try:
            out.append({"key": key(mission)})
        except ThrustshapeError as exc:
            out.append({"error": [type(exc).__name__, exc.field, exc.reason]})
    return {"keys": out}


def _has(module: str) -> bool:
    """Whether ``module`` is in this install, found without importing it: the server process stays free of the
    core's numerical stack (CasADi, SciPy: seconds per server start), which only the workers import."""
    try:
        return importlib.util.find_spec(module) is not None
    except ImportError:
        return False


@dataclass(frozen=True)
class TaskSet:
    """The task function behind each route; ``None`` = backend absent, route not registered.

    Tests pass their own (e.g. a CPU-bound task that overruns) to exercise timeouts and restarts.
    """

    analytic: TaskFn = analytic_reference
    optimize: TaskFn | None = None
    fallback: TaskFn | None = None
    compare: TaskFn | None = None
    batch_item: TaskFn | None = None
    #: a batch item's affinity key (e.g. :func:`structure_key`), computed in the parent; ``None``: no affinity
    batch_key: KeyFn | None = None
    model_check: TaskFn | None = None
    extra_preload: tuple[str, ...] = field(default=())


def available_tasks() -> TaskSet:
    """Tasks whose core modules exist in this install (checked when the app is created)."""
    has_opt = _has("ocp.optimize.solve") and _has("ocp.reference.fallback_answer")
    has_cmp = _has("ocp.optimize.compare")
    has_mc = _has("ocp.identify")
    from service.modelcheck import model_check

    return TaskSet(
        optimize=optimize_answer if has_opt else None,
        fallback=fallback_answer if has_opt else None,
        compare=compare_mission if has_cmp else None,
        batch_item=batch_answer if has_opt else None,
        batch_key=structure_key if has_opt else None,
        model_check=model_check if has_mc else None,
        extra_preload=tuple(m for m, ok in (("ocp.optimize.solve", has_opt), ("service.schemas", has_opt),
                                            ("ocp.optimize.compare", has_cmp),
                                            ("ocp.identify", has_mc)) if ok),
    )
