"""A wrong constant named on its estimate where the held-out blocks are too few to confirm its fall (issue #11,
session 55: :func:`ocp.identify.evidence.estimate_agrees`).

Proving-ground draw ``make_case(3224, kind="constant+one")`` (of the ``--kind constant+one`` set 3200..3399, never the
reported seeds 0..199): a 10 kHz tachometer step log of a motor with a thrust asymmetry whose ``B`` is 32 % above its
datasheet value. Freed beyond the tolerance, ``B`` takes the torque equation's held-out RMS from 1.77 to 1.25 noise
units, but the tachometer's low-passed rows make 9 held-out blocks only (t 2.6, under the one-sided 1 % quantile 2.9)
and the likelihood ratio reads z 1.4: the former tests missed it. Its estimate, +29 %, lies 5 standard errors beyond
the box, the blocks agree at 2.5 % and the torque equation is left at its noise. The oracle is the draw itself: the
error the proving ground put in the nominal constants, and the effect it added.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose, evidence
from ocp.logs import Log
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.identify.diagnosed import blind
from tests.proving_ground import make_case


@functools.cache
def _case(seed: int, kind: str | None = None) -> tuple[Any, Log]:
    case = make_case(seed, kind=kind) if kind else make_case(seed)
    return case, case_log(case)


def _diagnose(seed: int, kind: str | None = None, **told: float) -> Any:
    case, log = _case(seed, kind)
    return diagnose(DCMotorPlant(MotorParams(**{**case.nominal, **told})), log)


def test_viscous_error_named_on_its_estimate() -> None:
    case, _ = _case(3224, "constant+one")
    assert case.constant_error == {"B": pytest.approx(0.322, abs=0.005)} and case.logger.rate == 10000.0
    res = _diagnose(3224, "constant+one")
    assert sorted(res.verdict) == ["param:B", "thrust_asymmetry"]
    assert res.calibration["B"]["named"] and 0.2 < res.calibration["B"]["relative"] < 0.45  # (true: +32 %)


def test_without_the_estimate_test_it_is_missed(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(evidence, "estimate_agrees", lambda *a: False)
    assert _diagnose(3224, "constant+one").verdict == ["thrust_asymmetry"]


def test_told_the_true_value_nothing_more_is_named() -> None:
    case, _ = _case(3224, "constant+one")
    true_b = case.nominal["B"] * (1.0 + case.constant_error["B"])
    assert _diagnose(3224, "constant+one", B=true_b).verdict == ["thrust_asymmetry"]


def test_a_coarse_clean_log_keeps_its_bias_unnamed(monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving ground 6019: a clean 50 Hz log whose freed ``B`` reads 19 % low, 3.6 standard errors beyond the box,
    a bias of the coarse sampling; the held-out blocks agree only at the one-sided 5 % level (t 1.79 over 27 blocks),
    not at :data:`~ocp.identify.evidence.ESTIMATE_ALPHA`."""
    case, _ = _case(6019)
    assert not case.expected and case.logger.rate == 50.0
    assert _diagnose(6019).verdict == []
    monkeypatch.setattr(evidence, "ESTIMATE_ALPHA", 0.05)
    assert _diagnose(6019).verdict == ["param:B"]


def test_inductance_is_not_named_on_its_estimate() -> None:
    """Proving ground 23170: ``k`` 39 % off; freed, ``L`` reads 59 % low, 4.7 standard errors beyond its box, t 10.8
    for a fall of 1 %: the command timing and the current filter bias it beyond its standard error
    (:mod:`ocp.identify.inductance` judges ``L``)."""
    case, _ = _case(23170)
    assert set(case.expected) == {"param:k"}
    assert _diagnose(23170).verdict == ["param:k"]


def test_an_equation_left_above_its_noise_names_nothing_on_an_estimate(tmp_path: Path,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """The blind rig's 28 (``bench/blindrig``, written without reading the check; 286 Hz, a thrust asymmetry, every
    constant right): freed, ``B`` reads 39 % high, 3.9 standard errors beyond its box, the blocks agreeing (t 8.2
    over 466), for a fall of 3 % that leaves the torque equation at 1.38 noise units: a misfit the model lacks,
    which biases the estimate beyond its standard error."""
    res, truth = blind(28, tmp_path)
    assert truth["labels"] == ["thrust_asymmetry"] and res.verdict == ["thrust_asymmetry"]
    monkeypatch.setattr(evidence, "at_noise", lambda design, f: np.ones(3, dtype=bool))
    res, _ = blind(28, tmp_path)
    assert sorted(res.verdict) == ["param:B", "thrust_asymmetry"]


def test_an_estimate_just_beyond_its_box_is_a_bias_not_a_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The blind rig's 403 (500 Hz chirp, an angle ripple, every constant right): freed, ``R`` reads +11.9 %, 5.8
    standard errors beyond its box but only 1.9 % of nominal beyond it: a bias of the model's misfit, which
    :data:`~ocp.identify.evidence.ESTIMATE_MARGIN` keeps unnamed."""
    res, truth = blind(403, tmp_path)
    assert truth["labels"] == ["cogging"] and res.verdict == ["cogging"]
    monkeypatch.setattr(evidence, "ESTIMATE_MARGIN", 0.0)
    res, _ = blind(403, tmp_path)
    assert sorted(res.verdict) == ["cogging", "param:R"]
