#!/usr/bin/env python
"""Verification time per answer with and without the compiled simulator step, on the optimiser bench missions.

Usage::

    python bench/verify_time.py [--repeats N]

For every mission of ``bench/optimizer.py``'s suite (min-time excluded: several meshes per answer) the answer is
computed once (program built, compiled step built and cached on disk), then ``repeats`` times with the compiled
step turned off (``THRUSTSHAPE_SIM_COMPILE=0``: CasADi's virtual machine, the former verification) and on,
interleaved. Reported: the median ``solver["verify_time_s"]`` (evaluation, simulation and packaging of one
answer; every back-off round's verification included) and the largest relative difference of the returned
arrays between the two (numbers unchanged: 0 expected).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.optimizer import SUITE
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.solve import optimize_mesh
from ocp.simulate import compiled


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    print(f"C compiler: {compiled.compiler()}; cache: {compiled.cache_dir()}; load {os.getloadavg()[0]:.2f}")
    print(f"{'mission':22s} {'VM ms':>8s} {'C ms':>8s} {'ratio':>6s} {'max rel diff':>12s}")
    vm_all, c_all = [], []
    for spec in SUITE:
        if spec.get("objective") == "min-time":
            continue
        m = mission_from_mapping(spec)
        optimize_mesh(m)
        times: dict[str, list[float]] = {"0": [], "1": []}
        arrays: dict[str, dict[str, np.ndarray]] = {}
        for _ in range(args.repeats):
            for flag in ("0", "1"):
                os.environ["THRUSTSHAPE_SIM_COMPILE"] = flag
                r = optimize_mesh(m)
                times[flag].append(float(r.solver["verify_time_s"]))
                arrays[flag] = r.arrays
        diff = max(float(np.max(np.abs(arrays["0"][k] - arrays["1"][k]) / np.maximum(np.abs(arrays["0"][k]), 1e-300)))
                   for k in arrays["0"])
        vm, c = statistics.median(times["0"]), statistics.median(times["1"])
        vm_all.append(vm)
        c_all.append(c)
        ratio = vm / c if c > 0 else float("nan")  # 0: no verification (the fallback answered)
        print(f"{m.name:22s} {vm * 1e3:8.1f} {c * 1e3:8.1f} {ratio:6.1f} {diff:12.2e}", flush=True)
    print(f"{'median':22s} {statistics.median(vm_all) * 1e3:8.1f} {statistics.median(c_all) * 1e3:8.1f}; "
          f"load {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
