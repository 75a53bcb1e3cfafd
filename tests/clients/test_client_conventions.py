"""Client edge cases a server or network produces (a malformed ``Retry-After``, a dropped connection
while waiting for a batch) and the packaging conventions (extras, bounds, PEP 561, LICENSE)."""

from __future__ import annotations

import asyncio
import tomllib
from pathlib import Path
from typing import Any

import httpx
import pytest

from clients import AsyncClient, Client, ClientError, MalformedResponse, ServerBusy, TransportError

ROOT = Path(__file__).resolve().parents[2]


def busy(retry_after: str) -> httpx.Response:
    return httpx.Response(503, headers={"Retry-After": retry_after, "content-type": "application/problem+json"},
                          json={"title": "Server busy", "status": 503, "detail": "full"})


@pytest.mark.parametrize("value", ["soon", "", "nan", "Mon, 99 Foo 2026 99:99:99 GMT"])
def test_malformed_retry_after_is_a_client_error_naming_the_header(value: str) -> None:
    with Client("http://x", transport=httpx.MockTransport(lambda r: busy(value)), retries=2) as c, \
            pytest.raises(MalformedResponse) as err:
        c.health()
    assert isinstance(err.value, ClientError) and not isinstance(err.value, ValueError)
    assert err.value.field == "Retry-After" and repr(value) in str(err.value)
    assert ServerBusy(503, {}, {"retry-after": value}).retry_after is None  # the property never raises


def test_valid_retry_after_forms_are_still_honoured() -> None:
    calls: list[int] = []

    def handler(request: httpx.Request) -> httpx.Response:
        calls.append(1)
        return busy("0") if len(calls) == 1 else (busy("Thu, 01 Jan 1970 00:00:00 GMT") if len(calls) == 2
                                                  else httpx.Response(200, json={"status": "ok"}))

    with Client("http://x", transport=httpx.MockTransport(handler), retries=3) as c:
        assert c.health() == {"status": "ok"} and len(calls) == 3


class Flaky:
    """A batch status route whose connection drops ``drops`` times before each of its answers."""

    def __init__(self, answers: list[str], drops: int) -> None:
        self.answers, self.drops, self.calls, self._dropped = list(answers), drops, 0, 0

    def __call__(self, request: httpx.Request) -> httpx.Response:
        self.calls += 1
        if self._dropped < self.drops:
            self._dropped += 1
            raise httpx.RemoteProtocolError("server disconnected without sending a response", request=request)
        self._dropped = 0
        return httpx.Response(200, json={"id": "b", "status": self.answers.pop(0),
                                         "counts": {"done": 0, "failed": 0}})


def test_wait_batch_rides_out_dropped_connections() -> None:
    flaky = Flaky(["running", "running", "done"], drops=2)  # 2 drops before every answer: within 3 in a row
    seen: list[Any] = []
    with Client("http://x", transport=httpx.MockTransport(flaky)) as c:
        status = c.wait_batch("b", poll=0.0, reconnects=3, backoff=0.01, on_progress=seen.append)
    assert status["status"] == "done" and flaky.calls == 9 and len(seen) == 3


def test_wait_batch_gives_up_after_bounded_reconnects() -> None:
    flaky = Flaky(["done"], drops=100)
    with Client("http://x", transport=httpx.MockTransport(flaky)) as c, pytest.raises(TransportError):
        c.wait_batch("b", poll=0.0, reconnects=3, backoff=0.01)
    assert flaky.calls == 4  # the first try and 3 reconnects


def test_async_wait_batch_rides_out_dropped_connections() -> None:
    flaky = Flaky(["running", "done"], drops=1)

    async def go() -> dict[str, Any]:
        async with AsyncClient("http://x", transport=httpx.MockTransport(flaky)) as c:
            return await c.wait_batch("b", poll=0.0, reconnects=1, backoff=0.01)

    assert asyncio.run(go())["status"] == "done" and flaky.calls == 4


def test_packaging_extras_bounds_typing_and_license() -> None:
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    deps = " ".join(meta["project"]["dependencies"])
    assert "dask" not in deps and "rockit" not in deps  # optional features (pyarrow reads every CSV log: core)
    for pkg in ("numpy", "scipy", "casadi"):  # the stack behind the benchmark figures: below the next major
        [spec] = [d for d in meta["project"]["dependencies"] if d.startswith(pkg)]
        assert "<" in spec, spec
    extras = meta["project"]["optional-dependencies"]
    assert {"dask", "flightlogs", "xlsx", "bench", "dev"} <= set(extras)
    assert any("rockit" in d for d in extras["bench"]) and not any("rockit" in d for d in extras["dev"][1:])
    assert extras["dev"][0] == "thrustshape[dask,flightlogs,xlsx,bench]"
    for pkg in ("ocp", "service", "clients"):
        assert (ROOT / pkg / "py.typed").is_file() and "py.typed" in meta["tool"]["setuptools"]["package-data"][pkg]
    assert (ROOT / "LICENSE").read_text().startswith("MIT License") and meta["project"]["license"] == "MIT"


def test_a_missing_extra_is_named() -> None:
    from clients.cli.help import require_extra
    from ocp.errors import ThrustshapeError

    with pytest.raises(ThrustshapeError) as err:
        require_extra("surely_not_installed_pkg", "dask", "--dask")
    assert err.value.field == "--dask" and "pip install 'thrustshape[dask]'" in err.value.reason
    require_extra("json", "dask", "--dask")  # present: no error


def test_batch_progress_writes_lines_not_carriage_returns_off_a_terminal() -> None:
    import io as _io

    from clients.cli.service import Progress

    log = _io.StringIO()  # not a terminal
    bar = Progress(4, stream=log)
    for done, failed in ((0, 0), (1, 0), (1, 0), (2, 1), (3, 1)):
        bar(done, failed)
    bar.close()
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and len(lines) == 4  # one line per change, none for a repeat
    assert lines[-1].startswith("[" + "#" * 30 + "] 4/4 done=3 failed=1") and "/s" in lines[-1]
    assert "ETA" in lines[1] and lines[1].split()[1] == "1/4"
