"""Sign conventions: whether a channel of a time series is logged with the opposite sign to the motor model's
(a current sensor or shunt amplifier mounted the other way, an encoder counting the other way, a load cell
pushing instead of pulling, a drive whose positive command turns the rotor backwards).

A negated channel is no effect any catalogue explains: the check would name whatever takes up a residual the size
of the signal itself (a negated current came back as a brush drop, ``J`` and a dead band at 100-800 noise units).
Each equation's nominal terms are projected on its measured side with a free scale, ``beta`` (about 1 where the
signs agree, whatever the constants' errors; about -1 where they do not), on the low-passed rows the regression
uses (:func:`.columns.signals`):

- eq. dc_mechanical, ``k_t i`` against ``J w' + B w + c_tau w|w|``: ``beta_m``, the current against the speed;
- eq. dc_electrical, ``V`` against ``R i + L i'`` (the exact armature step) and ``k_e w`` together: ``beta_i``,
  ``beta_w``, the command against the current and the speed (a delay or a slow armature makes these the weaker);
- eq. thrust, ``F`` against ``c_f w|w|``: ``beta_f``.

Current and speed disagree where ``beta_m < -FLIP``; the armature equation says which (the one whose ``beta`` is
lower); the command is negated where current and speed agree (``beta_m > FLIP``) and both armature scales are
below ``-VOLTAGE_FLIP``; the thrust where ``beta_f`` (against the speed taken right way round) is below ``-FLIP``.
The thresholds were set before looking at logs (a scale of -1 within the 5-50 % constant errors the proving ground
draws, margins for effects and timing); on the proving ground's 1,000 logs of five 200-seed sets
(``python bench/sign_conventions.py``) no channel of a log as drawn was called negated, and a negated current or
speed was found on 995, a thrust on 991, a command on 961.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ocp.errors import LogError
from ocp.identify.columns import constant_columns, signals
from ocp.logs import Log, LogKind
from ocp.model.plant import DCMotorPlant

#: a scale below minus this is a negated channel (a right one is about +1, within the constants' errors)
FLIP = 0.3
#: ... the command's, from the armature equation alone, whose scales a delay or a slow armature weakens
VOLTAGE_FLIP = 0.5


def _scale(y: np.ndarray, x: np.ndarray) -> float:
    """Least-squares scale of ``x`` (M,) on ``y`` (M,); NaN where ``x`` is empty."""
    xx = float(x @ x)
    return float(y @ x) / xx if xx > 0 else float("nan")


def scales(plant: DCMotorPlant, log: Log) -> dict[str, float]:
    """The projections of the module doc [-]: ``mechanical``, ``current``, ``speed``, ``thrust`` (NaN where the log
    lacks the channel or the terms are empty). The terms are the constants' columns (:func:`.columns.constant_columns`,
    each the term its constant multiplies; the armature's ``R`` and ``L`` columns sum to its exact step)."""
    s = signals(log, plant.params)
    c = constant_columns(plant.params, s)
    # eq. dc_electrical (V against R i + L i' and k_e w), eq. dc_mechanical (k_t i against J w' + B w + c_tau w|w|),
    # eq. thrust (F against c_f w|w|): each a scale of about +1 where the signs agree
    beta_i, beta_w = np.linalg.lstsq(np.vstack([c["R"][1] + c["L"][1], c["k"][1]]).T, s.v, rcond=None)[0]
    thrust = "thrust" not in log.absent and bool(np.any(s.f))
    return {"mechanical": _scale(-c["k"][0], c["J"][0] + c["B"][0] + c["c_tau"][0]),
            "current": float(beta_i), "speed": float(beta_w),
            "thrust": _scale(s.f, c["c_f"][2]) if thrust else float("nan")}


def negated(plant: DCMotorPlant, log: Log) -> dict[str, str]:
    """Per channel (``voltage``, ``current``, ``omega``, ``thrust``) logged with the opposite sign to ``plant``'s
    convention, why (module doc); empty for a log that agrees, a sweep or a log without armature voltage."""
    if log.kind is not LogKind.TIME_SERIES or {"voltage", "current"} & log.absent or log.n < 8:
        return {}
    b = scales(plant, log)
    out: dict[str, str] = {}
    turned = False
    if b["mechanical"] < -FLIP:
        turned = b["speed"] < b["current"]
        which = "omega" if turned else "current"
        out[which] = (f"the current and the speed disagree in sign in the torque balance (k_t i against J w' + B w + "
                      f"c_tau w|w|: scale {b['mechanical']:.2f}, about +1 when they agree), and the armature equation "
                      f"points to the {'speed' if turned else 'current'} (its scale {min(b['speed'], b['current']):.2f}"
                      f", the {'current' if turned else 'speed'}'s {max(b['speed'], b['current']):.2f})")
    elif b["mechanical"] > FLIP and max(b["current"], b["speed"]) < -VOLTAGE_FLIP:
        out["voltage"] = (f"the current and the speed agree, but both oppose the command in the armature equation "
                          f"(scales {b['current']:.2f} and {b['speed']:.2f}, about +1 when they agree)")
    f = -b["thrust"] if turned else b["thrust"]
    if f < -FLIP:
        out["thrust"] = (f"the thrust opposes c_f w|w| (scale {f:.2f}, about +1 when they agree): positive speed must "
                         "push positive thrust")
    return out


def check_signs(plant: DCMotorPlant, log: Log) -> None:
    """Raise :class:`ocp.errors.LogError` naming the first channel :func:`negated` finds, with why and the fix; first,
    on the command where it is zero on every row (no sign to check, nothing to check the model against: a blind-rig
    log of a loop that never left zero came back as ``R`` 80 % low at 1e11 noise units)."""
    v = log.voltage[np.isfinite(log.voltage)]
    if not np.any(v != 0):
        raise LogError("voltage", "the command is zero on every row: the log holds nothing the model can be checked "
                                  "against (log the motor driven; a rotor held still under a voltage checks R and L)")
    found = negated(plant, log)
    if found:
        channel, why = next(iter(found.items()))
        others = [c for c in found if c != channel]
        raise LogError(channel, f"logged with the opposite sign to the motor model's (positive voltage drives positive "
                                f"current, speed and thrust): {why}"
                                + (f"; {', '.join(others)} too" if others else "") + f"; {_fix(list(found))}")


def check_point_signs(plant: DCMotorPlant, log: Log, equations: Sequence[str]) -> None:
    """The same for a log checked point by point (a sweep, an ESC rig; ``equations`` it checks): only the thrust map,
    eq. thrust_model, ``F`` against ``c_f w|w|`` over its finite rows, holds a sign there that no constant's error
    turns (a supply's current is no armature current, a command fraction no voltage). Raises
    :class:`ocp.errors.LogError` on the thrust, naming the speed as the other suspect."""
    if "thrust" not in equations:
        return
    w, f = log.omega, log.thrust
    ok = np.isfinite(w) & np.isfinite(f)
    b = _scale(f[ok], plant.params.c_f * w[ok] * np.abs(w[ok]))
    if b < -FLIP:
        raise LogError("thrust", f"the thrust and the speed disagree in sign (F against c_f w|w|: scale {b:.2f}, "
                                 "about +1 when they agree): one of them is logged with the opposite sign to the "
                                 "model's (positive speed pushes positive thrust; a load cell that pushes, an encoder "
                                 f"counting the other way); {_fix(['thrust'])}, or the speed (--negate omega)")


def _fix(channels: list[str]) -> str:
    """How to read ``channels`` back with the model's sign (:attr:`ocp.logs.ReadOptions.negate`)."""
    return f"negate it in the file, or read it with negate={channels!r} (CLI --negate {' --negate '.join(channels)})"
