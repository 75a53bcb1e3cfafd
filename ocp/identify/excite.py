"""Candidate excitations for a discriminating experiment, as missions the optimiser runs within the limits.

Every candidate is a desired *speed* profile ``w_d(t)`` over the same duration ``D`` (so candidates are
compared on equal time), starting and ending at rest, turned into the desired thrust ``F = c_f w|w|``
(eq. thrust_model) and sampled into a :class:`ocp.mission.Mission` ``profile``. Families (``W`` a fraction
of the fastest speed held within the limits, ``tau`` the mechanical time constant):

* ``slow-reversals`` -- ``W sin(2 pi t / P)``, three periods: time at every speed, six slow zero crossings;
* ``triangle`` -- speed ramps linearly between ``+-W``: equal time at every speed, the most time near zero
  (Coulomb vs Stribeck, dead band, brush drop);
* ``dwell-steps`` -- holds at ``+-W/3, +-2W/3, +-W`` alternating in sign, each settling for several ``tau``:
  steady points at several speeds in both directions (viscous ``B`` vs quadratic drag vs a constant torque);
* ``chirp`` -- ``W sin(2 pi phi(t))`` with the frequency rising linearly to about ``0.3 / tau``: the
  dynamics (``J``, lags) and crossings at several rates.

Arrays are (N,) in SI (s, rad/s, N).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ocp.optimize.mission import MAX_INTERVALS, OUTPUT_RATE

#: at most this many profile samples per candidate (the service bounds missions' samples)
PROFILE_SAMPLES = 2000
#: collocation intervals per phase (a phase lies between two reversals), and at most in total
INTERVALS_PER_PHASE = 40
MAX_TOTAL_INTERVALS = 800
FAMILIES = ("slow-reversals", "triangle", "dwell-steps", "chirp")
LEVELS = (0.5, 0.85)


@dataclass(frozen=True)
class Excitation:
    """One candidate: name, what it does (words), desired speed ``omega`` [rad/s] on ``t`` [s], (N,)."""

    name: str
    description: str
    t: np.ndarray
    omega: np.ndarray

    def crossings(self) -> int:
        s = np.sign(self.omega[np.abs(self.omega) > 1e-9 * max(float(np.max(np.abs(self.omega))), 1e-300)])
        return int(np.count_nonzero(np.diff(s)))


def _envelope(t: np.ndarray, duration: float, ramp: float) -> np.ndarray:
    """Smooth start and stop (raised-cosine ramps of ``ramp`` seconds): the run begins and ends at rest."""
    up = np.clip(t / ramp, 0.0, 1.0)
    down = np.clip((duration - t) / ramp, 0.0, 1.0)
    return (0.5 - 0.5 * np.cos(math.pi * up)) * (0.5 - 0.5 * np.cos(math.pi * down))


def _steps(t: np.ndarray, top: float, duration: float, tau: float) -> np.ndarray:
    levels = top * np.array([1 / 3, -1 / 3, 2 / 3, -2 / 3, 1.0, -1.0])
    hold = duration / levels.size
    k = np.minimum((t / hold).astype(int), levels.size - 1)
    w = levels[k]
    # cosine transitions of 1.5 tau between levels (a step would only ask the optimiser for a reshaping)
    edge = min(1.5 * tau, 0.3 * hold)
    prev = np.where(k > 0, levels[np.maximum(k - 1, 0)], 0.0)
    frac = np.clip((t - k * hold) / edge, 0.0, 1.0)
    return prev + (w - prev) * (0.5 - 0.5 * np.cos(math.pi * frac))


def excitation(family: str, level: float, top: float, duration: float, tau: float) -> Excitation:
    """Candidate ``family`` at speed amplitude ``level * top`` [rad/s] over ``duration`` [s] (module doc)."""
    n = min(PROFILE_SAMPLES, max(200, int(duration * OUTPUT_RATE / 5)))
    t = np.linspace(0.0, duration, n)
    w_top = level * top
    ramp = min(max(2.0 * tau, 0.02 * duration), 0.1 * duration)
    if family == "slow-reversals":
        w = w_top * np.sin(2 * math.pi * 3 * t / duration)
        text = f"three slow sine periods of the speed, +-{w_top:.4g} rad/s, {duration / 3:.3g} s each"
    elif family == "triangle":
        phase = (t / (duration / 2) + 0.25) % 1.0
        w = w_top * (1.0 - 4.0 * np.abs(phase - 0.5))
        text = f"speed ramped linearly between +-{w_top:.4g} rad/s, two periods of {duration / 2:.3g} s"
    elif family == "dwell-steps":
        w = _steps(t, w_top, duration, tau)
        text = f"holds at +-1/3, +-2/3 and +-1 of {w_top:.4g} rad/s, {duration / 6:.3g} s each, alternating sign"
    elif family == "chirp":
        f1 = min(0.3 / tau, 6.0 / duration)  # at most ~6 periods (12 reversals): a tractable program
        f0 = min(0.5 / duration, f1)
        w = w_top * np.sin(2 * math.pi * (f0 * t + 0.5 * (f1 - f0) * t * t / duration))
        text = f"speed chirp +-{w_top:.4g} rad/s, {f0:.3g} to {f1:.3g} Hz"
    else:
        raise ValueError(family)
    return Excitation(f"{family}@{level:g}", text, t, w * _envelope(t, duration, ramp))


def candidates(top: float, duration: float, tau: float) -> list[Excitation]:
    """Every family at every level of :data:`LEVELS` (chirp at the higher one only)."""
    return [excitation(f, lv, top, duration, tau) for f in FAMILIES for lv in LEVELS
            if not (f == "chirp" and lv != LEVELS[-1])]


def mission_for(exc: Excitation, params: dict[str, Any], c_f: float, voltage: float, current: float,
                time_limit_s: float = 10.0) -> dict[str, Any]:
    """The mission (JSON mapping for :class:`ocp.mission.Mission`) asking for ``exc``'s thrust within the
    limits, with the plant ``params`` (a parameter mapping, effects included)."""
    # eq:thrust_model  F = c_f w |w|
    thrust = c_f * exc.omega * np.abs(exc.omega)
    phases = exc.crossings() + 1
    intervals = int(min(MAX_TOTAL_INTERVALS, MAX_INTERVALS, max(120, INTERVALS_PER_PHASE * phases)))
    return {"name": f"design-experiment {exc.name}", "params": params,
            "limits": {"voltage": float(voltage), "current": float(current)}, "regularity": "bounded",
            "objective": "track", "retiming": {"min_stretch": 1.0, "max_stretch": 1.2},
            "collocation": {"intervals": intervals}, "time_limit_s": float(time_limit_s),
            "profile": {"t": [float(x) for x in exc.t], "thrust": [float(x) for x in thrust]}}
