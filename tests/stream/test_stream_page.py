"""The Stream tab end to end: a real uvicorn server and Debian's headless Chromium play the paper's impedance
example through WS /v1/stream and read what the page shows (limits held, crossings, plots); a bad look-ahead
comes back from the stream as an error next to its input."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from tests.browser import chromium, playwright, served, watched
from tests.service.test_service_support import ROOT, Server

pytestmark = pytest.mark.integration

playwright()
pytest.importorskip("websockets", reason="uvicorn needs the websockets package for WebSocket routes")


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    with served(tmp_path_factory.mktemp("stream-page")) as srv:
        yield srv


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    with chromium(tmp_path_factory.mktemp("chromium-profile"), height=1100) as ctx:
        yield ctx


@pytest.fixture()
def page(server: Server, browser: Any) -> Iterator[Any]:
    with watched(browser.new_page(), 60_000) as pg:
        pg.goto(server.url + "/#stream")
        yield pg


def _value(page: Any, key: str) -> str:
    return page.locator(f"#s-summary tr[data-key='{key}'] td.num").inner_text()


def test_stream_tab_plays_the_impedance_example(page: Any) -> None:
    page.select_option("#s-regularity", "continuous-voltage")
    page.fill("#s-duration", "6")
    page.click("#s-play")
    page.wait_for_function("document.querySelector('#s-status').textContent.startsWith('done')", timeout=120_000)
    assert _value(page, "samples") == "6001 of 6001"
    assert float(_value(page, "current")) <= 1.0
    assert float(_value(page, "voltage")) <= 12.0
    assert _value(page, "limits") == "yes"
    assert int(_value(page, "reversals")) >= 9  # the impedance example crosses zero about twice a second
    assert float(_value(page, "tracking")) < 10.0
    series = page.locator("#s-plot-thrust .series")  # uPlot's plot (plot.js) keeps one marker per series
    assert series.count() == 2 and int(series.nth(1).get_attribute("data-n")) == 6001
    assert page.locator("#s-plot-current .limit").count() == 2
    out = ROOT / "test-artifacts"
    out.mkdir(exist_ok=True)
    page.screenshot(path=str(out / "stream-tab.png"), full_page=True)


def test_stream_tab_shows_the_streams_error_next_to_the_field(page: Any) -> None:
    page.fill("#s-delay", "3")
    page.click("#s-play")
    err = page.locator("#tab-stream .field-error[data-error-for='delay']")
    err.wait_for()
    assert "less than or equal" in err.inner_text() or "1" in err.inner_text()
    assert page.locator("#s-status").inner_text().startswith("stopped")
