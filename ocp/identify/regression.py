"""Equation-error regression: every candidate as columns of one linear least-squares problem.

The three model equations, written as residuals of the NOMINAL plant on the (aligned, low-passed) log
(all (N,), SI)::

    r_mech = k_t i - J w' - B w - c_tau w|w|      [N m]   eq. dc_mechanical
    r_elec = V - L i' - R i - k_e w               [V]     eq. dc_electrical
    r_thr  = F - c_f w|w|                         [N]     eq. thrust_model

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
:func:`raw_signals`: mean speeds between samples, exact from the angle), judged through the same speed view
(:func:`speed_view`): a torque ripple locked to the rotor angle is often faster than the low-pass (20-60
periods/rev) and would be filtered out before it could be seen (:func:`ocp.identify.diagnose.diagnose`
uses that view wherever an angle is logged). The ripple's columns are its exact
means over each row (:func:`interval_ripple`), so a ripple faster than the sampling averages out instead
of aliasing, and its period count is found in the angle domain (:func:`angle_spectrum`; :func:`angle_limits`
says when the log cannot show it).

Rows are split into training and held-out samples (every ``holdout_every``-th segment); each
equation is weighted by its noise level. Only Gram matrices leave this module: fitting a model (a
subset of columns, bounded) and scoring it on held-out rows are ``P x P`` algebra (:mod:`.select`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from ocp.identify.align import cutoff_hz, smooth
from ocp.identify.angle import angle_limits, angle_spectrum, instant_spectrum, interval_ripple
from ocp.logs import Log, LogKind
from ocp.model.effects import CATALOGUE, ThrustLag, make_effect
from ocp.model.params import MotorParams
from ocp.model.plant import NUMPY

EQS = ("mechanical", "electrical", "thrust")
CONSTANTS: tuple[str, ...] = ("J", "B", "c_tau", "c_f", "k", "R", "L")
#: logger artefacts every model fits and no verdict names: ``current_lag``, the current sensor's lag [samples]
#: (a firmware filter) in the torque equation, where the true current is ``i + lag dt i'`` (in the armature
#: equation the same lag looks like an inductance: an unresolved ``L`` takes it up there)
NUISANCES: tuple[str, ...] = ("current_lag",)
#: effects found by regression (input_delay is found by the alignment)
REGRESSED = tuple(n for n in CATALOGUE if n != "input_delay")
GRID = 12
#: the torque equation's weight is at least this fraction of the smallest torque error a free run shows at
#: one noise level (:func:`visible_torque`): far smaller mismatches are averaged out of a long log but never
#: show in a prediction (tuned on proving-ground seeds 1000..1099)
VISIBLE_FRACTION = 0.15


@dataclass(frozen=True)
class Column:
    """One regressor: its candidate, the shape value it was built with, and its parameter name."""

    item: str
    key: str
    shape: float = math.nan


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
        periods: cogging periods per revolution chosen from the spectrum, and its amplitude [N m]
        spectrum: amplitude [N m] per period count 1..64 of the torque residual against angle
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
    #: per constant, the relative error a nuisance the log leaves open could mimic (``L`` under an unidentified
    #: command timing): its calibration box is ``tol`` wider by this, so it is named only beyond both
    slack: dict[str, float] = field(default_factory=dict)

    def index(self, item: str) -> list[int]:
        return [j for j, c in enumerate(self.columns) if c.item == item]


@dataclass(frozen=True)
class Signals:
    """Low-passed log channels over the held intervals k -> k+1, (M,) SI with M = N - 1 (sweeps: M = N).

    ``w0, w1``/``i0, i1``: at the interval's start and end; ``w, i``: their means; ``v``: the held command;
    ``f``, ``theta``: at the start; ``dt`` [s] (0 for a steady-state sweep: no dynamics).
    """

    w0: np.ndarray
    w1: np.ndarray
    i0: np.ndarray
    i1: np.ndarray
    w: np.ndarray
    i: np.ndarray
    v: np.ndarray
    f: np.ndarray
    theta: np.ndarray | None
    t: np.ndarray
    dt: float
    triangle: bool = False  # rows centred on the samples, torque weighted by a triangle (raw_signals)


def raw_signals(log: Log, theta: np.ndarray) -> Signals:
    """The log's rows as they are, for eq. dc_mechanical where a fast torque must keep its part, from the
    logged angle ``theta`` (N,) [rad]: row k compares the mean speeds over k-1 -> k and k -> k+1 (``w0, w1``,
    exact from the angle), whose difference times ``J`` is the torque's impulse under a triangle over
    k-1 -> k+1 (``triangle``); the current and speed are that triangle's means."""
    dt, n = log.dt, log.n
    mean_w = np.diff(theta) / dt  # (N-1,) over k -> k+1
    w0 = np.concatenate([mean_w[:1], mean_w[:-1]])
    i = log.current
    i0, i1 = 0.5 * (np.concatenate([i[:1], i[:n - 2]]) + i[:-1]), 0.5 * (i[:-1] + i[1:])  # at k -/+ half a sample
    return Signals(w0, mean_w, i0, i1, 0.5 * (w0 + mean_w), 0.5 * (i0 + i1), log.voltage[:-1], log.thrust[:-1],
                   theta[:-1], log.t[:-1], dt, triangle=True)


def signals(log: Log, p: MotorParams) -> Signals:
    if log.kind is LogKind.STEADY_STATE:
        w, i = log.omega, log.current
        return Signals(w, w, i, i, w, i, log.voltage, log.thrust, log.theta, log.t, 0.0)
    dt, fc = log.dt, cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e))
    i, v, f = (smooth(getattr(log, ch), dt, fc) for ch in ("current", "voltage", "thrust"))
    # a logged angle gives the speed without the lag of a backward-differenced or filtered speed column
    w = smooth(np.gradient(log.theta, dt) if log.theta is not None else log.omega, dt, fc)
    theta = log.theta if log.theta is not None else np.concatenate(
        [[0.0], np.cumsum(0.5 * (log.omega[1:] + log.omega[:-1]) * dt)])
    return Signals(w[:-1], w[1:], i[:-1], i[1:], 0.5 * (w[:-1] + w[1:]), 0.5 * (i[:-1] + i[1:]), v[:-1], f[:-1],
                   theta[:-1], log.t[:-1], dt)


def _armature(s: Signals, r: float, el: float) -> np.ndarray:
    """Voltage [V] that drives the current from i0 to i1 over one held sample (eq. dc_electrical, exact
    for a constant voltage: i1 = a i0 + (1 - a) V / R with a = exp(-R dt / L)); sweeps: R i."""
    if s.dt == 0:
        return r * s.i
    a = math.exp(-r * s.dt / el)
    return r * (s.i1 - a * s.i0) / (1.0 - a)


def targets(p: MotorParams, s: Signals) -> np.ndarray:
    """Nominal-model residuals (3, M): r_mech [N m], r_elec [V], r_thr [N] (module doc)."""
    dw = (s.w1 - s.w0) / s.dt if s.dt > 0 else 0.0 * s.w
    return np.vstack([p.k_t * s.i - p.J * dw - p.B * s.w - p.c_tau * s.w * np.abs(s.w),
                      s.v - _armature(s, p.R, p.L) - p.k_e * s.w,
                      s.f - p.c_f * s.w0 * np.abs(s.w0)])


def constant_columns(p: MotorParams, s: Signals) -> dict[str, np.ndarray]:
    """(3, M) per constant: the residual a relative error x = 1 of that constant leaves (to first order;
    R and L through the exact armature step by central differences)."""
    z = np.zeros_like(s.w)
    dw = (s.w1 - s.w0) / s.dt if s.dt > 0 else z
    h = 1e-4

    def arm(dr: float, dl: float) -> np.ndarray:
        return (_armature(s, p.R * (1 + dr), p.L * (1 + dl)) - _armature(s, p.R * (1 - dr), p.L * (1 - dl))) / (2 * h)

    return {"J": np.vstack([p.J * dw, z, z]), "B": np.vstack([p.B * s.w, z, z]),
            "c_tau": np.vstack([p.c_tau * s.w * np.abs(s.w), z, z]),
            "c_f": np.vstack([z, z, p.c_f * s.w0 * np.abs(s.w0)]),
            "k": np.vstack([-p.k_t * s.i, p.k_e * s.w, z]), "R": np.vstack([z, arm(h, 0.0), z]),
            "L": np.vstack([z, arm(0.0, h), z])}


def nuisance_columns(p: MotorParams, s: Signals) -> dict[str, np.ndarray]:
    """(3, M) per logger artefact (:data:`NUISANCES`) at one unit: a one-sample current lag leaves
    ``-k_t di`` in the torque residual (``di`` the current's step over the interval)."""
    z = np.zeros_like(s.w)
    return {"current_lag": np.vstack([-p.k_t * (s.i1 - s.i0) if s.dt > 0 else z, z, z])}


def _effect(name: str, values: dict[str, float], p: MotorParams, s: Signals) -> np.ndarray:
    """(3, N): an effect's contribution at these parameter values, through the catalogue's hooks."""
    eff = make_effect(name, values)
    z = np.zeros_like(s.w)
    mech = np.asarray(eff.load_torque(s.w, NUMPY, None), float) + z
    elec = s.v - np.asarray(eff.drive_voltage(s.v, s.i, NUMPY), float)
    ideal = p.c_f * s.w0 * np.abs(s.w0)
    thr = np.asarray(eff.thrust(ideal, s.w0, NUMPY, None), float) - ideal
    offset = float(eff.measured_current(0.0))
    return np.vstack([mech + p.k_t * offset, elec - p.R * offset, thr])


def _grid(lo: float, hi: float) -> np.ndarray:
    return np.geomspace(lo, hi, GRID)


def effect_columns(name: str, p: MotorParams, s: Signals, log: Log, periods: int) -> list[tuple[Column, np.ndarray]]:
    """Columns of one effect (one per shape value for shaped effects)."""
    w_peak = float(np.max(np.abs(s.w))) or 1.0
    v_peak = float(np.max(np.abs(s.v))) or 1.0
    if name == "stribeck":
        return [(Column(name, "tau_s", ws), _effect(name, {"tau_s": 1.0, "omega_s": ws}, p, s))
                for ws in _grid(0.003 * w_peak, 0.15 * w_peak)]
    if name == "brush_drop":  # the drop follows the current's sign, and while |V - k_e w| < v_b no current
        u = s.v - p.k_e * s.w  # flows: the drop is V - k_e w there, so clip(V - k_e w, +-v_b) (quasi-static)
        z = np.zeros_like(s.w)
        return [(Column(name, "v_b", vb), np.vstack([z, np.clip(u, -vb, vb) / vb, z]))
                for vb in _grid(0.005 * v_peak, 0.3 * v_peak)]
    if name == "voltage_deadband":  # a driver's dead zone: no output below v_db, the drop clip(V, +-v_db)
        z = np.zeros_like(s.w)  # (the catalogue's smooth V - v_db tanh(V / v_db) is for the optimiser)
        return [(Column(name, "v_db", vd), np.vstack([z, np.clip(s.v, -vd, vd) / vd, z]))
                for vd in _grid(0.005 * v_peak, 0.3 * v_peak)]
    if name == "thrust_lag":
        if log.kind is LogKind.STEADY_STATE:
            return []
        ideal = p.c_f * s.w0 * np.abs(s.w0)
        out = []
        for tau in _grid(max(2 * log.dt, 1e-3), 1.0):
            lagged = ThrustLag(tau=tau).observe(s.t, s.w0, s.v, ideal, None)[0]
            out.append((Column(name, "tau", tau), np.vstack([0 * ideal, 0 * ideal, lagged - ideal])))
        return out
    if name == "cogging":
        if s.theta is None or periods < 1:
            return []
        z = np.zeros_like(s.w)
        theta = np.append(s.theta, s.theta[-1] + s.w1[-1] * s.dt)
        means = list(interval_ripple(theta, periods, s.triangle))
        if not s.triangle:  # low-passed rows (no logged angle): the ripple low-passed like them
            fc = cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e))
            means = [smooth(m, log.dt, fc) for m in means]
        return [(Column(name, k, float(periods)), np.vstack([m, z, z]))
                for k, m in zip(("tau_sin", "tau_cos"), means, strict=True)]
    key = CATALOGUE[name].fitted[0]
    return [(Column(name, key), _effect(name, {key: 1.0}, p, s))]


def _rich_residual(t: np.ndarray, cols: list[np.ndarray], rows: np.ndarray) -> np.ndarray:
    """Per equation: the residual (N,) of the least-squares fit by every column's part in it (unbounded)."""
    a = np.column_stack(cols) if cols else np.zeros((t.size, 0))
    keep = np.flatnonzero(np.any(a != 0, axis=0)) if a.size else np.zeros(0, int)
    a = a[:, keep]
    if a.shape[1] == 0:
        return t
    x, *_ = np.linalg.lstsq(a[rows], t[rows], rcond=None)
    return t - a @ x


def speed_view(y: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """Torque rows (N,) [N m] seen as the speed error they cause: the rotor's first-order low-pass
    (eq. dc_mechanical ``J w' + D w = tau``, ``tau = J / D`` [s], unit gain at DC, exact for a held input),
    run forward and backward (zero phase, magnitude ``1 / (1 + (w tau)^2)``). The differentiated speed's
    noise (``J w'``, growing with frequency) falls below the speed noise, while a slow torque error keeps
    what moves the rotor: what a free run shows."""
    if dt == 0 or tau <= 2 * dt or y.size < 20:
        return y
    a = math.exp(-dt / tau)
    return np.asarray(signal.filtfilt([1.0 - a], [1.0, -a], y, padlen=0), float)


def rotor_tau(p: MotorParams, s: Signals) -> float:
    """Rotor time constant [s] at the logged speeds: ``J / (k_t k_e / R + B + 2 c_tau rms(w))`` (nominal)."""
    rms = float(np.sqrt(np.mean(s.w * s.w))) if s.w.size else 0.0
    return p.J / (p.k_t * p.k_e / p.R + p.B + 2.0 * p.c_tau * rms)


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
          noise: dict[str, float] | None = None, raw_torque: bool = False) -> Design:
    """Gram matrices (module doc) of the constants and ``effects`` on the ``train``/``test`` masks (N,).
    ``noise`` (per-sample channel noise, :func:`ocp.identify.predict.noise_levels`) floors the torque
    equation's weight at the smallest torque error a free run would show (:func:`visible_torque`).
    ``raw_torque``: eq. dc_mechanical on the raw rows where an angle is logged (module doc)."""
    s = signals(log, p)
    use_raw = raw_torque and log.kind is LogKind.TIME_SERIES and log.theta is not None
    raw = raw_signals(log, log.theta) if use_raw and log.theta is not None else s
    t = targets(p, s)
    smooth_t, t[0] = t[0].copy(), targets(p, raw)[0]
    rows = s.w.size
    edge = np.zeros(rows, dtype=bool)
    tau = rotor_tau(p, s) if log.kind is LogKind.TIME_SERIES else 0.0
    if log.kind is LogKind.TIME_SERIES:  # the low-passes' start-up and run-out transients
        m = min(math.ceil(1.5 / (cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e)) * log.dt)), rows // 6)
        edge[:m] = edge[rows - m:] = True
    train, test = train[:rows] & ~edge, test[:rows] & ~edge
    cols = _columns(p, s, raw, log, effects)
    # noise level per equation: what the richest fit (one shape per effect) leaves on training rows
    # (the motor constant is left out: with it, J, B and c_tau the torque balance scales to zero)
    keep = [j for j, (c, _) in enumerate(cols)
            if c.item != "k" and (math.isnan(c.shape) or c.shape == _mid(cols, c.item))]
    periods, spectrum, cands, angle = 0, np.zeros(0), [], {}
    if "cogging" in effects and s.theta is not None and raw.theta is not None and log.kind is LogKind.TIME_SERIES:
        theta = np.append(raw.theta, raw.theta[-1] + raw.w1[-1] * raw.dt)
        spectrum, share = angle_spectrum(_rich_residual(t[0], [cols[j][1][0] for j in keep], train), theta,
                                         raw.triangle, train, test)  # the raw rows: a fast ripple kept
        slow = instant_spectrum(_rich_residual(smooth_t, [cols[j][1][0] for j in keep], train), s.theta, train)
        cands = sorted({int(np.argmax(share)) + 1, int(np.argmax(slow)) + 1})

    # eq. dc_mechanical judged by the speed error it causes (speed_view), the others as they are; the
    # edge rows are zeroed on both sides first (still an equation), so their transients do not spread
    def view(y: np.ndarray) -> np.ndarray:
        return speed_view(np.where(edge, 0.0, y), s.dt, tau)

    for y in (t, *(a for _, a in cols)):
        y[0] = view(y[0])
    rich = [cols[j][1] for j in keep]
    if cands:
        periods, cogging = _pick_periods(cands, p, raw, log, t[0], [a[0] for a in rich], train, test, view)
        cols += cogging
        rich += [a for _, a in cogging]
        angle = angle_limits(raw.theta, periods, log.theta is not None)
    # (the armature and thrust equations keep the motor constant: their measured side does not scale)
    k_col = [a for c, a in cols if c.item == "k"]
    resid = np.vstack([_rich_residual(t[e], [a[e] for a in (rich if e == 0 else [*rich, *k_col])], train)
                       for e in range(3)])
    sigma = np.array([max(float(np.sqrt(np.mean(resid[e][train] ** 2))), 1e-12 * (np.std(t[e]) + 1e-30))
                      for e in range(3)])
    if noise is not None and s.dt > 0:
        sigma[0] = max(sigma[0], VISIBLE_FRACTION * visible_torque(p, s, noise))
    a_all = np.stack([a for _, a in cols], axis=2) / sigma[:, None, None]  # (3, N, Q)
    tw = t / sigma[:, None]
    g = {k: np.einsum("enq,enr->eqr", a_all[:, m], a_all[:, m]) for k, m in (("tr", train), ("te", test))}
    h = {k: np.einsum("enq,en->eq", a_all[:, m], tw[:, m]) for k, m in (("tr", train), ("te", test))}
    c = {k: np.einsum("en,en->e", tw[:, m], tw[:, m]) for k, m in (("tr", train), ("te", test))}
    n = {"tr": np.full(3, int(train.sum())), "te": np.full(3, int(test.sum()))}
    return Design([c_ for c_, _ in cols], g["tr"], g["te"], h["tr"], h["te"], c["tr"], c["te"], n["tr"], n["te"],
                  sigma, periods, [float(v) for v in spectrum], unresolved(p, log), angle, raw is not s,
                  _independence(p, log, s, tau))


def _independence(p: MotorParams, log: Log, s: Signals, tau: float) -> np.ndarray:
    """(3,) fraction of independent rows per equation: ``2 f_c dt`` after the low-pass (cutoff ``f_c`` [Hz]),
    and for the torque rows at most ``dt / (2 tau)`` (the speed view's memory, ``tau`` [s]); 1 on a sweep."""
    if s.dt == 0:
        return np.ones(3)
    low = min(1.0, 2.0 * cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e)) * s.dt)
    return np.array([min(low, s.dt / (2.0 * tau) if tau > 0 else 1.0), low, low])


def _columns(p: MotorParams, s: Signals, raw: Signals, log: Log,
             effects: tuple[str, ...]) -> list[tuple[Column, np.ndarray]]:
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
        if CATALOGUE[name].channel in ("mechanical", "current-sensor"):
            cols += both(functools.partial(_effect_columns_on, name, p, log))
        else:  # no torque part: its torque rows are zero either way
            cols += effect_columns(name, p, s, log, 0)
    return cols


def _effect_columns_on(name: str, p: MotorParams, log: Log, s: Signals) -> list[tuple[Column, np.ndarray]]:
    return effect_columns(name, p, s, log, 0)


def _pick_periods(cands: list[int], p: MotorParams, raw: Signals, log: Log, target: np.ndarray,
                  rich: list[np.ndarray], train: np.ndarray, test: np.ndarray,
                  view: Callable[[np.ndarray], np.ndarray]) -> tuple[int, list[tuple[Column, np.ndarray]]]:
    """Of the candidate period counts, the one whose ripple (columns seen through ``view``) explains most
    of the viewed torque residual ``target`` (M,) beyond the ``rich`` columns on the held-out rows."""
    resid = _rich_residual(target, rich, train)
    best: tuple[float, int, list[tuple[Column, np.ndarray]]] = (-math.inf, 0, [])
    for n in cands:
        cols = effect_columns("cogging", p, raw, log, n)
        for _, a in cols:
            a[0] = view(a[0])
        sc = np.column_stack([a[0] for _, a in cols])
        x, *_ = np.linalg.lstsq(sc[train], resid[train], rcond=None)
        e = resid[test] - sc[test] @ x
        gain = float(resid[test] @ resid[test] - e @ e)
        if gain > best[0]:
            best = (gain, n, cols)
    return best[1], best[2]


def unresolved(p: MotorParams, log: Log) -> dict[str, str]:
    """Constants this log cannot resolve from logger artefacts, with the reason: the inductance when the
    electrical time constant L/R is under two samples (a current filter or a fraction of a sample of
    command timing then looks the same)."""
    out = {}
    if log.kind is LogKind.STEADY_STATE or p.L / p.R < 2 * log.dt:
        out["L"] = (f"L/R = {1e3 * p.L / p.R:.3g} ms is under two samples ({1e3 * log.dt:.3g} ms): the log cannot tell "
                    "an inductance error from current filtering or sub-sample command timing")
    return out


def _mid(cols: list[tuple[Column, np.ndarray]], item: str) -> float:
    shapes = sorted(c.shape for c, _ in cols if c.item == item and not math.isnan(c.shape))
    return shapes[len(shapes) // 2] if shapes else math.nan
