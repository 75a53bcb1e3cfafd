"""The page's plots in headless Chromium (the server, browser and page fixtures of tests/page/conftest.py):
drag-to-zoom on a reversal (the Design plots zoom together), the legend reads out the sample under the
cursor, double-click zooms out; every plot downloads as PNG, SVG (the zoomed view) and CSV; the Compare
table downloads as CSV; the zip reader skips macOS metadata entries."""

from __future__ import annotations

import csv
import io
import json
import zipfile
from pathlib import Path
from typing import Any

import pytest

from tests.page.test_page import LONG, _mission, open_tab, shot
from tests.service.test_service_support import Server

THRUST = "#d-plot-thrust .plot"


def save(page: Any, button: str) -> bytes:
    with page.expect_download() as info:
        page.click(button)
    return Path(info.value.path()).read_bytes()


def span(page: Any, sel: str) -> tuple[float, float]:
    return float(page.get_attribute(sel, "data-xmin")), float(page.get_attribute(sel, "data-xmax"))


def x_pixel(page: Any, sel: str, value: float) -> float:
    """CSS pixel of t = ``value`` inside the plot's drawing area (uPlot's own scale)."""
    return float(page.evaluate("([s, v]) => document.querySelector(s)._uplot.valToPos(v, 'x')", [sel, value]))


def test_design_plots_zoom_read_out_and_download(page: Any, server: Server) -> None:
    open_tab(page, server, "design")
    page.click("#d-example")
    page.click("#d-run")
    page.wait_for_selector("#d-results:not([hidden])")
    tc = float(page.locator("#d-crossings tbody td.num").first.inner_text())  # the reversal's crossing time [s]
    full = span(page, THRUST)
    assert full[0] <= 0.0 and full[1] > 1.5

    over = page.locator("#d-plot-thrust .u-over").bounding_box()
    y = over["y"] + over["height"] / 2
    page.mouse.move(over["x"] + x_pixel(page, THRUST, tc - 0.02), y)
    page.mouse.down()
    page.mouse.move(over["x"] + x_pixel(page, THRUST, tc + 0.02), y, steps=8)
    page.mouse.up()
    lo, hi = span(page, THRUST)
    assert tc - 0.025 < lo < tc < hi < tc + 0.025, (lo, tc, hi)  # a 40 ms window on a 2 s reference
    assert span(page, "#d-plot-current .plot") == (lo, hi)  # the Design plots zoom together

    page.mouse.move(over["x"] + x_pixel(page, THRUST, tc), y)  # read-out at the crossing
    legend = page.locator("#d-plot-thrust .u-legend .u-series")
    t_read = float(legend.nth(0).locator(".u-value").inner_text())
    f_read = float(legend.nth(2).locator(".u-value").inner_text())
    assert abs(t_read - tc) < 0.5e-3  # within a sample (1 kHz) of where the cursor is
    idx = page.evaluate(f"document.querySelector('{THRUST}')._uplot.cursor.idx")
    sample = page.evaluate(f"document.querySelector('{THRUST}')._uplot.data[2][{idx}]")
    assert f_read == pytest.approx(sample, rel=1e-3, abs=1e-12)  # the legend shows the sample under the cursor
    assert abs(f_read) < 0.01  # and the thrust there is crossing zero (it swings +-0.4 N)
    shot(page, "plot-zoomed")

    svg = save(page, "#d-plot-thrust .plot-dl[data-format=svg]").decode()
    assert svg.startswith("<?xml") and "<svg" in svg and 'data-label="optimised (simulated)"' in svg
    n_in_view = int(svg.split('data-label="optimised (simulated)"')[1].split('data-n="')[1].split('"')[0])
    assert 20 < n_in_view < 60  # only the zoomed 40 ms of the 1 kHz reference
    png = save(page, "#d-plot-thrust .plot-dl[data-format=png]")
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000
    rows = list(csv.reader(io.StringIO(save(page, "#d-plot-current .plot-dl[data-format=csv]").decode())))
    assert rows[0] == ["t [s]", "i"] and 20 < len(rows) - 1 < 60
    assert all(lo <= float(r[0]) <= hi for r in rows[1:])

    page.mouse.dblclick(over["x"] + over["width"] / 2, y)  # zoom out
    assert span(page, THRUST) == pytest.approx(full)


def test_compare_table_and_bars_download(page: Any, server: Server) -> None:
    open_tab(page, server, "compare")
    assert page.is_disabled("#c-dl-csv")
    page.click("#c-run")
    page.wait_for_selector("#c-table tbody tr", timeout=LONG)
    table = list(csv.DictReader(io.StringIO(save(page, "#c-dl-csv").decode())))
    assert [r["label"].split(" ")[0] for r in table][1:] == ["sin^1", "sin^3", "sin^5", "sin^7"]
    assert table[1]["peak_current_a"] == "inf" and float(table[0]["peak_current_a"]) <= 1.0 + 1e-6
    shown = page.locator("#c-table tbody tr").nth(0).locator("td").nth(2).inner_text()
    assert float(shown) == pytest.approx(float(table[0]["peak_current_a"]), rel=1e-3)
    bars = list(csv.reader(io.StringIO(save(page, "#c-bars .plotbox:nth-child(1) .plot-dl[data-format=csv]").decode())))
    assert len(bars) == 6 and bars[2][1] == ""  # sin^1's unbounded peak has no bar
    assert save(page, "#c-bars .plotbox:nth-child(1) .plot-dl[data-format=png]")[:4] == b"\x89PNG"
    assert b"<svg" in save(page, "#c-plot-voltage .plot-dl[data-format=svg]")


def test_zip_reader_skips_macos_metadata(page: Any, server: Server) -> None:
    open_tab(page, server, "batch")
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("missions/a.json", json.dumps(_mission("zipped-a")))
        zf.writestr("__MACOSX/missions/._a.json", b"\x00\x05\x16\x07 AppleDouble resource fork")
        zf.writestr("missions/._b.json", b"\x00\x05\x16\x07")
        zf.writestr("missions/.hidden.json", b"not a mission")
    page.set_input_files("#b-files", [{"name": "mac.zip", "mimeType": "application/zip", "buffer": buf.getvalue()}])
    page.wait_for_function("document.querySelector('#b-list').textContent.startsWith('1 mission')")
    assert "zipped-a" in page.inner_text("#b-list")
    errors = page.evaluate("[...document.querySelectorAll('#tab-batch .field-error, #tab-batch .form-error')]"
                           ".map((e) => e.textContent.trim()).filter(Boolean)")
    assert errors == []  # the metadata entries were skipped, not reported as bad missions
