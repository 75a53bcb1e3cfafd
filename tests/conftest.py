from __future__ import annotations

import pytest

from ocp.params import MotorParams, load_params


@pytest.fixture(scope="session")
def rig() -> MotorParams:
    """The paper-rig preset (Section V of the seed paper, assumed electrical constants)."""
    return load_params("paper-rig")
