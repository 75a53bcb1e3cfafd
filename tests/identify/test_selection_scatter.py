"""The selection's sampling scatter (ocp/identify/scatter.py, select._ms_sd) against Monte-Carlo oracles, and the
prior on constant errors (select._prefer_effects)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from ocp.identify.regression import Column, Design
from ocp.identify.scatter import independence
from ocp.identify.select import Fitted, _ms_sd, _prefer_effects


def _ar1(a: float, n: int, draws: int, rng: np.random.Generator) -> np.ndarray:
    """(draws, n) unit-variance AR(1) sequences with coefficient ``a``."""
    e = rng.standard_normal((draws, n + 200)) * np.sqrt(1 - a * a)
    return signal.lfilter([1.0], [1.0, -a], e, axis=1)[:, 200:]


@pytest.mark.parametrize("a", [0.0, 0.6, 0.9])
def test_independence_of_an_ar1_noise_is_its_closed_form(a: float) -> None:
    """AR(1): rho_k = a^|k|, so sum_k rho_k^2 = (1 + a^2) / (1 - a^2); measured over a mask of segments."""
    rng = np.random.default_rng(5)
    x = _ar1(a, 20000, 3, rng)
    mask = (np.arange(x.shape[1]) // 500) % 4 != 3  # training segments, as diagnose holds every 4th out
    got = independence(x, mask)
    assert got[0] == pytest.approx(np.full(3, (1 - a * a) / (1 + a * a)), rel=0.15)
    assert got[1] == pytest.approx(np.full(3, (1 - a) / (1 + a)), rel=0.15)  # sum_k a^|k|


def test_mean_square_scatter_matches_a_monte_carlo_of_signal_plus_correlated_noise() -> None:
    """var MS = 2 / n + 4 S / m for a fixed slow unexplained signal s (mean square S) plus unit noise: the empirical
    spread over 400 noise draws agrees within 15 %; the cross term (the signal times the noise) dominates."""
    rng = np.random.default_rng(9)
    n, a = 4000, 0.8
    s = 3.0 * np.sin(np.linspace(0, 40 * np.pi, n))  # S = 4.5
    noise = _ar1(a, n, 400, rng)
    ms = np.mean((s + noise) ** 2, axis=1)
    ind = independence(noise[:1], np.ones(n, bool))[:, 0]
    design = Design([Column("R", "R")], *[np.zeros((3, 1, 1))] * 2, *[np.zeros((3, 1))] * 2, np.zeros(3),
                    np.zeros(3), np.full(3, n), np.full(3, n), np.ones(3),
                    independence=np.repeat(ind[:, None], 3, axis=1))
    per_eq = np.full(3, np.sqrt(np.mean(s**2) + 1.0))
    sd = _ms_sd(design, Fitted((), (0,), np.zeros(1), 0.0, float(per_eq[0]), per_eq))
    assert sd[0] == pytest.approx(np.std(ms), rel=0.15)
    assert np.sqrt(2 / (n * ind[0])) < 0.5 * np.std(ms)  # the noise's own chi-square alone: far too narrow


def _fit(score: float, x: float) -> Fitted:
    return Fitted((), (0,), np.array([x]), 0.0, score, np.full(3, score))


def test_an_implausible_constant_yields_to_an_effect_that_fits_as_well() -> None:
    design = Design([Column("B", "B")], *[np.zeros((3, 1, 1))] * 2, *[np.zeros((3, 1))] * 2, np.zeros(3),
                    np.zeros(3), np.full(3, 100), np.full(3, 100), np.ones(3))
    far, near, effect = ("B", _fit(1.00, 2.5)), ("B", _fit(1.00, 0.4)), ("coulomb_friction", _fit(1.01, 0.0))
    assert [n for n, _ in _prefer_effects(design, [far, effect], 0.02)] == ["coulomb_friction", "B"]
    assert _prefer_effects(design, [("B", _fit(1.0, -0.6)), effect], 0.02)[0][0] == "coulomb_friction"
    assert [n for n, _ in _prefer_effects(design, [near, effect], 0.02)] == ["B", "coulomb_friction"]
    worse = ("coulomb_friction", _fit(1.5, 0.0))  # beyond the tie margin and the scatter: the constant stays
    assert [n for n, _ in _prefer_effects(design, [far, worse], 0.02)] == ["B", "coulomb_friction"]
