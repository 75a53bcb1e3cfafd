"""The model-check answers as text: a check's points and equations, the alignment, a diagnosis (its evidence,
calibration and angle ripple), as ``thrustshape check``, ``diagnose`` and ``fit`` print them."""

from __future__ import annotations

from typing import Any

from clients.cli.io import fmt_number as _g


def print_points(d: dict[str, Any]) -> None:
    """A point-by-point check: residual RMS per equation, forward and reverse (text output)."""
    print(f"{d['one_step']['label']}, RMS by direction:")
    for eq, dirs in d["breakdown"]["direction"].items():
        unit = d["one_step"]["units"][eq]
        parts = [f"{k} {_g(v['rms'], '.4g')} {unit} ({_g(v['relative_rms'], '.1%')} of measured, n={v['n']})"
                 for k, v in dirs.items()]
        print(f"  {eq:10s} " + "; ".join(parts))
    drive = d.get("drive") or {}
    if drive:
        print(f"  drive: efficiency {_g(drive.get('efficiency'), '.3f')}, "
              f"idle power {_g(drive.get('idle_power_W'), '.3g')} W")


def _kept(c: dict[str, Any]) -> str:
    """A calibration row's note where the plant does not take the fitted value (``applied`` is not ``relative``, or
    the log gave no estimate: ``relative`` null)."""
    a, r = c.get("applied"), c.get("relative")
    if not isinstance(a, int | float) or (isinstance(r, int | float) and abs(a - r) <= 1e-12):
        return ""
    free = c.get("apparent")  # (its free column, quoted within a factor two of nominal: beyond, an artefact's value)
    reads = f"; its free column reads {100 * free:+.1f} %" if isinstance(free, int | float) and 0.5 <= 1 + free <= 2 \
        else ""
    keeps = "nominal" if a == 0 else f"{100 * a:+.1f} %"
    return f"  (not resolved by this log: the plant keeps {keeps}{reads})"


def print_equations(d: dict[str, Any]) -> None:
    """The equations checked and those that could not be, with why (text output)."""
    for note in d.get("notes", []):
        print(f"  read: {note}")
    print("equations:")
    for e in d.get("equations", []):
        mark = "checked    " if e["checked"] else "not checked"
        print(f"  {mark} {e['equation']:10s} {e.get('uses') or e.get('reason')}")
    for name, m in (d.get("maps") or {}).items():
        print(f"  {name} map per direction: forward {_g(m['forward'], '.4g')}, reverse {_g(m['reverse'], '.4g')} "
              f"{m['units']}; reverse/forward {_g(m['ratio_reverse_to_forward'], '.3f')}")
    ratio = (d.get("fitted_maps") or {}).get("thrust_ratio_reverse_to_forward")
    if ratio is not None:
        print(f"  fitted plant: reverse/forward thrust coefficient {_g(ratio, '.3f')}")


def print_alignment(d: dict[str, Any], rule: bool = False) -> None:
    """The command-to-sensor alignment of a check, fit or diagnosis (its ``alignment``), when it has one."""
    al = d.get("alignment")
    if not al:
        return
    a = al.get("applied_samples")  # (the lag the equations moved the command by, where it differs)
    moved = "" if a is None or abs(a - al["samples"]) < 0.005 else f"; the equations moved it {_g(a, '.2f')}"
    print(f"alignment: command acts {_g(al['samples'], '.2f')} samples ({_g(1e3 * al['seconds'], '.3g')} ms) after "
          f"its row{' -> input_delay' if al['called_input_delay'] else ' (removed: logging convention)'}{moved}")
    if rule:
        print(f"  rule: {al['rule']}")


def print_diagnosis(d: dict[str, Any]) -> None:
    print("nothing missing" if not d["verdict"] else "missing: " + ", ".join(d["verdict"]))
    print("".join(f"  {text}\n" for text in d["explanations"]), end="")
    _print_evidence(d.get("evidence") or {})
    for a in d.get("ambiguous") or []:
        print(f"ambiguous: {a['adopted']} or {a['alternative']}: {a['reason']}")
    for b in d.get("blind_spots") or []:
        print((f"this log cannot show {', '.join(b['hidden'])}: " if b["hidden"] else "note: ") + b["text"]
              + (" (design-experiment proposes a run that can)" if b.get("design") else ""))
    print_alignment(d, rule=True)
    cal = d.get("calibration") or {}
    if cal:
        print(f"calibration (refinements within {100 * d.get('tolerance', 0.1):.0f} % stay here; beyond it a constant "
              "is named in the verdict):" + ("\n  none applied: the nominal constants as given predict the held-out "
              "rows better than any refinement" if any(c.get("as_given") for c in cal.values()) else ""))
        for k, c in cal.items():  # (a constant the log cannot resolve has no estimate: "-")
            est = isinstance(c["relative"], int | float)
            fitted, rel = ((_g(c["fitted"], ".4g"), _g(100 * c["relative"], "+6.1f") + " %") if est
                           else ("-", "     -  "))
            print(f"  {k:6s} {_g(c['nominal'], '.4g'):>10s} -> {fitted:>10s} {c['unit']:16s} "
                  f"{rel}{'  NAMED' if c['named'] else ''}{_kept(c)}")
        print("".join(f"  {k}: {c['unresolved']}\n" for k, c in cal.items() if c.get("unresolved")), end="")
    ap = d.get("angle_periodic")
    if ap:
        print(f"angle-periodic torque: best fit at {ap['periods']} periods/rev, "
              f"amplitude {_g(ap['amplitude'], '.3g')} N m, explaining {_g(100 * ap['share'], '.0f')} % of the "
              f"held-out torque residual (median over 1..64: {_g(100 * ap['median_share'], '.0f')} %)"
              + ("" if "cogging" in d["verdict"] else f"; not named: {ap['unnamed']}"))
        if ap.get("rivals"):
            tracked = ap.get("max_tracked_periods")
            why = (f"beyond {tracked} periods/rev the integrated angle drifts faster than a ripple's phase can be "
                   "followed" if tracked is not None and ap["periods"] > tracked else
                   "a rotor resting at a few angles shows the torque there, not its period")
            print(f"  the count is not decided by this log: {rivals_text(ap['rivals'])} explain the held-out torque "
                  f"as well ({why})")
        if ap.get("note"):
            print(f"  {ap['note']}")
    print("ranking (held-out error reduction):")
    for e in d["ranking"][:8]:
        imp = 100 * e["improvement"] if isinstance(e["improvement"], int | float) else None
        print(f"  {e['effect']:18s} {_g(imp, '6.1f'):>6s} %  {'significant' if e['significant'] else ''}")
    print_equations(d)


def _print_evidence(evidence: dict[str, Any]) -> None:
    """How each name won (:mod:`ocp.identify.strength`): one line, each name's test and the held-out error of the
    equations it enters without and with it, then what each weak name won by."""
    if evidence:
        print("evidence: " + "; ".join(f"{k} {'strong' if e['strong'] else 'WEAK'} ({e['test']}"
                                       + (f", z {_g(e['z'], '.3g')}" if e.get("z") is not None else "")
                                       + _heldout(e.get("heldout") or {}) + ")" for k, e in evidence.items()))
    print("".join(f"  weak: {k} wins {e['says']}\n" for k, e in evidence.items() if not e["strong"]), end="")


def _heldout(heldout: dict[str, list[float]]) -> str:
    """``; held out: thrust 1.40 -> 1.00 noise units``: per equation, the held-out RMS without and with the name."""
    pairs = ", ".join(f"{eq} {_g(a, '#.3g')} -> {_g(b, '#.3g')}" for eq, (a, b) in heldout.items())
    return f"; held out: {pairs} noise units" if pairs else ""


def rivals_text(counts: list[int]) -> str:
    """``[3, 4, 5, 9]`` -> "3-5 and 9 periods/rev" (runs of consecutive counts joined)."""
    parts = runs(counts)
    return (", ".join(parts[:-1]) + " and " + parts[-1] if len(parts) > 1 else parts[0]) + " periods/rev"


def runs(counts: list[int]) -> list[str]:
    """Ascending counts as runs: ``[3, 4, 5, 9, 11, 12]`` -> ``["3-5", "9", "11, 12"]`` (three or more joined)."""
    out: list[list[int]] = []
    for n in counts:
        if out and n == out[-1][-1] + 1:
            out[-1].append(n)
        else:
            out.append([n])
    return [f"{r[0]}-{r[-1]}" if len(r) > 2 else ", ".join(map(str, r)) for r in out]
