"""The selection's backward pass over effects (``select.select``): a greedy first pick that stood for a mix of the
items adopted after it is tested again beside them and dropped. A hand-made regression (thrust equation only, rows
independent, residual in noise units): the true residual is ``5 x1 + 5 x2`` plus unit noise; a wrong effect's
column is ``0.7 x1 + 0.7 x2`` plus a little of its own, so it explains more than either true column alone and is
adopted first."""

from __future__ import annotations

import numpy as np

from ocp.identify.regression import Column, Design
from ocp.identify.select import select

TRUE = ("force_offset", "thrust_lag")
WRONG = "thrust_asymmetry"


def _design(n: int = 4000, seed: int = 11) -> Design:
    rng = np.random.default_rng(seed)
    x1, x2, own, u = rng.standard_normal((4, n))
    y = 5.0 * x1 + 5.0 * x2 + rng.standard_normal(n)
    cols = np.column_stack([0.7 * x1 + 0.7 * x2 + 0.3 * own, x1, x2, u])  # (n, 4): WRONG, TRUE, a right c_f
    train, test = np.arange(n) % 3 != 0, np.arange(n) % 3 == 0

    def gram(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        g, h, c = np.zeros((3, 4, 4)), np.zeros((3, 4)), np.zeros(3)
        g[2], h[2], c[2] = cols[rows].T @ cols[rows], cols[rows].T @ y[rows], y[rows] @ y[rows]
        return g, h, c

    (gtr, htr, ctr), (gte, hte, cte) = gram(train), gram(test)
    counts = lambda rows: np.array([0, 0, int(rows.sum())])  # noqa: E731
    columns = [Column(WRONG, "dc_f"), Column(TRUE[0], "f0"), Column(TRUE[1], "tau"), Column("c_f", "c_f")]
    return Design(columns, gtr, gte, htr, hte, ctr, cte, counts(train), counts(test), np.ones(3))


def test_a_first_pick_standing_for_the_later_items_is_dropped() -> None:
    sel = select(_design(), [WRONG, *TRUE], tol=0.1, min_improvement=0.12, noise_floor=1.0, max_items=4, margin=0.02)
    assert sel.steps[0].adopted == WRONG  # (the greedy pick: the class this guards)
    assert set(sel.final.items) == set(TRUE), sel.final.items
    assert sel.dropped == [WRONG]
    assert abs(sel.final.score - 1.0) < 0.1  # the two true columns leave the unit noise


def test_effects_needed_beside_each_other_are_kept() -> None:
    sel = select(_design(), list(TRUE), tol=0.1, min_improvement=0.12, noise_floor=1.0, max_items=4, margin=0.02)
    assert set(sel.final.items) == set(TRUE) and sel.dropped == []


def test_a_drop_whose_refit_the_catalogue_refuses_is_not_made() -> None:
    """Where the model without the first pick is unphysical (an effect fitted outside its catalogue range: on
    proving-ground draw 6050 a Stribeck level of 3.4e4 N m, and building the calibrated plant raised), the first
    pick is kept: a refit the catalogue refuses is no better explanation."""
    physical = lambda f: WRONG in f.items or len(f.items) < 2  # noqa: E731  (the true pair alone: refused)
    sel = select(_design(), [WRONG, *TRUE], tol=0.1, min_improvement=0.12, noise_floor=1.0, max_items=4, margin=0.02,
                 physical=physical)
    assert sel.steps[0].adopted == WRONG
    assert WRONG in sel.final.items and sel.dropped == []
