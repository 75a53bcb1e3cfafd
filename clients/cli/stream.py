"""``thrustshape stream``: the streaming shaper as a Unix filter.

Reads CSV rows ``t,thrust`` [s, N] from stdin (header first) as they arrive and writes
``t,thrust,omega,current,voltage`` [s, N, rad/s, A, V] to stdout, one flushed line per input row. The
output time equals the input time; the output thrust at ``t`` tracks the desired thrust at
``t - delay``. Without ``--dt`` the sample period is the spacing of the first two rows, so the first
output line is written when the second row arrives. A bad row stops the stream with an error naming
its line (1-based, the header is line 1); the lines already written stand.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator
from typing import TYPE_CHECKING, TextIO

from clients.cli.help import add_command
from ocp.errors import MissionError, ThrustshapeError

if TYPE_CHECKING:
    from ocp.stream import StreamSample, StreamShaper

#: the stream's crossing classes (ocp.stream.options.STREAM_REGULARITIES, spelled out so that
#: ``thrustshape --help`` imports no numerics; tests/test_stream_cli.py keeps the two equal)
REGULARITIES = ("bounded", "continuous-current", "continuous-voltage")
HEADER_IN = ("t", "thrust")
HEADER_OUT = "t,thrust,omega,current,voltage"


def register(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "stream", summary="shape a thrust reference sample by sample (stdin CSV t,thrust -> stdout)",
                    description="Each output line t,thrust,omega,current,voltage is written (flushed) as its "
                                "input row arrives;\nthe output thrust at t tracks the desired thrust at t - delay.",
                    examples=["thrustshape stream --params paper-rig --voltage 12 --current 1 < desired.csv"],
                    lists=("presets",))
    p.add_argument("--params", required=True, help="parameter file (JSON/YAML) or preset name, e.g. paper-rig")
    p.add_argument("--voltage", type=float, required=True, help="voltage limit |V| [V]")
    p.add_argument("--current", type=float, required=True, help="current limit |i| [A]")
    p.add_argument("--regularity", choices=REGULARITIES, default="continuous-voltage",
                   help="crossing class (default continuous-voltage: thrust ~ |s|^6 at reversals)")
    p.add_argument("--delay", type=float, default=0.1, help="look-ahead D [s]: output at t tracks input at t - D")
    p.add_argument("--dt", type=float, default=None, help="sample period [s] (default: from the first two rows)")
    p.add_argument("--bandwidth", type=float, default=20.0, help="tracker bandwidth [Hz]")
    p.set_defaults(func=cmd_stream)


def _header(stream: TextIO) -> None:
    """Read and check the input header ``t,thrust`` (line 1)."""
    header = stream.readline()
    if not header:
        raise MissionError("line 1", "empty input; expected the header t,thrust")
    if tuple(h.strip() for h in header.split(",")) != HEADER_IN:
        raise MissionError("line 1", f"header must be t,thrust, got {header.strip()!r}")


def _rows(stream: TextIO) -> Iterator[tuple[int, float, float]]:
    """(line number, t, thrust) per data row after the header."""
    for n, line in enumerate(iter(stream.readline, ""), start=2):
        if not line.strip():
            continue
        parts = line.split(",")
        if len(parts) != 2:
            raise MissionError(f"line {n}", f"expected 2 values t,thrust, got {len(parts)}")
        try:
            yield n, float(parts[0]), float(parts[1])
        except ValueError:
            raise MissionError(f"line {n}", f"not a number in {line.strip()!r}") from None


def _write(out: TextIO, s: StreamSample) -> None:
    out.write(f"{s.t!r},{s.thrust!r},{s.omega!r},{s.current!r},{s.voltage!r}\n")
    out.flush()


def cmd_stream(args: argparse.Namespace) -> int:
    from ocp.model.params import load_params
    from ocp.stream import StreamShaper, stream_options

    params = load_params(args.params)
    opts = dict(current=args.current, voltage=args.voltage, regularity=args.regularity, delay=args.delay,
                bandwidth=args.bandwidth)
    out = sys.stdout
    _header(sys.stdin)
    rows = _rows(sys.stdin)
    pending: list[tuple[int, float, float]] = []
    shaper: StreamShaper | None = None
    if args.dt is not None:
        shaper = StreamShaper(params, stream_options(**opts, dt=args.dt))
    out.write(HEADER_OUT + "\n")
    out.flush()
    for row in rows:
        if shaper is None:
            pending.append(row)
            if len(pending) < 2:
                continue
            dt = pending[1][1] - pending[0][1]
            if not dt > 0:
                raise MissionError(f"line {pending[1][0]}", "t must increase from the first row")
            shaper = StreamShaper(params, stream_options(**opts, dt=dt))
        for n, t, f in pending or [row]:
            try:
                _write(out, shaper.push(t, f))
            except ThrustshapeError as exc:
                raise MissionError(f"line {n}", f"{exc.field}: {exc.reason}") from None
        pending = []
    if pending:
        raise MissionError("line 2", "one data row is not a stream; give --dt or at least two rows")
    return 0
