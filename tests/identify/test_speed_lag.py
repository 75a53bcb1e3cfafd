"""A speed read late is a nuisance of the equations, as a current read late is (issue #11, session 33).

Many loggers write only the speed they differenced from an encoder, not its angle. A backward difference over ``d``
samples is the mean speed over them, ``d / 2`` samples late; read as the speed at the instant, it left
``k_e (d dt / 2) w'`` in eq. dc_electrical, an apparent ``R`` error ``k_e k_t d dt / (2 J R)``, named as a wrong
constant (proving ground without the angle column: 37 false ``R`` over 800 logs). The ``speed_lag`` nuisance
(:func:`ocp.identify.columns.nuisance_columns`) takes it. Proving-ground seeds 195 (a clean 500 Hz log) and 26 (a
thrust asymmetry at 200 Hz), encoders differenced over two samples, diagnosed without their angle column.
"""

from __future__ import annotations

import sys
from typing import Any

import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _fitted_lag(seed: int, angle: bool, monkeypatch: pytest.MonkeyPatch) -> tuple[Any, list[str], float]:
    """The case, its verdict, and the speed lag [samples] the final model fitted."""
    module = sys.modules["ocp.identify.diagnose"]
    seen: dict[str, Any] = {}
    explain = module._explain

    def spy(*args: Any, **kwargs: Any) -> Any:
        seen["design"], seen["sel"] = out = explain(*args, **kwargs)
        return out

    monkeypatch.setattr(module, "_explain", spy)
    case = make_case(seed)
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case, angle=angle))
    (j,) = seen["design"].index("speed_lag")
    return case, res.verdict, seen["sel"].final.coefficient(j)


@pytest.mark.parametrize("seed", [195, 26])
def test_a_differenced_speed_without_its_angle_names_no_resistance(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """Oracle: the logger's own differencing span: the lag fitted is half of it, within a third of a sample (0.73 and
    0.88 for 1); before, ``R`` was named +11.8 and +11.4 % (``k_e k_t d dt / (2 J R)``: 12.6 and 11.3 %)."""
    case, verdict, lag = _fitted_lag(seed, False, monkeypatch)
    assert case.logger.speed == "encoder" and case.logger.diff_span == 2 and "param:R" not in case.expected
    assert sorted(verdict) == sorted(case.expected)
    assert lag == pytest.approx(case.logger.diff_span / 2, abs=0.3)


def test_no_speed_lag_where_the_angle_shows_the_speed(monkeypatch: pytest.MonkeyPatch) -> None:
    """With the angle logged the equations see the exact mean speeds between samples: nothing left to lag."""
    _, verdict, lag = _fitted_lag(195, True, monkeypatch)
    assert verdict == [] and abs(lag) < 0.3
