"""The ``thrustshape`` command line.

Each command family lives in its own module exposing ``register(subparsers)``; every command
accepts ``--json`` for machine-readable output, writes errors to stderr and exits non-zero on error
(1: bad input or failed computation, 2: bad command-line usage).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from clients.client import ClientError
from ocp.errors import ThrustshapeError

#: command modules, in help order; each has ``register(subparsers) -> None``
COMMAND_MODULES: tuple[str, ...] = ("clients.cli.core", "clients.cli.optimize", "clients.cli.gallery",
                                    "clients.cli.service", "clients.cli.model", "clients.cli.stream")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="thrustshape",
        description="Reproducible thrust references for bidirectional propellers.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ThrustshapeError, OSError, ClientError) as exc:  # a ClientError carries the server's field and reason
        print(f"thrustshape {args.command}: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
