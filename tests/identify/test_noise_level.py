"""An equation's noise level where the rich fit can scale it to zero (issue #11, session 8).

Proving-ground draw constructed for this test (``make_case(3005, kind="constant")``, never the reported seeds
0..199): a 10 kHz tachometer log whose command is ONE level (8.44 V from rest). A current offset's column is
then a constant, so it spans the command; the constants' columns span the nominal model's prediction (``R`` and
``L`` add up to ``R i_arm``, ``k`` gives ``k_e w``): the rich fit that sets the armature equation's noise level
reproduced its residual exactly, noise and all, and the equation's noise level came out at the rounding floor
(3.5e-11 V: the nominal model's held-out error 4e8 noise units, where every candidate's score is the same).
"""

from __future__ import annotations

import numpy as np

from ocp.identify.diagnose import _pool, split
from ocp.identify.predict import noise_levels
from ocp.identify.regression import build
from ocp.identify.result import DiagnoseOptions
from ocp.identify.select import fit_model
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def test_constant_command_keeps_the_armature_noise_level() -> None:
    case = make_case(3005, kind="constant")
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    assert np.ptp(log.voltage) == 0.0 and log.dt < 2e-4  # the one-level command at 10 kHz this guards
    p, opt = MotorParams(**case.nominal), DiagnoseOptions()
    sp = split(log, min(opt.segment_s, log.n * log.dt / (3 * opt.holdout_every)), opt.holdout_every)
    effects, _ = _pool(DCMotorPlant(p), opt)
    design = build(p, log, sp.train, sp.test, effects, noise_levels(log), raw_torque=True)
    # the armature residual the nominal model leaves at the logged current's noise: R sigma_i is 0.02 V here
    assert 1e-3 < design.sigma[1] < 1.0
    nominal = fit_model(design, [], opt.tolerance)
    assert nominal.per_eq[1] < 10.0  # held-out [noise units]: a model a few tens of per cent off, not 4e8
