"""Service commands: ``serve`` (run the HTTP service) and ``batch`` (optimise many missions).

``thrustshape batch`` talks to a server over HTTP (``--server URL``, through :class:`clients.Client`)
or runs the core locally (default, ``--local``) on the service's worker pool or a Dask cluster. Either way it
shows a progress bar on stderr, prints a summary table and, with ``--out DIR``, writes one JSON
result per mission plus ``summary.csv``.
"""

from __future__ import annotations

import argparse
import asyncio
import csv
import json
import os
import re
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from clients.cli.help import STDIO, add_command, require_extra
from clients.cli.io import print_json
from ocp.errors import MissionError, ThrustshapeError

if TYPE_CHECKING:
    from ocp.optimize.mission import Mission

#: what the local worker processes import once at start-up
LOCAL_PRELOAD = ("ocp.optimize.mission", "ocp.optimize.solve", "service.tasks")
SUMMARY_COLUMNS = ("index", "name", "status", "source", "solve_time_s", "thrust_rms_error", "max_abs_current",
                   "max_abs_voltage", "error")


def register(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "serve", summary="run the HTTP service (FastAPI + uvicorn; docs at /docs)",
                    description="Options become THRUSTSHAPE_* settings (see service/settings.py for the rest: "
                                "API_KEY,\nQUEUE_SIZE, MAX_* limits, timeouts). The web page is at /, the "
                                "OpenAPI document at /openapi.json.",
                    examples=["thrustshape serve --port 8000 --workers 2",
                              "THRUSTSHAPE_API_KEY=secret thrustshape serve --db /var/lib/thrustshape/jobs.sqlite3"])
    p.add_argument("--host", default=None, help="bind address (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=None, help="port (default 8000)")
    p.add_argument("--workers", type=int, default=None, help="solver worker processes (default 2)")
    p.add_argument("--db", default=None, help="SQLite job store (default ./thrustshape-data/jobs.sqlite3)")
    p.add_argument("--dask", default=None, metavar="ADDR", help="run batch items on a Dask scheduler tcp://HOST:PORT")
    p.add_argument("--log-level", choices=("critical", "error", "warning", "info", "debug"), default="info")
    p.set_defaults(func=cmd_serve)

    p = add_command(sub, "batch", summary="optimise every mission of a file or directory, locally or on a server",
                    description="Every .json/.yaml/.yml file of a directory (or one file holding a mission, a "
                                "list, or\n{missions: [...]}); a progress bar on stderr, a summary table on "
                                "stdout, and with --out DIR\none <index>-<name>.json per mission plus "
                                "summary.csv.",
                    examples=["thrustshape batch examples/missions --out results",
                              "thrustshape batch examples/missions --server http://127.0.0.1:8000 --json"])
    p.add_argument("missions", help="mission file (JSON/YAML: one mission, a list, or {missions: [...]}), directory, "
                                    "or '-' (stdin)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--server", default=None, metavar="URL", help="submit to a thrustshape server")
    where.add_argument("--local", action="store_true", help="run here (the default)")
    how = p.add_mutually_exclusive_group()
    how.add_argument("--workers", type=int, default=None, help="local worker processes (default 2)")
    how.add_argument("--dask", default=None, metavar="ADDR", help="local run on a Dask scheduler tcp://HOST:PORT")
    p.add_argument("--out", default=None, metavar="DIR", help="write <index>-<name>.json per mission and summary.csv")
    p.add_argument("--api-key", default=os.environ.get("THRUSTSHAPE_API_KEY"), help="bearer token for --server")
    p.add_argument("--idempotency-key", default=None, help="with --server: resubmitting returns the same batch")
    p.add_argument("--timeout", type=float, default=None, help="give up waiting after this many seconds")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=cmd_batch)


# -- serve ------------------------------------------------------------------------------------------


def cmd_serve(args: argparse.Namespace) -> int:
    """Options become THRUSTSHAPE_* settings; uvicorn imports the app factory by name (HTTP boundary kept)."""
    import uvicorn

    if args.dask or os.environ.get("THRUSTSHAPE_DASK_ADDRESS"):
        require_extra("distributed", "dask", "--dask")
    overrides = {"HOST": args.host, "PORT": args.port, "WORKERS": args.workers, "DB_PATH": args.db,
                 "DASK_ADDRESS": args.dask}
    for key, value in overrides.items():
        if value is not None:
            os.environ[f"THRUSTSHAPE_{key}"] = str(value)
    host = os.environ.get("THRUSTSHAPE_HOST", "127.0.0.1")
    port = int(os.environ.get("THRUSTSHAPE_PORT", "8000"))
    from service.api.logging import log_config

    uvicorn.run("service.app:app_from_env", factory=True, host=host, port=port, log_level=args.log_level,
                log_config=log_config(args.log_level))
    return 0


# -- batch ------------------------------------------------------------------------------------------


def _documents(path: Path) -> Iterator[tuple[str, Any]]:
    import yaml

    if str(path) == STDIO:  # one JSON/YAML document on stdin (JSON is YAML)
        try:
            data = yaml.safe_load(sys.stdin.read())
        except yaml.YAMLError as exc:
            raise MissionError("stdin", f"not valid JSON/YAML: {exc}") from None
        data = data["missions"] if isinstance(data, dict) and "missions" in data else data
        for i, item in enumerate(data if isinstance(data, list) else [data]):
            yield (f"stdin[{i}]" if isinstance(data, list) else "stdin"), item
        return
    files = sorted(f for f in path.iterdir() if f.suffix.lower() in (".json", ".yaml", ".yml")) if path.is_dir() \
        else [path]
    if not files:
        raise MissionError(str(path), "no .json/.yaml/.yml mission files")
    for f in files:
        if not f.is_file():
            raise MissionError(str(f), "no such file")
        text = f.read_text(encoding="utf-8")
        try:
            data = json.loads(text) if f.suffix.lower() == ".json" else yaml.safe_load(text)
        except (json.JSONDecodeError, yaml.YAMLError) as exc:
            raise MissionError(f.name, f"not valid JSON/YAML: {exc}") from None
        if isinstance(data, dict) and "missions" in data:
            data = data["missions"]
        for i, item in enumerate(data if isinstance(data, list) else [data]):
            yield (f"{f.name}[{i}]" if isinstance(data, list) else f.name), item


def load_missions(path: str | Path) -> list[Mission]:
    """Every mission under ``path``, validated; errors name the file and the field."""
    from ocp.optimize.mission import mission_from_mapping

    out: list[Mission] = []
    for where, item in _documents(Path(path)):
        try:
            out.append(mission_from_mapping(item))
        except ThrustshapeError as exc:
            raise MissionError(f"{where}: {exc.field}", exc.reason) from None
    return out


class Progress:
    """Progress on stderr: on a terminal ``[#####-----] 5/10 done=5 failed=0 2.10/s ETA 2 s`` redrawn in
    place; elsewhere (a log file, CI) one plain line each time an item finishes, never a carriage return."""

    def __init__(self, total: int, width: int = 30, stream: Any = None) -> None:
        self.total, self.width, self._last = total, width, ""
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._t0 = time.monotonic()

    def line(self, done: int, failed: int) -> str:
        finished = done + failed
        filled = self.width * finished // max(self.total, 1)
        elapsed = max(time.monotonic() - self._t0, 1e-9)
        rate = finished / elapsed
        if 0 < finished < self.total:
            eta = f"ETA {(self.total - finished) / rate:.0f} s"
        else:
            eta = f"in {elapsed:.1f} s" if finished else "ETA -"
        return (f"[{'#' * filled}{'-' * (self.width - filled)}] {finished}/{self.total} done={done} failed={failed} "
                f"{rate:.2f}/s {eta}")

    def __call__(self, done: int, failed: int) -> None:
        key = f"{done}/{failed}"
        if key == self._last:
            return
        self._last = key
        text = self.line(done, failed)
        self.stream.write("\r" + text if self.tty else text + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.tty:
            self.stream.write("\n")


def _run_local(missions: list[Mission], workers: int, dask: str | None,
               progress: Callable[[int, int], None]) -> list[dict[str, Any]]:
    """Run the missions on the service's worker pool (:class:`service.workers.WorkerPool`, items of one solver
    structure on the worker that built it) or, with ``dask``, on a Dask cluster (:class:`DaskRunner`); the task
    is the service's batch item (:func:`service.tasks.optimize_mission`). A local parameter file is read here and
    sent as its mapping, as to a server."""
    from clients.cli.remote import params_for_server

    payloads = [{**m.model_dump(mode="json"), "params": params_for_server(m.params)} for m in missions]
    if dask:
        require_extra("distributed", "dask", "--dask")
    outcomes = asyncio.run(_run_items(payloads, workers, dask, progress))
    return [_item(i, m.name, o or {"error": {"type": "Missing", "reason": "no outcome"}})
            for i, (m, o) in enumerate(zip(missions, outcomes, strict=True))]


async def _run_items(payloads: list[dict[str, Any]], workers: int, dask: str | None,
                     progress: Callable[[int, int], None]) -> list[dict[str, Any] | None]:
    from service.dask_runner import DaskRunner
    from service.tasks import optimize_mission, structure_key
    from service.workers import Runner, WorkerPool

    pool = None if dask else WorkerPool(workers, 0, 1, preload=LOCAL_PRELOAD)
    runner: Runner = pool if pool is not None else await DaskRunner.connect(str(dask))
    outcomes: list[dict[str, Any] | None] = [None] * len(payloads)
    try:
        keys = [_key(structure_key, p) for p in payloads] if pool is not None else [None] * len(payloads)
        # the worker processes import the core meanwhile

        async def one(i: int) -> None:
            outcomes[i] = await _outcome(runner, optimize_mission, payloads[i], keys[i])
            progress(*_tally(outcomes))

        await asyncio.gather(*(one(i) for i in range(len(payloads))))
    finally:
        if pool is not None:
            pool.close()
        else:
            await cast(DaskRunner, runner).close()
    return outcomes


def _key(key: Callable[[dict[str, Any]], Any], payload: dict[str, Any]) -> Any:
    try:
        return key(payload)
    except ThrustshapeError:  # validated already; the worker reports it with the item
        return None


async def _outcome(runner: Any, task: Callable[[dict[str, Any]], dict[str, Any]], payload: dict[str, Any],
                   key: Any) -> dict[str, Any]:
    """``{"result": ...}`` or ``{"error": {type, field, reason}}`` of one item (never raises for the item)."""
    from service.errors import TaskFailed, TaskTimeout
    from service.settings import Settings

    timeout = float(Settings.model_fields["batch_item_timeout_s"].default)  # as the service's batch items
    try:
        return {"result": await runner.run(task, payload, timeout, wait=True, affinity=key)}
    except ThrustshapeError as exc:
        return {"error": {"type": type(exc).__name__, "field": exc.field, "reason": exc.reason}}
    except (TaskTimeout, TaskFailed) as exc:
        return {"error": {"type": type(exc).__name__, "field": None, "reason": str(exc)}}


def _tally(outcomes: list[dict[str, Any] | None]) -> tuple[int, int]:
    done = sum(1 for o in outcomes if o is not None and "result" in o)
    return done, sum(1 for o in outcomes if o is not None and "error" in o)


def _item(index: int, name: str, outcome: dict[str, Any]) -> dict[str, Any]:
    ok = "result" in outcome
    return {"index": index, "name": name, "status": "done" if ok else "failed",
            "result": outcome.get("result"), "error": outcome.get("error")}


def _run_server(missions: list[Mission], args: argparse.Namespace,
                progress: Callable[[int, int], None]) -> list[dict[str, Any]]:
    from clients.client import Client

    with Client(args.server, api_key=args.api_key) as client:
        accepted = client.submit_batch(missions, idempotency_key=args.idempotency_key)
        client.wait_batch(accepted["id"], poll=0.5, timeout=args.timeout,
                          on_progress=lambda s: progress(s["counts"]["done"], s["counts"]["failed"]))
        return list(client.batch_results(accepted["id"])["results"])


def _summary_row(item: dict[str, Any]) -> dict[str, Any]:
    res = item.get("result") or {}
    ver = res.get("verification") or {}
    err = item.get("error") or {}
    return {"index": item["index"], "name": item["name"], "status": item["status"], "source": res.get("source", ""),
            "solve_time_s": res.get("solve_time_s", ""), "thrust_rms_error": ver.get("thrust_rms_error", ""),
            "max_abs_current": ver.get("max_abs_current", ""), "max_abs_voltage": ver.get("max_abs_voltage", ""),
            "error": f"{err.get('field') or ''}: {err.get('reason', '')}" if err else ""}


def _fmt(v: Any) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _write_out(out: Path, items: list[dict[str, Any]], rows: list[dict[str, Any]]) -> None:
    """One JSON file per item (rendered by ``pydantic_core``: 16,000 numbers in about 1 ms, ``json.dumps`` takes
    about 10; the core spelled every non-finite number already) and ``summary.csv``."""
    import pydantic_core

    out.mkdir(parents=True, exist_ok=True)
    for it in items:
        safe = re.sub(r"[^A-Za-z0-9._-]+", "_", it["name"])[:80]
        (out / f"{it['index']:04d}-{safe}.json").write_bytes(pydantic_core.to_json(it) + b"\n")
    with (out / "summary.csv").open("w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=SUMMARY_COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def cmd_batch(args: argparse.Namespace) -> int:
    missions = load_missions(args.missions)
    if args.server and (args.workers is not None or args.dask):
        raise MissionError("--workers/--dask", "apply to local runs; the server chooses its own workers")
    if args.workers is not None and args.workers < 1:
        raise MissionError("--workers", "must be >= 1")
    bar = Progress(len(missions))
    t0 = time.monotonic()
    try:
        items = (_run_server(missions, args, bar) if args.server
                 else _run_local(missions, args.workers or 2, args.dask, bar))
    finally:
        bar.close()
    rows = [_summary_row(it) for it in items]
    if args.out:
        _write_out(Path(args.out), items, rows)
    failed = sum(r["status"] != "done" for r in rows)
    if args.json:
        print_json({"summary": rows, "failed": failed, "elapsed_s": time.monotonic() - t0})
    else:
        widths = {c: max(len(c), *(len(_fmt(r[c])) for r in rows)) for c in SUMMARY_COLUMNS}
        print("  ".join(c.ljust(widths[c]) for c in SUMMARY_COLUMNS).rstrip())
        for r in rows:
            print("  ".join(_fmt(r[c]).ljust(widths[c]) for c in SUMMARY_COLUMNS).rstrip())
        print(f"{len(rows) - failed} done, {failed} failed in {time.monotonic() - t0:.1f} s")
    return 1 if failed else 0
