"""How well the point-by-point diagnosis recovers a thruster's reverse/forward thrust coefficient ratio from
a vendor-like ESC sweep (tests/logfiles.py: own steady-state formulas, 0.3 % noise on force and power).

    python bench/sweep_asymmetry.py [--draws 30] [--seed 0]

Random draws: ratio uniform in [0.6, 1.0] (one in four exactly 1.0), nominal c_f off by a uniform factor in
[0.8, 1.25], PWM step 20-50 us. Printed: per draw the true and fitted ratio and the verdict; then the largest
ratio error among the draws where thrust_asymmetry was named, and a confusion matrix (asymmetric: r < 1).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ocp.identify import diagnose
from ocp.logs import read_log
from ocp.model.effects import load_plant
from tests.logfiles import Thruster, thruster_sweep, write_csv


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    errors, confusion = [], {(True, True): 0, (True, False): 0, (False, True): 0, (False, False): 0}
    print(f"{'true':>6s} {'fitted':>7s} {'c_f off':>7s} {'step':>5s}  verdict")
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(a.draws):
            ratio = 1.0 if k % 4 == 0 else float(rng.uniform(0.6, 1.0))
            off, step = float(rng.uniform(0.8, 1.25)), float(rng.choice([20.0, 25.0, 40.0, 50.0]))
            th = Thruster(ratio=ratio)
            path = Path(tmp) / f"s{k}.csv"
            write_csv(thruster_sweep(th, step=step, seed=int(rng.integers(1 << 30))), path)
            d = diagnose(load_plant(th.params() | {"c_f": th.c_f * off}), read_log(path)).to_dict()
            fitted = d["fitted_maps"]["thrust_ratio_reverse_to_forward"]  # None when no asymmetry was named
            named = "thrust_asymmetry" in d["verdict"]
            confusion[(ratio < 1.0, named)] += 1
            if named:
                errors.append(abs(fitted - ratio))
            print(f"{ratio:6.3f} {fitted if fitted is not None else float('nan'):7.3f} {off:7.3f} {step:5.0f}  "
                  f"{', '.join(d['verdict']) or 'nothing missing'}")
    print(f"\nlargest |fitted - true| ratio where named: {max(errors) if errors else float('nan'):.4f} "
          f"({len(errors)} draws)")
    print("confusion (rows: truly asymmetric?, columns: thrust_asymmetry named?)")
    for truth in (True, False):
        print(f"  {truth!s:5s}  named {confusion[(truth, True)]:3d}   not named {confusion[(truth, False)]:3d}")


if __name__ == "__main__":
    main()
