"""The core's one JSON encoder (ocp.encoding): one spelling of non-finite numbers, strict JSON out."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

from ocp.encoding import jsonable
from ocp.optimize.result import Source, Status, Verification


@dataclass
class _Row:
    x: float
    kept: list[float]
    hidden: int = field(default=0, metadata={"json": False})


def test_non_finite_numbers_have_one_spelling_everywhere() -> None:
    data = {"a": math.inf, "b": -np.inf, "c": np.float32("nan"), "arr": np.array([1.0, np.inf, -np.inf, np.nan]),
            "row": _Row(x=-math.inf, kept=[math.nan, 2.5], hidden=3), "n": np.int64(4), "ok": np.bool_(True)}
    out = jsonable(data)
    assert out == {"a": "inf", "b": "-inf", "c": None, "arr": [1.0, "inf", "-inf", None],
                   "row": {"x": "-inf", "kept": [None, 2.5]}, "n": 4, "ok": True}
    assert type(out["n"]) is int and type(out["ok"]) is bool
    json.dumps(out, allow_nan=False)  # strict JSON


def test_enums_are_their_values_and_records_choose_their_fields() -> None:
    v = Verification(thrust_rms_error=1e-4, thrust_max_error=2e-4, tracking_rms_error=3e-4, max_abs_current=math.inf,
                     max_abs_voltage=1.0, max_abs_speed=50.0, current_margin=-math.inf, voltage_margin=11.0,
                     path_ok=False)
    out = jsonable({"source": Source.ANALYTIC_FALLBACK, "status": Status.parse("Not_A_Status"), "v": v})
    assert out["source"] == "analytic-fallback" and out["status"] == "unknown"
    assert out["v"]["max_abs_current"] == "inf" and out["v"]["current_margin"] == "-inf"
    assert "max_abs_torque" not in out["v"] and "min_time_s" not in out["v"]  # unset groups left out
    v.max_abs_torque, v.torque_margin, v.min_time_note = 0.02, 0.0, ""
    out = jsonable(v)
    assert out["max_abs_torque"] == 0.02 and out["min_time_s"] is None and out["min_time_note"] == ""


def test_array_fast_path_equals_the_per_element_spelling() -> None:
    """Finite float, int and bool arrays skip the per-element walk (``tolist``); the output must be the walk's,
    element for element and type for type, and one non-finite element must send the array through the walk."""
    rng = np.random.default_rng(3)
    for arr in (rng.normal(size=(7,)) * 1e3, rng.normal(size=(3, 4)).astype(np.float32),
                rng.integers(-5, 5, size=9), rng.normal(size=6) > 0, np.array([1.0, 2.0, np.nan, -np.inf])):
        walk = [jsonable(v) for v in arr.tolist()] if arr.ndim == 1 else [[jsonable(v) for v in row]
                                                                          for row in arr.tolist()]
        out = jsonable(arr)
        assert out == walk
        flat = out if arr.ndim == 1 else [v for row in out for v in row]
        assert [type(v) for v in flat] == [type(v) for v in (walk if arr.ndim == 1 else
                                                             [v for row in walk for v in row])]
    assert jsonable(np.array([0.5, np.nan, np.inf])) == [0.5, None, "inf"]
