"""Service settings, read from the environment (prefix ``THRUSTSHAPE_``) or passed to ``create_app``.

Nothing here is built at import: :class:`Settings` is instantiated by whoever starts the service
(``thrustshape serve``, a test, uvicorn's ``--factory``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import Field, SecretStr, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

DEFAULT_DB = Path("thrustshape-data") / "jobs.sqlite3"


class Settings(BaseSettings):
    """Typed service configuration; every field maps to ``THRUSTSHAPE_<NAME>`` (e.g. ``THRUSTSHAPE_WORKERS``)."""

    model_config = SettingsConfigDict(env_prefix="THRUSTSHAPE_", extra="forbid", frozen=True)

    host: str = "127.0.0.1"
    port: Annotated[int, Field(ge=0, le=65535)] = 8000
    #: local solver processes (each keeps its own solver cache)
    workers: Annotated[int, Field(ge=1, le=256)] = 2
    #: processes for the analytic fallback of /v1/references/optimize (no IPOPT; they keep the fallback
    #: off the solver queue and out of the server process)
    fallback_workers: Annotated[int, Field(ge=1, le=64)] = 2
    #: added to the solver processes' nice value: under overload the short, deadline-bound fallbacks and the
    #: server's event loop get the CPU before the long solves
    solver_niceness: Annotated[int, Field(ge=0, le=19)] = 5
    #: requests allowed to wait for a busy worker before new ones get 503 + Retry-After
    queue_size: Annotated[int, Field(ge=0, le=10_000)] = 8
    #: SQLite job store (WAL); created with its directory on start; ``<db_path>.lock`` keeps a second
    #: server off the same database
    db_path: Path = DEFAULT_DB
    #: how long a job-store write waits for another connection's lock before it counts as a store error [s]
    store_busy_timeout_s: Annotated[float, Field(gt=0, le=600)] = 10.0
    #: ``tcp://HOST:PORT`` of a Dask scheduler: batch items run there instead of on local workers
    dask_address: str | None = None
    #: threads a model check runs its independent pieces in, in its worker (:mod:`ocp.parallel`, which reads
    #: ``THRUSTSHAPE_THREADS`` itself; declared here so that a bad value stops the server at start, not every check)
    threads: Annotated[int, Field(ge=1, le=256)] | None = None
    #: data memory each worker process may map [MiB] (RLIMIT_DATA: reserved address space, ~1.7x the resident peak;
    #: an idle worker maps ~220 MiB); a request that needs more is answered 422 naming this setting, its worker going
    #: on. None: no cap (a worker that runs the machine out of memory is the kernel's first choice to kill)
    worker_memory_mb: Annotated[int, Field(ge=1024, le=1 << 30)] | None = None
    #: bearer token; when set every route except ``/healthz`` requires ``Authorization: Bearer <key>``
    api_key: SecretStr | None = None

    # limits
    max_body_bytes: Annotated[int, Field(ge=1024)] = 8 * 1024 * 1024
    max_profile_samples: Annotated[int, Field(ge=2, le=100_000)] = 20_000
    max_intervals: Annotated[int, Field(ge=8, le=2_000)] = 1_000
    max_batch_missions: Annotated[int, Field(ge=1, le=100_000)] = 1_000
    max_reference_samples: Annotated[int, Field(ge=2, le=2_000_001)] = 200_001
    #: size of a model-check log upload (CSV/Parquet) [bytes]; replaces max_body_bytes on /v1/model-check/*
    max_upload_bytes: Annotated[int, Field(ge=1024)] = 32 * 1024 * 1024
    #: rows of a model-check log
    max_log_samples: Annotated[int, Field(ge=50, le=10_000_000)] = 500_000

    # time
    #: hard wall-clock deadline of a synchronous optimisation [s]; the mission's time_limit_s may shorten it
    optimize_deadline_s: Annotated[float, Field(gt=0, le=600)] = 30.0
    #: added to a mission's time_limit_s for building and verifying the solution [s]
    optimize_grace_s: Annotated[float, Field(ge=0, le=600)] = 5.0
    #: share of the deadline kept for the analytic fallback when the solver overruns [s]
    fallback_reserve_s: Annotated[float, Field(gt=0, le=60)] = 2.0
    #: how long a solver worker may go on building a new solver after the request that asked for it was
    #: answered by the fallback (its deadline ran out during the build); the built solver is cached for the
    #: next request. Past this the worker is killed [s]
    solver_build_limit_s: Annotated[float, Field(ge=0, le=600)] = 60.0
    #: hard timeout of any other worker task (analytic, compare, model check) [s]
    task_timeout_s: Annotated[float, Field(gt=0, le=3600)] = 60.0
    #: hard timeout of one batch item [s]; the item is retried up to ``batch_attempts`` times
    batch_item_timeout_s: Annotated[float, Field(gt=0, le=3600)] = 300.0
    batch_attempts: Annotated[int, Field(ge=1, le=10)] = 2
    #: batch items claimed beyond ``workers``: they wait in the pool so that a worker coming free can take one of
    #: the solver structure it already built (claimed items count as ``running``)
    batch_lookahead: Annotated[int, Field(ge=0, le=10_000)] = 4
    #: how long a finished batch item's outcome may wait for others to share its SQLite transaction [s]
    batch_write_group_s: Annotated[float, Field(ge=0, le=10)] = 0.05
    #: Retry-After [s] sent with 503 when the queue is full
    retry_after_s: Annotated[int, Field(ge=1, le=3600)] = 1

    @field_validator("dask_address")
    @classmethod
    def _dask_url(cls, v: str | None) -> str | None:
        if v is None or v == "":
            return None
        scheme, sep, rest = v.partition("://")
        if not sep or scheme not in ("tcp", "tls", "inproc", "ws", "wss") or not rest:
            raise ValueError("must look like tcp://HOST:PORT")
        return v
