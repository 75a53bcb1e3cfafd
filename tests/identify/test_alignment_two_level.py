"""Alignment on a slow two-level command (a PRBS whose bits last many samples), on logs of the independent
proving ground (``tests/proving_ground``: its own physics, integrator and logger). Only the rare level changes
tell the lag there; the drive's dead band acts on each held level, so its term must not become a free column on
the rows where the level changes (which absorbed any sub-sample lag and left the minimum flat: no lag, or a
wrong one, and the resulting timing error blamed on ``L``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify.align import estimate
from ocp.logs import Log, log_from_arrays
from tests.proving_ground.cases import draw_motor
from tests.proving_ground.excite import open_loop
from tests.proving_ground.logger import Logger, record
from tests.proving_ground.physics import run


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
