"""Analytic fallbacks: ``A sin^(2q+1)`` or local polynomial reversals within current/voltage limits.

For a requested regularity the smallest admissible ``q`` comes from the theory
(:func:`ocp.theory.min_sin_q`); then, with the amplitude fixed, the shortest period -- or, with the
period fixed, the largest amplitude -- whose closed-form peak current and voltage stay within the
limits is found by bisection (peaks fall monotonically with the period and rise with the amplitude).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ocp.analytic import LocalReversal, PiecewiseProfile, SinProfile, reference
from ocp.crossings import sign_change_times
from ocp.errors import MissionError
from ocp.params import MotorParams
from ocp.reference import Reference
from ocp.theory import ReversalRegularity, min_sin_q

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

    def max_amplitude(self, params: MotorParams) -> float:
        """Largest thrust [N] held in steady state within the limits (upper end of a bisection)."""
        if self.torque is not None:
            return params.c_f * self.torque / params.c_tau
        return params.c_f * params.max_steady_speed(self.voltage) ** 2


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


def design_reversals(params: MotorParams, t: np.ndarray, f: np.ndarray, current_limit: float,
                     voltage_limit: float, regularity: ReversalRegularity, voltage_driven: bool = True,
                     torque_limit: float | None = None) -> PiecewiseProfile | None:
    """Local-polynomial fallback for a sampled desired thrust ``f`` (N,) on ``t`` (N,) [s, N].

    Each phase between sign changes becomes a hold at its peak thrust; each reversal the local
    reversal of the smallest order ``p = 2q+1`` meeting ``regularity``, lasting the shortest time
    (bisection, at most the room between neighbouring reversals) whose exact current and voltage (with
    ``torque_limit`` [N m]: the torque channel's torque) stay within the limits. ``None`` when ``f``
    never changes sign.
    """
    ts = sign_change_times(t, f)
    if not ts:
        return None
    limits = DriveLimits(current_limit, voltage_limit, torque_limit)
    p = 2 * min_sin_q(regularity, voltage_driven and torque_limit is None) + 1
    bounds = [float(t[0]), *ts, float(t[-1])]
    levels = []
    for a, b in itertools.pairwise(bounds):
        seg = f[(t >= a) & (t <= b)]
        levels.append(float(seg[np.argmax(np.abs(seg))]) if seg.size else 0.0)
    edges = [float(t[0])] + [0.5 * (x + y) for x, y in itertools.pairwise(ts)] + [float(t[-1])]
    revs = []
    for k, tk in enumerate(ts):
        room = 2.0 * min(tk - edges[k], edges[k + 1] - tk)

        def fits(d: float, k: int = k, tk: float = tk) -> bool:
            rev = LocalReversal.between(levels[k], levels[k + 1], tk, p, d)
            grid = np.linspace(tk - d / 2, tk + d / 2, 801)
            return limits.admits(params, reference(rev, params, grid))

        lo, hi = 1e-4 * room, room
        if fits(hi):
            while hi / lo > 1.0 + 1e-3:
                mid = math.sqrt(lo * hi)
                lo, hi = (lo, mid) if fits(mid) else (mid, hi)
        revs.append(LocalReversal.between(levels[k], levels[k + 1], tk, p, hi))
    return PiecewiseProfile(pieces=tuple(revs), edges=tuple(edges))
