"""Response models generated from the core's result types, so the OpenAPI document lists every field with its
unit and the answer and its schema cannot drift apart.

:func:`model_of` turns a result dataclass (:mod:`ocp.optimize.result`) into a pydantic model: each field's
description is its ``doc`` metadata with its ``unit`` in brackets; a float reads as :data:`Real` (the core's
JSON spelling of non-finite numbers, :mod:`ocp.encoding`); a field with a default is optional.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from enum import Enum
from typing import Any, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, create_model

from ocp.optimize.result import (
    ARRAYS,
    COMPARE_CURVES,
    COMPARE_FIGURES,
    Crossing,
    MeshStep,
    SolverStats,
    Source,
    Status,
    Verification,
)

#: a number in the core's JSON: finite, "inf" / "-inf" where unbounded, null where it does not exist
Real = float | Literal["inf", "-inf"] | None


class _Open(BaseModel):
    model_config = ConfigDict(extra="allow")


def _describe(meta: typing.Mapping[str, Any]) -> str:
    unit = meta.get("unit", "")
    return f"{meta.get('doc', '')} [{unit}]" if unit else str(meta.get("doc", ""))


def _annotation(hint: Any, models: dict[type, type[BaseModel]]) -> Any:
    """The pydantic annotation of a dataclass field's type hint."""
    origin = typing.get_origin(hint)
    if origin in (Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        inner = _annotation(args[0], models) if len(args) == 1 else hint
        return inner if inner is Real else inner | None
    if origin is list:
        return list[_annotation(typing.get_args(hint)[0], models)]  # type: ignore[misc]
    if hint is float:
        return Real
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return model_of(hint, models)
    if isinstance(hint, type) and issubclass(hint, Enum):
        return hint
    return hint


def model_of(cls: type, models: dict[type, type[BaseModel]] | None = None) -> type[BaseModel]:
    """A pydantic model of the dataclass ``cls`` (fields with their units; nested dataclasses become models)."""
    models = {} if models is None else models
    if cls in models:
        return models[cls]
    hints = typing.get_type_hints(cls)
    fields: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        if not f.metadata.get("json", True):
            continue
        optional = f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
        default = None if optional else ...
        fields[f.name] = (_annotation(hints[f.name], models), Field(default=default, description=_describe(f.metadata)))
    model = create_model(f"{cls.__name__}Public", __base__=_Open, __doc__=(cls.__doc__ or "").strip(), **fields)
    models[cls] = model
    return model


_MODELS: dict[type, type[BaseModel]] = {}
SolverStatsPublic = model_of(SolverStats, _MODELS)
VerificationPublic = model_of(Verification, _MODELS)
OptimizeCrossingPublic = model_of(Crossing, _MODELS)
MeshStepPublic = model_of(MeshStep, _MODELS)


def _optimize_fields() -> dict[str, Any]:
    out: dict[str, Any] = {
        "name": (str, Field(description="the mission's name")),
        "source": (Source, Field(description="who answered: the solver or the analytic fallback")),
        "status": (Status, Field(description="IPOPT's return status, or fallback")),
        "reason": (str, Field(description="why the fallback answered (empty when optimised)")),
        "solve_time_s": (Real, Field(description="IPOPT wall time over every solve [s]")),
        "total_time_s": (Real, Field(description="wall time of the whole call [s]")),
        "iterations": (int, Field(description="IPOPT iterations [1]")),
        "solver": (SolverStatsPublic, Field(description="how the answer was computed")),
        "verification": (VerificationPublic, Field(description="the answer's command simulated and checked")),
        "crossings": (_annotation(list[Crossing], _MODELS), Field(description="reversals of the returned thrust")),
        "stretch": (list[Real], Field(description="achieved / desired duration per phase [1]")),
    }
    for name, (unit, doc) in ARRAYS.items():
        required = name != "torque"
        out[name] = (list[Real] if required else list[Real] | None,
                     Field(default=... if required else None, description=f"{doc}, shape (N,) [{unit}]"))
    return out


OptimizePublic = create_model(
    "OptimizePublic", __base__=_Open, **_optimize_fields(),
    __doc__=":meth:`ocp.optimize.result.OptimizeResult.to_dict`: the reference, who answered and how it was checked.")


def _list_of(model: type[BaseModel]) -> Any:
    return list[model]  # type: ignore[valid-type]


def _compare_models() -> tuple[type[BaseModel], type[BaseModel]]:
    row: dict[str, Any] = {"label": (str, Field(description="the shape: optimized (or fallback), sin^(2q+1)"))}
    for name, (unit, doc) in COMPARE_FIGURES.items():
        kind: Any = bool if name == "within_limits" else list[Real] if name == "crossing_exponents" else Real
        loop = name.startswith("loop_")
        row[name] = (kind | None if loop else kind,
                     Field(default=None if loop else ..., description=f"{doc} [{unit}]" if unit else doc))
    units = dict(zip(COMPARE_CURVES, ("s", "N", "rad/s", "A", "V"), strict=True))
    curve: dict[str, Any] = {"label": (str, Field(description="the shape"))}
    curve.update({k: (list[Real], Field(description=f"shape (M,) [{u}]; null where unbounded"))
                  for k, u in units.items()})
    return (create_model("CompareRowPublic", __base__=_Open, **row),
            create_model("CompareCurvePublic", __base__=_Open, **curve))


CompareRowPublic, CompareCurvePublic = _compare_models()
ComparePublic = create_model(
    "ComparePublic", __base__=_Open,
    mission=(str, Field(description="the mission's name")),
    table=(_list_of(CompareRowPublic), Field(description="one row per shape")),
    candidates=(_list_of(CompareCurvePublic), Field(description="each shape's arrays")),
    optimized_source=(Source, Field(description="who answered the optimised candidate")),
    optimized_reason=(str, Field(description="why the fallback answered (empty when optimised)")),
    __doc__=":meth:`ocp.optimize.compare.CompareResult.to_dict`: optimised vs analytic shapes of one mission.")
