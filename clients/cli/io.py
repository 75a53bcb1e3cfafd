"""Small I/O helpers shared by CLI commands: CSV columns in, CSV/JSON out (``-``: stdin / stdout).

numpy is imported inside the functions: the CLI's start-up must not pay for it."""

from __future__ import annotations

import csv
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clients.cli.help import STDIO, open_input
from ocp.errors import MissionError

if TYPE_CHECKING:
    import numpy as np


def read_csv_columns(path: str | Path, required: Sequence[str]) -> dict[str, np.ndarray]:
    """Numeric columns of a CSV file with a header row (``-``: stdin); errors name the file and the column."""
    import numpy as np

    p = Path("stdin" if str(path) == STDIO else path)
    if str(path) != STDIO and not p.is_file():
        raise MissionError(str(path), "no such file")
    with open_input(str(path)) as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise MissionError(str(path), "empty file")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in required if c not in header]
    if missing:
        raise MissionError(f"{p.name}:{missing[0]}", f"missing column; the header has {header}")
    out: dict[str, np.ndarray] = {}
    for c in required:
        j = header.index(c)
        try:
            out[c] = np.array([float(r[j]) for r in rows[1:] if r], dtype=float)
        except (ValueError, IndexError):
            raise MissionError(f"{p.name}:{c}", "has a non-numeric or missing value") from None
        if not np.all(np.isfinite(out[c])):
            raise MissionError(f"{p.name}:{c}", "contains NaN or inf")
    return out


def write_csv(columns: dict[str, np.ndarray], out: str | None) -> None:
    """Write equal-length columns as CSV to ``out`` (a path) or stdout (``None`` or ``-``); a ``.mat`` path
    gets a MATLAB file for Simulink instead (:func:`ocp.logs.write_reference_mat`: column vectors and
    ``ref_ts = [t, ...]``)."""
    if out and Path(out).suffix.lower() == ".mat":
        from ocp.logs import write_reference_mat

        write_reference_mat(columns, out)
        return
    names = list(columns)
    to_file = bool(out) and out != STDIO
    fh = open(out, "w", newline="", encoding="utf-8") if to_file and out else sys.stdout
    try:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(names)
        for row in zip(*(columns[n] for n in names), strict=True):
            w.writerow([repr(float(v)) for v in row])
    finally:
        if to_file:
            fh.close()


def fmt_number(v: Any, fmt: str, scale: float = 1.0) -> str:
    """``v * scale`` formatted, or ``nan`` where a JSON answer holds null (a non-finite value)."""
    return format(v * scale, fmt) if isinstance(v, int | float) else "nan"


def print_json(obj: Any) -> None:
    json.dump(obj, sys.stdout, indent=None, allow_nan=False)
    sys.stdout.write("\n")
