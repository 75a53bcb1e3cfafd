"""The prior on constant errors in the selection (select._prefer_effects): a constant that would have to be off by
more than a factor of two yields to an effect that fits the held-out data as well."""

from __future__ import annotations

import numpy as np

from ocp.identify.evidence import Fitted
from ocp.identify.regression import Column, Design
from ocp.identify.select import _prefer_effects, _prior_note


def _design() -> Design:
    """A one-column design (``B``) with 100 held-out rows per equation: only its bookkeeping is used."""
    g, h = np.zeros((3, 1, 1)), np.zeros((3, 1))
    return Design([Column("B", "B")], g, g, h, h, np.zeros(3), np.zeros(3), np.full(3, 100), np.full(3, 100),
                  np.ones(3))


def _fit(score: float, x: float) -> Fitted:
    """A fit with held-out ``score`` whose only column (``B``) is off by the relative ``x``."""
    return Fitted((), (0,), np.array([x]), 0.0, score, np.full(3, score))


def _order(tried: list[tuple[str, Fitted]]) -> list[str]:
    return [n for n, _ in _prefer_effects(_design(), tried, 0.02)]


def test_an_implausible_constant_yields_to_an_effect_that_fits_as_well() -> None:
    effect = ("coulomb_friction", _fit(1.01, 0.0))
    assert _order([("B", _fit(1.0, 2.5)), effect]) == ["coulomb_friction", "B"]  # B at 3.5x nominal
    assert _order([("B", _fit(1.0, -0.6)), effect]) == ["coulomb_friction", "B"]  # B at 0.4x nominal
    assert _order([("B", _fit(1.0, 0.4)), effect]) == ["B", "coulomb_friction"]  # 1.4x: a plausible error
    assert _order([("B", _fit(1.0, -0.45)), effect]) == ["B", "coulomb_friction"]  # 0.55x: within the factor
    # beyond the tie (the margin and the score's scatter, 2 / sqrt(2 * 300) = 8 %): the constant stays first
    assert _order([("B", _fit(1.0, 2.5)), ("coulomb_friction", _fit(1.12, 0.0))]) == ["B", "coulomb_friction"]
    # a constant behind an effect is never promoted, and a plausible runner-up constant is left where it is
    assert _order([effect, ("B", _fit(1.02, 2.5))]) == ["coulomb_friction", "B"]


def test_the_ambiguity_reason_says_why_the_effect_was_preferred() -> None:
    assert "param:B would have to be 3.5 x its nominal" in _prior_note(_design(), _fit(1.0, 2.5),
                                                                         "coulomb_friction", "B")
    assert _prior_note(_design(), _fit(1.0, 0.3), "coulomb_friction", "B") == ""
    assert _prior_note(_design(), _fit(1.0, 2.5), "R", "B") == ""  # a constant adopted: no effect was preferred


def test_a_calibration_box_open_above_stops_at_the_implausible_factor() -> None:
    """``L`` free above nominal (a current filter could raise the apparent inductance, Design.above) is still
    calibrated at most to twice its nominal: one fold of a 10 kHz clean log (6056) put it at 4.5x, and the
    held-out error of that fold made a current offset look needed."""
    from ocp.identify.evidence import IMPLAUSIBLE_FACTOR
    from ocp.identify.lsq import bounds as _bounds

    d = _design()
    d.columns[0] = Column("L", "L")
    lo, hi = _bounds(d, [0], set(), 0.1, {"L": np.inf})
    assert lo[0] == -0.1 and hi[0] == IMPLAUSIBLE_FACTOR - 1.0
    lo, hi = _bounds(d, [0], set(), 0.1, {"L": 0.25})  # a finite widening below the cap is kept
    assert hi[0] == 0.35
    lo, hi = _bounds(d, [0], {"L"}, 0.1, {"L": np.inf})  # named: the named bounds
    assert (lo[0], hi[0]) == (-0.8, 3.0)
