"""One model's fit (:mod:`.select`): bounded least squares on the Gram matrices of :mod:`.regression` over the
columns of its items, within the boxes its items take (:func:`bounds`: constants calibrated within the tolerance or
named, nuisances and effects as their bounds say), and its held-out score (:func:`score`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import cast

import numpy as np

from ocp.identify.boxqp import box_qp
from ocp.identify.coverage import ASYMMETRY, COMMON_GAIN
from ocp.identify.evidence import IMPLAUSIBLE_FACTOR, Fitted
from ocp.identify.regression import CONSTANTS, NUISANCE_BOUNDS, NUISANCES, Design
from ocp.model.effects import CATALOGUE

#: the relative box of a constant the model names (-80 % .. +300 %)
NAMED_BOUNDS = (-0.8, 3.0)
#: effects whose columns are a saturation ``clip(x, +-w) / w`` (a driver dead band, a brush drop: no output or no
#: current inside the band): physically the drop saturates at the band's width, so a column's amplitude is its
#: width, within this factor (a grid step, ~1.45, and the calibration of the constants); a 0.3 V "dead band" of
#: 1.4 V width is no dead band (it would explain a brush drop by a reduced gain at low voltage)
SATURATING = frozenset({"brush_drop", "voltage_deadband"})
SATURATION_SLACK = 1.5


def bounds(design: Design, cols: Sequence[int], named: set[str], tol: float,
           above: dict[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The boxes (lo (P,), hi (P,)) of the columns ``cols`` in a model naming the constants ``named`` (a constant's
    relative to nominal; ``above``: the widening above nominal, :attr:`.regression.Design.above` when None)."""
    lo, hi, items = [], [], {design.columns[j].item for j in cols}
    above = design.above if above is None else above
    for j in cols:
        c = design.columns[j]
        if c.item in NUISANCES:
            a, b = NUISANCE_BOUNDS[c.item]
        elif c.item in (*CONSTANTS, COMMON_GAIN):
            # unresolved: a free nuisance, never named (boxed, a current filter for L would be explained by a wrong
            # item); unseen (Design.unseen): never named, held at nominal beside its asymmetry (which then takes the
            # reverse rows), else calibrated; the box wider where a nuisance mimics the error
            unseen = c.item in design.unseen
            box = 0.0 if unseen and ASYMMETRY[c.item] in items else tol + design.slack.get(c.item, 0.0)
            a, b = (NAMED_BOUNDS[0], np.inf) if c.item in design.unresolved else NAMED_BOUNDS if \
                c.item in named and not unseen else (-box, min(box + above.get(c.item, 0.0), IMPLAUSIBLE_FACTOR - 1.0))
        elif c.item in SATURATING:  # the drop saturates at its width: amplitude = width (module doc)
            a, b = c.shape / SATURATION_SLACK, c.shape * SATURATION_SLACK
        else:
            a, b = (0.0 if CATALOGUE[c.item].bounds.get(c.key, (-1.0, 1.0))[0] >= 0 else -np.inf), np.inf
        lo.append(a)
        hi.append(b)
    return np.array(lo), np.array(hi)


def solve(design: Design, cols: Sequence[int], named: set[str], tol: float,
          above: dict[str, float] | None = None, near: Fitted | None = None) -> Fitted:
    """Bounded least squares on the training Gram matrices (``min x'Gx - 2h'x``) of columns ``cols`` (``above``:
    the boxes' widening above nominal, :attr:`.regression.Design.above` when None). ``near``: the fit of the first
    columns of ``cols`` alone, where the box QP starts (its bounds mostly bind again: the same minimum in fewer
    solves). Kept in the design's memo by everything the fit depends on (the same models are fitted again: their
    shapes and folds by each later round, blind rig 95: 8,568 fits, 4,888 different)."""
    above = design.above if above is None else above
    key = ("solve", tuple(cols), frozenset(named), tol, *(tuple(sorted(d.items())) for d in (above, design.slack)),
           frozenset(design.unresolved), frozenset(design.unseen))
    if key not in design.memo:
        design.memo[key] = _solve(design, cols, named, tol, above, near)
    return cast(Fitted, design.memo[key])


def _solve(design: Design, cols: Sequence[int], named: set[str], tol: float, above: dict[str, float],
           near: Fitted | None) -> Fitted:
    idx = np.array(cols, dtype=int)
    g = design.g_train[:, idx][:, :, idx].sum(axis=0)  # (the model's columns first: Q runs to hundreds)
    h = design.h_train[:, idx].sum(axis=0)
    d = np.sqrt(np.maximum(np.diag(g), 1e-300))
    gs = g / np.outer(d, d) + 1e-10 * np.eye(idx.size)
    lo, hi = bounds(design, cols, named, tol, above)
    try:
        np.linalg.cholesky(gs)
    except np.linalg.LinAlgError:
        gs = gs + 1e-6 * np.eye(idx.size)
    y = np.linalg.solve(gs, h / d)  # unconstrained first; bounded only when a bound binds
    if not np.all(np.isfinite(y)) or np.any(y < lo * d) or np.any(y > hi * d):  # (near-singular: bounded too)
        if near is not None:
            y[:near.x.size] = near.x * d[:near.x.size]
        y = box_qp(gs, h / d, lo * d, hi * d, y)
    x = np.where(d > 1e-9 * _reference(design, idx), y / d, 0.0)  # a column the log leaves empty: 0
    cost = float(design.c_train.sum() - 2 * h @ x + x @ g @ x)
    gt, ht = design.g_test[:, idx][:, :, idx], design.h_test[:, idx]
    ms = np.array([(design.c_test[e] - 2 * ht[e] @ x + x @ gt[e] @ x) / max(design.n_test[e], 1) for e in range(3)])
    return Fitted((), tuple(int(j) for j in idx), x, cost, score(design, ms), np.sqrt(np.maximum(ms, 0.0)))


def _reference(design: Design, idx: np.ndarray) -> np.ndarray:
    """(P,) for each column of ``idx`` the largest training norm among the columns of ``idx`` in the equations it
    enters: a column is empty (``L`` far under a sample) only against its own equations' columns. Against every
    column, an absolute one of another equation (a thrust asymmetry's ``dc_f`` in N s^2/rad^2: norm 2e9) emptied
    a relative ``L`` the current filter's lag had widened (proving ground 23144: the armature equation's held-out
    error rose 34-fold, the other coefficients fitted beside the ``L`` that was then zeroed)."""
    per_eq = np.sqrt(np.maximum(np.diagonal(design.g_train, axis1=1, axis2=2)[:, idx], 0.0))  # (3, P)
    return np.max(np.where(per_eq > 0, per_eq.max(axis=1, keepdims=True), 0.0), axis=0)


def score(design: Design, ms: np.ndarray) -> float:
    """The held-out score from the equations' mean squared errors ``ms`` (3,) [noise units squared] (module doc); an
    error the Gram algebra's cancellation leaves a hair under zero (a model-exact log, no noise) counts as zero."""
    live = design.n_test > 0
    return float(np.sqrt(np.mean(np.maximum(ms[live], 0.0)))) if live.any() else math.inf


def calibrated_columns(design: Design) -> list[int]:
    """The columns every model fits (the constants' and the nuisances'), in the design's order."""
    return [j for c in (*CONSTANTS, *NUISANCES) for j in design.index(c)]


def as_given(design: Design, calibrated: Fitted) -> Fitted:
    """The nominal model as given where it scores better than ``calibrated`` (the fit of no item,
    :func:`.select.fit_model`), else ``calibrated``: the forward rounds' start. As given, every constant is at nominal
    and every nuisance at its default (all coefficients zero), nothing fitted, and the held-out score is the nominal
    residual's on the held-out rows (every fold's the same model). An explanation of its own: where it scores better,
    the calibration fitted the training rows' noise through columns those rows do not excite, and an item must beat the
    nominal model, not that fit (a spin-up under one command, ``tests/identify/test_one_command.py``: the steady rows
    leave the unresolved ``L`` and the current's lag free, the differentiated current's noise pulled ``L`` to its -80 %
    box and the lag to 5 samples, and the fold that held the spin-up out read 24 noise units where the nominal model
    reads 1.1; a current offset cut that and was named)."""
    cols = tuple(calibrated_columns(design))
    ms = design.c_test / np.maximum(design.n_test, 1)
    one = Fitted((), cols, np.zeros(len(cols)), float(design.c_train.sum()), score(design, ms),
                 np.sqrt(np.maximum(ms, 0.0)), as_given=True)
    return replace(one, folds=(one,) * design.folds) if one.score < calibrated.score else calibrated
