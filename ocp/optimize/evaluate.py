"""One evaluator of an answer's objective, whichever program produced it (flat or Radau; benchmarks and tests).

The Radau and the flat program write the objective of ``ocp.optimize.data.WEIGHTS`` on their own variables; to
compare two answers honestly, :func:`objective_of` recomputes it from what the user receives: the simulated
thrust on the output grid and the held command. Terms (the Radau program's definitions):

* track: per phase ``(d_j / D) int_0^1 ((F - F_d) / F_s)^2 dtau`` = ``int (F - F_d)^2 dt / (F_s^2 stretch_j D)``
  (trapezoid on the 1 kHz output grid; ``D`` the desired span, ``F_s`` the thrust scale);
* stretch: ``sum_j (stretch_j - 1) d_j / D``;
* smoothness and effort of the control ``u`` on the Radau intervals (``N`` per phase): the command averaged
  over each interval, then (chain 1, 2) its first or second difference quotient; scaled by the control scale;
  ``sum (u_{k+1} - u_k)^2 / (P N)`` and ``sum u_k^2 / (P N)``.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.integrate import trapezoid

from ocp.optimize.data import WEIGHTS, problem_data
from ocp.optimize.problem import Problem
from ocp.optimize.result import OptimizeResult


def objective_terms(problem: Problem, result: OptimizeResult) -> dict[str, float]:
    """The objective's terms (unweighted) and ``total`` (weighted sum) of ``result`` for ``problem``."""
    st, arr = problem.structure, result.arrays
    sc = problem_data(problem).scales
    stretch, dur = np.asarray(result.stretch, float), problem.phases.durations
    total_d = float(np.sum(dur))
    edges = np.concatenate([[0.0], np.cumsum(stretch * dur)])
    t = arr["t"]
    j = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, st.n_phases - 1)
    err2 = ((arr["thrust"] - arr["thrust_desired"]) / sc.f) ** 2 / (stretch[j] * total_d)
    track = float(trapezoid(err2, t))
    u = _control(arr["command_t"], arr["command"][:-1], edges, st.intervals, st.chain) / sc.u
    n_u = st.n_phases * st.intervals
    terms = {"track": track, "stretch": float(np.dot(stretch - 1.0, dur) / total_d),
             "smooth": float(np.sum(np.diff(u) ** 2) / n_u), "effort": float(np.sum(u**2) / n_u)}
    w_track, _, w_stretch, w_smooth, w_effort = WEIGHTS[problem.mission.objective]
    terms["total"] = (w_track * terms["track"] + w_stretch * terms["stretch"] + w_smooth * terms["smooth"]
                      + w_effort * terms["effort"])
    return terms


def objective_of(problem: Problem, result: OptimizeResult) -> float:
    """The weighted objective of ``result`` (:func:`objective_terms`)."""
    return objective_terms(problem, result)["total"]


def _control(knots: np.ndarray, held: np.ndarray, phase_edges: np.ndarray, n: int, chain: int) -> np.ndarray:
    """The held input (``held[k]`` on ``[knots[k], knots[k+1])``) averaged over each of the ``n`` equal intervals
    of every phase, then differentiated ``chain`` times (difference quotients), shape (P n - chain,)."""
    area = np.concatenate([[0.0], np.cumsum(held * np.diff(knots))])  # integral of the input from 0
    cuts = np.concatenate([np.linspace(a, b, n + 1)[:-1] for a, b in itertools.pairwise(phase_edges)]
                          + [phase_edges[-1:]])
    mean = np.diff(np.interp(cuts, knots, area)) / np.diff(cuts)
    mids = 0.5 * (cuts[:-1] + cuts[1:])
    for _ in range(chain):
        mean = np.diff(mean) / np.diff(mids)
        mids = 0.5 * (mids[:-1] + mids[1:])
    return mean
