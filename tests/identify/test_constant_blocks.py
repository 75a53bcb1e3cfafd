"""A wrong viscous coefficient named on paired held-out evidence (issue #11, session 8).

Proving-ground draw constructed for this test (``make_case(3051, kind="constant")``, never the reported seeds
0..199 nor the tuning seeds 1000..1299): a 100 Hz encoder log (chirp, steps, PI) of a motor whose ``B`` is 36 %
below its datasheet value. Freeing ``B`` lowers the torque equation's held-out RMS by 19 %, where the unpaired
test (each RMS held to its own sampling noise over ~30 independent torque rows) needs ~26 %; but the two models
are nested and scored on the same rows: block by block (10 held-out blocks) the squared error falls every time,
3.5 standard errors of the blocks' own scatter. (Those figures predate session 10's exact current-lag column, with
which the fall is 29 % and the unpaired test passes as well; the paired test's own case is now seed 3117.)
"""

from __future__ import annotations

import pytest

from ocp.identify import diagnose
from ocp.identify.align import estimate
from ocp.identify.diagnose import _pool, split
from ocp.identify.evidence import beyond_scatter, block_t
from ocp.identify.predict import noise_levels
from ocp.identify.realign import realign
from ocp.identify.regression import build
from ocp.identify.result import DiagnoseOptions
from ocp.identify.select import fit_model
from ocp.logs import Log, log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _log(seed: int) -> tuple[Log, MotorParams, dict[str, float]]:
    case = make_case(seed, kind="constant")
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    return log, MotorParams(**case.nominal), case.constant_error


def test_viscous_error_named_on_paired_blocks() -> None:
    log, p, error = _log(3051)
    assert error["B"] == pytest.approx(-0.36, abs=0.01)
    res = diagnose(DCMotorPlant(p), log)
    assert res.verdict == ["param:B"]
    assert res.calibration["B"]["relative"] == pytest.approx(-0.36, abs=0.08)


@pytest.mark.parametrize("seed", [pytest.param(3117, marks=pytest.mark.xfail(
    strict=True, reason="session 14's proving ground: B's paired fall is 9.7 % of the RMS, under the 10 % asked"))])
def test_unpaired_test_alone_misses_it(seed: int) -> None:
    """What the paired test adds: the unpaired one does not pass, the blocks agree beyond 3 standard errors.
    (On 3051 the unpaired test passes too since session 10, when the current sensor's lag column became the
    filter's exact inverse and B's fall grew to 29 %; ``make_case(3117, kind="constant")``, B 31 % above its
    datasheet value, was this class until session 14. On the proving ground whose rig follows its equations
    (session 14) its blocks still agree (t = 4.6 over 28 blocks) but the fall is 9.7 % of the RMS, under the 10 %
    the paired test also asks, and B is missed; no draw of 3100..3373 is of the class: unpaired test failing,
    paired naming B.)"""
    raw, p, error = _log(seed)
    assert error["B"] == pytest.approx(0.31, abs=0.01)
    opt = DiagnoseOptions()
    log = realign(raw, estimate(raw, opt.max_logging_skew).samples)  # as diagnose aligns it
    sp = split(raw, min(opt.segment_s, log.n * log.dt / (3 * opt.holdout_every)), opt.holdout_every)
    effects, _ = _pool(DCMotorPlant(p), opt)
    design = build(p, log, sp.train, sp.test, effects, noise_levels(log), raw_torque=True)
    before, after = fit_model(design, [], opt.tolerance), fit_model(design, ["B"], opt.tolerance)
    assert not beyond_scatter(design, before, after)
    t, blocks = block_t(design, before, after)
    assert blocks >= 8 and t[0] > 3.0
    assert diagnose(DCMotorPlant(p), raw, DiagnoseOptions(cross_validate=False)).verdict == ["param:B"]
    # (the single split's rows: under the default cross-validation, session 11, every row is held out once, the
    # fall pooled over all of them is 5 % and Coulomb friction fits them better than B: B is missed on this log)
