"""Which of the blind rig's labels its logs can show: each label's footprint in the logged channels, in noise levels.

The blind rig (``bench/blindrig``) draws effects and wrong constants by size alone (Stribeck friction at 5-20 % of the
top torque, at least three current-noise equivalents; a constant 15-50 % off), without asking whether the log shows
them; the proving ground keeps only draws whose free run differs by :data:`VISIBLE` noise levels. This audit asks the
blind rig the proving ground's question, with the blind rig's own integrator and loggers: the logged command of case
``seed`` is replayed open-loop on the true rig and on the rig without the label (an effect removed; a wrong constant
moved to the nearest value calibration reaches, 10 % from nominal), with the same noise draws, and the measured
channels' RMS difference is taken in each channel's noise level (current and thrust: the sensor's noise or its
quantisation step; speed: the tachometer's noise, or an encoder's quantisation over its differencing window).

    python bench/blind_audit.py --records RUN.json [--procs 2]

``RUN.json``: ``bench/blind_check.py --json``'s records (the verdicts). Prints, per label, how many were drawn, how
many show (footprint >= VISIBLE) and the recall on those; and the exact-verdict rate with the labels that do not show
optional (a verdict is right with or without them). No calibration of the other constants or the timing is fitted
(the proving ground's audit does: :mod:`tests.proving_ground.calibration`), so a label counted as showing here may
still be absorbed by them. ~2 simulations a label.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from blindrig.draw import Case, draw_case
from blindrig.excite import Excitation
from blindrig.logger import LoggerConfig, run_log
from blindrig.rig import RigTruth

#: a footprint this many noise levels or more shows (the proving ground's rule, ``tests.proving_ground.cases``)
VISIBLE = 1.5
#: the relative error of a constant calibration takes up without naming it (the check's default tolerance)
TOLERANCE = 0.1
#: the constant each ``param:`` label moves: the rig's field(s) and the nominal file's key
FIELDS = {"R": (("R",), "R"), "L": (("L",), "L"), "k": (("k",), "k_t"), "J": (("J",), "J"), "B": (("B",), "B"),
          "c_tau": (("c_tau", "c_tau_rev"), "c_tau"), "c_f": (("c_f", "c_f_rev"), "c_f")}


def _without(case: Case, label: str) -> tuple[RigTruth, LoggerConfig]:
    """(rig, logger) of ``case`` without ``label``."""
    p, cfg = dataclasses.replace(case.truth), dataclasses.replace(case.cfg)
    if label.startswith("param:"):
        fields, key = FIELDS[label.removeprefix("param:")]
        nominal = case.nominal[key]
        true = getattr(p, fields[0])
        near = nominal * (1.0 + math.copysign(TOLERANCE, true / nominal - 1.0))  # calibration's reach
        reached = near if abs(true - nominal) > abs(near - nominal) else true
        for f in fields:
            setattr(p, f, getattr(p, f) * reached / true)
        return p, cfg
    off = {"coulomb_friction": ("tau_coulomb", 0.0), "stribeck": ("tau_stribeck", 0.0),
           "drag_asymmetry": ("c_tau_rev", p.c_tau), "thrust_asymmetry": ("c_f_rev", p.c_f),
           "voltage_deadband": ("deadband", 0.0), "brush_drop": ("V_brush", 0.0), "input_delay": ("delay", 0.0),
           "thrust_lag": ("thrust_tau", 0.0), "cogging": ("cog_amp", 0.0)}
    if label in off:
        setattr(p, *off[label])
    else:  # the loggers' offsets
        setattr(cfg, {"force_offset": "thr_offset", "current_offset": "cur_offset"}[label], 0.0)
    return p, cfg


def _noise(cfg: LoggerConfig) -> np.ndarray:
    """(3,) noise levels of the logged speed [rad/s], current [A], thrust [N] (module doc)."""
    q_i = 2.0 * cfg.cur_range / 2**cfg.cur_bits / math.sqrt(12.0)
    q_f = 2.0 * cfg.thr_range / 2**cfg.thr_bits / math.sqrt(12.0)
    if cfg.speed_sensor == "tacho":
        s_w = cfg.tach_noise
    else:  # two quantised angles over the window
        s_w = 2.0 * math.pi / cfg.cpr * cfg.rate / cfg.diff_window / math.sqrt(6.0)
    return np.array([s_w, max(cfg.cur_noise, q_i), max(cfg.thr_noise, q_f)])


def footprints(seed: int) -> dict[str, float]:
    """Per label of blind case ``seed``: its footprint, the largest channel RMS difference in noise levels."""
    case = draw_case(seed)
    base = run_log(case.truth, case.cfg, case.exc, case.h_max, np.random.default_rng([seed, 7]), case.theta0)
    n = case.cfg.n
    replay = Excitation("replay", ["replay"], np.zeros(n, dtype=bool), base["voltage"], np.zeros(n), False)
    sig = _noise(case.cfg)

    def logged(p: RigTruth, cfg: LoggerConfig) -> np.ndarray:  # (3, n) speed, current, thrust as logged
        c = run_log(p, cfg, replay, case.h_max, np.random.default_rng([seed, 7]), case.theta0)
        return np.vstack([c["omega"], c["current"], c["thrust"]])

    true = logged(case.truth, case.cfg)  # (the rig as drawn: once for all its labels)
    return {label: float(np.max(np.sqrt(np.mean((true - logged(*_without(case, label))) ** 2, axis=1)) / sig))
            for label in case.labels}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", required=True, help="bench/blind_check.py --json output")
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--json", default=None, help="write each label's footprint here")
    args = ap.parse_args(argv)
    recs = [r for r in json.loads(Path(args.records).read_text()) if r.get("verdict") is not None]
    with ProcessPoolExecutor(args.procs) as pool:
        prints = dict(zip((r["seed"] for r in recs), pool.map(footprints, [r["seed"] for r in recs]), strict=True))
    drawn: Counter[str] = Counter()
    shows: Counter[str] = Counter()
    found_shown: Counter[str] = Counter()
    found_hidden: Counter[str] = Counter()
    exact = exact_opt = 0
    for r in recs:
        fp, verdict, truth = prints[r["seed"]], set(r["verdict"]), set(r["truth"])
        shown = {label for label in truth if fp[label] >= VISIBLE}
        for label in truth:
            drawn[label] += 1
            if label in shown:
                shows[label] += 1
                found_shown[label] += label in verdict
            else:
                found_hidden[label] += label in verdict
        exact += verdict == truth
        exact_opt += shown <= verdict <= truth
        hidden = sorted(f"{label} {fp[label]:.2f}" for label in truth - shown)
        if verdict != truth:
            print(f"  seed {r['seed']:4d} truth={sorted(truth)} verdict={sorted(verdict)}"
                  + (f"  not shown: {hidden}" if hidden else ""))
    n = len(recs)
    print(f"\n{n} blind logs: exactly right {exact}/{n}; with the labels under {VISIBLE} noise levels optional "
          f"{exact_opt}/{n}")
    print(f"{'label':20s}{'drawn':>7s}{'shows':>7s}{'found/shows':>13s}{'recall':>8s}{'found/hidden':>14s}")
    for label in sorted(drawn):
        s = shows[label]
        rec = f"{100 * found_shown[label] / s:.0f} %" if s else "-"
        print(f"{label:20s}{drawn[label]:>7d}{s:>7d}{found_shown[label]:>8d}/{s:<4d}{rec:>8s}"
              f"{found_hidden[label]:>8d}/{drawn[label] - s:<4d}")
    if args.json:
        Path(args.json).write_text(json.dumps(prints, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
