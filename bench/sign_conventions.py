"""Whether a channel logged with the opposite sign is found, and named right (:mod:`ocp.identify.signs`): the
proving ground's time-series cases (:func:`bench.modelcheck.load_case`: every effect alone and in pairs, wrong
constants, loggers at 50 Hz-10 kHz), each as drawn (a channel called negated there is a false refusal) and with
each of voltage, current, speed (and angle) and thrust negated in turn.

    python bench/sign_conventions.py --first 0 --n 200 --cache DIR [--first 14000 ...]

Prints per channel how many negated logs were found exactly (that channel alone), found as another, and missed,
the seeds of the last two, and the false refusals of the logs as drawn. ~0.05 s a log and channel.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import case_log, load_case

CHANNELS = ("current", "omega", "thrust", "voltage")


def main(argv: list[str] | None = None) -> int:
    from ocp.identify.signs import negated as found
    from ocp.logs import negated
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--cache", default=None, help="the proving ground's cache (bench/modelcheck.py --cache)")
    args = ap.parse_args(argv)
    false: list[tuple[int, list[str]]] = []
    exact = dict.fromkeys(CHANNELS, 0)
    other: dict[str, list[tuple[int, list[str]]]] = {c: [] for c in CHANNELS}
    missed: dict[str, list[int]] = {c: [] for c in CHANNELS}
    seeds = range(args.first, args.first + args.n)
    for seed in seeds:
        case = load_case(seed, args.cache, False)
        log = case_log(case, True)
        plant = DCMotorPlant(MotorParams(**case.nominal))
        if given := list(found(plant, log)):
            false.append((seed, given))
        for ch in CHANNELS:
            got = list(found(plant, negated(log, [ch])))
            if got == [ch]:
                exact[ch] += 1
            elif got:
                other[ch].append((seed, got))
            else:
                missed[ch].append(seed)
    n = len(seeds)
    print(f"{n} proving-ground logs (seeds {args.first}..{args.first + n - 1})")
    print(f"as drawn, a channel called negated: {len(false)}" + "".join(f"; {s} {g}" for s, g in false))
    print(f"{'negated':10s} {'found':>8s} {'as another':>11s} {'missed':>7s}")
    for ch in CHANNELS:
        print(f"{ch:10s} {exact[ch]:>5d}/{n:<3d}{len(other[ch]):>8d}{len(missed[ch]):>9d}   "
              + "; ".join(f"{s} as {'+'.join(g)}" for s, g in other[ch])
              + (f"{'; ' if other[ch] else ''}missed {missed[ch]}" if missed[ch] else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
