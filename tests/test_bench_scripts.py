"""Every script under ``bench/`` (run on demand, most with no test of their own) still starts: ``--help`` from
outside the repository exits 0. An import moved or a file read relative to the working directory fails here, not
on the day someone runs the benchmark (``bench/min_time.py`` had lost its oracle's module and read
``examples/reversal.json`` from the working directory). A script's own figures are tested where it has a test."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench"
SCRIPTS = sorted(p for p in BENCH.glob("*.py") if '__name__ == "__main__"' in p.read_text(encoding="utf-8"))


def test_the_scripts_are_found() -> None:
    assert len(SCRIPTS) >= 30 and BENCH / "modelcheck.py" in SCRIPTS


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_a_bench_script_starts(script: Path, tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    run = subprocess.run([sys.executable, str(script), "--help"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.startswith("usage:")
