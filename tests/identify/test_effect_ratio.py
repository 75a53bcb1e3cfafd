"""An effect named by the torque equation's held-out likelihood ratio (issue #11, session 12).

On fast, short logs the torque rows are few and correlated (the speed view remembers a rotor time constant of
hundreds of samples): one equation's held-out RMS is then held to ``sqrt(2 / n_e)`` over a handful of
independent rows, and an effect that cut the torque equation from 1.98 to 0.12 noise units (Stribeck friction,
10 kHz) or by 97 % (Coulomb friction, 10 kHz; tuning seed 2240) was never named. The likelihood ratio
(:func:`ocp.identify.evidence.ratio_z`) judges the fall against the residual's own scatter along the change, as it
did for constants, at a tenth of a constant's level (:data:`ocp.identify.evidence.EFFECT_ALPHA`: a round tries
about ten effects). Hand-made regressions: the torque equation alone, 6000 rows a third held out, independent in
a fraction ``q`` (two independent held-out rows), its residual ``signal x + noise e``, ``x`` the effect's column.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify import DiagnoseOptions, diagnose
from ocp.identify.evidence import beyond_scatter, ratio_z
from ocp.identify.regression import Column, Design
from ocp.identify.select import fit_model, select
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case

EFFECT = "coulomb_friction"
HELD = 2000
Q = 2 / HELD


def _design(signal: float, noise: float, seed: int = 3) -> Design:
    rng = np.random.default_rng(seed)
    n = 3 * HELD
    x, e = rng.standard_normal((2, n))
    y = signal * x + noise * e
    test = np.arange(n) % 3 == 0
    g, h, c = (np.zeros((2, 3, 2, 2)), np.zeros((2, 3, 2)), np.zeros((2, 3)))
    for k, rows in enumerate((~test, test)):  # (a right J beside it: a column of zeros)
        g[k, 0, 0, 0], h[k, 0, 0], c[k, 0] = x[rows] @ x[rows], x[rows] @ y[rows], y[rows] @ y[rows]
    live = np.array([1, 0, 0])
    return Design([Column(EFFECT, "tau_c"), Column("J", "J")], g[0], g[1], h[0], h[1], c[0], c[1],
                  live * int((~test).sum()), live * HELD, np.ones(3), independence=np.array([Q, 1.0, 1.0]))


def _chosen(d: Design) -> tuple[str, ...]:
    opt = DiagnoseOptions()
    return select(d, [EFFECT], 0.1, opt.min_improvement, opt.noise_floor, 3, opt.ambiguity_margin).final.items


def test_an_effect_whose_fall_is_not_beyond_its_rms_scatter_wins_by_the_likelihood_ratio() -> None:
    d = _design(signal=math.sqrt(1 - 0.1**2), noise=0.1)  # torque at 1 noise unit, 99 % of its variance the effect's
    before, after = fit_model(d, [], 0.1), fit_model(d, [EFFECT], 0.1)
    assert 1 - after.per_eq[0] / before.per_eq[0] == pytest.approx(0.9, abs=0.02)
    assert not beyond_scatter(d, before, after, (EFFECT,))  # (over two rows it needs a fall of 2 / sqrt(2 n_e) = 1)
    assert ratio_z(d, before, after)[0] > 5.0
    assert _chosen(d) == (EFFECT,)


def test_a_material_fall_within_the_ratios_scatter_is_not_named() -> None:
    """A 20 % fall (material: over the 12 % an effect needs) that two independent rows cannot tell from chance."""
    d = _design(signal=0.6, noise=0.8)
    before, after = fit_model(d, [], 0.1), fit_model(d, [EFFECT], 0.1)
    assert 1 - after.per_eq[0] / before.per_eq[0] == pytest.approx(0.2, abs=0.03)
    assert ratio_z(d, before, after)[0] < 1.0
    assert _chosen(d) == ()


def test_coulomb_friction_on_a_short_10khz_log_is_named() -> None:
    """Tuning seed 2240: Coulomb friction beside a dead band, 10 kHz, 0.6 s; the friction cut the torque equation
    by 97 % over one or two independent rows (tau_m of hundreds of samples) and was not named before."""
    case = make_case(2240)
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    assert sorted(diagnose(DCMotorPlant(MotorParams(**case.nominal)), log).verdict) == sorted(case.expected)
    assert "coulomb_friction" in case.expected and case.logger.rate == 10000.0
