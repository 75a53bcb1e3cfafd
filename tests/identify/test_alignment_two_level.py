"""Alignment on a slow two-level command (a PRBS whose bits last many samples), on logs of the independent
proving ground (``tests/proving_ground``: its own physics, integrator and logger). Only the rare level changes
tell the lag there; the drive's dead band acts on each held level, so its term must not become a free column on
the rows where the level changes (which absorbed any sub-sample lag and left the minimum flat: no lag, or a
wrong one, and the resulting timing error blamed on ``L``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify import DiagnoseOptions, diagnose
from ocp.identify.align import Alignment, _pick, estimate, voltage_spread
from ocp.identify.diagnose import _explain, _pool, split
from ocp.identify.predict import noise_levels
from ocp.logs import Log, log_from_arrays
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.identify.test_one_command import P, step_log
from tests.proving_ground.cases import draw_motor
from tests.proving_ground.excite import open_loop
from tests.proving_ground.logger import Logger, record
from tests.proving_ground.physics import run
from tests.synthetic_rig import RigSpec, generate


def _prbs_log(seed: int, rate: float, skew: float, alpha: float) -> tuple[Log, float]:
    """A log (0.8 s) of a drawn motor under a slow PRBS, the drive applying row k's command ``skew`` samples
    later; the logged current through a first-order filter ``alpha``."""
    rng = np.random.default_rng(seed)
    truth, tau_m = draw_motor(rng)
    lg = Logger(rate=rate, skew=skew, speed="encoder", counts=4096, diff_span=1, noise_w=0.004 * truth.v_max / truth.k,
                alpha=alpha, noise_i=0.005 * truth.v_max / truth.R * 0.1, q_i=1e-4 * truth.v_max / truth.R,
                noise_f=1e-3, q_f=1e-4, q_v=2 * truth.v_max / 4096, jitter=0.0)
    n = int(0.8 * rate)
    cmds = np.round(open_loop("prbs", n, lg.dt, truth.v_max, tau_m, rng) / lg.q_v) * lg.q_v
    substeps = max(4, math.ceil(lg.dt / min(tau_m / 150.0, 5e-4)))
    samples, issued = run(truth, lambda k, _s: float(cmds[k]), n, lg.dt, skew * lg.dt, substeps)
    cols = record(lg, samples, issued, rng)
    log = log_from_arrays(cols["t"], cols["voltage"], cols["current"], cols["thrust"], omega=cols["omega"],
                          theta=cols["theta"])
    return log, skew


@pytest.mark.parametrize(("seed", "rate", "skew", "alpha"), [(4101, 5000.0, 2.12, 1.0), (4102, 1000.0, 0.6, 0.9)])
def test_a_slow_two_level_command_still_gives_the_lag(seed: int, rate: float, skew: float, alpha: float) -> None:
    log, true = _prbs_log(seed, rate, skew, alpha)
    a = estimate(log)
    assert abs(a.samples - true) <= 0.5, (a.samples, true)
    assert "not identifiable" not in a.rule


def test_a_plateau_inside_the_search_gives_its_midpoint_and_a_flat_end_none() -> None:
    lags = np.arange(0.0, 6.01, 0.125)
    plateau = np.where((lags >= 2.0) & (lags <= 3.0), 1.0, 1.5)  # bounded: only "somewhere in 2..3" is known
    assert _pick(lags, plateau) == (pytest.approx(2.5), True)
    smooth = 1.0 + 0.001 * lags  # within 1 % up to the search's end: not identifiable
    assert _pick(lags, smooth) == (0.0, False)
    sharp = 1.0 + (lags - 1.3) ** 2
    lag, known = _pick(lags, sharp)
    assert known and lag == pytest.approx(1.3, abs=0.01)


def test_the_command_spread_reads_one_magnitude_for_two_levels() -> None:
    """Closed forms: +-V0 and 0/V0 are one magnitude (1), a staircase 2, 4, 6 V spreads 2/6, all-zero is 1."""
    square = np.tile([6.0, -6.0], 50)
    assert voltage_spread(square) == 1.0 and voltage_spread(np.abs(square) * np.tile([1.0, 0.0], 50)) == 1.0
    assert voltage_spread(np.repeat([2.0, 4.0, 6.0], 100)) == pytest.approx(2.0 / 6.0)
    assert voltage_spread(np.zeros(10)) == 1.0


def test_a_square_wave_on_a_fast_armature_is_aligned_at_no_lag() -> None:
    """The exact zero-order-hold run of ``tests/identify/test_one_command.py``'s plant (``u[k]`` acts on
    ``[t_k, t_{k+1})``: no lag; L/R 0.2 samples) under a +-6 V square wave at 2 Hz, logged at 1 kHz with a tenth
    of the loggers' noise. With the brush drop's current-sign column in the free search, its residual was the same
    (0.00127 A) at every lag from 0 to 0.875 samples and 225 times that at 1: under one command magnitude the sign
    is the command's on every held row, and with it the rows where the level changes are fitted at any lag. The
    plateau's end passed as a sharp minimum (a whole sample to its left lies outside the search), 0.81 was applied
    as 0.99 samples, the armature equation read 432 noise units and a thrust lag was named. The column is left out
    under one command magnitude (where a drop is a gain on the command anyway): the search is sharp at 0, the model
    at the noise and nothing is named."""
    t = np.arange(3000) * 1e-3
    res = diagnose(DCMotorPlant(P), step_log(6.0 * np.sign(np.sin(2 * np.pi * 2.0 * t) + 1e-9), 0.1))
    assert res.alignment is not None and res.alignment.identified and res.alignment.applied == 0.0
    assert res.verdict == []


def test_an_unidentified_timing_leaves_the_inductance_unresolved(rig: MotorParams) -> None:
    """A sub-sample timing error leaves ``-d dt R i'`` in the armature equation, like an ``L`` error: where the
    alignment is not identified, ``L`` is calibrated as a nuisance and never named."""
    log = generate(rig, RigSpec(seconds=0.3, rate=10000.0, seed=3))  # L/R = 4 samples: resolved when timed
    opt = DiagnoseOptions()
    sp = split(log, 0.1, opt.holdout_every)
    effects, pool = _pool(DCMotorPlant(rig), opt)
    noise = noise_levels(log)
    known, flat = (_explain(DCMotorPlant(rig), log, sp, effects, pool, noise, opt, False, None,
                            Alignment(0.0, 0.0, False, "rule", identified=ok))[0] for ok in (True, False))
    assert "L" not in known.unresolved and "not identifiable" in flat.unresolved["L"]
