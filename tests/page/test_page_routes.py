"""The page's routes without a browser: ``/`` and ``/static/{name}`` serve the packaged files with their
types, public even when the API needs a key, and nothing outside ``service/static`` is reachable."""

from __future__ import annotations

import asyncio
import re

import httpx
import pytest
from pydantic import SecretStr

from service.api.routes.page import STATIC
from service.app import create_app
from service.settings import Settings


class Client:
    """GETs against the app in-process (no lifespan: these routes need neither workers nor the job store)."""

    def __init__(self) -> None:
        self.app = create_app(Settings(api_key=SecretStr("k")))

    def get(self, path: str) -> httpx.Response:
        async def go() -> httpx.Response:
            async with httpx.AsyncClient(transport=httpx.ASGITransport(app=self.app), base_url="http://page") as c:
                return await c.get(path)

        return asyncio.run(go())


@pytest.fixture(scope="module")
def client() -> Client:
    return Client()


def test_index_and_assets_are_served_without_the_api_key(client: Client) -> None:
    page = client.get("/")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    for ref in ("/static/app.js", "/static/plot.js", "/static/app.css"):
        assert ref in page.text
    assert "http://" not in page.text and "https://" not in page.text  # no CDN
    js = client.get("/static/app.js")
    assert js.status_code == 200 and js.headers["content-type"].startswith("text/javascript")
    assert client.get("/static/app.css").headers["content-type"].startswith("text/css")
    log = client.get("/static/example-log.csv")
    assert log.status_code == 200 and log.text.startswith("t,voltage,current")
    assert client.get("/v1/info").status_code == 401  # the API itself still needs the key


@pytest.mark.parametrize("name", ["nope.js", "..%2Fapp.py", "%2E%2E%2F%2E%2E%2Fpyproject.toml", ".hidden"])
def test_nothing_else_is_reachable(client: Client, name: str) -> None:
    assert client.get(f"/static/{name}").status_code == 404


def _scripts() -> dict[str, str]:
    """The page's scripts: those ``index.html`` loads and, from the ``app.js`` module, every module it imports
    (``import ... from "./name.js"``, transitively), each by name with its text."""
    html = (STATIC / "index.html").read_text(encoding="utf-8")
    todo = re.findall(r'<script[^>]*\bsrc="/static/([^"]+)"', html)
    seen: dict[str, str] = {}
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        assert (STATIC / name).is_file(), f"{name} is loaded but not packaged"
        seen[name] = (STATIC / name).read_text(encoding="utf-8")
        todo += re.findall(r'\bfrom\s+"\./([^"/]+\.js)"', seen[name])
    return seen


def test_every_script_and_style_the_page_loads_is_packaged(client: Client) -> None:
    html = (STATIC / "index.html").read_text(encoding="utf-8")
    scripts = _scripts()
    assert {"plot.js", "app.js", "common.js", "design.js", "compare.js", "model.js", "batch.js"} <= set(scripts)
    assert set(scripts) == {p.name for p in STATIC.glob("*.js")}, "a script in static/ that the page never loads"
    for name in scripts:  # served as JavaScript: module scripts are refused under any other type
        assert client.get(f"/static/{name}").headers["content-type"].startswith("text/javascript"), name
    for name in ("app.css", "example-mission.json", "example-log.csv"):
        assert (STATIC / name).is_file(), name
        assert name in html or any(name in text for text in scripts.values()), name
