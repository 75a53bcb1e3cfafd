"""A proving-ground case diagnosed, with what the last explanation fitted (for tests that read a nuisance's or an
effect's coefficient): the diagnosis's ``_explain`` is watched for the run; its alignment set by hand; and a blind-rig
case regenerated and diagnosed as a user would (its CSV and parameter file read back)."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

import pytest

from bench.modelcheck import case_log
from ocp.identify import DiagnoseResult, diagnose
from ocp.identify.evidence import Fitted
from ocp.identify.regression import Design
from ocp.logs import read_log
from ocp.model.effects import load_plant
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
        out = explain(*args, **kwargs)
        seen["design"], seen["sel"] = out[:2]  # (and the effects set aside as the method's)
        return out

    monkeypatch.setattr(module, "_explain", spy)
    case = make_case(seed)
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case, angle=angle))
    return case, res, seen["design"], seen["sel"].final


def aligned_late(monkeypatch: pytest.MonkeyPatch, samples: float) -> None:
    """The diagnosis's alignment estimate replaced by ``samples`` [samples] of lag, everything else as estimated: a
    timing error set by hand (session 62's, before session 63 mended the search)."""
    module = sys.modules["ocp.identify.diagnose"]
    estimate = module.estimate
    monkeypatch.setattr(module, "estimate", lambda log, *a, **k: dataclasses.replace(
        estimate(log, *a, **k), samples=samples, seconds=samples * log.dt))


def blind(seed: int, directory: Path) -> tuple[DiagnoseResult, dict[str, Any]]:
    """Blind-rig case ``seed`` (``bench/blindrig``: its own integrator, effect formulas and loggers) generated into
    ``directory``, diagnosed from its files, and its truth file."""
    bench = str(Path(__file__).resolve().parents[2] / "bench")
    if bench not in sys.path:
        sys.path.insert(0, bench)
    from blindrig.case import generate

    csv, params, truth = generate(seed, directory)
    return diagnose(load_plant(params), read_log(csv)), json.loads(Path(truth).read_text())
