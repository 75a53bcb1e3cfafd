"""Whether the diagnosis reports a gain on the command as the rival of what it names (:mod:`ocp.identify.gain`):
proving-ground rigs (:func:`tests.proving_ground.experiment.draw`, no hidden effect, exact nominal constants) under
random voltage steps of four levels and of two (:func:`tests.proving_ground.experiment.voltage_steps`), their logged
voltage scaled after the fact by ``s`` (the log says ``s`` x what the motor got: a common error ``s - 1`` of R, L,
k, J, B and c_tau), ``|s - 1|`` drawn in 15-50 % either way; the controls: the same logs unscaled but one of R, k, J,
B off by 20-50 % either way in the nominal file (no gain: the other constants exact), and scaled within 5 %
(within the tolerance: calibration).

    python bench/command_gain.py --first 100 --n 40 --procs 2

Prints per rig the verdicts and the gains reported, then per command the share of scaled logs with the gain
reported, its error against ``s - 1``, and the false reports of the controls.
"""

from __future__ import annotations

import argparse
import sys
from multiprocessing import Pool
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.proving_ground.experiment import draw, run_command, voltage_steps
from tests.rig_log import rig_log

COMMANDS = {"4 levels": (-1.0, -0.3, 0.3, 1.0), "2 levels": (-1.0, 1.0)}
CASES = ("scaled", "one constant", "within 5 %")


def one(seed: int) -> dict:
    from ocp.identify import diagnose
    from ocp.identify.coverage import COMMON_GAIN
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant

    rig = draw(seed, "coulomb_friction")
    rig.truth.effects = {}
    rng = np.random.default_rng(seed + 777)
    s = 1.0 + float(rng.uniform(0.15, 0.5) * rng.choice([-1, 1]))
    small = 1.0 + float(rng.uniform(-0.05, 0.05))
    const = str(rng.choice(["R", "k", "J", "B"]))
    err = float(rng.uniform(0.2, 0.5) * rng.choice([-1, 1]))
    wrong = dict(rig.nominal)
    for key in {"k": ("k_t", "k_e")}.get(const, (const,)):
        wrong[key] = rig.nominal[key] / (1.0 + err)
    out: dict = {"seed": seed, "rate": rig.logger.rate, "s": s, "const": f"{const} {err:+.2f}"}
    for name, levels in COMMANDS.items():
        t, v = voltage_steps(rig, seed, levels=levels)
        cols = run_command(rig, t, v, seed + 1)
        for case, scale, nominal in (("scaled", s, rig.nominal), ("one constant", 1.0, wrong),
                                     ("within 5 %", small, rig.nominal)):
            logged = dict(cols, voltage=cols["voltage"] * scale)
            res = diagnose(DCMotorPlant(MotorParams(**nominal)), rig_log(logged))
            gains = [float(a["relative"]) for a in res.ambiguous if a["alternative"] == COMMON_GAIN]
            out[(name, case)] = (sorted(res.verdict), gains)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=100)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--procs", type=int, default=2)
    args = ap.parse_args(argv)
    with Pool(args.procs) as pool:
        rows = pool.map(one, range(args.first, args.first + args.n), chunksize=1)
    for r in rows:
        print(f"{r['seed']:4d} {r['rate']:6.0f} Hz  s {r['s']:.2f}  {r['const']:9s} | " + " | ".join(
            f"{name} {case}: {','.join(r[(name, case)][0]) or '-'}"
            + (f" gain {r[(name, case)][1][0]:+.2f}" if r[(name, case)][1] else "")
            for name in COMMANDS for case in CASES), flush=True)
    n = len(rows)
    print(f"\n{n} rigs (seeds {args.first}..{args.first + n - 1}), no hidden effect{'':14s}"
          + "".join(f"{name:>12s}" for name in COMMANDS))
    print(f"{'scaled 15-50 %: gain reported':52s}" + "".join(
        f"{sum(bool(r[(name, 'scaled')][1]) for r in rows):>9d}/{n:<2d}" for name in COMMANDS))
    for name in COMMANDS:
        e = [abs(r[(name, 'scaled')][1][0] - (r["s"] - 1.0)) for r in rows if r[(name, "scaled")][1]]
        if e:
            print(f"  {name}: |reported - (s - 1)| median {np.median(e):.3f}, max {np.max(e):.3f}")
    for case, text in (("one constant", "one of R, k, J, B 20-50 % off: gain reported"),
                       ("within 5 %", "scaled within 5 %: gain reported")):
        print(f"{text:52s}" + "".join(f"{sum(bool(r[(name, case)][1]) for r in rows):>9d}/{n:<2d}"
                                      for name in COMMANDS))
    print(f"{'one constant: exactly it named':52s}" + "".join(
        f"{sum(r[(name, 'one constant')][0] == ['param:' + r['const'].split()[0]] for r in rows):>9d}/{n:<2d}"
        for name in COMMANDS))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
