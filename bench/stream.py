"""Streaming shaper benchmark (issue 18): approaches compared, the price of causality, speed of the step.

    PYTHONPATH=$PWD python bench/stream.py            # everything (the offline optimiser takes a while)
    PYTHONPATH=$PWD python bench/stream.py --quick    # skip the offline optimiser
    PYTHONPATH=$PWD python bench/stream.py --speed    # only the Python and C step timings

Profile: the seed paper's Section IV-B impedance reference (M_I = 0.65, B_I = 3.5, K_I = 5.0), 10 s at
1 kHz, scaled to +-0.4 N, 19 linear crossings; paper-rig motor, |i| <= 1 A, |V| <= 12 V, look-ahead 0.1 s.
Every approach is verified the same way: peaks of the returned i and V; the plant (ocp.simulate.open_loop, Radau)
driven by the returned voltage vs the returned thrust; local exponent at each reversal (log-log fit on
+-10 ms); tracking RMS against the desired thrust it tracks (delayed by the look-ahead for the stream).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

from ocp.gallery.interaction import InteractionSetup, Law, interaction_reference
from ocp.model.params import MotorParams, preset
from ocp.model.plant import DCMotorPlant
from ocp.simulate.open_loop import simulate
from ocp.stream import StreamShaper, shape_profile, stream_options
from ocp.stream.blend import blend_profile
from ocp.stream.codegen import build, compiler

AMPLITUDE, CURRENT, VOLTAGE, DELAY = 0.4, 1.0, 12.0, 0.1


def profile() -> tuple[np.ndarray, np.ndarray]:
    ref = interaction_reference(Law.IMPEDANCE, InteractionSetup(duration=10.0), rate=1000.0)
    return ref.t, ref.x2d / np.max(np.abs(ref.x2d)) * AMPLITUDE


def exponents(t: np.ndarray, f: np.ndarray, half: float = 0.010) -> list[float]:
    """Local exponent g at each sign change of f (log-log fit on |t - t_s| <= half, t_s refined)."""
    dt = t[1] - t[0]
    out = []
    for j in np.flatnonzero(f[:-1] * f[1:] < 0):
        if not half < t[j] < t[-1] - half:
            continue

        def fit(ts: float) -> tuple[float, float]:
            s = np.abs(t - ts)
            m = (s > 0.5 * dt) & (s <= half)
            x, y = np.log(s[m]), np.log(np.abs(f[m]))
            g, c = np.polyfit(x, y, 1)
            return float(np.sum((y - g * x - c) ** 2)), float(g)

        res = minimize_scalar(lambda ts: fit(ts)[0], bounds=(t[j], t[j + 1]), method="bounded")
        out.append(fit(float(res.x))[1])
    return out


def verify(p: MotorParams, name: str, t: np.ndarray, desired: np.ndarray, thrust: np.ndarray, current: np.ndarray,
           voltage: np.ndarray, us: float) -> dict[str, object]:
    sim = simulate(DCMotorPlant(p), t, voltage, (0.0, 0.0), rtol=1e-6, atol=1e-7)
    g = exponents(t, thrust)
    return {"approach": name, "track_%A": 100 * np.sqrt(np.mean((thrust - desired) ** 2)) / AMPLITUDE,
            "max|i| A": float(np.max(np.abs(current))), "max|V| V": float(np.max(np.abs(voltage))),
            "limits": bool(np.max(np.abs(current)) <= CURRENT and np.max(np.abs(voltage)) <= VOLTAGE),
            "sim_%A": 100 * np.sqrt(np.mean((sim.thrust - thrust) ** 2)) / AMPLITUDE,
            "g": f"{min(g):.2f}..{max(g):.2f} ({len(g)})" if g else "-", "us/sample": us}


def streams(p: MotorParams, t: np.ndarray, f: np.ndarray) -> list[dict[str, object]]:
    rows = []
    for reg in ("bounded", "continuous-voltage"):
        for bw in (10.0, 20.0, 40.0):
            o = stream_options(current=CURRENT, voltage=VOLTAGE, regularity=reg, delay=DELAY, bandwidth=bw)
            t0 = time.perf_counter()
            tr = shape_profile(p, o, t, f)
            us = (time.perf_counter() - t0) / t.size * 1e6
            rows.append(verify(p, f"governed preview, {reg}, {bw:g} Hz", t, tr.desired, tr.thrust, tr.current,
                               tr.voltage, us))
        o = stream_options(current=CURRENT, voltage=VOLTAGE, regularity=reg, delay=DELAY)
        t0 = time.perf_counter()
        b = blend_profile(p, o, t, f)
        us = (time.perf_counter() - t0) / t.size * 1e6
        rows.append(verify(p, f"analytic blend p=5, {reg}", t, b.desired, b.thrust, b.current, b.voltage, us))
    return rows


def offline(p: MotorParams, t: np.ndarray, f: np.ndarray) -> list[dict[str, object]]:
    """The offline optimiser on the whole profile (knows the future, no delay, no retiming)."""
    from ocp.optimize.mission import mission_from_mapping
    from ocp.optimize.solve import optimize

    rows = []
    for reg in ("bounded", "continuous-voltage"):
        m = mission_from_mapping({"name": "impedance-10s", "params": "paper-rig", "regularity": reg,
                                  "limits": {"voltage": VOLTAGE, "current": CURRENT},
                                  "retiming": {"min_stretch": 1.0, "max_stretch": 1.0},
                                  "collocation": {"intervals": 2000}, "time_limit_s": 600.0,
                                  "profile": {"t": t.tolist(), "thrust": f.tolist()}})
        t0 = time.perf_counter()
        r = optimize(m)
        el = time.perf_counter() - t0
        a, v = r.arrays, r.verification
        g = [c["exponent"] for c in r.crossings if c.get("sign_change", True)]
        # its own verification: it starts at the equilibrium of the first sample (the stream starts at rest)
        # and commands a piecewise-constant voltage, which a linear interpolation would misrepresent
        rows.append({"approach": f"offline optimiser ({r.source}), {reg}",
                     "track_%A": 100 * float(v["tracking_rms_error"]) / AMPLITUDE,
                     "max|i| A": float(np.max(np.abs(a["current"]))), "max|V| V": float(np.max(np.abs(a["voltage"]))),
                     "limits": bool(r.path_ok), "sim_%A": 100 * float(v["thrust_rms_error"]) / AMPLITUDE,
                     "g": f"{min(g):.2f}..{max(g):.2f} ({len(g)})" if g else "-", "us/sample": el / t.size * 1e6})
    return rows


def python_speed(p: MotorParams, t: np.ndarray, f: np.ndarray) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    for reg in ("bounded", "continuous-voltage"):
        sh = StreamShaper(p, stream_options(current=CURRENT, voltage=VOLTAGE, regularity=reg, delay=DELAY))
        per = np.empty(t.size)
        clock = time.perf_counter
        t_all = clock()
        for k, (a, b) in enumerate(zip(t.tolist(), f.tolist(), strict=True)):
            t0 = clock()
            sh.push(a, b)
            per[k] = clock() - t0
        total = clock() - t_all
        out[reg] = {"samples/s": t.size / total, "mean us": 1e6 * float(per.mean()),
                    "p99 us": 1e6 * float(np.percentile(per, 99)), "p99.9 us": 1e6 * float(np.percentile(per, 99.9)),
                    "max us": 1e6 * float(per.max())}
    return out


def c_speed(p: MotorParams, f: np.ndarray) -> dict[str, str]:
    if compiler() is None:
        return {"C step": "no C compiler"}
    out = {}
    for reg in ("bounded", "continuous-voltage"):
        o = stream_options(current=CURRENT, voltage=VOLTAGE, regularity=reg, delay=DELAY)
        with tempfile.TemporaryDirectory() as d:
            exe = build(p, o, Path(d))
            text = "\n".join(repr(float(x)) for x in np.tile(f, 5))
            runs = [subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True).stderr.strip()
                    for _ in range(3)]
        out[reg] = " | ".join(runs)
    return out


def table(rows: list[dict[str, object]]) -> None:
    cols = list(rows[0])
    print(" | ".join(cols))
    for r in rows:
        print(" | ".join(f"{r[c]:.3g}" if isinstance(r[c], float) else str(r[c]) for c in cols))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the offline optimiser")
    ap.add_argument("--speed", action="store_true", help="only the Python and C step timings")
    args = ap.parse_args()
    p = preset("paper-rig")
    t, f = profile()
    if not args.speed:
        rows = streams(p, t, f)
        if not args.quick:
            rows += offline(p, t, f)
        print("## approaches on the 10 s impedance reference (1 kHz, |i| <= 1 A, |V| <= 12 V, look-ahead 0.1 s)")
        table(rows)
    print("\n## Python API, one push() per sample (default bandwidth 20 Hz)")
    for reg, s in python_speed(p, t, f).items():
        print(reg, " ".join(f"{k}={v:.4g}" for k, v in s.items()))
    print("\n## generated C step (-O2), 50,000 samples, three runs")
    for reg, runs in c_speed(p, f).items():
        print(reg, runs)
    print(f"\n(python {sys.version.split()[0]}; single runs: the worst cases include the OS scheduling of a shared "
          "machine)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
