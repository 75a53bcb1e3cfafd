"""``--server URL`` / ``--api-key`` shared by the commands that can run on a thrustshape server."""

from __future__ import annotations

import argparse
import os
from typing import Any


def add_server_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--server", default=None, metavar="URL",
                   help="run on a thrustshape server (e.g. http://127.0.0.1:8000) instead of here")
    p.add_argument("--api-key", default=os.environ.get("THRUSTSHAPE_API_KEY"),
                   help="bearer token for --server (default: $THRUSTSHAPE_API_KEY)")


def client(args: argparse.Namespace) -> Any:
    """A :class:`clients.Client` for ``args.server`` (use as a context manager)."""
    from clients.client import Client

    return Client(args.server, api_key=args.api_key)


def params_for_server(params: str | dict[str, Any]) -> str | dict[str, Any]:
    """A preset name stays a name; a local parameter file is read here and sent as its mapping
    (the server never reads files)."""
    from ocp.model.params import PRESETS, read_mapping

    if isinstance(params, dict) or params in PRESETS:
        return params
    return read_mapping(params)
