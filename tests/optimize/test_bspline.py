"""The vectorised de Boor evaluation (ocp.optimize.bspline) against scipy's ``BSpline``, bit for bit.

Oracle: scipy's ``BSpline.__call__`` and ``BSpline.derivative()`` (the evaluation the flat plan used before, one
spline, phase and order at a time), on knot vectors like the flat program's (clamped, graded) and unclamped ones,
degrees 3 to 5, points inside, at every knot, at the ends and beyond them.
"""

import numpy as np
import pytest
from scipy.interpolate import BSpline

from ocp.optimize import bspline, flat


def _knot_vectors() -> list[tuple[np.ndarray, int]]:
    rng = np.random.default_rng(5)
    unclamped = np.sort(rng.uniform(-1.0, 2.0, 17))
    return [(flat.knots(8), 5), (flat.knots(20), 5), (unclamped, 5), (unclamped, 3),
            (np.concatenate([np.zeros(4), np.sort(rng.uniform(0.0, 1.0, 9)), np.ones(4)]), 4)]


@pytest.mark.parametrize("case", range(5))
def test_values_and_derivatives_are_scipys_bit_for_bit(case: int) -> None:
    """Three splines (phases) on one knot vector, each evaluated at its own points: the value and the first two
    derivatives (scipy's ``derivative()`` chain) equal scipy's to the last bit."""
    t, k = _knot_vectors()[case]
    rng = np.random.default_rng(case)
    n = t.size - k - 1
    coef = rng.standard_normal((3, n)) * 10.0 ** rng.uniform(-3, 3, (3, 1))
    lo, hi = t[k], t[n]
    x = np.concatenate([rng.uniform(lo, hi, 3000), t[k: n + 1], [lo - 0.1, hi + 0.1, np.nextafter(hi, lo)]])
    which = rng.integers(0, 3, x.size)
    kn = bspline.knots(t, k)
    ell, funcs = bspline.basis(kn, x, k - 2)
    chain = [BSpline(t, coef.T, k)]
    for _ in range(2):
        chain.append(chain[-1].derivative())
    for r in range(3):
        got = bspline.combine(kn, ell, funcs[r], bspline.windows(np.asarray(chain[r].c)[:n].T, k), which)
        for p in range(3):
            spline = BSpline(t, coef[p], k)
            expect = (spline.derivative(r) if r else spline)(x[which == p])
            np.testing.assert_array_equal(got[which == p], expect)


def test_repeated_interior_knots_are_refused() -> None:
    """A zero-length interior interval would divide by zero where scipy skips a term: refused, not mis-evaluated."""
    t = np.array([0, 0, 0, 0, 0.5, 0.5, 1, 1, 1, 1], float)
    with pytest.raises(ValueError, match="distinct interior knots"):
        bspline.knots(t, 3)
