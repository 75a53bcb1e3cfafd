"""The torque channel in normalised-thrust coordinates (paper eq. sys2): ``x2 = w|w|`` driven by ``u = tau/J``.

Its drift and input gain (Fig. f2_map) and the unique input that reproduces a thrust trajectory away from a
reversal (eq. inv_u), which is unbounded where the gain vanishes.
"""

from __future__ import annotations

import numpy as np


# eq:sys2  x2' = -2k sign(x2)|x2|^(3/2) + 2 sqrt|x2| u
def normal_form_rhs(x2: np.ndarray | float, u: np.ndarray | float, k: float) -> np.ndarray:
    """Normalised-thrust dynamics of eq. sys2; ``x2 = w|w|`` [rad^2/s^2], ``u`` [rad/s^2]."""
    x2 = np.asarray(x2, dtype=float)
    return -2.0 * k * np.sign(x2) * np.abs(x2) ** 1.5 + 2.0 * np.sqrt(np.abs(x2)) * u


def normal_form_drift(x2: np.ndarray | float, k: float) -> np.ndarray:
    """Drift ``f2(x2) = -2k sign(x2)|x2|^(3/2)`` of eq. sys2 (Fig. f2_map)."""
    return normal_form_rhs(x2, 0.0, k)


def normal_form_gain(x2: np.ndarray | float) -> np.ndarray:
    """Input gain ``g2(x2) = 2 sqrt|x2|`` of eq. sys2; vanishes at thrust reversal (Fig. f2_map)."""
    return 2.0 * np.sqrt(np.abs(np.asarray(x2, dtype=float)))


# eq:inv_u  u = y'' / (2 sqrt|y'|) + k y'
def inverse_input(ydot: np.ndarray | float, yddot: np.ndarray | float, k: float) -> np.ndarray:
    """Unique input reproducing ``(y', y'')`` away from reversal; +-inf where ``y' = 0, y'' != 0``."""
    yd = np.asarray(ydot, dtype=float)
    ydd = np.asarray(yddot, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = ydd / (2.0 * np.sqrt(np.abs(yd))) + k * yd
    return np.where((yd == 0) & (ydd == 0), 0.0, u)
