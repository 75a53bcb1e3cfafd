"""The ``thrustshape`` command line.

Each command family lives in its own module exposing ``register(subparsers)``; every command
accepts ``--json`` for machine-readable output, writes errors to stderr and exits non-zero on error
(1: bad input or failed computation, 2: bad command-line usage). With ``--json`` an error is one
problem+json-like object on stderr (``{"type", "title", "status", "detail", "field", "reason"}``).

Start-up stays light (``thrustshape --help`` in well under 0.5 s): command modules import numpy,
scipy, CasADi, matplotlib and the core only inside the command functions, never at module level
(``tests/test_cli_conventions.py`` checks it). A file argument ``-`` is stdin; ``--out -`` is
stdout; a closed pipe (``thrustshape analytic ... | head``) ends the command quietly with 141
(128 + SIGPIPE, as the shell's own tools do).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from clients.cli.help import Parser, VersionAction, error_json
from ocp.errors import ThrustshapeError

#: command modules, in help order; each has ``register(subparsers) -> None``
COMMAND_MODULES: tuple[str, ...] = ("clients.cli.core", "clients.cli.optimize", "clients.cli.gallery",
                                    "clients.cli.service", "clients.cli.model", "clients.cli.design",
                                    "clients.cli.stream")

#: exit status after a closed output pipe (128 + SIGPIPE)
EXIT_PIPE = 141


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="thrustshape",
        description="Reproducible thrust references for bidirectional propellers.",
        epilog="Run 'thrustshape COMMAND --help' for a command's options and an example.",
    )
    parser.add_argument("--version", action=VersionAction, help="show the version and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def _known_error(exc: BaseException) -> bool:
    """A user-facing error: the core's tree, a file error, or the HTTP client's (only importable errors
    can have been raised, so the client is never imported here just to test for its class)."""
    if isinstance(exc, ThrustshapeError | OSError):
        return True
    errors = sys.modules.get("clients.errors")
    return errors is not None and isinstance(exc, errors.ClientError)


def _pipe_closed() -> int:
    """The reader went away: silence the interpreter's final flush of stdout and exit like SIGPIPE."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout without a file descriptor (captured in tests)
        pass
    return EXIT_PIPE


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    Parser.json_errors = "--json" in (sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    try:
        code = int(args.func(args) or 0)
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        return _pipe_closed()
    except Exception as exc:
        if not _known_error(exc):
            raise
        if getattr(args, "json", False):
            print(error_json(exc, args.command), file=sys.stderr)
        else:  # a ClientError carries the server's field and reason
            print(f"thrustshape {args.command}: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
