"""Headless Chromium for the page tests: Debian's ``/usr/bin/chromium`` driven by Playwright against a real
uvicorn server (tmp SQLite, real worker processes). ``scripts/test.sh`` installs chromium when run as root with
apt-get; a module that needs it is skipped with the reason otherwise (:func:`playwright`)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from tests.service.test_service_support import Server, start_server

CHROMIUM = Path("/usr/bin/chromium")
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def playwright() -> Any:
    """``playwright.sync_api``; skips the calling test module, saying why, when chromium or Playwright is absent."""
    if not (CHROMIUM.is_file() and os.access(CHROMIUM, os.X_OK)):
        pytest.skip("Debian's chromium is not installed at /usr/bin/chromium (scripts/test.sh installs it with "
                    "apt-get when run as root)", allow_module_level=True)
    return pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed (dev extra)")


@contextmanager
def served(tmp: Path, **env: str) -> Iterator[Server]:
    """A real server on a job store in ``tmp``; ``env``: more ``THRUSTSHAPE_*`` settings."""
    srv = start_server(tmp, {"THRUSTSHAPE_DB_PATH": str(tmp / "jobs.sqlite"), **env})
    try:
        yield srv
    finally:
        srv.stop()


@contextmanager
def chromium(profile: Path, height: int = 1000, **options: Any) -> Iterator[Any]:
    """A persistent headless Chromium context (1400 px wide) with its profile in ``profile``."""
    with playwright().sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(str(profile), executable_path=str(CHROMIUM), args=ARGS,
                                                    headless=True, viewport={"width": 1400, "height": height},
                                                    **options)
        try:
            yield ctx
        finally:
            ctx.close()


@contextmanager
def watched(pg: Any, timeout_ms: int = 30_000) -> Iterator[Any]:
    """The tab ``pg``, closed afterwards; the test fails on any uncaught script error on the page."""
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.set_default_timeout(timeout_ms)
    try:
        yield pg
        assert errors == [], f"script errors on the page: {errors}"
    finally:
        pg.close()
