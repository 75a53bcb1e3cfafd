"""A-posteriori verification: the plant simulated under the returned input, its peaks checked against the limits.

The simulation is fixed-step RK4 on a grid of at most ``SIM_STEP`` (shortened for a stiff plant, see
:func:`sim_step`), an integrator independent of the collocation scheme; :func:`verification` reports the
reproduction error and the peaks and margins of the simulated response on the integration grid.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, cast

import casadi as ca
import numpy as np

from ocp.errors import MissionError
from ocp.model.plant import CASADI, Plant
from ocp.optimize.mission import Mission
from ocp.simulate.open_loop import rk4

PATH_TOLERANCE = 1e-3  # relative excess over a limit accepted as rounding
SIM_STEP = 2.5e-4  # s, longest verification step (two RK4 sub-steps each)
RK4_STIFFNESS = 0.32  # largest |h lambda| of an RK4 sub-step: RK4 is stable to 2.78, its error ~ (h lambda)^5 / 120
MAX_SIM_STEPS = 2_000_000  # verification steps of one answer (about a second of computing)


@lru_cache(maxsize=16)
def _rk4_function(plant: Any) -> ca.Function:
    """CasADi RK4 step ``(x, u, dt) -> x+`` with 2 sub-steps, built once per plant."""
    nx = len(plant.state_names)
    x, u, dt = ca.SX.sym("x", nx), ca.SX.sym("u"), ca.SX.sym("dt")
    return ca.Function("rk4", [x, u, dt], [ca.vertcat(*rk4(plant, [x[i] for i in range(nx)], u, dt, 2, CASADI))])


@lru_cache(maxsize=64)
def _rk4_accumulator(plant: Any, steps: int) -> ca.Function:
    """``steps`` RK4 steps chained (CasADi ``mapaccum``), cached per plant and length."""
    return _rk4_function(plant).mapaccum("sim", steps)


@lru_cache(maxsize=16)
def _jacobian_function(plant: Any) -> ca.Function:
    """``(x, u) -> d rhs / d x`` of ``plant``, built once per plant."""
    nx = len(plant.state_names)
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u")
    rhs = ca.vertcat(*plant.rhs([x[i] for i in range(nx)], u, CASADI))
    return ca.Function("rhs_jacobian", [x, u], [ca.jacobian(rhs, x)])


def sim_step(plant: Plant, x0: np.ndarray, u0: float) -> float:
    """Verification step [s]: ``SIM_STEP``, shortened until each RK4 sub-step keeps ``|h lambda| <=
    RK4_STIFFNESS`` for the fastest eigenvalue ``lambda`` [1/s] of the plant's Jacobian at ``x0`` and at
    ``x0`` with the speed set to zero (for the DC motor it is about ``-R/L``: 2500 1/s for the paper rig;
    a 20 uH winding makes it 100x faster, and a fixed step would make the simulation diverge)."""
    jac = _jacobian_function(cast(Hashable, plant))
    at_rest = np.array(x0, float)
    at_rest[0] = 0.0
    lam = max(float(np.max(np.abs(np.linalg.eigvals(np.asarray(jac(x, u0)))))) for x in (x0, at_rest))
    return min(SIM_STEP, 2.0 * RK4_STIFFNESS / lam) if lam > 0 else SIM_STEP


@dataclass(frozen=True)
class Response:
    """A simulated response. Attributes: ``at_out`` states (nx, M) at the requested times; ``t`` the
    integration grid [s] (K,), ``x`` the states on it (nx, K), ``u`` the input held from each grid point
    on (K,; the last one repeated)."""

    at_out: np.ndarray
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray


def simulate_response(plant: Plant, t_knots: np.ndarray, u_of_interval: np.ndarray, x0: np.ndarray,
                      t_out: np.ndarray) -> Response:
    """Integrate ``plant`` from ``x0`` under the input held at ``u_of_interval[k]`` on
    ``[t_knots[k], t_knots[k+1])``, on a grid through the knots and ``t_out`` (M,) with steps of at most
    :func:`sim_step`.

    Raises :class:`MissionError` (``params``) when the plant is too stiff to verify within ``MAX_SIM_STEPS``.
    """
    grid = np.union1d(t_knots, t_out)
    step_max = sim_step(plant, x0, float(u_of_interval[0]))
    n_sub = np.maximum(1, np.ceil(np.diff(grid) / step_max).astype(int))
    if n_sub.sum() > MAX_SIM_STEPS:
        raise MissionError("params", f"too stiff to verify: the plant's fastest mode needs steps of {step_max:.3g} s, "
                                     f"{int(n_sub.sum())} of them over {grid[-1] - grid[0]:.3g} s "
                                     f"(at most {MAX_SIM_STEPS})")
    # every grid step split into n_sub equal sub-steps, vectorised
    first = np.repeat(np.cumsum(n_sub) - n_sub, n_sub)
    fine = np.append(np.repeat(grid[:-1], n_sub) + (np.arange(n_sub.sum()) - first) * np.repeat(np.diff(grid) / n_sub,
                                                                                                  n_sub), grid[-1])
    k = np.clip(np.searchsorted(t_knots, fine[:-1], side="right") - 1, 0, u_of_interval.size - 1)
    u = u_of_interval[k]
    step = _rk4_accumulator(cast(Hashable, plant), fine.size - 1)
    xs = np.asarray(step(x0, u[None, :], np.diff(fine)[None, :]))
    states = np.concatenate([np.asarray(x0, float)[:, None], xs], axis=1)
    idx = np.clip(np.searchsorted(fine, t_out), 0, fine.size - 1)
    return Response(at_out=states[:, idx], t=fine, x=states, u=np.append(u, u[-1]))


def channels(m: Mission, resp: Response) -> dict[str, np.ndarray]:
    """The simulated response on the integration grid as the result's channels (t, omega, current,
    voltage, and for the torque plant its normalised torque with the DC equivalent current and voltage)."""
    out = {"t": resp.t, "omega": resp.x[0]}
    if m.plant == "dc-motor":
        out["current"], out["voltage"] = resp.x[1], resp.u
    else:
        out["torque"] = resp.u
        out["current"], out["voltage"] = torque_plant_commands(m, resp.x[0], resp.u)
    return out


def torque_plant_commands(m: Mission, w: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Current and voltage a DC motor would need for the torque-plant solution (tau = J u)."""
    p = m.motor()
    i = p.J * u / p.k_t + p.B * w / p.k_t  # torque input J u covers inertia + drag; B adds
    return i, p.R * i + p.k_e * w


def verification(m: Mission, arrays: dict[str, np.ndarray], f_plan: np.ndarray,
                  fine: dict[str, np.ndarray]) -> dict[str, Any]:
    """Reproduction error (simulated vs planned thrust) on the output grid; peaks and margins of the
    simulated response on the integration grid ``fine`` (between the output samples too)."""
    err = arrays["thrust"] - f_plan

    def peak(name: str) -> float:
        return max(float(np.max(np.abs(arrays[name]))), float(np.max(np.abs(fine[name]))))

    i_max, v_max, w_max = peak("current"), peak("voltage"), peak("omega")
    lim = m.limits
    tol = 1.0 + PATH_TOLERANCE
    out: dict[str, Any] = {
        "thrust_rms_error": float(np.sqrt(np.mean(err**2))),
        "thrust_max_error": float(np.max(np.abs(err))),
        "tracking_rms_error": float(np.sqrt(np.mean((arrays["thrust"] - arrays["thrust_desired"]) ** 2))),
        "max_abs_current": i_max, "max_abs_voltage": v_max, "max_abs_speed": w_max,
        "current_margin": lim.current - i_max, "voltage_margin": lim.voltage - v_max,
    }
    if "torque" in arrays:  # the torque channel: its drive owns i and V (reported as the DC equivalent)
        tau_max = peak("torque") * m.motor().J
        out.update(max_abs_torque=tau_max, torque_margin=m.torque_limit() - tau_max)
        path_ok = tau_max <= m.torque_limit() * tol
    else:
        path_ok = i_max <= lim.current * tol and v_max <= lim.voltage * tol
    if lim.speed is not None:
        path_ok = path_ok and w_max <= lim.speed * tol
    out["path_ok"] = bool(path_ok)
    return out
