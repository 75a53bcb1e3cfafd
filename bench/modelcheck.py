"""Model-check proving ground: diagnose many logs from rigs and loggers this project's identifier never saw.

Each case comes from ``tests/proving_ground`` (its own physics, integrator, loggers; see that package):
a 5 W .. 500 W motor, a 50 Hz .. 10 kHz logger with command skew, encoder or tachometer, filtered current,
quantisation and noise, one to three excitations, and clean / one effect / two effects / a wrong constant /
an effect and a wrong constant. ``thrustshape``'s :func:`ocp.identify.diagnose` gets the log and the
nominal constants; its verdict is compared with the truth.

    python bench/modelcheck.py                 # 200 logs, seeds 0..199, 2 processes
    python bench/modelcheck.py --n 40 --first 1000   # a tuning set (keep tuning seeds apart from these)
    python bench/modelcheck.py --n 100 --first 1000 --cache /tmp/pg   # keep generated logs for the next run
    python bench/modelcheck.py --n 200 --first 2000 --json new.json   # every record, for the two below
    python bench/modelcheck.py --seeds 6003 9204 10014 --json few.json   # a chosen class of logs, before and after
    python bench/modelcheck.py --records a.json b.json   # the table of recorded runs (merged), nothing diagnosed
    python bench/modelcheck.py --compare old.json new.json   # seed by seed: the logs a change fixed and broke
    python bench/modelcheck.py --n 200 --first 2000 --noise-free --json quiet.json   # the same logs without noise
    python bench/modelcheck.py --n 200 --first 2000 --no-angle --json speed.json   # encoders exported without angle
    python bench/modelcheck.py --n 200 --first 2000 --shapes --json shaped.json   # friction/ripple off-catalogue
    python bench/modelcheck.py --n 200 --first 3000 --kind constant --json c.json   # every draw of one kind
    python bench/modelcheck.py --records a.json --audit --cache DIR --json a+.json   # + the labels' audit (below)

``--audit``: each label's footprint left after calibration (:mod:`tests.proving_ground.calibration`: the proving
ground's own replays, the rig without the label corrected within the tolerance, the logging conventions' lag, the
current filter and the other labels' amplitudes); a label under the proving ground's ``VISIBLE`` there is optional: the
log is reproduced without it by corrections a check makes without naming anything, so a verdict is right with or
without it. The table is then printed twice: on the labels as drawn, and with those labels optional.

Prints: verdicts exactly right, false alarms on clean logs, per label (effect or named constant)
precision and recall with counts, time per log (diagnose only, and generating), and the alignment's error against
the drawn command lag (logs without a delay, by the armature's L/R in samples and by the current filter), and the
noise levels the diagnosis read against the logger's own (regular clocks and jittered ones apart).
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import itertools
import json
import math
import multiprocessing
import pickle
import statistics
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


#: the proving ground's modules that make a case (:func:`tests.proving_ground.make_case` imports no other)
GENERATOR = ("__init__.py", "cases.py", "excite.py", "logger.py", "physics.py")


def generator_stamp() -> str:
    """Digest (12 hex) of the modules that generate a case (:data:`GENERATOR`): a cached log is read back only by
    the generator that wrote it (session 14 changed the rig's integrator; a flat cache would have served the old
    logs without a word). The proving ground's other modules (experiment rigs for tests) do not make cases."""
    h = hashlib.sha256()
    for name in GENERATOR:
        h.update(name.encode() + (ROOT / "tests" / "proving_ground" / name).read_bytes())
    return h.hexdigest()[:12]


def _prefix(shapes: bool, kind: str | None) -> str:
    """A cached file's name prefix: a shaped case or one of a forced kind is another draw than the seed's own."""
    return ("shaped-" if shapes else "") + (f"{kind}-" if kind else "")


def load_case(seed: int, cache: str | None, shapes: bool = False, kind: str | None = None) -> Any:
    """Proving-ground case ``seed``, generated, or read from (and written to) the ``cache`` folder (under the
    generator's :func:`generator_stamp`); ``shapes``: with friction and ripple shapes outside the catalogue
    (:func:`tests.proving_ground.cases.draw_shape`); ``kind``: of this kind (``make_case``'s), not the seed's draw."""
    from tests.proving_ground import make_case

    if cache is None:
        return make_case(seed, kind, shapes=shapes)
    path = Path(cache) / generator_stamp() / f"{_prefix(shapes, kind)}case-{seed}.pkl"
    if path.exists():
        return pickle.loads(path.read_bytes())
    case = make_case(seed, kind, shapes=shapes)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(pickle.dumps(case))
    return case


def noise_free(case: Any) -> Any:
    """``case`` with its log recorded again by a logger with no sensor noise, quantisation or time-stamp jitter
    (its rate, skew, speed sensor and current filter kept): the rig replayed under the logged commands (the same
    run; a PI loop's commands are as issued). What the identifier gets wrong there, its equations get wrong, not
    the noise (the expected verdict stands: an effect visible against the noise is the more visible without)."""
    from dataclasses import replace

    import numpy as np

    from tests.proving_ground.cases import _replay
    from tests.proving_ground.logger import record

    quiet = replace(case.logger, noise_w=0.0, noise_i=0.0, q_i=1e-9, noise_f=0.0, q_f=1e-9, counts=2**40, jitter=0.0)
    cmds = case.columns["voltage"]
    out = _replay(case.truth, cmds, case.logger, case.meta["tau_m"])
    return replace(case, columns=record(quiet, out, cmds, np.random.default_rng(case.seed)), logger=quiet)


def case_log(case: Any, angle: bool = True) -> Any:
    """The case's log as :func:`ocp.logs.log_from_arrays` reads it (a jittery logger's time stamps resampled to a
    uniform grid, as the file readers do, and say); ``angle=False``: without the encoder's angle column, as a logger
    that exports only the speed it differenced writes it."""
    from ocp.logs import log_from_arrays
    from ocp.logs.timebase import uniform

    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    return log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"],
                           theta=c.get("theta") if angle else None, source=f"proving-ground-{case.seed}")


def one(seed: int, cache: str | None = None, quiet: bool = False, angle: bool = True,
        shapes: bool = False, kind: str | None = None) -> dict[str, Any]:
    """Generate case ``seed`` (or read it from ``cache``) and diagnose it (``quiet``: its log recorded without
    noise, :func:`noise_free`; ``angle=False``: without its angle column, :func:`case_log`; ``shapes``, ``kind``:
    see :func:`load_case`); a JSON-ready record."""
    from ocp.identify import diagnose
    from ocp.identify.coverage import COMMON_GAIN
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant
    from tests.proving_ground.logger import noise_levels

    t0 = time.perf_counter()
    case = load_case(seed, cache, shapes, kind)
    if quiet:
        case = noise_free(case)
    t1 = time.perf_counter()
    log = case_log(case, angle)
    try:
        res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
        verdict, err = sorted(res.verdict), None
        align = res.alignment.samples if res.alignment else 0.0
        measured = bool(res.alignment and res.alignment.identified)
        amb = bool(res.ambiguous)
        gain = next((float(a["relative"]) for a in res.ambiguous if a["alternative"] == COMMON_GAIN), None)
        evidence = {k: e["test"] for k, e in res.evidence.items()}
        pairs = [[str(a["adopted"]), str(a["alternative"])] for a in res.ambiguous]
        # the noise levels read, over the logger's own (its white noise and ADC steps; a noise-free log has none)
        noise = None if quiet else {ch: res.noise[ch] / float(level) for ch, level in
                                    zip(NOISE_CHANNELS, noise_levels(case.logger), strict=True)}
    except Exception as exc:  # a crash is a wrong verdict, recorded with its message
        verdict, err, align, amb, measured, gain = [], f"{type(exc).__name__}: {exc}", 0.0, False, False, None
        evidence, pairs, noise = {}, [], None
    t2 = time.perf_counter()
    lag = case.logger.skew + case.truth.e("input_delay", "delay") / case.logger.dt
    return {"seed": seed, "kind": case.kind, "expected": sorted(case.expected), "verdict": verdict, "error": err,
            "ambiguous": amb, "gain": gain, "evidence": evidence, "rate": case.logger.rate, "n": log.n,
            "speed": case.logger.speed, "excitations": list(case.excitations), "true_lag": lag, "alignment": align,
            "align_measured": measured, "armature": case.nominal["L"] / case.nominal["R"] / case.logger.dt,
            "current_filter": (1.0 - case.logger.alpha) / case.logger.alpha,
            "constant_error": case.constant_error, "t_generate": t1 - t0, "t_diagnose": t2 - t1, "noise_free": quiet,
            "angle": log.theta is not None, "shapes": shapes, "forced_kind": kind, "pairs": pairs,
            "jitter": case.logger.jitter, "noise_ratio": noise}


def audit_stamp() -> str:
    """Digest (12 hex) of the generator and the audit (:func:`tests.proving_ground.calibration.audit`)."""
    return hashlib.sha256((generator_stamp() + (ROOT / "tests" / "proving_ground" / "calibration.py")
                           .read_text(encoding="utf-8")).encode()).hexdigest()[:12]


def audit(seed: int, cache: str | None, shapes: bool = False, kind: str | None = None) -> dict[str, list[float]]:
    """Case ``seed``'s labels' footprints after calibration (noise levels (3,) each), read from (and written to)
    ``cache`` under :func:`audit_stamp` (``shapes``, ``kind``: of :func:`load_case`'s case)."""
    from tests.proving_ground.calibration import audit as footprints

    path = Path(cache) / generator_stamp() / f"audit-{audit_stamp()}" / f"{_prefix(shapes, kind)}{seed}.json" \
        if cache else None
    if path is not None and path.exists():
        return dict(json.loads(path.read_text(encoding="utf-8")))
    out = footprints(load_case(seed, cache, shapes, kind))
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(out), encoding="utf-8")
    return out


def audited(r: dict[str, Any], cache: str | None) -> dict[str, Any]:
    """Record ``r`` with its labels' audit: ``footprints`` and ``required`` (the labels that show beyond
    calibration, :func:`tests.proving_ground.calibration.required`; the others are optional)."""
    from tests.proving_ground.calibration import required

    fp = audit(r["seed"], cache, bool(r.get("shapes")), r.get("forced_kind"))
    return {**r, "footprints": fp, "required": sorted(required(r["expected"], fp))}


def right(r: dict[str, Any], optional: bool = False) -> bool:
    """Whether record ``r``'s verdict is exactly the truth (``optional``: holds its ``required`` labels and no label
    it was not drawn with)."""
    v = set(r["verdict"])
    return set(r["required"]) <= v <= set(r["expected"]) if optional else v == set(r["expected"])


def table(rows: list[dict[str, Any]], optional: bool = False) -> str:
    """The confusion summary as text (``optional``: the labels an audit found optional count neither way)."""
    exact = sum(right(r, optional) for r in rows)
    clean = [r for r in rows if not r["expected"]]
    alarms = sum(bool(r["verdict"]) for r in clean)
    tp: Counter[str] = Counter()
    fp: Counter[str] = Counter()
    fn: Counter[str] = Counter()
    for r in rows:
        e, v = set(r["expected"]), set(r["verdict"])
        tp.update(e & v)
        fp.update(v - e)
        fn.update(set(r["required"] if optional else e) - v)
    labels = sorted(set(tp) | set(fp) | set(fn))
    td = sorted(r["t_diagnose"] for r in rows)
    lines = [f"logs: {len(rows)}   verdicts exactly right: {exact}/{len(rows)} ({100 * exact / len(rows):.1f} %)",
             f"clean logs: {len(clean)}   false alarms: {alarms}   "
             f"crashes: {sum(r['error'] is not None for r in rows)}",
             f"time per log (diagnose): median {td[len(td) // 2]:.2f} s, max {td[-1]:.2f} s;   generating: "
             f"median {sorted(r['t_generate'] for r in rows)[len(rows) // 2]:.2f} s",
             "", f"{'label':22s} {'TP':>4s} {'FP':>4s} {'FN':>4s} {'precision':>9s} {'recall':>7s}"]
    for lb in labels:
        p = tp[lb] / (tp[lb] + fp[lb]) if tp[lb] + fp[lb] else float("nan")
        rc = tp[lb] / (tp[lb] + fn[lb]) if tp[lb] + fn[lb] else float("nan")
        lines.append(f"{lb:22s} {tp[lb]:4d} {fp[lb]:4d} {fn[lb]:4d} {100 * p:8.1f}% {100 * rc:6.1f}%")
    kinds = Counter(r["kind"] for r in rows)
    ok = Counter(r["kind"] for r in rows if right(r, optional))
    lines += ["", "by case kind: " + ", ".join(f"{k} {ok[k]}/{kinds[k]}" for k in sorted(kinds))]
    gains = [r for r in rows if r.get("gain") is not None]  # (records before session 42 have none)
    lines += [f"a gain on the command listed beside the verdict (ocp.identify.gain): {len(gains)} logs"
              + "".join(f"; {r['seed']} ({'+'.join(r['expected']) or 'clean'}: {100 * r['gain']:+.0f} %)"
                        for r in gains)]
    named = [(test, label in r["expected"]) for r in rows for label, test in r.get("evidence", {}).items()]
    return "\n".join(lines + evidence_table(named) + alignment_table(rows) + noise_table(rows))


def evidence_table(named: list[tuple[str, bool]]) -> list[str]:
    """Per test a name won by (:mod:`ocp.identify.strength`), how many names it won and how many of them were
    drawn, from ``named`` (test, drawn) pairs, one per name in a verdict (none, as in records written before session
    68: no lines)."""
    from ocp.identify.strength import STRONG

    won, drawn = Counter(t for t, _ in named), Counter(t for t, ok in named if ok)
    lines = ["", "names by the test they won beside the others (ocp/identify/strength.py):",
             f"{'test':20s} {'strength':8s} {'named':>6s} {'drawn':>6s} {'precision':>9s}"]
    for group in (True, False):
        word = "strong" if group else "weak"
        tests = [t for t in STRONG if STRONG[t] is group and won[t]]
        lines += [f"{t:20s} {word:8s} {won[t]:6d} {drawn[t]:6d} {100 * drawn[t] / won[t]:8.1f}%" for t in tests]
        n, ok = sum(won[t] for t in tests), sum(drawn[t] for t in tests)
        lines += [f"{'all ' + word:29s} {n:6d} {ok:6d} {100 * ok / n:8.1f}%"] if n else []
    return lines if named else []


#: the nominal armature time constants L/R [samples] the alignment's errors are grouped by (:func:`alignment_table`)
ARMATURE_BINS = (0.0, 0.5, 2.0, 7.0, math.inf)


def alignment_table(rows: list[dict[str, Any]]) -> list[str]:
    """The alignment's error, found minus drawn command lag [samples], on the logs without a transport delay whose
    lag ``diagnose`` measured, by the nominal armature time constant L/R [samples] and by the current filter
    (records without ``armature``, written before it was recorded, are left out; none: no lines)."""
    rec = [r for r in rows if "armature" in r and r["error"] is None and "input_delay" not in r["expected"]]
    if not rec:
        return []
    seen = [r for r in rec if r["align_measured"]]
    lines = ["", f"alignment (found - drawn lag [samples]) on the {len(seen)} of {len(rec)} logs without a delay "
             f"whose lag was measured:", f"{'':24s} {'logs':>5s} {'median |e|':>10s} {'mean e':>7s} {'|e|>0.5':>7s} "
             f"{'|e|>1':>6s}"]
    groups = [(f"L/R {lo:g}-{hi:g} samples", [r for r in seen if lo <= r["armature"] < hi])
              for lo, hi in itertools.pairwise(ARMATURE_BINS)]
    groups += [("no current filter", [r for r in seen if r["current_filter"] == 0.0]),
               ("current filter", [r for r in seen if r["current_filter"] > 0.0]), ("all", seen)]
    for name, grp in groups:
        e = [r["alignment"] - r["true_lag"] for r in grp]
        if not e:
            continue
        a = [abs(x) for x in e]
        lines.append(f"{name:24s} {len(e):5d} {statistics.median(a):10.2f} {sum(e) / len(e):+7.2f} "
                     f"{sum(x > 0.5 for x in a):7d} {sum(x > 1.0 for x in a):6d}")
    return lines


#: the channels of a record's ``noise_ratio`` (:func:`one`), in the order of the proving ground's ``noise_levels``
NOISE_CHANNELS = ("omega", "current", "thrust")


def noise_table(rows: list[dict[str, Any]]) -> list[str]:
    """The noise levels ``diagnose`` read over the logger's own (records' ``noise_ratio``; records written before it
    was recorded and noise-free ones are left out; none: no lines), per channel the median ratio and the share within
    10 %, on the logs with a regular clock and on those whose jittered time stamps the reader resampled."""
    rec = [r for r in rows if r.get("noise_ratio")]
    if not rec:
        return []
    lines = ["", "noise levels read / the logger's own (median ratio, share within 10 %):",
             f"{'':24s} {'logs':>5s}" + "".join(f" {ch:>16s}" for ch in NOISE_CHANNELS)]
    for name, grp in (("regular clock", [r for r in rec if not r["jitter"]]),
                      ("jittered, resampled", [r for r in rec if r["jitter"]])):
        if grp:
            cells = [(statistics.median(r["noise_ratio"][ch] for r in grp),
                      sum(abs(math.log(r["noise_ratio"][ch])) < math.log(1.1) for r in grp) / len(grp))
                     for ch in NOISE_CHANNELS]
            lines.append(f"{name:24s} {len(grp):5d}" + "".join(f" {m:9.2f} {100 * w:4.0f} %" for m, w in cells))
    return lines


def compare(old: list[dict[str, Any]], new: list[dict[str, Any]]) -> str:
    """Seed by seed over the seeds both recorded runs hold: each log whose verdict changed (FIXED: now exactly
    right, BROKE: no longer, CHANGED: wrong either way), then the exact verdicts and the false alarms on clean logs
    before and after (how a change to the identifier is judged: no set's total falls, no clean log gains a verdict)."""
    a, b = ({r["seed"]: r for r in rows} for rows in (old, new))
    seeds = sorted(set(a) & set(b))
    lines = []
    for s in (s for s in seeds if set(a[s]["verdict"]) != set(b[s]["verdict"])):
        tag = "FIXED" if right(b[s]) and not right(a[s]) else "BROKE" if right(a[s]) and not right(b[s]) else "CHANGED"
        lines.append(f"{tag:8s}{s:6d} {b[s]['kind']:13s} expected {b[s]['expected']} {a[s]['verdict']} -> "
                     f"{b[s]['verdict']} rate {b[s]['rate']:g} {b[s]['excitations']}")
    alarms = lambda d: sum(1 for s in seeds if not d[s]["expected"] and d[s]["verdict"])  # noqa: E731
    lines.append(f"{len(seeds)} logs: exactly right {sum(right(a[s]) for s in seeds)} -> "
                 f"{sum(right(b[s]) for s in seeds)}, false alarms on clean logs {alarms(a)} -> {alarms(b)}")
    return "\n".join(lines)


def _records(paths: list[str]) -> list[dict[str, Any]]:
    rows = {r["seed"]: r for p in paths for r in json.loads(Path(p).read_text(encoding="utf-8"))}
    return [rows[s] for s in sorted(rows)]


def _run(seeds: list[int], args: argparse.Namespace) -> list[dict[str, Any]]:
    """Every seed's record (:func:`one`) in ``args.procs`` processes, by seed."""
    with multiprocessing.get_context("spawn").Pool(args.procs) as pool:
        rows = []
        job = functools.partial(one, cache=args.cache, quiet=args.noise_free, angle=not args.no_angle,
                                shapes=args.shapes, kind=args.kind)
        for k, r in enumerate(pool.imap_unordered(job, seeds), 1):
            rows.append(r)
            print(f"\r{k}/{len(seeds)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return sorted(rows, key=lambda r: r["seed"])


def seeds(args: argparse.Namespace) -> list[int]:
    """The seeds a run diagnoses: ``--seeds`` (sorted, once each), else ``--n`` from ``--first``."""
    return sorted(set(args.seeds)) if args.seeds else list(range(args.first, args.first + args.n))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=200, help="number of logs")
    ap.add_argument("--first", type=int, default=0, help="first seed (tuning: use seeds >= 1000)")
    ap.add_argument("--seeds", type=int, nargs="+", metavar="SEED", help="these seeds instead of --n/--first (a class "
                    "of logs, e.g. those with a label drawn, judged before and after a change)")
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--json", default=None, help="write every record here")
    ap.add_argument("--cache", default=None,
                    help="folder of generated logs: read a seed's log from it, write it there when missing "
                         "(only the diagnosis is then timed afresh), in a subfolder named by the generator's "
                         "source digest: a changed proving ground writes new logs")
    ap.add_argument("--misses", action="store_true", help="list the wrong verdicts")
    ap.add_argument("--noise-free", action="store_true",
                    help="diagnose each log recorded again without sensor noise, quantisation or jitter (compare "
                         "with a run on the logs as generated: the misses that stay are the identifier's equations)")
    ap.add_argument("--no-angle", action="store_true",
                    help="diagnose each encoder log without its angle column (many loggers export only the speed "
                         "they differenced; compare with a run on the logs as generated)")
    ap.add_argument("--shapes", action="store_true",
                    help="Stribeck friction and ripples shaped unlike the identifier's catalogue (a decay exponent "
                         "0.5-2 for its Gaussian, harmonics at 2 and 3 times a ripple's count; other logs as without)")
    ap.add_argument("--kind", choices=("clean", "one", "two", "constant", "constant+one"), default=None,
                    help="every log of this kind (the seed draws the rest; other draws than the seeds' own)")
    ap.add_argument("--records", nargs="+", metavar="JSON", help="print the table of these recorded runs (--json "
                    "files, merged by seed) instead of diagnosing")
    ap.add_argument("--audit", action="store_true", help="audit every label (module doc; slow: ~10 s a label, "
                    "kept in --cache) and print the table with the optional labels too")
    ap.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"), help="compare two recorded runs seed by seed")
    args = ap.parse_args(argv)
    if args.compare:
        print(compare(*(_records([p]) for p in args.compare)))
        return 0
    t0 = time.perf_counter()
    rows = _records(args.records) if args.records else _run(seeds(args), args)
    if args.audit:
        with multiprocessing.get_context("spawn").Pool(args.procs) as pool:
            rows = pool.map(functools.partial(audited, cache=args.cache), rows)
    print(table(rows))
    if all("required" in r for r in rows):
        hidden = [(r["seed"], i) for r in rows for i in r["expected"] if i not in r["required"]]
        print(f"\nwith the labels calibration absorbs optional ({len(hidden)} of "
              f"{sum(len(r['expected']) for r in rows)}: {', '.join(f'{s}:{i}' for s, i in hidden) or 'none'}):")
        print(table(rows, optional=True))
    if not args.records:
        print(f"wall time {time.perf_counter() - t0:.0f} s with {args.procs} processes")
    if args.misses:
        for r in rows:
            if not right(r):
                print(f"  seed {r['seed']:4d} {r['kind']:13s} expected {r['expected']} got {r['verdict']} "
                      f"rate {r['rate']:g} lag {r['true_lag']:.2f}->{r['alignment']:.2f} {r['excitations']} "
                      f"{r['constant_error'] or ''} {r['error'] or ''}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
