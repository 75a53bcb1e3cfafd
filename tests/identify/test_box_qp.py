"""The bounded least squares of the selection (boxqp.box_qp) against scipy's BVLS (the independent oracle)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from ocp.identify.boxqp import box_qp


def _objective(g: np.ndarray, h: np.ndarray, x: np.ndarray) -> float:
    return float(x @ g @ x - 2 * h @ x)


def _bvls(g: np.ndarray, h: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The oracle: scipy's BVLS on ``|R x - R^-T h|`` (``G = R'R``), the variables boxed to a point (``lo == hi``,
    which BVLS refuses) substituted at their value."""
    free = lo < hi
    ref = lo.copy()
    gf, hf = g[np.ix_(free, free)], h[free] - g[np.ix_(free, ~free)] @ lo[~free]
    r = np.linalg.cholesky(gf).T
    ref[free] = lsq_linear(r, np.linalg.solve(r.T, hf), bounds=(lo[free], hi[free]), method="bvls", tol=1e-14).x
    return ref


@pytest.mark.parametrize("seed", range(300))
def test_box_qp_matches_bvls(seed: int) -> None:
    rng = np.random.default_rng(seed)
    p = int(rng.integers(1, 16))
    a = rng.normal(size=(p + int(rng.integers(0, 20)), p)) * rng.uniform(0.1, 10.0, p)  # badly scaled columns
    b = rng.normal(size=a.shape[0]) * 3.0
    g, h = a.T @ a + 1e-9 * np.eye(p), a.T @ b
    base = rng.uniform(-2.0, 0.5, p)
    lo = np.where(rng.random(p) < 0.3, -np.inf, base)
    hi = np.where(rng.random(p) < 0.3, np.inf, base + rng.uniform(0.0, 2.0, p))
    ref = _bvls(g, h, lo, hi)
    for start in (None, np.linalg.solve(g, h), rng.normal(size=p) * 5):  # cold, unconstrained, anywhere
        x = box_qp(g, h, lo, hi, start)
        assert np.all(x >= lo) and np.all(x <= hi)
        assert _objective(g, h, x) <= _objective(g, h, ref) + 1e-9 * (1.0 + abs(_objective(g, h, ref)))
        assert np.allclose(x, ref, atol=1e-6 * (1.0 + np.abs(ref).max()))


def test_an_inner_minimum_is_the_unconstrained_solution() -> None:
    g, h = np.array([[2.0, 0.5], [0.5, 1.0]]), np.array([0.3, -0.2])
    assert np.allclose(box_qp(g, h, np.full(2, -10.0), np.full(2, 10.0)), np.linalg.solve(g, h))


def test_a_box_of_one_point() -> None:
    g, h = np.eye(3), np.array([5.0, -5.0, 0.1])
    lo, hi = np.array([1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0])
    assert np.allclose(box_qp(g, h, lo, hi), [1.0, -1.0, 0.1])


def test_a_pinned_variable_is_never_released() -> None:
    """A variable boxed to one point (``lo == hi``: a constant held at nominal beside its asymmetry) whose gradient
    points out of the box is on both bounds: releasing it stepped nowhere and held it again, and where its pull was
    the strongest the active set cycled on it to ``max_iter`` and never released the variable that had to move
    (here the second: the cold start holds it at 0, its minimum is at its upper bound 1)."""
    g, h = np.eye(3), np.array([5.0, 2.0, 0.5])
    lo, hi = np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 1.0])
    assert np.allclose(box_qp(g, h, lo, hi), [0.0, 1.0, 0.5])


@pytest.mark.parametrize("seed", range(100))
def test_box_qp_with_pinned_variables_matches_bvls(seed: int) -> None:
    """Random problems with some variables pinned (``lo == hi``), against BVLS on the others."""
    rng = np.random.default_rng(1000 + seed)
    p = int(rng.integers(2, 16))
    a = rng.normal(size=(p + int(rng.integers(0, 20)), p)) * rng.uniform(0.1, 10.0, p)
    b = rng.normal(size=a.shape[0]) * 3.0
    g, h = a.T @ a + 1e-9 * np.eye(p), a.T @ b
    lo = rng.uniform(-2.0, 0.5, p)
    hi = lo + rng.uniform(0.0, 2.0, p)
    pinned = rng.random(p) < 0.3
    pinned[int(rng.integers(p))] = True
    hi[pinned] = lo[pinned] = np.where(rng.random(p) < 0.5, 0.0, lo)[pinned]
    if pinned.all():
        hi[0] = lo[0] + 1.0
    ref = _bvls(g, h, lo, hi)
    for start in (None, np.linalg.solve(g, h), rng.normal(size=p) * 5):
        x = box_qp(g, h, lo, hi, start)
        assert np.all(x >= lo) and np.all(x <= hi)
        assert np.allclose(x, ref, atol=1e-6 * (1.0 + np.abs(ref).max()))
