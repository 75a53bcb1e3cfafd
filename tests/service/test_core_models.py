"""The optimise answer's response model is generated from the core's result types: every numeric field is
documented with its unit, and real answers (the analytic fallback on both plants, an optimised min-time answer)
carry no field the model does not declare and validate against it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from pydantic import BaseModel

from ocp.optimize.compare import compare
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.solve import optimize
from ocp.reference.fallback_answer import analytic_fallback
from service.core_models import ComparePublic, OptimizePublic
from service.schemas import OptimizePublic as RouteModel

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())


def _undeclared(model: type[BaseModel], data: dict[str, Any], path: str = "") -> list[str]:
    """Keys of ``data`` (recursively) that ``model`` does not declare."""
    out = []
    for key, value in data.items():
        if key not in model.model_fields:
            out.append(path + key)
            continue
        ann = model.model_fields[key].annotation
        inner = [a for a in getattr(ann, "__args__", (ann,)) if isinstance(a, type) and issubclass(a, BaseModel)]
        if inner and isinstance(value, dict):
            out += _undeclared(inner[0], value, f"{path}{key}.")
        elif inner and isinstance(value, list):
            for item in value:
                out += _undeclared(inner[0], item, f"{path}{key}[].")
    return out


def test_the_route_serves_the_generated_model() -> None:
    assert RouteModel is OptimizePublic


@pytest.mark.parametrize("model", [OptimizePublic, ComparePublic])
def test_every_numeric_field_is_documented_with_its_unit(model: type[BaseModel]) -> None:
    schema = model.model_json_schema()
    missing = []
    for name, props in [("OptimizePublic", schema), *schema["$defs"].items()]:
        for field, spec in props.get("properties", {}).items():
            text = json.dumps(spec)
            numeric = '"number"' in text or '"integer"' in text
            if numeric and "[" not in spec.get("description", ""):
                missing.append(f"{name}.{field}")
    assert missing == []


def test_the_units_are_the_fields_own() -> None:
    defs = OptimizePublic.model_json_schema()["$defs"]
    assert "[N m]" in defs["VerificationPublic"]["properties"]["max_abs_torque"]["description"]
    assert defs["SolverStatsPublic"]["properties"]["solve_time_s"]["description"].endswith("[s]")
    assert "[J]" in ComparePublic.model_json_schema()["$defs"]["CompareRowPublic"]["properties"]["energy_j"][
        "description"]


@pytest.mark.parametrize("plant", ["dc-motor", "torque"])
def test_fallback_answers_match_the_model(plant: str) -> None:
    limits = {"torque": 0.02} if plant == "torque" else {"voltage": 12.0, "current": 1.0}
    d = analytic_fallback(mission_from_mapping({**EXAMPLE, "plant": plant, "limits": limits}), "test").to_dict()
    assert _undeclared(OptimizePublic, d) == []
    OptimizePublic.model_validate(d)
    assert ("max_abs_torque" in d["verification"]) == (plant == "torque")


def test_a_min_time_answer_matches_the_model() -> None:
    d = optimize(mission_from_mapping({**EXAMPLE, "objective": "min-time", "collocation": {"intervals": 40},
                                       "time_limit_s": 0.5})).to_dict()
    assert _undeclared(OptimizePublic, d) == []
    OptimizePublic.model_validate(d)
    assert "min_time_note" in d["verification"]


def test_a_comparison_matches_the_model() -> None:
    """sin^1 has an unbounded ideal command: its peaks and its unbounded samples are null."""
    d = compare(mission_from_mapping(EXAMPLE), (0,)).to_dict()
    assert _undeclared(ComparePublic, d) == []
    ComparePublic.model_validate(d)
    assert d["table"][1]["peak_current_a"] is None and d["table"][1]["energy_j"] is None
    assert all(v is None or isinstance(v, float) for v in d["candidates"][1]["current"])
