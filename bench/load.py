"""Load benchmark of the HTTP service (loopback only, bounded, stops by itself).

Starts ``thrustshape serve`` on 127.0.0.1 with a temporary SQLite file, then for analytic and
optimise requests drives it with ``c = 1x`` and ``2x`` the worker count of concurrent clients (and
one overload round far past workers + queue) for a fixed number of requests each, and reports
throughput, p50/p95 latency and the status codes seen. At overload the only errors allowed are 503.

    python bench/load.py [--workers 2] [--requests 40] [--json]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[1]
ANALYTIC = {"amplitude": 0.5, "period": 2.0, "q": 2, "rate": 500}
OPTIMIZE = {"name": "bench", "collocation": {"intervals": 60}, "time_limit_s": 5.0,
            "segments": [{"kind": "hold", "duration": 0.2, "thrust": 0.3},
                         {"kind": "reversal", "duration": 1.0, "to": -0.3},
                         {"kind": "hold", "duration": 0.2, "thrust": -0.3}]}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _start(workers: int, queue: int, db: Path) -> tuple[subprocess.Popen[bytes], str]:
    port = _free_port()
    env = {**os.environ, "THRUSTSHAPE_QUEUE_SIZE": str(queue)}
    proc = subprocess.Popen([sys.executable, "-m", "clients.cli", "serve", "--port", str(port), "--workers",
                             str(workers), "--db", str(db), "--log-level", "warning"], cwd=ROOT, env=env)
    url = f"http://127.0.0.1:{port}"
    end = time.monotonic() + 120
    while time.monotonic() < end:
        with contextlib.suppress(httpx.TransportError):
            if httpx.get(url + "/healthz", timeout=1).status_code == 200:
                return proc, url
        time.sleep(0.2)
    proc.kill()
    raise SystemExit("server did not start")


async def _round(url: str, path: str, body: dict[str, Any], concurrency: int, total: int) -> dict[str, Any]:
    latencies: list[float] = []
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
                if "source" in r.json():
                    sources[r.json()["source"]] += 1

    limits = httpx.Limits(max_connections=concurrency + 2)
    t0 = time.perf_counter()
    async with httpx.AsyncClient(base_url=url, timeout=120, limits=limits) as http:
        await asyncio.gather(*(client(http) for _ in range(concurrency)))
    wall = time.perf_counter() - t0
    q = statistics.quantiles(latencies, n=20) if len(latencies) >= 2 else [float("nan")] * 19
    return {"concurrency": concurrency, "requests": total, "ok": codes[200], "wall_s": wall,
            "throughput_rps": codes[200] / wall, "p50_ms": 1e3 * statistics.median(latencies) if latencies else None,
            "p95_ms": 1e3 * q[18], "codes": dict(codes), "sources": dict(sources)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--requests", type=int, default=40, help="requests per round")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    queue = args.workers  # capacity = 2x workers: the 2x round fits, the overload round does not
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        proc, url = _start(args.workers, queue, Path(tmp) / "jobs.sqlite3")
        try:
            for kind, path, body in (("analytic", "/v1/references/analytic", ANALYTIC),
                                     ("optimize", "/v1/references/optimize", OPTIMIZE)):
                asyncio.run(_round(url, path, body, 1, 2))  # warm the workers' caches
                for mult in (1, 2, 4):
                    n = args.requests if mult < 4 else 2 * args.requests
                    row = asyncio.run(_round(url, path, body, mult * args.workers, n))
                    rows.append({"kind": kind, "load": f"{mult}x" if mult < 4 else "overload 4x", **row})
        finally:
            proc.terminate()
            proc.wait(30)
    bad = [r for r in rows if any(c >= 500 and c != 503 for c in r["codes"])
           or (not r["load"].startswith("overload") and set(r["codes"]) - {200})]
    if args.json:
        print(json.dumps({"workers": args.workers, "queue": queue, "rows": rows, "ok": not bad}, indent=1))
    else:
        print(f"workers={args.workers} queue={queue} cpus={os.cpu_count()}")
        print(f"{'kind':<9} {'load':<12} {'req/s':>7} {'p50 ms':>8} {'p95 ms':>8}  codes")
        for r in rows:
            print(f"{r['kind']:<9} {r['load']:<12} {r['throughput_rps']:>7.1f} {r['p50_ms'] or 0:>8.1f} "
                  f"{r['p95_ms']:>8.1f}  {r['codes']} {r['sources'] or ''}")
    if bad:
        print("FAIL: unexpected status codes", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
