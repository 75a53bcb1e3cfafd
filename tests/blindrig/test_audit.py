"""The blind rig's visibility audit (``bench/blind_audit.py``) against what must hold whatever the rig: its replay
reproduces the log it audits, a label the log never exercises has no footprint at all, and one it does has."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import blind_audit
from blindrig.draw import draw_case
from blindrig.excite import Excitation
from blindrig.logger import run_log


def test_the_open_loop_replay_of_a_closed_loop_log_is_that_log() -> None:
    """The audit replays the logged command open-loop: on the true rig, with the same noise draws, it must give the
    logged channels exactly (seed 65: a PI loop on random set points, every row closed-loop)."""
    case = draw_case(65)
    assert case.exc.closed.all()
    log = run_log(case.truth, case.cfg, case.exc, case.h_max, np.random.default_rng([65, 7]), case.theta0)
    n = case.cfg.n
    replay = Excitation("replay", ["replay"], np.zeros(n, dtype=bool), log["voltage"], np.zeros(n), False)
    again = run_log(case.truth, case.cfg, replay, case.h_max, np.random.default_rng([65, 7]), case.theta0)
    for ch in ("omega", "current", "thrust", "theta"):
        np.testing.assert_array_equal(again[ch], log[ch])


def test_a_label_the_log_never_exercises_has_no_footprint() -> None:
    """Seed 6: a thrust asymmetry on a rotor that never turns in reverse (the rig's own note: invisible); the wrong
    ``k`` beside it shows."""
    prints = blind_audit.footprints(6)
    assert prints["thrust_asymmetry"] == 0.0
    assert prints["param:k"] >= blind_audit.VISIBLE


def test_a_reverse_only_asymmetry_shows() -> None:
    """Seed 151: a drag asymmetry on a rotor that turns in reverse only (the rig's note calls it invisible: it looks
    for forward rotation); reverse rotation is where it acts."""
    assert blind_audit.footprints(151)["drag_asymmetry"] >= 10 * blind_audit.VISIBLE
