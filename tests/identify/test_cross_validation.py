"""Cross-validated scores (regression.Design.g_fold, select.fit_model): every class of held-out segments in turn,
checked against a brute-force K-fold least squares on the rows themselves (the independent oracle)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ocp.identify.evidence import Fitted, beyond_scatter, block_t, ratio_z
from ocp.identify.lsq import solve
from ocp.identify.regression import Column, Design, _blocks
from ocp.identify.select import fit_model

N, K = 600, 3


def _rows(seed: int) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Weighted columns (3, N, 2) (a B error and a force offset: both unbounded at these sizes), targets (3, N)
    with 3 % of B and an offset of 0.3 in noise of unit RMS, and K folds of 50-row segments."""
    rng = np.random.default_rng(seed)
    a = np.zeros((3, N, 2))
    a[0, :, 0] = np.sin(np.linspace(0, 9, N)) * 5  # B w, torque equation
    a[2, :, 1] = 1.0  # force offset, thrust equation
    t = np.einsum("enq,q->en", a, [0.03, 0.3]) + rng.normal(size=(3, N))
    folds = [(np.arange(N) // 50) % K == k for k in range(K)]
    return a, t, folds


def _design(a: np.ndarray, t: np.ndarray, folds: list[np.ndarray]) -> Design:
    g, h, c = np.einsum("enq,enr->eqr", a, a), np.einsum("enq,en->eq", a, t), np.einsum("en,en->e", t, t)
    per_fold = [_blocks(m, 40) for m in folds]
    blocks = [b for bs in per_fold for b in bs]
    return Design([Column("B", "B"), Column("force_offset", "f0")], g, g, h, h, c, c, np.full(3, N), np.full(3, N),
                  np.ones(3), g_blocks=np.stack([np.einsum("enq,enr->eqr", a[:, b], a[:, b]) for b in blocks]),
                  h_blocks=np.stack([np.einsum("enq,en->eq", a[:, b], t[:, b]) for b in blocks]),
                  c_blocks=np.stack([np.einsum("en,en->e", t[:, b], t[:, b]) for b in blocks]),
                  g_fold=np.stack([np.einsum("enq,enr->eqr", a[:, m], a[:, m]) for m in folds]),
                  h_fold=np.stack([np.einsum("enq,en->eq", a[:, m], t[:, m]) for m in folds]),
                  c_fold=np.stack([np.einsum("en,en->e", t[:, m], t[:, m]) for m in folds]),
                  n_fold=np.array([np.full(3, int(m.sum())) for m in folds]),
                  block_fold=np.array([k for k, bs in enumerate(per_fold) for _ in bs]))


def _oracle(a: np.ndarray, t: np.ndarray, folds: list[np.ndarray], cols: list[int]) -> np.ndarray:
    """(3,) held-out RMS per equation: for each fold, the columns ``cols`` fitted by least squares on every other
    row (all equations stacked), its squared error on the fold's rows summed, over all rows."""
    sse = np.zeros(3)
    for m in folds:
        x = np.linalg.lstsq(a[:, ~m][:, :, cols].reshape(-1, len(cols)), t[:, ~m].ravel(), rcond=None)[0] \
            if cols else np.zeros(0)
        sse += np.sum((t[:, m] - a[:, m][:, :, cols] @ x) ** 2, axis=1)
    return np.sqrt(sse / N)


def test_the_cross_validated_score_is_the_k_fold_held_out_error() -> None:
    a, t, folds = _rows(3)
    d = _design(a, t, folds)
    for items, cols in (((), [0]), (("force_offset",), [0, 1])):
        f = fit_model(d, items, tol=0.5)  # B refined within 50 %: its 3 % stays inside the box
        assert np.allclose(f.per_eq, _oracle(a, t, folds, cols), rtol=1e-9)
        assert np.isclose(f.score, np.sqrt(np.mean(f.per_eq ** 2)), rtol=1e-12)
        assert len(f.folds) == K
        # the coefficients are fitted on all rows
        x_all = np.linalg.lstsq(a[:, :, cols].reshape(-1, len(cols)), t.ravel(), rcond=None)[0]
        assert np.allclose([f.coefficient(j) for j in cols], x_all, rtol=1e-9)


def test_the_paired_tests_use_each_folds_own_fit() -> None:
    a, t, folds = _rows(4)
    d = _design(a, t, folds)
    before, after = fit_model(d, (), tol=0.5), fit_model(d, ("force_offset",), tol=0.5)
    # per block, the fall of the squared error with each fold's own fits, by hand
    per_block: list[np.ndarray] = []  # (3,) per block: each equation's fall
    dd = np.zeros(3)
    for m in folds:
        xb = np.linalg.lstsq(a[0, ~m][:, [0]], t[0, ~m], rcond=None)[0]  # before: B alone (torque rows only)
        xa = np.linalg.lstsq(a[:, ~m].reshape(-1, 2), t[:, ~m].ravel(), rcond=None)[0]
        dd += np.sum((a[:, m] @ xa - a[:, m][:, :, [0]] @ xb) ** 2, axis=1)  # the prediction's change
        for b in _blocks(m, 40):
            eb = np.sum((t[:, b] - a[:, b][:, :, [0]] @ xb) ** 2, axis=1)
            ea = np.sum((t[:, b] - a[:, b] @ xa) ** 2, axis=1)
            per_block.append(eb - ea)
    falls = np.array(per_block)[:, 2]  # the offset's thrust equation
    want = falls.mean() / falls.std(ddof=1) * np.sqrt(len(falls))
    t_stat, nb = block_t(d, before, after)
    assert nb == len(falls)
    assert np.isclose(t_stat[2], want, rtol=1e-9)
    # the likelihood ratio: the held-out squared error's fall over its scatter, the prediction's change by hand
    fall = (_oracle(a, t, folds, [0]) ** 2 - _oracle(a, t, folds, [0, 1]) ** 2) * N
    want_z = fall[2] / (2.0 * after.per_eq[2] * np.sqrt(dd[2])) / np.sqrt(K)  # (one fold's rows: Design.n_held)
    z = ratio_z(d, before, after)
    assert np.isclose(z[2], want_z, rtol=1e-9) and want_z > 2.0 and z[1] == 0.0


def test_a_fall_counts_alone_only_in_an_equation_the_item_enters() -> None:
    """A force offset (thrust equation) refits the shared constants; a fall it brings to the torque equation that
    way is not its own evidence (evidence.beyond_scatter with ``items``)."""
    a, t, folds = _rows(5)
    d = replace(_design(a, t, folds), independence=np.array([1.0, 1.0, 0.01]))  # pooled scatter: 33 %
    per_eq = np.array([1.5, 1.0, 1.0]), np.array([1.2, 1.0, 1.0])  # the torque equation -20 %
    before, after = (Fitted(items, cols, np.zeros(len(cols)), 0.0, float(np.sqrt(np.mean(e ** 2))), e)
                     for items, cols, e in (((), (0,), per_eq[0]), (("force_offset",), (0, 1), per_eq[1])))
    assert beyond_scatter(d, before, after)  # any equation: the torque rows' fall passes
    assert not beyond_scatter(d, before, after, ("force_offset",))  # its own (thrust) equation did not move
    assert beyond_scatter(d, before, after, ("B",))  # an item of the torque equation would have it


def test_the_memo_serves_a_fit_again_and_never_across_a_change_of_the_boxes() -> None:
    """:func:`ocp.identify.lsq.solve` keeps its fits in the design's memo: the same call gives the same fit (and
    the folds the same designs); a box widened afterwards (``slack``, ``above``, ``unresolved``, as
    :mod:`ocp.identify.inductance` and ``diagnose`` do on a built design) gives the fit a fresh design gives, not the
    stored one; a design made by ``replace`` starts with an empty memo."""
    a, t, folds = _rows(3)
    d = _design(a, t, folds)
    tight = solve(d, [0], set(), 0.01)  # B's 3 % error held at the 1 % box
    assert solve(d, [0], set(), 0.01) is tight and d.fold(1) is d.fold(1)
    assert tight.x[0] == np.float64(0.01)
    for change in ({"slack": {"B": 0.5}}, {"above": {"B": 0.5}}, {"unresolved": {"B": "not resolved"}}):
        d = _design(a, t, folds)
        assert solve(d, [0], set(), 0.01).x[0] == tight.x[0]
        for name, value in change.items():
            getattr(d, name).update(value)
        fresh = solve(replace(d), [0], set(), 0.01)
        assert not replace(d).memo
        assert fresh.x[0] > 0.02  # (the widened box lets B reach its 3 %)
        assert solve(d, [0], set(), 0.01).x[0] == fresh.x[0]


def test_a_fit_started_near_its_first_columns_fit_is_the_same_fit() -> None:
    """``solve(..., near=...)`` starts the box QP at the fit of the first columns alone (the shape search's base
    model): the minimum is the one a cold start finds (the bound of B binds in both)."""
    a, t, folds = _rows(5)
    for tol in (0.01, 0.5):
        cold = solve(_design(a, t, folds), [0, 1], set(), tol)
        d = _design(a, t, folds)
        warm = solve(d, [0, 1], set(), tol, near=solve(d, [0], set(), tol))
        assert np.allclose(warm.x, cold.x, rtol=1e-12, atol=0) and warm.train_cost == pytest.approx(cold.train_cost)
    assert cold.x[0] < 0.5 and solve(_design(a, t, folds), [0, 1], set(), 0.01).x[0] == np.float64(0.01)
