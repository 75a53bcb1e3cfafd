#!/usr/bin/env python
"""Batch benchmark: N mixed missions through ``thrustshape batch --local --workers W`` (issue #14 target:
1,000 missions on 2 workers in at most 25 s).

Usage::

    python bench/batch.py [--n 1000] [--workers 2] [--seed 7] [--before DIR] [--json]
    python bench/batch.py --builds [--n 200]    # solver builds with and without structure affinity

The missions are drawn from a fixed seed: one and two reversals (cosine or ramp), a sampled sine profile,
levels 0.15-0.45 N, two motors (the ``paper-rig`` preset and a mapping), regularities ``bounded`` (60 %),
``continuous-current`` (25 %) and ``continuous-voltage`` (15 %), 40 or 60 collocation intervals: 12 solver
structures mixed in random order. They are written to one file and run by the real CLI in a subprocess
(worker start-up, solver builds and the summary included in the wall time). ``--before DIR`` runs the same
file with the code in ``DIR`` (e.g. ``git archive <commit> | tar -x -C DIR``) right before, for a side-by-side
row in one run. The machine's load (``uptime``) is printed beside each row: on a shared machine the
figures move with it.
This is a benchmark, not a test: it prints a table and never fails the build.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 25.0  # issue #14: 1,000 mixed missions, 2 workers
#: a second motor (SI): the paper rig with 4 Ohm and a heavier propeller
MOTOR_B = {"J": 3.0e-5, "B": 5.31e-5, "c_tau": 2.2e-6, "c_f": 1.4e-4, "k_t": 0.0573, "k_e": 0.0573, "R": 4.0,
           "L": 0.002}


def _segments(rng: random.Random) -> list[dict[str, Any]]:
    level = round(rng.uniform(0.15, 0.45), 3)
    shape = rng.choice(["cosine", "ramp"])
    rev = round(rng.uniform(0.3, 0.8), 3)
    hold = round(rng.uniform(0.2, 0.6), 3)
    one = [{"kind": "hold", "duration": hold, "thrust": level},
           {"kind": "reversal", "duration": rev, "to": -level, "shape": shape},
           {"kind": "hold", "duration": hold, "thrust": -level}]
    if rng.random() < 0.3:  # and back again
        return [*one, {"kind": "reversal", "duration": rev, "to": level, "shape": shape},
                {"kind": "hold", "duration": hold, "thrust": level}]
    return one


def _profile(rng: random.Random) -> dict[str, Any]:
    """A sampled sine through zero, 200 Hz over 1-2 s (one or two reversals)."""
    import math

    duration, amp = rng.choice([1.0, 2.0]), round(rng.uniform(0.15, 0.4), 3)
    n = int(200 * duration) + 1
    t = [i / 200 for i in range(n)]
    return {"t": t, "thrust": [round(amp * math.sin(math.pi * ti + 0.3), 6) for ti in t]}


def missions(n: int, seed: int) -> list[dict[str, Any]]:
    """``n`` mixed missions (JSON mappings) from ``seed``."""
    rng = random.Random(seed)
    out = []
    for i in range(n):
        m: dict[str, Any] = {"name": f"m{i:04d}", "params": rng.choice(["paper-rig", MOTOR_B]),
                             "limits": {"voltage": 12.0, "current": 1.0},
                             "regularity": rng.choices(["bounded", "continuous-current", "continuous-voltage"],
                                                       [0.6, 0.25, 0.15])[0],
                             "collocation": {"intervals": rng.choice([40, 60])}, "time_limit_s": 10.0}
        if rng.random() < 0.15:
            m["profile"] = _profile(rng)
        else:
            m["segments"] = _segments(rng)
        out.append(m)
    return out


def _load() -> str:
    return os.getloadavg().__repr__() if hasattr(os, "getloadavg") else "?"


def run(code: Path, path: Path, workers: int) -> dict[str, Any]:
    """One ``thrustshape batch --local`` run of the code in ``code`` on the missions file ``path``."""
    env = {**os.environ, "PYTHONPATH": str(code)}
    load_before = _load()
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "clients.cli", "batch", str(path), "--local", "--workers",
                           str(workers), "--json"], cwd=code, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    try:
        out = json.loads(proc.stdout)
    except json.JSONDecodeError:
        return {"code": str(code), "wall_s": wall, "error": proc.stderr[-2000:], "load": load_before}
    rows = out["summary"]
    return {"code": str(code), "wall_s": wall, "elapsed_s": out["elapsed_s"], "n": len(rows),
            "failed": out["failed"], "sources": dict(Counter(r["source"] or r["status"] for r in rows)),
            "load_before": load_before, "load_after": _load()}


def pool_run(payloads: list[dict[str, Any]], workers: int, affinity: bool) -> dict[str, Any]:
    """The missions on a :class:`service.workers.WorkerPool` directly (what ``batch --local`` does), with or
    without structure affinity; the solver builds each worker reported."""
    import asyncio

    from service.tasks import optimize_mission, structure_key
    from service.workers import WorkerPool

    async def go() -> dict[str, Any]:
        pool = WorkerPool(workers, 0, 1, preload=("ocp.optimize.mission", "ocp.optimize.solve", "service.tasks"))
        try:
            await pool.warm()
            keys = [structure_key(p) if affinity else None for p in payloads]
            t0 = time.perf_counter()
            await asyncio.gather(*(pool.run(optimize_mission, p, 300.0, wait=True, affinity=k)
                                   for p, k in zip(payloads, keys, strict=True)), return_exceptions=True)
            return {"wall_s": time.perf_counter() - t0, "builds": pool.builds()}
        finally:
            pool.close()

    load_before = _load()
    out = asyncio.run(go())
    return {**out, "load_before": load_before, "load_after": _load()}


def timed_optimize(payload: dict[str, Any]) -> dict[str, Any]:
    """The batch item's task (:func:`service.tasks.optimize_mission`) with where its worker time went: the
    result's own report (setup, builds, IPOPT, verification) plus the encoding (``to_dict``) and the pickled
    size of the answer, timed around the same calls; returns only the timing (runs in a worker)."""
    import pickle

    from ocp.optimize.collocation import SolveContext
    from ocp.optimize.solve import optimize
    from service.tasks import untrusted_mission
    from service.workers import report_phase

    start = time.monotonic()  # system-wide clock: the parent compares it with its own
    t0 = time.perf_counter()
    mission = untrusted_mission(payload)
    t1 = time.perf_counter()
    result = optimize(mission, warm=None, context=SolveContext(on_build=report_phase))
    t2 = time.perf_counter()
    answer = result.to_dict()
    t3 = time.perf_counter()
    size = len(pickle.dumps(("ok", answer), protocol=pickle.HIGHEST_PROTOCOL))
    s = result.solver
    return {"validate": t1 - t0, "setup": s.setup_time_s, "build": s.build_time_s, "ipopt": s.solve_time_s,
            "verify": s.verify_time_s, "rest of optimize": (t2 - t1) - s.setup_time_s - s.build_time_s
            - s.solve_time_s - s.verify_time_s, "encode": t3 - t2, "pickle_bytes": size, "task": t3 - t0,
            "source": str(result.source), "reason": (result.reason or "")[:60], "backoff": s.backoff_rounds,
            "pid": os.getpid(), "start": start, "end": start + time.perf_counter() - t0}


def breakdown(payloads: list[dict[str, Any]], workers: int) -> dict[str, Any]:
    """Where the wall time of ``batch --local`` goes, the steps it takes timed apart: validation and affinity
    keys in the parent, worker start-up, then every item on the pool with :func:`timed_optimize` (its worker
    time split; the rest of each call's wall time is the pipe, the pickling and the dispatch)."""
    import asyncio

    from ocp.optimize.mission import mission_from_mapping
    from service.tasks import structure_key
    from service.workers import WorkerPool

    t0 = time.perf_counter()
    for p in payloads:
        mission_from_mapping(p)
    t_validate = time.perf_counter() - t0
    t0 = time.perf_counter()
    keys = [structure_key(p) for p in payloads]
    t_keys = time.perf_counter() - t0

    async def go() -> dict[str, Any]:
        t0 = time.perf_counter()
        pool = WorkerPool(workers, 0, 1, preload=("ocp.optimize.mission", "ocp.optimize.solve", "service.tasks"))
        try:
            await pool.warm()
            t_start = time.perf_counter() - t0

            async def one(p: dict[str, Any], k: Any) -> dict[str, Any]:
                return await pool.run(timed_optimize, p, 300.0, wait=True, affinity=k)

            t0 = time.perf_counter()
            items = await asyncio.gather(*(one(p, k) for p, k in zip(payloads, keys, strict=True)))
            return {"startup_s": t_start, "run_s": time.perf_counter() - t0, "items": items, "builds": pool.builds()}
        finally:
            pool.close()

    out = asyncio.run(go())
    return {"validate_s": t_validate, "keys_s": t_keys, **out}


def _gaps(items: list[dict[str, Any]]) -> list[float]:
    """Per item, the time its worker spent between the previous item's end and this one's start: sending the
    answer back and the next call over the pipe (pickling both ways), the parent's dispatch; 0 for a worker's
    first item."""
    out = []
    last: dict[int, float] = {}
    for i in sorted(items, key=lambda i: i["start"]):
        out.append(i["start"] - last[i["pid"]] if i["pid"] in last else 0.0)
        last[i["pid"]] = i["end"]
    return out


def print_breakdown(b: dict[str, Any], workers: int) -> None:
    items = b["items"]
    n = len(items)
    print(f"{n} missions, {workers} workers; parent: validate {b['validate_s']:.2f} s, structure keys "
          f"{b['keys_s']:.2f} s; worker start-up (spawn + imports, in parallel) {b['startup_s']:.2f} s; "
          f"items {b['run_s']:.1f} s wall ({n / b['run_s']:.1f} items/s), builds per worker {b['builds']}")
    parts = ["validate", "setup", "build", "ipopt", "verify", "rest of optimize", "encode"]
    worker_total = sum(i["task"] for i in items)
    print(f"worker time over all items: {worker_total:.1f} s = {worker_total / workers / b['run_s']:.0%} of "
          f"{workers} workers x the items' wall time")
    print(f"{'part':<28} {'total s':>8} {'share':>6} {'mean ms':>8} {'median ms':>9}")
    pipe = _gaps(items)
    rows = [(k, [i[k] for i in items]) for k in parts] + [("pipe + pickle + dispatch", pipe)]
    for name, vals in rows:
        tot = sum(vals)
        print(f"{name:<28} {tot:>8.2f} {tot / max(worker_total + sum(pipe), 1e-9):>6.1%} {1e3 * tot / n:>8.1f} "
              f"{1e3 * sorted(vals)[n // 2]:>9.1f}")
    print(f"answer pickled: median {sorted(i['pickle_bytes'] for i in items)[n // 2] / 1e3:.0f} kB")
    by = Counter(i["source"] for i in items)
    for src in by:
        sel = [i for i in items if i["source"] == src]
        print(f"  {src}: {len(sel)} items, {sum(i['task'] for i in sel):.1f} s of worker time, back-off rounds "
              f"{sum(i['backoff'] for i in sel)}; reasons {dict(Counter(i['reason'] for i in sel).most_common(3))}")
    slow = sorted(items, key=lambda i: -i["task"])[:5]
    print("slowest items [s]: " + ", ".join(f"{i['task']:.2f} ({i['source']})" for i in slow))


def dispatch_cost(n: int, keys: int = 12, seed: int = 7) -> float:
    """Event-loop time per item [ms] of :class:`service.dispatch.Dispatcher` pairing ``n`` calls queued at once
    (as ``batch --local`` queues them) with 2 workers that finish at once (no process, no solve)."""
    import asyncio

    from service.dispatch import Dispatcher

    rng = random.Random(seed)

    async def go() -> float:
        d: Dispatcher[str] = Dispatcher(["w1", "w2"])

        async def one(key: str) -> None:
            w = await d.get(key)
            await asyncio.sleep(0)
            d.remember(w, key)
            d.put(w)

        t0 = time.perf_counter()
        await asyncio.gather(*(one(f"k{rng.randrange(keys)}") for _ in range(n)))
        return 1e3 * (time.perf_counter() - t0) / n

    return asyncio.run(go())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--before", type=Path, default=None, help="a checkout of older code to run first, for comparison")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--builds", action="store_true",
                    help="instead: run the missions on the worker pool in this process with and without structure "
                         "affinity, and count the solver builds")
    ap.add_argument("--breakdown", action="store_true",
                    help="instead: the steps of a local batch timed apart in this process (parent validation and "
                         "keys, worker start-up, per-item worker time split into solve, verification, encoding, "
                         "pipe)")
    ap.add_argument("--dispatch", action="store_true",
                    help="instead: the dispatcher's cost per item with 100, 1,000 and 3,000 items queued")
    args = ap.parse_args(argv)
    if args.dispatch:
        sys.path.insert(0, str(ROOT))
        for n in (100, 1000, 3000):
            print(f"{n:>5} items queued: {dispatch_cost(n):.3f} ms of the event loop per item")
        return 0
    if args.breakdown:
        sys.path.insert(0, str(ROOT))
        print(f"load average before: {_load()}")
        print_breakdown(breakdown(missions(args.n, args.seed), args.workers), args.workers)
        print(f"load average after: {_load()}")
        return 0
    if args.builds:
        sys.path.insert(0, str(ROOT))
        payloads = missions(args.n, args.seed)
        print(f"{args.n} mixed missions on WorkerPool({args.workers}), worker start-up excluded")
        print(f"{'affinity':<9} {'wall s':>7} {'builds per worker':<18} load average before -> after")
        for affinity in (False, True):
            r = pool_run(payloads, args.workers, affinity)
            print(f"{'on' if affinity else 'off':<9} {r['wall_s']:>7.1f} {r['builds']!s:<18} "
                  f"{r['load_before']} -> {r['load_after']}")
        return 0
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "missions.json"
        path.write_text(json.dumps({"missions": missions(args.n, args.seed)}))
        for label, code in (("before", args.before), ("this tree", ROOT)):
            if code is not None:
                rows.append({"label": label, **run(code.resolve(), path, args.workers)})
    if args.json:
        print(json.dumps({"n": args.n, "workers": args.workers, "target_s": TARGET_S, "rows": rows}, indent=1))
        return 0
    print(f"{args.n} mixed missions, thrustshape batch --local --workers {args.workers}, cpus={os.cpu_count()}, "
          f"target <= {TARGET_S:g} s for 1,000 on 2 workers")
    print(f"{'code':<10} {'wall s':>7} {'items/s':>8} {'failed':>6}  sources; load average (1, 5, 15 min) "
          "before -> after")
    for r in rows:
        if "error" in r:
            print(f"{r['label']:<10} {r['wall_s']:>7.1f}  ERROR {r['error']}")
            continue
        met = "meets" if r["wall_s"] * 1000 / max(r["n"], 1) <= TARGET_S else "misses"
        print(f"{r['label']:<10} {r['wall_s']:>7.1f} {r['n'] / r['wall_s']:>8.1f} {r['failed']:>6}  {r['sources']}; "
              f"{r['load_before']} -> {r['load_after']}  ({met} the target)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
