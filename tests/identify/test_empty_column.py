"""A column is empty (its coefficient set to 0 after the fit: ``L`` far under a sample) only against the columns of its
own equations (:func:`ocp.identify.lsq.solve`, session 40).

The columns' norms span many decades by their units (a relative ``L`` correction beside an absolute thrust asymmetry
``dc_f`` in N s^2/rad^2). Judged against every column, adding a thrust column emptied an ``L`` that a current filter's
lag had widened and that the armature equation needed (proving ground 23144: that equation's held-out error rose
34-fold, the candidate was named on the thrust equation alone and a wrong round order followed). Oracle: the
equations share no column, so least squares separates by equation, and a column added to the thrust equation cannot
change the armature equation's fit. Hand-made regression (rows independent, residuals in noise units).
"""

from __future__ import annotations

import numpy as np

from ocp.identify.regression import Column, Design
from ocp.identify.select import fit_model


def _design(l_scale: float) -> Design:
    """Armature equation: residual ``2 x + e / 2`` explained by an ``L`` column ``l_scale x`` (``L`` unresolved, a
    free nuisance: its coefficient ``2 / l_scale`` is inside its box); thrust equation: residual ``3 z + e / 2``
    explained by an absolute thrust-asymmetry column ``1e9 z`` (coefficient 3e-9)."""
    n = 3000
    rng = np.random.default_rng(7)
    x, z, e1, e2 = rng.standard_normal((4, n))
    train, test = np.arange(n) % 3 != 0, np.arange(n) % 3 == 0
    q = 2
    g_tr, g_te = np.zeros((3, q, q)), np.zeros((3, q, q))
    h_tr, h_te, c_tr, c_te = np.zeros((3, q)), np.zeros((3, q)), np.zeros(3), np.zeros(3)
    parts = [(1, np.column_stack([l_scale * x, 0 * x]), 2.0 * x + 0.5 * e1),
             (2, np.column_stack([0 * z, 1e9 * z]), 3.0 * z + 0.5 * e2)]
    for k, cols, y in parts:
        for g, h, c, rows in ((g_tr, h_tr, c_tr, train), (g_te, h_te, c_te, test)):
            g[k], h[k], c[k] = cols[rows].T @ cols[rows], cols[rows].T @ y[rows], y[rows] @ y[rows]
    live = np.array([0, 1, 1])
    return Design([Column("L", "L"), Column("thrust_asymmetry", "dc_f")], g_tr, g_te, h_tr, h_te, c_tr, c_te,
                  live * int(train.sum()), live * int(test.sum()), np.ones(3),
                  unresolved={"L": "L/R far under a sample"})


def test_a_column_of_another_equation_does_not_empty_a_small_one() -> None:
    d = _design(1e-4)
    alone, beside = fit_model(d, [], 0.1), fit_model(d, ["thrust_asymmetry"], 0.1)
    assert abs(alone.coefficient(0) * 1e-4 - 2.0) < 0.05  # (the armature residual explained by L)
    assert beside.coefficient(0) == alone.coefficient(0)
    np.testing.assert_allclose(beside.per_eq[1], alone.per_eq[1], rtol=1e-9)
    assert beside.per_eq[1] < 0.6 and beside.per_eq[2] < 0.6  # (both equations down to their noise, 0.5)
