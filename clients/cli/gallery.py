"""``thrustshape gallery``: regenerate the seed paper's figures, examples and experiment table."""

from __future__ import annotations

import argparse

from clients.cli.help import add_command
from clients.cli.io import print_json


def register(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "gallery", summary="regenerate the paper's figures and the closed-loop table (PNG, SVG, HTML)",
                    description="Every figure of the seed paper from the project's own code, plus the Section V "
                                "closed-loop\ntable, into DIR/index.html (each figure as PNG and SVG).",
                    examples=["thrustshape gallery --out gallery && xdg-open gallery/index.html"])
    p.add_argument("--out", default="gallery", help="output directory (default: ./gallery)")
    p.add_argument("--json", action="store_true", help="print the file list and table as JSON")
    p.set_defaults(func=cmd_gallery)


def cmd_gallery(args: argparse.Namespace) -> int:
    from ocp.gallery.build import build_gallery, summary_lines

    result = build_gallery(args.out)
    if args.json:
        print_json({"out": str(result.out), "index": str(result.out / "index.html"),
                    "figures": {k: files for k, (_, files) in result.figures.items()},
                    "table": result.table, "optimised_note": result.optimised_note})
        return 0
    print("\n".join(summary_lines(result)))
    return 0
