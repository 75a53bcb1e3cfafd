"""A worker process's own limits on memory (run inside the worker, at its start: :mod:`service.workers`).

* :func:`first_to_go_when_memory_runs_out`: when the machine runs out of memory, the kernel kills a worker, which the
  pool replaces and whose request alone fails, before the server that holds every other request.
* :func:`cap_memory`: with ``THRUSTSHAPE_WORKER_MEMORY_MB`` set, an allocation past the cap raises
  :class:`MemoryError` in the task, answered as the request's fault (:func:`over_memory`) by a worker that goes on.
"""

from __future__ import annotations

import contextlib
import os

#: added to a worker's ``oom_score_adj`` (Linux; at most 1000)
OOM_SCORE_RAISE = 500

_CAP_MIB: list[int] = []  # this worker's memory cap [MiB], when it has one


def first_to_go_when_memory_runs_out() -> None:
    """Raise this process's ``oom_score_adj`` by :data:`OOM_SCORE_RAISE` (any process may raise its own; nothing
    on a system without it)."""
    with contextlib.suppress(OSError, ValueError), open("/proc/self/oom_score_adj", "r+") as f:
        now = int(f.read())
        f.seek(0)
        f.write(str(min(1000, now + OOM_SCORE_RAISE)))


def cap_memory(mib: int) -> None:
    """Cap this process's data memory (``RLIMIT_DATA``: heap and private writable mappings) at ``mib`` MiB, so that
    an allocation beyond it raises :class:`MemoryError` in the task instead of drawing the OOM killer. Arrow's
    allocator is set to the system's first: its default (mimalloc) reserves a 1 GiB arena the limit would count."""
    import resource

    os.environ["ARROW_DEFAULT_MEMORY_POOL"] = "system"
    limit = mib << 20
    _, hard = resource.getrlimit(resource.RLIMIT_DATA)
    resource.setrlimit(resource.RLIMIT_DATA, (limit if hard == resource.RLIM_INFINITY else min(limit, hard), hard))
    _CAP_MIB[:] = [mib]


def over_memory() -> str:
    """The reason given for a task that ran out of memory in this worker."""
    cap = f" ({_CAP_MIB[0]} MiB, THRUSTSHAPE_WORKER_MEMORY_MB)" if _CAP_MIB else ""
    return f"needs more memory than a worker may use{cap}: send a shorter log, or fewer samples or intervals"
