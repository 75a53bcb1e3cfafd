"""The page's model tab with an ESC sweep (real uvicorn server, Debian's headless Chromium): the read
options reach the server (pole pairs and the rest: tests/test_readers_api.py), the answer lists the
equations checked and not, the verdict names the asymmetry. The server, browser and tab: tests/page/conftest.py."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from ocp.identify import diagnose
from ocp.logs import write_log_csv
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.logfiles import Thruster, thruster_sweep, write_csv
from tests.page.test_page import LONG, custom_params, diagnose_on_page, open_tab, shot
from tests.proving_ground.experiment import draw, run_command, voltage_steps
from tests.rig_log import rig_log
from tests.service.test_service_support import Server

pytestmark = pytest.mark.integration


def test_page_diagnoses_an_esc_sweep_and_lists_the_equations(page: Any, server: Server, tmp_path: Path) -> None:
    th = Thruster(ratio=0.8)
    write_csv(thruster_sweep(th), tmp_path / "sweep.csv", title="Thruster at 16 V")
    diagnose_on_page(page, server, tmp_path / "sweep.csv", th.params())
    assert page.get_attribute("#m-verdict", "data-verdict") == "thrust_asymmetry"
    eq = page.locator("#m-diag-equations li")
    states = {eq.nth(k).get_attribute("data-equation"): eq.nth(k).get_attribute("data-checked")
              for k in range(eq.count())}
    assert states == {"thrust": "true", "mechanical": "false", "electrical": "false", "power": "true"}
    assert "supply" in page.inner_text("#m-diag-equations li[data-equation=electrical]")
    assert "fitted thrust reverse/forward 0.8" in page.inner_text("#m-diag-equations")
    shot(page, "esc-sweep")



def test_a_negated_current_is_refused_and_read_back(page: Any, server: Server, tmp_path: Path) -> None:
    """A proving-ground rig log with its current negated: the server's refusal names the current and the fix; the
    read option "Channels logged with the opposite sign" reads it back, and the diagnosis answers."""
    rig = draw(3, "coulomb_friction")
    t, v = voltage_steps(rig, 3)
    cols = run_command(rig, t, v, 4)
    write_log_csv(rig_log(dict(cols, current=-cols["current"])), tmp_path / "flipped.csv")
    open_tab(page, server, "model")
    page.set_input_files("#m-log", str(tmp_path / "flipped.csv"))
    custom_params(page, rig.nominal)
    page.click("#m-diagnose")
    err = page.locator("#tab-model .field-error", has_text="opposite sign").first
    err.wait_for(timeout=LONG)
    assert "current" in err.inner_text() and "--negate current" in err.inner_text()
    page.fill("#m-negate", "current")
    page.click("#m-diagnose")
    page.wait_for_selector("#m-diag-results:not([hidden])", timeout=LONG)
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    assert page.get_attribute("#m-verdict", "data-verdict") == ",".join(diagnose(plant, rig_log(cols)).verdict)
    assert "negated as asked: current" in (page.text_content("#m-diag-equations") or "")  # (folded: the reader's notes)
