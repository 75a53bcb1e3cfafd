"""The torque equation's floor on proving-ground logs against a labelled item's footprint: with the TRUE
constants and hidden effects (the proving ground's own load torque), what eq. dc_mechanical still leaves on the
identifier's rows (the aligned log, raw rows where an angle is logged, seen through the rotor's low-pass as
:mod:`ocp.identify.regression` sees it, the current sensor's lag fitted as the identifier's nuisance always is), and
what the item alone puts there. (Calibration of the constants within the tolerance, which every model of the
identifier also has, can take a further share of the floor, and of the footprint.)

    python bench/pg_floor.py --items 6132:stribeck 113:param:B 88:cogging --cache DIR [--noise-free]
    python bench/pg_floor.py --records a.json b.json --label stribeck --cache DIR [--noise-free]

``--records``: the logs of ``bench/modelcheck.py --json`` records whose verdict missed ``--label`` where the audit
(``bench/modelcheck.py --audit``) finds it required: which misses the equations' rows could show at all.

A footprint under the floor is an item that no choice of columns can show on these rows: the equations'
discretisation against the logger (sample means, an encoder's difference, a sub-sample skew), not noise or a
missing column, stands above it (``--noise-free``: each log recorded again without sensor noise, quantisation or
jitter, :func:`bench.modelcheck.noise_free`: what is left is the equations'). Load-torque items only
(``coulomb_friction``, ``stribeck``, ``drag_asymmetry``, ``cogging``, ``param:B``, ``param:c_tau``); a current
offset is taken out of the measured current.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import audited, case_log, load_case, noise_free
from ocp.identify.align import estimate
from ocp.identify.columns import nuisance_columns, raw_signals, signals
from ocp.identify.realign import realign
from ocp.identify.regression import speed_view
from ocp.identify.resolution import rotor_tau
from ocp.model.params import MotorParams
from tests.proving_ground.calibration import without
from tests.proving_ground.physics import load_torque

#: points along a row's path at which the load torque is averaged (the identifier's ``columns.ROW_POINTS``, not read)
ROW_POINTS = 8
LOAD_ITEMS = ("coulomb_friction", "stribeck", "drag_asymmetry", "cogging", "param:B", "param:c_tau")


def row_mean(load: Callable[[float, float], float], s: Any, theta: np.ndarray) -> np.ndarray:
    """Each row's mean (M,) [N m] of the load torque ``load(w, theta)`` along the rotor's path over the row of
    ``s`` (:class:`ocp.identify.columns.Signals`), ``theta`` (M,) [rad] at the row's sample: raw rows k-1 -> k+1
    under a triangle (the mean speed over each half, the angle exact at k), low-passed rows k -> k+1 (the speed
    linear over the row, the angle its integral); :data:`ROW_POINTS` points per half or row."""
    u = (np.arange(ROW_POINTS) + 0.5) / ROW_POINTS
    if s.triangle:
        paths = [(s.w0, theta - (1.0 - x) * s.dt * s.w0, x) for x in u] + \
            [(s.w1, theta + x * s.dt * s.w1, 1.0 - x) for x in u]
    else:
        paths = [(s.w0 + x * (s.w1 - s.w0), theta + s.dt * (x * s.w0 + 0.5 * x * x * (s.w1 - s.w0)), 1.0) for x in u]
    total = sum(wt * np.array([load(float(a), float(b)) for a, b in zip(w, th, strict=True)]) for w, th, wt in paths)
    return np.asarray(total, float) / sum(wt for _, _, wt in paths)


def floor_and_footprint(case: Any, item: str) -> tuple[float, float]:
    """(floor, footprint) [N m]: RMS over the middle 80 % of the rows, speed view (module doc). The load torque is
    each row's mean along the rotor's path over it, as the torque balance holds it (a ripple of several periods
    within a row, a dry friction whose sign flips inside one), not its value at one point."""
    t = case.truth
    log = case_log(case)
    nominal = case.nominal
    log = realign(log, estimate(log, 2.0, (nominal["L"] / nominal["R"], nominal["k_e"])).samples)
    p = MotorParams(J=t.J, B=t.B, c_tau=t.c_tau, c_f=t.c_f, k_t=t.k, k_e=t.k, R=t.R, L=t.L)
    s = raw_signals(log, log.theta) if log.theta is not None else signals(log, p)
    theta = s.theta if s.theta is not None else np.zeros_like(s.w)

    def torque(x: Any) -> np.ndarray:
        return row_mean(load_torque(x), s, theta)

    other = without(case, item)
    offset = t.e("current_offset", "i0")
    resid = p.k_t * (s.i - offset) - p.J * (s.w1 - s.w0) / s.dt - torque(t)
    tau = rotor_tau(p, signals(log, p).w)
    rows = slice(s.w.size // 10, -(s.w.size // 10))
    r = speed_view(resid, s.dt, tau)[rows]
    lag = speed_view(nuisance_columns(p, s)["current_lag"][0], s.dt, tau)[rows]
    r = r - lag * float(lag @ r) / max(float(lag @ lag), 1e-300)  # the current lag, fitted
    f = speed_view(torque(t) - torque(other), s.dt, tau)[rows]
    return float(np.sqrt(np.mean(r * r))), float(np.sqrt(np.mean(f * f)))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    which = ap.add_mutually_exclusive_group(required=True)
    which.add_argument("--items", nargs="+", help="SEED:ITEM, e.g. 6132:stribeck or 113:param:B")
    which.add_argument("--records", nargs="+", help="bench/modelcheck.py --json files (with --label)")
    ap.add_argument("--label", choices=LOAD_ITEMS, help="with --records: the label whose required misses to take")
    ap.add_argument("--cache", default=None, help="as bench/modelcheck.py's")
    ap.add_argument("--noise-free", action="store_true", help="the logs recorded again without noise")
    args = ap.parse_args(argv)
    if args.records and not args.label:
        ap.error("--records needs --label")
    specs = [(int(s.split(":", 1)[0]), s.split(":", 1)[1], None) for s in args.items] if args.items else \
        [(r["seed"], args.label, r.get("forced_kind")) for r in _required_misses(args.records, args.label, args.cache)]
    under = 0
    for seed, item, kind in specs:
        if item not in LOAD_ITEMS:
            print(f"{seed}:{item}: not a load-torque item ({', '.join(LOAD_ITEMS)})")
            continue
        case = load_case(seed, args.cache, kind=kind)
        case = noise_free(case) if args.noise_free else case
        floor, foot = floor_and_footprint(case, item)
        under += foot < floor
        print(f"{seed:6d} {item:17s} {case.logger.rate:6.0f} Hz {case.logger.speed:8s} floor {floor:9.3g} N m "
              f"footprint {foot:9.3g} N m  ratio {foot / floor:7.2f}", flush=True)
    print(f"footprint under the floor: {under} of {len(specs)}")
    return 0


def _required_misses(files: list[str], label: str, cache: str | None) -> list[dict[str, Any]]:
    """The records in ``files`` whose verdict misses ``label`` where the audit finds it required."""
    rows = [r for f in files for r in json.loads(Path(f).read_text(encoding="utf-8"))]
    missed = [r for r in rows if label in r["expected"] and label not in r["verdict"]]
    return [r for r in missed if label in audited(r, cache)["required"]]


if __name__ == "__main__":
    raise SystemExit(main())
