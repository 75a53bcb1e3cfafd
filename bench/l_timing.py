"""Can a sub-sample command timing hide an inductance error? For each proving-ground log whose wrong ``L`` the model
check missed (from ``bench/modelcheck.py --json`` records), replay the true rig and the rig with the nominal ``L``
under the logged commands, the second with the command timing shifted (by 0.75, 1 and 1.25 times the shift that
moves each current transient's charge as the ``L`` error does, ``(L - L_nominal) / R``), and report the difference
in noise levels (the generator's visibility measure, largest over speed, current and thrust) at the true timing
and at the best shift. Where the best shift brings a visible difference under ``VISIBLE``, the log cannot tell the
``L`` error from command timing; where it does not, ``L`` is identifiable in principle.

    python bench/l_timing.py --records a.json b.json --cache DIR [--samples 800]

Replays the first ``--samples`` samples at the generator's sub-steps (the drive switches at its exact instant,
whatever the shift). Session 13's figures (4 of 25 hidden) came from the generator before session 14's, whose
switch fell on sub-steps and needed up to 4,000 of them a sample to resolve the shift.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import load_case
from tests.proving_ground import cases as pg
from tests.proving_ground.logger import logged, noise_levels
from tests.proving_ground.physics import run


def gap(seed: int, cache: str | None, samples: int) -> tuple[float, float, float, float]:
    """(L/R [samples], visibility at the true timing, best visibility over timing shifts, that shift [samples])."""
    case = load_case(seed, cache)
    t, lg = case.truth, case.logger
    cmds = case.columns["voltage"][:samples]
    sig = noise_levels(lg)
    nominal = replace(t, L=t.L / (1.0 + case.constant_error["L"]))
    charge = (t.L - nominal.L) / t.R / lg.dt  # the timing shift [samples] that moves each transient's charge alike
    sub = pg._substeps(t, lg, case.meta["tau_m"])
    lag = pg._lag(t, lg)

    def replay(x: pg.Truth, at: float) -> np.ndarray:
        return logged(lg, run(x, lambda k, _s: float(cmds[k]), cmds.size, lg.dt, max(at, 0.0), sub)[0])

    def seen(b: np.ndarray) -> float:
        return float(np.max(np.sqrt(np.mean((a - b) ** 2, axis=1)) / sig))

    a = replay(t, lag)
    best = min((seen(replay(nominal, lag + s * lg.dt)), s) for s in charge * np.array([0.75, 1.0, 1.25]))
    return t.L / t.R / lg.dt, seen(replay(nominal, lag)), *best


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", nargs="+", required=True, metavar="JSON", help="bench/modelcheck.py --json records")
    ap.add_argument("--cache", default=None, help="the generated logs' folder (bench/modelcheck.py --cache)")
    ap.add_argument("--samples", type=int, default=800)
    args = ap.parse_args(argv)
    rows = [r for p in args.records for r in json.loads(Path(p).read_text(encoding="utf-8"))
            if "param:L" in r["expected"] and "param:L" not in r["verdict"]]
    shows = hidden = 0
    print("seed   L/R [samples]  seen at true timing  best over shifts (shift [samples])")
    for r in rows:
        ratio, same, best, shift = gap(r["seed"], args.cache, args.samples)
        shows += same >= pg.VISIBLE
        hidden += same >= pg.VISIBLE > best
        print(f"{r['seed']:5d} {ratio:10.2f} {same:16.2f} {best:16.2f} ({shift:+.3f})"
              f"{'  hidden by timing' if same >= pg.VISIBLE > best else ''}", flush=True)
    print(f"missed L errors: {len(rows)}; visible in the replayed part: {shows}; of those hidden by a timing shift: "
          f"{hidden}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
