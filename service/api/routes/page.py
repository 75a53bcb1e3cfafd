"""The web page: ``GET /`` (``static/index.html``) and ``GET /static/{name}`` (its scripts, styles and
bundled examples). Everything is served from the package, nothing from a CDN, so the page works offline.
The page and its files are public (they hold no data); the API calls it makes carry the API key the
user types in, when the server has one.
"""

from __future__ import annotations

import mimetypes
from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse
from starlette.exceptions import HTTPException

STATIC = Path(__file__).resolve().parents[2] / "static"
_TYPES = {".js": "text/javascript; charset=utf-8", ".css": "text/css; charset=utf-8",
          ".html": "text/html; charset=utf-8", ".csv": "text/csv; charset=utf-8",
          ".json": "application/json", ".svg": "image/svg+xml"}
_NO_CACHE = {"Cache-Control": "no-cache"}

router = APIRouter(include_in_schema=False)


def _files() -> dict[str, Path]:
    """The servable files: regular files directly in ``static/`` (no subpaths, no dotfiles)."""
    if not STATIC.is_dir():
        return {}
    return {p.name: p for p in STATIC.iterdir() if p.is_file() and not p.name.startswith(".")}


def _serve(path: Path) -> FileResponse:
    media = _TYPES.get(path.suffix.lower()) or mimetypes.guess_type(path.name)[0] or "application/octet-stream"
    return FileResponse(path, media_type=media, headers=_NO_CACHE)


@router.get("/")
async def index() -> FileResponse:
    page = _files().get("index.html")
    if page is None:
        raise HTTPException(404, "the web page is not installed")
    return _serve(page)


@router.get("/static/{name}")
async def static(name: str) -> FileResponse:
    path = _files().get(name)
    if path is None:
        raise HTTPException(404, f"no static file {name!r}")
    return _serve(path)
