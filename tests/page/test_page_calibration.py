"""The Model check tab's calibration line in headless Chromium against a real server: a constant the log cannot
resolve (the paper rig's L/R of 0.4 ms under two samples at 1 kHz, a current filter of four samples) is shown
with its apparent value and says that the calibrated plant keeps the nominal one; under one constant command the
line says no refinement was applied (the nominal model as given predicts the held-out rows better)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ocp.logs import Log, write_log_csv
from ocp.model.params import load_params
from tests.identify.test_one_command import P, step_log
from tests.page.test_page import LONG, diagnose_on_page, open_tab
from tests.service.test_service_support import Server
from tests.synthetic_rig import RigSpec, generate

pytestmark = pytest.mark.integration


def test_an_unresolved_constant_is_shown_as_kept_at_nominal(page: Any, server: Server,
                                                            tmp_path: Path) -> None:
    log = generate(load_params("paper-rig"), RigSpec(seconds=1.0, seed=9))
    a = np.exp(-0.25)  # first-order current filter, time constant 4 samples: L's column takes it up
    i = log.current.copy()
    for k in range(1, i.size):
        i[k] = a * i[k - 1] + (1 - a) * log.current[k]
    write_log_csv(Log(log.t, log.voltage, i, log.omega, log.theta, log.thrust, log.kind), tmp_path / "filtered.csv")
    open_tab(page, server, "model")
    page.set_input_files("#m-log", str(tmp_path / "filtered.csv"))
    page.select_option("#m-preset", "paper-rig")
    page.click("#m-diagnose")
    page.wait_for_selector("#m-diag-results:not([hidden])", timeout=LONG)
    entries = dict(e.split(" ", 1) for e in page.inner_text("#m-calibration").split(": ", 1)[1].split(", "))
    assert "not resolved by this log: plant keeps nominal" in entries["L"]
    assert entries["L"].startswith("— ") and "%" not in entries["L"]  # no estimate, not its free column's value
    assert "not resolved" not in entries["R"]


def test_constants_held_as_given_are_said_once(page: Any, server: Server, tmp_path: Path) -> None:
    write_log_csv(step_log(np.full(2000, 6.0), 1.0), tmp_path / "step.csv")
    diagnose_on_page(page, server, tmp_path / "step.csv", P.model_dump())
    text = page.inner_text("#m-calibration")
    assert text.count("None applied: the nominal constants as given predict the held-out rows better") == 1
