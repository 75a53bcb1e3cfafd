"""Closed-loop simulation of the seed paper's Section V rig controller.

The controller (paper, Section V) computes a drive command from position, speed and thrust errors::

    u = Kp e_theta + Ki int(e_theta) + Kd e_omega + KpF e_F + KiF int(e_F)      (+ feedforward)

with ``e_theta = theta_d - theta``, ``e_omega = omega_d - omega``, ``e_F = F_d - F``; a 3 ms first-order
low-pass on ``e_omega``, 0.02 s on ``e_F``, 15 Hz on the remaining measurement (the position error);
integrator anti-windup (conditional integration); one-count quantisation of a +-2048-count command
range, i.e. 12 V / 2048 = 5.86 mV per count and a +-12 V limit; 1 ms sampling with zero-order hold.
Between samples the plant (:class:`~ocp.model.plant.DCMotorPlant`, or any voltage-input plant with state
``(omega, current)``) is integrated by :func:`ocp.simulate.open_loop.rk4_step`.

**Gain units (an interpretation).** The paper does not state the units of its gains. They are read
here as *counts* per SI unit of error (counts/rad, counts/(rad s), counts/(rad/s), counts/N,
counts/(N s)), because the controller works on a +-2048-count command: read as volts, ``Kd = 7``
would turn the paper's reported 37.6 (rad/s) local speed error into 263 V, whereas the paper reports a
2.70 V local peak; read as counts it is 1.54 V. :class:`GainUnit` lets a caller choose the volts
reading instead.

Array layout: every signal has shape (N,) on the controller's sample grid ``t`` [s].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ocp.errors import MissionError
from ocp.model.plant import DCMotorPlant
from ocp.simulate.open_loop import rk4_step
from ocp.theory.crossings import sign_change_times

#: half-width [s] of the window around each reversal in which local peaks are taken (paper: ~50 ms)
REVERSAL_WINDOW = 0.05


class GainUnit(StrEnum):
    """Unit of the controller output the gains are expressed in."""

    COUNTS = "counts"  # gains in counts per error unit; 1 count = v_max / counts_max volts
    VOLTS = "volts"  # gains in volts per error unit


@dataclass(frozen=True)
class PaperController:
    """Gains, filters and limits of the Section V controller (defaults: the paper's values).

    Attributes:
        kp: position gain [counts/rad]
        ki: position integral gain [counts/(rad s)]
        kd: speed gain [counts/(rad/s)]
        kp_f: thrust gain [counts/N]
        ki_f: thrust integral gain [counts/(N s)]
        tau_speed: time constant of the low-pass on e_omega [s]
        tau_thrust: time constant of the low-pass on e_F [s]
        f_measurement: cut-off of the low-pass on the remaining measurement, e_theta [Hz]
        counts_max: command range +-counts_max [counts]
        v_max: voltage at +-counts_max [V] (the saturation limit)
        sample_time: controller period [s]; the command is held (ZOH) over it
        quantise: round the command to whole counts (one-count quantisation)
        gain_unit: whether the gains produce counts (paper reading, see module doc) or volts
        substeps: RK4 sub-steps per sample for the plant (4 -> 0.25 ms, well inside RK4's stability
            limit for the rig's ~0.4 ms electrical time constant)
    """

    kp: float = 190.0
    ki: float = 5.0
    kd: float = 7.0
    kp_f: float = 500.0
    ki_f: float = 5.0
    tau_speed: float = 3e-3
    tau_thrust: float = 0.02
    f_measurement: float = 15.0
    counts_max: int = 2048
    v_max: float = 12.0
    sample_time: float = 1e-3
    quantise: bool = True
    gain_unit: GainUnit = GainUnit.COUNTS
    substeps: int = 4

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd", "kp_f", "ki_f", "v_max", "sample_time", "tau_speed", "tau_thrust",
                     "f_measurement"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise MissionError(f"controller.{name}", "must be a finite non-negative number")
        if self.v_max <= 0 or self.sample_time <= 0:
            raise MissionError("controller.v_max" if self.v_max <= 0 else "controller.sample_time", "must be > 0")
        if not (isinstance(self.counts_max, int) and self.counts_max >= 1):
            raise MissionError("controller.counts_max", "must be a positive integer")
        if not (isinstance(self.substeps, int) and 1 <= self.substeps <= 1000):
            raise MissionError("controller.substeps", "must be an integer in 1..1000")

    @property
    def volts_per_count(self) -> float:
        """Command resolution [V/count] (paper: 12 V / 2048 = 5.86 mV)."""
        return self.v_max / self.counts_max

    @property
    def output_scale(self) -> float:
        """Volts per unit of the gains' output [V/count or 1]."""
        return self.volts_per_count if self.gain_unit is GainUnit.COUNTS else 1.0


def lowpass_coefficient(tau: float, dt: float) -> float:
    """Exact ZOH discretisation of ``tau y' = x - y``: ``y[k] = y[k-1] + a (x[k] - y[k-1])``.

    ``a = 1 - exp(-dt/tau)`` [-]; ``tau = 0`` means no filter (a = 1).
    """
    return 1.0 if tau <= 0 else 1.0 - math.exp(-dt / tau)


@dataclass(frozen=True)
class TrackingMetrics:
    """Global and reversal-local tracking figures (SI: rad/s, N, V, A).

    Attributes:
        speed_mae / speed_rms: mean-absolute / RMS of omega_ref - omega over the run [rad/s]
        thrust_rms: RMS of thrust_ref - thrust [N]
        reversal_times: sign changes of thrust_ref inside the run [s]
        local_speed_error: max |omega_ref - omega| within +-window of any reversal [rad/s] (0 if none)
        local_voltage / local_current: max |V| [V] / |i| [A] within those windows (0 if none)
        peak_voltage / peak_current: max |V| [V] / |i| [A] over the run
        window: the half-width used [s]
    """

    speed_mae: float
    speed_rms: float
    thrust_rms: float
    reversal_times: tuple[float, ...]
    local_speed_error: float
    local_voltage: float
    local_current: float
    peak_voltage: float
    peak_current: float
    window: float


@dataclass(frozen=True)
class ClosedLoopResult:
    """One closed-loop run; every array has shape (N,) on ``t`` [s].

    Attributes:
        thrust_ref [N], omega_ref [rad/s], theta_ref [rad], feedforward [V]: what was asked
        thrust [N], omega [rad/s], theta [rad], current [A]: the plant at the samples
        voltage [V]: the held command applied on [t[k], t[k+1]) (after quantisation and saturation)
        saturated: True where the command hit +-v_max
        metrics: :class:`TrackingMetrics` with the default +-50 ms reversal window
    """

    t: np.ndarray
    thrust_ref: np.ndarray
    omega_ref: np.ndarray
    theta_ref: np.ndarray
    feedforward: np.ndarray
    thrust: np.ndarray
    omega: np.ndarray
    theta: np.ndarray
    current: np.ndarray
    voltage: np.ndarray
    saturated: np.ndarray
    metrics: TrackingMetrics

    @property
    def speed_error(self) -> np.ndarray:
        """omega_ref - omega [rad/s], shape (N,)."""
        return self.omega_ref - self.omega

    @property
    def thrust_error(self) -> np.ndarray:
        """thrust_ref - thrust [N], shape (N,)."""
        return self.thrust_ref - self.thrust


def reversal_times(t: np.ndarray, thrust_ref: np.ndarray) -> tuple[float, ...]:
    """Sign changes [s] of ``thrust_ref`` (N,) strictly inside the grid (linear interpolation)."""
    return tuple(sign_change_times(t, thrust_ref))


def tracking_metrics(t: np.ndarray, thrust_ref: np.ndarray, omega_ref: np.ndarray, thrust: np.ndarray,
                     omega: np.ndarray, voltage: np.ndarray, current: np.ndarray,
                     window: float = REVERSAL_WINDOW) -> TrackingMetrics:
    """Metrics of a run; all arrays (N,) on ``t`` [s], ``window`` [s] around each reversal."""
    e_w = np.abs(omega_ref - omega)
    e_f = thrust_ref - thrust
    rev = reversal_times(t, thrust_ref)
    near = np.zeros(t.shape, dtype=bool)
    for ts in rev:
        near |= np.abs(t - ts) <= window

    def local_max(a: np.ndarray) -> float:
        return float(np.max(np.abs(a[near]))) if near.any() else 0.0

    return TrackingMetrics(
        speed_mae=float(np.mean(e_w)), speed_rms=float(np.sqrt(np.mean(e_w**2))),
        thrust_rms=float(np.sqrt(np.mean(e_f**2))), reversal_times=rev,
        local_speed_error=local_max(e_w), local_voltage=local_max(voltage), local_current=local_max(current),
        peak_voltage=float(np.max(np.abs(voltage))), peak_current=float(np.max(np.abs(current))), window=window)


def _on_grid(t: np.ndarray, dt: float, signals: dict[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Resample ``signals`` (N,) given on ``t`` onto ``t[0] + k dt`` (linear) unless already there."""
    n = math.floor((t[-1] - t[0]) / dt + 1e-9) + 1
    grid = t[0] + dt * np.arange(n)
    if grid.size == t.size and np.allclose(grid, t, rtol=0.0, atol=1e-9 * max(1.0, abs(t[-1]))):
        return t, signals
    return grid, {k: np.interp(grid, t, v) for k, v in signals.items()}


def _validated(t: np.ndarray, refs: dict[str, np.ndarray]) -> None:
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise MissionError("t", "must be a strictly increasing finite 1-D grid of at least two samples")
    for name, v in refs.items():
        if v.shape != t.shape:
            raise MissionError(name, f"shape {v.shape} does not match t {t.shape}")
        if np.any(np.isnan(v)) or (name != "feedforward" and not np.all(np.isfinite(v))):
            raise MissionError(name, "contains NaN or inf" if name != "feedforward" else "contains NaN")


def track(plant: DCMotorPlant, t: np.ndarray, thrust_ref: np.ndarray, omega_ref: np.ndarray,
          theta_ref: np.ndarray, controller: PaperController | None = None,
          feedforward: np.ndarray | None = None, x0: tuple[float, float] | None = None) -> ClosedLoopResult:
    """Simulate the Section V loop tracking the given references.

    Args:
        plant: voltage-input plant with state (omega [rad/s], current [A])
        t: reference grid [s], shape (N,); if it is not the controller grid ``t[0] + k sample_time``
            the references are linearly resampled onto that grid (the result is on the controller grid)
        thrust_ref [N], omega_ref [rad/s], theta_ref [rad]: references, shape (N,)
        controller: gains/filters/limits (default :class:`PaperController`)
        feedforward: optional additive voltage [V], shape (N,); +-inf samples (an ideal unbounded
            command) are allowed and end up saturated at +-v_max
        x0: initial (omega [rad/s], current [A]); default: omega_ref[0] at its steady-state current;
            internal states of stateful plant effects, if any, start at 0
    """
    ctrl = PaperController() if controller is None else controller
    t = np.asarray(t, dtype=float)
    refs = {"thrust_ref": np.asarray(thrust_ref, float), "omega_ref": np.asarray(omega_ref, float),
            "theta_ref": np.asarray(theta_ref, float)}
    if feedforward is not None:
        ff_in = np.asarray(feedforward, float)
        refs["feedforward"] = np.clip(ff_in, -ctrl.v_max, ctrl.v_max) if ff_in.shape == t.shape else ff_in
    _validated(t, refs)
    t, refs = _on_grid(t, ctrl.sample_time, refs)
    ff = refs.get("feedforward", np.zeros_like(t))
    if x0 is None:
        w0 = float(refs["omega_ref"][0])
        x0 = (w0, plant.steady_state(w0)[0])
    if not all(math.isfinite(v) for v in x0):
        raise MissionError("x0", "initial state must be finite")
    w, i, th, u, sat, f_meas = _loop(plant, ctrl, t, refs["thrust_ref"], refs["omega_ref"], refs["theta_ref"], ff, x0)
    thrust = f_meas
    metrics = tracking_metrics(t, refs["thrust_ref"], refs["omega_ref"], thrust, w, u, i)
    return ClosedLoopResult(t=t, thrust_ref=refs["thrust_ref"], omega_ref=refs["omega_ref"],
                            theta_ref=refs["theta_ref"], feedforward=ff, thrust=thrust, omega=w, theta=th,
                            current=i, voltage=u, saturated=sat, metrics=metrics)


def _loop(plant: DCMotorPlant, c: PaperController, t: np.ndarray, f_ref: np.ndarray, w_ref: np.ndarray,
          th_ref: np.ndarray, ff: np.ndarray, x0: tuple[float, float]) -> tuple[np.ndarray, ...]:
    """The sampled loop; returns (omega, current, theta, voltage, saturated, thrust), each (N,)."""
    n, dt = t.size, c.sample_time
    a_w = lowpass_coefficient(c.tau_speed, dt)
    a_f = lowpass_coefficient(c.tau_thrust, dt)
    a_th = lowpass_coefficient(1.0 / (2.0 * math.pi * c.f_measurement) if c.f_measurement > 0 else 0.0, dt)
    scale = c.output_scale
    vmax_counts = c.v_max / scale  # the limit in the gains' output unit
    cf = plant.params.c_f if plant.effects == () else None
    w_out, i_out, th_out = np.empty(n), np.empty(n), np.empty(n)
    u_out, sat_out, f_out = np.empty(n), np.zeros(n, dtype=bool), np.empty(n)
    x = np.zeros(len(plant.state_names))  # effect states (if any) start at 0
    x[:2] = x0
    theta = 0.0 + float(th_ref[0])
    ew_f = ef_f = eth_f = 0.0
    int_th = int_f = 0.0
    fr, wr, thr, ffc = f_ref.tolist(), w_ref.tolist(), th_ref.tolist(), (ff / scale).tolist()
    for k in range(n):
        w, i = float(x[0]), float(x[1])
        w_out[k], i_out[k], th_out[k] = w, i, theta
        f_meas = cf * w * abs(w) if cf is not None else float(plant.thrust(list(x)))
        f_out[k] = f_meas
        e_th, e_f = thr[k] - theta, fr[k] - f_meas
        ew_f += a_w * (wr[k] - w - ew_f)
        ef_f += a_f * (e_f - ef_f)
        eth_f += a_th * (e_th - eth_f)
        new_int_th, new_int_f = int_th + eth_f * dt, int_f + ef_f * dt
        cmd = c.kp * eth_f + c.ki * new_int_th + c.kd * ew_f + c.kp_f * ef_f + c.ki_f * new_int_f + ffc[k]
        saturated = abs(cmd) >= vmax_counts
        if not saturated or cmd * eth_f < 0:  # conditional integration: never wind further into saturation
            int_th = new_int_th
        if not saturated or cmd * ef_f < 0:
            int_f = new_int_f
        cmd = min(max(cmd, -vmax_counts), vmax_counts)
        if c.quantise and c.gain_unit is GainUnit.COUNTS:
            cmd = float(round(cmd))
        elif c.quantise:
            cmd = round(cmd / c.volts_per_count) * c.volts_per_count
        volts = cmd * scale
        u_out[k], sat_out[k] = volts, saturated
        if k + 1 < n:
            x = rk4_step(plant, x, volts, dt, c.substeps)
            theta += 0.5 * dt * (w + float(x[0]))
    return w_out, i_out, th_out, u_out, sat_out, f_out
