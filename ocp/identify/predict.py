"""Model predictions of a log: free run and one-step (equation) residuals.

Two ways to confront a plant with a time-series log (all arrays (N,) SI unless stated):

* **free run** -- the plant integrated under the measured voltage (zero-order held, as a digital
  drive applies it), restarted from the measured state at the start of every segment of
  ``segment_s`` seconds, the rotor angle read from the log at every sample (:func:`measured_states`: a ripple's
  phase is lost within a segment of the free run's own angle); compared with the measured speed, current and
  thrust. Integrated by the project's one zero-order-hold
  simulator (:mod:`ocp.simulate.zoh`: CasADi ``mapaccum`` of the same ``plant.rhs`` the optimiser uses, RK4
  steps under its stability rule from the plant's fastest eigenvalue).
* **one-step residuals** -- from the measured state at sample k, one sample of integration under
  ``V[k]``; the mismatch at k+1 is written in equation units: torque [N m] for eq. dc_mechanical
  (``J dw / dt``), voltage [V] for eq. dc_electrical (``R di / (1 - exp(-R dt/L))``), thrust [N]
  for eq. thrust_model (static). Effect states (delay, inflow lag, rotor angle) come from
  :meth:`ocp.model.effects.StatefulBase.observe` driven by the measured signals.

Steady-state sweeps have no dynamics: the "free run" is the equilibrium reached under each row's
voltage (solved per row), and the equation residuals are the right-hand sides at the measured
operating point (``J w'``, ``L i'``) -- what the plant would accelerate by if the row were not steady.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ocp.errors import LogError, SolverError
from ocp.filters import iir
from ocp.identify.noise_level import sensor_noise
from ocp.logs import Log, LogKind
from ocp.model.effects import measured_current, stateful
from ocp.model.plant import NUMPY, DCMotorPlant
from ocp.parallel import threads
from ocp.simulate.zoh import SUBSTEPS, rk4, segment_simulator, steps_per_sample

CHANNELS: tuple[str, ...] = ("omega", "current", "thrust")
EQUATIONS: tuple[str, ...] = ("mechanical", "electrical", "thrust")
EQUATION_UNITS = {"mechanical": "N m", "electrical": "V", "thrust": "N"}
CHANNEL_UNITS = {"omega": "rad/s", "current": "A", "thrust": "N"}
#: a plant needing more RK4 steps a sample than this is not free-run (:func:`free_run` raises): a fitted brush
#: contact or Stribeck band gone sharp took 31,000-61,000 steps a sample and 17-127 s for one log (session 14)
MAX_STEPS_PER_SAMPLE = 4096


@dataclass(frozen=True)
class FreeRun:
    """Free-run prediction on the evaluated samples ``idx`` (M,) of the log.

    Attributes:
        idx: sample indices into the log, (M,): whole segments of ``length`` rows (1: equilibria, row by row)
        omega [rad/s], current [A] (as the sensor would read it), thrust [N]: predictions, (M,)
        current_lag: the current sensor's first-order lag [samples] the current was read through
            (:func:`read_current`; 0: as simulated)
    """

    idx: np.ndarray
    omega: np.ndarray
    current: np.ndarray
    thrust: np.ndarray
    length: int = 1
    current_lag: float = 0.0

    def channel(self, name: str) -> np.ndarray:
        return {"omega": self.omega, "current": self.current, "thrust": self.thrust}[name]


@dataclass(frozen=True)
class Residuals:
    """One-step equation residuals at the samples ``idx`` (M,): measured minus model.

    Attributes:
        mechanical [N m], electrical [V], thrust [N]: (M,)
    """

    idx: np.ndarray
    mechanical: np.ndarray
    electrical: np.ndarray
    thrust: np.ndarray

    def equation(self, name: str) -> np.ndarray:
        return {"mechanical": self.mechanical, "electrical": self.electrical, "thrust": self.thrust}[name]


def substeps(plant: DCMotorPlant, dt: float, x_ref: np.ndarray | None = None) -> int:
    """RK4 sub-steps per sample of ``dt`` [s]: the simulator's stability rule (:func:`ocp.simulate.zoh.step_limit`)
    at the state ``x_ref`` (n_states,; default at rest), ``SUBSTEPS`` per step."""
    x = np.zeros(len(plant.state_names)) if x_ref is None else x_ref
    return SUBSTEPS * steps_per_sample(plant, dt, x, 0.0)


def current_offset(plant: DCMotorPlant) -> float:
    """Sensor offset [A]: measured minus true current (current-sensor effects are affine, slope 1)."""
    return float(measured_current(plant, 0.0))


def observed_states(plant: DCMotorPlant, log: Log) -> np.ndarray:
    """Full plant state (n_states, N) reconstructed from the log: measured speed, true current
    (sensor offset removed) and the effect states observed from the measured signals."""
    rows = [log.omega, log.current - current_offset(plant)]
    ideal = plant.params.c_f * log.omega * np.abs(log.omega)
    for eff in stateful(plant):
        if log.kind is LogKind.STEADY_STATE:
            rows += list(eff.steady(log.omega, log.voltage, ideal, log.theta))
        else:
            rows += list(eff.observe(log.t, log.omega, log.voltage, ideal, log.theta))
    return np.vstack(rows)


def measured_states(plant: DCMotorPlant) -> tuple[int, ...]:
    """Indices of the plant's states a log measures (:attr:`ocp.model.stateful_effects.StatefulBase.measured`: the
    rotor angle), which a free run reads at every sample. A ripple's torque depends on the angle to a fraction of
    its period; a free run's own angle, integrated from its speed, loses that within a segment (proving ground 42066,
    10 periods/rev on a 2 kHz encoder log: with the ripple ``fit``'s first stage finds, 50 mN m for the rig's 47.5,
    the free run's speed error rose from 4.5 to 12.2 rad/s with its own angle and falls to 2.3 with the log's)."""
    out: list[int] = []
    j = 2
    for eff in stateful(plant):
        if eff.measured:
            out += range(j, j + len(eff.states))
        j += len(eff.states)
    return tuple(out)


def segments(log: Log, segment_s: float) -> np.ndarray:
    """Start indices (B,) of whole segments of ``segment_s`` seconds (a trailing partial one is dropped)."""
    length = max(2, round(segment_s / log.dt))
    if log.n < length:
        raise LogError("t", f"too short for {segment_s} s segments ({log.n} samples of {log.dt:.3g} s)")
    return np.arange(0, log.n - length + 1, length)


def run_rows(log: Log, segment_s: float) -> np.ndarray:
    """Rows (K,) a time-series free run predicts: every whole segment of ``segment_s`` [s] (:func:`segments`)."""
    length = max(2, round(segment_s / log.dt))
    return (segments(log, segment_s)[:, None] + np.arange(length)[None, :]).ravel()


#: backward-difference spans [samples] :func:`speed_span` tries for a speed differenced from a logged angle
MAX_SPEED_SPAN = 4


def speed_span(log: Log) -> int:
    """How the logged speed was formed from the logged angle: ``d`` [samples] where ``omega[k]`` is the backward
    difference ``(theta[k] - theta[k - d]) / (d dt)`` (the mean speed over the last ``d`` samples, ``d`` = 1 ..
    :data:`MAX_SPEED_SPAN`: a firmware differencing its encoder), 0 where it is the speed at the sample (a
    tachometer; a speed the reader differentiated from the angle, centrally). The candidate whose speed from the
    angle is nearest the logged one (RMS over the rows all candidates share) -- where the speed changes little
    over a few samples they tie, and the choice then moves the prediction by less than that difference. 0 without
    a logged angle or for steady-state sweeps."""
    th = log.theta
    if th is None or log.kind is not LogKind.TIME_SERIES or log.n < 2 * MAX_SPEED_SPAN + 2:
        return 0
    rows = slice(MAX_SPEED_SPAN, log.n - 1)
    w = log.omega[rows]
    central = (th[MAX_SPEED_SPAN + 1:] - th[MAX_SPEED_SPAN - 1:-2]) / (2 * log.dt)
    miss = [float(np.mean((w - central) ** 2))]
    for d in range(1, MAX_SPEED_SPAN + 1):
        back = (th[MAX_SPEED_SPAN:-1] - th[MAX_SPEED_SPAN - d:log.n - 1 - d]) / (d * log.dt)
        miss.append(float(np.mean((w - back) ** 2)))
    return int(np.argmin(miss))


def sensed_speed(omega: np.ndarray, span: int, length: int) -> np.ndarray:
    """The speed a logger differencing over ``span`` samples (:func:`speed_span`) reads from the predicted speeds
    ``omega`` (B * length,) of B segments of ``length`` samples each: the mean over the last ``span`` samples (the
    trapezoid rule between samples: second order in the sample time), the speed itself on a segment's first
    ``span`` rows (no predicted history there) and for ``span`` 0."""
    if span == 0:
        return omega
    w = omega.reshape(-1, length)
    out = w.copy()
    acc = 0.5 * (w[:, span:] + w[:, :-span])
    for j in range(1, span):
        acc = acc + w[:, j:length - span + j]
    out[:, span:] = acc / span
    return out.reshape(-1)


def free_run(plant: DCMotorPlant, log: Log, segment_s: float = 0.5) -> FreeRun:
    """Free-run prediction of a time-series log (see module doc); steady-state sweeps: equilibria. The speed is
    predicted as the logger read it (:func:`speed_span`, :func:`sensed_speed`: an encoder differenced over two
    samples at 200 Hz reads a rotor reversing at +-390 rad/s a sample late, 24 rad/s RMS from the speed itself).
    Raises :class:`SolverError` (``plant``) for a plant needing over :data:`MAX_STEPS_PER_SAMPLE` RK4 steps a
    sample, before simulating."""
    if log.kind is LogKind.STEADY_STATE:
        return equilibrium(plant, log)
    starts = segments(log, segment_s)
    length = max(2, round(segment_s / log.dt))
    nx = len(plant.state_names)
    x_obs = observed_states(plant, log)
    per_sample = substeps(plant, log.dt, x_obs[:, 0]) // SUBSTEPS
    if per_sample > MAX_STEPS_PER_SAMPLE:
        raise SolverError("plant", f"too stiff to free-run: {per_sample} RK4 steps a sample of {log.dt:.3g} s "
                                   f"(at most {MAX_STEPS_PER_SAMPLE}); a sharp effect (brush contact, Stribeck band)?")
    read = measured_states(plant)
    # built once per plant and shape; the segments run in CasADi's threads, inside the one call (ocp.parallel's
    # pieces may not call CasADi)
    sim = segment_simulator(plant, per_sample, length, starts.size, read, threads())
    inputs = np.vstack([log.voltage, x_obs[list(read)]])  # (1 + R, N): the command, the states read from the log
    u_blocks = np.concatenate([inputs[:, s:s + length - 1] for s in starts], axis=1)
    traj = np.asarray(sim(x_obs[:, starts], u_blocks, log.dt / per_sample))
    traj = traj.reshape(nx, starts.size, length - 1)
    full = np.concatenate([x_obs[:, starts].reshape(nx, starts.size, 1), traj], axis=2).reshape(nx, -1)
    idx = run_rows(log, segment_s)
    if not np.all(np.isfinite(full)):
        full = np.where(np.isfinite(full), full, 1e6)  # a diverging model: huge error, not a crash
    thrust = np.asarray(plant.thrust(list(full)), dtype=float)
    speed = sensed_speed(full[0], speed_span(log), length)
    return FreeRun(idx, speed, np.asarray(measured_current(plant, full[1]), float), thrust, length)


#: the current sensor's lags [samples] :func:`read_current` tries: a firmware's first-order filter
#: ``y += (i - y) / (1 + lag)`` delays a slow current by ``lag`` samples (the proving ground's loggers draw 0 - 0.7)
CURRENT_LAGS: tuple[float, ...] = tuple(round(0.1 * j, 1) for j in range(21))


def lagged_current(fr: FreeRun, lag: float) -> np.ndarray:
    """The current (M,) [A] a sensor with a first-order filter of ``lag`` samples reads from ``fr``'s predicted
    current, each segment's filter starting from the segment's first row (the logged current the run starts from)."""
    if lag <= 0.0 or fr.length < 2:
        return fr.current
    a = 1.0 / (1.0 + lag)
    c = fr.current.reshape(-1, fr.length)
    out = c.copy()
    out[:, 1:] = iir([a], [1.0, a - 1.0], c[:, 1:].T, start=c[:, 0]).T  # (from the steady state at the first row)
    return out.reshape(-1)


def read_current(fr: FreeRun, log: Log, rows: np.ndarray | None = None) -> FreeRun:
    """``fr`` with its current read through the current sensor's lag (:data:`CURRENT_LAGS`, :func:`lagged_current`)
    that best matches the logged current on ``rows`` (bool (N,): rows the lag is fitted on, default every row; a
    held-out score fits it on the training rows). A logger's filter is not the model's failure: unread, the exact
    plant's ``check`` was a median 2.6 noise units off in current on the 52 clean and constant-only proving-ground
    logs of seeds 0..199, 19 at the 90th percentile (1.5 and 5.1 read through the lag fitted, within 0.3 samples of
    the logger's on the 50 whose alignment is within a quarter sample; a sample's misalignment is partly taken up as
    lag: ``bench/checkfloor.py``). Equilibria (``length`` 1) and runs with no fitting row are returned as they are."""
    keep = np.ones(fr.idx.size, bool) if rows is None else rows[fr.idx]
    if fr.length < 2 or not keep.any():
        return fr
    measured = log.current[fr.idx][keep]
    miss = [float(np.sum((measured - lagged_current(fr, lag)[keep]) ** 2)) for lag in CURRENT_LAGS]
    lag = CURRENT_LAGS[int(np.argmin(miss))]
    return replace(fr, current=lagged_current(fr, lag), current_lag=lag)


def one_step(plant: DCMotorPlant, log: Log) -> Residuals:
    """One-step equation residuals (measured minus model) of a log (see module doc)."""
    p = plant.params
    x = observed_states(plant, log)
    if log.kind is LogKind.STEADY_STATE:
        d = np.asarray(plant.rhs(list(x), log.voltage, NUMPY)[:2])
        f = log.thrust - np.asarray(plant.thrust(list(x)), float)
        return Residuals(np.arange(log.n), -p.J * d[0], -p.L * d[1], f)
    dt = log.dt
    xk = [row[:-1] for row in x]
    pred = rk4(plant, xk, log.voltage[:-1], dt, substeps(plant, dt, x[:, 0]), NUMPY)
    a = math.exp(-p.R * dt / p.L)
    mech = p.J * (log.omega[1:] - pred[0]) / dt
    elec = p.R / (1.0 - a) * (log.current[1:] - measured_current(plant, pred[1]))
    thrust = log.thrust[:-1] - np.asarray(plant.thrust(xk), float)
    return Residuals(np.arange(log.n - 1), mech, elec, thrust)


def equilibrium(plant: DCMotorPlant, log: Log, iterations: int = 60) -> FreeRun:
    """Steady operating point (omega, current) under each row's voltage (damped Newton, vectorised)."""
    x = observed_states(plant, log)
    extra = [row for row in x[2:]]
    w, i = x[0].copy(), x[1].copy()
    for _ in range(iterations):
        f = np.asarray(plant.rhs([w, i, *extra], log.voltage)[:2])
        hw, hi = 1e-4 * (1.0 + np.abs(w)), 1e-6 * (1.0 + np.abs(i))
        fw = (np.asarray(plant.rhs([w + hw, i, *extra], log.voltage)[:2]) - f) / hw
        fi = (np.asarray(plant.rhs([w, i + hi, *extra], log.voltage)[:2]) - f) / hi
        det = fw[0] * fi[1] - fi[0] * fw[1]
        dw = (-f[0] * fi[1] + fi[0] * f[1]) / det
        di = (-fw[0] * f[1] + f[0] * fw[1]) / det
        w, i = w + np.clip(dw, -20.0, 20.0), i + np.clip(di, -1.0, 1.0)
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(i))):
        raise SolverError("equilibrium", "no steady operating point found for some rows")
    thrust = np.asarray(plant.thrust([w, i, *extra]), float)
    return FreeRun(np.arange(log.n), w, np.asarray(measured_current(plant, i), float), thrust)


def noise_levels(log: Log) -> dict[str, float]:
    """Robust white-noise level [channel unit] per channel from second differences (MAD / sqrt(6)).

    For steady-state sweeps (no smooth time axis), 1 % of the channel's RMS is used instead.
    """
    out = {}
    for ch in CHANNELS:
        y = getattr(log, ch)
        if log.kind is LogKind.STEADY_STATE or y.size < 10:
            out[ch] = max(0.01 * float(np.sqrt(np.mean(y * y))), 1e-12)
            continue
        out[ch] = max(sensor_noise(y), 1e-6 * float(np.max(np.abs(y))), 1e-12)
    return out
