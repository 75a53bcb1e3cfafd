"""The page tests' server, browser and tab: one real uvicorn server (tmp SQLite, two solver workers) for every page
test module a test process runs (each start warms worker processes: seconds of CPU the suite paid once per module),
and a headless Chromium per module (Playwright's sync API keeps an event loop running in the thread while it is
open: a later module's ``asyncio.run`` would fail)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from tests.browser import chromium, served, watched
from tests.service.test_service_support import Server


@pytest.fixture(scope="session")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    with served(tmp_path_factory.mktemp("page-server"), THRUSTSHAPE_WORKERS="2") as srv:
        yield srv


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    with chromium(tmp_path_factory.mktemp("chromium-profile"), accept_downloads=True) as ctx:
        yield ctx


@pytest.fixture()
def page(browser: Any, server: Server) -> Iterator[Any]:
    """A fresh tab on the server; fails the test on any uncaught script error."""
    with watched(browser.new_page()) as pg:
        yield pg
