"""The one place that turns a plant kind into a plant: every other module asks the plant, never its kind."""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum
from typing import Any

from ocp.errors import MissionError
from ocp.model.effects import load_plant
from ocp.model.params import MotorParams
from ocp.model.plant import DrivenPlant, TorquePlant


class PlantKind(StrEnum):
    """Which plant a mission drives: the voltage-driven DC motor (paper eqs. dc_mechanical, dc_electrical)
    or the normalised torque channel (eq. omega_dyn) of a drive that controls torque."""

    DC_MOTOR = "dc-motor"
    TORQUE = "torque"


def make_plant(kind: PlantKind, params: str | Mapping[str, Any], motor: MotorParams) -> DrivenPlant:
    """The plant of ``kind``: the DC motor with the effects of its parameter source ``params`` (a preset, a
    file or a mapping: a calibrated plant from ``thrustshape fit``), or the torque channel of ``motor``
    (which takes no effects: :class:`~ocp.errors.MissionError` ``params.effects``)."""
    if kind is PlantKind.DC_MOTOR:
        return load_plant(params)
    if isinstance(params, Mapping) and params.get("effects"):
        raise MissionError("params.effects", "effects act on the dc-motor plant, not on the torque channel")
    return TorquePlant.from_params(motor)
