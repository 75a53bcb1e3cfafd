"""A-posteriori verification: the plant simulated under the returned input, its peaks checked against the limits.

The simulation is the project's one zero-order-hold simulator (:mod:`ocp.simulate.zoh`: fixed-step RK4 on a
grid of at most ``SIM_STEP``, shortened for a stiff plant by its stability rule, the step compiled to C where a
compiler is available), an integrator independent of the collocation scheme; :func:`verification` reports the
reproduction error and the peaks and margins of the simulated response on the integration grid.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ocp.model.plant import Plant
from ocp.optimize.mission import Mission
from ocp.simulate.zoh import MAX_SIM_STEPS, RK4_STIFFNESS, SIM_STEP, Response, simulate_held, step_limit

PATH_TOLERANCE = 1e-3  # relative excess over a limit accepted as rounding

__all__ = ["MAX_SIM_STEPS", "PATH_TOLERANCE", "RK4_STIFFNESS", "SIM_STEP", "Response", "channels", "sim_step",
           "simulate_response", "torque_plant_commands", "verification"]


def sim_step(plant: Plant, x0: np.ndarray, u0: float) -> float:
    """Verification step [s] (two RK4 sub-steps): :func:`ocp.simulate.zoh.step_limit` capped at ``SIM_STEP``."""
    return step_limit(plant, x0, u0, SIM_STEP)


def simulate_response(plant: Plant, t_knots: np.ndarray, u_of_interval: np.ndarray, x0: np.ndarray,
                      t_out: np.ndarray) -> Response:
    """The plant from ``x0`` (nx,) under ``u_of_interval[k]`` held on ``[t_knots[k], t_knots[k+1])``, on a grid
    through the knots and ``t_out`` (M,) (:func:`ocp.simulate.zoh.simulate_held`; raises
    :class:`~ocp.errors.MissionError` (``params``) for a plant too stiff to verify)."""
    return simulate_held(plant, t_knots, u_of_interval, x0, t_out, SIM_STEP)


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
