"""What a time-series log exercises, and which effects it therefore cannot show (issue #11, "an effect cannot show in
the log"): :func:`coverage` measures reversals, time at low speed, the range of speeds and of command voltages and
the rows slow enough for an angle ripple; :data:`GAPS` names the effects each missing one hides, which
:func:`ocp.identify.design.design` probes and :func:`blind_spots` reports beside a diagnosis."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, cast

import numpy as np

from ocp.identify.align import ONE_MAGNITUDE, voltage_spread
from ocp.identify.angle import MAX_PERIODS, angle_limits, rotor_angle
from ocp.identify.clipping import clip_spot
from ocp.logs import Log, LogKind

#: the effects and constants each coverage gap hides (the probes :func:`ocp.identify.design.design` adds)
GAPS: dict[str, tuple[str, ...]] = {
    "reversal": ("drag_asymmetry", "thrust_asymmetry", "coulomb_friction", "voltage_deadband", "brush_drop"),
    "forward": ("param:c_tau", "param:c_f"),
    "low_speed": ("coulomb_friction", "stribeck"), "speed_range": ("param:B",), "ripple_reach": ("cogging",),
    "voltage_range": ("voltage_deadband", "brush_drop")}
#: the constants a gain ``a`` on the command (under one voltage magnitude a dead band's ``V0 - v_db``) is taken up by:
#: ``a V`` in the armature equation is ``R / a``, ``L / a`` and ``k / a``, with ``k`` the torque equation's ``J``,
#: ``B``, ``c_tau`` (:mod:`.gain`); as verdict names
COMMON = ("R", "L", "k", "J", "B", "c_tau")
GAIN = tuple(f"param:{c}" for c in COMMON)
#: the regression's pseudo-item for one common error of the constants a gain on the command scales (:mod:`.gain`)
COMMON_GAIN = "command_gain"
#: ... and those a log checked point by point can have (its rows hold no time, angle or voltage levels that count)
ROW_GAPS: dict[str, tuple[str, ...]] = {"reversal": ("drag_asymmetry", "thrust_asymmetry")}
#: the share of the moving rows that must resolve a 64-period ripple (:func:`coverage`): a log near one speed has
#: none; the proposals that revealed a hidden ripple on the proving ground had 3.7-14 % (seeds 0, 2, 6, 9 of
#: :mod:`tests.proving_ground.experiment`), so the gap closes once such an experiment is logged
RIPPLE_ROWS = 0.01
#: a direction the rotor turns on fewer of the rows than this (beyond 5 % of its top speed, :func:`directions`) is not
#: in the log (:func:`unseen`; set once, not tuned)
SEEN_ROWS = 0.01
#: the forward coefficients and the effects that are reverse rotation's departure from them
ASYMMETRY = {"c_tau": "drag_asymmetry", "c_f": "thrust_asymmetry"}
GAP_TEXT = {"reversal": "the log never reverses", "low_speed": "the log spends no time at low speed",
            "speed_range": "the log holds one speed only",
            "forward": "the rotor never turns forward: the forward drag and thrust coefficients are not checked, and "
                       "what reverse rotation shows against them beyond the tolerance is the asymmetry",
            "voltage_range": "the command holds one voltage magnitude (a dead band or a brush drop then acts as a "
                             "gain on it, which the constants take up; the two differ only where the current opposes "
                             "the command: a brush drop named here is reported ambiguous where the dead band fits "
                             "as well)",
            "ripple_reach": f"under {100 * RIPPLE_ROWS:g} % of the moving rows are slow enough to show an angle "
                            f"ripple of {MAX_PERIODS} periods/rev (the log resolves at most {{ripple_periods}} "
                            "periods/rev on half of them)"}


def coverage(log: Log) -> dict[str, Any]:
    """What the log exercises: both directions (a reversal), forward rotation at all (:func:`unseen`), time at low speed
    (< 10 % of its top speed), a range of speeds (10th over 90th percentile of |w| below one half), rows slow enough to
    show an angle ripple of :data:`.angle.MAX_PERIODS` periods/rev (sampled twice a period, ``64 |d theta| < pi``) on at
    least :data:`RIPPLE_ROWS` of the moving rows (``ripple_rows``; ``ripple_periods``: the largest count resolved on
    half of them; an angle integrated from the speed where none is logged), and a range of command voltage magnitudes
    (``voltage_spread``: 10th over 90th percentile of |V| over the rows above 1 % of its peak, below one half): under a
    two-level command (+-V0, or 0 and V0) a dead band's ``V0 - v_db`` and a brush drop's ``V0 - v_b`` (the current
    following the command's sign) are a gain on the command, which ``k`` and ``R`` take up (proving-ground rigs 0..5
    under random +-0.6 V_max steps: the dead band named on none of six, with four levels on all six)."""
    theta = rotor_angle(log)
    step = np.abs(np.diff(theta))
    moving = step[step > 0]
    slow = float(np.mean(MAX_PERIODS * moving < math.pi)) if moving.size else 1.0
    reach = cast(int, angle_limits(theta, MAX_PERIODS, log.theta is not None)["max_resolved_periods"])
    w = np.abs(log.omega)
    pos, neg, low = directions(log.omega)
    spread = float(np.percentile(w, 10) / max(float(np.percentile(w, 90)), 1e-300))
    levels = voltage_spread(log.voltage)
    return {"reversal": min(pos, neg) > 0.05, "forward": pos >= SEEN_ROWS, "low_speed": low > 0.05,
            "speed_range": spread < 0.5, "ripple_reach": slow >= RIPPLE_ROWS, "voltage_range": levels < ONE_MAGNITUDE,
            "forward_fraction": pos, "reverse_fraction": neg, "low_speed_fraction": low, "speed_spread": spread,
            "ripple_rows": slow, "ripple_periods": reach, "voltage_spread": levels}


def unseen(log: Log) -> dict[str, str]:
    """The constants a time-series ``log`` does not exercise, with the reason: the forward drag and thrust
    coefficients where the rotor turns in reverse but never forward (under :data:`SEEN_ROWS` of the rows). The
    model's ``c_tau`` and ``c_f`` are forward rotation's; reverse rotation's are ``c_tau + dc_tau`` and ``c_f + dc_f``
    (:class:`ocp.model.effects.DragAsymmetry`, :class:`ocp.model.effects.ThrustAsymmetry`). On such a log the two
    constants' columns are the asymmetries' own, and a mismatch there is reverse rotation departing from the nominal
    forward values: the asymmetry. Named, the constant would claim a forward error the log never saw (the blind rig,
    ``bench/blind_check.py``, seeds 151 and 162: reverse drag 44 % high and reverse thrust 31 % low, on logs turning in
    reverse only, came back as ``c_tau`` and ``c_f`` errors). They are never named: a model without the asymmetry
    calibrates them within the tolerance (the nominal values' own error, which an asymmetry must not be named for),
    one with it holds them at nominal, the asymmetry taking all of reverse rotation's departure (the two columns are
    one on these rows: any split would be arbitrary) (:attr:`.regression.Design.unseen`, :func:`.lsq.solve`)."""
    if log.kind is not LogKind.TIME_SERIES:
        return {}
    pos, neg, _ = directions(log.omega)
    if pos >= SEEN_ROWS or neg < SEEN_ROWS:
        return {}
    why = (f"the rotor never turns forward ({100 * pos:.2g} % of the rows): the forward coefficient is not in this "
           "log and is never named (calibrated within the tolerance, or at nominal beside the asymmetry, which takes "
           "what reverse rotation shows beyond it)")
    return dict.fromkeys(ASYMMETRY, why)


def unseen_rivals(unseen_: dict[str, str], verdict: Sequence[str], score: float) -> list[dict[str, Any]]:
    """Ambiguities (as :func:`ocp.identify.diagnose`'s ``ambiguous``) for each asymmetry ``verdict`` names whose
    forward coefficient the log does not exercise (``unseen_``, :func:`unseen`): that constant off in both directions
    fits the log identically (one column on these rows; ``score`` [noise units] both). The asymmetry is the one named:
    the nominal coefficients are forward rotation's (a propeller's data), and reverse rotation departing from them is
    the propeller's asymmetry more often than a wrong forward value; a run that turns forward tells them apart (the
    blind rig's fresh seeds 200..399 drew four such constants and three such asymmetries on reverse-only logs)."""
    return [{"adopted": effect, "alternative": f"param:{const}", "score": score, "alternative_score": score,
             "reason": f"the rotor never turns forward: {const} off in both directions and {effect} (reverse rotation "
                       "only) are one column on these rows and fit the log identically; the asymmetry is named, the "
                       f"nominal {const} being forward rotation's; a run that turns forward tells them apart"}
            for const, effect in ASYMMETRY.items() if const in unseen_ and effect in verdict]


def directions(omega: np.ndarray) -> tuple[float, float, float]:
    """The fractions of the rows (N,) of ``omega`` [rad/s] turning forward and in reverse (beyond 5 % of the top
    speed, the 99th percentile of |w|), and slowly (under 10 % of it)."""
    w = np.abs(omega)
    top = float(np.percentile(w, 99)) or 1.0
    return float(np.mean(omega > 0.05 * top)), float(np.mean(omega < -0.05 * top)), float(np.mean(w < 0.1 * top))


def blind_spots(log: Log, named: Sequence[str] = (), rows: bool = False, gain: bool = False,
                cov: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """Per coverage gap of ``log`` (:func:`coverage`): ``gap``, why (``text``), the effects and constants it hides
    (``hidden``, catalogue names or ``param:<key>``, those ``named`` left out: a verdict's, shown after all) and
    whether ``design-experiment`` probes it (``design``: a time series); a verdict without them says nothing about
    them. ``rows``: a log checked point by point (a sweep, an ESC rig, a flight log: no time, maybe no armature
    voltage), where only the direction counts: turning one way only, it cannot show a drag or thrust asymmetry
    (:data:`ROW_GAPS`). ``gain``: one gain on the command fits the named corrections as well (:mod:`.gain`); on one
    voltage magnitude the text says whether the corrections named among :data:`GAIN` are that gain. ``cov``: the
    log's :func:`coverage`, where the caller has it. A clipped current (:mod:`.clipping`) is said too, hiding
    nothing (``hidden`` empty: its rows are left out)."""
    if rows:
        pos, neg, _ = directions(log.omega)
        cov, table = {"reversal": min(pos, neg) > 0.05}, ROW_GAPS
    else:
        cov, table = cov or coverage(log), GAPS
    taken = [n for n in named if n in GAIN]  # a one-magnitude command's gain, taken up as corrections?
    said = "" if not taken else f"; the corrections named here ({', '.join(taken)}) " + (
        "fit as one gain on it (listed under ambiguous)" if gain else "are not that gain alone (held-out fit)")
    spots = [(g, text + (said if g == "voltage_range" else ""), [h for h in hidden if h not in named])
             for g, text, hidden in open_gaps(cov, table)]
    clip = None if rows else clip_spot(log.current)  # (no effect hidden: the rows are left out, said here)
    return [{"gap": g, "text": text, "hidden": hidden, "design": not rows} for g, text, hidden in spots if hidden] + \
        ([clip] if clip else [])


def open_gaps(cov: dict[str, Any], table: dict[str, tuple[str, ...]] = GAPS) -> list[tuple[str, str, tuple[str, ...]]]:
    """The gaps of ``table`` that ``cov`` (:func:`coverage`) leaves open: each one's name, why, what it hides. A rotor
    turning in reverse only shows the asymmetries, against the nominal forward coefficients (:func:`unseen`): its
    reversal gap does not hide them."""
    shown = set(ASYMMETRY.values()) if cov.get("forward") is False and cov["reverse_fraction"] >= SEEN_ROWS else set()
    return [(g, GAP_TEXT[g].format(**cov), tuple(h for h in table[g] if h not in shown)) for g in table if not cov[g]]
