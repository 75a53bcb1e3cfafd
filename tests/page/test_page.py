"""The web page end to end: a real uvicorn server (tmp SQLite, real worker processes) and Debian's headless
Chromium driven by Playwright click through Design, Compare, Model check, bad input and Batch on the bundled
examples, assert on what the page shows, and save screenshots under ``test-artifacts/``.

Needs ``/usr/bin/chromium`` (``scripts/test.sh`` installs it when run as root with apt-get); skipped with the
reason otherwise.
"""

from __future__ import annotations

import io
import json
import re
import zipfile
from pathlib import Path
from typing import Any

import pytest

from tests.browser import playwright
from tests.page.test_page_example import HIDDEN, MISSION
from tests.service.test_service_support import ROOT, Server

pytestmark = pytest.mark.integration

ARTIFACTS = ROOT / "test-artifacts"
LONG = 120_000  # ms: diagnose fits every catalogue effect (seconds on a shared 2-core machine)
sync_api = playwright()


def shot(page: Any, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"page-{name}.png"), full_page=True)


def open_tab(page: Any, server: Server, tab: str) -> None:
    page.goto(f"{server.url}/#{tab}")
    page.wait_for_selector("#d-segments tr", state="attached")  # the example mission is loaded at start
    page.wait_for_function("document.querySelector('#d-preset').options.length > 1")


def custom_params(page: Any, params: dict[str, float]) -> None:
    """The Model check tab's parameters: a custom parameter file (JSON) instead of a preset."""
    page.select_option("#m-preset", "__custom__")
    page.fill("#m-params", json.dumps(params))


def diagnose_on_page(page: Any, server: Server, log: Path, params: dict[str, Any]) -> None:
    """The Model check tab's diagnosis of the log file ``log`` with the parameters ``params`` (a custom parameter
    file), waited for until it is shown."""
    open_tab(page, server, "model")
    page.set_input_files("#m-log", str(log))
    custom_params(page, params)
    page.click("#m-diagnose")
    page.wait_for_selector("#m-diag-results:not([hidden])", timeout=LONG)


def number(text: str) -> float:
    return float(text.strip().replace("−", "-"))


def downloaded(page: Any, button: str) -> str:
    with page.expect_download() as info:
        page.click(button)
    return Path(info.value.path()).read_text(encoding="utf-8")


def test_design_optimises_the_bundled_example(page: Any, server: Server) -> None:
    open_tab(page, server, "design")
    page.click("#d-example")
    assert page.input_value("#d-name") == "reversal-2s"
    assert page.locator("#d-segments tr").count() == 3
    page.click("#d-run")
    page.wait_for_selector("#d-results:not([hidden])")
    assert page.get_attribute("#d-source", "data-source") == "optimized"
    assert page.inner_text("#d-source") == "optimiser"
    verification = page.locator("#d-verification tr[data-key='within limits along the path'] td").nth(1)
    assert verification.inner_text() == "yes"
    peak = page.locator("#d-verification tr[data-key='max |current| [A]'] td").nth(1).inner_text()
    assert 0.1 < number(peak) <= 1.0  # the mission's current limit is 1 A
    assert page.inner_text("#d-crossings tbody td.exponent") == "g = 2"
    assert "g = 2" in (page.locator("#d-plot-thrust .marker-label").first.text_content() or "")
    for plot in ("thrust", "speed", "current", "voltage"):
        assert int(page.get_attribute(f"#d-plot-{plot} .plot", "data-points")) > 500, plot
    assert int(page.get_attribute("#d-plot-thrust .series[data-label=desired]", "data-n")) > 500
    assert page.locator("#d-plot-current .limit").count() == 2
    assert page.locator("#d-plot-voltage .limit").count() == 2
    csv_text = downloaded(page, "#d-dl-csv").splitlines()
    assert csv_text[0] == "t,thrust,thrust_desired,omega,theta,current,voltage"
    assert len(csv_text) > 500
    result = json.loads(downloaded(page, "#d-dl-json"))
    assert result["source"] == "optimized"
    assert result["crossings"][0]["exponent"] == pytest.approx(2.0, abs=0.2)
    shot(page, "design")


def test_compare_puts_the_optimised_reference_beside_the_sine_family(page: Any, server: Server) -> None:
    open_tab(page, server, "compare")
    page.click("#c-run")
    page.wait_for_selector("#c-table tbody tr", timeout=LONG)
    rows = page.locator("#c-table tbody tr")
    assert rows.count() == 5
    labels = [rows.nth(k).locator("td").first.inner_text() for k in range(5)]
    assert labels[0] in ("optimized", "fallback")
    assert [lb.split(" ")[0] for lb in labels[1:]] == ["sin^1", "sin^3", "sin^5", "sin^7"]
    assert "unbounded" in rows.nth(1).inner_text()  # sin^1: linear crossing, the ideal current is unbounded
    assert "unbounded" not in rows.nth(0).inner_text()
    assert rows.nth(0).locator("td.good").count() == 1  # optimised: within limits
    assert int(page.get_attribute("#c-bars .plotbox:nth-child(3) svg", "data-points")) == 5
    assert int(page.get_attribute("#c-plot-thrust .plot", "data-points")) > 500
    shot(page, "compare")


def test_model_check_finds_the_hidden_effect_and_the_refit_lowers_the_error(page: Any, server: Server) -> None:
    open_tab(page, server, "model")
    page.click("#m-example")
    page.wait_for_function("document.querySelector('#m-log-info').textContent.includes('example-log.csv')")
    page.click("#m-diagnose")
    page.wait_for_selector("#m-diag-results:not([hidden])", timeout=LONG)
    hidden = next(iter(HIDDEN))
    assert page.get_attribute("#m-verdict", "data-verdict") == hidden
    assert hidden in page.inner_text("#m-verdict strong")
    evidence = page.inner_text("#m-evidence")
    assert evidence.startswith(f"Evidence: {hidden} strong (likelihood ratio, z = ")
    held = re.search(r"; held out: \w+ ([\d.]+) → ([\d.]+) noise units\)", evidence)
    assert held is not None, evidence
    without, with_ = map(float, held.groups())
    assert with_ < without  # (the held-out error of the equation the name enters, without and with it)
    first = page.locator("#m-ranking tbody tr").first
    assert first.get_attribute("data-effect") == hidden
    assert first.locator("input[type=checkbox]").is_checked()
    # where it fails: measured vs simulated figure and the breakdowns (check runs after the diagnosis)
    page.wait_for_selector("#m-figures img[alt=free_run]", timeout=LONG)
    groups = page.locator("#m-breakdown .plotbox")
    assert {groups.nth(k).get_attribute("data-group") for k in range(groups.count())} >= {
        "direction", "reversal", "speed band", "rotor angle"}
    assert "samples" in page.inner_text("#m-check-alignment")  # compared after the logging convention's lag
    omega_ratio = page.locator("#m-errors tr[data-channel=omega] td").nth(4).inner_text()
    assert number(omega_ratio.rstrip("×")) > 5  # the nominal model misses the friction: far above the noise
    page.click("#m-fit")
    page.wait_for_selector("#m-fit-results:not([hidden])", timeout=LONG)
    for ch in ("omega", "current", "thrust"):
        r = page.locator(f"#m-beforeafter tr[data-channel={ch}]")
        before, after = float(r.get_attribute("data-before")), float(r.get_attribute("data-after"))
        assert after < 0.5 * before, ch
    calibrated = json.loads(downloaded(page, "#m-dl-params"))
    fitted = calibrated["effects"][hidden]["tau_c"]
    assert fitted == pytest.approx(HIDDEN[hidden]["tau_c"], rel=0.1)
    shot(page, "model-check")


def test_bad_input_is_shown_next_to_its_field(page: Any, server: Server) -> None:
    open_tab(page, server, "design")
    page.fill("#d-current", "-1")
    page.click("#d-run")
    err = page.locator(".field-error[data-error-for='limits.current']")
    err.wait_for()
    assert "greater than 0" in err.inner_text()
    # next to the input: right after the label that holds it
    assert page.evaluate("document.querySelector(\".field-error[data-error-for='limits.current']\")"
                         ".previousElementSibling.contains(document.querySelector('#d-current'))")
    assert page.locator("#d-current.invalid").count() == 1
    assert page.is_hidden("#d-results")
    page.fill("#d-current", "1")
    page.locator("#d-segments tr").nth(1).locator("[data-key=duration]").fill("0")
    page.click("#d-run")
    seg = page.locator(".field-error[data-error-for='segments.1.duration']")
    seg.wait_for()
    assert "greater than or equal to 0.000001" in seg.inner_text()  # the shortest segment, 1 us
    assert page.locator("#d-current.invalid").count() == 0  # the old message went away
    page.select_option("#d-preset", "__custom__")
    page.fill("#d-params", '{"J": 1e-5')
    page.click("#d-run")
    assert "not valid JSON" in page.locator(".field-error[data-error-for=params]").inner_text()
    shot(page, "bad-input")
    # a log without the needed columns: the server names the field, the page puts it next to the log input
    page.click("#tabs button[data-tab=model]")
    page.set_input_files("#m-log", {"name": "bad.csv", "mimeType": "text/csv", "buffer": b"a,b\n1,2\n3,4\n"})
    page.click("#m-check")
    log_err = page.locator("#tab-model .field-error").first
    log_err.wait_for()
    assert "missing column" in log_err.inner_text()
    assert page.locator("#m-log.invalid").count() == 1  # the log's column errors land next to the log input
    shot(page, "bad-log")


def _mission(name: str) -> dict[str, Any]:
    m = json.loads(MISSION.read_text(encoding="utf-8"))
    return {**m, "name": name, "collocation": {"intervals": 40}}


def test_batch_of_missions_from_a_zip_and_a_file_reaches_done(page: Any, server: Server) -> None:
    open_tab(page, server, "batch")
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("a.json", json.dumps(_mission("zipped-a")))
        zf.writestr("more/b.json", json.dumps({"missions": [_mission("zipped-b")]}))
    page.set_input_files("#b-files", [
        {"name": "missions.zip", "mimeType": "application/zip", "buffer": buf.getvalue()},
        {"name": "single.json", "mimeType": "application/json", "buffer": json.dumps(_mission("single")).encode()},
    ])
    page.wait_for_function("document.querySelector('#b-list').textContent.startsWith('3 mission')")
    page.click("#b-run")
    page.wait_for_selector("#b-status[data-status=done]", timeout=LONG)
    assert page.evaluate("document.querySelector('#b-progress').value") == 1
    page.wait_for_selector("#b-table tbody tr")
    rows = page.locator("#b-table tbody tr")
    assert rows.count() == 3
    names = [rows.nth(k).locator("td").nth(1).inner_text() for k in range(3)]
    assert names == ["zipped-a", "zipped-b", "single"]
    assert [rows.nth(k).locator("td").nth(2).inner_text() for k in range(3)] == ["done"] * 3
    summary = downloaded(page, "#b-dl-csv").splitlines()
    assert summary[0].startswith("index,name,status") and len(summary) == 4
    shot(page, "batch")
