"""Mission -> problem: phases, plant, structure and scales, resolved once (no bounds, no solve).

A :class:`Problem` is what every later step reads: the desired profile split at its reversals
(:class:`Phases`), the mission's plant, the :class:`~ocp.optimize.collocation.Structure` of its program,
and the :class:`Scales` that make every decision variable O(1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp.errors import MissionError
from ocp.model.plant import DrivenPlant, Plant
from ocp.optimize import collocation as col
from ocp.optimize.mission import MAX_INTERVALS, Mission
from ocp.theory.crossings import sign_change_times
from ocp.theory.reversal import ReversalRegularity

MIN_INTERVALS_PER_PHASE = (8, 30)  # piecewise-constant input, input as a state


@dataclass(frozen=True)
class Phases:
    """Desired profile split at its reversals.

    Attributes:
        bounds: phase boundaries in desired time [s], shape (P+1,)
        signs: speed sign per phase (+1/-1), shape (P,)
    """

    bounds: np.ndarray
    signs: np.ndarray

    @property
    def durations(self) -> np.ndarray:
        """Desired phase durations [s], shape (P,)."""
        return np.diff(self.bounds)


def split_phases(t: np.ndarray, f: np.ndarray) -> Phases:
    """Phases between sign changes of the desired thrust ``f`` (N,) on ``t`` (N,) (strictly increasing): each
    phase's sign is the majority sign of its samples strictly inside it (the middle's when it has none)."""
    cuts = sign_change_times(t, f, 1e-12 * float(np.max(np.abs(f))))
    bounds = np.array([t[0], *cuts, t[-1]])
    # the samples strictly inside phase j are [first[j], last[j]); the sum of their signs from a running sum
    # (whole numbers: exact in any order)
    votes = np.concatenate([[0.0], np.cumsum(np.sign(f))])
    first, last = np.searchsorted(t, bounds[:-1], side="right"), np.searchsorted(t, bounds[1:], side="left")
    signs = []
    for a, b, lo, hi in zip(bounds[:-1], bounds[1:], first, last, strict=True):
        s = np.sign(votes[hi] - votes[lo]) if hi > lo else np.sign(np.interp(0.5 * (a + b), t, f))
        signs.append(1.0 if s >= 0 else -1.0)
    if np.any(np.diff(bounds) <= 0):
        raise MissionError("profile", "reversals are closer than the sampling allows")
    return Phases(bounds=bounds, signs=np.array(signs))


def chain_order(mission: Mission) -> int:
    """Input-chain length: 0 piecewise-constant command, 1 continuous, 2 C^1 (see ocp.optimize.collocation)."""
    base = {ReversalRegularity.BOUNDED: 0, ReversalRegularity.CONTINUOUS_CURRENT: 0,
            ReversalRegularity.CONTINUOUS_VOLTAGE: 1, ReversalRegularity.C1_VOLTAGE: 2}[mission.regularity]
    if mission.limits.voltage_rate is not None:
        base = max(base, 1)  # a slew limit makes the command a state
    return base


def crossing_order(mission: Mission) -> int:
    """Thrust exponent g imposed at reversals: the mission's, else 6 when the voltage must be continuous
    (current and voltage both vanish at the reversal, as for sin^5), else 2."""
    if mission.min_crossing_order is not None:
        return mission.min_crossing_order
    smooth_v = mission.regularity in (ReversalRegularity.CONTINUOUS_VOLTAGE, ReversalRegularity.C1_VOLTAGE)
    return mission.drive_plant().smooth_reversal_order if smooth_v else 2


@dataclass(frozen=True)
class Problem:
    """Everything one solve needs, derived from a mission (arrays documented in ocp.optimize.collocation).

    Attributes:
        t_desired, f_desired: the desired thrust samples [s], [N], shape (M,)
    """

    mission: Mission
    plant: DrivenPlant
    structure: col.Structure
    t_desired: np.ndarray
    f_desired: np.ndarray
    phases: Phases


def _plant_key(plant: Plant) -> str:
    return repr(plant)  # frozen dataclasses: constants and effects with their values


def problem_for(mission: Mission) -> Problem:
    """Phases, plant and structure of a mission (no solve)."""
    t, f = mission.desired()
    phases = split_phases(t, f)
    n_phases = phases.signs.size
    total = mission.collocation.intervals
    chain = chain_order(mission)
    # a flat reversal (chain >= 1, omega ~ s^3) needs room on both sides of each boundary
    per_phase = max(MIN_INTERVALS_PER_PHASE[min(chain, 1)], total // n_phases)
    if per_phase * n_phases > 2 * MAX_INTERVALS:
        raise MissionError("collocation.intervals", f"{n_phases} phases need more than {2 * MAX_INTERVALS} intervals")
    plant = mission.drive_plant()
    st = col.Structure(plant_key=_plant_key(plant), n_phases=n_phases, intervals=per_phase, chain=chain)
    return Problem(mission=mission, plant=plant, structure=st, t_desired=t, f_desired=f, phases=phases)


@dataclass(frozen=True)
class Scales:
    """Per-call scaling: every decision variable is ``value / scale`` (O(1)); SI scales.

    Attributes:
        x: per state (nx,): speed [rad/s], current [A], effect states, input chain [V, V/s, ...]
        u: control scale (input, its slew or its second derivative)
        u_lim: input limit [V] (or normalised torque [rad/s^2])
        f: thrust [N]
    """

    x: np.ndarray
    u: float
    u_lim: float
    f: float


def scales(problem: Problem, x_full_speed: np.ndarray) -> Scales:
    """Scales of ``problem``; ``x_full_speed`` (n_plant_states,): the plant's equilibrium at the peak desired
    speed (sizes the effect states). Raises :class:`MissionError` (``limits.speed``) when the speed limit
    cannot produce the peak desired thrust."""
    m, plant, st = problem.mission, problem.plant, problem.structure
    params, lim, dur = m.motor(), m.limits, problem.phases.durations
    f_scale = max(float(np.max(np.abs(problem.f_desired))), 1e-6)
    w_scale = math.sqrt(f_scale / params.c_f)
    if lim.speed is not None and lim.speed < w_scale * math.sqrt(0.999):
        raise MissionError("limits.speed", f"{lim.speed} rad/s cannot produce the desired peak thrust "
                                           f"{f_scale:.4g} N (needs {w_scale:.4g} rad/s)")
    u_lim = plant.input_limit(m.bounds())
    t_int = float(np.sum(dur)) / (st.n_phases * st.intervals)
    rate = lim.voltage_rate if lim.voltage_rate is not None else u_lim / t_int
    # a bounded state: its limit; an effect state: its size at full speed; an angle grows with time, scaled by
    # the angle travelled
    angle = max(1.0, w_scale * float(np.sum(dur)))
    bounded = plant.state_limits(m.bounds())
    states = [bounded[k] if k in bounded else angle if name.endswith(".theta") else max(abs(float(z)), 1e-3)
              for k, (name, z) in enumerate(zip(plant.state_names, x_full_speed, strict=True)) if k > 0]
    x = np.array([w_scale, *states, *[u_lim, rate][: st.chain]])
    return Scales(x=x, u=[u_lim, rate, rate / t_int][st.chain], u_lim=u_lim, f=f_scale)
