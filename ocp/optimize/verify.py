"""A-posteriori verification: the plant simulated under the returned input, its peaks checked against the limits.

The simulation is the project's one zero-order-hold simulator (:mod:`ocp.simulate.zoh`: fixed-step RK4 on a
grid of at most ``SIM_STEP``, shortened for a stiff plant by its stability rule, the step compiled to C where a
compiler is available), an integrator independent of the collocation scheme; :func:`verification` reports the
reproduction error and the peaks and margins of the simulated response on the integration grid.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from ocp.model.plant import Plant
from ocp.optimize.mission import Mission
from ocp.optimize.result import Verification
from ocp.simulate.zoh import MAX_SIM_STEPS, RK4_STIFFNESS, SIM_STEP, Response, simulate_held, step_limit

PATH_TOLERANCE = 1e-3  # relative excess over a limit accepted as rounding

__all__ = ["MAX_SIM_STEPS", "PATH_TOLERANCE", "RK4_STIFFNESS", "SIM_STEP", "Response", "channels", "sim_step",
           "simulate_response", "verification"]


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
    return {"t": resp.t, "omega": resp.x[0], **m.drive_plant().channels(resp.x, resp.u)}


def verification(m: Mission, arrays: dict[str, np.ndarray], f_plan: np.ndarray,
                 fine: dict[str, np.ndarray]) -> Verification:
    """Reproduction error (simulated vs planned thrust) on the output grid; peaks and margins of the
    simulated response on the integration grid ``fine`` (between the output samples too)."""
    err = arrays["thrust"] - f_plan

    @cache  # the drive's peak report asks for the current and the voltage again
    def peak(name: str) -> float:
        return max(float(np.max(np.abs(arrays[name]))), float(np.max(np.abs(fine[name]))))

    i_max, v_max, w_max = peak("current"), peak("voltage"), peak("omega")
    lim = m.limits
    tol = 1.0 + PATH_TOLERANCE
    extra, path_ok = m.drive_plant().peak_report(peak, m.bounds(), tol)  # the drive's own limits
    if lim.speed is not None:
        path_ok = path_ok and w_max <= lim.speed * tol
    return Verification(
        thrust_rms_error=float(np.sqrt(np.mean(err**2))), thrust_max_error=float(np.max(np.abs(err))),
        tracking_rms_error=float(np.sqrt(np.mean((arrays["thrust"] - arrays["thrust_desired"]) ** 2))),
        max_abs_current=i_max, max_abs_voltage=v_max, max_abs_speed=w_max,
        current_margin=lim.current - i_max, voltage_margin=lim.voltage - v_max, path_ok=bool(path_ok), **extra)
