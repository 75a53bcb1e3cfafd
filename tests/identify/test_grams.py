"""The Gram matrices every held-out score is built from (footprint.grams) against the plain sums they stand for."""

from __future__ import annotations

import numpy as np
import pytest

from ocp.identify import footprint
from ocp.identify.footprint import grams


@pytest.mark.parametrize("at_once", [1 << 15, 64])
@pytest.mark.parametrize("seed", range(5))
def test_grams_are_the_sums_over_each_set_of_rows(seed: int, at_once: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """Per set of rows (a boolean mask or an index array), per equation: ``A'A``, ``A'r`` and ``r'r`` summed row by
    row (the oracle: an explicit loop over rows), the Gram matrix exactly symmetric; whole, and summed over pieces
    of 64 rows (a set's rows copied out a piece at a time)."""
    monkeypatch.setattr(footprint, "ROWS_AT_ONCE", at_once)
    rng = np.random.default_rng(seed)
    n, q = 400, 7
    a_all = rng.normal(size=(3, q, n)) * rng.uniform(0.01, 100.0, q)[:, None]  # (3, Q, N) (badly scaled columns)
    tw = rng.normal(size=(3, n))
    rows = [rng.random(n) < 0.3, np.flatnonzero(rng.random(n) < 0.5), np.zeros(n, dtype=bool)]
    g, h, c = grams(a_all, tw, rows)
    assert g.shape == (3, 3, q, q) and h.shape == (3, 3, q) and c.shape == (3, 3)
    for k, m in enumerate(rows):
        idx = np.flatnonzero(m) if m.dtype == bool else m
        for e in range(3):
            ref_g = sum((np.outer(a_all[e, :, i], a_all[e, :, i]) for i in idx), np.zeros((q, q)))
            ref_h = sum((a_all[e, :, i] * tw[e, i] for i in idx), np.zeros(q))
            ref_c = sum((tw[e, i] ** 2 for i in idx), 0.0)
            assert np.allclose(g[k, e], ref_g, rtol=1e-12, atol=1e-9 * (1.0 + np.abs(ref_g).max()))
            assert np.allclose(h[k, e], ref_h, rtol=1e-12, atol=1e-9 * (1.0 + np.abs(ref_h).max()))
            assert np.isclose(c[k, e], ref_c, rtol=1e-12)
            assert np.array_equal(g[k, e], g[k, e].T)


def test_no_sets_of_rows() -> None:
    g, h, c = grams(np.ones((3, 2, 5)), np.ones((3, 5)), [])
    assert g.shape == (0, 3, 2, 2) and h.shape == (0, 3, 2) and c.shape == (0, 3)
