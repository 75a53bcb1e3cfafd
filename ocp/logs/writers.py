"""Writers: a log as SI CSV, and a reference (or any named SI arrays) as a MATLAB ``.mat`` for Simulink."""

from __future__ import annotations

import csv
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ocp.logs.model import Log


def write_log_csv(log: Log, path: str | Path) -> None:
    """Write a log as CSV in SI with the canonical column names (channels present only)."""
    cols = log.columns()
    with Path(path).open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(list(cols))
        for row in zip(*cols.values(), strict=True):
            w.writerow([repr(float(v)) for v in row])


def write_reference_mat(arrays: Mapping[str, np.ndarray], path: str | Path, name: str = "ref") -> None:
    """Write equal-length SI arrays (N,) as a MATLAB v5 ``.mat``: each as a column vector (N, 1) at top
    level (``t``, ``thrust``, ``omega``, ...), and ``<name>_ts = [t, thrust, omega, ...]`` (N, 1+K), the
    matrix a Simulink *From Workspace* block takes (first column time), with ``<name>_columns`` naming its
    columns (one comma-separated string)."""
    from scipy import io as sio

    cols = {k: np.asarray(v, dtype=float).reshape(-1, 1) for k, v in arrays.items()}
    data: dict[str, object] = dict(cols)
    if "t" in cols:
        rest = [v for k, v in cols.items() if k != "t"]
        data[f"{name}_ts"] = np.hstack([cols["t"], *rest])
        data[f"{name}_columns"] = ",".join(["t", *(k for k in cols if k != "t")])
    sio.savemat(Path(path), data, do_compression=True, oned_as="column")
