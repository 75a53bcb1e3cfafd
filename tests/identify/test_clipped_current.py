"""A current clipped at its sensor's range (issue #11: rigs this project did not build; :mod:`ocp.identify.clipping`).

The blind rig (``bench/blind_check.py``) clips its current ADC on about one log in fifteen, and four of its seven
false angle ripples were among them. Here: clean logs of the independent proving ground (``tests/proving_ground``,
its own physics and logger) with the current clipped at 45 % of its peak. The seeds were picked where the clipped
rows, unhandled, named something (``bench/clipped_current.py`` runs all of them; its figures are in
docs/model-check-rules.md); since session 60's alignment (the lag read from the nearest whole sample) 162's,
unhandled, name nothing, and the counterfactual runs on the other three.
"""

from __future__ import annotations

import numpy as np
import pytest

import ocp.identify.holdout as holdout
from ocp.errors import LogError
from ocp.identify import diagnose
from ocp.identify.clipping import clipped
from ocp.logs import Log, log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case

SEEDS = (64, 79, 97, 162)
LEVEL = 0.45


def _clipped_log(seed: int) -> tuple[Log, DCMotorPlant]:
    case = make_case(seed)
    assert case.expected == set()  # clean
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    level = LEVEL * float(np.max(np.abs(c["current"])))
    log = log_from_arrays(t, c["voltage"], np.clip(c["current"], -level, level), c["thrust"], omega=c.get("omega"),
                          theta=c.get("theta"))
    return log, DCMotorPlant(MotorParams(**case.nominal))


@pytest.fixture(scope="module", params=SEEDS)
def clipped_case(request: pytest.FixtureRequest) -> tuple[Log, DCMotorPlant]:
    return _clipped_log(int(request.param))


def test_clipped_rows_are_found_and_said(clipped_case: tuple[Log, DCMotorPlant]) -> None:
    log, plant = clipped_case
    m = clipped(log.current)
    level = float(np.max(np.abs(log.current)))
    assert m.any() and np.all(np.abs(log.current[m]) == level)
    assert np.sum(np.abs(log.current) == level) == m.sum()  # every row at the range, and only those
    d = diagnose(plant, log)
    assert d.verdict == [], d.verdict
    (spot,) = [s for s in d.blind_spots if s["gap"] == "clipped_current"]
    assert spot["hidden"] == [] and f"{level:.4g} A" in spot["text"]


@pytest.mark.parametrize("seed", SEEDS[:3])
def test_unhandled_the_clipped_rows_are_named_as_physics(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    log, plant = _clipped_log(seed)
    never = lambda x: np.zeros(x.size, dtype=bool)  # noqa: E731
    monkeypatch.setattr(holdout, "clipped", never)  # (the split's and the equations' cut: .holdout.usable)
    assert diagnose(plant, log).verdict != []


def test_a_peak_or_a_coarse_plateau_is_not_clipping() -> None:
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 4.0, 4000)
    x = 3.0 * np.sin(2 * np.pi * t) + 0.02 * rng.standard_normal(t.size)
    assert not clipped(x).any()  # a noisy peak touches its top once
    q = np.round(x / 0.05) * 0.05  # quantised: the top level a few times, as often as the one under it
    assert not clipped(q).any()
    steps = np.round((np.repeat([0.0, 2.0, 1.0, 2.0], 1000) + 0.03 * rng.standard_normal(4000)) / 0.01) * 0.01
    assert not clipped(steps).any()  # a plateau at the top, its noise spread over levels
    cut = np.clip(x, -2.5, 2.5)  # the sensor's range
    assert np.array_equal(clipped(cut), np.abs(x) >= 2.5)


def test_a_log_clipped_until_nothing_is_left_is_refused_with_its_reason() -> None:
    """Proving ground 23018 (clean, 50 Hz PRBS, 509 rows) clipped at 45 % of its peak: 131 rows at the range, and
    with their low-pass transient (84 rows either side) cut, no row is left to fit on. Before: the noise levels were
    the mean of no rows (NaN) and a delay was named; now a LogError on the current says why."""
    log, plant = _clipped_log(23018)
    with pytest.raises(LogError) as err:
        diagnose(plant, log)
    assert err.value.field == "current" and f"fewer than {holdout.MIN_ROWS}" in str(err.value)


def test_usable_rows_are_counted_from_the_cut() -> None:
    """:func:`.holdout.usable` on a made-up current: a run of 5 rows at the range, cut with 3 rows either side, and
    the ends' transients; the masks left are counted here row by row."""
    n = 200
    current = np.sin(np.linspace(0.0, 3.0, n))
    current[100:105] = 1.5  # (the range: the top, five rows in a row)
    edge = np.zeros(n, bool)
    edge[:10] = edge[-10:] = True
    train, test = np.arange(n) % 4 != 0, np.arange(n) % 4 == 0
    kept, held, cut = holdout.usable(train, test, edge, current, 3)
    gone = edge.copy()
    gone[97:108] = True
    assert np.array_equal(cut, gone)
    assert np.array_equal(kept, train & ~gone) and np.array_equal(held, test & ~gone)
    with pytest.raises(LogError) as err:  # a short log: the transients alone leave too few held-out rows
        holdout.usable(train[:120], test[:120], np.r_[np.ones(50, bool), np.zeros(20, bool), np.ones(50, bool)],
                       np.sin(np.linspace(0.0, 3.0, 120)), 3)
    assert err.value.field == "t" and "5 to hold out" in str(err.value)
