"""The torque ripple's period count, searched beside the other columns of the torque equation (issue #11).

:func:`pick_periods` fits a ripple of each count 1..64 (:func:`.columns.effect_columns`, its phase tracked along an
integrated angle, :func:`.columns.ripple_phase`) as an added variable (:func:`residualizer`) beside the columns the
regression's noise level comes from (:func:`.regression.build`), and keeps the count that best predicts the held-out
rows; its share of the held-out residual per count is the spectrum the report shows.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ocp.identify.angle import MAX_PERIODS
from ocp.identify.columns import Column, Signals, effect_columns, ripple_phase, turn_ripple
from ocp.logs import Log
from ocp.model.params import MotorParams


def residualizer(cols: list[np.ndarray], rows: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``y -> y - A x`` (N,) with ``x`` the least-squares fit of ``y`` (N,) by the columns ``cols`` (N,) each (``A``,
    all-zero ones left out) on the ``rows`` mask (N,): what the columns leave of ``y``. Fitting what it leaves of a
    target by what it leaves of further columns is the joint fit (Frisch-Waugh-Lovell): the further columns'
    coefficients and the residual on every row are those of the fit by all columns together."""
    a = np.column_stack(cols) if cols else np.zeros((rows.size, 0))
    a = a[:, np.any(a != 0, axis=0)] if a.size else a
    if a.shape[1] == 0:
        return lambda y: y
    proj = np.linalg.pinv(a[rows])  # (Q, rows): computed once for the many targets of a period search
    return lambda y: y - a @ (proj @ y[rows])


def pick_periods(p: MotorParams, raw: Signals, log: Log, target: np.ndarray, rich: list[np.ndarray],
                  train: np.ndarray, test: np.ndarray, view: Callable[[np.ndarray], np.ndarray]
                  ) -> tuple[int, list[tuple[Column, np.ndarray]], float, np.ndarray]:
    """The torque ripple at 1..64 periods per revolution (and, along an integrated angle, phases: one, or tracked)
    whose columns (seen through ``view``) explain most of the viewed torque target ``target`` (M,) on the held-out
    rows when fitted beside the ``rich`` columns (M,) each on the training rows: its period count, its columns (as
    built, not seen through ``view``), its amplitude [N m], and per count (64,) the fraction of the held-out residual
    it explains (at most 1; negative where it predicts worse than nothing): the residual's spectrum against the rotor
    angle. (An amplitude per count is no
    spectrum: where the speed view averages a count's ripple out, its columns are tiny and the fitted amplitude is
    noise, larger than the true ripple's.) Measured as the added variable (:func:`residualizer`: the joint fit,
    exactly). A ripple fitted to what the rich columns alone had left found the share of it they took up missing (a
    ripple holding a stalled rotor in its detents, taken up by an offset and friction: the true count explained
    nothing and a wrong one half; proving-ground seeds 12089, 12156: ripples of 31 and 47 periods not named)."""
    added = residualizer(rich, train)
    resid = added(target)
    total = float(resid[test] @ resid[test])
    shares = np.full(MAX_PERIODS, -math.inf)
    best: tuple[float, int, list[tuple[Column, np.ndarray]], float] = (-math.inf, 0, [], 0.0)
    for n in range(1, MAX_PERIODS + 1):  # a drifting integrated angle: also the ripple with its phase tracked
        ripple = effect_columns("cogging", p, raw, log, n)
        phase = ripple_phase(raw, log, n, ripple, resid, train, view)
        for unviewed in (ripple,) if phase is None else (ripple, turn_ripple(ripple, phase)):
            cols = [(c, np.vstack([view(a[0]), a[1:]])) for c, a in unviewed]
            sc = np.column_stack([added(a[0]) for _, a in cols])
            x, *_ = np.linalg.lstsq(sc[train], resid[train], rcond=None)
            e = resid[test] - sc[test] @ x
            gain = total - float(e @ e)
            shares[n - 1] = max(shares[n - 1], gain / total if total > 0 else 0.0)
            if gain > best[0]:
                best = (gain, n, unviewed, math.hypot(*x))
    return best[1], best[2], best[3], shares
