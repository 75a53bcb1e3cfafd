"""Model checks as jobs: stored in the SQLite job store, run in the worker processes, with progress.

A long model check (a diagnosis of a long log, an experiment design: seconds to minutes) must never hit a
request timeout. ``POST /v1/model-check/jobs`` stores the upload (log bytes and the checked form) in the
``model_checks`` table of the job store's file before answering 202; a background task per job runs it on
the worker pool (``wait=True``: it waits for a free worker and yields to requests with a deadline) under
``batch_item_timeout_s``. The task, in its worker process, writes its progress (0..1) into the job's row
through its own SQLite connection (:class:`ProgressWriter`, at most every 0.2 s; progress is advisory, a
failed write is skipped). A job moves ``queued -> running -> done | failed`` in one row; the log is dropped
from the row once the job has finished (the result stays). After a restart, jobs left ``queued`` or
``running`` run again (at most ``attempts`` times in all). At most ``max_pending`` jobs are unfinished at
once (503 + Retry-After beyond).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import sqlite3
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from ocp.errors import ThrustshapeError
from service.jobs import JobStore
from service.workers import QueueFull, Runner, TaskFailed, TaskFn, TaskTimeout

log = logging.getLogger("thrustshape.modelcheck")

JobState = Literal["queued", "running", "done", "failed"]

_SCHEMA = """
CREATE TABLE IF NOT EXISTS model_checks (
    id TEXT PRIMARY KEY,
    op TEXT NOT NULL,
    created_at REAL NOT NULL,
    payload TEXT NOT NULL,
    log BLOB NOT NULL,
    state TEXT NOT NULL CHECK (state IN ('queued', 'running', 'done', 'failed')),
    progress REAL NOT NULL DEFAULT 0,
    attempts INTEGER NOT NULL DEFAULT 0,
    result TEXT,
    error TEXT,
    finished_at REAL
)
"""


@dataclass(frozen=True)
class CheckJob:
    """One stored model-check job (``result``/``error`` loaded only by :meth:`CheckJobStore.get` with them)."""

    id: str
    op: str
    state: JobState
    progress: float
    attempts: int
    created_at: float
    finished_at: float | None
    result: dict[str, Any] | None = None
    error: dict[str, Any] | None = None


class CheckJobStore:
    """The ``model_checks`` table in the job store's SQLite file (its transactions, its file checks)."""

    def __init__(self, store: JobStore) -> None:
        self.store = store
        with store.transaction() as db:
            db.execute(_SCHEMA)

    @property
    def path(self) -> Path:
        return self.store.path

    def create(self, op: str, payload: dict[str, Any], log_bytes: bytes) -> str:
        job_id = uuid.uuid4().hex
        with self.store.transaction() as db:
            db.execute("INSERT INTO model_checks (id, op, created_at, payload, log, state) VALUES (?,?,?,?,?,'queued')",
                       (job_id, op, time.time(), json.dumps(payload, allow_nan=False), log_bytes))
        return job_id

    def pending(self) -> int:
        with self.store.transaction() as db:
            return int(db.execute("SELECT COUNT(*) FROM model_checks WHERE state IN ('queued', 'running')")
                       .fetchone()[0])

    def get(self, job_id: str, full: bool = False) -> CheckJob | None:
        cols = "result, error" if full else "NULL, error"  # the result can be large: read it only when asked
        with self.store.transaction() as db:
            r = db.execute(f"SELECT id, op, state, progress, attempts, created_at, finished_at, {cols} "
                           "FROM model_checks WHERE id = ?", (job_id,)).fetchone()
        if r is None:
            return None
        return CheckJob(r[0], r[1], r[2], float(r[3]), int(r[4]), float(r[5]), r[6],
                        json.loads(r[7]) if r[7] is not None else None, json.loads(r[8]) if r[8] is not None else None)

    def start(self, job_id: str) -> tuple[dict[str, Any], bytes, int] | None:
        """Mark a queued (or, after a restart, running) job running; its payload, log and attempt number."""
        with self.store.transaction() as db:
            r = db.execute("SELECT payload, log, attempts FROM model_checks WHERE id = ? AND state IN "
                           "('queued', 'running')", (job_id,)).fetchone()
            if r is None:
                return None
            db.execute("UPDATE model_checks SET state = 'running', attempts = attempts + 1, progress = 0 "
                       "WHERE id = ?", (job_id,))
        return json.loads(r[0]), bytes(r[1]), int(r[2]) + 1

    def finish(self, job_id: str, result: dict[str, Any] | None, error: dict[str, Any] | None) -> None:
        """Store the outcome once (only a running job), drop the log."""
        text = json.dumps(result, allow_nan=False) if result is not None else None
        with self.store.transaction() as db:
            db.execute("UPDATE model_checks SET state = ?, result = ?, error = ?, progress = ?, finished_at = ?, "
                       "log = x'' WHERE id = ? AND state = 'running'",
                       ("done" if error is None else "failed", text,
                        json.dumps(error, allow_nan=False) if error is not None else None,
                        1.0 if error is None else 0.0, time.time(), job_id))

    def unfinished(self) -> list[str]:
        with self.store.transaction() as db:
            rows = db.execute("SELECT id FROM model_checks WHERE state IN ('queued', 'running') "
                              "ORDER BY created_at").fetchall()
        return [str(r[0]) for r in rows]


class ProgressWriter:
    """Inside a worker: writes a job's progress into its row (own connection; throttled; never raises)."""

    def __init__(self, db_path: str, job_id: str, every_s: float = 0.2) -> None:
        self.db_path, self.job_id, self.every_s = db_path, job_id, every_s
        self._last = 0.0

    def __call__(self, fraction: float) -> None:
        now = time.monotonic()
        if now - self._last < self.every_s and fraction < 1.0:
            return
        self._last = now
        with contextlib.suppress(sqlite3.Error, OSError):
            db = sqlite3.connect(self.db_path, timeout=0.5, isolation_level=None)
            try:
                db.execute("UPDATE model_checks SET progress = ? WHERE id = ? AND state = 'running'",
                           (min(max(float(fraction), 0.0), 0.99), self.job_id))
            finally:
                db.close()


class CheckJobRunner:
    """Runs stored model-check jobs on the worker pool, one asyncio task each (module doc)."""

    def __init__(self, jobs: CheckJobStore, runner: Runner, task: TaskFn, *, timeout: float, attempts: int,
                 max_pending: int, retry_after: int) -> None:
        self.jobs, self._runner, self._task = jobs, runner, task
        self._timeout, self._attempts = timeout, attempts
        self._max_pending, self._retry_after = max_pending, retry_after
        self._tasks: set[asyncio.Task[None]] = set()

    async def submit(self, op: str, payload: dict[str, Any], log_bytes: bytes) -> str:
        """Store a job (refused with :class:`QueueFull` past ``max_pending`` unfinished ones) and start it."""
        if await asyncio.to_thread(self.jobs.pending) >= self._max_pending:
            raise QueueFull(self._retry_after)
        job_id = await asyncio.to_thread(self.jobs.create, op, payload, log_bytes)
        self._spawn(job_id)
        return job_id

    def resume(self) -> int:
        """After a restart: run again every job a previous server left unfinished; how many."""
        ids = self.jobs.unfinished()
        for job_id in ids:
            self._spawn(job_id)
        if ids:
            log.info("resuming %d model-check jobs left unfinished by a previous server", len(ids))
        return len(ids)

    def _spawn(self, job_id: str) -> None:
        t = asyncio.create_task(self._run(job_id), name=f"model-check-{job_id}")
        self._tasks.add(t)
        t.add_done_callback(self._tasks.discard)

    async def _run(self, job_id: str) -> None:
        while True:
            started = await asyncio.to_thread(self.jobs.start, job_id)
            if started is None:
                return
            payload, data, attempt = started
            payload = {**payload, "log": data, "progress": {"db": str(self.jobs.path), "id": job_id}}
            result, error = None, None
            try:
                result = await self._runner.run(self._task, payload, self._timeout, wait=True)
            except ThrustshapeError as exc:
                error = {"type": type(exc).__name__, "field": exc.field, "reason": exc.reason,
                         "form_field": getattr(exc, "form_field", None)}
            except (TaskTimeout, TaskFailed) as exc:
                log.warning("model-check job %s attempt %d: %s", job_id, attempt, exc)
                if attempt < self._attempts and not (isinstance(exc, TaskTimeout) and exc.phase == "run"):
                    continue  # a worker that died before reaching it: run it again
                error = {"type": type(exc).__name__, "field": None, "reason": str(exc), "form_field": None}
            await asyncio.to_thread(self.jobs.finish, job_id, result, error)
            return

    async def close(self) -> None:
        for t in list(self._tasks):
            t.cancel()
        for t in list(self._tasks):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await t
