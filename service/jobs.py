"""SQLite job store for batches (WAL, ``synchronous=FULL``).

One row per batch, one row per item. An item moves ``queued -> running -> done | failed``; the move
to ``done`` is a single ``UPDATE ... WHERE state = 'running'`` that stores the result in the same
statement, so a result is written once or not at all; the outcomes of a group of finished items are written
in one transaction (:meth:`JobStore.record`: one fsync per group, all or nothing). After a crash,
:meth:`JobStore.recover` puts ``running`` items back to ``queued``: they run again, finished ones are never touched.

A batch submitted with an idempotency key is stored under that key (unique); resubmitting the same
body returns the stored batch, a different body under the same key is refused.

Thread-safe (one connection behind a lock); call it from a thread, not the event loop, when the
latency matters (``asyncio.to_thread``). One server per database file: :func:`lock_store` takes an
exclusive lock on ``<db>.lock`` for the server's lifetime and a second server refuses to start. Every
transaction first checks that the database file is still the one opened: SQLite would go on writing
into a deleted file and answer as if all were well; here a vanished file is :class:`StoreUnavailable`.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import sqlite3
import threading
import time
import uuid
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Literal

from service.errors import IdempotencyConflict, StoreUnavailable
from service.tasks import RENDERED

ItemState = Literal["queued", "running", "done", "failed"]
BatchState = Literal["queued", "running", "done", "failed"]

_SCHEMA = """
CREATE TABLE IF NOT EXISTS batches (
    id TEXT PRIMARY KEY,
    idempotency_key TEXT UNIQUE,
    body_sha256 TEXT NOT NULL,
    created_at REAL NOT NULL,
    size INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS items (
    batch_id TEXT NOT NULL REFERENCES batches(id),
    idx INTEGER NOT NULL,
    name TEXT NOT NULL,
    mission TEXT NOT NULL,
    state TEXT NOT NULL CHECK (state IN ('queued', 'running', 'done', 'failed')),
    attempts INTEGER NOT NULL DEFAULT 0,
    result TEXT,
    error TEXT,
    finished_at REAL,
    PRIMARY KEY (batch_id, idx)
);
CREATE INDEX IF NOT EXISTS items_by_state ON items (state, batch_id, idx);
"""


class StoreLocked(RuntimeError):
    """Another server holds the database's lock file."""


def lock_store(db_path: Path) -> IO[str]:
    """Exclusive lock on ``<db_path>.lock`` (held while the returned file stays open); raises
    :class:`StoreLocked` naming the other server's pid when it is taken."""
    db_path.parent.mkdir(parents=True, exist_ok=True)
    lock_path = db_path.with_name(db_path.name + ".lock")
    fh = open(lock_path, "a+", encoding="utf-8")
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        fh.seek(0)
        other = fh.read().strip() or "?"
        fh.close()
        raise StoreLocked(f"another thrustshape server (pid {other}) is using the job store {db_path}; one server "
                          f"per database: stop it, or give this one another THRUSTSHAPE_DB_PATH") from None
    fh.seek(0)
    fh.truncate()
    fh.write(str(os.getpid()))
    fh.flush()
    return fh


@dataclass(frozen=True)
class BatchCounts:
    """Item counts of one batch and the state derived from them."""

    id: str
    created_at: float
    total: int
    queued: int
    running: int
    done: int
    failed: int

    @property
    def finished(self) -> int:
        return self.done + self.failed

    @property
    def status(self) -> BatchState:
        """done / failed when every item finished (failed: none succeeded), else running / queued."""
        if self.finished == self.total:
            return "done" if self.done > 0 else "failed"
        if self.running or self.finished:
            return "running"
        return "queued"

    @property
    def progress(self) -> float:
        return self.finished / self.total if self.total else 1.0


@dataclass(frozen=True)
class Item:
    batch_id: str
    index: int
    name: str
    state: ItemState
    attempts: int
    mission: dict[str, Any] | None  # loaded by claim() only (the runner needs it; status reads do not)
    result: dict[str, Any] | None
    error: dict[str, Any] | None


@dataclass(frozen=True)
class Outcome:
    """What running one item gave: its ``result``, or its ``error`` and whether to ``retry`` it."""

    batch_id: str
    index: int
    result: dict[str, Any] | None = None
    error: dict[str, Any] | None = None
    retry: bool = False


def result_text(result: dict[str, Any]) -> str:
    """A result as the JSON text stored: rendered already by the worker (``{RENDERED: bytes}``,
    :func:`service.tasks.batch_answer`; no 16,000-number ``json.dumps`` in the server process) or rendered here."""
    rendered = result.get(RENDERED) if len(result) == 1 else None
    return rendered.decode() if isinstance(rendered, bytes) else json.dumps(result, allow_nan=False)


def body_digest(missions: Sequence[dict[str, Any]]) -> str:
    """SHA-256 of the canonical JSON of the missions (idempotency check)."""
    canon = json.dumps(list(missions), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(canon.encode()).hexdigest()


class JobStore:
    """The batch tables in one SQLite file; see the module doc."""

    def __init__(self, path: Path, busy_timeout: float = 10.0) -> None:
        """``busy_timeout`` [s]: how long a write waits for another connection's lock before failing."""
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._lock = threading.Lock()
        self._db = sqlite3.connect(path, check_same_thread=False, isolation_level=None, timeout=busy_timeout)
        self._identity = _identity(path)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=FULL")
        self._db.execute("PRAGMA foreign_keys=ON")
        with self._tx() as db:
            for stmt in filter(str.strip, _SCHEMA.split(";")):
                db.execute(stmt)

    def check(self) -> None:
        """Raise :class:`StoreUnavailable` unless the database file is still the one this store opened."""
        now = _identity(self.path)
        if now != self._identity:
            raise StoreUnavailable(f"the job store file {self.path.name} vanished or was replaced while the server "
                                   "ran (data directory deleted?); restart the server")

    def ping(self) -> None:
        """Health check: the file is in place and answers a read (raises :class:`StoreUnavailable`)."""
        self.check()
        try:
            with self._lock:
                self._db.execute("SELECT COUNT(*) FROM batches").fetchone()
        except sqlite3.Error as exc:
            raise StoreUnavailable(f"the job store does not answer: {exc}") from None

    @contextmanager
    def _tx(self) -> Iterator[sqlite3.Connection]:
        """One ``BEGIN IMMEDIATE`` transaction; SQLite errors (locked past the busy timeout, disk full, I/O)
        become :class:`StoreUnavailable` after a rollback."""
        self.check()
        with self._lock:
            try:
                self._db.execute("BEGIN IMMEDIATE")
            except sqlite3.Error as exc:
                raise StoreUnavailable(f"the job store is not writable: {exc}") from None
            try:
                yield self._db
                self._db.execute("COMMIT")
            except BaseException as exc:
                with contextlib.suppress(sqlite3.Error):
                    self._db.execute("ROLLBACK")
                if isinstance(exc, sqlite3.Error):
                    raise StoreUnavailable(f"the job store write failed: {exc}") from None
                raise

    def transaction(self) -> contextlib.AbstractContextManager[sqlite3.Connection]:
        """One write transaction (see ``_tx``) for other tables of this file (the model-check jobs)."""
        return self._tx()

    def close(self) -> None:
        with self._lock:
            self._db.close()

    def create_batch(self, missions: Sequence[dict[str, Any]], key: str | None) -> tuple[str, bool]:
        """Store a batch durably; returns ``(id, created)``; ``created`` False when the key already had it."""
        digest = body_digest(missions)
        with self._tx() as db:
            if key is not None:
                row = db.execute("SELECT id, body_sha256 FROM batches WHERE idempotency_key = ?", (key,)).fetchone()
                if row is not None:
                    if row[1] != digest:
                        raise IdempotencyConflict(key, row[0])
                    return str(row[0]), False
            batch_id = uuid.uuid4().hex
            db.execute("INSERT INTO batches (id, idempotency_key, body_sha256, created_at, size) VALUES (?,?,?,?,?)",
                       (batch_id, key, digest, time.time(), len(missions)))
            db.executemany(
                "INSERT INTO items (batch_id, idx, name, mission, state) VALUES (?,?,?,?,'queued')",
                [(batch_id, i, str(m.get("name", "mission")), json.dumps(m, allow_nan=False))
                 for i, m in enumerate(missions)])
        return batch_id, True

    def counts(self, batch_id: str) -> BatchCounts | None:
        self.check()
        with self._lock:
            head = self._db.execute("SELECT created_at, size FROM batches WHERE id = ?", (batch_id,)).fetchone()
            if head is None:
                return None
            rows = self._db.execute("SELECT state, COUNT(*) FROM items WHERE batch_id = ? GROUP BY state",
                                    (batch_id,)).fetchall()
        n = dict(rows)
        return BatchCounts(batch_id, head[0], head[1], n.get("queued", 0), n.get("running", 0), n.get("done", 0),
                           n.get("failed", 0))

    def items(self, batch_id: str) -> list[Item]:
        """A batch's items for status and result reads (``mission`` not loaded: it can be large)."""
        self.check()
        with self._lock:
            rows = self._db.execute(
                "SELECT batch_id, idx, name, state, attempts, NULL, result, error FROM items "
                "WHERE batch_id = ? ORDER BY idx", (batch_id,)).fetchall()
        return [_item(r) for r in rows]

    def claim(self, limit: int) -> list[Item]:
        """Mark up to ``limit`` queued items (oldest batch first) running and return them."""
        if limit <= 0:
            return []
        with self._tx() as db:
            rows = db.execute(
                "SELECT i.batch_id, i.idx, i.name, i.state, i.attempts, i.mission, i.result, i.error "
                "FROM items i JOIN batches b ON b.id = i.batch_id WHERE i.state = 'queued' "
                "ORDER BY b.created_at, i.batch_id, i.idx LIMIT ?", (limit,)).fetchall()
            db.executemany("UPDATE items SET state = 'running', attempts = attempts + 1 WHERE batch_id = ? AND idx = ?",
                           [(r[0], r[1]) for r in rows])
        return [_item((r[0], r[1], r[2], "running", r[4] + 1, r[5], None, None)) for r in rows]

    def record(self, outcomes: Sequence[Outcome]) -> list[ItemState | None]:
        """Store the outcomes of running items in ONE transaction (one fsync for the group): a result moves its
        item to ``done``; an error to ``queued`` (``retry``) or ``failed``. All land or none does (a failure rolls
        the group back: the caller keeps it and tries again). Per outcome, the state written, or None when the
        item was not running (nothing written: each outcome lands once)."""
        now = time.time()
        written: list[ItemState | None] = []
        with self._tx() as db:
            for o in outcomes:
                state: ItemState = "done" if o.result is not None else "queued" if o.retry else "failed"
                cur = db.execute(
                    "UPDATE items SET state = ?, result = ?, error = ?, finished_at = ? "
                    "WHERE batch_id = ? AND idx = ? AND state = 'running'",
                    (state, None if o.result is None else result_text(o.result),
                     None if o.error is None else json.dumps(o.error, allow_nan=False),
                     None if state == "queued" else now, o.batch_id, o.index))
                written.append(state if cur.rowcount == 1 else None)
        return written

    def finish(self, batch_id: str, index: int, result: dict[str, Any]) -> bool:
        """Store a running item's result; False (and nothing written) when it is not running."""
        return self.record([Outcome(batch_id, index, result=result)])[0] == "done"

    def fail(self, batch_id: str, index: int, error: dict[str, Any], retry: bool) -> ItemState | None:
        """A running item failed: back to ``queued`` when ``retry``, else ``failed``; None if it was not running."""
        return self.record([Outcome(batch_id, index, error=error, retry=retry)])[0]

    def recover(self) -> int:
        """After a restart: items left ``running`` by a dead server go back to ``queued``; returns how many."""
        with self._tx() as db:
            cur = db.execute("UPDATE items SET state = 'queued' WHERE state = 'running'")
        return cur.rowcount


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _item(r: tuple[Any, ...]) -> Item:
    def loads(text: str | None) -> Any:
        return json.loads(text) if text is not None else None

    return Item(batch_id=r[0], index=r[1], name=r[2], state=r[3], attempts=r[4], mission=loads(r[5]),
                result=loads(r[6]), error=loads(r[7]))
