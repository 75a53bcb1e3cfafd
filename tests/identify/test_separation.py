"""The separation criterion of the experiment design (``ocp/identify/separation.py``) against oracles: the
raw separation is the noise-weighted distance of two independently integrated responses (scipy's Radau); a
rival that may refit the one constant that differs explains the difference away; under a tight prior
(nothing may move) all of it stays; ``Phi(-z/2)`` is the likelihood-ratio test's error rate (Monte Carlo)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify.separation import Rival, confusion, pair_separations, simulate
from ocp.model.params import load_params
from ocp.model.plant import DCMotorPlant
from ocp.simulate.open_loop import simulate as radau

T = np.arange(0.0, 0.6, 1e-3)
V = 6.0 * np.sin(2 * math.pi * 1.5 * T) + 2.0 * np.sin(2 * math.pi * 4.0 * T)
SIGMA = np.array([0.5, 0.01, 0.005])  # omega [rad/s], current [A], thrust [N]


def _plants() -> tuple[DCMotorPlant, DCMotorPlant]:
    p = load_params("paper-rig")
    return DCMotorPlant(p), DCMotorPlant(p.model_copy(update={"B": 1.3 * p.B}))


def test_raw_separation_is_the_weighted_distance_of_independent_simulations() -> None:
    a, b = _plants()
    z, rms = pair_separations([Rival("a", (), a), Rival("b", (), b)], T, V, SIGMA, rate=1e3, tolerance=None)
    ys = []
    for plant in (a, b):  # Radau on the held voltage, sampled on T
        # a held sample acts like the smooth signal half a sample late (error O(dt^2) on this slow voltage)
        tr = radau(plant, T, np.interp(T - 0.5e-3, T, V), [0.0, 0.0], rtol=1e-7, atol=1e-9)
        ys.append(np.vstack([tr.x[0], tr.x[1], tr.thrust]))
    d = (ys[0] - ys[1]) / SIGMA[:, None]
    assert z["a vs b"] == pytest.approx(float(np.linalg.norm(d)), rel=0.03)
    assert rms["a vs b"] == pytest.approx(float(np.sqrt(np.mean(d * d))), rel=0.03)
    ours = simulate(a, T, V)
    assert np.max(np.abs(ours[0] - ys[0][0])) < 0.02 * np.max(np.abs(ys[0][0]))


def test_a_rival_that_may_refit_the_differing_constant_explains_it_away() -> None:
    a, b = _plants()
    raw, _ = pair_separations([Rival("a", (), a), Rival("b", (), b)], T, V, SIGMA, 1e3, None)
    free, _ = pair_separations([Rival("a", ("param:B",), a), Rival("b", ("param:B",), b)], T, V, SIGMA, 1e3, 0.10)
    boxed, _ = pair_separations([Rival("a", (), a), Rival("b", (), b)], T, V, SIGMA, 1e3, 1e-6)
    assert raw["a vs b"] > 20
    assert free["a vs b"] < 0.05 * raw["a vs b"]  # a 30 % B change, refitted (linearised: a small remainder)
    assert boxed["a vs b"] == pytest.approx(raw["a vs b"], rel=1e-3)  # nothing may move: nothing explained


def test_confusion_is_the_likelihood_ratio_test_error_rate() -> None:
    rng = np.random.default_rng(0)
    for z in (0.5, 2.0, 4.0):
        x = rng.standard_normal(400_000)  # the statistic under the first hypothesis (mean 0; the other: z)
        assert confusion(z) == pytest.approx(float(np.mean(x > z / 2)), abs=3e-3)
