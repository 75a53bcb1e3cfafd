"""The prior on constant errors judged with the fit's uncertainty (evidence.implausible_factor,
evidence.standard_error): the standard error against the scatter of least-squares fits over many noise draws,
rows repeated (correlated) counted once, and a factor at the prior's edge left to the data."""

from __future__ import annotations

import numpy as np

from ocp.identify.evidence import Fitted, implausible_factor, standard_error
from ocp.identify.regression import Column, Design

ROWS, REPEAT, DRAWS = 300, 4, 4000


def _design(a: np.ndarray, independence: float) -> Design:
    """Torque-equation-only design of columns ``a`` (N, 2) in noise units (``B``, ``c_tau``)."""
    g = np.zeros((3, 2, 2))
    g[0] = a.T @ a
    zero = np.zeros((3, 2))
    return Design([Column("B", "B"), Column("c_tau", "c_tau")], g, g, zero, zero, np.zeros(3), np.zeros(3),
                  np.full(3, a.shape[0]), np.full(3, a.shape[0]), np.ones(3),
                  independence=np.array([independence, 1.0, 1.0]))


def _columns() -> np.ndarray:
    w = np.linspace(-1.0, 1.0, ROWS) + 0.3 * np.sin(np.arange(ROWS))
    return np.column_stack([w, 0.8 * w * np.abs(w)])  # correlated, as B w and c_tau w|w| are


def test_the_standard_error_is_the_scatter_of_fits_over_noise_draws() -> None:
    a = _columns()
    rng = np.random.default_rng(0)
    fits = np.array([np.linalg.lstsq(a, rng.standard_normal(ROWS), rcond=None)[0] for _ in range(DRAWS)])
    f = Fitted(("B",), (0, 1), np.zeros(2), 0.0, 1.0, np.ones(3))
    se = [standard_error(_design(a, 1.0), f, j) for j in (0, 1)]
    # 4000 draws: an estimated standard deviation scatters by 1 / sqrt(2 * 4000) = 1.1 %; within three of those
    assert np.allclose(se, fits.std(axis=0), rtol=0.035)
    # each row repeated REPEAT times (one noise value each): a design that counts them all, scaled by its
    # independence 1 / REPEAT, gives the same standard error as the rows counted once
    rep = np.repeat(a, REPEAT, axis=0)
    assert np.allclose([standard_error(_design(rep, 1.0 / REPEAT), f, j) for j in (0, 1)], se, rtol=1e-9)
    # a residual twice the noise doubles it
    f2 = Fitted(("B",), (0, 1), np.zeros(2), 0.0, 2.0, np.array([2.0, 1.0, 1.0]))
    assert np.isclose(standard_error(_design(a, 1.0), f2, 0), 2 * se[0])


def test_a_factor_at_the_edge_of_the_prior_is_left_to_the_data() -> None:
    a = _columns()
    d = _design(a, 1.0)
    se = standard_error(d, Fitted(("B",), (0, 1), np.zeros(2), 0.0, 1.0, np.ones(3)), 0)

    def fit(x: float) -> Fitted:
        return Fitted(("B",), (0, 1), np.array([x, 0.0]), 0.0, 1.0, np.ones(3))

    # half the nominal minus one standard error: within reach of a factor of two
    assert implausible_factor(d, fit(-0.5 - se), "B") is None
    # beyond it by three standard errors: implausible, the fitted factor reported
    below = implausible_factor(d, fit(-0.5 - 3 * se), "B")
    assert below is not None and np.isclose(below, 0.5 - 3 * se)
    assert implausible_factor(d, fit(1.0 + se), "B") is None
    above = implausible_factor(d, fit(1.0 + 3 * se), "B")
    assert above is not None and np.isclose(above, 2.0 + 3 * se)


def test_an_interval_reaching_nominal_is_plausible() -> None:
    """A factor whose interval reaches past nominal is plausible, however far its point estimate (a 50 Hz log's B
    fitted at 1.25 +- 1.45, 11130)."""
    a = _columns()
    d = _design(a, 0.01)  # few independent rows: a wide interval
    f = Fitted(("B",), (0, 1), np.array([2.5, 0.0]), 0.0, 1.0, np.ones(3))
    assert 2 * standard_error(d, f, 0) > 2.5
    assert implausible_factor(d, f, "B") is None
    g = Fitted(("B",), (0, 1), np.array([-0.9, 0.0]), 0.0, 1.0, np.ones(3))
    assert implausible_factor(d, g, "B") is None
