"""Draw one blind case (rig truth, nominal parameter file, logger, excitation, labels) from a seed.

Everything is deterministic in the seed (numpy default_rng). ``draw_case(seed)`` only draws; the log itself
is produced by :func:`blindrig.case.generate`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .excite import Excitation, make_excitation
from .logger import LoggerConfig
from .rig import RigTruth, no_load_speed, stiffness_step

EFFECTS = ("coulomb_friction", "stribeck", "drag_asymmetry", "thrust_asymmetry", "force_offset",
           "voltage_deadband", "brush_drop", "current_offset", "input_delay", "thrust_lag", "cogging")
PARAMS = ("R", "L", "k", "J", "B", "c_tau", "c_f")
KIND_P = (("clean", 0.15), ("param", 0.20), ("effect", 0.40), ("two_effects", 0.15), ("effect_param", 0.10))
MAX_STEPS = 1_500_000  # integrator substeps per log (CPU guard, ~10 s)


@dataclass
class Case:
    """One drawn case.

    Attributes:
        seed: the seed. kind: case kind (clean, param, effect, two_effects, effect_param).
        truth: true rig. nominal: the parameter file handed to the checker (SI).
        cfg: logger. exc: excitation. labels: the expected verdict. h_max: integrator substep bound [s].
        meta: every other drawn quantity (scales, magnitudes, SNRs, notes).
    """

    seed: int
    kind: str
    truth: RigTruth
    nominal: dict
    cfg: LoggerConfig
    exc: Excitation
    labels: list[str]
    h_max: float
    theta0: float
    meta: dict = field(default_factory=dict)


def _logu(rng: np.random.Generator, lo: float, hi: float) -> float:
    """Log-uniform draw in [lo, hi]."""
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def draw_motor(rng: np.random.Generator) -> tuple[RigTruth, dict]:
    """Draw a consistent motor + propeller (no effects); returns it and its scales.

    Scales: w_nl = V/k [rad/s], w_top (steady speed at full supply) [rad/s], T_stall = k V/R [N m],
    T_top (motor torque at top speed) [N m], I_stall [A], F_top [N], tau_m = J R/k^2 [s],
    tau_eff = J / (k^2/R + B + 2 c_tau w_top) [s], B_share (viscous share of the top-speed torque).
    """
    for _ in range(10_000):
        Vs = _logu(rng, 3.7, 48.0)
        P_max = _logu(rng, 10.0, 1500.0)  # V^2 / (4 R): peak mechanical power of the bare motor [W]
        R = Vs * Vs / (4.0 * P_max)
        w_nl = _logu(rng, 150.0, 3000.0)
        k = Vs / w_nl
        LR = _logu(rng, 5e-5, 5e-3)
        tau_m = _logu(rng, 5e-3, 1.0)
        J = tau_m * k * k / R
        if not (0.05 <= R <= 10.0 and 0.002 <= k <= 0.1 and 1e-7 <= J <= 1e-3):
            continue
        T_stall = k * Vs / R
        rho = rng.uniform(0.2, 0.8)
        c_tau = rho * T_stall / w_nl**2
        sB = rng.uniform(0.01, 0.10)
        p = RigTruth(V_supply=Vs, R=R, L=LR * R, k=k, J=J, B=0.0, c_tau=c_tau, c_tau_rev=c_tau, c_f=1.0,
                     c_f_rev=1.0)
        for _ in range(30):  # B w_top = sB * T_top at the top speed
            w_top = no_load_speed(p, Vs)
            p.B = sB * k * (Vs - k * w_top) / R / w_top
        w_top = no_load_speed(p, Vs)
        T_top = k * (Vs - k * w_top) / R
        P_top = T_top * w_top
        F_top = float(np.clip(_logu(rng, 0.02, 0.12) * P_top, 0.05, 50.0))
        p.c_f = p.c_f_rev = F_top / w_top**2
        tau_eff = J / (k * k / R + p.B + 2 * c_tau * w_top)
        if not (0.003 <= tau_eff <= 1.0 and P_top >= 1.0):
            continue
        sc = dict(w_nl=w_nl, w_top=w_top, T_stall=T_stall, T_top=T_top, I_stall=Vs / R, I_top=T_top / k,
                  F_top=F_top, P_top=P_top, P_max=P_max, tau_m=tau_m, tau_eff=tau_eff, B_share=sB,
                  drag_share_of_stall_at_w_nl=rho, L_over_R=LR)
        return p, sc
    raise RuntimeError("no consistent motor")


def draw_logger(rng: np.random.Generator, sc: dict, rate: float, n: int) -> LoggerConfig:
    """Draw the sensors and logging settings for scales ``sc`` at rate [Hz] with n rows."""
    enc = rng.random() < 0.55
    columns = "omega" if not enc else ("theta" if rng.random() < 0.35 else "both")
    cpr = int(rng.choice([256, 500, 512, 1000, 1024, 2048, 4096]))
    # difference window keeping the speed quantum at most ~2 % of top speed (up to 16 rows)
    win = int(np.clip(math.ceil(2 * math.pi * rate / (cpr * 0.02 * sc["w_top"])), 1, 16))
    return LoggerConfig(
        rate=rate, n=n, skew=int(rng.integers(0, 3)),
        jitter=float(rng.uniform(0.005, 0.04)) if rng.random() < 0.25 else 0.0,
        speed_sensor="encoder" if enc else "tacho", columns=columns,
        tach_noise=rng.uniform(0.002, 0.01) * sc["w_top"],
        tach_filter=0.0 if rng.random() < 0.3 else rng.uniform(0.2, 3.0),
        cpr=cpr, diff_window=win,
        cur_noise=rng.uniform(0.002, 0.01) * sc["I_stall"],
        cur_filter=0.0 if rng.random() < 0.4 else rng.uniform(0.2, 2.0),
        cur_bits=int(rng.integers(10, 17)), cur_range=rng.uniform(1.1, 1.5) * sc["I_stall"], cur_offset=0.0,
        thr_noise=rng.uniform(0.003, 0.015) * sc["F_top"], thr_bits=int(rng.choice([16, 20, 24])),
        thr_range=rng.uniform(1.5, 3.0) * sc["F_top"], thr_offset=0.0,
        thr_filter=0.0 if rng.random() < 0.6 else rng.uniform(0.2, 1.0),
        pi_kp=0.0, pi_ki=0.0)


def apply_effect(rng: np.random.Generator, name: str, p: RigTruth, cfg: LoggerConfig, sc: dict,
                 labels: list[str], eff: dict) -> None:
    """Put the effect ``name`` into the rig/logger; append its label(s) and record its magnitude in ``eff``."""
    k_sig_i = p.k * cfg.cur_noise  # torque equivalent of the current noise [N m]
    with_c = name == "stribeck" and "coulomb_friction" not in labels and rng.random() < 0.5
    if name == "coulomb_friction" or with_c:
        p.tau_coulomb = max(rng.uniform(0.05, 0.2) * sc["T_top"], 3 * k_sig_i)
        labels.append("coulomb_friction")
        eff["coulomb_friction"] = dict(tau_c_Nm=p.tau_coulomb, of_T_top=p.tau_coulomb / sc["T_top"],
                                       current_equiv_over_noise=p.tau_coulomb / k_sig_i, with_stribeck=with_c,
                                       formula="tau_c tanh(w / w_0)")
        if name == "coulomb_friction":
            return
    if name == "stribeck":
        p.tau_stribeck = max(rng.uniform(0.05, 0.2) * sc["T_top"], 3 * k_sig_i)
        p.w_stribeck = rng.uniform(0.02, 0.06) * sc["w_top"]
        labels.append("stribeck")
        eff["stribeck"] = dict(tau_s_excess_Nm=p.tau_stribeck, w_s_rad_s=p.w_stribeck,
                               w_s_of_top=p.w_stribeck / sc["w_top"], of_T_top=p.tau_stribeck / sc["T_top"],
                               current_equiv_over_noise=p.tau_stribeck / k_sig_i,
                               formula="(tau_c + tau_s exp(-(w/w_s)^2)) tanh(w/w_0)")
    elif name in ("drag_asymmetry", "thrust_asymmetry"):
        d = rng.uniform(0.15, 0.6)
        r = 1.0 + d if rng.random() < 0.5 else 1.0 - d
        if name == "drag_asymmetry":
            p.c_tau_rev = p.c_tau * r
        else:
            p.c_f_rev = p.c_f * r
        labels.append(name)
        eff[name] = dict(reverse_over_forward=r)
    elif name == "force_offset":
        cfg.thr_offset = float(rng.choice([-1, 1])) * max(rng.uniform(0.03, 0.12) * sc["F_top"], 5 * cfg.thr_noise)
        labels.append(name)
        eff[name] = dict(offset_N=cfg.thr_offset, of_F_top=cfg.thr_offset / sc["F_top"],
                         over_noise=abs(cfg.thr_offset) / cfg.thr_noise)
    elif name == "voltage_deadband":
        p.deadband = rng.uniform(0.04, 0.12) * p.V_supply
        p.deadband_mode = "zero" if rng.random() < 0.5 else "shift"
        labels.append(name)
        eff[name] = dict(deadband_V=p.deadband, of_supply=p.deadband / p.V_supply, mode=p.deadband_mode)
    elif name == "brush_drop":
        p.V_brush = float(np.clip(rng.uniform(0.025, 0.08) * p.V_supply, 0.15, 2.0))
        p.i_brush = 0.02 * sc["I_stall"]
        labels.append(name)
        eff[name] = dict(V_b=p.V_brush, i_smooth_A=p.i_brush, of_supply=p.V_brush / p.V_supply,
                         current_equiv_over_noise=p.V_brush / p.R / cfg.cur_noise,
                         formula="V_b tanh(i / i_b)")
    elif name == "current_offset":
        cfg.cur_offset = float(rng.choice([-1, 1])) * max(rng.uniform(0.015, 0.05) * sc["I_stall"],
                                                          4 * cfg.cur_noise)
        labels.append(name)
        eff[name] = dict(offset_A=cfg.cur_offset, of_I_top=cfg.cur_offset / sc["I_top"],
                         over_noise=abs(cfg.cur_offset) / cfg.cur_noise)
    elif name == "input_delay":
        if cfg.rate > 2000 and rng.random() < 0.5:
            p.delay = max(rng.uniform(1e-3, 5e-3), 3.0 / cfg.rate)
        else:
            p.delay = (int(rng.integers(3, 21)) + (rng.uniform(0, 1) if rng.random() < 0.3 else 0.0)) / cfg.rate
        labels.append(name)
        eff[name] = dict(delay_s=p.delay, delay_samples=p.delay * cfg.rate, over_skew=p.delay * cfg.rate - cfg.skew,
                         over_L_over_R=p.delay / (p.L / p.R), over_tau_eff=p.delay / sc["tau_eff"])
    elif name == "thrust_lag":
        p.thrust_tau = rng.uniform(0.01, 0.2)
        labels.append(name)
        eff[name] = dict(tau_s=p.thrust_tau, samples=p.thrust_tau * cfg.rate, over_tau_eff=p.thrust_tau / sc["tau_eff"])
    elif name == "cogging":
        p.cog_N = int(rng.integers(2, 25)) if rng.random() < 0.7 else int(rng.integers(1, 65))
        p.cog_amp = max(rng.uniform(0.015, 0.05) * sc["T_stall"], 3 * k_sig_i)
        p.cog_a2 = 0.0 if rng.random() < 0.5 else rng.uniform(0.1, 0.5)
        p.cog_p1, p.cog_p2 = rng.uniform(0, 2 * math.pi, 2)
        labels.append(name)
        eff[name] = dict(N=p.cog_N, amp_Nm=p.cog_amp, of_T_stall=p.cog_amp / sc["T_stall"], a2=p.cog_a2,
                         current_equiv_over_noise=p.cog_amp / k_sig_i, theta_logged=cfg.columns != "omega",
                         freq_at_top_Hz=p.cog_N * sc["w_top"] / (2 * math.pi),
                         formula="A (sin(N th + p1) + a2 sin(2 N th + p2))")
    else:
        raise ValueError(name)


def draw_case(seed: int) -> Case:
    """Draw the whole case of ``seed`` (no simulation)."""
    rng = np.random.default_rng(seed)
    p, sc = draw_motor(rng)
    kinds, probs = [k for k, _ in KIND_P], [q for _, q in KIND_P]
    kind = str(rng.choice(kinds, p=np.asarray(probs)))
    rate = float(rng.choice([500.0, 1000.0])) if rng.random() < 0.5 else round(_logu(rng, 50.0, 10_000.0), 1)
    length = rng.uniform(2.0, 20.0)
    p.w_smooth = 0.003 * sc["w_top"]
    # CPU guard: shorten the log if the integrator would need too many substeps
    h_max = stiffness_step(p, sc["w_top"])
    steps_per_s = max(rate, 1.0 / h_max)
    length_drawn = length
    length = min(length, MAX_STEPS / steps_per_s, 200_000 / rate)
    n = max(int(length * rate), 20)
    cfg = draw_logger(rng, sc, rate, n)
    labels: list[str] = []
    eff: dict = {}
    n_eff = {"clean": 0, "param": 0, "effect": 1, "two_effects": 2, "effect_param": 1}[kind]
    for name in rng.choice(EFFECTS, n_eff, replace=False):
        if name in labels:  # coulomb already added by a stribeck-with-Coulomb draw
            continue
        apply_effect(rng, str(name), p, cfg, sc, labels, eff)
    h_max = stiffness_step(p, sc["w_top"])  # friction may tighten it
    nominal = {"J": p.J, "B": p.B, "c_tau": p.c_tau, "c_f": p.c_f, "k_t": p.k, "k_e": p.k, "R": p.R, "L": p.L}
    calib = {key: float(rng.uniform(-0.03, 0.03)) for key in ("J", "B", "c_tau", "c_f", "k", "R", "L")}
    wrong = None
    if kind in ("param", "effect_param"):
        ok = [q for q in PARAMS if not (q == "B" and sc["B_share"] < 0.05)
              and not (q == "L" and sc["L_over_R"] * rate < 2.0)]
        wrong = str(rng.choice(ok))
        d = rng.uniform(0.15, 0.5)
        calib[wrong] = d if rng.random() < 0.5 else -d
        labels.append(f"param:{wrong}")
    for key, e in calib.items():
        if key == "k":
            nominal["k_t"] *= 1.0 + e
            nominal["k_e"] *= 1.0 + e
        else:
            nominal[key] *= 1.0 + e
    # excitation
    reverses = bool(rng.random() < 0.8)
    tau_x = sc["tau_eff"]
    exc = make_excitation(rng, n, 1.0 / rate, p.V_supply, sc["w_top"], tau_x, reverses)
    damp_mid = p.k**2 / p.R + p.B + p.c_tau * sc["w_top"]
    Kdc, tau_pi = (p.k / p.R) / damp_mid, p.J / damp_mid
    wc = min(rng.uniform(2.0, 6.0) / tau_pi, 2 * math.pi * rate / 30.0)
    cfg.pi_kp = wc * tau_pi / Kdc
    cfg.pi_ki = cfg.pi_kp / tau_pi
    meta = dict(scales=sc, effects=eff, calibration_rel_errors=calib, wrong_param=wrong,
                rate_Hz=rate, n_rows=n, length_s=n / rate, length_drawn_s=length_drawn,
                L_over_R_samples=sc["L_over_R"] * rate, tau_eff_samples=sc["tau_eff"] * rate,
                pi=dict(wc_rad_s=wc, kp=cfg.pi_kp, ki=cfg.pi_ki), h_max_s=h_max,
                w_smooth_rad_s=p.w_smooth)
    return Case(seed=seed, kind=kind, truth=p, nominal=nominal, cfg=cfg, exc=exc, labels=labels,
                h_max=min(h_max, 1.0 / rate), theta0=float(rng.uniform(0, 2 * math.pi)), meta=meta)
