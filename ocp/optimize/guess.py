"""Initial guesses of a problem's program: the static inverse of the desired thrust, and for a min-time
mission the fastest analytic reversal within the limits."""

from __future__ import annotations

import math

import numpy as np

from ocp.errors import MissionError
from ocp.model.plant import speed_from_thrust
from ocp.optimize import collocation as col
from ocp.optimize.mission import Mission
from ocp.optimize.problem import Problem, Scales
from ocp.reference.analytic import SinProfile, reference
from ocp.reference.fallback import design_sin


def fastest_analytic(mission: Mission) -> SinProfile | None:
    """The fastest ``A sin^(2q+1)`` within the mission's limits and regularity
    (:func:`ocp.reference.fallback.design_sin`) at the larger of the first and last thrust levels, phase 0; half
    its period is the analytic reversal time. None when no period meets the limits."""
    _, f = mission.desired()
    amp = max(abs(float(f[0])), abs(float(f[-1])))
    try:
        return design_sin(mission.motor(), mission.limits.current, mission.limits.voltage, mission.regularity,
                          amplitude=amp, torque_limit=mission.drive_plant().torque_limit(mission.bounds())).profile
    except MissionError:
        return None


def initial_guess(problem: Problem, lay: col.Layout, x0: np.ndarray, fd: np.ndarray, xscale: np.ndarray,
                   uscale: float, chain: int, lbx: np.ndarray, ubx: np.ndarray) -> np.ndarray:
    """Static inverse of the desired thrust at the collocation points (nominal steady current and
    input), effect states held at their initial values; clipped into the bounds."""
    params = problem.mission.motor()
    P, N = problem.structure.n_phases, problem.structure.intervals
    npx = len(problem.plant.state_names)
    guess = x0.copy()
    start = x0[lay.x0]
    for j in range(P):
        w = problem.phases.signs[j] * np.abs(speed_from_thrust(fd[j], params.c_f).reshape(N, col.DEGREE))
        nominal, u = problem.plant.static_inverse(w)  # speed (and current) of the nominal plant
        for k in range(len(nominal), npx):  # effect states
            guess[lay.xc[j, :, :, k]] = start[k]
        for k, value in enumerate(nominal):
            guess[lay.xc[j, :, :, k]] = value / xscale[k]
        if chain >= 1:
            guess[lay.xc[j, :, :, npx]] = u / xscale[npx]
        if chain == 0:
            guess[lay.u[j, :, 0]] = u[:, -1] / uscale
    return np.clip(guess, lbx, ubx)


def analytic_guess(problem: Problem, lay: col.Layout, guess: np.ndarray, sc: Scales, lbx: np.ndarray,
                    ubx: np.ndarray) -> np.ndarray:
    """Min-time initial guess from the analytic fallback: the fastest ``A sin^(2q+1)`` within the limits
    (:func:`fastest_analytic`), started at its peak of the first phase's sign, so phase j lasts a quarter
    period at either end and half a period in between; states and input are its exact feedforward
    (nominal plant) at the retimed collocation points. Unchanged when no sine meets the limits."""
    m, st = problem.mission, problem.structure
    fastest = fastest_analytic(m)
    if fastest is None:
        return guess
    P, N, chain = st.n_phases, st.intervals, st.chain
    npx = len(problem.plant.state_names)
    quarter = 0.25 * fastest.period
    h = np.full(P, 2.0 * quarter)
    h[0] = h[-1] = quarter
    edges = np.concatenate([[0.0], np.cumsum(h)])
    taus = ((np.arange(N)[:, None] + col.TAU[None, 1:]) / N).ravel()  # (N*DEGREE,)
    t = (edges[:-1, None] + taus[None, :] * h[:, None]).ravel()  # (P*N*DEGREE,) strictly increasing
    prof = SinProfile(fastest.amplitude, fastest.period, fastest.q, phase=0.5 * math.pi * problem.phases.signs[0])
    ref = reference(prof, m.motor(), t)
    nominal, chain_0 = problem.plant.feedforward(ref)  # speed (and current), input
    inputs = [chain_0]  # input, its slew, its second derivative at the points
    for _ in range(chain):
        inputs.append(np.gradient(inputs[-1], t))
    out = guess.copy()
    out[lay.stretch] = h / problem.phases.durations
    shape = (P, N, col.DEGREE)
    for k, value in enumerate(nominal):
        out[lay.xc[:, :, :, k]] = value.reshape(shape) / sc.x[k]
    for c in range(chain):
        out[lay.xc[:, :, :, npx + c]] = inputs[c].reshape(shape) / sc.x[npx + c]
    out[lay.u[:, :, 0]] = inputs[chain].reshape(shape)[:, :, -1] / sc.u
    return np.clip(out, lbx, ubx)
