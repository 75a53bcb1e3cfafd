"""Whether the rate ``design-experiment`` advises checks an inductance the log could not (issue #11): proving-ground
rigs (:func:`tests.proving_ground.experiment.draw`, no hidden effect) whose L/R is under two samples at their drawn
rate, the nominal ``L`` off by 25-50 % either way (or exact: false alarms), logged under random voltage steps
(:func:`tests.proving_ground.experiment.voltage_steps`) at the drawn rate, at two and at four samples per nominal L/R
(:func:`ocp.identify.regression.advised_rate`), the logger's other habits kept (:func:`.experiment.at_rate`).

    python bench/logging_rate.py --first 100 --n 60 --procs 2

Prints per rig the verdicts and a table: ``L`` named (exactly ``param:L``) at each rate, and ``L`` named on the
exact-``L`` rigs. Session 41, seeds 100..159 (41 rigs under two samples; the advice's four samples were chosen on
seeds 0..11, eight rigs): named 4 / 26 / 36 of 41 at the log's rate / two / four samples per L/R;
none of the exact-``L`` rigs named ``L``.
"""

from __future__ import annotations

import argparse
import sys
from multiprocessing import Pool
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.proving_ground.experiment import at_rate, draw, run_command, voltage_steps
from tests.rig_log import rig_log

#: the sampling rates compared: the log's own, then samples per nominal L/R
RATES = (None, 2.0, 4.0)


def one(seed: int) -> dict | None:
    from ocp.identify import diagnose
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant

    rig = draw(seed, "coulomb_friction")
    rig.truth.effects = {}
    if rig.truth.L / rig.truth.R >= 2 * rig.logger.dt:
        return None
    rng = np.random.default_rng(seed + 999)
    err = float(rng.uniform(0.25, 0.5) * rng.choice([-1, 1]))
    t, v = voltage_steps(rig, seed)
    out: dict = {"seed": seed, "err": err, "samples": rig.truth.L / rig.truth.R / rig.logger.dt,
                 "rate": rig.logger.rate, "alpha": rig.logger.alpha}
    for name, e in (("wrong", err), ("exact", 0.0)):
        nominal = dict(rig.nominal, L=rig.truth.L / (1 + e))
        plant = DCMotorPlant(MotorParams(**nominal))
        verdicts = []
        for k in RATES:
            rate = rig.logger.rate if k is None else k * nominal["R"] / nominal["L"]
            verdicts.append(sorted(diagnose(plant, rig_log(run_command(at_rate(rig, rate), t, v, seed + 1))).verdict))
        out[name] = verdicts
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=100)
    ap.add_argument("--n", type=int, default=60)
    ap.add_argument("--procs", type=int, default=2)
    args = ap.parse_args(argv)
    with Pool(args.procs) as pool:
        rows = [r for r in pool.map(one, range(args.first, args.first + args.n), chunksize=1) if r]
    heads = ["log rate", "2 per L/R", "4 per L/R"]
    print(f"{'seed':>5} {'L err':>6} {'L/R [samples]':>13} {'rate':>7} {'alpha':>5}  " + " | ".join(heads))
    for r in rows:
        print(f"{r['seed']:5d} {r['err']:+6.2f} {r['samples']:13.2f} {r['rate']:7.0f} {r['alpha']:5.2f}  "
              + " | ".join(",".join(v) or "-" for v in r["wrong"]) + "   exact L: "
              + " | ".join(",".join(v) or "-" for v in r["exact"]))
    print(f"\n{len(rows)} rigs with L/R under two samples")
    print(f"{'':22s}" + "".join(f"{h:>12s}" for h in heads))
    print(f"{'L named (L wrong)':22s}" + "".join(f"{sum(r['wrong'][j] == ['param:L'] for r in rows):12d}"
                                               for j in range(len(RATES))))
    print(f"{'L named (L exact)':22s}" + "".join(f"{sum('param:L' in r['exact'][j] for r in rows):12d}"
                                               for j in range(len(RATES))))
    print(f"{'anything (L exact)':22s}" + "".join(f"{sum(bool(r['exact'][j]) for r in rows):12d}"
                                                for j in range(len(RATES))))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
