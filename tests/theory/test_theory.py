from fractions import Fraction

import numpy as np
import pytest
import sympy

from ocp.theory.normal_form import inverse_input
from ocp.theory.reversal import (
    BOUNDED_DISCONTINUOUS,
    CONTINUOUS,
    SMOOTH,
    UNBOUNDED,
    Monomial,
    R_m,
    ReversalRegularity,
    crossing_class,
    feasibility_bounds,
    in_feasibility_set,
    lemma1,
    lemma1_sufficient,
    min_sin_q,
    parse_regularity,
    regularity_label,
    table_one,
)

# The paper's Table I, as printed: (p, torque, current, voltage). "at least Ck" means >= Ck;
# "regular" is not a precise class and only says "at least continuous".
PAPER_TABLE = {
    1: ("unbounded", "unbounded", "unbounded"),
    2: ("bounded-discontinuous", "bounded-discontinuous", "unbounded"),
    3: ("continuous", "continuous", "unbounded"),
    4: (">=continuous", ">=continuous", "continuous"),
    5: (">=C1", ">=C1", "continuous"),
    7: (">=C2", ">=C2", ">=C1"),
}


def _matches(level: int, stated: str) -> bool:
    if stated.startswith(">="):
        return level >= parse_regularity(stated[2:])
    return level == parse_regularity(stated)


def test_table_one_agrees_with_paper_where_it_states_a_class():
    rows = table_one()
    assert [r.p for r in rows] == list(PAPER_TABLE)
    for row in rows:
        torque, current, voltage = PAPER_TABLE[row.p]
        assert row.r == row.p + 1
        assert _matches(row.torque, torque), row
        assert _matches(row.current, current), row
        if row.p == 4:
            # the exact lemma is sharper than the table: the voltage is smooth, not only continuous
            assert row.voltage == SMOOTH
        else:
            assert _matches(row.voltage, voltage), row


def test_exact_classes_where_paper_says_at_least():
    assert crossing_class(5).torque == 1
    assert crossing_class(7).torque == 2 and crossing_class(7).voltage == 1


def _sympy_class(a: int, e: Fraction, kmax: int = 6) -> int:
    """Independent oracle: one-sided limits of the derivatives of sign(s)^a |s|^e, by sympy."""
    s = sympy.symbols("s", positive=True)
    ee = sympy.Rational(e.numerator, e.denominator)
    right = s**ee  # s > 0
    left = (-1) ** a * s**ee  # value at -s, s > 0: derivatives pick up (-1)^j
    level = None
    for j in range(kmax + 1):
        lr = sympy.limit(sympy.diff(right, s, j), s, 0, "+")
        ll = sympy.limit((-1) ** j * sympy.diff(left, s, j), s, 0, "+")
        if not (lr.is_finite and ll.is_finite):
            return UNBOUNDED if j == 0 else j - 1
        if sympy.simplify(lr - ll) != 0:
            return BOUNDED_DISCONTINUOUS if j == 0 else j - 1
        level = j
    assert level is not None  # the loop ran (kmax >= 0) and went through
    return SMOOTH if level == kmax else level


@pytest.mark.parametrize("r", range(2, 14))
def test_lemma1_against_symbolic_limits(r):
    exact = lemma1(r)
    oracle = _sympy_class(r - 2, Fraction(r - 3, 2))
    assert exact == Monomial(r - 2, Fraction(r - 3, 2)).regularity()
    if exact >= 6:  # the oracle probes derivatives up to order 6
        assert oracle == SMOOTH or oracle >= 6
    else:
        assert exact == oracle, (r, exact, oracle)


@pytest.mark.parametrize("m", range(0, 6))
def test_rm_threshold_is_exact_lemma_bound(m):
    # r >= R_m always gives C^m; the largest r below R_m that is not 4q+1 does not
    for r in range(R_m(m), R_m(m) + 8):
        assert lemma1(r) >= m
    below = [r for r in range(2, R_m(m)) if not lemma1_sufficient(r, m)]
    assert below and all(lemma1(r) < m for r in below)
    for q in range(1, 5):
        assert lemma1(4 * q + 1) == SMOOTH and lemma1_sufficient(4 * q + 1, m)


def test_labels_round_trip():
    for level in (UNBOUNDED, BOUNDED_DISCONTINUOUS, CONTINUOUS, 1, 2, 7, SMOOTH):
        assert parse_regularity(regularity_label(level)) == level


def test_feasibility_boundary_is_inverse_at_bounds():
    k, ul, uh = 0.08, 3.0, 5.0
    yd = np.linspace(-50, 50, 101)
    yd = yd[yd != 0]
    lo, hi = feasibility_bounds(yd, k, ul, uh)
    np.testing.assert_allclose(inverse_input(yd, lo, k), -ul, rtol=1e-12)
    np.testing.assert_allclose(inverse_input(yd, hi, k), uh, rtol=1e-12)
    assert in_feasibility_set(yd, 0.5 * (lo + hi), k, ul, uh).all()
    assert not in_feasibility_set(yd, hi + 1e-6 + 1e-9 * np.abs(hi), k, ul, uh).any()
    assert not in_feasibility_set(np.array([0.0]), np.array([0.0]), k, ul, uh).any()


def test_sin_family_regularity_rule():
    # q=0 unreproducible, q=1 continuous current, q>=2 continuous voltage (Section IV-A)
    assert crossing_class(1).current == UNBOUNDED
    assert crossing_class(3).current == CONTINUOUS and crossing_class(3).voltage == UNBOUNDED
    assert crossing_class(5).voltage >= CONTINUOUS
    assert min_sin_q(ReversalRegularity.CONTINUOUS_VOLTAGE) == 2
    assert min_sin_q(ReversalRegularity.C1_VOLTAGE) == 3
    assert min_sin_q(ReversalRegularity.CONTINUOUS_CURRENT, voltage_driven=False) == 1
