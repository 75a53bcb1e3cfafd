"""User-like missions of issue 14 for ``bench/optimizer.py``: what a new user sends first.

A small brushed motor with a ~10 cm propeller (about 5 W electrical at full thrust), SI:

* J = 4e-5 kg m^2, R = 3 Ohm, L = 2 mH, k_t = k_e = 0.03 (N m/A, V s/rad) -- the issue's motor;
* c_tau = 1e-6 N m s^2/rad^2: 0.5 A of drag current at 120 rad/s (0.3 N), 15 mN m;
* c_f = 2e-5 N s^2/rad^2: c_f / c_tau = 20 1/m, a propeller of about 10 cm diameter; 0.3 N at 122 rad/s;
* B = 1e-6 N m s/rad: 0.1 mN m of viscous friction at 100 rad/s (bearings), small beside the drag.

At 0.3 N the steady point takes 0.5 A and 5.2 V (about 3 W): holds are inside the 6 V limit and the
0.8-1 A current limits, the reversals are not (the current limit binds on every one of them).

Profiles are sampled at 200 Hz over 2 s (401 samples): sines of 0.5 and 1 Hz and a ramp through zero
(held at either end), each with the ``bounded`` and the ``continuous-voltage`` regularity.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

SMALL_MOTOR: dict[str, float] = {"J": 4e-5, "B": 1e-6, "c_tau": 1e-6, "c_f": 2e-5, "k_t": 0.03, "k_e": 0.03,
                                 "R": 3.0, "L": 2e-3}
VOLTAGE_V = 6.0
RATE_HZ, SPAN_S = 200.0, 2.0
REGULARITIES = ("bounded", "continuous-voltage")
#: profile name -> (kind, frequency [Hz], level [N], current limit [A])
PROFILES: dict[str, tuple[str, float, float, float]] = {
    "sine-0.5hz": ("sine", 0.5, 0.3, 0.8),  # 2 reversals
    "sine-1hz": ("sine", 1.0, 0.25, 1.0),  # 4 reversals
    "ramp": ("ramp", 0.0, 0.3, 0.8),  # hold 0.5 s, ramp through zero in 1 s, hold 0.5 s
}


def _profile(kind: str, hz: float, level: float) -> tuple[np.ndarray, np.ndarray]:
    """401 samples at 200 Hz over 2 s: times [s], thrust [N]."""
    t = np.linspace(0.0, SPAN_S, round(RATE_HZ * SPAN_S) + 1)
    if kind == "sine":
        return t, level * np.cos(2.0 * math.pi * hz * t)
    return t, level * np.clip(1.0 - 2.0 * (t - 0.5), -1.0, 1.0)


def user_missions() -> list[dict[str, Any]]:
    """The user-like missions (mission mappings), 3 profiles x 2 regularities."""
    out = []
    for name, (kind, hz, level, current) in PROFILES.items():
        t, f = _profile(kind, hz, level)
        for reg in REGULARITIES:
            out.append({"name": f"user-{name}-{'cv' if reg == 'continuous-voltage' else 'b'}",
                        "params": dict(SMALL_MOTOR), "limits": {"voltage": VOLTAGE_V, "current": current},
                        "regularity": reg, "profile": {"t": t.tolist(), "thrust": f.tolist()}})
    return out


USER = [m["name"] for m in user_missions()]
