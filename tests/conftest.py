from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from ocp.model.params import MotorParams, load_params


@pytest.fixture(scope="session")
def rig() -> MotorParams:
    """The paper-rig preset (Section V of the seed paper, assumed electrical constants)."""
    return load_params("paper-rig")


@pytest.fixture()
def http(server: Any) -> Iterator[httpx.Client]:
    """An HTTP client on the test module's ``server`` fixture (a real uvicorn process)."""
    with httpx.Client(base_url=server.url, timeout=60.0) as c:
        yield c
