"""The worker tasks answer plain JSON: only dict/list/str/int/float/bool/None, finite floats.

The core's ``to_dict()`` methods promise this; the tasks return them as they are (no second walk per
request), so this is the contract that keeps every route's answer serialisable.
"""

import json
import math
from pathlib import Path
from typing import Any

import pytest

from service.modelcheck import model_check
from service.tasks import analytic_reference, compare_mission, fallback_mission, optimize_mission

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())
UPLOAD = {"log": Path("service/static/example-log.csv").read_bytes(), "filename": "example-log.csv",
          "params": "paper-rig", "max_samples": 100_000}


def _plain(obj: Any, where: str = "$") -> None:
    if isinstance(obj, dict):
        for k, v in obj.items():
            assert type(k) is str, f"{where}: key {k!r}"
            _plain(v, f"{where}.{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            _plain(v, f"{where}[{i}]")
    elif type(obj) is float:
        assert math.isfinite(obj), f"{where}: {obj}"
    else:
        assert obj is None or type(obj) in (str, int, bool), f"{where}: {type(obj).__name__}"


@pytest.mark.parametrize("task, payload", [
    (analytic_reference, {"request": {"amplitude": 0.4, "period": 1.0, "q": 0}, "max_samples": 10_000}),
    (analytic_reference, {"request": {"amplitude": 0.4, "limits": {"voltage": 12.0, "current": 1.0},
                                      "regularity": "continuous-voltage"}, "max_samples": 10_000}),
    (optimize_mission, EXAMPLE),
    (optimize_mission, {**EXAMPLE, "plant": "torque", "limits": {"torque": 0.02}, "objective": "min-time"}),
    (fallback_mission, {"mission": EXAMPLE, "reason": "test"}),
    (compare_mission, {"mission": {**EXAMPLE, "collocation": {"intervals": 60}}, "qs": [0, 2]}),
    (model_check, {"op": "check", **UPLOAD}),
    (model_check, {"op": "diagnose", **UPLOAD}),
    (model_check, {"op": "fit", **UPLOAD,
                   "effects": ["coulomb_friction"]}),
])
def test_task_answers_are_plain_json(task, payload):
    out = task(payload)
    _plain(out)
    json.dumps(out, allow_nan=False)


def test_route_tasks_answer_the_batch_tasks_content_checked_and_rendered_in_the_worker() -> None:
    """The optimise route's tasks answer ``{RENDERED: bytes}``: the same content as the dict tasks (the analytic
    fallback is deterministic), checked against the public model before rendering (a malformed answer fails in
    the worker, not as a 200)."""
    import pydantic

    from service import tasks

    payload = {"mission": EXAMPLE, "reason": "test"}
    out = tasks.fallback_answer(payload)
    assert set(out) == {tasks.RENDERED} and isinstance(out[tasks.RENDERED], bytes)
    assert json.loads(out[tasks.RENDERED]) == fallback_mission(payload)
    with pytest.raises(pydantic.ValidationError):
        tasks._rendered({**fallback_mission(payload), "t": "not a list"})


def test_a_batch_answer_rendered_in_the_worker_is_stored_as_its_json(tmp_path) -> None:
    """A result the worker rendered (``{RENDERED: bytes}``) lands in the job store as that JSON text and reads
    back as the same content as the unrendered dict."""
    from service import tasks
    from service.jobs import JobStore, Outcome

    answer = fallback_mission({"mission": EXAMPLE, "reason": "test"})
    store = JobStore(tmp_path / "jobs.sqlite3")
    try:
        batch_id, _ = store.create_batch([EXAMPLE, EXAMPLE], None)
        assert len(store.claim(2)) == 2
        rendered = tasks._rendered(answer, check=False)
        assert store.record([Outcome(batch_id, 0, result=rendered), Outcome(batch_id, 1, result=answer)]) == \
            ["done", "done"]
        first, second = store.items(batch_id)
        assert first.result == answer == second.result
    finally:
        store.close()


def test_repeated_optimise_requests_start_warm() -> None:
    """The worker's optimise task asks for warm starts: its second request of a mission (and one 5 % stronger)
    starts from the first one's solution, with fewer IPOPT iterations, the same objective (rel 1e-3) or better and
    the limits held. (In process: the worker process runs this same function.)"""
    def mission(level: float) -> dict[str, Any]:
        return {"name": "again", "limits": {"voltage": 12.0, "current": 1.0}, "collocation": {"intervals": 60},
                "segments": [{"kind": "hold", "duration": 0.2, "thrust": level},
                             {"kind": "reversal", "duration": 1.0, "to": -level},
                             {"kind": "hold", "duration": 0.2, "thrust": -level}]}

    first, again, nearby = (optimize_mission(mission(level)) for level in (0.3, 0.3, 0.315))
    assert first["solver"]["program"] == "flat"
    for answer in (again, nearby):
        assert answer["source"] == "optimized" and answer["solver"]["warm_start"]
        assert answer["verification"]["path_ok"]
    assert again["solver"]["iterations"] < first["solver"]["iterations"] or first["solver"]["warm_start"]
    assert again["solver"]["objective"] <= first["solver"]["objective"] * (1 + 1e-3)
