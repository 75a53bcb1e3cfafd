"""A proving-ground case diagnosed, with what the last explanation fitted (for tests that read a nuisance's or an
effect's coefficient): the diagnosis's ``_explain`` is watched for the run."""

from __future__ import annotations

import sys
from typing import Any

import pytest

from bench.modelcheck import case_log
from ocp.identify import DiagnoseResult, diagnose
from ocp.identify.evidence import Fitted
from ocp.identify.regression import Design
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def diagnosed(seed: int, angle: bool, monkeypatch: pytest.MonkeyPatch) -> tuple[Any, DiagnoseResult, Design, Fitted]:
    """Case ``seed`` (its angle column kept or left out, :func:`bench.modelcheck.case_log`), its diagnosis, and the
    last explanation's design and final fit."""
    module = sys.modules["ocp.identify.diagnose"]
    seen: dict[str, Any] = {}
    explain = module._explain

    def spy(*args: Any, **kwargs: Any) -> Any:
        seen["design"], seen["sel"] = out = explain(*args, **kwargs)
        return out

    monkeypatch.setattr(module, "_explain", spy)
    case = make_case(seed)
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case, angle=angle))
    return case, res, seen["design"], seen["sel"].final
