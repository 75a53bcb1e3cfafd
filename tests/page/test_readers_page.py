"""The page's model tab with an ESC sweep (real uvicorn server, Debian's headless Chromium): the read
options reach the server (pole pairs and the rest: tests/test_readers_api.py), the answer lists the
equations checked and not, the verdict names the asymmetry. The server, browser and tab: tests/page/conftest.py."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.logfiles import Thruster, thruster_sweep, write_csv
from tests.page.test_page import LONG, custom_params, open_tab, shot
from tests.service.test_service_support import Server

pytestmark = pytest.mark.integration


def test_page_diagnoses_an_esc_sweep_and_lists_the_equations(page: Any, server: Server, tmp_path: Path) -> None:
    th = Thruster(ratio=0.8)
    write_csv(thruster_sweep(th), tmp_path / "sweep.csv", title="Thruster at 16 V")
    open_tab(page, server, "model")
    page.set_input_files("#m-log", str(tmp_path / "sweep.csv"))
    custom_params(page, th.params())
    page.click("#m-diagnose")
    page.wait_for_selector("#m-diag-results:not([hidden])", timeout=LONG)
    assert page.get_attribute("#m-verdict", "data-verdict") == "thrust_asymmetry"
    eq = page.locator("#m-diag-equations li")
    states = {eq.nth(k).get_attribute("data-equation"): eq.nth(k).get_attribute("data-checked")
              for k in range(eq.count())}
    assert states == {"thrust": "true", "mechanical": "false", "electrical": "false", "power": "true"}
    assert "supply" in page.inner_text("#m-diag-equations li[data-equation=electrical]")
    assert "fitted thrust reverse/forward 0.8" in page.inner_text("#m-diag-equations")
    shot(page, "esc-sweep")

