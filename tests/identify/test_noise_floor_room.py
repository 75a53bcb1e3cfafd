"""The noise floor (``DiagnoseOptions.noise_floor``, ``select._room``): an item is adopted only where it enters an
equation whose held-out RMS is above the floor, and the floor is the noise level itself. Hand-made regressions
(rows independent, residuals in noise units, 4000 rows a third held out)."""

from __future__ import annotations

import numpy as np

from ocp.identify import DiagnoseOptions
from ocp.identify.regression import Column, Design
from ocp.identify.select import select

EFFECT = "force_offset"


def _design(eq: int, signal: float, noise: float, other: float, seed: int = 5) -> Design:
    """Equation ``eq``'s residual ``signal x + noise e``, explained by EFFECT's column ``x``; the thrust equation
    (2, unless ``eq`` is 2) unit-free noise of RMS ``other`` that no column explains, beside a right ``c_f``."""
    n = 4000
    rng = np.random.default_rng(seed)
    x, e, u, z = rng.standard_normal((4, n))
    train, test = np.arange(n) % 3 != 0, np.arange(n) % 3 == 0
    g_tr, g_te = np.zeros((3, 2, 2)), np.zeros((3, 2, 2))
    h_tr, h_te, c_tr, c_te = np.zeros((3, 2)), np.zeros((3, 2)), np.zeros(3), np.zeros(3)
    parts = [(eq, np.column_stack([x, 0 * x]), signal * x + noise * e)]
    if eq != 2 and other > 0:
        parts.append((2, np.column_stack([0 * u, u]), other * z))
    for k, cols, y in parts:
        for g, h, c, rows in ((g_tr, h_tr, c_tr, train), (g_te, h_te, c_te, test)):
            g[k], h[k], c[k] = cols[rows].T @ cols[rows], cols[rows].T @ y[rows], y[rows] @ y[rows]
    live = np.array([k in {p[0] for p in parts} for k in range(3)], int)
    return Design([Column(EFFECT, "f0"), Column("c_f", "c_f")], g_tr, g_te, h_tr, h_te, c_tr, c_te,
                  live * int(train.sum()), live * int(test.sum()), np.ones(3))


def _adopted(d: Design, floor: float) -> tuple[str, ...]:
    return select(d, [EFFECT], tol=0.1, min_improvement=0.12, noise_floor=floor, max_items=3, margin=0.02).final.items


def test_an_item_is_not_adopted_for_an_equation_at_its_noise_while_another_is_above() -> None:
    d = _design(eq=1, signal=0.8, noise=0.45, other=1.5)  # armature at ~0.92 noise units, thrust at 1.5
    assert _adopted(d, DiagnoseOptions().noise_floor) == ()
    assert _adopted(d, 0.5) == (EFFECT,)  # (it would win: only the floor stops it)


def test_an_equation_just_above_its_noise_is_still_explained() -> None:
    d = _design(eq=0, signal=0.8, noise=0.75, other=0.0)  # torque at ~1.10 noise units, half of it the effect
    assert _adopted(d, DiagnoseOptions().noise_floor) == (EFFECT,)
