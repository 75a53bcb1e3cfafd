"""Optimisation results: extraction of the collocation solution, a-posteriori verification, fallback.

Verification integrates the plant (fixed-step RK4 on a grid of at most 0.25 ms, an integrator
independent of the collocation scheme) under the returned input and reports the reproduction error.
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING, Any, cast

import casadi as ca
import numpy as np
from scipy.integrate import cumulative_trapezoid

from ocp.errors import InfeasibleError, MissionError
from ocp.model.equilibrium import equilibrium
from ocp.model.plant import CASADI, DCMotorPlant, Plant, TorquePlant
from ocp.optimize import collocation as col
from ocp.optimize.mission import MAX_OUTPUT_S, OUTPUT_RATE, Mission
from ocp.reference.analytic import reference
from ocp.reference.fallback import DESIGN_STEPS, DriveLimits, channel_torque, design_sin, hold_limit, plan_reversals
from ocp.simulate.open_loop import rk4

if TYPE_CHECKING:
    from ocp.optimize.solve import Problem

PATH_TOLERANCE = 1e-3  # relative excess over a limit accepted as rounding
SIM_STEP = 2.5e-4  # s, longest verification step (two RK4 sub-steps each)
RK4_STIFFNESS = 0.32  # largest |h lambda| of an RK4 sub-step: RK4 is stable to 2.78, its error ~ (h lambda)^5 / 120
MAX_SIM_STEPS = 2_000_000  # verification steps of one answer (about a second of computing)
COMMAND_SUBSTEPS = 4  # held pieces per collocation interval of a continuous command (simulation and output)


@dataclass
class OptimizeResult:
    """A reference and how it was obtained. Arrays have shape (N,) on ``t`` [s], SI units.

    Attributes:
        source: "optimized" or "analytic-fallback"
        status: IPOPT return status, or "fallback"
        reason: why the fallback was used ("" when optimised)
        arrays: t, thrust, thrust_desired, omega, theta, current, voltage (and ``torque`` for the
            torque plant: normalised input [rad/s^2])
        crossings: [{"t", "exponent", "sign_change"}] at each reversal of the returned thrust
        stretch: per phase, achieved duration / desired duration
        verification: thrust_rms_error, thrust_max_error [N] (simulation vs returned), tracking_rms_error
            [N] (returned vs desired), max_abs_current [A], max_abs_voltage [V], margins, path_ok
        solver: status, iterations, objective, constraint_violation, and times [s]: setup_time_s (mission
            -> problem data), build_time_s (0 when the structure's solver is cached), solve_time_s (IPOPT),
            verify_time_s (simulation and packaging); solve and verify add up over back-off rounds
    """

    name: str
    source: str
    status: str
    reason: str
    arrays: dict[str, np.ndarray]
    crossings: list[dict[str, Any]]
    stretch: list[float]
    verification: dict[str, Any]
    solver: dict[str, Any] = field(default_factory=dict)
    total_time_s: float = 0.0
    #: the simulated response on the integration grid (t, omega, current, voltage[, torque]), shapes (K,):
    #: what the limits are checked on between the output samples; not serialised
    fine: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def path_ok(self) -> bool:
        return bool(self.verification.get("path_ok", False))

    @property
    def solve_time_s(self) -> float:
        return float(self.solver.get("solve_time_s", 0.0))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (no NaN/inf) dict: the CLI's ``--json`` and the service's answer."""
        out: dict[str, Any] = {
            "name": self.name, "source": self.source, "status": self.status, "reason": self.reason,
            "solve_time_s": self.solve_time_s, "total_time_s": self.total_time_s,
            "iterations": self.solver.get("iterations"), "solver": json_ready(self.solver),
            "verification": json_ready(self.verification), "crossings": json_ready(self.crossings),
            "stretch": json_ready(self.stretch),
        }
        for k, v in self.arrays.items():
            out[k] = json_ready(np.asarray(v, float).tolist())
        return out


def json_ready(obj: Any) -> Any:
    """``obj`` with numpy scalars made plain and non-finite floats made ``None`` (strict JSON)."""
    if isinstance(obj, dict):
        return {k: json_ready(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_ready(v) for v in obj]
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


# ---------------------------------------------------------------------------------------------
# evaluation of the collocation solution


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


def extract(problem: Problem, prog: col.Program, xopt: np.ndarray, data: dict[str, np.ndarray]) -> Solution:
    st = problem.structure
    lay = prog.layout
    xs, us = data["xscale"], float(data["uscale"][0])
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


def _channels(m: Mission, resp: Response) -> dict[str, np.ndarray]:
    """The simulated response on the integration grid as the result's channels (t, omega, current,
    voltage, and for the torque plant its normalised torque with the DC equivalent current and voltage)."""
    out = {"t": resp.t, "omega": resp.x[0]}
    if m.plant == "dc-motor":
        out["current"], out["voltage"] = resp.x[1], resp.u
    else:
        out["torque"] = resp.u
        out["current"], out["voltage"] = _torque_plant_commands(m, resp.x[0], resp.u)
    return out


def _output_grid(total: float) -> np.ndarray:
    """Output times [s] at OUTPUT_RATE over ``total``; a horizon over MAX_OUTPUT_S (a min-time solve's
    free horizon) is refused rather than sampled."""
    if not total <= MAX_OUTPUT_S:
        raise MissionError("retiming", f"the reference would last {total:.4g} s; at most {MAX_OUTPUT_S:g} s")
    n = max(2, math.ceil(total * OUTPUT_RATE) + 1)
    return np.linspace(0.0, total, n)


def finish_result(problem: Problem, prog: col.Program, xopt: np.ndarray, data: dict[str, np.ndarray],
                  solver_info: dict[str, Any]) -> OptimizeResult:
    """Evaluate, verify and package a solved program.

    The returned speed, current and thrust are the plant's response to the returned command
    (simulated); the collocation solution is the plan, and the gap between the two is reported as
    ``verification.thrust_rms_error``. Between nodes the polynomial of a fast state (the current,
    with L/R ~ 0.4 ms) says little, the simulated response is what the motor does.
    """
    m, plant = problem.mission, problem.plant
    sol = extract(problem, prog, xopt, data)
    t = _output_grid(float(sol.phase_edges[-1]))
    x_plan, u = sol.states(t)
    npx = prog.n_plant_states
    f_plan = np.asarray(plant.thrust([x_plan[i] for i in range(npx)]), float)
    # desired thrust at the retimed time (same normalised time within each phase)
    j = np.clip(np.searchsorted(sol.phase_edges, t, side="right") - 1, 0, problem.phases.signs.size - 1)
    frac = (t - sol.phase_edges[j]) / np.diff(sol.phase_edges)[j]
    f_des = np.interp(problem.phases.bounds[j] + frac * problem.phases.durations[j], problem.t_desired,
                      problem.f_desired)
    if sol.chain:  # continuous input: knots on the output grid and COMMAND_SUBSTEPS per collocation interval
        # (a 1 kHz hold smears a voltage that turns within one interval: a min-time solve's do, in 0.1 ms)
        knots = np.union1d(t, _subdivide(sol.edges, COMMAND_SUBSTEPS))
        u_knots = sol.states(0.5 * (knots[:-1] + knots[1:]))[1]
    else:
        knots, u_knots = sol.edges, sol.controls
    resp = simulate_response(plant, knots, u_knots, sol.points[0, 0, :npx], t)
    x = resp.at_out
    thrust = np.asarray(plant.thrust([x[i] for i in range(npx)]), float)
    arrays = {"t": t, "thrust": thrust, "thrust_desired": f_des, "omega": x[0],
              "theta": cumulative_trapezoid(x[0], t, initial=0.0)}
    dc = isinstance(plant, DCMotorPlant)
    if dc:
        arrays["current"], arrays["voltage"] = x[1], u
    else:
        arrays["torque"] = u
        arrays["current"], arrays["voltage"] = _torque_plant_commands(m, x[0], u)
    arrays["command_t"], arrays["command"] = knots, np.append(u_knots, u_knots[-1])
    fine = _channels(m, resp)
    verification = _verification(m, arrays, f_plan, fine)
    crossings = _crossings(sol, data["xscale"], float(data["uscale"][0]))
    stretch = (np.diff(sol.phase_edges) / problem.phases.durations).tolist()
    return OptimizeResult(name=m.name, source="optimized", status=solver_info["status"], reason="",
                          arrays=arrays, crossings=crossings, stretch=stretch, verification=verification,
                          solver=solver_info, fine=fine)


def _subdivide(edges: np.ndarray, parts: int) -> np.ndarray:
    """``edges`` (K,) with ``parts - 1`` equally spaced points inserted in each gap, shape ((K-1) parts + 1,)."""
    frac = np.arange(parts) / parts
    inner = (edges[:-1, None] + frac[None, :] * np.diff(edges)[:, None]).ravel()
    return np.append(inner, edges[-1])


def _torque_plant_commands(m: Mission, w: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Current and voltage a DC motor would need for the torque-plant solution (tau = J u)."""
    p = m.motor()
    i = p.J * u / p.k_t + p.B * w / p.k_t  # torque input J u covers inertia + drag; B adds
    return i, p.R * i + p.k_e * w


def _verification(m: Mission, arrays: dict[str, np.ndarray], f_plan: np.ndarray,
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


def _crossings(sol: Solution, xscale: np.ndarray, uscale: float) -> list[dict[str, Any]]:
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
        out.append({"t": float(ts), "exponent": float(2 * n + 2), "sign_change": True,
                    "current": float(node_si[1]) if node.size > 1 else None, "voltage": float(volts)})
    return out


# ---------------------------------------------------------------------------------------------
# fallback




def analytic_fallback(m: Mission, reason: str, solver_info: dict[str, Any] | None = None) -> OptimizeResult:
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
    params, lim = m.motor(), m.limits
    last: OptimizeResult | None = None
    error: InfeasibleError | None = None
    stretches = sorted({m.retiming.min_stretch, m.retiming.max_stretch})
    for margin, shrink in DESIGN_STEPS:
        drive = DriveLimits(margin * lim.current, margin * lim.voltage,
                            None if m.plant == "dc-motor" else margin * m.torque_limit())
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
    v = res.verification
    if "max_abs_torque" in v:
        return "limits.torque"
    ratios = {"limits.current": v["max_abs_current"] / m.limits.current,
              "limits.voltage": v["max_abs_voltage"] / m.limits.voltage}
    if m.limits.speed is not None:
        ratios["limits.speed"] = v["max_abs_speed"] / m.limits.speed
    return max(ratios, key=lambda k: ratios[k] if math.isfinite(ratios[k]) else math.inf)


def _fallback_try(m: Mission, drive: DriveLimits, cap: float, stretch: float, reason: str,
                  solver_info: dict[str, Any] | None) -> tuple[OptimizeResult, float]:
    """One fallback design with hold levels capped at ``cap`` [N] and time stretched ``stretch`` x, simulated
    and verified; returns it and the smallest level / desired level."""
    params = m.motor()
    t_d, f_d = m.desired()
    t_d = (t_d - t_d[0]) * stretch
    dc = m.plant == "dc-motor"
    t = _output_grid(float(t_d[-1]))
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
                     solver_info: dict[str, Any] | None) -> OptimizeResult:
    """Closed-form reference of ``prof`` on ``t`` (M,), simulated on the mission's plant and verified."""
    params = m.motor()
    dc = m.plant == "dc-motor"
    ref = reference(prof, params, t)
    arrays = {"t": t, "thrust": ref.thrust, "thrust_desired": np.interp(t, t_d, f_d), "omega": ref.omega,
              "theta": ref.theta}
    # the closed forms are the nominal model's; the check runs the mission's plant, effects included
    plant: Plant
    if dc:
        plant = m.dc_plant()
        x0 = equilibrium(plant, float(ref.omega[0]))[0]
        x0[1] = ref.current[0]
        command = ref.voltage
        arrays["current"], arrays["voltage"] = ref.current, ref.voltage
    else:
        plant = TorquePlant.from_params(params)
        x0 = np.array([ref.omega[0]])
        command = channel_torque(params, ref) / params.J  # normalised input u [rad/s^2]
        arrays["torque"] = command
        arrays["current"], arrays["voltage"] = _torque_plant_commands(m, ref.omega, command)
    u_knots = 0.5 * (command[:-1] + command[1:])
    resp = simulate_response(plant, t, u_knots, x0, t)
    arrays["command_t"], arrays["command"] = t, np.append(u_knots, u_knots[-1])
    f_sim = np.asarray(plant.thrust([resp.at_out[k] for k in range(resp.at_out.shape[0])]), float)
    fine = _channels(m, resp)
    verification = _verification(m, {**arrays, "thrust": f_sim}, ref.thrust, fine)
    crossings = [{"t": float(ts), "exponent": float(p or 0), "sign_change": True}
                 for ts, p in zip(ref.crossing_times, ref.crossing_orders, strict=True) if 0.0 < ts < t[-1]]
    return OptimizeResult(name=m.name, source="analytic-fallback", status="fallback", reason=reason, arrays=arrays,
                          crossings=crossings, stretch=[], verification=verification, solver=solver_info or {},
                          fine=fine)
