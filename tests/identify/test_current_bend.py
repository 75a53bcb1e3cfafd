"""The raw rows' current quadrature and its ``current_bend`` nuisance against closed forms: a raw row's current is the
triangle's (1, 2, 1)/4 rule over its samples, which overstates the triangle's exact mean of a current bending between
the samples by ``Signals.bend``; the nuisance's torque column at one unit is ``k_t`` times that, so a current that
bends smoothly leaves a residual the column takes up at a coefficient of 1, and a current that steps (a fast
armature) one it does not take up (its box is 0..1). Low-passed rows have no bend."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from ocp.identify import columns
from ocp.identify.columns import nuisance_columns, raw_signals, signals
from ocp.logs import Log, log_from_arrays
from ocp.model.params import MotorParams

P = MotorParams(J=1e-4, B=1e-5, c_tau=1e-7, c_f=1e-5, k_t=0.02, k_e=0.02, R=0.5, L=1e-4)
DT = 1e-3  # [s]
N = 600


def _log(current: np.ndarray) -> Log:
    t = np.arange(current.size) * DT
    return log_from_arrays(t, np.zeros(t.size), current, np.zeros(t.size), omega=np.full(t.size, 20.0),
                           theta=20.0 * t)


def test_the_triangle_rows_bend_is_the_rules_error_on_a_sine() -> None:
    """Raw rows: the triangle over k-1 -> k+1 (weight ``1 - |t - t_k| / h``) of ``sin(w t)`` is
    ``sin(w t_k) 2 (1 - cos w h) / (w h)^2``; the rule less the bend is within 1 % of the rule's own error of it."""
    w = 2 * np.pi * 60.0  # [rad/s]: 17 samples a period, a current that bends hard between the samples
    t = np.arange(N) * DT
    i = np.sin(w * t)
    s = raw_signals(_log(i), 20.0 * t)
    exact = np.sin(w * t[:-1]) * 2 * (1 - np.cos(w * DT)) / (w * DT) ** 2
    assert s.bend is not None
    rule, fixed = (s.i - exact)[1:], (s.i - s.bend - exact)[1:]  # (the first row has no sample before it)
    assert np.max(np.abs(rule)) > 0.02  # the (1, 2, 1)/4 rule is 2 % of the amplitude off ...
    assert np.max(np.abs(fixed)) < 0.01 * np.max(np.abs(rule))  # ... and the bend takes up all but 1 % of that


def test_the_nuisance_takes_up_a_bending_current_and_not_a_stepping_one() -> None:
    """The torque residual a bending current leaves (``k_t`` (rule - exact mean)) is the nuisance's column times
    1 within 1 %; a current stepping at the samples (held levels, exact row means known) leaves a residual the
    column explains less than a tenth of."""
    t = np.arange(N) * DT
    w = 2 * np.pi * 60.0
    bending = np.sin(w * t)
    s = raw_signals(_log(bending), 20.0 * t)
    left = P.k_t * (s.i - np.sin(w * t[:-1]) * 2 * (1 - np.cos(w * DT)) / (w * DT) ** 2)
    col = nuisance_columns(P, s)["current_bend"][0]
    coef = float(col[1:] @ left[1:] / (col[1:] @ col[1:]))
    assert abs(coef - 1.0) < 0.01
    # a staircase: the current holds i_k over k -> k+1 (it settles at the start of each row): the triangle's exact
    # mean at k is (i_k-1 + i_k) / 2
    levels = np.random.default_rng(3).uniform(-1.0, 1.0, N)
    s = raw_signals(_log(levels), 20.0 * t)
    left = P.k_t * (s.i - 0.5 * (np.concatenate([levels[:1], levels[:-2]]) + levels[:-1]))
    col = nuisance_columns(P, s)["current_bend"][0]
    share = float((col[1:] @ left[1:]) ** 2 / (col[1:] @ col[1:]) / (left[1:] @ left[1:]))
    assert share < 0.1


def test_low_passed_rows_have_no_bend() -> None:
    t = np.arange(N) * DT
    s = signals(_log(np.sin(2 * np.pi * 60.0 * t)), P)
    assert s.bend is None and not np.any(nuisance_columns(P, s)["current_bend"])


def test_a_ripple_hidden_by_the_bent_current_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving-ground seed 12047 (a validation set; found in session 25): a 4-period ripple beside a thrust
    asymmetry logged at 100 Hz by an encoder, under steps. Both are named; without the nuisance (its column zero)
    the ripple is not (the test can fail)."""
    from bench.modelcheck import case_log
    from ocp.identify import diagnose
    from ocp.model.plant import DCMotorPlant
    from tests.proving_ground import make_case

    case = make_case(12047)
    plant = DCMotorPlant(MotorParams(**case.nominal))
    assert sorted(case.expected) == ["cogging", "thrust_asymmetry"]
    assert sorted(diagnose(plant, case_log(case)).verdict) == ["cogging", "thrust_asymmetry"]
    real = columns.nuisance_columns

    def unbent(p: MotorParams, s: columns.Signals) -> dict[str, np.ndarray]:
        out = real(p, s)
        return {**out, "current_bend": np.zeros_like(out["current_bend"])}

    monkeypatch.setattr(sys.modules["ocp.identify.regression"], "nuisance_columns", unbent)
    assert diagnose(plant, case_log(case)).verdict == ["thrust_asymmetry"]
