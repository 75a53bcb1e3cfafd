"""How closely the proving ground's rig follows its own equations: each case's commands replayed at the generator's
sub-steps and at 16 times as many, the difference in the logged channels (``logged``: an encoder's speed, the
filtered current) in the logger's noise levels (RMS over the first ``--samples`` rows).

    python bench/pg_accuracy.py --n 100 --first 0 --cache DIR     # the cases bench/modelcheck.py diagnoses

Prints per case the error in noise levels per channel (speed, current, thrust), then how many cases exceed a half
and one noise level. A generator whose logs are off their own equations by a noise level asks the identifier to
explain its integrator (until session 14: 32 of seeds 0..99 over one noise level, up to 12).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import load_case
from tests.proving_ground import cases as pg
from tests.proving_ground.logger import logged, noise_levels
from tests.proving_ground.physics import run

FINE = 16  # the reference's sub-steps, in multiples of the generator's


def error(seed: int, cache: str | None, samples: int) -> tuple[np.ndarray, int]:
    """(RMS difference (3,) in noise levels between the generator's and the fine replay, the generator's sub-steps)."""
    case = load_case(seed, cache)
    t, lg = case.truth, case.logger
    cmds = case.columns["voltage"][:samples]
    sub = pg._substeps(t, lg, case.meta["tau_m"])

    def replay(m: int) -> np.ndarray:
        return logged(lg, run(t, lambda k, _s: float(cmds[k]), cmds.size, lg.dt, pg._lag(t, lg), m)[0])

    return np.sqrt(np.mean((replay(sub) - replay(FINE * sub)) ** 2, axis=1)) / noise_levels(lg), sub


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--cache", default=None, help="the generated logs' folder (bench/modelcheck.py --cache)")
    ap.add_argument("--samples", type=int, default=1500, help="rows replayed per case")
    args = ap.parse_args(argv)
    worst = []
    print(f"{'seed':>6} {'sub':>4}  error / noise level: speed  current  thrust")
    for seed in range(args.first, args.first + args.n):
        e, sub = error(seed, args.cache, args.samples)
        worst.append(float(np.max(e)))
        print(f"{seed:6d} {sub:4d}  {e[0]:22.3f} {e[1]:8.3f} {e[2]:7.3f}", flush=True)
    w = np.array(worst)
    print(f"cases: {w.size}   worst channel: median {np.median(w):.3f}, max {np.max(w):.3f} noise levels; "
          f"over 0.5: {int(np.sum(w > 0.5))}, over 1: {int(np.sum(w > 1.0))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
