"""The Model check tab says when a refit is not adopted (headless Chromium, real server): proving-ground draw
``make_case(42101, "one")``, a 41-period ripple on a 100 Hz log the log cannot resolve; refitting with the ripple
ticked predicts the free run worse than the nominal plant, and the page says the fit is not adopted and why, beside
the before/after table that shows the rise; the calibrated file it offers is the starting plant."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bench.modelcheck import case_log
from ocp.logs import write_log_csv
from tests.page.test_page import LONG, diagnose_on_page, downloaded
from tests.proving_ground import make_case
from tests.service.test_service_support import Server

pytestmark = pytest.mark.integration


def test_a_refit_that_predicts_worse_is_said_not_adopted(page: Any, server: Server, tmp_path: Path) -> None:
    case = make_case(42101, "one")
    write_log_csv(case_log(case), tmp_path / "ripple.csv")
    diagnose_on_page(page, server, tmp_path / "ripple.csv", case.nominal)
    boxes = page.locator("#m-ranking input[type=checkbox]")
    for k in range(boxes.count()):
        boxes.nth(k).set_checked(boxes.nth(k).get_attribute("value") == "cogging")
    page.click("#m-fit")
    page.wait_for_selector("#m-fit-results:not([hidden])", timeout=LONG)
    note = page.locator("#m-fit-note")
    assert note.is_visible() and note.inner_text().startswith("not adopted: the fitted plant predicts")
    r = page.locator("#m-beforeafter tr[data-channel=omega]")
    assert float(r.get_attribute("data-after")) > float(r.get_attribute("data-before"))
    calibrated = json.loads(downloaded(page, "#m-dl-params"))
    assert calibrated.get("effects", {}) == {} and calibrated["notes"]["adopted"] is False
