"""The plant: parameters (params), the motor-propeller plant and its effects (plant, effects), equilibria."""
