"""How far ``check`` puts the EXACT plant from its own log: the free-run floor the logger leaves.

On the proving ground's logs with no effect (clean, and a wrong constant: checked with the true constants), the
exact plant's free run would sit at the noise if ``check`` read the model as the logger reads the rig. Printed per
channel (noise units, median / 90th percentile / max) for the current as simulated and as read through the current
sensor's lag ``check`` fits (:func:`ocp.identify.predict.read_current`), and that lag against the logger's
(``(1 - alpha) / alpha`` samples) where the alignment found is within a quarter sample of the drawn skew.

    python bench/checkfloor.py --n 200 --first 0 --cache /tmp/pg     # session 27: the 52 such logs of 0..199
"""

from __future__ import annotations

import argparse
import multiprocessing
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.modelcheck import case_log, load_case  # noqa: E402
from ocp.identify import check  # noqa: E402
from ocp.identify.check import CheckOptions, CheckResult  # noqa: E402
from ocp.identify.diagnose import aligned  # noqa: E402
from ocp.identify.predict import free_run  # noqa: E402
from ocp.logs import LogKind  # noqa: E402
from ocp.model.params import MotorParams  # noqa: E402
from ocp.model.plant import DCMotorPlant  # noqa: E402


def one(seed: int, cache: str | None) -> dict[str, Any] | None:
    """The exact plant's check of case ``seed`` (None for a case with an effect or a steady-state sweep)."""
    case = load_case(seed, cache)
    log = case_log(case)
    if case.truth.effects or log.kind is not LogKind.TIME_SERIES:
        return None
    t = case.truth
    plant = DCMotorPlant(MotorParams(J=t.J, B=t.B, c_tau=t.c_tau, c_f=t.c_f, k_t=t.k, k_e=t.k, R=t.R, L=t.L))
    res = check(plant, log)
    assert isinstance(res, CheckResult)
    _, realigned = aligned(plant, log, CheckOptions().max_logging_skew)
    sim = free_run(plant, realigned, CheckOptions().segment_s).current
    unread = float(np.sqrt(np.mean((realigned.current[res.free.idx] - sim) ** 2)))
    units = {ch: res.free_run_rms[ch] / res.noise[ch] for ch in res.free_run_rms}
    return {"seed": seed, "omega": units["omega"], "unread": unread / res.noise["current"],
            "read": units["current"], "thrust": units["thrust"], "lag": res.free.current_lag,
            "logger_lag": (1.0 - case.logger.alpha) / case.logger.alpha,
            "aligned": abs(res.alignment.samples - case.logger.skew) < 0.25}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--cache", default=None)
    args = ap.parse_args(argv)
    seeds = range(args.first, args.first + args.n)
    with multiprocessing.Pool(args.procs) as pool:
        rows = [r for r in pool.starmap(one, [(s, args.cache) for s in seeds]) if r is not None]
    print(f"{len(rows)} logs without an effect among seeds {seeds.start}..{seeds.stop - 1}; exact plant, noise units")
    if not rows:
        return 0
    print(f"{'channel':28s} {'median':>8s} {'p90':>8s} {'max':>8s}")
    for key, label in (("omega", "speed"), ("unread", "current as simulated"),
                       ("read", "current read through the lag"), ("thrust", "thrust")):
        v = np.array([r[key] for r in rows])
        print(f"{label:28s} {np.median(v):8.2f} {np.percentile(v, 90):8.2f} {v.max():8.2f}")
    err = np.array([abs(r["lag"] - r["logger_lag"]) for r in rows if r["aligned"]])
    print(f"lag fitted - logger's [samples], {err.size} logs aligned within a quarter sample"
          + (f": median {np.median(err):.2f}, max {err.max():.2f}" if err.size else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
