"""The model-check report draws on its own Agg canvases: a caller's pyplot backend and open figures
are left as they were (it used to call ``matplotlib.use("Agg")``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import matplotlib
matplotlib.use("svg")              # the caller's choice, not Agg
import matplotlib.pyplot as plt
plt.figure()                       # and one open figure of its own
from ocp.identify import check
from ocp.identify.report import html_report
from ocp.model.params import load_params
from ocp.model.plant import DCMotorPlant
from tests.synthetic_rig import RigSpec, generate
rig = load_params("paper-rig")
log = generate(rig, RigSpec(seconds=0.5, seed=1))
page = html_report(check(DCMotorPlant(rig), log), log)
assert page.count("data:image/png;base64,") == 4
print(matplotlib.get_backend(), len(plt.get_fignums()))
"""


def test_report_keeps_the_callers_backend_and_figures() -> None:
    run = subprocess.run([sys.executable, "-c", SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=300,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "MPLBACKEND": ""})
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["svg", "1"]
