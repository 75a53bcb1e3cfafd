from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from ocp.model.params import MotorParams, load_params


def pytest_configure(config: pytest.Config) -> None:
    """The suite's solves keep CasADi's virtual machine: a program solved 20 times would otherwise start a ~25 s
    C build of its functions in the background (the tests of that path, ``tests/optimize/test_native_nlp.py``,
    turn it on with a cache directory of their own)."""
    os.environ.setdefault("THRUSTSHAPE_NLP_COMPILE", "0")


@pytest.fixture(scope="session")
def rig() -> MotorParams:
    """The paper-rig preset (Section V of the seed paper, assumed electrical constants)."""
    return load_params("paper-rig")


@pytest.fixture()
def http(server: Any) -> Iterator[httpx.Client]:
    """An HTTP client on the test module's ``server`` fixture (a real uvicorn process)."""
    with httpx.Client(base_url=server.url, timeout=60.0) as c:
        yield c
