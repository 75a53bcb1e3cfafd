"""The Model check tab's angle-periodic line in headless Chromium against a real server: where the held-out rows
cannot tell the ripple's count from its neighbours (a short 200 Hz log of a 48-period ripple: its aliases fit
nearly as well), the line says the log does not decide the count and lists the rivals the JSON holds."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from clients.cli.answers import runs
from ocp.identify import diagnose
from ocp.logs import write_log_csv
from ocp.model.params import load_params
from ocp.model.plant import DCMotorPlant
from tests.identify.test_angle_periodic import RIPPLE
from tests.page.test_page import LONG, open_tab
from tests.service.test_service_support import Server
from tests.synthetic_rig import RigSpec, generate

pytestmark = pytest.mark.integration


def test_an_undecided_count_is_said_on_the_page(page: Any, server: Server, tmp_path: Path) -> None:
    rig = load_params("paper-rig")
    log = generate(rig, RigSpec(effects={"cogging": RIPPLE}, seconds=1.5, seed=12, rate=200.0))
    rivals = diagnose(DCMotorPlant(rig), log).angle_periodic["rivals"]  # type: ignore[index]
    assert rivals  # the case: aliased neighbours of the 48 periods
    write_log_csv(log, tmp_path / "ripple.csv")
    open_tab(page, server, "model")
    page.set_input_files("#m-log", str(tmp_path / "ripple.csv"))
    page.select_option("#m-preset", "paper-rig")
    page.click("#m-diagnose")
    page.wait_for_selector("#m-diag-results:not([hidden])", timeout=LONG)
    text = page.inner_text("#m-angle")
    assert "best fit at 48 periods/rev" in text and "the count is not decided by this log" in text
    assert f"({', '.join(runs(rivals))})" in text  # the page's runs (model.js) as the CLI forms them

