"""The reference a user gets: thrust, speed, angle, current, voltage on one time grid.

Every array has shape (N,) on ``t`` [s]; SI units: thrust [N], omega [rad/s], omega_dot [rad/s^2],
omega_ddot [rad/s^3], theta [rad], current [A], voltage [V]. At a crossing whose ideal command is
unbounded the sample holds +-inf and ``unbounded[channel]`` is True: never a silent NaN.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocp.encoding import jsonable

CSV_COLUMNS: tuple[str, ...] = ("t", "thrust", "omega", "theta", "current", "voltage")
CHANNELS: tuple[str, ...] = ("thrust", "omega", "omega_dot", "omega_ddot", "theta", "current", "voltage")


@dataclass(frozen=True)
class Reference:
    """Sampled reference; see module doc for units and shapes.

    Attributes:
        unbounded: per channel, True when the ideal channel is unbounded somewhere on the profile
            (decided by the theory at each crossing, not by whether a sample hit the crossing).
        crossing_times: thrust zeros [s] inside the grid.
        crossing_orders: thrust order p at each zero (None when it is not an integer order).
    """

    t: np.ndarray
    thrust: np.ndarray
    omega: np.ndarray
    omega_dot: np.ndarray
    omega_ddot: np.ndarray
    theta: np.ndarray
    current: np.ndarray
    voltage: np.ndarray
    unbounded: dict[str, bool] = field(default_factory=dict)
    crossing_times: tuple[float, ...] = ()
    crossing_orders: tuple[int | None, ...] = ()

    def peak(self, channel: str) -> float:
        """max |channel| over the grid (inf if unbounded)."""
        if self.unbounded.get(channel, False):
            return math.inf
        return float(np.max(np.abs(getattr(self, channel))))

    def to_csv(self) -> str:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(CSV_COLUMNS)
        cols = [getattr(self, c) for c in CSV_COLUMNS]
        for row in zip(*cols, strict=True):
            w.writerow([repr(float(v)) for v in row])
        return buf.getvalue()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (:func:`ocp.encoding.jsonable`: +-inf samples become the strings "inf" / "-inf")."""
        out: dict[str, Any] = {"t": jsonable(np.asarray(self.t, float))}
        for c in CHANNELS:
            out[c] = jsonable(np.asarray(getattr(self, c), float))
        out["unbounded"] = dict(self.unbounded)
        out["crossings"] = [{"t": float(ts), "p": p} for ts, p in zip(self.crossing_times, self.crossing_orders,
                                                                       strict=True)]
        return out

