"""Liveness: ``GET /healthz`` (never needs the API key)."""

from __future__ import annotations

from fastapi import APIRouter

from service.schemas import Health

router = APIRouter(tags=["health"])


@router.get("/healthz", response_model=Health, summary="Liveness probe")
async def healthz() -> Health:
    return Health()
