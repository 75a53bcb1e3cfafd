"""Property-based fuzzing of every documented operation (Schemathesis, from the served OpenAPI spec)
against a real uvicorn server: whatever the body, the server never answers 5xx.

Bounded: a few examples per operation; optimise/compare missions are capped at 60 intervals and a
2 s deadline by the server's settings so a fuzzed mission cannot run long.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis.checks import not_a_server_error
from schemathesis.core.result import Ok

from tests.service.test_service_support import Server, start_server

pytestmark = [pytest.mark.integration, pytest.mark.slow]


@pytest.fixture(scope="module")
def fuzz_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("fuzz")
    srv = start_server(tmp, {"TS_TEST_TASKS": "slow-batch", "TS_TEST_ITEM_SECONDS": "0.01",
                             "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"), "THRUSTSHAPE_MAX_INTERVALS": "60",
                             "THRUSTSHAPE_OPTIMIZE_DEADLINE_S": "3", "THRUSTSHAPE_TASK_TIMEOUT_S": "20",
                             "THRUSTSHAPE_MAX_REFERENCE_SAMPLES": "20001", "THRUSTSHAPE_MAX_PROFILE_SAMPLES": "2000",
                             "THRUSTSHAPE_QUEUE_SIZE": "64"})
    yield srv
    srv.stop()


def test_no_server_errors(fuzz_server: Server) -> None:
    """Every operation of the served spec, a bounded number of generated requests each (one test:
    Schemathesis' pytest fixture loader does not run on this pytest version, so operations are
    driven through their Hypothesis strategies directly)."""
    schema = schemathesis.openapi.from_url(f"{fuzz_server.url}/openapi.json")
    results = list(schema.get_all_operations())
    unread = [r.err() for r in results if not isinstance(r, Ok)]  # operations Schemathesis cannot read
    assert not unread, unread
    operations = [r.ok() for r in results if isinstance(r, Ok)]
    assert len(operations) >= 7
    tried: list[str] = []
    for op in operations:

        @given(case=op.as_strategy())
        @settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True,
                  database=None)
        def fuzz(case: Any) -> None:
            case.call_and_validate(checks=[not_a_server_error], timeout=60)

        fuzz()
        tried.append(op.label)
    assert "POST /v1/batches" in tried and "POST /v1/references/analytic" in tried
    assert {"POST /v1/model-check/check", "POST /v1/model-check/diagnose", "POST /v1/model-check/fit"} <= set(tried)
