"""Which reading of the seed paper's "Hz" is physical? Rotor figures of a preset at the experiment's thrust.

The paper gives ``c_f = 1.4e-4 N/Hz^2`` and ``c_tau = 2.2e-6 N m/Hz^2`` for a 0.20 m propeller on a 12 V,
2000 r/min motor that produced 0.59 N. Read "Hz" as rad/s (preset ``paper-rig``) or as rev/s (preset
``paper-rig-revs``); :func:`rotor_evidence` computes, for either, what a propeller engineer checks first:

* the speed the thrust needs, ``w = sqrt(F / c_f)`` [rad/s], against the motor's 2000 r/min rating and
  against the steady speed the preset's motor reaches at 12 V (:meth:`MotorParams.max_steady_speed`);
* the thrust coefficient ``C_T = F / (rho n^2 D^4)`` (n in rev/s): a 2-blade propeller is about 0.05-0.15;
* the shaft power ``P = c_tau w^3`` [W] (drag torque times speed) against momentum theory's minimum
  ``P_ideal = F^(3/2) / sqrt(2 rho A)`` for a disc of area ``A = pi D^2 / 4``; their ratio, the figure
  of merit ``FM = P_ideal / P``, cannot exceed 1 (real small propellers: about 0.4-0.7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ocp.model.params import MotorParams

AIR_DENSITY = 1.225  # kg/m^3, ISA sea level
RAD_PER_REV = 2.0 * math.pi


@dataclass(frozen=True)
class RotorEvidence:
    """Rotor figures at one thrust (SI; ``rpm`` in r/min).

    Attributes:
        thrust: [N]; speed: needed for it [rad/s]; rpm: the same [r/min]
        thrust_coefficient: C_T = F / (rho n^2 D^4) [-]
        shaft_power: c_tau w^3 [W]; ideal_power: momentum-theory minimum [W]
        figure_of_merit: ideal_power / shaft_power [-] (physical: <= 1)
        rated_speed: the motor's rating [rad/s]; speed_at_voltage: steady speed of the preset's motor at
            the supply voltage [rad/s]
    """

    thrust: float
    speed: float
    rpm: float
    thrust_coefficient: float
    shaft_power: float
    ideal_power: float
    figure_of_merit: float
    rated_speed: float
    speed_at_voltage: float

    @property
    def physical(self) -> bool:
        """Momentum theory holds (FM <= 1)."""
        return self.figure_of_merit <= 1.0

    @property
    def within_rating(self) -> bool:
        """The speed the thrust needs is within the motor's rated speed."""
        return self.speed <= self.rated_speed


def rotor_evidence(params: MotorParams, thrust: float = 0.59, diameter: float = 0.20, rated_rpm: float = 2000.0,
                   voltage: float = 12.0) -> RotorEvidence:
    """Figures of ``params`` at ``thrust`` [N] for a propeller of ``diameter`` [m] (see module doc)."""
    w = math.sqrt(thrust / params.c_f)
    n = w / RAD_PER_REV  # rev/s
    area = math.pi * diameter**2 / 4.0
    power = params.c_tau * w**3  # drag torque c_tau w^2 times w
    ideal = thrust**1.5 / math.sqrt(2.0 * AIR_DENSITY * area)
    return RotorEvidence(thrust=thrust, speed=w, rpm=n * 60.0,
                         thrust_coefficient=thrust / (AIR_DENSITY * n**2 * diameter**4), shaft_power=power,
                         ideal_power=ideal, figure_of_merit=ideal / power, rated_speed=rated_rpm * RAD_PER_REV / 60.0,
                         speed_at_voltage=params.max_steady_speed(voltage))
