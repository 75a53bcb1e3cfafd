"""Does the proposed experiment settle what a log cannot? (issue #11 item 5, on demand, not a test)

For each seed: a proving-ground rig (``tests/proving_ground``, no code shared with ``ocp``) with one hidden
effect, logged only near ONE operating speed (:func:`tests.proving_ground.experiment.single_speed`); the
log is diagnosed; :func:`ocp.identify.design.design` proposes an experiment (limits: the supply voltage and
half the stall current); the optimiser turns its mission into a voltage command; the proving ground plays
that command on the same rig and logger; the new log is diagnosed. Printed per case and in total: the
first verdict (and whether ambiguous), the proposal and its predicted separation z (this log's z beside
it), the second verdict, and whether it is exactly right.

    python bench/design_experiment.py [--first 100] [--n 10] [--effects coulomb_friction,stribeck]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def one(seed: int, effect: str) -> dict[str, Any]:
    from ocp.identify import diagnose
    from ocp.identify.design import DesignOptions, design
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant
    from ocp.optimize.mission import Mission
    from ocp.optimize.solve import optimize
    from tests.proving_ground.experiment import draw, run_command, single_speed
    from tests.rig_log import rig_log

    rig = draw(seed, effect)
    log = rig_log(single_speed(rig, seed))
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    t0 = time.perf_counter()
    first = diagnose(plant, log)
    # a drive's limits: the supply voltage, half the stall current (not the log's small operating current)
    limits = DesignOptions(voltage=rig.truth.v_max, current=0.5 * rig.truth.v_max / rig.truth.R)
    d = design(plant, log, first, limits)
    t_design = time.perf_counter() - t0
    out: dict[str, Any] = {"seed": seed, "effect": effect, "first": first.verdict,
                              "ambiguous": bool(first.ambiguous), "needed": d.needed, "t_design": t_design}
    if d.mission is None or d.chosen is None:
        return {**out, "proposal": None, "second": None, "right": False}
    res = optimize(Mission.model_validate(d.mission))
    second = diagnose(plant, rig_log(run_command(rig, res.arrays["t"], res.arrays["voltage"], seed + 7)))
    return {**out, "proposal": d.chosen.name, "z": d.chosen.worst, "z_log": min(d.current_log.values()),
            "second": second.verdict, "second_ambiguous": bool(second.ambiguous),
            "right": second.verdict == [effect] and not second.ambiguous}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=100)
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--effects", default="coulomb_friction,stribeck")
    args = ap.parse_args(argv)
    rows = []
    print(f"{'seed':>5s} {'effect':17s} {'first verdict':28s} {'proposal':20s} {'z':>7s} {'z log':>7s} "
          f"{'second verdict':28s} right  design s")
    for effect in args.effects.split(","):
        for seed in range(args.first, args.first + args.n):
            r = one(seed, effect)
            rows.append(r)
            first = ",".join(r["first"]) + (" (ambiguous)" if r["ambiguous"] else "")
            second = "-" if r["second"] is None else ",".join(r["second"]) or "nothing"
            print(f"{seed:5d} {effect:17s} {first or 'nothing':28s} {r['proposal']!s:20s} "
                  f"{float(r.get('z', np.nan)):7.3g} {float(r.get('z_log', np.nan)):7.3g} {second:28s} "
                  f"{'yes' if r['right'] else 'NO':5s}  {float(r['t_design']):6.1f}", flush=True)
    unsettled = [r for r in rows if r["ambiguous"] or r["first"] != [r["effect"]]]
    print(f"\nlogs: {len(rows)}; first log unsettled (ambiguous or wrong): {len(unsettled)}; "
          f"right after the proposed experiment: {sum(bool(r['right']) for r in rows)}/{len(rows)} "
          f"(of the unsettled: {sum(bool(r['right']) for r in unsettled)}/{len(unsettled)}); "
          f"design time median {np.median([float(r['t_design']) for r in rows]):.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
