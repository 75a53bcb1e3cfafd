"""The Model check tab's "Design the experiment" button in headless Chromium against a real server: a
proving-ground log held at one speed (Coulomb friction and a drag change look alike) and its parameter file
are uploaded, the design runs as a job with a progress bar, the page shows why, every candidate and the
separation per rival pair, and the proposed mission downloads as a valid mission within the typed limits."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ocp.logs import log_from_arrays, write_log_csv
from ocp.optimize.mission import Mission
from tests.page.test_page import LONG, custom_params, downloaded, open_tab, shot
from tests.proving_ground.experiment import draw, single_speed
from tests.service.test_service_support import Server

pytestmark = pytest.mark.integration


def test_the_model_tab_designs_the_experiment_and_downloads_its_mission(page: Any, server: Server,
                                                                        tmp_path: Path) -> None:
    rig = draw(6, "coulomb_friction")
    cols = single_speed(rig, 6)
    log = log_from_arrays(cols["t"], cols["voltage"], cols["current"], cols["thrust"], omega=cols["omega"],
                          theta=cols.get("theta"))
    csv = tmp_path / "one-speed.csv"
    write_log_csv(log, csv)
    current = round(3.0 * float(np.max(np.abs(log.current))), 3)
    open_tab(page, server, "model")
    page.set_input_files("#m-log", str(csv))
    custom_params(page, rig.nominal)
    page.fill("#m-d-voltage", str(rig.truth.v_max))
    page.fill("#m-d-current", str(current))
    page.click("#m-design")
    page.wait_for_selector("#m-design-results:not([hidden])", timeout=LONG)
    assert page.get_attribute("#m-design-progress", "data-status") == "done"
    assert page.get_attribute("#m-design-message", "data-needed") == "true"
    assert "z =" in page.inner_text("#m-design-message")
    assert page.locator("#m-design-reasons li").count() >= 1
    rows = page.locator("#m-design-candidates tbody tr")
    assert rows.count() == 7 and page.locator("#m-design-candidates tr.chosen").count() == 1
    pairs = page.locator("#m-design-pairs tbody tr")
    assert pairs.count() >= 1
    proposed = [float(pairs.nth(k).locator("td").nth(1).inner_text()) for k in range(pairs.count())]
    before = [float(pairs.nth(k).locator("td").nth(2).inner_text()) for k in range(pairs.count())]
    assert min(proposed) > min(before)
    assert page.get_attribute("#m-verdict", "data-verdict") is not None  # the diagnosis it settles is shown
    mission = json.loads(downloaded(page, "#m-dl-mission"))
    m = Mission.model_validate(mission)
    assert m.limits.voltage == pytest.approx(rig.truth.v_max) and m.limits.current == pytest.approx(current)
    chosen = page.locator("#m-design-candidates tr.chosen").get_attribute("data-candidate")
    assert mission["name"] == f"design-experiment {chosen}"
    shot(page, "model-design-experiment")
