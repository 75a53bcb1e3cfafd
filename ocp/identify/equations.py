"""Which model equations a log can check, and their residuals point by point (measured - model).

Each equation needs some measured channels (:func:`statuses` says which are checked and why the
others are not); a log that lacks a channel disables only what needs it:

* ``thrust`` -- eq. thrust_model ``F = c_f w|w|`` (+ thrust effects): speed and thrust [N];
* ``mechanical`` -- eq. dc_mechanical ``J w' = k_t i - B w - c_tau w|w|`` (+ load effects): speed and
  the armature current, or a torque cell (it reads the reaction torque ``J w' + load``) [N m];
* ``electrical`` -- eq. dc_electrical ``L i' = V - R i - k_e w`` (+ drive effects): speed, armature
  voltage and current [V];
* ``power`` -- *beyond the paper*, for ESC rigs and flight logs whose voltage and current are the
  supply's: ``V_s I_s = p0 + (tau w + R (tau/k_t)^2) / eta`` with ``tau = J w' + load(w)`` [W]. The
  drive's efficiency ``eta`` and idle power ``p0`` are not in the model: they are fitted (linear least
  squares) each time, so the power balance checks the *shape* of the torque map (direction, speed
  dependence), not its scale -- a ``c_tau`` error is indistinguishable from ``eta``.

Time derivatives ``w'``, ``i'`` are 0 on steady-state sweeps and central differences on a time series.
Effects that need time (delays, lags, the rotor angle, ``J``, ``L``) are never checkable here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ocp.identify.noise_level import floored_noise
from ocp.logs import Log, LogKind
from ocp.model.effect_base import EffectBase
from ocp.model.effects import measured_current, stateful
from ocp.model.plant import DCMotorPlant

EQUATION_NAMES: tuple[str, ...] = ("thrust", "mechanical", "electrical", "power")
UNITS = {"thrust": "N", "mechanical": "N m", "electrical": "V", "power": "W"}
LABELS = {"thrust": "thrust map F(w) (eq. thrust_model)", "mechanical": "torque balance (eq. dc_mechanical)",
          "electrical": "armature circuit (eq. dc_electrical)",
          "power": "supply power balance V I = p0 + (tau w + R i^2)/eta (beyond the paper)"}
TIME_EFFECTS = frozenset({"input_delay", "thrust_lag", "cogging", "param:J", "param:L"})
_ON = {"thrust": ("thrust",), "mechanical": ("mechanical", "power"), "electrical": ("electrical",),
       "current-sensor": ("mechanical", "electrical")}
_POWER_ONLY = frozenset({"coulomb_friction", "stribeck", "drag_asymmetry"})  # shape, not scale (see doc)


@dataclass(frozen=True)
class EquationStatus:
    """Whether one equation is checked on a log, from which channels, or why not."""

    name: str
    checked: bool
    how: str

    def to_dict(self) -> dict[str, Any]:
        return {"equation": self.name, "label": LABELS[self.name], "checked": self.checked,
                ("uses" if self.checked else "reason"): self.how, "units": UNITS[self.name]}


def _armature(log: Log, ch: str) -> bool:
    return log.has(ch) and log.electrical == "armature"


def statuses(log: Log) -> tuple[EquationStatus, ...]:
    """Every equation of :data:`EQUATION_NAMES`: checked (and from what) or not (and why)."""
    supply = "the voltage and current are the supply's (ESC/flight log), not the armature's"
    out = [EquationStatus("thrust", True, "speed and measured thrust") if log.has("thrust") else
           EquationStatus("thrust", False, "no thrust channel (flight logs have none)")]
    if log.torque is not None:
        out.append(EquationStatus("mechanical", True, "speed and the measured reaction torque"))
    elif _armature(log, "current"):
        out.append(EquationStatus("mechanical", True, "speed and the armature current"))
    else:
        out.append(EquationStatus("mechanical", False, "no torque cell, and the current is the supply's, not the "
                                  "armature's (the torque side is checked by the power balance)"
                                  if log.has("current") else "no torque cell and no armature current"))
    if _armature(log, "voltage") and _armature(log, "current"):
        out.append(EquationStatus("electrical", True, "speed, armature voltage and current"))
    else:
        out.append(EquationStatus("electrical", False, supply if log.electrical == "supply" else
                                  "needs the armature voltage and current"))
    if log.electrical == "supply" and log.has("voltage") and log.has("current"):
        out.append(EquationStatus("power", True, "speed, supply voltage and current (drive efficiency and idle "
                                                 "power fitted)"))
    else:
        out.append(EquationStatus("power", False, "voltage and current are the armature's: checked by the "
                                                  "electrical and torque equations" if log.electrical == "armature"
                                  else "needs the supply voltage and current"))
    return tuple(out)


def checked(log: Log) -> tuple[str, ...]:
    return tuple(s.name for s in statuses(log) if s.checked)


def allowed(name: str, channel: str, log: Log) -> bool:
    """Whether a candidate (catalogue name or ``param:<key>``, acting on ``channel``) can be judged on ``log``.

    On a complete time series (the dynamic check) every candidate can; otherwise never one that needs
    time, and only those acting on a checked equation (on the power balance alone: load-shape effects).
    """
    if log.complete and log.kind is LogKind.TIME_SERIES:
        return True
    if name in TIME_EFFECTS:
        return False
    eqs = set(checked(log))
    if name.startswith("param:") and name != "param:c_f" and eqs & set(_ON[channel]) == {"power"}:
        return False
    if eqs & set(_ON[channel]) == {"power"}:
        return name in _POWER_ONLY
    if (channel == "current-sensor" or name == "param:k_t") and not _armature(log, "current"):
        return False  # both act through the armature current
    return bool(eqs & set(_ON[channel]))


def rates(log: Log) -> tuple[np.ndarray, np.ndarray]:
    """(w' [rad/s^2], i' [A/s]) (N,): zero on a sweep, central differences on a time series."""
    if log.kind is LogKind.STEADY_STATE:
        return np.zeros(log.n), np.zeros(log.n)
    di = np.gradient(log.current, log.t) if log.has("current") else np.zeros(log.n)
    return np.gradient(log.omega, log.t), di


def _state(plant: DCMotorPlant, log: Log, current: np.ndarray, volts: np.ndarray) -> list[np.ndarray]:
    ideal = plant.params.c_f * log.omega * np.abs(log.omega)
    rows = [log.omega, current]
    for eff in stateful(plant):
        rows += list(eff.steady(log.omega, volts, ideal, log.theta))
    return rows


def model_load(plant: DCMotorPlant, log: Log, volts: np.ndarray | None = None) -> np.ndarray:
    """Model load torque [N m] (N,) at the measured speeds: ``B w + c_tau w|w|`` + load effects."""
    zero = np.zeros(log.n)
    x = _state(plant, log, zero, zero if volts is None else volts)
    # eq:dc_mechanical  J w' = k_t i - load(w): at i = 0, load = -J w'
    return -plant.params.J * np.asarray(plant.rhs(x, zero)[0], float)


#: a sweep's row is at rest where its speed is within this fraction of the sweep's largest (stated, not tuned: the
#: speed a stalled rotor's sensor may read)
REST_FRACTION = 0.01


def held(plant: DCMotorPlant, log: Log, r: np.ndarray, drive: np.ndarray, volts: np.ndarray) -> np.ndarray:
    """The torque balance's residual ``r`` (N,) [N m] with a sweep's rows at rest (:data:`REST_FRACTION`) set-valued:
    dry friction (or an angle ripple) holds whatever torque is within its breakaway (the effects' ``breakaway()``
    summed), so there the residual is the motor's torque ``drive`` less the load without them, shrunk by that
    breakaway (a stalled row of a sweep with Stribeck friction, at rest under 8.4 mN m, left a residual no smooth
    friction explains). On a time series, or without such an effect, ``r`` as it is."""
    hold = sum(e.breakaway() for e in plant.effects if isinstance(e, EffectBase))
    if log.kind is not LogKind.STEADY_STATE or hold <= 0.0:
        return r
    rest = np.abs(log.omega) <= REST_FRACTION * float(np.max(np.abs(log.omega), initial=0.0))
    smooth = DCMotorPlant(plant.params, tuple(e for e in plant.effects
                                              if not (isinstance(e, EffectBase) and e.breakaway() > 0.0)))
    free = drive - model_load(smooth, log, volts)
    return np.where(rest, np.sign(free) * np.maximum(np.abs(free) - hold, 0.0), r)


def residuals(plant: DCMotorPlant, log: Log, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Residuals (N,) measured - model of the equations ``names`` (module doc; units :data:`UNITS`)."""
    p = plant.params
    wd, di = rates(log)
    arm_i = _armature(log, "current")
    i_true = log.current - float(measured_current(plant, 0.0)) if arm_i else np.zeros(log.n)
    volts = log.voltage if _armature(log, "voltage") else np.zeros(log.n)
    out: dict[str, np.ndarray] = {}
    zero_i = _state(plant, log, np.zeros(log.n), volts)
    load = model_load(plant, log, volts)
    for eq in names:
        if eq == "thrust":
            out[eq] = log.thrust - np.asarray(plant.thrust(zero_i), float)
        elif eq == "mechanical":
            drive = log.torque if log.torque is not None else p.k_t * i_true
            out[eq] = held(plant, log, drive - load - p.J * wd, drive, volts)
        elif eq == "electrical":
            # eq:dc_electrical  L i' = V - R i - k_e w  ->  residual [V] = L (rhs_i - i')
            rhs = plant.rhs(_state(plant, log, i_true, volts), volts)
            out[eq] = p.L * (np.asarray(rhs[1], float) - di)
        elif eq == "power":
            out[eq] = power_residual(log.voltage * log.current, (load + p.J * wd) * log.omega
                                     + p.R * ((load + p.J * wd) / p.k_t) ** 2)[0]
    return out


def power_residual(p_supply: np.ndarray, p_motor: np.ndarray) -> tuple[np.ndarray, float, float]:
    """``(P_s - p0 - a P_m (N,), eta = 1/a, p0 [W])``: ``a``, ``p0`` by linear least squares (``a = 1`` if not > 0)."""
    a_mat = np.column_stack([np.ones_like(p_motor), p_motor])
    coef, *_ = np.linalg.lstsq(a_mat, p_supply, rcond=None)
    p0, a = float(coef[0]), float(coef[1])
    if not a > 0:
        a = 1.0
        p0 = float(np.mean(p_supply - p_motor))
    return p_supply - p0 - a * p_motor, 1.0 / a, p0


def measured_side(log: Log, plant: DCMotorPlant, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The measured side (N,) of each equation, in its unit: thrust, torque (cell or ``k_t i``), voltage,
    supply power ``V I``."""
    side = {"thrust": lambda: log.thrust, "electrical": lambda: log.voltage,
            "power": lambda: log.voltage * log.current,
            "mechanical": lambda: log.torque if log.torque is not None else plant.params.k_t * log.current}
    return {eq: np.asarray(side[eq](), float) for eq in names}


def noise(log: Log, names: tuple[str, ...], plant: DCMotorPlant) -> dict[str, float]:
    """Noise level [equation unit] of each equation's measured side: 1 % of its RMS on a sweep, the MAD of
    second differences / sqrt(6) on a time series (as :func:`ocp.identify.predict.noise_levels`)."""
    out = {}
    for eq, y in measured_side(log, plant, names).items():
        rms = float(np.sqrt(np.mean(y * y)))
        if log.kind is LogKind.STEADY_STATE or y.size < 10:
            out[eq] = max(0.01 * rms, 1e-12)
            continue
        out[eq] = floored_noise(y)
    return out


def annotate(answer: dict[str, Any], log: Log) -> dict[str, Any]:
    """A result's ``to_dict()`` with ``route`` (``dynamic``: free run under the armature voltage, or
    ``point-by-point``), ``equations`` (checked or not, and why) and ``notes`` (what the reader did)."""
    dynamic = log.complete and log.kind is LogKind.TIME_SERIES
    answer.setdefault("route", "dynamic" if dynamic else "point-by-point")
    answer.setdefault("equations", [s.to_dict() for s in statuses(log)])
    answer.setdefault("notes", list(log.notes))
    return answer
