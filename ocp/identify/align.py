"""Timing alignment between the logged command and the sensors: a nuisance estimated before anything else.

A logged command drives the armature some time after the row it is logged in: a zero-order-held drive
applies it over the following sample (half a sample on average), a loop that logs the command it is
about to write next to the sensors it just read adds a whole sample, a drive that latches on the next
PWM period adds a fraction. The *alignment* is that lag, in samples, beyond the zero-order hold.

Estimate: the armature equation over one held sample (eq. dc_electrical, exact under a zero-order hold) with free
coefficients, so wrong nominal constants do not bias it, plus brush-drop, dead-band and offset terms:
``i[k+1] = a1 i[k] + a2 V[k - lag] + a3 w[k] + a3' w[k+1] + a4 sign(i) + a5 + a6 sign(V[k - lag])`` (the speed at both
ends free: a fast armature's end current shows the end's back-EMF, a slow one's the row's mean, and a tachometer's
filter or a differenced encoder logs the speed late, to first order a share of its step; with their mean alone the fit
moved the command to match, session 60: ``tests/identify/test_alignment_speed_lag.py``), fitted by least squares (raw
samples) for whole-sample lags up to :func:`search_range` (24 samples or 5 ms, whichever is longer, at most 64 samples),
then on a grid of 1/8 sample around the best; the lag of the smallest residual, refined by a parabola through its
neighbours, is the alignment (0 for a log whose row-k command drives k -> k+1). The dead-band term is the held commands'
dead band shifted (the drive's nonlinearity acts on each held level before two of them share a sample), ``v_db tanh(V /
v_db)`` (the catalogue's form, eq. voltage_deadband) with its width searched per lag on :data:`DEAD_BAND_WIDTHS` (a
width fixed at 5 % of the command's spread left a 2.3 V dead band under a 10 V PI command 8 A off inside the band, and
the lag a sample short; proving ground 117). The current-sign column is left out under one command magnitude
(:func:`voltage_spread`: a square wave, a PRBS), where the sign is the command's on every held row and fits its level
changes at any lag (a square wave's residual was flat from 0 to 0.875 samples, session 62), and a drop is a gain on the
command anyway. Residuals under :data:`RESOLUTION` of the current's spread count as equal (a noise-free step after 25
rows at rest passed 1 % differences of the integrator's error as a sharp minimum: a 12-sample delay, session 63). A
minimum that is not sharp (residual within 1 % one sample either side) is a plateau: bounded inside the search and at
most two samples wide (a slow two-level command, whose rare level changes tell the lag only to within about a sample),
its midpoint is the alignment; wider or reaching an end of the search (slow, smooth excitation), the free fit cannot
tell the lag: a smooth command delayed by ``d`` samples looks like one through an armature lag ``L/R`` longer by ``d``
samples, and the free ``a1`` takes either. The datasheet can, where the armature is fast: given the nominal ``L/R`` (at
most :data:`NOMINAL_TAU` samples, so that a 50 % inductance error moves the lag by at most a sample) and ``k_e``, the
search is repeated with both held at nominal, as an output error (the current simulated from the command through that
first-order lag, eq. dc_electrical, with free gains and the speed read up to three samples ahead: noise in the
logged current then biases nothing, nor a lagging speed sensor):
:func:`_nominal_curve`. A lag found so is reported as resting on the nominal armature (:attr:`Alignment.nominal`), and
the caller must not judge ``L`` from the same log as if the timing were measured. Where that search is flat too (no fast
enough command change at all), the lag is unidentifiable: none is assumed then, and none is called a delay. Held at a
slower armature's ``L/R`` of ``tau`` samples, a 50 % inductance error moves the lag by ``tau / 2``
(:data:`HELD_L_ERROR`, :attr:`Alignment.bias`): a lag found so beyond the conventions is a delay only where it predicts
the held-out data better than the longer ``L/R`` that would explain it (the caller's test, :mod:`.diagnose`;
:func:`gain` does not vouch for a held curve). (Until session 53 a lag within that share was not offered to that test:
blind seed 431's was named ``L`` +45 %.) Of the 1,800 proving-ground logs, 45 with a slow armature had a flat free
search: six delays, of which this finds three, and no false one among the 39 others, nor with their inductance 50 %
above nominal; with it twice nominal, one (measured with the share as a filter).

Rule (stated, user-settable): an alignment up to ``max_logging_skew + 0.75`` samples is what logging conventions
explain (default 2 samples: a command logged up to two rows early, plus a fraction for the drive's update instant); it
is removed from the log (its fraction of a sample as the drive switching within the row, :func:`switched`) and
reported as ``alignment``. Beyond that, the lag is a transport delay: ``input_delay`` enters the verdict with
``delay`` = the whole lag [s] -- when it predicts the held-out data better than the best lag within the conventions
(:func:`within`; the test is the caller's, :mod:`.diagnose`), or when the search's residual there is
:data:`DELAY_GAIN` times that of the best lag within them (:func:`gain`). (The free runs of the held-out test use the
nominal constants: a 34 % inertia error or a dead band beside a delay swamped it on 4 of the 100 delayed logs among
1,200 benchmark logs, whose gains were 2.3 to 12; the largest gain of a lag beyond the conventions on the 1,100 logs
without a delay was 1.45.)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from ocp.filters import butter2, filtfilt, iir
from ocp.logs import Log, LogKind
from ocp.parallel import ordered

#: finest lag step [samples]; the search range: at least MIN_LAG samples and MIN_LAG_S seconds, at most MAX_LAG
LAG_STEP = 0.125
MIN_LAG = 24
MIN_LAG_S = 0.005
MAX_LAG = 64
#: the fraction of a sample a drive's update instant adds to the logging skew (the rule, module doc)
SKEW_FRACTION = 0.75
#: longest nominal armature time constant L/R [samples] for which a lag is measured with it held
#: (:func:`_nominal_curve`): a 50 % inductance error then moves the lag by at most a sample
NOMINAL_TAU = 2.0
#: [samples] how far ahead the logged speed may be read by :func:`_nominal_curve` (free gains): a sensor's lag
SPEED_LEADS = (1, 2, 3)
#: the inductance error [fraction of nominal] a lag measured with a slower armature held may stand for: it moves the
#: lag by that share of the L/R (:attr:`Alignment.bias`), the same 50 % that bounds :data:`NOMINAL_TAU`'s one sample
HELD_L_ERROR = 0.5
#: how many times lower the search residual (eq. dc_electrical, free coefficients) must be at a lag beyond the
#: conventions than at the best lag within them for that lag to be measured as a delay by itself (:func:`gain`)
DELAY_GAIN = 2.0
#: the dead band's widths tried in the free search [fractions of the command's standard deviation] (module doc)
DEAD_BAND_WIDTHS = (0.05, 0.1, 0.2, 0.3, 0.5)
#: a magnitudes' spread (:func:`voltage_spread`) from here up is one command magnitude (a two-level command)
ONE_MAGNITUDE = 0.5
#: the armature time constants L/R tried by :func:`armature_error` [x nominal]: a factor four either way, wider than
#: the factor-two prior, so that the conventions' lag has every longer L/R to mimic a delay with
ARMATURE_TAUS = tuple(float(x) for x in np.geomspace(0.25, 4.0, 33))
#: widest flat minimum [samples] taken as a measured lag (its midpoint): a level change of a two-level command
#: pins the lag to within about a sample on either side; a wider one is a smooth excitation's (no lag measured)
PLATEAU = 2.0
#: the finest current residual a search tells apart [x the logged current's standard deviation]: a 13-bit logger's
#: quantization; below it, a 1 % difference is the integrator's or the float's error, not the timing
RESOLUTION = 1e-4


@dataclass(frozen=True)
class Alignment:
    """Command-to-sensor alignment.

    Attributes:
        samples: lag beyond the zero-order hold [samples] (0 for a log whose row k command drives k -> k+1)
        seconds: the same [s]
        delay: True when the rule calls it an ``input_delay`` (then ``seconds`` is the delay)
        rule: the rule in words
        curve: (lags [samples], normalised residual RMS) of the search, for plots
        identified: False when the search's residual is flat (then ``samples`` is 0 by assumption, not measured)
        nominal: True when the lag was found only with the armature's nominal ``L/R`` and ``k_e`` (module doc)
        bias: [samples] how far a :data:`HELD_L_ERROR` inductance error moves a lag found with a nominal ``L/R``
            over :data:`NOMINAL_TAU` samples (0 otherwise): such a lag is a delay only where held-out data prefer it
            to that longer ``L/R`` (the caller's test)
        applied: [samples] the lag the equations saw the command moved by (:func:`applying`: ``samples`` read by
            :func:`switched`, less the plant's own delay), where the log was realigned; None otherwise
    """

    samples: float
    seconds: float
    delay: bool
    rule: str
    curve: tuple[tuple[float, ...], tuple[float, ...]] = ((), ())
    identified: bool = True
    nominal: bool = False
    bias: float = 0.0
    applied: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"samples": round(self.samples, 3), "seconds": self.seconds, "called_input_delay": self.delay,
                "rule": self.rule, "identified": self.identified, "from_nominal_armature": self.nominal,
                "applied_samples": None if self.applied is None else round(self.applied, 3)}


def smooth(y: np.ndarray, dt: float, cutoff: float) -> np.ndarray:
    """Zero-phase 2nd-order Butterworth low-pass of ``y`` (N,) at ``cutoff`` [Hz] (identity at/above Nyquist)."""
    wn = 2.0 * cutoff * dt
    if wn >= 0.95 or y.size < 20:
        return y.astype(float)
    b, a = butter2(wn)
    return filtfilt(b, a, y, padlen=min(3 * max(len(a), len(b)), y.size - 1))


def shifted(y: np.ndarray, lag: float) -> np.ndarray:
    """``y`` (N,) or each column of ``y`` (N, B) delayed by ``lag`` samples (fractional: linear interpolation;
    edges held)."""
    k = np.arange(y.shape[0], dtype=float)
    if y.ndim == 1:
        return np.interp(k - lag, k, y)
    return np.column_stack([np.interp(k - lag, k, c) for c in y.T])


def cutoff_hz(log: Log, tau_m: float) -> float:
    """Low-pass used on every channel before derivatives [Hz]: ``4/tau_m`` (about 25 times the mechanical
    bandwidth, ``tau_m = J R / (k_t k_e)`` [s] nominal), within 2 Hz .. 15 % of the sample rate."""
    return float(np.clip(4.0 / tau_m, 2.0, min(0.15 / log.dt, 400.0)))


def search_range(dt: float) -> int:
    """Longest lag searched [samples]: ``MIN_LAG`` samples or ``MIN_LAG_S`` seconds, whichever is longer, at
    most ``MAX_LAG`` samples (a fast logger sees a transport delay of a few ms as tens of samples)."""
    return int(min(max(MIN_LAG, math.ceil(MIN_LAG_S / dt)), MAX_LAG))


def _residual(target: np.ndarray, gram: np.ndarray, cross: np.ndarray, cols: np.ndarray, v: np.ndarray,
              bands: np.ndarray) -> float:
    """Smallest RMS over the dead-band terms ``bands`` (M, B) of the least-squares fit of ``target`` (M,) by ``cols``
    (M, P) (Gram ``gram``, ``cross`` = cols' target), the command ``v`` (M,) and one dead-band term; normal equations
    (few columns, many rows)."""
    extra = np.column_stack([v, bands])  # (M, 1 + B)
    cx = cols.T @ extra
    g_all = np.block([[gram, cx], [cx.T, extra.T @ extra]])  # every product over the rows, once
    h_all = np.concatenate([cross, extra.T @ target])
    p = cols.shape[1]
    best = math.inf
    for b in range(1, extra.shape[1]):
        pick = [*range(p + 1), p + b]  # cols, v and one dead-band term
        g, h = g_all[np.ix_(pick, pick)], h_all[pick]
        d = np.sqrt(np.maximum(np.diag(g), 1e-300))
        x = np.linalg.lstsq(g / np.outer(d, d), h / d, rcond=1e-12)[0] / d
        best = min(best, float(target @ target - 2 * h @ x + x @ g @ x))
    return math.sqrt(max(best, 0.0) / target.size)


def estimate(log: Log, max_logging_skew: float = 2.0, armature: tuple[float, float] | None = None) -> Alignment:
    """Alignment of a time-series log (see module doc); steady-state sweeps have none. ``armature``: the nominal
    ``(L/R [s], k_e [V s/rad])``, used only where the free search is flat."""
    rule = (f"lags up to {max_logging_skew:g} + {SKEW_FRACTION:g} samples are logging conventions, removed and "
            "reported; a longer lag is an input_delay (the whole lag)")
    if log.kind is LogKind.STEADY_STATE:
        return Alignment(0.0, 0.0, False, rule)
    v, i, w = log.voltage, log.current, log.omega  # raw: the relation is exact per held sample
    top = min(search_range(log.dt), max(log.n // 4 - 12, 1))
    k = np.arange(top + 10, max(top + 20, log.n - 10))
    ibar = 0.5 * (i[k] + i[k + 1])
    # the speed at both ends of the row, free: the back-EMF at the row's end (a fast armature's end current) or its mean
    # (a slow one's), a speed sensor's lag to first order; a brush drop's current sign, not under one magnitude (doc)
    sign = [np.tanh(ibar / (0.05 * np.std(i) + 1e-12))] if voltage_spread(v) < ONE_MAGNITUDE else []
    cols = np.column_stack([i[k], w[k], w[k + 1], *sign, np.ones(k.size)])
    gram, cross = np.einsum("mp,mq->pq", cols, cols), np.einsum("mp,m->p", cols, i[k + 1])
    # the drive's dead band acts on each held command, before the held commands share a sample: shifted after
    # the nonlinearity (else, for a two-level command, it is a free column on the rows where the level changes,
    # and absorbs any sub-sample lag there)
    bands = np.tanh(v[:, None] / (np.asarray(DEAD_BAND_WIDTHS) * np.std(v) + 1e-12))  # (N, B)

    def curve(lags: np.ndarray) -> np.ndarray:  # (at each lag, the best dead-band width; lags in threads)
        return np.array(list(ordered(
            lambda lag: _residual(i[k + 1], gram, cross, cols, shifted(v, lag)[k], shifted(bands, lag)[k]), lags)))

    floor = RESOLUTION * float(np.std(i))
    lags, res = _search(curve, top, floor)
    samples, sharp = _pick(lags, res)
    nominal, bias = False, 0.0
    if not sharp and armature is not None:
        tau = armature[0] / log.dt
        for leads in (SPEED_LEADS, ()):  # (the speed as logged where its free lead leaves the lag open)
            lags, res = _search(_nominal_curve(log, tau, armature[1], k, leads), top, floor)
            held, sharp = _pick(lags, res)
            if sharp:
                break
        # a slower armature's lag is taken only as a delay candidate (a HELD_L_ERROR inductance error moves it by
        # bias): the caller claims it where it predicts held-out data better than a longer L/R (.diagnose._delay_wins)
        bias = HELD_L_ERROR * tau if tau > NOMINAL_TAU else 0.0
        sharp = sharp and (bias == 0.0 or held > max_logging_skew + SKEW_FRACTION)
        samples, nominal = (held if sharp else 0.0), sharp
        rule += ("; the free search was flat (a smooth command: a delay looks like a longer armature lag), so the lag "
                 "was measured with the armature's time constant held at its nominal L/R" if sharp else "")
        if sharp and bias:
            rule += (f" ({tau:.3g} samples: a {100 * HELD_L_ERROR:.0f} % inductance error would move it by "
                     f"{bias:.2g}: a delay only where it predicts the held-out data better than that longer L/R)")
    if not sharp:
        rule += "; here the lag is not identifiable (flat residual), none is assumed"
    plot = (tuple(float(x) for x in lags), tuple(float(x / (np.std(i) or 1.0)) for x in res))
    return Alignment(float(samples), float(samples * log.dt), bool(samples > max_logging_skew + SKEW_FRACTION), rule,
                     plot, sharp, nominal, bias if nominal else 0.0)


def _search(curve: Callable[[np.ndarray], np.ndarray], top: int, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """``curve`` (residual per lag) over whole samples 0..``top``, then every 1/8 sample within 1.5 samples of
    the best: the lags (K,) increasing and their residuals (K,), none below ``floor`` (:data:`RESOLUTION`)."""
    coarse = np.arange(0.0, top + 1e-9, 1.0)
    res = curve(coarse)
    best = float(coarse[int(np.argmin(res))])
    fine = np.setdiff1d(np.arange(max(best - 1.5, 0.0), min(best + 1.5, top) + 1e-9, LAG_STEP), coarse)
    order = np.argsort(np.concatenate([coarse, fine]))
    return np.concatenate([coarse, fine])[order], np.maximum(np.concatenate([res, curve(fine)])[order], floor)


def _nominal_curve(log: Log, tau: float, k_e: float, k: np.ndarray,
                   leads: tuple[int, ...]) -> Callable[[np.ndarray], np.ndarray]:
    """The output-error residual per lag (module doc): the logged current on rows ``k`` (M,) fitted by the
    back-EMF-corrected command ``V[n - lag] - k_e w[n]`` [V], the speed's lead ``w[n + d] - w[n]`` for each ``d`` in
    ``leads`` [samples] (:data:`SPEED_LEADS`, or none) [rad/s], its dead-band term, the current's sign (a brush drop)
    and a constant, each passed through the armature's first-order lag ``i[n+1] = p i[n] + (1 - p) x[n]``, ``p =
    exp(-1/tau)``, ``tau`` [samples] the nominal ``L/R``, exact under a zero-order hold (eq. dc_electrical). ``tau`` is
    held, not fitted: with it free, lag and ``tau`` trade along a valley, and a longer ``tau`` wins by smoothing the
    speed's noise (a lag biased short by most of ``L/R``). The leads are free: a filtered tachometer or a differenced
    encoder logs the speed rows late, and with the back-EMF held to the logged speed the command was moved to match it
    (the blind rig's 476, a 2.9-row tachometer filter beside a 2-sample skew: a 4.6-sample delay; 663, a differenced
    encoder beside a 2-sample skew: 3.6 samples; ``tests/identify/test_alignment_nominal_armature.py``). Where they
    leave the lag open, the caller searches again without them (:func:`estimate`): read ahead, 607's lag, 2.7 samples
    for a drawn 2, went to none."""
    v, i, w = log.voltage, log.current, log.omega
    band, sign = _soft_sign(v), _soft_sign(i)
    rows = k[k >= min(k[-1], k[0] + int(10 * tau) + 1)]  # (the filters' start-up transient left out)
    lead = [shifted(w, -d) - w for d in leads]  # (N,) each [rad/s]: read d samples ahead, the last held

    def one(lag: float) -> float:
        x = np.column_stack([shifted(v, lag) - k_e * w, *lead, shifted(band, lag), sign, np.ones(v.size)])
        a = _through_armature(x, tau)[rows]
        coef = np.linalg.lstsq(a, i[rows], rcond=None)[0]
        return float(np.sqrt(np.mean((i[rows] - a @ coef) ** 2)))

    return lambda lags: np.array(list(ordered(one, [float(lag) for lag in lags])))


def _soft_sign(y: np.ndarray) -> np.ndarray:
    """``tanh(y / (5 % of y's spread))`` (N,): the sign of a command (a dead band's term) or of a current (a brush
    drop's), smooth across zero."""
    return np.tanh(y / (0.05 * np.std(y) + 1e-12))


def _through_armature(x: np.ndarray, tau: float) -> np.ndarray:
    """Each column of ``x`` (N, C) through the armature's first-order lag ``y[n+1] = p y[n] + (1 - p) x[n]``,
    ``p = exp(-1/tau)``, ``tau`` [samples] its ``L/R``, from rest: exact under a zero-order hold (eq.
    dc_electrical)."""
    p = math.exp(-1.0 / max(tau, 1e-3))
    return np.ascontiguousarray(iir([0.0, 1.0 - p], [1.0, -p], x))


def armature_error(log: Log, lag: float, tau: float, train: np.ndarray, test: np.ndarray) -> float:
    """Held-out output error [A] of the armature (eq. dc_electrical) with the command ``lag`` samples late: the
    current simulated from the logged command and speed through a first-order lag ``i[n+1] = p i[n] + (1 - p) x[n]``
    (exact under a zero-order hold), its gains (command, back-EMF, dead band, brush drop, offset) and its ``L/R``
    fitted on the ``train`` rows (N,) (the ``L/R`` within :data:`ARMATURE_TAUS` times the nominal ``tau`` [samples]:
    that grid's best, refined between its neighbours), and its RMS on the ``test`` rows (N,); NaN for a log too short
    for it. Only the logged speed and command enter, so a wrong inertia or a missing load effect, which swamp a free
    run of the whole plant, bias it little, and a lag and a longer ``L/R`` each get their best fit: a delay wins over
    the conventions' lag only where dead time, not a slower rise, is what the current shows
    (:func:`.diagnose._delay_wins`). (A free ``L/R`` also smooths the noise of the speed it is driven by, and a longer
    one more: :func:`_nominal_curve`'s reason to hold it. Here that favours the shorter lag, against a delay.)"""
    v, i, w = log.voltage, log.current, log.omega
    x = np.column_stack([shifted(v, lag), w, shifted(_soft_sign(v), lag), _soft_sign(i), np.ones(v.size)])
    settled = np.arange(v.size) >= min(10.0 * ARMATURE_TAUS[-1] * tau, v.size / 2)  # (start-up transients left out)
    tr, te = train & settled, test & settled
    if tr.sum() < 10 * x.shape[1] or te.sum() < 10:
        return math.nan

    def fit(log_f: float) -> tuple[float, float]:  # (training mean square, held-out RMS) at L/R = e^log_f tau
        a = _through_armature(x, math.exp(log_f) * tau)
        coef = np.linalg.lstsq(a[tr], i[tr], rcond=None)[0]
        return float(np.mean((i[tr] - a[tr] @ coef) ** 2)), float(np.sqrt(np.mean((i[te] - a[te] @ coef) ** 2)))

    grid = np.log(ARMATURE_TAUS)
    k = int(np.argmin([f[0] for f in ordered(fit, [float(g) for g in grid])]))
    best = optimize.minimize_scalar(lambda g: fit(g)[0], bounds=(grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]),
                                    method="bounded", options={"xatol": 1e-3})
    return fit(float(best.x))[1]


def _pick(lags: np.ndarray, res: np.ndarray) -> tuple[float, bool]:
    """The lag [samples] of the smallest residual on the increasing grid ``lags`` (K,), refined by a parabola
    through its neighbours, and whether it is identified: a sharp minimum (the residual rises by >= 1 % one
    sample either side), or a plateau within 1 % bounded inside the grid and at most :data:`PLATEAU` samples wide
    (then its midpoint); 0 when neither."""
    j = int(np.argmin(res))
    lag = float(lags[j])
    if 0 < j < lags.size - 1:  # the vertex of the parabola through the neighbours
        x0, x1, x2 = lags[j - 1:j + 2] - lag
        y0, y1, y2 = res[j - 1:j + 2]
        den = x0 * (y1 - y2) + x1 * (y2 - y0) + x2 * (y0 - y1)
        if den != 0:
            shift = 0.5 * (x0**2 * (y1 - y2) + x1**2 * (y2 - y0) + x2**2 * (y0 - y1)) / den
            lag += float(np.clip(shift, x0, x2))
    side = [float(np.interp(lags[j] + d, lags, res)) for d in (-1.0, 1.0) if lags[0] <= lags[j] + d <= lags[-1]]
    if side and min(side) >= 1.01 * res[j]:
        return max(lag, 0.0), True
    # a flat minimum: the lags within 1 % of the smallest residual. Bounded on both sides inside the search and at
    # most PLATEAU samples wide (rare level changes, e.g. a slow PRBS, pin the lag to within a sample or two), its
    # midpoint; wider or reaching an end of the search (slow, smooth excitation), the lag is not identifiable: 0
    flat = lags[res <= 1.01 * res[j]]
    if flat[0] > lags[0] and flat[-1] < lags[-1] and flat[-1] - flat[0] <= PLATEAU:
        return float(0.5 * (flat[0] + flat[-1])), True
    return 0.0, False


def spread(align: Alignment) -> float:
    """How far [samples] the command timing may be off after ``align``: half the width of the lags whose search
    residual is within the 1 % :func:`_pick` uses of the residual at the lag taken (a PRBS whose rare level changes
    leave a plateau: half its width), at least :data:`LAG_STEP` (the grid); ``inf`` where the timing was not
    measured (no search, flat residual) or some lag of the search fits beyond that 1 % better than the one taken
    (the lag was held to the logging conventions by :func:`within`, not found there)."""
    lags, res = (np.asarray(x, float) for x in align.curve)
    if not align.identified or lags.size < 2:
        return math.inf
    j = int(np.clip(np.searchsorted(lags, align.samples), 1, lags.size - 1))
    j = j - 1 if res[j - 1] <= res[j] else j  # the better grid point bracketing the lag taken
    r0 = float(res[j])
    if res.min() * 1.01 < r0:
        return math.inf
    near = np.flatnonzero(res <= 1.01 * r0)
    runs = np.split(near, np.flatnonzero(np.diff(near) > 1) + 1)
    run = min(runs, key=lambda r: float(np.min(np.abs(r - j)))) if near.size else np.array([j])
    return max(LAG_STEP, 0.5 * float(lags[run[-1]] - lags[run[0]]))


def _conventional(lags: np.ndarray, max_logging_skew: float) -> np.ndarray:
    """Which of the search's ``lags`` (K,) [samples] logging conventions explain (the rule, module doc)."""
    return lags <= max_logging_skew + SKEW_FRACTION + 1e-9


def gain(align: Alignment, max_logging_skew: float) -> float:
    """How many times lower the search residual is at the lag taken than at the best lag within the conventions
    (lags up to ``max_logging_skew + SKEW_FRACTION``): the one-step armature equation with free coefficients, so a
    wrong nominal constant or a missing load effect biases it little, where a free run under nominal constants is
    dominated by them (a 34 % ``J`` error, a dead band). 1 where the lag is not a minimum bracketed inside the
    search (the residual still falls at its end: a smooth command traded against the armature's lag, not a
    measured delay), not identified, or found with a slow armature held (:attr:`Alignment.bias`: a held curve
    falls as deep for an inductance error as for a delay)."""
    lags, res = (np.asarray(x, float) for x in align.curve)
    keep = _conventional(lags, max_logging_skew)
    if not align.identified or align.bias or not keep.any() or keep.all() or align.samples >= lags[-1] - 0.5:
        return 1.0
    return float(res[keep].min() / max(float(np.interp(align.samples, lags, res)), 1e-300))


def within(align: Alignment, max_logging_skew: float, dt: float) -> Alignment:
    """``align`` restricted to what logging conventions explain (lags up to ``max_logging_skew`` + 0.75
    samples): the best lag of its search curve there, never a delay (a longer lag was not confirmed); none (not
    identified) for a curve held at a slow armature (:attr:`Alignment.bias`), whose lags there are its ``L``'s."""
    lags, res = (np.asarray(x, float) for x in align.curve)
    keep = _conventional(lags, max_logging_skew)
    if not keep.any() or align.bias:  # (a slow held armature's lag within the conventions: not claimed)
        return Alignment(0.0, 0.0, False, align.rule + (
            f"; the {align.samples:.2f}-sample lag did not predict the held-out data better than the conventions' "
            "lags or a longer L/R, and no lag within them is claimed from a slow armature held" if align.bias else ""),
            align.curve, False)
    samples, known = _pick(lags[keep], res[keep])
    return Alignment(samples, samples * dt, False, align.rule + f"; the {align.samples:.2f}-sample lag of the "
                     "search did not predict the held-out data better than one within the conventions, so the "
                     "best lag within them is used and no input_delay is called", align.curve, known,
                     align.nominal and known)


def voltage_spread(v: np.ndarray) -> float:
    """The spread of a command's magnitudes ``v`` (N,) [V]: the 10th over the 90th percentile of ``|v|`` over the rows
    above 1 % of its peak; :data:`ONE_MAGNITUDE` or more is one magnitude (a two-level command, +-V0 or 0 and V0)."""
    a = np.abs(v)
    on = a[a > 0.01 * float(np.max(a))] if a.size else a
    return float(np.percentile(on, 10) / max(float(np.percentile(on, 90)), 1e-300)) if on.size else 1.0


def sample_rate(log: Log) -> float:
    return 1.0 / log.dt if log.kind is LogKind.TIME_SERIES else math.nan
