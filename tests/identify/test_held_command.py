"""A jittered logger's command, held between its rows, read as held (:func:`ocp.logs.timebase.held_mean`): on the
blind rig's logs (``bench/blindrig``: its own integrator, effect formulas and loggers) the ramps that linear
interpolation put into every step of the command no longer leave a misfit that a false effect takes."""

from __future__ import annotations

from pathlib import Path

import pytest

from ocp.logs import read_log
from tests.identify.diagnosed import blind


@pytest.mark.parametrize("seed", [744, 509])
def test_a_jittered_loggers_command_steps_name_nothing_undrawn(seed: int, tmp_path: Path) -> None:
    """744: a clean 60 Hz PRBS, rows up to 30 % of a step off their grid, L/R 0.02 samples, named a dead band,
    ``k`` and ``c_tau``. 509: a 1 kHz PRBS with a 17-sample delay, named a 2-sample ``thrust_lag`` besides: the
    armature equation's misfit at the steps (34 noise units) put the speed sensor's lag nuisance at its bound,
    and the thrust map's lag undid it there. Both from the command interpolated across its jittered steps."""
    res, truth = blind(seed, tmp_path)
    assert truth["logger"]["jitter"] > 0 and truth["L_over_R_samples"] < 0.2
    assert any("held between rows" in n for n in read_log(tmp_path / f"case-{seed}.csv").notes)
    assert sorted(res.verdict) == sorted(truth["labels"])
