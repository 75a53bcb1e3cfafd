"""The generated C step (ocp.stream.codegen) built with the system compiler matches the Python step."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from ocp.model.params import MotorParams
from ocp.stream import shape_profile, stream_options
from ocp.stream.codegen import build, compiler

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler (cc/gcc) on PATH")
CHANNELS = ("thrust", "omega", "omega_dot", "omega_ddot", "current", "voltage", "desired")


@pytest.mark.parametrize("regularity", ["bounded", "continuous-voltage"])
def test_c_step_matches_python(rig: MotorParams, tmp_path: Path, regularity: str) -> None:
    t = np.arange(3000) * 0.001
    f = 0.45 * np.sin(2 * np.pi * 1.3 * t) + 0.1 * np.sin(2 * np.pi * 5.0 * t + 1.0)
    # a tight current limit so the governor acts (its C port is exercised, not only the linear law)
    opts = stream_options(current=0.6, voltage=12.0, regularity=regularity, delay=0.06)
    py = shape_profile(rig, opts, t, f)
    assert py.saturated.sum() > 5
    exe = build(rig, opts, tmp_path)
    run = subprocess.run([str(exe)], input="\n".join(repr(float(x)) for x in f), capture_output=True, text=True,
                         timeout=60, check=True)
    y = np.array([[float(v) for v in line.split()] for line in run.stdout.splitlines()])
    assert y.shape == (t.size, 8)
    for j, name in enumerate(CHANNELS):
        ref = getattr(py, name)
        # omega'' is the governed decision itself: the governor's finite-difference slopes turn the last-bit
        # differences of the summation order (numpy's pairwise dot vs C's loop) into ~1e-7 of it
        tol = 1e-6 if name == "omega_ddot" else 1e-9
        np.testing.assert_allclose(y[:, j], ref, rtol=0, atol=tol * np.max(np.abs(ref)), err_msg=name)
    np.testing.assert_array_equal(y[:, 7].astype(bool), py.saturated)
    assert "worst_us" in run.stderr
