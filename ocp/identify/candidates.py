"""Candidates a model check can add: catalogue effects and corrections of the nominal constants.

A candidate has a name (an effect name of :data:`ocp.model.effects.CATALOGUE`, or ``"param:<key>"`` for a
correction of a :class:`~ocp.model.params.MotorParams` constant), the parameters it fits, their bounds
and starting points, and knows how to put fitted values into a plant.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ocp.errors import ParameterError
from ocp.model.effects import CATALOGUE, EffectBase, make_effect
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant

PARAM_PREFIX = "param:"
PARAM_KEYS: tuple[str, ...] = ("J", "B", "c_tau", "c_f", "k_t", "k_e", "k", "R", "L")
PARAM_UNITS = {"J": "kg m^2", "B": "N m s/rad", "c_tau": "N m s^2/rad^2", "c_f": "N s^2/rad^2",
               "k_t": "N m/A", "k_e": "V s/rad", "k": "N m/A", "R": "Ohm", "L": "H"}
PARAM_CHANNEL = {"J": "mechanical", "B": "mechanical", "c_tau": "mechanical", "c_f": "thrust",
                 "k_t": "mechanical", "k_e": "electrical", "k": "electrical", "R": "electrical", "L": "electrical"}
PARAM_SIGNATURE = {
    "J": "torque residual proportional to the acceleration",
    "B": "torque residual proportional to the speed, odd, in both directions",
    "c_tau": "torque residual proportional to w|w|, same relative size in both directions",
    "c_f": "thrust residual proportional to w|w|, same relative size in both directions",
    "k_t": "torque residual proportional to the current",
    "k_e": "voltage residual proportional to the speed (back-emf off): steady speed off by a fixed ratio",
    "k": "torque residual proportional to the current and voltage residual proportional to the speed "
         "(k_t and k_e together, their ratio kept)",
    "R": "voltage residual proportional to the current",
    "L": "voltage residual proportional to the current rate (fast current transients mis-predicted)",
}
#: nonlinear parameters get extra starting points (factors of the guess) against local minima
_NONLINEAR_STARTS = (1.0, 5.0, 0.3)
_NONLINEAR = {"omega_s", "delay", "tau", "v_db"}
_NONLINEAR_PARAMS = {"J", "L"}


@dataclass(frozen=True)
class Candidate:
    """One thing to add: an effect or a nominal-constant correction.

    Attributes:
        name: effect name or ``"param:<key>"``
        keys: fitted parameter names
    """

    name: str
    keys: tuple[str, ...]

    @property
    def is_param(self) -> bool:
        return self.name.startswith(PARAM_PREFIX)

    @property
    def param_key(self) -> str:
        return self.name.removeprefix(PARAM_PREFIX)

    @property
    def linear(self) -> bool:
        """Whether the equations are (nearly) affine in the fitted parameters: Gauss-Newton suffices."""
        if self.is_param:
            return self.param_key not in _NONLINEAR_PARAMS
        return not (_NONLINEAR & set(self.keys))

    @property
    def channel(self) -> str:
        """Equation it acts on: mechanical, electrical, thrust or current-sensor."""
        return PARAM_CHANNEL[self.param_key] if self.is_param else CATALOGUE[self.name].channel

    def units(self) -> dict[str, str]:
        return {self.param_key: PARAM_UNITS[self.param_key]} if self.is_param else dict(CATALOGUE[self.name].units)

    def bounds(self, plant: DCMotorPlant, torque: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Boxes of the fitted values (SI). ``torque`` [N m], the motor's peak torque in the log
        (:func:`ocp.identify.estimate.peak_torque`): a torque-valued parameter's box reaches it where the catalogue's
        is narrower (the catalogue's 0.1 N m is a small motor's: ``fit`` held large motors' 0.24-1.5 N m ripples at
        0.1 on the proving ground, ``bench/ripple_fit.py``)."""
        if self.is_param:
            v = _param(plant, self.param_key)
            return np.array([0.25 * v]), np.array([4.0 * v])
        eff = CATALOGUE[self.name]
        lo, hi = (np.array([eff.bounds[k][j] for k in self.keys]) for j in (0, 1))
        wide = np.array([eff.units.get(k) == "N m" for k in self.keys]) & (torque > 0)
        return np.where(wide & (lo < 0), np.minimum(lo, -torque), lo), np.where(wide, np.maximum(hi, torque), hi)

    def starts(self, plant: DCMotorPlant) -> list[np.ndarray]:
        """Starting points (one, or several when a parameter enters nonlinearly)."""
        lo, hi = self.bounds(plant)
        if self.is_param:
            return [np.array([_param(plant, self.param_key)])]
        current = _existing(plant, self.name)
        g = CATALOGUE[self.name].guess
        base = np.array([current.parameters()[k] if current is not None else g[k] for k in self.keys])
        factors = _NONLINEAR_STARTS if _NONLINEAR & set(self.keys) else (1.0,)
        return [np.clip(base * f if f != 1.0 else base, lo, hi) for f in factors]

    def apply(self, plant: DCMotorPlant, values: Sequence[float]) -> DCMotorPlant:
        """``plant`` with this candidate's fitted ``values`` (an existing effect of that name replaced)."""
        if self.is_param:
            data = plant.params.model_dump()
            if self.param_key == "k":  # the motor constant: k_t and k_e scaled together
                data["k_e"] *= float(values[0]) / data["k_t"]
                data["k_t"] = float(values[0])
            else:
                data[self.param_key] = float(values[0])
            return DCMotorPlant(MotorParams(**data), plant.effects)
        current = _existing(plant, self.name)
        fixed = current.parameters() if current is not None else {}
        eff = make_effect(self.name, {**fixed, **dict(zip(self.keys, map(float, values), strict=True))})
        if current is None:
            return DCMotorPlant(plant.params, (*plant.effects, eff))
        return DCMotorPlant(plant.params, tuple(eff if e.name == self.name else e for e in plant.effects))

    def values(self, plant: DCMotorPlant) -> dict[str, float]:
        """The candidate's parameters as they are in ``plant``."""
        if self.is_param:
            return {self.param_key: _param(plant, self.param_key)}
        eff = _existing(plant, self.name)
        return {k: eff.parameters()[k] for k in self.keys} if eff is not None else {}

    def explain(self, before: DCMotorPlant, after: DCMotorPlant) -> str:
        """Words: what was found, its fitted magnitude with units, the signature that gives it away."""
        if self.is_param:
            k = self.param_key
            v0, v1 = _param(before, k), _param(after, k)
            return (f"{k} correction: nominal {v0:.4g} -> fitted {v1:.4g} {PARAM_UNITS[k]} "
                    f"({100 * (v1 / v0 - 1):+.1f} %). Signature: {PARAM_SIGNATURE[k]}")
        eff = _existing(after, self.name)
        return eff.describe() if eff is not None else self.name


def _param(plant: DCMotorPlant, key: str) -> float:
    """A constant's value; ``k`` (the motor constant) reads k_t."""
    return float(getattr(plant.params, "k_t" if key == "k" else key))


def _existing(plant: DCMotorPlant, name: str) -> EffectBase | None:
    for e in plant.effects:
        if e.name == name and isinstance(e, EffectBase):
            return e
    return None


def candidate(name: str) -> Candidate:
    """Candidate by name; unknown names raise :class:`ParameterError` naming it."""
    if name.startswith(PARAM_PREFIX):
        key = name.removeprefix(PARAM_PREFIX)
        if key not in PARAM_KEYS:
            raise ParameterError(name, f"unknown constant; corrections exist for {list(PARAM_KEYS)}")
        return Candidate(name, (key,))
    if name not in CATALOGUE:
        raise ParameterError(name, f"unknown effect; the catalogue has {sorted(CATALOGUE)} "
                                   f"and corrections {[PARAM_PREFIX + k for k in PARAM_KEYS]}")
    return Candidate(name, CATALOGUE[name].fitted)


def all_candidates(include_params: bool = True) -> list[Candidate]:
    """Every catalogue effect, and (optionally) a correction of every nominal constant."""
    out = [candidate(n) for n in CATALOGUE]
    if include_params:
        out += [candidate(PARAM_PREFIX + k) for k in PARAM_KEYS]
    return out
