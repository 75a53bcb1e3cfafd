"""Batches by structure: items of one collocation structure run on the worker that built it (real worker
processes, real IPOPT solves, builds counted by the workers' own reports), outcomes are written to a real
SQLite file in groups, a crash loses no stored result, and a mission naming a file is refused wherever it
comes from (the runner and the worker both validate with the untrusted rule)."""

from __future__ import annotations

import asyncio
import json
import os
import sqlite3
import time
from collections import Counter
from pathlib import Path
from typing import Any

import httpx
import pytest

from ocp.errors import MissionError
from service.batches import BatchRunner
from service.dispatch import Dispatcher
from service.jobs import JobStore
from service.schemas import MissionRequest
from service.tasks import available_tasks, optimize_mission, structure_key
from service.workers import WorkerPool
from tests.service.test_service_support import (
    ROOT,
    broken_key,
    digest,
    mission,
    slow_item,
    start_server,
    structure_key_noting_pid,
)

needs_optimize = pytest.mark.skipif(available_tasks().optimize is None, reason="ocp.optimize.solve is not installed")
PARAMS_FILE = str(ROOT / "examples" / "params.yaml")  # a real file on this machine: never to be read


def _payload(name: str, intervals: int) -> dict[str, Any]:
    return MissionRequest.model_validate(mission(name, collocation={"intervals": intervals})).model_dump(mode="json")


# -- the dispatcher alone (no processes) -----------------------------------------------------------------------


async def _settled() -> None:
    for _ in range(3):
        await asyncio.sleep(0)


def test_dispatcher_pairs_by_affinity_serves_urgent_calls_first_and_builds_twice_only_for_a_crowd() -> None:
    async def main() -> None:
        d: Dispatcher[str] = Dispatcher(["w1", "w2"], slots=2, patience=4, crowd=2)
        assert await d.get("A") == "w1" and await d.get("B") == "w2"
        d.remember("w1", "A")
        d.remember("w2", "B")
        calls = [asyncio.ensure_future(d.get(k)) for k in ("B", "A", "C")]
        await _settled()
        d.put("w1")  # w1 holds A: it takes the A call although the B call waited longer
        await _settled()
        assert calls[1].done() and calls[1].result() == "w1" and not calls[0].done()
        d.put("w1")  # B is w2's; C is nobody's: a build nobody else does
        await _settled()
        assert calls[2].result() == "w1" and not calls[0].done()
        urgent = asyncio.ensure_future(d.get(urgent=True))
        await _settled()
        d.put("w2")  # a deadline-bound call first, even before the B call w2 holds
        await _settled()
        assert urgent.result() == "w2" and not calls[0].done()
        d.remember("w1", "C")
        d.put("w1")  # idle, but the B call waits for w2, which holds B: no duplicate build for one call
        await _settled()
        assert not calls[0].done()
        more = [asyncio.ensure_future(d.get("B")) for _ in range(2)]
        await _settled()  # three B calls for one holder (crowd 2): w1 builds B too, for the oldest
        assert calls[0].result() == "w1" and not any(m.done() for m in more)
        d.forget("w1")
        assert d.holds("w1") == () and d.holds("w2") == ("B",)
        for m in more:
            m.cancel()
        await _settled()
        d.put("w2")  # cancelled calls take no worker
        assert await d.get() == "w2"

    asyncio.run(main())


def test_dispatcher_lets_no_call_starve_behind_better_matches() -> None:
    async def main() -> None:
        d: Dispatcher[str] = Dispatcher(["w1", "w2"], patience=2, crowd=100)
        assert await d.get("A") == "w1" and await d.get("B") == "w2"
        d.remember("w1", "A")
        d.remember("w2", "B")
        old = asyncio.ensure_future(d.get("B"))  # waits for w2, which stays busy
        for _ in range(2):  # two newer A calls pass it ...
            a = asyncio.ensure_future(d.get("A"))
            await _settled()
            d.put("w1")
            await _settled()
            assert a.result() == "w1" and not old.done()
        late = asyncio.ensure_future(d.get("A"))
        await _settled()
        d.put("w1")  # ... then its patience is used up: served by w1 although w1 holds A and an A call waits
        await _settled()
        assert old.result() == "w1" and not late.done()
        late.cancel()
        await _settled()

    asyncio.run(main())


class _BruteForce:
    """The dispatcher's rule written out the slow way, as its oracle: every waiting call ranked against every
    idle worker at every pairing (no candidate shortcut, no shared code)."""

    def __init__(self, workers: list[str], slots: int, patience: int, crowd: int) -> None:
        self.idle = list(workers)
        self.waiting: list[list[Any]] = []  # [call, key, urgent, skipped], oldest first
        self.held: dict[str, list[Any]] = {w: [] for w in workers}  # least recently used first
        self.running: dict[str, Any] = {}
        self.slots, self.patience, self.crowd = slots, patience, crowd

    def arrive(self, call: int, key: Any, urgent: bool) -> list[tuple[int, str]]:
        self.waiting.append([call, key, urgent, 0])
        return self.match()

    def finish(self, worker: str, key: Any) -> list[tuple[int, str]]:
        if key is not None:
            held = [k for k in self.held[worker] if k != key] + [key]
            self.held[worker] = held[-self.slots:]
        self.running.pop(worker)
        self.idle.append(worker)
        return self.match()

    def rank(self, w: str, call: list[Any]) -> int | None:
        _, key, urgent, skipped = call
        if urgent:
            return 0
        if skipped >= self.patience:
            return 1
        if key is None:
            return 3
        if key in self.held[w]:
            return 2
        holders = [v for v in self.held if key in self.held[v] or self.running.get(v, object()) == key]
        if not holders:
            return 3
        queue = {v: sum(1 for c in self.waiting if c[1] in self.held[v] or c[1] == self.running.get(v, object()))
                 for v in holders}
        return 4 if min(queue.values()) > self.crowd else None

    def match(self) -> list[tuple[int, str]]:
        out: list[tuple[int, str]] = []
        while True:
            pairs = [(r, pos, len(self.held[w]), i) for i, w in enumerate(self.idle)
                     for pos, c in enumerate(self.waiting) if (r := self.rank(w, c)) is not None]
            if not pairs:
                return out
            _, pos, _, i = min(pairs)
            for c in self.waiting[:pos]:
                c[3] += 1
            call = self.waiting.pop(pos)
            worker = self.idle.pop(i)
            self.running[worker] = call[1]
            out.append((call[0], worker))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_dispatcher_pairs_as_the_brute_force_rule_does_with_many_calls_waiting(seed: int) -> None:
    """Random arrivals (keys, none, urgent) and finishes: every pairing equals the brute-force rule's."""
    import random

    rng = random.Random(seed)
    workers = ["w1", "w2", "w3"]

    async def main() -> None:
        d: Dispatcher[str] = Dispatcher(workers, slots=2, patience=5, crowd=3)
        oracle = _BruteForce(workers, slots=2, patience=5, crowd=3)
        made: list[tuple[int, str]] = []
        keys: dict[int, Any] = {}
        busy: dict[str, int] = {}
        for step in range(600):
            if rng.random() < 0.55 or not busy:
                key = rng.choice(["A", "B", "C", "D", "E", None])
                urgent = rng.random() < 0.08
                keys[step] = key
                t = asyncio.ensure_future(d.get(key, urgent=urgent))

                def paired(t: asyncio.Future[str], c: int = step) -> None:
                    made.append((c, t.result()))

                t.add_done_callback(paired)
                want = oracle.arrive(step, key, urgent)
            else:
                w = rng.choice(sorted(busy))
                key = keys[busy.pop(w)]
                d.remember(w, key)
                d.put(w)
                want = oracle.finish(w, key)
            await _settled()
            assert made == want, f"step {step}"
            busy.update({w: c for c, w in made})
            made.clear()
        assert d.waiting == len(oracle.waiting) > 50  # many calls were waiting: the shortcut was exercised

    asyncio.run(main())


# -- real worker processes, real solves --------------------------------------------------------------------


@needs_optimize
@pytest.mark.slow
def test_a_structure_is_built_once_per_batch_not_per_item() -> None:
    """N same-structure items on 2 workers build at most 2 programs; a second structure mixed in is built by one
    worker only (without affinity both would build it); and the worker's own validation refuses a file."""

    async def main() -> tuple[int, int, list[dict[str, Any]], MissionError]:
        pool = WorkerPool(2, 0, 1, preload=("ocp.optimize.solve", "service.tasks"))
        try:
            same = [_payload(f"a{i}", 40) for i in range(6)]
            assert len({structure_key(p) for p in same}) == 1
            await asyncio.gather(*(pool.run(optimize_mission, p, 300, wait=True, affinity=structure_key(p))
                                   for p in same))
            first = sum(pool.builds())
            mixed = [_payload(f"{'ab'[i % 2]}{i}", 40 if i % 2 == 0 else 60) for i in range(8)]
            assert len({structure_key(p) for p in mixed}) == 2
            out = await asyncio.gather(*(pool.run(optimize_mission, p, 300, wait=True, affinity=structure_key(p))
                                         for p in mixed))
            with pytest.raises(MissionError) as refused:  # sent past the parent's check: the worker refuses
                await pool.run(optimize_mission, {**same[0], "params": PARAMS_FILE}, 60)
            return first, sum(pool.builds()) - first, out, refused.value
        finally:
            pool.close()

    first, second, out, refused = asyncio.run(main())
    assert 1 <= first <= 2
    assert second == 1
    assert all(r["source"] == "optimized" and r["verification"]["max_abs_voltage"] <= 12.0 + 1e-6 for r in out)
    assert refused.field == "params" and "files are not read" in refused.reason


async def _finished(store: JobStore, batch_id: str, n: int, timeout: float = 120.0) -> None:
    """Wait until ``n`` items of the batch finished (fails the test after ``timeout`` [s])."""
    end = time.monotonic() + timeout
    while (c := store.counts(batch_id)) is not None and c.finished < n:
        assert time.monotonic() < end, "batch did not finish"
        await asyncio.sleep(0.05)


def test_the_runner_routes_by_structure_groups_writes_and_refuses_files(tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """A real JobStore file and real worker processes (a CPU-bound test task that reports its pid): the items of
    each structure all run in one process, outcomes land in fewer transactions than items, and a mission naming
    a file fails at once, naming ``params``, without reaching a worker."""
    monkeypatch.setenv("TS_TEST_ITEM_SECONDS", "0.3")
    monkeypatch.setenv("TS_TEST_KEY_PIDS", str(tmp_path / "key-pids"))
    missions = [mission(f"{'ab'[i % 2]}{i}", collocation={"intervals": 40 if i % 2 == 0 else 60}) for i in range(8)]
    missions.append(mission("file", params=PARAMS_FILE))

    async def main() -> tuple[str, JobStore, int]:
        store = JobStore(tmp_path / "jobs.sqlite3")
        batch_id, _ = store.create_batch(missions, None)
        pool = WorkerPool(2, 0, 1, preload=("tests.service.test_service_support",))
        keys = WorkerPool(1, 0, 1, preload=("tests.service.test_service_support",))  # as the server's fallbacks
        # every item claimed at once (lookahead): each free worker has the whole choice
        runner = BatchRunner(store, pool, slow_item, concurrency=2, timeout=60, attempts=1,
                             key=structure_key_noting_pid, key_runner=keys, lookahead=len(missions), group_s=1.0)
        runner.start()
        try:
            await _finished(store, batch_id, len(missions))
        finally:
            await runner.close()
            pool.close()
            key_pids = set((tmp_path / "key-pids").read_text().split())
            assert key_pids == {str(keys.pids()[0])} and str(os.getpid()) not in key_pids  # no key computed here
            keys.close()
        return batch_id, store, runner.groups

    batch_id, store, groups = asyncio.run(main())
    items = store.items(batch_id)
    refused = items[-1]
    assert refused.state == "failed" and refused.error is not None and refused.result is None
    assert refused.error["field"] == "params" and "files are not read" in refused.error["reason"]
    done = items[:-1]
    assert all(it.state == "done" and it.result is not None for it in done)
    pids = {k: {it.result["pid"] for it in done if it.name[0] == k and it.result} for k in "ab"}
    assert len(pids["a"]) == 1 and len(pids["b"]) == 1 and pids["a"] != pids["b"], pids
    assert groups < len(missions)
    with sqlite3.connect(store.path) as con:  # one transaction stamps one time on its group
        stamps = Counter(t for (t,) in con.execute("SELECT finished_at FROM items WHERE batch_id = ?", (batch_id,)))
    assert len(stamps) == groups and max(stamps.values()) >= 2
    store.close()


def test_items_run_without_affinity_when_their_keys_call_fails(tmp_path: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """A keys call that fails in its worker (a broken key function) costs the group its affinity, never its
    items: every claimed item still runs and lands once."""
    monkeypatch.setenv("TS_TEST_ITEM_SECONDS", "0.05")
    missions = [mission(f"k{i}") for i in range(4)]

    async def main() -> JobStore:
        store = JobStore(tmp_path / "jobs.sqlite3")
        batch_id, _ = store.create_batch(missions, None)
        pool = WorkerPool(1, 0, 1, preload=("tests.service.test_service_support",))
        keys = WorkerPool(1, 0, 1, preload=("tests.service.test_service_support",))
        runner = BatchRunner(store, pool, slow_item, concurrency=1, timeout=60, attempts=1, key=broken_key,
                             key_runner=keys, group_s=0.0)
        runner.start()
        try:
            await _finished(store, batch_id, len(missions))
        finally:
            await runner.close()
            pool.close()
            keys.close()
        return store

    store = asyncio.run(main())
    with sqlite3.connect(store.path) as con:
        states = [s for (s,) in con.execute("SELECT state FROM items ORDER BY idx")]
    assert states == ["done"] * len(missions)
    store.close()


@pytest.mark.integration
@pytest.mark.slow
def test_grouped_writes_lose_no_result_when_the_server_is_killed(tmp_path: Path) -> None:
    """Outcomes wait up to 0.4 s to share a transaction; the server is SIGKILLed mid-batch. Every result the
    store held survives unchanged, every outcome not yet written is recomputed after the restart, each item
    lands once."""
    db = tmp_path / "jobs.sqlite3"
    env = {"TS_TEST_TASKS": "slow-batch", "TS_TEST_ITEM_SECONDS": "0.15", "THRUSTSHAPE_DB_PATH": str(db),
           "THRUSTSHAPE_WORKERS": "2", "THRUSTSHAPE_FALLBACK_WORKERS": "1", "THRUSTSHAPE_BATCH_WRITE_GROUP_S": "0.4"}
    missions = [mission(f"g{i}", amplitude=0.1 + 0.01 * i) for i in range(16)]
    first = start_server(tmp_path, env)
    try:
        batch_id = httpx.post(f"{first.url}/v1/batches", json={"missions": missions}, timeout=10).json()["id"]
        end = time.monotonic() + 60
        while httpx.get(f"{first.url}/v1/batches/{batch_id}", timeout=10).json()["counts"]["done"] < 4:
            assert time.monotonic() < end, "batch made no progress"
            time.sleep(0.02)
    finally:
        first.kill()
    with sqlite3.connect(db) as con:
        before = dict(con.execute("SELECT idx, result FROM items WHERE batch_id = ? AND state = 'done'",
                                  (batch_id,)).fetchall())
        stamps = Counter(t for (t,) in con.execute("SELECT finished_at FROM items WHERE batch_id = ? AND "
                                                   "state = 'done'", (batch_id,)))
    assert 4 <= len(before) < len(missions) and max(stamps.values()) >= 2  # grouped, and killed mid-batch
    second = start_server(tmp_path, env)
    try:
        end = time.monotonic() + 90
        while httpx.get(f"{second.url}/v1/batches/{batch_id}", timeout=10).json()["status"] != "done":
            assert time.monotonic() < end, "batch not finished after restart"
            time.sleep(0.1)
    finally:
        second.stop()
    with sqlite3.connect(db) as con:
        rows = con.execute("SELECT idx, state, result FROM items WHERE batch_id = ? ORDER BY idx",
                           (batch_id,)).fetchall()
    assert [r[0] for r in rows] == list(range(len(missions))) and {r[1] for r in rows} == {"done"}
    for idx, result in before.items():  # stored before the kill: untouched
        assert rows[idx][2] == result
    expected = [digest(MissionRequest.model_validate(m).model_dump(mode="json")) for m in missions]
    assert [json.loads(r[2])["digest"] for r in rows] == expected
