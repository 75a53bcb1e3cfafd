"""Load benchmark of the HTTP service (loopback only, bounded, stops by itself).

Starts ``thrustshape serve`` on 127.0.0.1 with a temporary SQLite file, then for analytic and
optimise requests drives it with ``c = 1x`` and ``2x`` the worker count of concurrent clients (and
one overload round far past workers + queue) for a fixed number of requests each, and reports
throughput, p50/p95 latency and the status codes seen. At overload the only errors allowed are 503.

``--faults`` adds the issue #12 run: 2x overload of optimise requests (normal and adversarial missions:
hundreds of reversals, a 0.05 A limit) while a batch runs, with faults injected -- a worker process
SIGKILLed every few seconds and the database locked by another process past the store's busy timeout.
It passes when no answer is a 5xx, every 200 is within its limits (``verification`` peaks), every 422
is ``infeasible`` naming a limit, and every batch item finishes exactly once (none lost, none twice).

    python bench/load.py [--workers 2] [--requests 40] [--kinds analytic,optimize] [--before DIR] [--json]
    python bench/load.py --faults [--fault-seconds 60] [--factor 2]

``--before DIR`` runs the same rounds first against a server of the code in ``DIR`` (e.g. ``git archive
<commit> | tar -x -C DIR``), for before/after rows in one table; the load average is printed beside each row.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import random
import re
import signal
import socket
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[1]
ANALYTIC = {"amplitude": 0.5, "period": 2.0, "q": 2, "rate": 500}
OPTIMIZE: dict[str, Any] = {"name": "bench", "collocation": {"intervals": 60}, "time_limit_s": 5.0,
                            "segments": [{"kind": "hold", "duration": 0.2, "thrust": 0.3},
                                         {"kind": "reversal", "duration": 1.0, "to": -0.3},
                                         {"kind": "hold", "duration": 0.2, "thrust": -0.3}]}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _start(workers: int, queue: int, db: Path, code: Path = ROOT, **extra: str) -> tuple[subprocess.Popen[bytes], str]:
    """``thrustshape serve`` of the code in ``code`` (default this tree)."""
    port = _free_port()
    env = {**os.environ, "THRUSTSHAPE_QUEUE_SIZE": str(queue), "PYTHONPATH": str(code), **extra}
    proc = subprocess.Popen([sys.executable, "-m", "clients.cli", "serve", "--port", str(port), "--workers",
                             str(workers), "--db", str(db), "--log-level", "warning"], cwd=code, env=env)
    url = f"http://127.0.0.1:{port}"
    end = time.monotonic() + 120
    while time.monotonic() < end:
        with contextlib.suppress(httpx.TransportError):
            if httpx.get(url + "/healthz", timeout=1).status_code == 200:
                return proc, url
        time.sleep(0.2)
    proc.kill()
    raise SystemExit("server did not start")


_SOURCE = re.compile(rb'"source":\s*"([a-z-]+)"')


_TIMES = {k: re.compile(rb'"' + k.encode() + rb'":\s*([0-9.eE+-]+)') for k in ("total_time_s", "solve_time_s",
                                                                               "verify_time_s", "build_time_s")}


def _times(body: bytes) -> dict[str, float]:
    """The answer's own timing (``total_time_s``, the solver's IPOPT, verification and build times) from its
    head, without decoding the whole answer."""
    head = body[:1500]
    return {k: float(m.group(1)) for k, rx in _TIMES.items() if (m := rx.search(head))}


def _source(body: bytes) -> str | None:
    """The answer's ``source`` from the head of its JSON (the client's CPU is the server's on a small machine:
    no 200 kB decode per answer)."""
    m = _SOURCE.search(body[:400])
    return m.group(1).decode() if m else None


def _proc_stat(pid: int) -> tuple[float, int]:
    """CPU seconds (user + system) a process used so far, and its nice value (Linux ``/proc``)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK"), int(fields[16])


def _cpu(server: int | None) -> dict[str, float]:
    """CPU seconds so far of this client process, the server process and its worker processes (solver workers
    run niced, ``SOLVER_NICENESS``; the fallback workers do not), for a per-request CPU breakdown."""
    out = {"client": time.process_time(), "server": 0.0, "solver workers": 0.0, "fallback workers": 0.0}
    if server is None or not Path(f"/proc/{server}").exists():
        return out
    out["server"] = _proc_stat(server)[0]
    for pid in _workers(server):
        with contextlib.suppress(OSError):
            cpu, nice = _proc_stat(pid)
            out["solver workers" if nice > _proc_stat(server)[1] else "fallback workers"] += cpu
    return out


async def _round(url: str, path: str, body: dict[str, Any], concurrency: int, total: int,
                 server: int | None = None) -> dict[str, Any]:
    """``total`` requests from ``concurrency`` clients; with the ``server`` pid, the CPU each process spent per
    answered request [ms] (client, server, solver and fallback workers)."""
    cpu0 = _cpu(server)
    latencies: list[float] = []
    times: list[dict[str, float]] = []
    codes: Counter[int] = Counter()
    sources: Counter[str] = Counter()
    todo = iter(range(total))

    async def client(http: httpx.AsyncClient) -> None:
        for _ in todo:
            t0 = time.perf_counter()
            r = await http.post(path, json=body)
            codes[r.status_code] += 1
            if r.status_code == 200:
                latencies.append(time.perf_counter() - t0)
                if (source := _source(r.content)) is not None:
                    sources[source] += 1
                times.append({**_times(r.content), "latency": latencies[-1]})

    limits = httpx.Limits(max_connections=concurrency + 2)
    t0 = time.perf_counter()
    async with httpx.AsyncClient(base_url=url, timeout=120, limits=limits) as http:
        await asyncio.gather(*(client(http) for _ in range(concurrency)))
    wall = time.perf_counter() - t0
    cpu1 = _cpu(server)
    cpu_ms = {k: 1e3 * (cpu1[k] - cpu0[k]) / max(codes[200], 1) for k in cpu0}
    q = statistics.quantiles(latencies, n=20) if len(latencies) >= 2 else [float("nan")] * 19
    return {"concurrency": concurrency, "requests": total, "ok": codes[200], "wall_s": wall,
            "throughput_rps": codes[200] / wall, "p50_ms": 1e3 * statistics.median(latencies) if latencies else None,
            "p95_ms": 1e3 * q[18], "codes": dict(codes), "sources": dict(sources), "cpu_ms_per_ok": cpu_ms,
            "wall_ms": _wall_split(times)}


def _wall_split(times: list[dict[str, float]]) -> dict[str, float]:
    """Medians [ms] of the answers' latency split: IPOPT, verification, the rest of the worker's ``optimize``
    (setup, builds, evaluation, packaging), and everything around it (queue wait, the task's validation and
    rendering, the pipe, the server, HTTP, this client)."""
    rows = [t for t in times if "total_time_s" in t]
    if not rows:
        return {}
    parts = {"ipopt": [t.get("solve_time_s", 0.0) for t in rows], "verify": [t.get("verify_time_s", 0.0) for t in rows],
             "rest of optimize": [t["total_time_s"] - t.get("solve_time_s", 0.0) - t.get("verify_time_s", 0.0)
                                  for t in rows],
             "around the solve": [t["latency"] - t["total_time_s"] for t in rows]}
    return {k: 1e3 * statistics.median(v) for k, v in parts.items()}


# ---------------------------------------------------------------------------------------------
# 2x overload with faults (issue #12)

LIMIT_TOL = 1.0 + 1e-3  # ocp.optimize.verify.PATH_TOLERANCE
ADVERSARIAL = [
    {**OPTIMIZE, "name": "tiny-current", "limits": {"current": 0.05}},
    {**OPTIMIZE, "name": "60-reversals", "time_limit_s": 2.0,
     "segments": [{"kind": "sine", "duration": 6.0, "amplitude": 0.6, "period": 0.2}]},
    {**OPTIMIZE, "name": "fast-sine-1A", "time_limit_s": 2.0, "limits": {"voltage": 12.0, "current": 1.0},
     "segments": [{"kind": "sine", "duration": 4.0, "amplitude": 0.5, "period": 0.2}]},
]


def _workers(pid: int) -> list[int]:
    """Worker processes of the server ``pid`` (spawned children; not multiprocessing's resource tracker)."""
    kids = [int(c) for task in Path(f"/proc/{pid}/task").iterdir() for c in (task / "children").read_text().split()]
    out = []
    for k in kids:
        with contextlib.suppress(OSError):
            if b"spawn_main" in Path(f"/proc/{k}/cmdline").read_bytes():
                out.append(k)
    return out


def _inject(server_pid: int, db: Path, stop: threading.Event, log: list[str]) -> None:
    """Every 8 s SIGKILL one worker process (solver or fallback); every 7 s hold the database for 2 s (past the
    store's busy timeout)."""
    rng, tick = random.Random(12), 0
    while not stop.wait(1.0):
        tick += 1
        if tick % 8 == 0 and (kids := _workers(server_pid)):
            victim = rng.choice(kids)
            with contextlib.suppress(ProcessLookupError):
                os.kill(victim, signal.SIGKILL)
                log.append(f"kill {victim}")
        if tick % 7 == 0:
            conn = sqlite3.connect(db, isolation_level=None)
            conn.execute("BEGIN EXCLUSIVE")
            log.append("lock db")
            stop.wait(2.0)
            conn.execute("ROLLBACK")
            conn.close()


def _over_limits(body: dict[str, Any], mission: dict[str, Any]) -> bool:
    lim = {"voltage": 12.0, "current": 2.0, **mission.get("limits", {})}
    v = body["verification"]
    return not (v["path_ok"] and v["max_abs_current"] <= lim["current"] * LIMIT_TOL
                and v["max_abs_voltage"] <= lim["voltage"] * LIMIT_TOL)


async def _fault_clients(url: str, concurrency: int, seconds: float) -> dict[str, Any]:
    late: list[float] = []  # seconds past each answer's own deadline (min(30, time_limit_s + 5))
    codes: Counter[int] = Counter()
    sources: Counter[str] = Counter()
    bad: list[str] = []
    details: list[str] = []
    end = time.monotonic() + seconds
    missions = [OPTIMIZE, *ADVERSARIAL]

    async def client(http: httpx.AsyncClient, k: int) -> None:
        n = k
        while time.monotonic() < end:
            m = missions[n % len(missions)]
            n += 1
            t0 = time.monotonic()
            r = await http.post("/v1/references/optimize", json=m)
            late.append(time.monotonic() - t0 - min(30.0, float(m["time_limit_s"]) + 5.0))
            codes[r.status_code] += 1
            if r.status_code == 200:
                sources[r.json()["source"]] += 1
                if _over_limits(r.json(), m):
                    bad.append(f"{m['name']}: over its limits")
            elif r.status_code == 422 and r.json().get("code") != "infeasible":
                bad.append(f"{m['name']}: 422 {r.json().get('field')}")
            elif r.status_code >= 500 and len(details) < 3:
                details.append(f"{r.status_code} {m['name']}: {r.json().get('detail')}")

    async with httpx.AsyncClient(base_url=url, timeout=120) as http:
        await asyncio.gather(*(client(http, k) for k in range(concurrency)))
    return {"codes": dict(codes), "sources": dict(sources), "bad": bad, "5xx_examples": details,
            "max_past_deadline_s": max(late, default=0.0)}


def _batch_check(url: str, batch: str, missions: list[dict[str, Any]]) -> list[str]:
    """Wait for the batch; every item finished once, in order, within its limits."""
    end = time.monotonic() + 600
    with httpx.Client(base_url=url, timeout=60) as http:
        while time.monotonic() < end:
            with contextlib.suppress(httpx.HTTPError):
                if http.get(f"/v1/batches/{batch}").json()["status"] in ("done", "failed"):
                    break
            time.sleep(0.5)
        items = http.get(f"/v1/batches/{batch}/results").json()["results"]
    problems = [] if [it["index"] for it in items] == list(range(len(missions))) else ["items lost or duplicated"]
    for it, m in zip(items, missions, strict=False):
        if it["status"] == "done" and _over_limits(it["result"], m):
            problems.append(f"batch item {it['index']} over its limits")
        elif it["status"] not in ("done", "failed"):
            problems.append(f"batch item {it['index']} never finished ({it['status']})")
    return problems


def run_faults(workers: int, seconds: float, as_json: bool, factor: int = 2) -> int:
    """``factor`` x overload of optimise requests plus a batch, with worker kills and database locks; see the
    doc. The server runs with its default queue and fallback settings."""
    concurrency = factor * workers
    # batch items: the normal mission and the 0.05 A one (a many-reversal build takes minutes under load)
    missions = [{**(ADVERSARIAL[0] if i % 4 == 0 else OPTIMIZE), "name": f"item-{i}"} for i in range(24)]
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "jobs.sqlite3"
        proc, url = _start(workers, 8, db, THRUSTSHAPE_STORE_BUSY_TIMEOUT_S="0.5")  # 8: the default queue
        stop = threading.Event()
        log: list[str] = []  # the faults injected
        try:
            asyncio.run(_round(url, "/v1/references/optimize", OPTIMIZE, 1, 2))  # warm the solver caches
            batch = httpx.post(url + "/v1/batches", json={"missions": missions}, timeout=60).json()["id"]
            injector = threading.Thread(target=_inject, args=(proc.pid, db, stop, log), daemon=True)
            injector.start()
            t0 = time.perf_counter()
            out = asyncio.run(_fault_clients(url, concurrency, seconds))
            stop.set()
            injector.join(10)
            out["batch_problems"] = _batch_check(url, batch, missions)
            out["wall_s"] = time.perf_counter() - t0
        finally:
            stop.set()
            proc.terminate()
            proc.wait(30)
    fives = sum(n for c, n in out["codes"].items() if c >= 500)
    ok = not fives and not out["bad"] and not out["batch_problems"]
    summary = {"workers": workers, "concurrency": concurrency, "seconds": seconds, "faults": Counter(
        f.split()[0] for f in log), **out, "ok": ok}
    if as_json:
        print(json.dumps(summary, indent=1))
    else:
        print(f"{factor}x overload with faults: workers={workers} clients={concurrency} {seconds:g} s, "
              f"faults {dict(summary['faults'])}")
        print(f"  optimise answers {out['codes']} sources {out['sources']}; slowest answer "
              f"{out['max_past_deadline_s']:+.2f} s from its deadline")
        print(f"  5xx: {fives}  over limits / unexpected 422: {len(out['bad'])}  batch problems: "
              f"{out['batch_problems'] or 'none'} (24 items)")
        for d in out["5xx_examples"]:
            print(f"  e.g. {d}")
        print("PASS" if ok else f"FAIL {out['bad'][:5]}")
    return 0 if ok else 1


def _rounds(code: Path, label: str, workers: int, queue: int, requests: int,
            kinds: list[tuple[str, str, dict[str, Any]]]) -> list[dict[str, Any]]:
    """1x, 2x and overload rounds of each kind against a fresh server of the code in ``code``."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        proc, url = _start(workers, queue, Path(tmp) / "jobs.sqlite3", code)
        try:
            for kind, path, body in kinds:
                asyncio.run(_round(url, path, body, workers, 2 * workers))  # warm every worker's cache
                for mult in (1, 2, 4):
                    n = requests if mult < 4 else 2 * requests
                    row = asyncio.run(_round(url, path, body, mult * workers, n, proc.pid))
                    rows.append({"code": label or "this", "kind": kind,
                                 "load": f"{mult}x" if mult < 4 else "overload 4x",
                                 "loadavg": " ".join(f"{x:.1f}" for x in os.getloadavg()), **row})
        finally:
            proc.terminate()
            proc.wait(30)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--requests", type=int, default=40, help="requests per round")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--faults", action="store_true", help="only the 2x overload run with injected faults")
    ap.add_argument("--fault-seconds", type=float, default=60.0, help="length of the fault run [s]")
    ap.add_argument("--factor", type=int, default=2, help="fault run: concurrent clients per solver worker")
    ap.add_argument("--kinds", default="analytic,optimize", help="request kinds to run (comma-separated)")
    ap.add_argument("--before", type=Path, default=None,
                    help="a checkout of older code: its server runs the same rounds first, for a side-by-side table")
    args = ap.parse_args(argv)
    if args.faults:
        return run_faults(args.workers, args.fault_seconds, args.json, args.factor)
    queue = args.workers  # capacity = 2x workers: the 2x round fits, the overload round does not
    rows: list[dict[str, Any]] = []
    kinds = [k for k in (("analytic", "/v1/references/analytic", ANALYTIC),
                         ("optimize", "/v1/references/optimize", OPTIMIZE)) if k[0] in args.kinds.split(",")]
    for label, code in (("before", args.before), ("", ROOT)):
        if code is not None:
            rows += _rounds(code.resolve(), label, args.workers, queue, args.requests, kinds)
    bad = [r for r in rows if any(c >= 500 and c != 503 for c in r["codes"])
           or (not r["load"].startswith("overload") and set(r["codes"]) - {200})]
    if args.json:
        print(json.dumps({"workers": args.workers, "queue": queue, "rows": rows, "ok": not bad}, indent=1))
    else:
        print(f"workers={args.workers} queue={queue} cpus={os.cpu_count()}")
        print(f"{'code':<7} {'kind':<9} {'load':<12} {'req/s':>7} {'p50 ms':>8} {'p95 ms':>8}  codes; load average")
        for r in rows:
            print(f"{r['code']:<7} {r['kind']:<9} {r['load']:<12} {r['throughput_rps']:>7.1f} {r['p50_ms'] or 0:>8.1f} "
                  f"{r['p95_ms']:>8.1f}  {r['codes']} {r['sources'] or ''}; {r['loadavg']}")
        print("CPU per answered request [ms] (user + system, /proc; 2 cores give 2,000 ms per second of wall):")
        print(f"{'code':<7} {'kind':<9} {'load':<12} " + " ".join(f"{k:>16}" for k in rows[0]["cpu_ms_per_ok"]))
        for r in rows:
            print(f"{r['code']:<7} {r['kind']:<9} {r['load']:<12} "
                  + " ".join(f"{v:>16.1f}" for v in r["cpu_ms_per_ok"].values()))
        split = [r for r in rows if r["wall_ms"]]
        if split:
            print("Latency split, medians [ms] (from the answers' own times; 'around' = queue wait, pipe, server, "
                  "HTTP, client):")
            print(f"{'code':<7} {'kind':<9} {'load':<12} " + " ".join(f"{k:>17}" for k in split[0]["wall_ms"]))
            for r in split:
                print(f"{r['code']:<7} {r['kind']:<9} {r['load']:<12} "
                      + " ".join(f"{v:>17.1f}" for v in r["wall_ms"].values()))
    if bad:
        print("FAIL: unexpected status codes", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
