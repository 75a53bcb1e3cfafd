"""The regression's rows and columns: the log's channels over held intervals (:class:`Signals`), the nominal
model's residuals (:func:`targets`) and what each candidate leaves in them (:func:`constant_columns`,
:func:`nuisance_columns`, :func:`effect_columns`), all (3, M) over the three equations of :mod:`.regression`
(eq. dc_mechanical [N m], eq. dc_electrical [V], eq. thrust_model [N]), SI.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ocp.identify.align import cutoff_hz, smooth
from ocp.identify.angle import drift_windows, interval_ripple, rotor_angle, track_phase
from ocp.identify.noise_level import sensor_noise
from ocp.identify.thrust_square import low_passed_square
from ocp.logs import Log, LogKind
from ocp.model.effects import CATALOGUE, ThrustLag, make_effect
from ocp.model.params import MotorParams
from ocp.model.plant import NUMPY

GRID = 12  # shape values per shaped effect (geometric grid)
#: saturating voltage drops (their columns: :func:`.drops.drop_columns`)
DROPS = ("brush_drop", "voltage_deadband")
#: a Stribeck band is offered only where some row shows at least this share of its level (:func:`effect_columns`)
STRIBECK_REACH = 0.5
#: Stribeck friction's decay exponents offered (``exp(-|w / omega_s|^delta)``): the Gaussian (the catalogue's
#: default) and Tustin's exponential (:mod:`.shape_choice` prefers the first). With the Gaussian alone, a friction
#: decaying as ``exp(-|r|^0.5..0.9)`` (proving ground ``--shapes``) was named with a Coulomb friction or a ``B``
#: beside it; 0.5 offered too took Coulomb frictions (seeds 107, 126)
STRIBECK_DECAYS = (2.0, 1.0)
#: Coulomb friction's sign is offered at these smoothing widths ``omega_eps`` (fractions of the logged peak speed, the
#: grid's ends; the catalogue's 0.5 rad/s at most the upper end): dry friction is a sign, sharp at zero speed, and
#: its rotor dwells there at speeds far under 0.5 rad/s while the motor torque stays within ``+-tau_c``. The
#: catalogue's smoothing (set for the optimiser) left a residual at every dwell, which a ripple of some period
#: count or a Stribeck band then took up (proving ground: Coulomb friction alone named with cogging)
COULOMB_EDGES = (1e-4, 1e-2)
#: ... at this many widths (geometric, a step of 2.5x; the fit mixes neighbours): twelve took ~10 % more diagnosis
#: time and got one verdict fewer right on 1,000 proving-ground logs (10009)
COULOMB_GRID = 6


@dataclass(frozen=True)
class Column:
    """One regressor: its candidate, the shape value it was built with, and its parameter name."""

    item: str
    key: str
    shape: float = math.nan
    #: a second shape, fixed per column: Stribeck friction's decay exponent (:data:`STRIBECK_DECAYS`), a dead
    #: band's form (:data:`.drops.DEAD_BAND_FORMS`), a brush contact's soft form (:data:`.drops.SOFT_CONTACT`: ``shape``
    #: is then its current width [A]); grid neighbours (:func:`.select.fit_model`) share it
    form: float = math.nan
    #: False: zero at the rows where the rotor is at rest (:func:`at_rest`), for a model whose dry friction holds it
    at_rest: bool = True
    #: True: fitted only as a rival to an adopted item (:func:`.select._challenge`), never offered to the selection
    #: nor in the noise level's rich fit: a dead band under a command of one magnitude (:func:`.drops.drop_columns`)
    rival: bool = False

    @property
    def plain(self) -> bool:
        """Whether the column has no second shape, or the catalogue's default one (the first offered)."""
        return math.isnan(self.form) or (self.item == "stribeck" and self.form == STRIBECK_DECAYS[0])



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
    #: (M,) [A] by how much the raw row's current ``i`` overstates its triangle's mean of a current that bends
    #: smoothly between the samples (``current_bend``, :func:`nuisance_columns`); None on low-passed rows
    bend: np.ndarray | None = None
    #: the speed is the identifier's own central derivative of a logged angle: no logger's lag (``speed_lag``)
    from_angle: bool = False
    #: (M,) [rad^2/s^2] ``w|w|`` at the interval's start as the thrust's low-pass sees it (:func:`speed_square`); None:
    #: ``w0 |w0|`` (raw rows, or a speed too noisy for it: :func:`.thrust_square.low_passed_square`)
    square: np.ndarray | None = None


def raw_signals(log: Log, theta: np.ndarray) -> Signals:
    """The log's rows as they are, for eq. dc_mechanical where a fast torque must keep its part, from the
    logged angle ``theta`` (N,) [rad]: row k compares the mean speeds over k-1 -> k and k -> k+1 (``w0, w1``,
    exact from the angle), whose difference times ``J`` is the torque's impulse under a triangle over
    k-1 -> k+1 (``triangle``); the current and speed are that triangle's means."""
    dt, n = log.dt, log.n
    mean_w = np.diff(theta) / dt  # (N-1,) over k -> k+1
    w0 = np.concatenate([mean_w[:1], mean_w[:-1]])
    i = log.current
    before = np.concatenate([i[:1], i[:n - 2]])  # (N-1,) the sample k-1 (the first row: its own)
    i0, i1 = 0.5 * (before + i[:-1]), 0.5 * (i[:-1] + i[1:])  # at k -/+ half a sample
    # eq. dc_mechanical over k-1 -> k+1: the triangle's (1, 2, 1)/4 rule against its exact mean of a quadratic,
    # i_k + i''/12
    bend = (before - 2.0 * i[:-1] + i[1:]) / 6.0
    return Signals(w0, mean_w, i0, i1, 0.5 * (w0 + mean_w), 0.5 * (i0 + i1), log.voltage[:-1], log.thrust[:-1],
                   theta[:-1], log.t[:-1], dt, triangle=True, bend=bend, from_angle=True)


def signals(log: Log, p: MotorParams) -> Signals:
    if log.kind is LogKind.STEADY_STATE:
        w, i = log.omega, log.current
        return Signals(w, w, i, i, w, i, log.voltage, log.thrust, log.theta, log.t, 0.0)
    dt, fc = log.dt, cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e))
    i, v, f = (smooth(getattr(log, ch), dt, fc) for ch in ("current", "voltage", "thrust"))
    # a logged angle gives the speed without the lag of a backward-differenced or filtered speed column
    raw = np.gradient(log.theta, dt) if log.theta is not None else log.omega
    w = smooth(raw, dt, fc)
    # eq. thrust_model on the low-passed thrust: the low-pass of c_f w|w|, not c_f times the square of the low-passed
    # speed (their difference does not fall with the sample time)
    square = low_passed_square(log, raw, w, fc, p.c_f)
    theta = rotor_angle(log)
    return Signals(w[:-1], w[1:], i[:-1], i[1:], 0.5 * (w[:-1] + w[1:]), 0.5 * (i[:-1] + i[1:]), v[:-1], f[:-1],
                   theta[:-1], log.t[:-1], dt, from_angle=log.theta is not None,
                   square=None if square is None else square[:-1])


def speed_square(s: Signals) -> np.ndarray:
    """(M,) [rad^2/s^2] ``w|w|`` at each interval's start, for eq. thrust_model: on low-passed rows the low-pass of
    ``w|w|`` (:func:`.thrust_square.low_passed_square`), which the low-passed thrust is to be compared with; else (and
    where the speed is too noisy for it) ``w0 |w0|``."""
    return s.w0 * np.abs(s.w0) if s.square is None else s.square


#: the rotor is taken at rest over runs of at least REST_ROWS rows whose low-passed speed stays within REST_NOISE
#: noise levels of zero (:func:`at_rest`; both set before any proving-ground run, not tuned)
REST_NOISE = 3.0
REST_ROWS = 3


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """The maximal runs ``[a, b)`` of True rows in ``mask`` (M,), in order."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _rest_speed(s: Signals, log: Log, p: MotorParams) -> float:
    """:data:`REST_NOISE` noise levels [rad/s] of the low-passed speed: the speed column's per-sample noise
    (:func:`.noise_level.sensor_noise`) through the low-pass."""
    low = min(1.0, 2.0 * cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e)) * s.dt)
    return REST_NOISE * sensor_noise(log.omega) * math.sqrt(low)


def at_rest(s: Signals, log: Log, p: MotorParams) -> np.ndarray:
    """Rows (M,) where the rotor is at rest: its low-passed speed within :data:`REST_NOISE` noise levels of zero
    (:func:`_rest_speed`) for at least :data:`REST_ROWS` rows in a row. There dry friction is set-valued: it holds
    whatever torque stays within its level, and the torque equation's residual is wherever the rotor stopped (none on
    a sweep)."""
    out = np.zeros(s.w.size, dtype=bool)
    if s.dt == 0:
        return out
    for a, b in runs(np.abs(s.w) <= _rest_speed(s, log, p)):
        out[a:b] = b - a >= REST_ROWS
    return out


#: a run at rest is HELD where the nominal torque over it would have changed the speed by more than this many times
#: what it did (and by over REST_NOISE noise levels; :func:`held_still`; set before any proving-ground run, not tuned)
HOLD_RATIO = 2.0


def held_still(s: Signals, log: Log, p: MotorParams, rest: np.ndarray) -> np.ndarray:
    """Rows (M,) where something holds the rotor (dry friction, a detent): the runs at rest ``rest`` (M,)
    (:func:`at_rest`) over which the nominal torque balance would have moved it, ``sum (k_t i - B w - c_tau w|w|) dt
    / J`` [rad/s] (eq. dc_mechanical), by :data:`HOLD_RATIO` times the speed change the log shows and by
    :data:`REST_NOISE` noise levels of the low-passed speed, but the rotor stayed. There the torque balance holds an
    unknown torque (whatever stays within the friction's level), which no column expresses; a rotor passing zero
    freely, or standing without a torque, is not held. (A ripple's detent holds a rotor too, with a torque its
    columns do express: cut with the rest, that evidence is lost; proving ground, session 23: 7 of 137 ripples.)"""
    out = np.zeros_like(rest)
    if not rest.any():
        return out
    level = _rest_speed(s, log, p)
    # eq. dc_mechanical: the speed change per row the nominal torque balance gives
    dw = (p.k_t * s.i - p.B * s.w - p.c_tau * s.w * np.abs(s.w)) * s.dt / p.J
    for a, b in runs(rest):
        out[a:b] = abs(float(dw[a:b].sum())) > max(HOLD_RATIO * abs(float(s.w1[b - 1] - s.w0[a])), level)
    return out


def settle_weight(p: MotorParams, dt: float) -> float:
    """``c = 1/(1 - a) - L/(R dt)``, ``a = exp(-R dt/L)``: the weight of a held row's end speed in the back-EMF that
    its exact armature step sees (:func:`emf_speed`); 1/2 for an armature much slower than a row, 1 for one much
    faster (its current follows the speed and shows the end's back-EMF). ``dt`` [s] the row."""
    x = dt * p.R / p.L
    return 1.0 / -math.expm1(-x) - 1.0 / x if x < 700.0 else 1.0


def emf_speed(s: Signals, p: MotorParams) -> np.ndarray:
    """The speed [rad/s] (M,) whose back-EMF eq. dc_electrical pairs with the held row's exact step
    (:func:`_armature`): ``w0 + c (w1 - w0)``, ``c`` = :func:`settle_weight`, exact for a speed linear over the row.
    (The row's mean speed, ``c = 1/2``, is right only for an armature much slower than a row: at a mechanical time
    constant of 4.5 samples and L/R a few hundredths of one, clean proving-ground logs had ``R`` named 11-22 %
    high.) Sweeps: the speed."""
    if s.dt == 0:
        return s.w
    # eq:dc_electrical  L i' = V - R i - k_e w  over [0, dt] with w = w0 + (w1 - w0) t / dt, V held:
    # i1 = a i0 + (1 - a) (V - k_e w0) / R - k_e (w1 - w0) (dt - (L/R)(1 - a)) / (R dt)
    return s.w0 + settle_weight(p, s.dt) * (s.w1 - s.w0)


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
                      s.v - _armature(s, p.R, p.L) - p.k_e * emf_speed(s, p),
                      s.f - p.c_f * speed_square(s)])


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
            "c_f": np.vstack([z, z, p.c_f * speed_square(s)]),
            "k": np.vstack([-p.k_t * s.i, p.k_e * emf_speed(s, p), z]), "R": np.vstack([z, arm(h, 0.0), z]),
            "L": np.vstack([z, arm(0.0, h), z])}


def nuisance_columns(p: MotorParams, s: Signals) -> dict[str, np.ndarray]:
    """(3, M) per logger artefact (:data:`NUISANCES`) at one unit: a current sensor's first-order filter of lag
    ``lam`` samples, ``i_f[n] = i_f[n-1] + (i[n] - i_f[n-1]) / (1 + lam)``, is undone exactly by
    ``i[n] = i_f[n] + lam (i_f[n] - i_f[n-1])``: a BACKWARD difference. A row averages the current at its two
    ends (or three samples under a triangle), so it leaves ``-k_t lam`` times the mean of the backward differences
    at those samples in the torque residual: ``(di + di_prev) / 2`` with ``di = i1 - i0`` the row's own step. (The
    row's own step alone is that derivative half a sample late: the same for a smooth current, but a current that
    steps, a fast armature under a stepped command, then leaves a residual the acceleration's column takes: ``J``
    was named 11-14 % low on tuning logs with a right J, at a mechanical time constant of four samples.)

    ``switch_phase``, ``x = phi - 1/2``: the drive applies a new command ``phi`` of a row after the sample (the
    alignment removes whole samples; a fraction the current cannot show where the armature settles within a row, so
    the torque equation measures it). The row's mean current is then the end samples' mean less ``x (2c - 1) q``,
    ``q = (i1 - i0) + (k_e/R)(w1 - w0)``, ``c`` = :func:`settle_weight`: eq. dc_electrical over the row, exact for
    a switch at its start at any armature speed and for any ``phi`` where the armature settles within the row (for
    a fast armature ``q`` is the command's step over ``R``: the impulse of switching late; a slow one has
    ``c = 1/2`` and no column). With the row's mean current fixed at the samples' mean, ``J`` was held at the edge of
    its box and ``B`` at the other's (proving ground, mechanical time constant of 4.5 samples).

    ``current_bend``, ``x`` in 0..1, on the raw rows: their current is the triangle's (1, 2, 1)/4 rule, exact for a
    current that holds or steps at the samples, but over the exact mean of a current that bends smoothly between
    them by ``Signals.bend`` (its second difference over 6): the torque residual keeps ``k_t x bend``. A fast
    armature under a PI loop's or a chirp's command bends its current every row: on noise-free proving-ground
    replays at 200-500 Hz (L/R under half a sample) the column took 30-60 % of the torque error the other two
    nuisances leave (23174: 2.1 -> 0.8 mN m), the error that hid a ripple at reversals (cogging at 100 Hz: 12047).
    (The low-passed rows' current is smooth within the low-pass; there the column gave a tachometer log at 47 Hz a
    false ripple beside Coulomb friction: ``tests/identify/test_emf_speed.py``, rig 3203.)

    ``speed_lag``, ``x`` samples: the logged speed is the rotor's ``x`` samples earlier, ``w_true = w + x dt w'``;
    eq. dc_electrical keeps ``k_e x (w1 - w0)``, the thrust map ``2 c_f |w| x (w1 - w0)`` and eq. dc_mechanical
    ``x dt (J w'' + (B + 2 c_tau |w|) w')``. An encoder's speed differenced over ``d`` samples and logged without its
    angle is the mean over them, ``d / 2`` samples late, which left ``k_e k_t d dt / (2 J)`` in the armature equation
    as a false ``R`` (session 33: proving-ground logs with the angle column left out, 37 false ``R`` over 800; fitted
    0.7-1.0 samples for a two-sample difference, about 0 for a tachometer). Without its torque part the current's lag
    took the speed's in eq. dc_mechanical, at its bound of -1 sample where the current was not filtered, and ``J``
    was named beside right verdicts (without the angle, 6000..6199: 177 -> 182 exactly right with it). Where the
    angle is logged the speed is this module's own central derivative of it: no column (fitted there, 1.8 samples
    took the armature residual of a PRBS log, 14000, and a false ``thrust_lag`` undid it in the thrust map)."""
    z = np.zeros_like(s.w)
    if s.dt == 0:
        return {name: np.vstack([z, z, z]) for name in ("current_lag", "switch_phase", "current_bend", "speed_lag")}
    step = s.i1 - s.i0
    d = 0.5 * (step + np.concatenate([step[:1], step[:-1]]))  # (M,): the first row has no previous step: its own
    dw = s.w1 - s.w0  # [rad/s] (M,): the row's speed step, dt w'
    q = step + p.k_e / p.R * dw  # [A] (M,)
    # eq. dc_mechanical at w + x dt w': x dt (J w'' + (B + 2 c_tau |w|) w') [N m] per unit x
    torque = p.J * (np.gradient(dw / s.dt) if dw.size > 1 else z) + (p.B + 2.0 * p.c_tau * np.abs(s.w)) * dw
    return {"current_lag": np.vstack([-p.k_t * d, z, z]),
            "switch_phase": np.vstack([-(2.0 * settle_weight(p, s.dt) - 1.0) * p.k_t * q, z, z]),
            "current_bend": np.vstack([p.k_t * (z if s.bend is None else s.bend), z, z]),
            "speed_lag": np.vstack([z, z, z]) if s.from_angle else
            np.vstack([torque, p.k_e * dw, 2.0 * p.c_f * np.abs(s.w0) * dw])}


def _effect(name: str, values: dict[str, float], p: MotorParams, s: Signals) -> np.ndarray:
    """(3, N): an effect's contribution at these parameter values, through the catalogue's hooks (a load torque as
    its mean over each row, :func:`_row_mean`)."""
    eff = make_effect(name, values)
    z = np.zeros_like(s.w)
    mech = _row_mean(lambda w: np.asarray(eff.load_torque(w, NUMPY, None), float) + z, s)
    elec = s.v - np.asarray(eff.drive_voltage(s.v, s.i, NUMPY), float)
    ideal = p.c_f * speed_square(s)
    thr = np.asarray(eff.thrust(ideal, s.w0, NUMPY, None), float) - ideal
    offset = float(eff.measured_current(0.0))
    return np.vstack([mech + p.k_t * offset, elec - p.R * offset, thr])


#: points of the row mean of a load torque over the speed's path within a row (:func:`_row_mean`)
ROW_POINTS = 8


def _row_mean(torque: Callable[[np.ndarray], np.ndarray], s: Signals) -> np.ndarray:
    """A load torque's mean over each row (M,) [N m] (eq. dc_mechanical holds over the held interval), the speed
    taken linear from the row's start ``w0`` to its end ``w1`` (midpoint rule, :data:`ROW_POINTS` points): a
    friction's sign flips inside the row where the speed passes zero, and at the row's mean speed it would be
    taken whole (a sweep, ``dt = 0``: at the speed)."""
    if s.dt == 0:
        return torque(s.w)
    u = (np.arange(ROW_POINTS) + 0.5) / ROW_POINTS
    return np.mean([torque(s.w0 + f * (s.w1 - s.w0)) for f in u], axis=0)


def _grid(lo: float, hi: float, n: int = GRID) -> np.ndarray:
    return np.geomspace(lo, hi, n)


def _peak_speed(log: Log) -> float:
    """The logged peak speed [rad/s], at least 10: the friction grids' scale (their ends in the catalogue's ranges)."""
    return max(float(np.max(np.abs(log.omega))), 10.0)  # (a rotor held still crashed diagnose: blind rig 281)


def stribeck_bands(log: Log) -> list[tuple[float, float]]:
    """Stribeck bands offered, (speed [rad/s], decay exponent) each: the speeds on a grid over 0.3-15 % of the
    logged peak speed, for each decay of :data:`STRIBECK_DECAYS` (by decay, then speed), less the bands no logged
    row shows at :data:`STRIBECK_REACH` of their level or more (the friction's level would be extrapolated from
    its tail: a 4.5 rad/s band fitted at 178 N m for 3.7 mN m of Stribeck friction at 15 rad/s, on a log whose
    rotor either stood still or ran above 15 rad/s, and the free run of that plant took two minutes)."""
    w_peak = _peak_speed(log)
    return [(float(ws), d) for d in STRIBECK_DECAYS for ws in _grid(0.003 * w_peak, 0.15 * w_peak)
            if np.max(np.abs(make_effect("stribeck", {"tau_s": 1.0, "omega_s": ws, "delta": d}).load_torque(
                log.omega, NUMPY, None))) >= STRIBECK_REACH]


def ripple_windows(log: Log, s: Signals, periods: int) -> np.ndarray:
    """(M, K) hat functions over the rows ``s`` for a ripple of ``periods``/rev (:func:`.angle.drift_windows`):
    where the angle is integrated from the log's speed column (no angle logged), from that column's noise; else
    (M, 1) ones."""
    if log.theta is not None or s.dt == 0:
        return np.ones((s.t.size, 1))
    return drift_windows(s.t, periods, sensor_noise(log.omega), s.dt)


def ripple_phase(s: Signals, log: Log, periods: int, cols: list[tuple[Column, np.ndarray]], resid: np.ndarray,
                 train: np.ndarray, view: Callable[[np.ndarray], np.ndarray]) -> np.ndarray | None:
    """Unit phasors (M,) tracking the ripple ``cols`` (cogging's two columns at ``periods``/rev,
    :func:`effect_columns`) along an angle integrated from the speed column (:func:`.angle.track_phase` on the torque
    residual ``resid`` (M,), columns seen through ``view``), or None where the angle is logged or its drift stays
    within one phase (:func:`ripple_windows`)."""
    h = ripple_windows(log, s, periods)
    if h.shape[1] < 2:
        return None
    sin, cos = (a[0] for _, a in cols)
    return track_phase(cos + 1j * sin, h, resid, train, view)


def turn_ripple(cols: list[tuple[Column, np.ndarray]], phase: np.ndarray) -> list[tuple[Column, np.ndarray]]:
    """Cogging's two columns (``tau_sin``, ``tau_cos``; (3, M) each) turned by the unit phasors ``phase`` (M,) of a
    drifting integrated angle (:func:`ripple_phase`); new arrays."""
    (c_sin, a_sin), (c_cos, a_cos) = cols
    z = (a_cos[0] + 1j * a_sin[0]) * phase
    return [(c_sin, np.vstack([z.imag, a_sin[1:]])), (c_cos, np.vstack([z.real, a_cos[1:]]))]


def effect_columns(name: str, p: MotorParams, s: Signals, log: Log, periods: int) -> list[tuple[Column, np.ndarray]]:
    """Columns of one effect (one per shape value for shaped effects; cogging's at ``periods``/rev, turned along a
    drifting angle by :func:`turn_ripple`)."""
    if name == "stribeck":  # on the logged speed's range, the same for the low-passed and the raw rows
        return [(Column(name, "tau_s", ws, form=d), _effect(name, {"tau_s": 1.0, "omega_s": ws, "delta": d}, p, s))
                for ws, d in stribeck_bands(log)]
    if name == "coulomb_friction":  # the sign's sharpness on a grid (COULOMB_EDGES)
        w_peak = _peak_speed(log)
        return [(Column(name, "tau_c", eps), _effect(name, {"tau_c": 1.0, "omega_eps": eps}, p, s))
                for eps in _grid(COULOMB_EDGES[0] * w_peak, max(0.5, COULOMB_EDGES[1] * w_peak), COULOMB_GRID)]
    if name in DROPS:
        raise ValueError(f"{name}: a voltage drop's columns are formed on the held command (.drops.drop_columns)")
    if name == "thrust_lag":
        if log.kind is LogKind.STEADY_STATE:
            return []
        ideal = p.c_f * speed_square(s)
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
