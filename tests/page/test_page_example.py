"""The page's bundled examples: the model-check log is the synthetic rig with a hidden effect, regenerated
here bit for bit (``python -m tests.page.test_page_example`` rewrites it), small, and readable by the log reader."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ocp.logs import read_log
from ocp.model.params import load_params
from ocp.optimize.mission import load_mission
from tests.synthetic_rig import RigSpec, generate

STATIC = Path(__file__).resolve().parents[2] / "service" / "static"
LOG = STATIC / "example-log.csv"
MISSION = STATIC / "example-mission.json"
HIDDEN = {"coulomb_friction": {"tau_c": 0.003}}  # what the page's diagnose must find
SPEC = RigSpec(effects=HIDDEN, seconds=1.0, seed=7)  # sine, sin^5, chirp: 3 s at 1 kHz
FORMATS = {"t": "%.3f", "voltage": "%.6f", "current": "%.3f", "omega": "%.3f", "theta": "%.5f", "thrust": "%.4f"}


def example_log_csv() -> str:
    cols = generate(load_params("paper-rig"), SPEC).columns()
    lines = [",".join(FORMATS)]
    rows = np.column_stack([cols[k] for k in FORMATS])
    fmt = ",".join(FORMATS.values())
    lines += [(fmt % tuple(r)).replace("-0.000,", "0.000,") for r in rows]
    return "\n".join(lines) + "\n"


def test_bundled_log_is_the_synthetic_rig_and_small() -> None:
    assert LOG.read_text(encoding="utf-8") == example_log_csv()
    assert LOG.stat().st_size < 300_000
    log = read_log(LOG)
    assert log.n == 3000
    assert log.theta is not None


def test_bundled_mission_is_the_repository_example() -> None:
    root = STATIC.parents[1] / "examples" / "reversal.json"
    assert json.loads(MISSION.read_text(encoding="utf-8")) == json.loads(root.read_text(encoding="utf-8"))
    assert load_mission(MISSION).name == "reversal-2s"


if __name__ == "__main__":
    LOG.write_text(example_log_csv(), encoding="utf-8")
    print(f"wrote {LOG} ({LOG.stat().st_size} bytes)")
