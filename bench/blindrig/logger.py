"""Sensors, speed controller and the logging loop of the blind rig.

The loop at row n: read the sensors at the (possibly jittered) instant t_n, compute the command (open-loop
table or PI on the measured speed), log the command beside the sensors; the command acts on the drive from
t_{n+skew} + delay (skew: logging convention, delay: the input_delay effect), held until the next one acts.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .excite import Excitation
from .rig import Rig, RigTruth

TWO_PI = 2.0 * math.pi


@dataclass
class LoggerConfig:
    """Logger settings (SI units).

    Attributes:
        rate: nominal logging rate [Hz]; n: number of rows; skew: command-to-sensor logging skew [rows].
        jitter: std of the sampling-instant jitter as a fraction of the period [-] (0: none).
        speed_sensor: "tacho" or "encoder"; columns: "omega", "theta" or "both" (encoder only for theta).
        tach_noise: tachometer noise std [rad/s]; tach_filter: its first-order filter time [rows].
        cpr: encoder counts per revolution; diff_window: encoder difference window [rows].
        cur_noise: current noise std [A]; cur_filter: current filter time [rows]; cur_bits: ADC bits;
        cur_range: ADC full scale +- [A]; cur_offset: current-sensor offset [A] (effect; 0 none).
        thr_noise: load-cell noise std [N]; thr_bits: ADC bits; thr_range: full scale +- [N];
        thr_offset: load-cell offset [N] (effect; 0 none); thr_filter: load-cell filter time [rows].
        pi_kp: PI proportional gain [V s/rad]; pi_ki: integral gain [V/rad].
    """

    rate: float
    n: int
    skew: int
    jitter: float
    speed_sensor: str
    columns: str
    tach_noise: float
    tach_filter: float
    cpr: int
    diff_window: int
    cur_noise: float
    cur_filter: float
    cur_bits: int
    cur_range: float
    cur_offset: float
    thr_noise: float
    thr_bits: int
    thr_range: float
    thr_offset: float
    thr_filter: float
    pi_kp: float
    pi_ki: float

    def to_dict(self) -> dict:
        """Plain dict of all fields."""
        return asdict(self)


def _alpha(tau_rows: float) -> float:
    """Gain of a first-order discrete low-pass with time constant tau_rows [rows] (0: pass-through)."""
    return 1.0 if tau_rows <= 0.0 else 1.0 - math.exp(-1.0 / tau_rows)


def _quant(x: float, full: float, bits: int) -> float:
    """Quantise x to a bipolar ADC of +-full with the given bits, saturating."""
    q = 2.0 * full / (2**bits)
    return max(-full, min(full - q, round(x / q) * q))


def sample_times(rng: np.random.Generator, cfg: LoggerConfig, extra: int) -> np.ndarray:
    """Actual sampling instants [s] of n + extra rows: nominal grid plus clipped Gaussian jitter."""
    dt = 1.0 / cfg.rate
    m = cfg.n + extra
    t = np.arange(m) * dt
    if cfg.jitter > 0.0:
        t = t + np.clip(rng.normal(0.0, cfg.jitter * dt, m), -0.3 * dt, 0.3 * dt)
        t[0] = 0.0
    return t


def run_log(truth: RigTruth, cfg: LoggerConfig, exc: Excitation, h_max: float, rng: np.random.Generator,
            theta0: float = 0.0) -> dict[str, np.ndarray]:
    """Simulate the rig under the excitation and log it.

    Returns columns: ``t`` [s], ``voltage`` [V] (the logged command), ``current`` [A], ``omega`` [rad/s],
    ``theta`` [rad], ``thrust`` [N] (all measured), plus ``true_i``, ``true_w``, ``true_F``, ``u_motor``
    (true motor voltage [V] over the interval following each row) and the substep count ``n_steps``.
    """
    n = cfg.n
    dt = 1.0 / cfg.rate
    t = sample_times(rng, cfg, cfg.skew + 3)
    delay = truth.delay
    act = t[cfg.skew:cfg.skew + n] + delay  # row m's command acts from t_{m+skew} + delay
    rig = Rig(truth, h_max, theta0=theta0)
    cols = {k: np.zeros(n) for k in ("voltage", "current", "omega", "theta", "thrust",
                                     "true_i", "true_w", "true_F", "u_motor")}
    e_cur = rng.normal(0.0, cfg.cur_noise, n)
    e_tach = rng.normal(0.0, cfg.tach_noise, n)
    e_thr = rng.normal(0.0, cfg.thr_noise, n)
    a_cur, a_tach, a_thr = _alpha(cfg.cur_filter), _alpha(cfg.tach_filter), _alpha(cfg.thr_filter)
    y_cur = y_tach = y_thr = 0.0
    counts: list[int] = []
    k_cnt = cfg.cpr / TWO_PI
    th_offset = math.floor(theta0 * k_cnt)
    integ = 0.0
    was_closed = False
    u = rig.drive(0.0)
    p = 0
    cmds = np.zeros(n)
    closed, ref, cmd_tab = exc.closed, exc.ref, exc.cmd
    Vs = truth.V_supply
    for m in range(n):
        tm = t[m]
        # ---- sensors at t_m
        i_true, w_true, F_true = rig.i, rig.w, rig.thrust()
        y_cur += a_cur * (i_true + cfg.cur_offset + e_cur[m] - y_cur)
        i_meas = _quant(y_cur, cfg.cur_range, cfg.cur_bits)
        y_thr += a_thr * (F_true + cfg.thr_offset + e_thr[m] - y_thr)
        F_meas = _quant(y_thr, cfg.thr_range, cfg.thr_bits)
        c = math.floor(rig.th * k_cnt) - th_offset
        counts.append(c)
        if cfg.speed_sensor == "encoder":
            j = max(0, m - cfg.diff_window)
            w_meas = (c - counts[j]) / k_cnt / (max(m - j, 1) * dt)
        else:
            y_tach += a_tach * (w_true + e_tach[m] - y_tach)
            w_meas = y_tach
        cols["current"][m] = i_meas
        cols["thrust"][m] = F_meas
        cols["omega"][m] = w_meas
        cols["theta"][m] = c / k_cnt
        cols["true_i"][m], cols["true_w"][m], cols["true_F"][m] = i_true, w_true, F_true
        # ---- command
        if closed[m]:
            if not was_closed:
                integ = float(np.clip(cmd_tab[m - 1] if m > 0 else 0.0, -Vs, Vs))
            e = ref[m] - w_meas
            integ_new = integ + cfg.pi_ki * e * dt
            v = cfg.pi_kp * e + integ_new
            if -Vs < v < Vs:
                integ = integ_new
            v = max(-Vs, min(Vs, cfg.pi_kp * e + integ))
            was_closed = True
        else:
            v = float(cmd_tab[m])
            was_closed = False
        cmds[m] = v
        # ---- integrate to t_{m+1}, applying the commands whose activation time falls inside
        t_cur = tm
        t_next = t[m + 1]
        while p <= m and act[p] < t_next:
            if act[p] > t_cur:
                rig.advance(u, act[p] - t_cur)
                t_cur = act[p]
            u = rig.drive(cmds[p])
            p += 1
        rig.advance(u, t_next - t_cur)
        cols["u_motor"][m] = u
    cols["voltage"] = cmds
    cols["t"] = t[:n].copy()
    cols["n_steps"] = np.array([rig.n_steps])
    return cols
