"""Batch jobs: ``POST /v1/batches``, ``GET /v1/batches/{id}``, ``GET /v1/batches/{id}/results``.

A batch is stored (SQLite, fsync'd) before the 202 is sent; the lifespan's
:class:`~service.batches.BatchRunner` then works through it, surviving restarts.
"""

from __future__ import annotations

import asyncio
import csv
import io
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Header, Path, Query, Response
from starlette.exceptions import HTTPException

from service.api.deps import BatchesDep, SettingsDep, StoreDep, check_mission_limits
from service.api.problems import error_responses
from service.errors import TooLarge
from service.jobs import BatchCounts, Item, JobStore
from service.schemas import (
    BatchAccepted,
    BatchCountsPublic,
    BatchCreate,
    BatchItemPublic,
    BatchPublic,
    BatchResults,
    ItemError,
)

router = APIRouter(prefix="/v1/batches", tags=["batches"])

BatchId = Annotated[str, Path(min_length=1, max_length=64, description="batch id from POST /v1/batches")]
IdempotencyKey = Annotated[str | None, Header(alias="Idempotency-Key", min_length=1, max_length=200,
                                              description="resubmitting with the same key returns the same batch")]

CSV_COLUMNS = ("index", "name", "status", "attempts", "source", "solve_time_s", "thrust_rms_error",
               "max_abs_current", "max_abs_voltage", "error_type", "error_field", "error_reason")


def _public(c: BatchCounts) -> BatchPublic:
    return BatchPublic(id=c.id, status=c.status, created_at=c.created_at, progress=c.progress,
                       counts=BatchCountsPublic(total=c.total, queued=c.queued, running=c.running, done=c.done,
                                                failed=c.failed))


async def _counts(store: JobStore, batch_id: str) -> BatchCounts:
    counts = await asyncio.to_thread(store.counts, batch_id)
    if counts is None:
        raise HTTPException(404, f"no batch {batch_id!r}")
    return counts


@router.post("", status_code=202, response_model=BatchAccepted, responses=error_responses(401, 413, 422),
             summary="Submit missions for batch optimisation (stored durably before the answer)")
async def submit(body: BatchCreate, response: Response, settings: SettingsDep, store: StoreDep,
                 batches: BatchesDep, idempotency_key: IdempotencyKey = None) -> BatchAccepted:
    if len(body.missions) > settings.max_batch_missions:
        raise TooLarge("missions", f"{len(body.missions)} missions; this server accepts at most "
                                   f"{settings.max_batch_missions} per batch")
    for i, m in enumerate(body.missions):
        check_mission_limits(m, settings, prefix=f"missions.{i}.")
    missions = [m.model_dump(mode="json") for m in body.missions]
    batch_id, created = await asyncio.to_thread(store.create_batch, missions, idempotency_key)
    if created:
        batches.wake()
    else:
        response.headers["Idempotent-Replayed"] = "true"
    response.headers["Location"] = f"/v1/batches/{batch_id}"
    counts = await _counts(store, batch_id)
    return BatchAccepted(id=batch_id, status=counts.status)


@router.get("/{batch_id}", response_model=BatchPublic, responses=error_responses(401, 404),
            summary="Batch status, counts and progress")
async def status(batch_id: BatchId, store: StoreDep) -> BatchPublic:
    return _public(await _counts(store, batch_id))


def _item_public(it: Item) -> BatchItemPublic:
    return BatchItemPublic(index=it.index, name=it.name, status=it.state, attempts=it.attempts,
                           result=it.result if it.state == "done" else None,
                           error=ItemError(**it.error) if it.error is not None and it.state == "failed" else None)


def _csv(items: list[Item]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for it in items:
        res: dict[str, Any] = it.result if it.state == "done" and it.result else {}
        ver = res.get("verification") or {}
        err = it.error if it.state == "failed" and it.error else {}
        w.writerow([it.index, it.name, it.state, it.attempts, res.get("source", ""), res.get("solve_time_s", ""),
                    ver.get("thrust_rms_error", ""), ver.get("max_abs_current", ""), ver.get("max_abs_voltage", ""),
                    err.get("type", ""), err.get("field") or "", err.get("reason", "")])
    return buf.getvalue()


@router.get("/{batch_id}/results", response_model=BatchResults,
            responses={**error_responses(401, 404), 200: {"content": {"text/csv": {}}}},
            summary="Per-item results in submission order (JSON), or a one-row-per-item CSV summary")
async def results(batch_id: BatchId, store: StoreDep,
                  format: Annotated[Literal["json", "csv"] | None, Query(description="default: from Accept")] = None,
                  accept: Annotated[str | None, Header(max_length=1000)] = None) -> Any:
    counts = await _counts(store, batch_id)
    items = await asyncio.to_thread(store.items, batch_id)
    want_csv = format == "csv" or (format is None and accept is not None and "text/csv" in accept)
    if want_csv:
        return Response(_csv(items), media_type="text/csv")
    return BatchResults(id=batch_id, status=counts.status, results=[_item_public(it) for it in items])
