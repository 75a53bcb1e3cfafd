"""``python -m ocp.gallery [--out DIR]``: the same as ``thrustshape gallery`` without the CLI package."""

from __future__ import annotations

import argparse
import sys

from ocp.errors import ThrustshapeError
from ocp.gallery.build import build_gallery, summary_lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ocp.gallery", description=__doc__)
    parser.add_argument("--out", default="gallery", help="output directory (default: ./gallery)")
    args = parser.parse_args(argv)
    try:
        result = build_gallery(args.out)
    except (ThrustshapeError, OSError) as exc:
        print(f"gallery: error: {exc}", file=sys.stderr)
        return 1
    print("\n".join(summary_lines(result)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
