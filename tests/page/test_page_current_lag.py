"""The Model check tab says through which current-sensor lag the free run's current was read (headless Chromium,
real server): a fresh clean proving-ground log whose logger filters the current (lag 0.66 samples), checked with
its exact constants, shows the fitted lag on the alignment line, as the JSON has it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bench.modelcheck import case_log
from ocp.identify import check
from ocp.identify.check import CheckResult
from ocp.logs import write_log_csv
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.identify.test_current_sensor_lag import DRAWS
from tests.page.test_page import LONG, custom_params, open_tab
from tests.proving_ground import make_case
from tests.service.test_service_support import Server

pytestmark = pytest.mark.integration


def test_the_fitted_current_lag_is_said_on_the_page(page: Any, server: Server, tmp_path: Path) -> None:
    case = make_case(DRAWS[0], "clean")
    log = case_log(case)
    res = check(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert isinstance(res, CheckResult) and res.free.current_lag > 0.3
    write_log_csv(log, tmp_path / "filtered.csv")
    open_tab(page, server, "model")
    page.set_input_files("#m-log", str(tmp_path / "filtered.csv"))
    custom_params(page, case.nominal)
    page.click("#m-check")
    page.wait_for_selector("#m-check-results:not([hidden])", timeout=LONG)
    text = page.inner_text("#m-check-alignment")
    assert f"read through the current sensor's lag that fits the log, {res.free.current_lag:g} samples" in text
