"""A rotor that turns one way only (:func:`ocp.identify.coverage.unseen`): the proving ground's clean cases
(:func:`tests.proving_ground.make_case`, its own integrator and loggers), their commands rectified to one sign and
replayed on the rig with a drawn discrepancy, diagnosed with the rule (as shipped) and without it (the forward
coefficients treated as on any log).

    python bench/one_way.py --first 100 --n 40 [--procs 2]

Per rig, four logs: reverse only with a drag or thrust asymmetry (reverse/forward 0.4-0.85 or 1.15-1.6, drawn),
reverse only with ``c_tau`` and ``c_f`` off by under 5 % (the nominal values' own error: nothing to name), forward only
with ``c_tau`` or ``c_f`` 15-50 % off (the constant itself), and the rig as drawn (both ways: the rule must not act).
Prints how many verdicts are exactly the drawn discrepancy either way, and the reported asymmetry's error against
the drawn one. ~15 s a rig.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ocp.logs import Log

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

KINDS = ("reverse: asymmetry", "reverse: constants within 5 %", "forward: one constant off", "as drawn (both ways)")


def _logs(seed: int) -> list[tuple[str, list[str], Log, dict[str, float], float | None]]:
    """(kind, drawn labels, log, nominal, drawn relative asymmetry) for rig ``seed``'s four logs."""
    import numpy as np

    from bench.modelcheck import case_log
    from tests.proving_ground import make_case
    from tests.proving_ground.cases import replay

    case = make_case(seed, kind="clean")
    rng = np.random.default_rng([seed, 1018])
    tr = case.truth

    def one_way(sign: float, **change: object) -> Log:
        cols = replay(case, sign * np.abs(case.columns["voltage"]), rng, **change)
        return case_log(dataclasses.replace(case, columns=cols))

    which = str(rng.choice(["drag_asymmetry", "thrust_asymmetry"]))
    ratio = float(rng.uniform(0.15, 0.6)) * (1.0 if rng.random() < 0.5 else -1.0)
    key, base = ("dc_tau", tr.c_tau) if which == "drag_asymmetry" else ("dc_f", tr.c_f)
    const = str(rng.choice(["c_tau", "c_f"]))
    off = float(rng.uniform(0.15, 0.5)) * (1.0 if rng.random() < 0.5 else -1.0)
    small = rng.uniform(-0.05, 0.05, 2)
    return [
        (KINDS[0], [which], one_way(-1.0, effects={which: {key: ratio * base}}), case.nominal, ratio),
        (KINDS[1], [], one_way(-1.0, c_tau=tr.c_tau * (1 + small[0]), c_f=tr.c_f * (1 + small[1])), case.nominal,
         None),
        (KINDS[2], [f"param:{const}"], one_way(1.0, **{const: getattr(tr, const) * (1 + off)}), case.nominal, None),
        (KINDS[3], [], case_log(case, True), case.nominal, None),
    ]


def _one(seed: int) -> list[tuple[str, list[str], list[str], list[str], float | None]]:
    """Per log of rig ``seed``: (kind, drawn, verdict with the rule, verdict without, reported asymmetry error)."""
    import ocp.identify.regression as regression
    from ocp.identify import diagnose
    from ocp.identify.coverage import unseen
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant

    out = []
    for kind, drawn, log, nominal, ratio in _logs(seed):
        plant = DCMotorPlant(MotorParams(**nominal))
        d = diagnose(plant, log)
        err = None
        if ratio is not None:
            key, base = ("dc_tau", "c_tau") if drawn[0] == "drag_asymmetry" else ("dc_f", "c_f")
            got = [getattr(e, key) / nominal[base] for e in d.plant.effects if e.name == drawn[0]]
            err = got[0] - ratio if got else None
        regression.unseen = lambda log: {}
        try:
            without = diagnose(plant, log).verdict
        finally:
            regression.unseen = unseen
        out.append((kind, drawn, d.verdict, without, err))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=100)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--procs", type=int, default=2)
    args = ap.parse_args(argv)
    seeds = range(args.first, args.first + args.n)
    with ProcessPoolExecutor(args.procs) as pool:
        rows = [(seed, r) for seed, rs in zip(seeds, pool.map(_one, seeds), strict=True) for r in rs]
    right: Counter[tuple[str, str]] = Counter()
    named: Counter[str] = Counter()
    errors = []
    for seed, (kind, drawn, with_rule, without, err) in rows:
        for how, verdict in (("with", with_rule), ("without", without)):
            right[kind, how] += sorted(verdict) == sorted(drawn)
            if sorted(verdict) != sorted(drawn):
                named.update(f"{how}: {v}" for v in verdict if v not in drawn)
                print(f"  {seed:5d} {kind:32s} {how:8s} drawn={drawn} verdict={verdict}")
        if err is not None:
            errors.append(abs(err))
    n = len(seeds)
    print(f"\n{n} clean proving-ground rigs (seeds {seeds[0]}..{seeds[-1]}), exactly right:")
    print(f"{'':34s}{'with the rule':>16s}{'without':>10s}")
    for kind in KINDS:
        print(f"{kind:34s}{right[kind, 'with']:>12d}/{n:<3d}{right[kind, 'without']:>6d}/{n:<3d}")
    if errors:
        errors.sort()
        print(f"reported asymmetry - drawn (relative to the forward coefficient), on the {len(errors)} named: "
              f"median |e| {errors[len(errors) // 2]:.3f}, max {errors[-1]:.3f}")
    print("false items:", dict(named.most_common()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
