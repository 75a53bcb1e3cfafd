"""Analytic fallbacks: ``A sin^(2q+1)`` or local polynomial reversals within current/voltage limits.

For a requested regularity the smallest admissible ``q`` comes from the theory
(:func:`ocp.theory.reversal.min_sin_q`); then, with the amplitude fixed, the shortest period -- or, with the
period fixed, the largest amplitude -- whose closed-form peak current and voltage stay within the
limits is found by bisection (peaks fall monotonically with the period and rise with the amplitude).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from ocp.errors import InfeasibleError, MissionError
from ocp.model.params import MotorParams
from ocp.reference.analytic import LocalReversal, PiecewiseProfile, SinProfile, reference
from ocp.reference.trajectory import Reference
from ocp.theory.crossings import sign_change_times
from ocp.theory.reversal import ReversalRegularity, min_sin_q

_GRID = 4001


@dataclass(frozen=True)
class SinDesign:
    """Result of :func:`design_sin`: the profile and its peaks |i| [A], |V| [V] over one period."""

    profile: SinProfile
    peak_current: float
    peak_voltage: float


def sin_peaks(params: MotorParams, profile: SinProfile) -> tuple[float, float]:
    """Peak |current| [A] and |voltage| [V] of the exact feedforward over one period (inf if unbounded)."""
    t = np.linspace(0.0, profile.period, _GRID)
    ref = reference(profile, params, t)
    return ref.peak("current"), ref.peak("voltage")


def channel_torque(params: MotorParams, ref: Reference) -> np.ndarray:
    """Torque [N m] the torque channel needs for a reference, shape of ``ref.t``."""
    # eq:omega_dyn  J w' = tau - c_tau w|w|  (u = tau / J)
    return params.J * ref.omega_dot + params.c_tau * ref.omega * np.abs(ref.omega)


@dataclass(frozen=True)
class DriveLimits:
    """What an analytic reference must respect: the DC motor's current [A] and voltage [V], or, when
    ``torque`` [N m] is set, the torque channel's torque (its drive controls torque; i and V are its own)."""

    current: float
    voltage: float
    torque: float | None = None

    def peaks(self, params: MotorParams, ref: Reference) -> str:
        if self.torque is not None:
            return f"{float(np.max(np.abs(channel_torque(params, ref)))):.3g} N m"
        return f"{ref.peak('current'):.3g} A, {ref.peak('voltage'):.3g} V"

    def admits(self, params: MotorParams, ref: Reference) -> bool:
        if self.torque is not None:
            return bool(np.max(np.abs(channel_torque(params, ref))) <= self.torque)
        return ref.peak("current") <= self.current and ref.peak("voltage") <= self.voltage

    def binding(self, params: MotorParams, profile: Any) -> str:
        """The limit field a profile exceeds most (``limits.current`` / ``.voltage`` / ``.torque``)."""
        t0, t1 = _span(profile)
        ref = reference(profile, params, np.linspace(t0, t1, 801))
        if self.torque is not None:
            return "limits.torque"
        return "limits.current" if ref.peak("current") / self.current >= ref.peak("voltage") / self.voltage \
            else "limits.voltage"

    def max_amplitude(self, params: MotorParams) -> float:
        """Largest thrust [N] held in steady state within the limits (upper end of a bisection)."""
        if self.torque is not None:
            return params.c_f * self.torque / params.c_tau
        return params.c_f * params.max_steady_speed(self.voltage) ** 2


def _span(profile: Any) -> tuple[float, float]:
    if isinstance(profile, LocalReversal):
        half = profile.flat + profile.blend
        return profile.t_s - half, profile.t_s + half
    return 0.0, float(getattr(profile, "period", 1.0))


def _fits(params: MotorParams, profile: SinProfile, limits: DriveLimits) -> tuple[bool, Reference]:
    ref = reference(profile, params, np.linspace(0.0, profile.period, _GRID))
    return limits.admits(params, ref), ref


@lru_cache(maxsize=256)
def design_sin(
    params: MotorParams,
    current_limit: float,
    voltage_limit: float,
    regularity: ReversalRegularity = ReversalRegularity.CONTINUOUS_VOLTAGE,
    amplitude: float | None = None,
    period: float | None = None,
    voltage_driven: bool = True,
    torque_limit: float | None = None,
) -> SinDesign:
    """Smallest-q sine-power reference within the limits; give ``amplitude`` [N] or ``period`` [s].

    With ``torque_limit`` [N m] the reference is for the torque channel: ``q`` is the torque-driven one
    and the torque is checked instead of the current and voltage.

    Pure in its arguments and cached (the bisection costs tens of milliseconds).

    Raises :class:`MissionError` naming ``amplitude``/``limits`` when no period can meet the limits
    (the steady-state current or voltage at the amplitude already exceeds them).
    """
    if not (current_limit > 0 and voltage_limit > 0) or (torque_limit is not None and not torque_limit > 0):
        raise MissionError("limits", "current, voltage and torque limits must be positive")
    limits = DriveLimits(current_limit, voltage_limit, torque_limit)
    q = min_sin_q(regularity, voltage_driven and torque_limit is None)
    if amplitude is not None and period is None:
        return _shortest_period(params, limits, q, amplitude)
    if period is not None and amplitude is None:
        return _largest_amplitude(params, limits, q, period)
    raise MissionError("amplitude", "give exactly one of amplitude and period")


def _design(params: MotorParams, prof: SinProfile) -> SinDesign:
    i, v = sin_peaks(params, prof)
    return SinDesign(prof, i, v)


def _shortest_period(params: MotorParams, limits: DriveLimits, q: int, amplitude: float) -> SinDesign:
    hi = 0.01
    while True:
        ok, ref = _fits(params, SinProfile(amplitude, hi, q), limits)
        if ok:
            break
        if hi > 1e4:
            raise MissionError("amplitude", f"{amplitude} N cannot be held within the limits at any period "
                                            f"(peaks {limits.peaks(params, ref)} at T = 1e4 s)")
        hi *= 2.0
    lo = hi / 2.0 if hi > 0.01 else 1e-4
    while hi / lo > 1.0 + 1e-4:
        mid = math.sqrt(lo * hi)
        if _fits(params, SinProfile(amplitude, mid, q), limits)[0]:
            hi = mid
        else:
            lo = mid
    return _design(params, SinProfile(amplitude, hi, q))


def _largest_amplitude(params: MotorParams, limits: DriveLimits, q: int, period: float) -> SinDesign:
    hi = limits.max_amplitude(params)
    lo = 0.0
    while hi - lo > 1e-6 * hi:
        mid = 0.5 * (lo + hi)
        if _fits(params, SinProfile(mid, period, q), limits)[0]:
            lo = mid
        else:
            hi = mid
    if lo <= 0.0:
        raise MissionError("period", f"no positive amplitude fits the limits at period {period} s")
    return _design(params, SinProfile(lo, period, q))


#: The output and integration grids see peaks the design grid misses, and effects the closed forms leave
#: out add a little: when the simulated fallback exceeds a limit the design is redone with less room.
#: (share of each limit, share of the hold limit) tried in turn until the simulated fallback is within the
#: limits: the first is tight (the design meets the limits exactly on its own grid)
DESIGN_STEPS = ((1.0, 1.0), (0.97, 1.0), (0.9, 0.9), (0.8, 0.75), (0.65, 0.5), (0.5, 0.3))
_REVERSAL_GRID = 401
_MIN_LEVEL_SCALE = 1e-3  # a reversal that needs its levels lowered further is infeasible


def hold_limit(params: MotorParams, limits: DriveLimits, speed: float | None = None) -> float:
    """Largest thrust [N] the motor holds in steady state within the limits (and ``speed`` [rad/s])."""
    if limits.torque is not None:
        w = math.sqrt(limits.torque / params.c_tau)  # eq:omega_dyn at rest: c_tau w^2 = tau
    else:
        # eq:dc_mechanical at rest: k_t i = B w + c_tau w^2 with i at its limit
        b, c = params.B, params.c_tau
        w_i = (-b + math.sqrt(b * b + 4.0 * c * params.k_t * limits.current)) / (2.0 * c)
        w = min(w_i, params.max_steady_speed(limits.voltage))
    if speed is not None:
        w = min(w, speed)
    return params.c_f * w * w


def _reversal_fits(params: MotorParams, limits: DriveLimits, a: float, b: float, tk: float, p: int,
                   d: float) -> bool:
    """Whether the reversal from ``a`` to ``b`` [N] lasting ``d`` [s] stays within the limits (its peaks do
    not depend on when it happens: evaluated at t_s = 0, cached -- a periodic profile repeats it)."""
    return _fits_at_zero(params, limits, a, b, p, d)


@lru_cache(maxsize=4096)
def _fits_at_zero(params: MotorParams, limits: DriveLimits, a: float, b: float, p: int, d: float) -> bool:
    rev = LocalReversal.between(a, b, 0.0, p, d)
    return limits.admits(params, reference(rev, params, np.linspace(-d / 2, d / 2, _REVERSAL_GRID)))


def _level_scale(params: MotorParams, limits: DriveLimits, a: float, b: float, tk: float, p: int,
                 room: float) -> float:
    """Largest factor c <= 1 (bisection, 2 % resolution) for which the reversal between ``c a`` and ``c b``
    fits in ``room`` [s]; 0 when not even ``_MIN_LEVEL_SCALE`` does."""
    if _reversal_fits(params, limits, a, b, tk, p, room):
        return 1.0
    lo, hi = _MIN_LEVEL_SCALE, 1.0
    if not _reversal_fits(params, limits, lo * a, lo * b, tk, p, room):
        return 0.0
    while hi / lo > 1.02:
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if _reversal_fits(params, limits, mid * a, mid * b, tk, p, room) else (lo, mid)
    return lo


def _shortest(params: MotorParams, limits: DriveLimits, a: float, b: float, tk: float, p: int,
              room: float) -> float | None:
    """Shortest reversal duration [s] within ``room`` (bisection, 0.1 %), None when ``room`` is too short."""
    if not _reversal_fits(params, limits, a, b, tk, p, room):
        return None
    lo, hi = 1e-4 * room, room
    while hi / lo > 1.0 + 1e-3:
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if _reversal_fits(params, limits, a, b, tk, p, mid) else (mid, hi)
    return hi


@dataclass(frozen=True)
class ReversalDesign:
    """Result of :func:`design_reversals`: the profile and its hold levels [N] beside the desired ones."""

    profile: PiecewiseProfile
    levels: tuple[float, ...]
    desired_levels: tuple[float, ...]

    @property
    def lowered(self) -> float:
        """Smallest level / desired level (1.0 when no level was lowered)."""
        return min((lv / d for lv, d in zip(self.levels, self.desired_levels, strict=True) if d != 0), default=1.0)


def design_reversals(params: MotorParams, t: np.ndarray, f: np.ndarray, current_limit: float,
                     voltage_limit: float, regularity: ReversalRegularity, voltage_driven: bool = True,
                     torque_limit: float | None = None) -> PiecewiseProfile | None:
    """The profile of :func:`plan_reversals` (hold levels uncapped)."""
    plan = plan_reversals(params, t, f, current_limit, voltage_limit, regularity, voltage_driven, torque_limit)
    return None if plan is None else plan.profile


def plan_reversals(params: MotorParams, t: np.ndarray, f: np.ndarray, current_limit: float,
                   voltage_limit: float, regularity: ReversalRegularity, voltage_driven: bool = True,
                   torque_limit: float | None = None, level_cap: float = math.inf) -> ReversalDesign | None:
    """Local-polynomial fallback for a sampled desired thrust ``f`` (N,) on ``t`` (N,) [s, N].

    Each phase between sign changes becomes a hold at its peak thrust, capped at ``level_cap`` [N];
    each reversal the local reversal of the smallest order ``p = 2q+1`` meeting ``regularity``, lasting
    the shortest time (bisection, at most the room between neighbouring reversals) whose exact current
    and voltage (with ``torque_limit`` [N m]: the torque channel's torque) stay within the limits. When
    the room is too short at the desired levels, both levels of that reversal are lowered until it fits.
    ``None`` when ``f`` never changes sign.

    Raises :class:`~ocp.errors.InfeasibleError` naming the binding limit when a reversal does not fit even
    with its levels lowered a thousandfold.
    """
    ts = [x for x in sign_change_times(t, f) if t[0] < x < t[-1]]  # a zero at an end is no reversal
    if not ts:
        return None
    limits = DriveLimits(current_limit, voltage_limit, torque_limit)
    p = 2 * min_sin_q(regularity, voltage_driven and torque_limit is None) + 1
    bounds = [float(t[0]), *ts, float(t[-1])]
    desired = []
    for a, b in itertools.pairwise(bounds):
        seg = f[(t >= a) & (t <= b)]
        desired.append(float(seg[np.argmax(np.abs(seg))]) if seg.size else 0.0)
    levels = [math.copysign(min(abs(x), level_cap), x) for x in desired]
    edges = [float(t[0])] + [0.5 * (x + y) for x, y in itertools.pairwise(ts)] + [float(t[-1])]
    rooms = [2.0 * min(tk - edges[k], edges[k + 1] - tk) for k, tk in enumerate(ts)]
    for _ in range(4):  # lower levels until every reversal fits; a shared level takes the smaller factor
        scale = [_level_scale(params, limits, levels[k], levels[k + 1], tk, p, rooms[k]) for k, tk in enumerate(ts)]
        if min(scale) <= 0.0:
            k = scale.index(0.0)
            raise InfeasibleError(limits.binding(params, LocalReversal.between(
                _MIN_LEVEL_SCALE * levels[k], _MIN_LEVEL_SCALE * levels[k + 1], ts[k], p, rooms[k])),
                f"the reversal at t = {ts[k]:.4g} s cannot stay within the limits in {rooms[k]:.3g} s, "
                f"even at {_MIN_LEVEL_SCALE:g} of its thrust levels")
        edge = [1.0, *scale, 1.0]
        levels = [lv * min(edge[j], edge[j + 1]) for j, lv in enumerate(levels)]
        durations = [_shortest(params, limits, levels[k], levels[k + 1], tk, p, rooms[k]) for k, tk in enumerate(ts)]
        if all(d is not None for d in durations):
            revs = tuple(LocalReversal.between(levels[k], levels[k + 1], tk, p, float(durations[k] or 0.0))
                         for k, tk in enumerate(ts))
            return ReversalDesign(PiecewiseProfile(pieces=revs, edges=tuple(edges)), tuple(levels), tuple(desired))
    raise InfeasibleError("limits", "the reversals could not be fitted within the limits")
