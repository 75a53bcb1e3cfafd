"""Simulate a drawn case and write ``case-<seed>.csv``, ``.params.json`` and ``.truth.json``."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np

from .draw import Case, draw_case
from .logger import run_log


def _visibility(case: Case, cols: dict[str, np.ndarray]) -> dict:
    """Post-hoc notes on whether each label could show in this log (heuristics, recorded not acted on)."""
    p, sc = case.truth, case.meta["scales"]
    w = cols["true_w"]
    wt = sc["w_top"]
    v = cols["voltage"]
    out: dict = dict(
        true_w_min_over_top=float(w.min() / wt), true_w_max_over_top=float(w.max() / wt),
        reverses_actual=bool(w.min() < -0.1 * wt and w.max() > 0.1 * wt),
        frac_rows_reverse_above_20pct=float(np.mean(w < -0.2 * wt)),
        frac_rows_forward_above_20pct=float(np.mean(w > 0.2 * wt)),
        frac_rows_near_zero_5pct=float(np.mean(np.abs(w) < 0.05 * wt)),
        zero_crossings=int(np.sum(np.diff(np.sign(w[np.abs(w) > 0.01 * wt])) != 0)),
        max_abs_true_i_over_stall=float(np.abs(cols["true_i"]).max() / sc["I_stall"]),
        cmd_over_supply_max=float(np.abs(v).max() / p.V_supply),
    )
    notes = []
    lab = case.labels
    cfg = case.cfg
    sat = float(np.mean(np.abs(cols["current"]) >= cfg.cur_range * (1.0 - 4.0 / 2**cfg.cur_bits)))
    out["frac_rows_current_adc_saturated"] = sat
    if sat > 0.001:
        notes.append(f"current ADC (+-{cfg.cur_range:.3g} A) saturates in {sat:.1%} of rows (reversal current)")
    tau_rows = case.meta["tau_eff_samples"]
    filt = cfg.tach_filter if cfg.speed_sensor == "tacho" else 0.5 * cfg.diff_window
    out["speed_sensor_lag_rows"] = filt
    out["current_filter_rows"] = cfg.cur_filter
    if filt >= 0.3 * tau_rows or cfg.cur_filter >= 0.3 * tau_rows:
        notes.append(f"sensor lag (speed {filt:.2g}, current {cfg.cur_filter:.2g} rows) comparable to "
                     f"tau_eff ({tau_rows:.2g} rows)")
    if ("drag_asymmetry" in lab or "thrust_asymmetry" in lab) and out["reverses_actual"] and \
            min(out["frac_rows_reverse_above_20pct"], out["frac_rows_forward_above_20pct"]) < 0.02:
        notes.append("asymmetry: one direction hardly exceeds 20 % of top speed: weak")
    if ("drag_asymmetry" in lab or "thrust_asymmetry" in lab) and not out["reverses_actual"]:
        notes.append("asymmetry drawn but rotor never runs in reverse: INVISIBLE")
    if "voltage_deadband" in lab:
        inside = float(np.mean(np.abs(v) < p.deadband))
        out["frac_cmd_inside_deadband"] = inside
        if p.deadband_mode == "zero" and inside < 0.005:
            notes.append("zero-mode dead band never entered: INVISIBLE")
    if "stribeck" in lab:
        out["frac_rows_below_2ws"] = float(np.mean(np.abs(w) < 2 * p.w_stribeck))
        if out["frac_rows_below_2ws"] < 0.002:
            notes.append("Stribeck speed range hardly visited: weak")
    if "cogging" in lab:
        moving = np.abs(w) > 0.01 * wt
        w_med = float(np.median(np.abs(w[moving]))) if moving.any() else 0.0
        f_med = p.cog_N * w_med / (2 * math.pi)
        out["cogging_freq_at_median_speed_Hz"] = f_med
        out["cogging_freq_over_nyquist"] = f_med / (cfg.rate / 2)
        out["cogging_speed_ripple_at_median_speed"] = p.cog_amp / (p.J * p.cog_N * w_med) if w_med > 0 else None
        out["frac_rows_cogging_below_nyquist"] = float(np.mean(p.cog_N * np.abs(w) / (2 * math.pi) < cfg.rate / 2))
        if case.cfg.columns == "omega":
            notes.append("cogging with no theta column (omega only)")
        if f_med > cfg.rate / 2:
            notes.append(f"cogging frequency at the median speed is {f_med / (cfg.rate / 2):.3g} x Nyquist")
    if "param:L" in lab:
        out["L_over_R_samples"] = case.meta["L_over_R_samples"]
    if "param:J" in lab:
        acc = np.gradient(w, cols["t"])
        tq = p.k * cols["true_i"]
        out["J_acc_rms_over_torque_rms"] = float(np.sqrt(np.mean((p.J * acc) ** 2)) / np.sqrt(np.mean(tq**2)))
    if "thrust_lag" in lab:
        F = cols["true_F"]
        Fq = np.where(w >= 0, p.c_f, p.c_f_rev) * w * np.abs(w)
        out["thrust_lag_rms_err_over_noise"] = float(np.sqrt(np.mean((F - Fq) ** 2)) / case.cfg.thr_noise)
    if "input_delay" in lab:
        out["delay_samples"] = p.delay * case.cfg.rate
    out["notes"] = notes
    return out


def _jsonable(x: object) -> object:
    """Convert numpy scalars/arrays and tuples inside x to JSON types."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def paths(seed: int, outdir: Path) -> tuple[Path, Path, Path]:
    """(csv, params, truth) paths of a seed in outdir."""
    return (outdir / f"case-{seed}.csv", outdir / f"case-{seed}.params.json", outdir / f"case-{seed}.truth.json")


def generate(seed: int, outdir: Path | str, regen: bool = False) -> tuple[Path, Path, Path]:
    """Draw, simulate and write the case of ``seed`` into ``outdir`` (kept if present unless ``regen``)."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    csv, par, tru = paths(seed, outdir)
    if not regen and csv.exists() and par.exists() and tru.exists():
        return csv, par, tru
    case = draw_case(seed)
    t0 = time.process_time()
    cols = run_log(case.truth, case.cfg, case.exc, case.h_max, np.random.default_rng([seed, 7]), case.theta0)
    cpu = time.process_time() - t0
    names = ["t", "voltage", "current"]
    if case.cfg.columns in ("omega", "both"):
        names.append("omega")
    if case.cfg.columns in ("theta", "both"):
        names.append("theta")
    names.append("thrust")
    data = np.column_stack([cols[c] for c in names])
    fmt = ["%.9g"] + ["%.7g"] * (len(names) - 1)
    tmp = csv.with_suffix(".csv.tmp")
    np.savetxt(tmp, data, delimiter=",", header=",".join(names), comments="", fmt=fmt)
    tmp.replace(csv)
    par.write_text(json.dumps(case.nominal, indent=1))
    truth = dict(seed=seed, kind=case.kind, labels=case.labels, columns=names,
                 rig=case.truth.to_dict(), nominal=case.nominal, logger=case.cfg.to_dict(),
                 excitation=dict(kind=case.exc.kind, parts=case.exc.parts, reverses=case.exc.reverses,
                                 closed_fraction=float(case.exc.closed.mean()), info=case.exc.info),
                 reverses=case.exc.reverses, rate_Hz=case.cfg.rate, skew=case.cfg.skew,
                 L_over_R_samples=case.meta["L_over_R_samples"], meta=case.meta,
                 visibility=_visibility(case, cols), sim=dict(cpu_s=cpu, substeps=int(cols["n_steps"][0])))
    tru.write_text(json.dumps(_jsonable(truth), indent=1))
    return csv, par, tru
