"""``thrustshape stream`` as a real subprocess: rows in one at a time, one flushed line out per row."""

from __future__ import annotations

import io
import os
import selectors
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from clients.cli import main
from ocp.model.params import MotorParams
from ocp.stream import shape_profile, stream_options

ROOT = Path(__file__).resolve().parents[2]
ARGS = ["--params", "paper-rig", "--voltage", "12", "--current", "1", "--delay", "0.05"]


def _start(*extra: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "clients.cli", "stream", *ARGS, *extra], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1, env=env)


def _line(proc: subprocess.Popen[str], timeout: float = 30.0) -> str:
    """The next stdout line, failing if none arrives within ``timeout`` s (i.e. the CLI did not flush)."""
    assert proc.stdout is not None
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    assert sel.select(timeout), "no output line arrived"
    return proc.stdout.readline()


def test_stream_answers_each_row_before_the_next_arrives(rig: MotorParams) -> None:
    t = np.arange(120) * 0.001
    f = 0.3 * np.sin(2 * np.pi * 4.0 * t)
    proc = _start("--dt", "0.001")
    assert proc.stdin is not None
    proc.stdin.write("t,thrust\n")
    assert _line(proc).strip() == "t,thrust,omega,current,voltage"
    rows = []
    for a, b in zip(t, f, strict=True):
        proc.stdin.write(f"{float(a)!r},{float(b)!r}\n")
        proc.stdin.flush()
        rows.append([float(x) for x in _line(proc).split(",")])
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    got = np.array(rows)
    ref = shape_profile(rig, stream_options(current=1.0, voltage=12.0, delay=0.05), t, f)
    np.testing.assert_array_equal(got[:, 0], t)  # output time = input time
    for j, name in enumerate(("thrust", "omega", "current", "voltage"), start=1):
        np.testing.assert_allclose(got[:, j], getattr(ref, name), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(("extra", "text", "lines_out", "message"), [
    ((), "t,thrust\n0,0.1\n0.001,0.1\n0.002,0.1\n0.003,abc\n0.004,0.1\n", 4, "line 5: not a number"),
    (("--dt", "0.001"), "t,thrust\n0,0.1\n0.01,0.1\n", 2, "line 3: t: advances by 0.01 s"),
    (("--dt", "0.001"), "t,thrust\n0,0.1\n0.001,nan\n", 2, "line 3: thrust: must be a finite number"),
    ((), "time,F\n0,1\n", 0, "line 1: header must be t,thrust"),
    ((), "t,thrust\n0,0.1\n", 1, "line 2: one data row is not a stream"),
])
def test_stream_errors_name_the_line(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
                                     extra: tuple[str, ...], text: str, lines_out: int, message: str) -> None:
    """In process (the same ``main`` the console script runs): rows before the bad one are already out."""
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    assert main(["stream", *ARGS, *extra]) == 1
    out, err = capsys.readouterr()
    assert len(out.splitlines()) == lines_out
    assert message in err, err


def test_cli_regularities_are_the_shapers() -> None:
    from clients.cli.stream import REGULARITIES
    from ocp.stream.options import STREAM_REGULARITIES

    assert tuple(r.value for r in STREAM_REGULARITIES) == REGULARITIES
