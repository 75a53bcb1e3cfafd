"""Materiality on the rows a banded effect acts on (footprint.Footprints, evidence.band_score): a Stribeck
band acts near zero speed only, so its fall of the held-out error is judged there too, not only on the whole log's
score, which the rows it cannot touch dilute. Checked against a brute-force K-fold least squares on the rows
themselves (the independent oracle), and on rows whose friction acts on 3 % of them."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ocp.identify.evidence import band_alike, band_fall, band_score, is_material, off_band_fall
from ocp.identify.footprint import FOOTPRINT, Footprints, grams
from ocp.identify.regression import Column, Design
from ocp.identify.select import _challenge, fit_model

N, K = 1200, 3


def _rows(seed: int, level: float) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Weighted torque-equation columns (3, N, 2): a B error (``B w`` over a slow sine) and a Stribeck band that
    acts on the rows near the sine's zero crossings only (a Gaussian of the speed, signed); targets with 2 % of B,
    the band at ``level`` and noise of unit RMS; K folds of 60-row segments."""
    rng = np.random.default_rng(seed)
    w = 8.0 * np.sin(np.linspace(0.0, 4 * np.pi, N))
    a = np.zeros((3, N, 2))
    a[0, :, 0] = w
    a[0, :, 1] = np.sign(w) * np.exp(-(w / 0.25) ** 2)
    t = np.einsum("enq,q->en", a, [0.02, level]) + rng.normal(size=(3, N)) * np.array([[1.0], [0.0], [0.0]])
    t[1:] = rng.normal(size=(2, N))  # the other equations: noise (no column enters them)
    folds = [(np.arange(N) // 60) % K == k for k in range(K)]
    return a, t, folds


def _design(a: np.ndarray, t: np.ndarray, folds: list[np.ndarray]) -> Design:
    a = a.transpose(0, 2, 1).copy()  # (3, Q, N): the design's layout, a column's rows contiguous
    g, h, c = (x.sum(axis=0) for x in grams(a, t, folds))
    fg, fh, fc = grams(a, t, folds)
    return Design([Column("B", "B"), Column("stribeck", "tau_s", 0.25)], g, g, h, h, c, c, np.full(3, N),
                  np.full(3, N), np.ones(3), g_fold=fg, h_fold=fh, c_fold=fc,
                  n_fold=np.array([np.full(3, int(m.sum())) for m in folds]),
                  block_fold=np.zeros(0, dtype=int), footprint=Footprints(a, t, folds, [1]))


def _band_oracle(a: np.ndarray, t: np.ndarray, folds: list[np.ndarray], cols: list[int], off: bool = False) -> float:
    """The torque equation's held-out RMS on the band's rows: each fold's rows where the band column reaches
    FOOTPRINT of its peak (``off``: the other rows), predicted by ``cols`` fitted on every other row (all equations
    stacked)."""
    acts = (np.abs(a[0, :, 1]) >= FOOTPRINT * np.abs(a[0, :, 1]).max()) != off
    sse, n = 0.0, 0
    for m in folds:
        x = np.linalg.lstsq(a[:, ~m][:, :, cols].reshape(-1, len(cols)), t[:, ~m].ravel(), rcond=None)[0]
        rows = m & acts
        sse += float(np.sum((t[0, rows] - a[0, rows][:, cols] @ x) ** 2))
        n += int(rows.sum())
    return float(np.sqrt(sse / n))


def test_the_band_score_is_the_k_fold_held_out_error_on_the_bands_rows() -> None:
    a, t, folds = _rows(11, 1.5)
    d = _design(a, t, folds)
    acts = np.array([True, False, False])
    for items, cols in (((), [0]), (("stribeck",), [0, 1])):
        f = fit_model(d, items, tol=0.5)
        assert np.isclose(band_score(d, f, 1, acts), _band_oracle(a, t, folds, cols), rtol=1e-9)
    # the band's rows: a few per cent of the log (the oracle's mask, counted independently)
    assert d.footprint is not None
    rows = int(d.footprint.grams(1)[3][:, 0].sum())
    assert 0.02 * N < rows < 0.15 * N


def test_a_band_too_small_for_the_whole_score_is_material_on_its_rows() -> None:
    """A friction acting on 3 % of the rows cuts the torque equation's held-out error by 2 % (under a 12 %
    materiality) and its own rows' by a third: material there. Without the footprint it would not be."""
    a, t, folds = _rows(12, 1.5)
    d = _design(a, t, folds)
    before, after = fit_model(d, (), tol=0.5), fit_model(d, ("stribeck",), tol=0.5)
    assert after.per_eq[0] > 0.88 * before.per_eq[0]  # the whole torque equation: not 12 % better
    assert is_material(d, before, after, ("stribeck",), 0.12)
    assert not is_material(replace(d, footprint=None), before, after, ("stribeck",), 0.12)
    # noise alone on those rows (no friction drawn): not material there either
    a0, t0, f0 = _rows(13, 0.0)
    d0 = _design(a0, t0, f0)
    assert not is_material(d0, fit_model(d0, (), tol=0.5), fit_model(d0, ("stribeck",), tol=0.5), ("stribeck",),
                           0.12)


def test_the_bands_fall_and_share_as_the_ranking_reports_them() -> None:
    """``band_fall`` (the ranking's sentence: diagnose._entry): the fall of the band's rows' held-out error and their
    share of the held-out rows, from the oracle's numbers; None for an item without a band."""
    a, t, folds = _rows(12, 1.5)
    d = _design(a, t, folds)
    before, after = fit_model(d, (), tol=0.5), fit_model(d, ("stribeck",), tol=0.5)
    fall = band_fall(d, before, after, "stribeck")
    assert fall is not None
    want = 1.0 - _band_oracle(a, t, folds, [0, 1]) / _band_oracle(a, t, folds, [0])
    acts = np.abs(a[0, :, 1]) >= FOOTPRINT * np.abs(a[0, :, 1]).max()
    assert np.isclose(fall[0], want, rtol=1e-9) and 0.25 < want < 0.5
    assert np.isclose(fall[1], acts.sum() / N)
    assert band_fall(d, before, fit_model(d, ("B",), tol=0.5), "B") is None


def test_an_alternative_must_fit_the_bands_rows_too_to_be_its_equal() -> None:
    """The ambiguity challenge (select._challenge): the pooled score, which the band's rows barely move, cannot tell
    a Stribeck band from a B correction here; on the band's rows B explains nothing, so the band is not ambiguous
    with it. Without the footprint the pooled score alone calls them equal."""
    a, t, folds = _rows(12, 1.5)
    d = _design(a, t, folds)
    best = fit_model(d, ("stribeck",), tol=0.5)
    assert _challenge(d, ["stribeck"], ["stribeck", "B"], best, tol=0.5, margin=0.12, min_improvement=0.12) == []
    alt = fit_model(d, ("B",), tol=0.5)
    assert alt.score <= best.score * 1.12  # the pooled score alone calls them equal ...
    assert not band_alike(d, "stribeck", best, alt, 0.12)  # ... the band's rows do not
    assert band_alike(replace(d, footprint=None), "stribeck", best, alt, 0.12)


def test_the_fall_off_the_band_is_the_held_out_error_on_the_other_rows() -> None:
    """``off_band_fall`` (a ripple beside a Stribeck band must be material there too: evidence.win_test): the fall of
    the torque equation's K-fold held-out error on the rows where the band does NOT act, from the oracle's numbers.
    The band itself, which explains a third of its own rows' error, moves the other rows by under 2 %."""
    a, t, folds = _rows(12, 1.5)
    d = _design(a, t, folds)
    before, after = fit_model(d, (), tol=0.5), fit_model(d, ("stribeck",), tol=0.5)
    want = 1.0 - _band_oracle(a, t, folds, [0, 1], off=True) / _band_oracle(a, t, folds, [0], off=True)
    assert np.isclose(off_band_fall(d, before, after), want, rtol=1e-9, atol=1e-12)
    assert off_band_fall(d, before, fit_model(d, ("B",), tol=0.5)) == np.inf  # (no band: nothing to judge off it)
    assert abs(want) < 0.02 < 0.25 < 1.0 - _band_oracle(a, t, folds, [0, 1]) / _band_oracle(a, t, folds, [0])


def test_a_band_over_every_row_leaves_nothing_to_judge_off_it() -> None:
    """A run that never leaves the band (a rotor dwelling at low speed, as a ripple's own test runs it): no held-out
    row off the band, so the fall there is not judged (``inf``: the ripple's other tests decide alone, as before)."""
    a, t, folds = _rows(12, 1.5)
    a[0, :, 1] = np.where(a[0, :, 0] >= 0.0, 1.0, -1.0)  # (the band's column at its peak on every row)
    d = _design(a, t, folds)
    assert d.footprint is not None and int(d.footprint.grams(1)[3][:, 0].sum()) == N  # (every held-out row)
    assert off_band_fall(d, fit_model(d, (), tol=0.5), fit_model(d, ("stribeck",), tol=0.5)) == np.inf
