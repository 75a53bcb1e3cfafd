"""Whether ``design-experiment`` settles a dead band or a brush drop a two-level command hides: proving-ground rigs
(:func:`tests.proving_ground.experiment.draw`) with a hidden voltage dead band or brush drop, logged under random
steps between +-0.6 V_max (:func:`tests.proving_ground.experiment.voltage_steps`: one voltage magnitude, where either
effect is a gain on the command the constants take up), diagnosed and designed for; the proposal is optimised,
played on the same rig (the proving ground's own simulation) and diagnosed again.

    python bench/design_levels.py --first 20 --n 12

Per rig and effect: the verdict under the two-level command, whether the one-magnitude gap was raised
(:func:`ocp.identify.design.coverage`: ``voltage_range``), the proposal and the verdict after it; then how many were
right before and after, and on how many a gain on the command was the named constants' rival (:mod:`ocp.identify.gain`).
Session 41: the gap was built on seeds 0..5. ~30 s a rig and effect.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.proving_ground.experiment import draw, run_command, voltage_steps
from tests.rig_log import rig_log

EFFECTS = ("voltage_deadband", "brush_drop")


def main(argv: list[str] | None = None) -> int:
    from ocp.identify import diagnose
    from ocp.identify.coverage import COMMON_GAIN, coverage
    from ocp.identify.design import DesignOptions, design
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant
    from ocp.optimize.mission import Mission
    from ocp.optimize.solve import optimize

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=20)
    ap.add_argument("--n", type=int, default=12)
    args = ap.parse_args(argv)

    before = after = gapped = gained = total = 0
    for seed in range(args.first, args.first + args.n):
        for effect in EFFECTS:
            rig = draw(seed, effect)
            t, v = voltage_steps(rig, seed, levels=(-1.0, 1.0))
            log = rig_log(run_command(rig, t, v, seed + 1))
            plant = DCMotorPlant(MotorParams(**rig.nominal))
            first = diagnose(plant, log)
            gap = not coverage(log)["voltage_range"]
            total += 1
            gapped += gap
            before += first.verdict == [effect]
            gain = any(a["alternative"] == COMMON_GAIN for a in first.ambiguous)
            gained += gain
            d = design(plant, log, first, DesignOptions(voltage=rig.truth.v_max,
                                                        current=3.0 * float(np.max(np.abs(log.current))))).to_dict()
            head = (f"{seed:4d} {effect:16s} {rig.logger.rate:6.0f} Hz | two-level: {first.verdict}"
                    f"{' (gain rival)' if gain else ' (ambiguous)' if first.ambiguous else ''}"
                    f" | gap {'yes' if gap else 'no '}")
            if d["mission"] is None:
                print(f"{head} | no proposal: {d['message'][:90]}", flush=True)
                continue
            res = optimize(Mission.model_validate(d["mission"]))
            second = diagnose(plant, rig_log(run_command(rig, res.arrays["t"], res.arrays["voltage"], seed + 7)))
            after += second.verdict == [effect]
            print(f"{head} | {d['chosen']['name']:18s} | after: {second.verdict}"
                  f"{' (ambiguous)' if second.ambiguous else ''}", flush=True)
    print(f"\nexactly right under the two-level command: {before} of {total}; a gain on the command the rival of "
          f"named constants on {gained}; the gap raised on {gapped}; "
          f"exactly right after the proposed experiment: {after} of {total}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
