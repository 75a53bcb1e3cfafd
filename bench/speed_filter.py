"""The model check on speeds logged through a filter: proving-ground logs whose speed column passed a first-order
low-pass of ``LAG`` samples before it was written (a tachometer's RC filter, an encoder speed smoothed in firmware),
the angle column left out (a logger that writes only the speed it filtered).

The proving ground's tachometer is unfiltered (``tests/proving_ground/logger.py``); the blind rig's filters 70 % of its
tachometers by 0.2-3 rows, and a real one may by more. The identifier reads a late speed as a nuisance of its
equations (``speed_lag``, :data:`ocp.identify.regression.NUISANCE_BOUNDS`: up to two samples): a first-order filter
of ``T`` is undone exactly by ``w = y + T y'``, so beyond the bound what is left reads as a wrong constant (``R``:
``k_e k_t T / (J R)``, the lag over the mechanical time constant). The filter here is this script's own recursion,
``y[n] = y[n-1] + (w[n] - y[n-1]) / (1 + LAG)``, applied to the logged speed (never the identifier's code).

    python bench/speed_filter.py --kind clean --first 3000 --n 40 --lags 0 2 3 4 --cache DIR

Prints per lag: verdicts exactly right, false alarms (any name on a clean draw), and the names added beyond the
truth. Session 70 at ``a9f4b77``, clean 3000..3039 (``--cache`` of the ten sets): 40/40 at lag 0, 32/40 at 3 samples
(``R`` on 5, a ripple on 3, a dead band on 2); with the bound at four samples (a trial, not kept: blind rig 785 -> 784)
36/40.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def filtered(w: np.ndarray, lag: float) -> np.ndarray:
    """``w`` (n,) [rad/s] through a first-order low-pass of ``lag`` samples (0: unchanged)."""
    if lag <= 0.0:
        return w.copy()
    a, y, acc = 1.0 / (1.0 + lag), np.empty_like(w), float(w[0])
    for k, x in enumerate(w):
        acc += a * (float(x) - acc)
        y[k] = acc
    return y


def one(args: tuple[int, float, str | None, str | None]) -> tuple[int, float, list[str], list[str]]:
    """(seed, lag, truth, verdict) of one case with its speed filtered by ``lag`` samples."""
    from bench.modelcheck import case_log, load_case
    from ocp.identify import diagnose
    from ocp.logs import log_from_arrays
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant

    seed, lag, kind, cache = args
    case = load_case(seed, cache, False, kind)
    x = case_log(case, angle=False)
    log = log_from_arrays(x.t, x.voltage, x.current, x.thrust, omega=filtered(x.omega, lag),
                          source=f"proving-ground-{seed}-speed-lag-{lag:g}")
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    return seed, lag, sorted(case.expected), sorted(res.verdict)


def table(rows: list[tuple[int, float, list[str], list[str]]]) -> str:
    """Per lag: exact verdicts, false alarms on clean draws, the names beyond the truth."""
    out = [f"{'lag':>5s} {'exact':>9s} {'clean FA':>9s}  names beyond the truth"]
    for lag in sorted({r[1] for r in rows}):
        rs = [r for r in rows if r[1] == lag]
        exact = sum(e == v for _, _, e, v in rs)
        clean = [r for r in rs if not r[2]]
        fa = sum(bool(v) for _, _, _, v in clean)
        extra = Counter(x for _, _, e, v in rs for x in set(v) - set(e))
        out.append(f"{lag:5g} {exact:4d}/{len(rs):<4d} {fa:4d}/{len(clean):<4d}  "
                   + ", ".join(f"{k} {n}" for k, n in extra.most_common()))
    return "\n".join(out)


def main(argv: list[str] | None = None) -> Any:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--first", type=int, default=3000)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--kind", default="clean", choices=["clean", "one", "two", "constant", "constant+one", "drawn"],
                    help="the proving ground's draw kind ('drawn': as each seed draws it)")
    ap.add_argument("--lags", type=float, nargs="+", default=[0.0, 3.0], help="filter lags [samples]")
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--cache", default=None, help="directory of generated logs (bench/modelcheck.py --cache)")
    ap.add_argument("--cases", action="store_true", help="also print every case's truth and verdict")
    a = ap.parse_args(argv)
    kind = None if a.kind == "drawn" else a.kind
    jobs = [(s, lag, kind, a.cache) for lag in a.lags for s in range(a.first, a.first + a.n)]
    with ProcessPoolExecutor(a.procs) as ex:
        rows = list(ex.map(one, jobs))
    if a.cases:
        for s, lag, e, v in rows:
            print(f"seed {s} lag {lag:g}: truth={e} verdict={v}{'' if e == v else '  X'}")
    print(table(rows))
    return rows


if __name__ == "__main__":
    main()
