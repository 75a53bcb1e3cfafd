"""Model-exact logs under the commands users send first: does ``diagnose`` say nothing is missing?

The plant of ``tests/identify/test_one_command.py`` is run under eight commands (3 s at 1 kHz: +-6 V and 0/6 V
squares at 2 Hz, a 1 Hz sine, a step down 6 -> 2 V, a ramp through zero, a chirp, a step from rest after 200 rows, a
PRBS) by the catalogue's own ZOH integration, logged with the loggers' noise at each given scale (1: 10 mA, 0.5
rad/s, 1 mN; 0: none), and diagnosed against that very plant: the right verdict is the empty one.

    python bench/exact_commands.py                  # noise scales 0, 0.01, 0.1, 1
    python bench/exact_commands.py --scales 0 0.01

Prints each command's verdict per scale and the clean count per scale. Not a test: always exits 0.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from ocp.identify import diagnose
from ocp.model.plant import DCMotorPlant
from tests.identify.test_one_command import P, step_log

N = 3000


def commands() -> dict[str, np.ndarray]:
    """The eight commands (N,) [V] on rows of 1 ms."""
    t = np.arange(N) * 1e-3
    flips = np.cumsum(np.random.default_rng(3).random(N) > 0.98)  # (a PRBS: a level change on 2 % of the rows)
    return {"square +-6 V": 6.0 * np.sign(np.sin(2 * np.pi * 2.0 * t) + 1e-9),
            "square 0/6 V": np.where(np.sin(2 * np.pi * 2.0 * t) > 0, 6.0, 0.0),
            "sine 1 Hz": 6.0 * np.sin(2 * np.pi * 1.0 * t),
            "step down 6 -> 2 V": np.where(np.arange(N) < N // 2, 6.0, 2.0),
            "ramp -6 -> 6 V": np.linspace(-6.0, 6.0, N),
            "chirp 0.5-12.5 Hz": 6.0 * np.sin(2 * np.pi * (0.5 * t + 2.0 * t ** 2)),
            "step from rest": np.where(np.arange(N) >= 200, 6.0, 0.0),
            "PRBS +-6 V": 6.0 * np.sign(np.sin(2 * np.pi * flips / 4 + 0.3))}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scales", type=float, nargs="+", default=[0.0, 0.01, 0.1, 1.0],
                    help="the loggers' noise, as a multiple of the full level")
    args = ap.parse_args(argv)
    plant, cmds = DCMotorPlant(P), commands()
    print(f"{'command':21s}" + "".join(f"noise x{s:<19g}" for s in args.scales))
    clean = dict.fromkeys(args.scales, 0)
    for name, u in cmds.items():
        row = []
        for s in args.scales:
            verdict = diagnose(plant, step_log(u, s)).verdict
            clean[s] += not verdict
            row.append(", ".join(verdict) or "clean")
        print(f"{name:21s}" + "".join(f"{v:<25s} " for v in row))
    print(f"{'clean':21s}" + "".join(f"{clean[s]}/{len(cmds)}".ljust(26) for s in args.scales))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
