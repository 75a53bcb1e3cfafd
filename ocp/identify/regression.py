"""Equation-error regression: every candidate as columns of one linear least-squares problem.

The three model equations, written as residuals of the NOMINAL plant on the (aligned, low-passed) log
(all (N,), SI)::

    r_mech = k_t i - J w' - B w - c_tau w|w|      [N m]   eq. dc_mechanical
    r_elec = V - L i' - R i - k_e w               [V]     eq. dc_electrical
    r_thr  = F - c_f w|w|                         [N]     eq. thrust_model (w|w| low-passed as F: speed_square)

are explained by a linear combination of columns, one set per candidate:

* a constant off by a relative ``x`` (true = nominal (1 + x)): ``J w'``, ``B w``, ``c_tau w|w|``,
  ``c_f w|w|`` (thrust), ``R i``, ``L i'``, and the motor constant ``k`` (k_t = k_e, both scaled):
  ``-k_t i`` (mech) with ``k_e w`` (elec);
* an effect at unit amplitude, taken from the catalogue's own hooks (:mod:`ocp.model.effects`): load torques
  (mech), the drive-voltage loss ``V - V_a`` (elec), the thrust change (thr), a current-sensor offset
  (``+k_t`` in mech, ``-R`` in elec);
* effects with a shape parameter (Stribeck speed, dead-band width, wake time constant) get one column per
  value on a grid; cogging gets ``sin/cos(n theta)`` with ``n`` from the residual's spectrum against angle.

Where an angle is logged, the torque equation can also be written on the RAW rows (``raw_torque``;
:func:`.columns.raw_signals`: mean speeds between samples, exact from the angle), judged through the same speed view
(:func:`speed_view`): a torque ripple locked to the rotor angle is often faster than the low-pass (20-60
periods/rev) and would be filtered out before it could be seen (:func:`ocp.identify.diagnose.diagnose` uses that
view wherever an angle is logged). The ripple's columns are its exact means over each row (:func:`interval_ripple`),
so a ripple faster than the sampling averages out instead of aliasing; its period count is the one whose columns,
fitted beside the others, best predict held-out rows (:func:`.ripple.pick_periods`; :func:`angle_limits` says when the
log cannot show it).

Where something holds the rotor (:func:`.columns.held_still`: dry friction holds whatever stays within its level), the
torque balance holds a torque no column expresses: those rows are cut from the torque equation for every model.

Rows are split into training and held-out samples (every ``holdout_every``-th segment), or into folds held out
in turn (cross-validation, :attr:`Design.g_fold`); each equation is weighted by its noise level. Only Gram matrices
leave this module: fitting a model (a subset of columns, bounded) and scoring it on held-out rows are ``P x P``
algebra (:mod:`.select`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, cast

import numpy as np

from ocp.filters import filtfilt
from ocp.identify.align import cutoff_hz
from ocp.identify.angle import MAX_PERIODS, angle_limits, ripple_independence, tracked_periods
from ocp.identify.columns import (
    DROPS,
    Column,
    Signals,
    at_rest,
    constant_columns,
    effect_columns,
    held_still,
    nuisance_columns,
    raw_signals,
    runs,
    signals,
    targets,
)
from ocp.identify.coverage import unseen
from ocp.identify.drops import drop_columns
from ocp.identify.footprint import BANDED, Footprints, grams, weighted
from ocp.identify.holdout import usable
from ocp.identify.noise_level import sensor_noise
from ocp.identify.resolution import rotor_tau, unresolved
from ocp.identify.ripple import pick_periods, residualizer
from ocp.logs import Log, LogKind
from ocp.model.effects import CATALOGUE
from ocp.model.params import MotorParams

EQS = ("mechanical", "electrical", "thrust")
#: the lift [of a column's peak] that keeps :func:`speed_view`'s filter out of the subnormal range
SUBNORMAL_LIFT = 1e-150
CONSTANTS: tuple[str, ...] = ("J", "B", "c_tau", "c_f", "k", "R", "L")
#: logger artefacts every model fits and no verdict names: ``current_lag``, the current sensor's lag [samples]
#: (a firmware filter) in the torque equation, where the true current is ``i + lag dt i'`` (in the armature
#: equation the same lag looks like an inductance: an unresolved ``L`` takes it up there); ``switch_phase``, where
#: within a row the drive applies a new command; ``current_bend``, how far the current bends smoothly between its
#: samples (:func:`.columns.nuisance_columns`). Each with its box: a sensor lag, or a lead of up to one sample (a
#: current settling within a sample); the switching instant anywhere in the row; a current from held steps (0) to
#: one smooth between the samples (1); a speed read late by up to two samples, never early (an encoder's backward
#: difference over ``d`` samples, read as the speed at the instant, is ``d / 2`` samples late; open to -2 samples,
#: the lag was fitted below zero where it took another item's residual: session 34, 193 and 6043)
NUISANCE_BOUNDS: dict[str, tuple[float, float]] = {"current_lag": (-1.0, math.inf), "switch_phase": (-0.5, 0.5),
                                                   "current_bend": (0.0, 1.0), "speed_lag": (0.0, 2.0)}
NUISANCES: tuple[str, ...] = tuple(NUISANCE_BOUNDS)
#: dry friction: set-valued where the rotor is at rest (:func:`.columns.at_rest`), where a ripple beside it is left out
DRY = frozenset({"coulomb_friction", "stribeck"})
#: effects found by regression (input_delay is found by the alignment)
REGRESSED = tuple(n for n in CATALOGUE if n != "input_delay")
#: the torque equation's weight is at least this fraction of the smallest torque error a free run shows at
#: one noise level (:func:`visible_torque`): far smaller mismatches are averaged out of a long log but never
#: show in a prediction (tuned on proving-ground seeds 1000..1099)
VISIBLE_FRACTION = 0.15
#: a rich fit leaving less than this fraction of an equation's nominal residual has scaled the equation to zero
#: (:func:`_noise_residual`): rounding, not noise (measured noise leaves ~1e-2 and more)
DEGENERATE = 1e-6
#: a held-out block (:func:`_blocks`) spans at least this many independent torque rows (rotor time constants of
#: the speed view), so that blocks are nearly independent of each other
BLOCK_INDEPENDENT = 3.0


@dataclass
class Design:
    """Weighted Gram matrices of all columns, per equation, on training and held-out rows.

    Attributes:
        columns: (Q,) descriptions
        g_train, g_test: (3, Q, Q) ``A_e^T A_e`` per equation e (weighted)
        h_train, h_test: (3, Q) ``A_e^T r_e``
        c_train, c_test: (3,) ``r_e^T r_e``
        n_train, n_test: (3,) row counts
        sigma: (3,) equation weights (noise level) [N m, V, N]
        periods: cogging periods per revolution chosen from the spectrum (its amplitude [N m] in ``angle``)
        spectrum: per period count 1..64, the fraction of the torque equation's held-out residual a ripple of that
            count explains beside the other columns (:func:`.ripple.pick_periods`)
    """

    columns: list[Column]
    g_train: np.ndarray
    g_test: np.ndarray
    h_train: np.ndarray
    h_test: np.ndarray
    c_train: np.ndarray
    c_test: np.ndarray
    n_train: np.ndarray
    n_test: np.ndarray
    sigma: np.ndarray
    periods: int = 0
    spectrum: list[float] = field(default_factory=list)
    unresolved: dict[str, str] = field(default_factory=dict)
    angle: dict[str, object] = field(default_factory=dict)  # how far the log resolves the ripple (angle_limits)
    raw_torque: bool = False  # eq. dc_mechanical written on the raw rows (module doc)
    #: (3,) per equation, the fraction of rows that are independent (low-passed rows are correlated; the
    #: torque rows' speed view remembers a rotor time constant)
    independence: np.ndarray = field(default_factory=lambda: np.ones(3))
    dt: float = 0.0  # [s] the log's sample period (0: a steady-state sweep)
    #: per constant, the relative error a nuisance the log leaves open could mimic (``L`` under an unidentified
    #: command timing): its calibration box is ``tol`` wider by this, so it is named only beyond both
    slack: dict[str, float] = field(default_factory=dict)
    #: per constant, a further widening of its calibration box ABOVE nominal only (``inf``: open above): what a
    #: logger artefact that can only raise the apparent value mimics (a first-order current filter of time
    #: constant ``t_f`` adds ``R t_f`` to the apparent inductance, never less)
    above: dict[str, float] = field(default_factory=dict)
    #: the apparent inductance's relative rise per sample of current lag, ``dt R / L`` (0: not used): a model's
    #: ``L`` box is widened above by the ``current_lag`` that model fits (:func:`.select.fit_model`)
    lag_inductance: float = 0.0
    #: constants the log resolves loosely on one side (above nominal: unnamed, they calibrate nothing), with the reason
    one_sided: dict[str, str] = field(default_factory=dict)
    #: constants the log does not exercise, calibrated but never named, with the reason (:func:`.coverage.unseen`)
    unseen: dict[str, str] = field(default_factory=dict)
    #: the held-out rows cut into blocks (contiguous, each at least a few independent torque rows long,
    #: :func:`_blocks`): per block b and equation e, ``g_blocks[b, e]`` (B, 3, Q, Q), ``h_blocks`` (B, 3, Q),
    #: ``c_blocks`` (B, 3), as ``g_test`` etc. (they sum to them): a paired comparison's scatter between blocks
    g_blocks: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 0, 0)))
    h_blocks: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 0)))
    c_blocks: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    #: cross-validation over K folds (each a set of held-out segments, every row held out once): per fold k the
    #: Gram matrices of its rows, ``g_fold`` (K, 3, Q, Q), ``h_fold`` (K, 3, Q), ``c_fold`` (K, 3), ``n_fold`` (K, 3),
    #: and each block's fold, ``block_fold`` (B,); ``g_train``/``g_test`` etc. then both hold ALL rows (a model's
    #: coefficients are fitted on all of them, its score is the folds' held-out error, :meth:`fold`). K = 0: one
    #: split, ``g_test`` its held-out rows.
    g_fold: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 0, 0)))
    h_fold: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 0)))
    c_fold: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    n_fold: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    block_fold: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    #: the banded effects' columns (:data:`.footprint.BANDED`) and the held-out rows where each acts
    #: (:class:`.footprint.Footprints`); None in a fold's design (:meth:`fold`)
    footprint: Footprints | None = None
    #: what is computed again and again from this design: :meth:`fold`'s designs, :func:`.lsq.solve`'s fits (keyed
    #: by their arguments and the boxes' state); a design made by ``replace`` starts with none
    memo: dict[object, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    def index(self, item: str) -> list[int]:
        return [j for j, c in enumerate(self.columns) if c.item == item]

    @property
    def folds(self) -> int:
        return int(self.g_fold.shape[0])

    @property
    def n_held(self) -> np.ndarray:
        """(3,) the held-out rows the sampling-noise formulas of :mod:`.evidence` count: under cross-validation
        one fold's (the pooled error of K folds comes from K overlapping fits, and the naive variance of a
        cross-validated comparison understates its scatter: the thresholds stay those of one held-out fold)."""
        return self.n_test / max(self.folds, 1)

    def fold(self, k: int) -> Design:
        """Fold ``k`` as a one-split design: trained on every other row, held out on the fold's (its blocks)."""
        if ("fold", k) not in self.memo:  # (kept: a model's folds are fitted again by every later round's models)
            b, o = self.block_fold == k, np.arange(self.folds) != k  # (the other folds summed: no cancellation)
            self.memo["fold", k] = replace(
                self, g_train=self.g_fold[o].sum(axis=0), h_train=self.h_fold[o].sum(axis=0),
                c_train=self.c_fold[o].sum(axis=0), n_train=self.n_fold[o].sum(axis=0),
                g_test=self.g_fold[k], h_test=self.h_fold[k], c_test=self.c_fold[k], n_test=self.n_fold[k],
                g_blocks=self.g_blocks[b], h_blocks=self.h_blocks[b], c_blocks=self.c_blocks[b],
                g_fold=self.g_fold[:0], h_fold=self.h_fold[:0], c_fold=self.c_fold[:0], n_fold=self.n_fold[:0],
                block_fold=self.block_fold[:0], footprint=None)
        return cast(Design, self.memo["fold", k])


def _noise_residual(t: np.ndarray, rich: list[np.ndarray], fixed: list[np.ndarray], rows: np.ndarray) -> np.ndarray:
    """An equation's residual (N,) [its unit] for its noise level: what the ``rich`` columns (N,) leave of the
    nominal residual ``t`` (N,) on ``rows``; where they leave nothing (below :data:`DEGENERATE` of ``t``'s RMS),
    what the constants' and nuisances' columns ``fixed`` alone leave. The constants' columns span the nominal
    model's own prediction (eq. dc_electrical: ``R i_arm`` is homogeneous in ``(R, L)``, so its R and L columns
    add up to it; ``k`` gives ``k_e w``), so the rich fit reproduces ``t`` exactly, noise and all, wherever an
    effect's column also spans the measured side: a constant command is a current offset's (and a saturated dead
    band's) column. That fit scales the equation to zero, no noise level; the effects cannot be told from it."""
    r = residualizer(rich, rows)(t)
    if not rows.any() or np.sqrt(np.mean(r[rows] ** 2)) >= DEGENERATE * np.sqrt(np.mean(t[rows] ** 2)):
        return r
    return residualizer(fixed, rows)(t)


def speed_view(y: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """Torque rows (N,) or (N, K) [N m] seen as the speed error they cause: the rotor's first-order low-pass
    (eq. dc_mechanical ``J w' + D w = tau``, ``tau = J / D`` [s], unit gain at DC, exact for a held input),
    run forward and backward (zero phase, magnitude ``1 / (1 + (w tau)^2)``). The differentiated speed's
    noise (``J w'``, growing with frequency) falls below the speed noise, while a slow torque error keeps
    what moves the rotor: what a free run shows.

    A column that is zero away from a few rows (a hat of :func:`.angle.drift_windows`, a step) leaves a tail decaying
    through the subnormal range, where each operation costs ~100 times more (blind rig 12: a fifth of the viewed
    values, the filter and the Gram products after it 10-25 times slower). Each column is lifted by
    :data:`SUBNORMAL_LIFT` of its peak before the filter (its DC gain is one: the lift comes back out) and what is left
    under a thousand lifts is zero: the same view to within 1e-147 of the column's peak."""
    if dt == 0 or tau <= 2 * dt or y.shape[0] < 20:
        return y
    a = math.exp(-dt / tau)
    lift = SUBNORMAL_LIFT * np.max(np.abs(y), axis=0)  # () or (K,)
    lifted = np.empty(y.shape[::-1]).T  # (N, K), each column contiguous: the filter runs along it
    np.add(y, lift, out=lifted)
    z = filtfilt([1.0 - a], [1.0, -a], lifted, overwrite=True)  # (lifted's buffer, filtered in place)
    z -= lift
    np.copyto(z, 0.0, where=np.abs(z) < 1e3 * lift)
    return np.ascontiguousarray(z)


def visible_torque(p: MotorParams, s: Signals, noise: dict[str, float]) -> float:
    """Smallest slow torque error [N m] a free run shows at one noise level in some channel: it moves the
    speed by ``dtau / D``, the current by ``k dtau / (R D)`` and the thrust by ``2 c_f |w| dtau / D``
    (quasi-static, voltage-driven rotor, ``D = k_t k_e / R + B + 2 c_tau |w|`` [N m s/rad]); ``noise``
    holds the channels' per-sample noise levels (omega [rad/s], current [A], thrust [N])."""
    rms = float(np.sqrt(np.mean(s.w * s.w))) if s.w.size else 0.0
    d = p.k_t * p.k_e / p.R + p.B + 2.0 * p.c_tau * rms
    via = [noise["omega"] * d, noise["current"] * p.R * d / p.k_t]
    if p.c_f * rms > 0:
        via.append(noise["thrust"] * d / (2.0 * p.c_f * rms))
    return min(via)


def build(p: MotorParams, log: Log, train: np.ndarray, test: np.ndarray, effects: tuple[str, ...],
          noise: dict[str, float] | None = None, raw_torque: bool = False,
          held: tuple[np.ndarray, float] | None = None, folds: list[np.ndarray] | None = None) -> Design:
    """Gram matrices (module doc) of the constants and ``effects`` on the ``train``/``test`` masks (N,).
    ``folds``: held-out masks (N,) for cross-validation (:attr:`Design.g_fold`; ``train``/``test`` then only serve
    the noise levels and the ripple's period count).
    ``noise`` (per-sample channel noise, :func:`ocp.identify.predict.noise_levels`) floors the torque
    equation's weight at the smallest torque error a free run would show (:func:`visible_torque`).
    ``raw_torque``: eq. dc_mechanical on the raw rows where an angle is logged (module doc). ``held``: the command
    (N,) [V] before the alignment shifted it, and the shift [samples] (:func:`.drops.drop_columns`)."""
    s = signals(log, p)
    use_raw = raw_torque and log.kind is LogKind.TIME_SERIES and log.theta is not None
    raw = raw_signals(log, log.theta) if use_raw and log.theta is not None else s
    t = targets(p, s)
    t[0] = targets(p, raw)[0]
    rows = s.w.size
    edge, m = np.zeros(rows, dtype=bool), 0
    tau = rotor_tau(p, s.w) if log.kind is LogKind.TIME_SERIES else 0.0
    if log.kind is LogKind.TIME_SERIES:  # the low-passes' start-up and run-out transients
        m = min(math.ceil(1.5 / (cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e)) * log.dt)), rows // 6)
        edge[:m] = edge[rows - m:] = True
    # a clipped current and its transient cut as the ends (.clipping); too few rows left: a LogError
    train, test, edge = usable(train[:rows], test[:rows], edge, log.current[:rows], m)
    cols = _columns(p, s, raw, log, effects, held)
    # noise level per equation: what the richest fit (one shape per effect) leaves on training rows
    # (the motor constant is left out: with it, J, B and c_tau the torque balance scales to zero)
    keep = [j for j, (c, _) in enumerate(cols)
            if c.item != "k" and (math.isnan(c.shape) or (c.shape == _mid(cols, c.item) and c.plain))]
    periods, spectrum, angle = 0, np.zeros(0), {}
    ripple = "cogging" in effects and s.theta is not None and raw.theta is not None and log.kind is LogKind.TIME_SERIES

    # eq. dc_mechanical judged by the speed error it causes (speed_view), the others as they are; the
    # edge rows are zeroed on both sides first (still an equation), so their transients do not spread, and the
    # rows next to them tapered in (edge_taper: the low-passed J w' of a log cut off there holds the speed of one row)
    # where something holds the rotor the torque balance carries a holding torque no column expresses (dry friction
    # holds whatever stays within its level): those rows are cut too, for every model alike (cut_taper)
    rest = at_rest(s, log, p)
    stuck = held_still(s, log, p, rest)
    hidden = edge | stuck
    taper = cut_taper(edge, stuck, raw is not s, tau / s.dt if s.dt > 0 else 0.0)

    def view(y: np.ndarray) -> np.ndarray:  # (M,) or (M, K): rows first
        cut = y * _rows(taper, y)
        cut[hidden] = 0.0
        return speed_view(cut, s.dt, tau)

    for y in (t, *(a for _, a in cols)):
        y[0] = view(y[0])
    rich = [cols[j][1] for j in keep]
    if ripple:
        periods, unviewed, amplitude, spectrum = pick_periods(p, raw, log, t[0], [a[0] for a in rich], train, test,
                                                              view)
        cogging = [(c, np.vstack([view(a[0]), a[1:]])) for c, a in unviewed]
        cols += cogging
        rich += [a for _, a in cogging]
        if rest.any() and DRY.intersection(effects):  # the ripple beside dry friction that holds the rotor at rest
            cols += [(replace(c, at_rest=False), np.vstack([view(np.where(rest, 0.0, a[0])), a[1:]]))
                     for c, a in unviewed]
        tracked = MAX_PERIODS if log.theta is not None or raw.dt == 0 else \
            tracked_periods(raw.t, sensor_noise(log.omega), raw.dt)
        angle = {"amplitude": amplitude, **angle_limits(raw.theta, periods, log.theta is not None, tracked)}
    # (the armature and thrust equations keep the motor constant: their measured side does not scale)
    k_col = [a for c, a in cols if c.item == "k"]
    fixed = [a for j, (c, a) in enumerate(cols) if j in keep and c.item in (*CONSTANTS, *NUISANCES)]
    resid = np.vstack([_noise_residual(t[e], [a[e] for a in (rich if e == 0 else [*rich, *k_col])],
                                       [a[e] for a in (fixed if e == 0 else [*fixed, *k_col])], train)
                       for e in range(3)])
    sigma = np.array([max(float(np.sqrt(np.mean(resid[e][train] ** 2))), 1e-12 * (np.std(t[e]) + 1e-30))
                      for e in range(3)])
    if noise is not None and s.dt > 0:
        sigma[0] = max(sigma[0], VISIBLE_FRACTION * visible_torque(p, s, noise))
    items, arrays = [c for c, _ in cols], [a for _, a in cols]
    del cols, rich, fixed, k_col, resid, y  # (the columns' only references are now in arrays, which weighted empties)
    if ripple:
        del unviewed, cogging
    a_all = weighted(arrays, sigma)
    tw = t / sigma[:, None]
    tests = [m[:rows] & ~edge for m in folds] if folds else [test]
    fg, fh, fc = grams(a_all, tw, tests)  # (one set when not cross-validating: the held-out rows)
    if folds:  # cross-validation: every row is fitted on, the folds are held out in turn (Design.fold)
        (g_tr, h_tr, c_tr), n_tr = (fg.sum(axis=0), fh.sum(axis=0), fc.sum(axis=0)), sum(int(m.sum()) for m in tests)
        g_te, h_te, c_te, n_te = g_tr, h_tr, c_tr, n_tr
    else:
        (g_tr, h_tr, c_tr), n_tr = (x[0] for x in grams(a_all, tw, [train])), int(train.sum())
        g_te, h_te, c_te, n_te = fg[0], fh[0], fc[0], int(test.sum())
    independence = _independence(p, log, s, tau)
    if angle and raw.theta is not None:  # the ripple's own independence against the torque residual (select)
        theta = np.append(raw.theta, raw.theta[-1] + raw.w1[-1] * raw.dt)
        angle["independence"] = ripple_independence(theta, periods, float(independence[0]),
                                                    1.0 if raw is not s else float(independence[1]))
    per_fold = [_blocks(m, math.ceil(BLOCK_INDEPENDENT / float(independence.min()))) for m in tests]
    gb, hb, cb = grams(a_all, tw, [b for bs in per_fold for b in bs])
    design = Design(items, g_tr, g_te, h_tr, h_te, c_tr, c_te, np.full(3, n_tr), np.full(3, n_te),
                    sigma, periods, [float(v) for v in spectrum], unresolved(p, log), angle, raw is not s,
                    independence, dt=s.dt, g_blocks=gb, h_blocks=hb, c_blocks=cb,
                    footprint=Footprints(a_all, tw, tests, [j for j, c_ in enumerate(items) if c_.item in BANDED]),
                    unseen=unseen(log))
    if not folds:
        return design
    return replace(design, g_fold=fg, h_fold=fh, c_fold=fc, n_fold=np.array([np.full(3, int(m.sum())) for m in tests]),
                   block_fold=np.array([k for k, bs in enumerate(per_fold) for _ in bs], dtype=int))


def _rows(x: np.ndarray, like: np.ndarray) -> np.ndarray:
    """Per-row ``x`` (M,) shaped to broadcast over ``like`` (M,) or (M, K)."""
    return x if like.ndim == 1 else x[:, None]


def edge_taper(edge: np.ndarray, rows: float) -> np.ndarray:
    """Row weights (M,) for the torque rows before :func:`speed_view`: 0 on the ``edge`` rows (M,) (the log's cut
    ends, and the rows where the rotor is held, :func:`.columns.held_still`), rising as a raised cosine over ``rows``
    (the rotor time constant in rows; at most a sixth of the run) on either side of each run of rows between, 1
    beyond. The view of a log cut off at a row weights ``J w'`` as ``J (w - w_low) / tau``,
    the speed of that one row against its past: a coarse encoder's speed over one row (61 rad/s steps at 10 kHz
    and 1024 counts) then ran through a rotor time constant's worth of rows as a torque error of ~100 noise units.
    Tapered, the cut weights the speed over ``rows`` rows, its noise averaged as inside the log; every equation
    row is scaled alike (still an equation)."""
    w = np.where(edge, 0.0, 1.0)
    for a, b in runs(~edge):  # each run of rows between cut rows
        k = min(math.ceil(rows), (b - a) // 6)
        if k < 2:
            continue
        ramp = 0.5 * (1.0 - np.cos(np.pi * (np.arange(k) + 1.0) / (k + 1.0)))
        w[a:a + k] = ramp
        w[b - k:b] = ramp[::-1]
    return w


def cut_taper(edge: np.ndarray, stuck: np.ndarray, raw_rows: bool, rows: float) -> np.ndarray:
    """Row weights (M,) for the torque rows cut at the log's ``edge`` (M,) and where the rotor is held, ``stuck`` (M,)
    (:func:`edge_taper`, ``rows`` the rotor time constant in rows). On ``raw_rows`` (mean speeds from the angle) the
    rows beside a held run are tapered in as at the log's ends: a raw row's speed is one sample's, a coarse encoder's
    count per row, and cut off hard it is a step a ripple fits (proving-ground draw 13012: 5 kHz, 1024 counts, a
    false ripple). Low-passed rows meet a held rotor at its low-passed speed, within noise of zero, and are not
    tapered there: a taper would fade out the rows where dry friction lets go, which show it."""
    return edge_taper(edge | stuck if raw_rows else edge, rows)


def _blocks(test: np.ndarray, length: int) -> list[np.ndarray]:
    """The held-out rows of mask ``test`` (M,) as blocks of row indices: each contiguous run of held-out rows
    (a held-out segment) cut into pieces of at least ``length`` rows (a run shorter than that is one block)."""
    out: list[np.ndarray] = []
    for a, b in runs(test):
        out += [piece for piece in np.array_split(np.arange(a, b), max(1, (b - a) // max(length, 1))) if piece.size]
    return out


def _independence(p: MotorParams, log: Log, s: Signals, tau: float) -> np.ndarray:
    """(3,) fraction of independent rows per equation: ``2 f_c dt`` after the low-pass (cutoff ``f_c`` [Hz]),
    and for the torque rows at most ``dt / (2 tau)`` (the speed view's memory, ``tau`` [s]); 1 on a sweep."""
    if s.dt == 0:
        return np.ones(3)
    low = min(1.0, 2.0 * cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e)) * s.dt)
    return np.array([min(low, s.dt / (2.0 * tau) if tau > 0 else 1.0), low, low])


def _columns(p: MotorParams, s: Signals, raw: Signals, log: Log, effects: tuple[str, ...],
             held: tuple[np.ndarray, float] | None = None) -> list[tuple[Column, np.ndarray]]:
    """Columns (3, M) of the constants, nuisances and ``effects`` (but cogging) on the low-passed rows ``s``,
    their torque rows on the ``raw`` rows (module doc)."""
    def both(make: Callable[[Signals], list[tuple[Column, np.ndarray]]]) -> list[tuple[Column, np.ndarray]]:
        out = make(s)
        if raw is not s:
            for (_, a), (_, b) in zip(out, make(raw), strict=True):
                a[0] = b[0]
        return out

    def fixed(x: Signals) -> list[tuple[Column, np.ndarray]]:
        return [(Column(c, c), a) for c, a in (constant_columns(p, x) | nuisance_columns(p, x)).items()]

    cols = both(fixed)
    for name in effects:
        if name == "cogging":
            continue
        if name in DROPS:
            cols += drop_columns(name, p, s, log, held)
        elif CATALOGUE[name].channel in ("mechanical", "current-sensor"):
            cols += both(functools.partial(_effect_columns_on, name, p, log))
        else:  # no torque part: its torque rows are zero either way
            cols += effect_columns(name, p, s, log, 0)
    return cols


def _effect_columns_on(name: str, p: MotorParams, log: Log, s: Signals) -> list[tuple[Column, np.ndarray]]:
    return effect_columns(name, p, s, log, 0)


def _mid(cols: list[tuple[Column, np.ndarray]], item: str) -> float:
    """The middle shape of ``item``'s plain columns (:attr:`.columns.Column.plain`), not rivals; NaN if none."""
    shapes = sorted(c.shape for c, _ in cols if c.item == item and c.plain and not (c.rival or math.isnan(c.shape)))
    return shapes[len(shapes) // 2] if shapes else math.nan
