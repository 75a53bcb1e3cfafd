"""The proving ground's audit of a label (:mod:`tests.proving_ground.calibration`) against closed forms.

Oracles: (1) a thrust coefficient believed 30 % low, with calibration free to move it 10 %: the thrust channel's
footprint is left at (1.3 - 1.1) / (1.3 - 1.0) of itself (F = c_f w|w| holds the speed alone; nothing else can
move the thrust without moving the speed, which an encoder of 65,536 counts logs to 0.02 rad/s: the weighted fit
gains next to nothing by trading speed for thrust); (2) a brush drop ``v_b sign(i)`` under a two-level command is
``v_b sign(V)`` wherever the current has the command's sign, i.e. the armature ``V (1 - v_b/|V|) = R i + k w``: ``R``
and ``k`` scaled by ``1 / (1 - v_b / |V|)``, here 3 %: calibration takes it all; (3) the same drop under commands of
many levels is no scaling of any constant, and stays.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.proving_ground import cases as pg
from tests.proving_ground.calibration import CONSTANTS, residual_footprint
from tests.proving_ground.logger import Logger, logged, noise_levels
from tests.proving_ground.physics import Truth

RIG = Truth(J=3.45e-6, B=2.27e-6, c_tau=7.0e-8, c_f=1.39e-6, k=7.56e-3, R=0.535, L=7.4e-5, v_max=6.0)
LOGGER = Logger(rate=500.0, skew=1.1, speed="tacho", counts=1024, diff_span=1, noise_w=3.6, alpha=1.0,
                noise_i=0.023, q_i=0.003, noise_f=0.002, q_f=0.0002, q_v=0.047, jitter=0.0)
TAU_M = RIG.J * RIG.R / RIG.k**2  # [s]
N = 1500
V = 4.8  # [V] the command's level


def _commands(levels: bool) -> np.ndarray:
    """(N,) [V]: a two-level PRBS of ``+-V`` (``levels``: steps to uniformly drawn levels in ``+-V``), holding 20-60
    samples."""
    rng = np.random.default_rng(7)
    out, k, sign = np.empty(N), 0, 1.0
    while k < N:
        hold = int(rng.integers(20, 60))
        out[k:k + hold] = rng.uniform(-V, V) if levels else sign * V
        sign, k = -sign, k + hold
    return out


def _footprints(truth: Truth, without: Truth, cmds: np.ndarray,
                lg: Logger = LOGGER) -> tuple[np.ndarray, np.ndarray]:
    """(before, after) (3,) [speed, current, thrust] in noise levels."""
    sig = noise_levels(lg)
    lag, sub = pg._lag(truth, lg), pg._substeps(truth, lg, TAU_M)
    a, b = (logged(lg, pg._replay(x, cmds, lg, TAU_M)) for x in (truth, without))
    before = np.sqrt(np.mean((a - b) ** 2, axis=1)) / sig
    believed = {c: getattr(without, c) for c in CONSTANTS}
    return before, residual_footprint(truth, without, believed, set(), cmds, lg, lag, sub, sig)


def test_a_constant_keeps_its_error_beyond_the_tolerance() -> None:
    truth = replace(RIG, c_f=RIG.c_f * 1.3)
    encoder = replace(LOGGER, speed="encoder", counts=65536)
    before, after = _footprints(truth, RIG, _commands(levels=True), encoder)
    assert before[2] > 10 * pg.VISIBLE and before[0] == before[1] == 0.0
    closed = before[2] * (1.3 - 1.1) / (1.3 - 1.0)  # c_f moved to the box's edge, nothing else
    assert after[2] == pytest.approx(closed, rel=0.02)
    assert np.sum(after**2) <= closed**2 * 1.001  # whatever else it moved, no worse than that feasible correction


def test_a_brush_drop_under_two_levels_is_calibration() -> None:
    truth = replace(RIG, effects={"brush_drop": {"v_b": 0.03 * V}})
    before, after = _footprints(truth, RIG, _commands(levels=False))
    assert max(before) > 2 * pg.VISIBLE  # (the proving ground's criterion alone calls it visible)
    assert max(after) < 0.2 * max(before) and max(after) < pg.VISIBLE


def test_a_brush_drop_under_many_levels_stays() -> None:
    truth = replace(RIG, effects={"brush_drop": {"v_b": 0.03 * V}})
    before, after = _footprints(truth, RIG, _commands(levels=True))
    assert max(after) > pg.VISIBLE and max(after) > 0.3 * max(before)
