"""Blind check of ``thrustshape diagnose`` against independently simulated rig logs.

Usage::

    python bench/blind_check.py --first 0 --n 60 --procs 2 --dir /work/blindcache --json /work/blind_0.json

Generates ``case-<seed>.*`` into DIR (kept unless --regen), runs the checker on each through its CLI
(subprocess, timeout 120 s; the code of the tree this script is in, :data:`TREE`, first on its path: the installed
CLI is an editable install of one checkout, and run from another worktree it checked that one) and prints the
exact-verdict rate, false alarms on clean logs, per-label confusion, exact rates by case kind and by logging-rate
band, timing and every wrong verdict.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from collections import Counter, defaultdict
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from blindrig.case import generate
from blindrig.draw import EFFECTS, PARAMS
from modelcheck import evidence_table

#: the checkout whose ``ocp`` and ``clients`` the CLI runs (PYTHONPATH, ahead of the editable install's)
TREE = Path(__file__).resolve().parents[1]
CLI = Path(sys.executable).with_name("thrustshape")
if not CLI.exists():
    CLI = Path(shutil.which("thrustshape") or "thrustshape")
KEEP_KEYS = ("verdict", "ambiguous", "message", "blind_spots", "notes", "route", "tolerance", "alignment",
             "calibration", "noise", "units", "rounds", "angle_periodic", "evidence")
ALL_LABELS = [*EFFECTS, *(f"param:{q}" for q in PARAMS)]


def _trim(x: object, limit: int = 4000) -> object:
    """x if its JSON is short, else a truncated string of it."""
    s = json.dumps(x, default=str)
    return x if len(s) <= limit else s[:limit] + "...(truncated)"


def run_one(seed: int, outdir: str, regen: bool, timeout: float = 120.0) -> dict:
    """Generate the case of ``seed`` and run the checker on it; return its record."""
    t0 = time.time()
    csv, par, tru = generate(seed, outdir, regen)
    gen_s = time.time() - t0
    truth = json.loads(Path(tru).read_text())
    rec: dict = dict(seed=seed, kind=truth["kind"], truth=truth["labels"], rate=truth["rate_Hz"],
                     excitation=truth["excitation"]["kind"], parts=truth["excitation"]["parts"],
                     reverses=truth["reverses"], columns=truth["columns"], notes_truth=truth["visibility"]["notes"],
                     gen_s=gen_s, verdict=None, rc=None, error=None)
    cmd = [str(CLI), "diagnose", str(csv), "--params", str(par), "--json"]
    t1 = time.time()
    try:
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (str(TREE), os.environ.get("PYTHONPATH"))))}
        pr = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        rec.update(time_s=time.time() - t1, error=f"timeout {timeout} s")
        return rec
    rec["time_s"] = time.time() - t1
    rec["rc"] = pr.returncode
    err_tail = "\n".join(pr.stderr.strip().splitlines()[-5:])
    rec["stderr_tail"] = err_tail
    if pr.returncode != 0:
        rec["error"] = f"exit {pr.returncode}: {err_tail}"
        return rec
    try:
        out = json.loads(pr.stdout)
    except json.JSONDecodeError as e:
        rec["error"] = f"bad JSON ({e}); stdout head {pr.stdout[:300]!r}"
        return rec
    rec["verdict"] = list(out.get("verdict") or [])
    rec["diagnose"] = {k: _trim(out[k]) for k in KEEP_KEYS if k in out}
    rank = out.get("ranking")
    rec["ranking_head"] = _trim(rank[:5] if isinstance(rank, list) else rank)
    return rec


def band(rate: float) -> str:
    """Logging-rate band name of a rate [Hz]."""
    return "<500Hz" if rate < 500 else ("500Hz-1kHz" if rate <= 1000 else ">1kHz")


def report(recs: list[dict]) -> None:
    """Print the summary tables of the records."""
    done = [r for r in recs if r["verdict"] is not None]
    failed = [r for r in recs if r["verdict"] is None]
    exact = [set(r["verdict"]) == set(r["truth"]) for r in done]
    print(f"cases: {len(recs)}  ran: {len(done)}  crashes/timeouts/nonzero: {len(failed)}")
    if done:
        print(f"exact-verdict rate: {sum(exact)}/{len(done)} = {sum(exact) / len(done):.1%}")
    clean = [r for r in done if not r["truth"]]
    fa = [r for r in clean if r["verdict"]]
    print(f"false alarms on clean logs: {len(fa)}/{len(clean)}")
    print("\nper label:  TP   FP   FN  precision  recall")
    for lab in ALL_LABELS:
        tp = sum(lab in r["truth"] and lab in r["verdict"] for r in done)
        fp = sum(lab not in r["truth"] and lab in r["verdict"] for r in done)
        fn = sum(lab in r["truth"] and lab not in r["verdict"] for r in done)
        if tp + fp + fn == 0:
            continue
        pr = f"{tp / (tp + fp):.2f}" if tp + fp else "  -"
        rc = f"{tp / (tp + fn):.2f}" if tp + fn else "  -"
        print(f"  {lab:18s} {tp:4d} {fp:4d} {fn:4d}  {pr:>9s}  {rc:>6s}")
    other = Counter(lab for r in done for lab in r["verdict"] if lab not in ALL_LABELS)
    if other:
        print(f"  labels outside the catalogue: {dict(other)}")
    for title, key in (("case kind", lambda r: r["kind"]), ("rate band", lambda r: band(r["rate"])),
                       ("excitation", lambda r: r["excitation"])):
        groups: dict[str, list[bool]] = defaultdict(list)
        for r, ok in zip(done, exact, strict=True):
            groups[key(r)].append(ok)
        print(f"\nexact by {title}:")
        for g, oks in sorted(groups.items()):
            print(f"  {g:14s} {sum(oks):3d}/{len(oks):3d} = {sum(oks) / len(oks):.0%}")
    print("\n".join(evidence_table([(e["test"], k in r["truth"]) for r in done
                                     if isinstance(ev := r["diagnose"].get("evidence"), dict) for k, e in ev.items()])))
    ts = sorted(r["time_s"] for r in recs if "time_s" in r)
    if ts:
        print(f"\ntime per log (checker): median {ts[len(ts) // 2]:.1f} s, max {ts[-1]:.1f} s")
    wrong = [r for r, ok in zip(done, exact, strict=True) if not ok]
    print(f"\nwrong verdicts ({len(wrong)}):")
    for r in wrong:
        amb = r.get("diagnose", {}).get("ambiguous")
        if isinstance(amb, list):
            amb = [f"{a.get('adopted')}~{a.get('alternative')}" if isinstance(a, dict) else a for a in amb]
        elif isinstance(amb, str):
            amb = amb[:200]
        print(f"  seed {r['seed']:4d} {r['kind']:12s} {r['rate']:8.1f} Hz {r['excitation']:9s} "
              f"truth={sorted(r['truth'])} verdict={sorted(r['verdict'])}"
              + (f" ambiguous={amb}" if amb else "") + (f" NOTE={r['notes_truth']}" if r["notes_truth"] else ""))
    for r in failed:
        print(f"  FAILED seed {r['seed']} {r['kind']} truth={r['truth']}: {r['error']}")


def main(argv: list[str] | None = None) -> int:
    """CLI entry point."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--dir", default="/work/blindcache")
    ap.add_argument("--json", dest="json_out", default=None)
    ap.add_argument("--regen", action="store_true")
    a = ap.parse_args(argv)
    seeds = list(range(a.first, a.first + a.n))
    with ProcessPoolExecutor(a.procs) as ex:
        futs = [ex.submit(run_one, s, a.dir, a.regen) for s in seeds]
        recs = []
        for s, f in zip(seeds, futs, strict=True):
            try:
                recs.append(f.result())
            except Exception as e:  # generation failure: our bug, record it
                recs.append(dict(seed=s, kind="?", truth=[], rate=0.0, excitation="?", verdict=None,
                                 error=f"generation failed: {e!r}", notes_truth=[]))
            r = recs[-1]
            print(f"seed {s}: truth={r['truth']} verdict={r['verdict']} "
                  f"{r.get('time_s', 0):.1f}s {r.get('error') or ''}", file=sys.stderr, flush=True)
    report(recs)
    if a.json_out:
        Path(a.json_out).write_text(json.dumps(recs, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
