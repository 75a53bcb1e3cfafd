"""What every command shares and that must stay light to import: the parser class (help with a
description, an example and lazily computed lists of presets and effects; usage errors as JSON under
``--json``), ``--version``, the JSON error line, and ``-`` as stdin/stdout.

Nothing here imports numpy, pydantic or the core at module level: ``thrustshape --help`` must not
pay for them.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from collections.abc import Sequence
from contextlib import AbstractContextManager
from pathlib import Path
from typing import IO, Any, Literal, NoReturn

#: ``-`` as a file argument: stdin (inputs) or stdout (``--out -``)
STDIO = "-"

Listing = Literal["presets", "effects", "regularities"]


def version() -> str:
    """The installed distribution's version (``0+unknown`` from a source tree without metadata)."""
    from importlib import metadata

    try:
        return metadata.version("thrustshape")
    except metadata.PackageNotFoundError:
        return "0+unknown"


class VersionAction(argparse.Action):
    """``--version``: the version is looked up only when asked for (importlib.metadata is slow to import)."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS, **kw: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help=kw.get("help", "show the version and exit"))

    def __call__(self, parser: argparse.ArgumentParser, *args: Any) -> None:
        print(f"{parser.prog} {version()}")
        parser.exit()


def _listing(kind: Listing) -> str:
    """One help line naming what a command accepts, read from the core only when help is printed."""
    if kind == "presets":
        from ocp.model.params import PRESETS

        return "presets (--params NAME): " + ", ".join(PRESETS)
    if kind == "effects":
        from ocp.model.effects import CATALOGUE

        return "effects (--effects NAME,...; or param:<key>): " + ", ".join(sorted(CATALOGUE))
    from ocp.theory.reversal import ReversalRegularity

    return "regularities (mission 'regularity'): " + ", ".join(r.value for r in ReversalRegularity)


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose help keeps the examples' line breaks and may end with lists that are
    looked up only when the help is printed; with ``--json`` on the command line a usage error is a
    JSON object on stderr (exit 2) like every other error."""

    #: set by :func:`clients.cli.main` when ``--json`` is among the arguments
    json_errors = False

    def __init__(self, *args: Any, lists: Sequence[Listing] = (), **kw: Any) -> None:
        kw.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kw)
        self.lists = tuple(lists)

    def format_help(self) -> str:
        if self.lists:
            extra = "\n".join(_listing(k) for k in self.lists)
            self.epilog = f"{self.epilog}\n\n{extra}" if self.epilog else extra
            self.lists = ()
        return super().format_help()

    def error(self, message: str) -> NoReturn:
        if Parser.json_errors:
            body = {"type": "about:blank", "title": "Usage error", "detail": message, "field": None,
                    "reason": message, "error_type": "UsageError", "command": self.prog, "exit_code": 2}
            print(json.dumps(body), file=sys.stderr)
            sys.exit(2)
        super().error(message)


def add_command(sub: argparse._SubParsersAction, name: str, *, summary: str, description: str = "",
                examples: Sequence[str] = (), lists: Sequence[Listing] = ()) -> argparse.ArgumentParser:
    """A subcommand with a one-line ``summary`` (the command list), a ``description`` and ``examples``
    (its ``--help``), and ``lists`` of accepted names appended to its help."""
    epilog = ("examples:\n" + "\n".join(f"  {e}" for e in examples)) if examples else None
    return sub.add_parser(name, help=summary, description=f"{summary}.\n\n{description}".strip() if description
                          else summary, epilog=epilog, lists=lists)


def open_input(path: str) -> AbstractContextManager[IO[str]]:
    """``path`` opened for reading text, or stdin for ``-`` (left open after the ``with``: it is the process's)."""
    if path == STDIO:
        return contextlib.nullcontext(sys.stdin)
    return open(path, encoding="utf-8", newline="")


def read_text(path: str) -> str:
    """The text of ``path``, or of stdin for ``-``."""
    with open_input(path) as fh:
        return str(fh.read())


def write_text(text: str, out: str | None) -> None:
    """``text`` to the file ``out``, or to stdout for ``None`` / ``-``."""
    if out is None or out == STDIO:
        sys.stdout.write(text)
    else:
        Path(out).write_text(text, encoding="utf-8")


def require_extra(module: str, extra: str, field: str) -> None:
    """Fail with a clear message naming the extra to install when an optional dependency is missing."""
    import importlib.util

    if importlib.util.find_spec(module) is None:
        from ocp.errors import MissionError

        raise MissionError(field, f"needs the optional dependency {module!r}: pip install 'thrustshape[{extra}]'")


def error_json(exc: BaseException, command: str) -> str:
    """One problem+json-like line for an error: ``type, title, detail, field, reason, error_type`` and the
    exit code; a server's error keeps its own problem fields and HTTP ``status``."""
    body: dict[str, Any] = {"type": "about:blank", "title": type(exc).__name__, "detail": str(exc),
                            "field": getattr(exc, "field", None), "reason": getattr(exc, "reason", None),
                            "error_type": type(exc).__name__, "command": command, "exit_code": 1}
    problem = getattr(exc, "problem", None)
    if isinstance(problem, dict):  # the server's problem+json, as it sent it
        body.update({k: v for k, v in problem.items() if k not in ("command", "exit_code", "error_type")})
        body["status"] = getattr(exc, "status", problem.get("status"))
    if isinstance(exc, OSError) and getattr(exc, "filename", None):
        body.update(field=str(exc.filename), reason=exc.strerror or str(exc))
    return json.dumps(body, default=str)
