"""A wrong viscous coefficient named by the held-out likelihood-ratio test on a short log (issue #11, session 11).

Hand-made from a clean proving-ground draw constructed for this test (``make_case(3123, kind="clean")``, a 100 Hz
tachometer log; never the reported nor the tuning seeds): its first half only, so that the torque equation's
held-out rows are few and correlated, and the datasheet ``B`` told 40 % too high (true = 0.6 nominal, as the
proving ground states a wrong constant). The former tests (each RMS against its own scatter, and the block test's
Student quantile over a handful of blocks) left it unnamed; ``evidence.ratio_z`` judges the fall against the
residual's own scatter. The same half log with the right ``B`` names nothing.
"""

from __future__ import annotations

import functools

import pytest

from ocp.identify import diagnose
from ocp.logs import Log, log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


@functools.cache
def _half() -> tuple[Log, dict[str, float]]:
    case = make_case(3123, kind="clean")
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    n = t.size // 2
    theta = c.get("theta")
    log = log_from_arrays(t[:n], c["voltage"][:n], c["current"][:n], c["thrust"][:n], omega=c["omega"][:n],
                          theta=None if theta is None else theta[:n])
    return log, dict(case.nominal)


@pytest.mark.parametrize(("error", "verdict"), [(-0.4, ["param:B"]), (0.0, [])])
def test_viscous_error_on_a_short_log(error: float, verdict: list[str]) -> None:
    log, nominal = _half()
    res = diagnose(DCMotorPlant(MotorParams(**{**nominal, "B": nominal["B"] / (1.0 + error)})), log)
    assert res.verdict == verdict
    if verdict:
        assert res.calibration["B"]["relative"] == pytest.approx(error, abs=0.12)
