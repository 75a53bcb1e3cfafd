"""The analytic fallback answer: what :func:`ocp.optimize.solve.optimize` returns when it cannot optimise.

Hold levels joined by local polynomial reversals (or ``A sin^(2q+1)``) designed within the limits by
:mod:`ocp.reference.fallback`, simulated on the mission's plant and verified like an optimised answer.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ocp.errors import InfeasibleError, MissionError
from ocp.model.equilibrium import equilibrium
from ocp.optimize.mission import Mission, output_grid
from ocp.optimize.result import Crossing, OptimizeResult, SolverStats, Source, Status
from ocp.optimize.verify import channels, simulate_response, verification
from ocp.reference.analytic import reference
from ocp.reference.fallback import DESIGN_STEPS, DriveLimits, design_sin, hold_limit, plan_reversals


def analytic_fallback(m: Mission, reason: str, solver_info: SolverStats | None = None) -> OptimizeResult:
    """Analytic reference within the mission's limits: hold levels joined by local polynomial reversals
    of the order the regularity needs (``alpha (t - t_s)^p chi``), or, for a profile that never
    reverses, the ``A sin^(2q+1)`` design at the mission's peak thrust. For the torque channel the
    reversals are sized to its torque bound and the plant is driven by the torque.

    Never over the limits: hold levels are capped at what the motor holds in steady state, a reversal
    without room is first given the room of the longest retiming (``retiming.max_stretch``), then its
    levels are lowered; the mission's plant (effects included) is simulated and the design redone with
    lower levels until the simulated response stays within the limits on the integration grid.

    Raises :class:`~ocp.errors.InfeasibleError` naming the binding limit when nothing within the limits
    is found.
    """
    params, lim, torque = m.motor(), m.limits, m.drive_plant().torque_limit(m.bounds())
    last: OptimizeResult | None = None
    error: InfeasibleError | None = None
    stretches = sorted({m.retiming.min_stretch, m.retiming.max_stretch})
    for margin, shrink in DESIGN_STEPS:
        drive = DriveLimits(margin * lim.current, margin * lim.voltage, None if torque is None else margin * torque)
        cap = shrink * hold_limit(params, drive, None if lim.speed is None else margin * lim.speed)
        best: tuple[float, OptimizeResult] | None = None
        for stretch in stretches:  # the shortest retiming unless it needs lower levels than the longest
            try:
                res, lowered = _fallback_try(m, drive, cap, stretch, reason, solver_info)
            except InfeasibleError as exc:
                error = exc
                continue
            if not res.path_ok:
                last = res
                continue
            if lowered >= 0.999:
                return res
            if best is None or lowered > best[0]:
                best = (lowered, res)
        if best is not None:
            return best[1]
    if last is None and error is not None:
        raise error
    field = _binding(m, last)
    raise InfeasibleError(field, f"no reference within the limits: even the analytic fallback with lowered hold "
                                 f"levels and stretched time exceeds {field}")


def _binding(m: Mission, res: OptimizeResult | None) -> str:
    """The limit field the (failed) fallback exceeds most."""
    if res is None:
        return "limits"
    # the peaks the verification reports: over the returned arrays and the integration grid
    peaks = {k: max(float(np.max(np.abs(res.arrays[k]))), float(np.max(np.abs(v)))) for k, v in res.fine.items()}
    ratios = {k: float(r) for k, r in m.drive_plant().limit_ratios(peaks, m.bounds()).items()}
    if m.limits.speed is not None:
        ratios["limits.speed"] = res.verification.max_abs_speed / m.limits.speed
    return max(ratios, key=lambda k: ratios[k] if math.isfinite(ratios[k]) else math.inf)


def _fallback_try(m: Mission, drive: DriveLimits, cap: float, stretch: float, reason: str,
                  solver_info: SolverStats | None) -> tuple[OptimizeResult, float]:
    """One fallback design with hold levels capped at ``cap`` [N] and time stretched ``stretch`` x, simulated
    and verified; returns it and the smallest level / desired level."""
    params = m.motor()
    t_d, f_d = m.desired()
    t_d = (t_d - t_d[0]) * stretch
    dc = m.drive_plant().voltage_driven
    t = output_grid(float(t_d[-1]))
    design = plan_reversals(params, t_d, f_d, drive.current, drive.voltage, m.regularity, dc, drive.torque,
                            level_cap=cap)
    lowered, notes = 1.0, []
    prof: Any
    if design is not None:
        prof, lowered = design.profile, design.lowered
    else:
        amp = min(max(float(np.max(np.abs(f_d))), 1e-6), cap)
        lim = (params, drive.current, drive.voltage, m.regularity)
        try:
            prof = design_sin(*lim, amplitude=amp, voltage_driven=dc, torque_limit=drive.torque).profile
        except MissionError:
            try:
                prof = design_sin(*lim, period=2.0 * float(t_d[-1]), voltage_driven=dc,
                                  torque_limit=drive.torque).profile
            except MissionError as exc:
                raise InfeasibleError("limits", f"no analytic reference fits the limits: {exc.reason}") from None
        lowered = abs(prof.amplitude) / max(float(np.max(np.abs(f_d))), 1e-6)
    if lowered < 0.999:
        notes.append(f"hold levels lowered to {100 * lowered:.3g} % of the desired thrust to meet the limits")
    if stretch != 1.0:
        notes.append(f"time stretched {stretch:g}x (retiming)")
    return _fallback_result(m, prof, t, t_d, f_d, "; ".join([reason, *notes]), solver_info), lowered


def _fallback_result(m: Mission, prof: Any, t: np.ndarray, t_d: np.ndarray, f_d: np.ndarray, reason: str,
                     solver_info: SolverStats | None) -> OptimizeResult:
    """Closed-form reference of ``prof`` on ``t`` (M,), simulated on the mission's plant and verified."""
    params, plant = m.motor(), m.drive_plant()
    ref = reference(prof, params, t)
    arrays = {"t": t, "thrust": ref.thrust, "thrust_desired": np.interp(t, t_d, f_d), "omega": ref.omega,
              "theta": ref.theta}
    # the closed forms are the nominal model's; the check runs the mission's plant, effects included
    nominal, command = plant.feedforward(ref)  # speed (and current), input [V or rad/s^2]
    x0 = equilibrium(plant, float(ref.omega[0]))[0]  # effect states at rest
    x0[: len(nominal)] = [s[0] for s in nominal]
    arrays.update(plant.channels(np.array(nominal), command))
    u_knots = 0.5 * (command[:-1] + command[1:])
    resp = simulate_response(plant, t, u_knots, x0, t)
    arrays["command_t"], arrays["command"] = t, np.append(u_knots, u_knots[-1])
    f_sim = np.asarray(plant.thrust([resp.at_out[k] for k in range(resp.at_out.shape[0])]), float)
    fine = channels(m, resp)
    report = verification(m, {**arrays, "thrust": f_sim}, ref.thrust, fine)
    crossings = [Crossing(t=float(ts), exponent=float(p or 0), sign_change=True)
                 for ts, p in zip(ref.crossing_times, ref.crossing_orders, strict=True) if 0.0 < ts < t[-1]]
    return OptimizeResult(name=m.name, source=Source.ANALYTIC_FALLBACK, status=Status.FALLBACK, reason=reason,
                          arrays=arrays, crossings=crossings, stretch=[], verification=report,
                          solver=solver_info if solver_info is not None else SolverStats(),
                          fine=fine)
