"""Solved program -> optimised answer: the collocation solution evaluated, its command simulated and verified.

:func:`extract` turns the decision vector into piecewise polynomials (:class:`Solution`); :func:`finish_result`
samples the command, simulates the plant under it (:mod:`ocp.optimize.verify`) and packages an
:class:`~ocp.optimize.result.OptimizeResult` with the crossing exponents achieved.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid

from ocp.optimize import collocation as col
from ocp.optimize.data import ProblemData
from ocp.optimize.mission import output_grid
from ocp.optimize.problem import Problem
from ocp.optimize.result import Crossing, OptimizeResult, SolverStats, Source
from ocp.optimize.verify import channels, simulate_response, verification

COMMAND_SUBSTEPS = 4  # held pieces per collocation interval of a continuous command (simulation and output)


@dataclass(frozen=True)
class Solution:
    """Piecewise-polynomial states of a solved program (SI).

    Attributes:
        edges: interval boundaries [s], shape (P*N+1,)
        points: interval node values, shape (P*N, DEGREE+1, nx)
        controls: piecewise-constant control per interval, shape (P*N,)
        signs: speed sign per interval, shape (P*N,)
        phase_edges: phase boundaries [s], shape (P+1,)
    """

    edges: np.ndarray
    points: np.ndarray
    controls: np.ndarray
    signs: np.ndarray
    phase_edges: np.ndarray
    chain: int
    n_plant_states: int

    def states(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(states (nx, M), plant input (M,)) at times ``t`` (M,)."""
        k = np.clip(np.searchsorted(self.edges, t, side="right") - 1, 0, self.controls.size - 1)
        s = (t - self.edges[k]) / (self.edges[k + 1] - self.edges[k])
        basis = col.lagrange_basis(s)  # (M, D+1)
        x = np.einsum("md,mdn->nm", basis, self.points[k])
        u = x[self.n_plant_states] if self.chain else self.controls[k]
        return x, u


def extract(problem: Problem, prog: col.Program, xopt: np.ndarray, data: ProblemData) -> Solution:
    st = problem.structure
    lay = prog.layout
    xs, us = data.scales.x, data.scales.u
    P, N = st.n_phases, st.intervals
    h = xopt[lay.stretch] * problem.phases.durations
    phase_edges = np.concatenate([[0.0], np.cumsum(h)])
    edges = np.concatenate([phase_edges[j] + np.arange(N) * h[j] / N for j in range(P)] + [phase_edges[-1:]])
    xc = xopt[lay.xc] * xs  # (P, N, D, nx)
    start = np.empty((P, N, prog.nx))
    flat = xc.reshape(P * N, col.DEGREE, prog.nx)
    start_flat = start.reshape(P * N, prog.nx)
    start_flat[0] = xopt[lay.x0] * xs
    start_flat[1:] = flat[:-1, -1, :]
    points = np.concatenate([start_flat[:, None, :], flat], axis=1)
    controls = xopt[lay.u].reshape(P * N) * us
    signs = np.repeat(problem.phases.signs, N)
    return Solution(edges=edges, points=points, controls=controls, signs=signs, phase_edges=phase_edges,
                    chain=st.chain, n_plant_states=prog.n_plant_states)


def finish_result(problem: Problem, prog: col.Program, xopt: np.ndarray, data: ProblemData,
                  solver_info: SolverStats) -> OptimizeResult:
    """Evaluate, verify and package a solved program.

    The returned speed, current and thrust are the plant's response to the returned command
    (simulated); the collocation solution is the plan, and the gap between the two is reported as
    ``verification.thrust_rms_error``. Between nodes the polynomial of a fast state (the current,
    with L/R ~ 0.4 ms) says little, the simulated response is what the motor does.
    """
    sol = extract(problem, prog, xopt, data)
    t = output_grid(float(sol.phase_edges[-1]))
    if sol.chain:  # continuous input: knots on the output grid and COMMAND_SUBSTEPS per collocation interval
        # (a 1 kHz hold smears a voltage that turns within one interval: a min-time solve's do, in 0.1 ms)
        knots = np.union1d(t, _subdivide(sol.edges, COMMAND_SUBSTEPS))
        u_knots = sol.states(0.5 * (knots[:-1] + knots[1:]))[1]
    else:
        knots, u_knots = sol.edges, sol.controls
    crossings = _crossings(sol, data.scales.x, data.scales.u)
    return package(problem, t, sol.states(t), sol.phase_edges, (knots, u_knots),
                   sol.points[0, 0, :prog.n_plant_states], crossings, solver_info)


def package(problem: Problem, t: np.ndarray, planned: tuple[np.ndarray, np.ndarray], phase_edges: np.ndarray,
            command: tuple[np.ndarray, np.ndarray], x0: np.ndarray, crossings: list[Crossing],
            solver_info: SolverStats) -> OptimizeResult:
    """The answer of a solved program (Radau or flat) on the output times ``t`` (M,) [s]
    (:func:`~ocp.optimize.mission.output_grid` of the retimed length): ``planned`` its plan there (states (nx, M),
    input (M,)); ``phase_edges`` (P+1,) [s]; ``command`` (knots (K+1,) [s], input held from each (K,)); ``x0``
    (n_plant_states,) the initial state. The command is simulated and verified on the output grid."""
    m, plant = problem.mission, problem.plant
    npx = len(plant.state_names)
    x_plan, u = planned
    f_plan = np.asarray(plant.thrust([x_plan[i] for i in range(npx)]), float)
    # desired thrust at the retimed time (same normalised time within each phase)
    j = np.clip(np.searchsorted(phase_edges, t, side="right") - 1, 0, problem.phases.signs.size - 1)
    frac = (t - phase_edges[j]) / np.diff(phase_edges)[j]
    f_des = np.interp(problem.phases.bounds[j] + frac * problem.phases.durations[j], problem.t_desired,
                      problem.f_desired)
    knots, u_knots = command
    resp = simulate_response(plant, knots, u_knots, x0, t)
    x = resp.at_out
    thrust = np.asarray(plant.thrust([x[i] for i in range(npx)]), float)
    arrays = {"t": t, "thrust": thrust, "thrust_desired": f_des, "omega": x[0],
              "theta": cumulative_trapezoid(x[0], t, initial=0.0)}
    arrays.update(plant.channels(x, u))
    arrays["command_t"], arrays["command"] = knots, np.append(u_knots, u_knots[-1])
    fine = channels(m, resp)
    report = verification(m, arrays, f_plan, fine)
    stretch = (np.diff(phase_edges) / problem.phases.durations).tolist()
    return OptimizeResult(name=m.name, source=Source.OPTIMIZED, status=solver_info.status, reason="",
                          arrays=arrays, crossings=crossings, stretch=stretch, verification=report,
                          solver=solver_info, fine=fine)


def _subdivide(edges: np.ndarray, parts: int) -> np.ndarray:
    """``edges`` (K,) with ``parts - 1`` equally spaced points inserted in each gap, shape ((K-1) parts + 1,)."""
    frac = np.arange(parts) / parts
    inner = (edges[:-1, None] + frac[None, :] * np.diff(edges)[:, None]).ravel()
    return np.append(inner, edges[-1])


def _crossings(sol: Solution, xscale: np.ndarray, uscale: float) -> list[Crossing]:
    """Local exponent g (|F| ~ |t - t_s|^g) achieved at each phase boundary, exact from the ODE.

    At a boundary omega = 0 and omega' is proportional to the next element of the chain: current,
    then voltage, then its slew (dc_mechanical / dc_electrical); for the torque plant the input,
    then its slew. If the first ``n`` elements vanish, omega ~ s^(n+1) and the thrust ~ s^(2n+2).
    Elements count as zero below 1e-6 of their scale; the held control, taken on both sides of the
    crossing, stands last. Also reported: the planned current and input (voltage; for a piecewise
    constant command the value held after the crossing) at the crossing.
    """
    out = []
    N = sol.controls.size // (sol.phase_edges.size - 1)
    for k, ts in enumerate(sol.phase_edges[1:-1]):
        node = sol.points[(k + 1) * N - 1, -1, :] / xscale
        left, right = sol.controls[(k + 1) * N - 1], sol.controls[(k + 1) * N]
        npx = sol.n_plant_states
        links = ([1] if npx > 1 else []) + list(range(npx, npx + sol.chain))  # current, then the input chain
        chain = [*np.abs(node[links]), max(abs(left), abs(right)) / uscale]
        n = 0
        while n < len(chain) and chain[n] <= 1e-6:
            n += 1
        node_si = node * xscale
        volts = node_si[sol.n_plant_states] if sol.chain else right
        out.append(Crossing(t=float(ts), exponent=float(2 * n + 2), sign_change=True,
                            current=float(node_si[1]) if node.size > 1 else None, voltage=float(volts)))
    return out
