"""Whole-array runs of the streaming shaper (tests, benches, the page's example): the same per-sample
step, collected into arrays."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocp.errors import MissionError
from ocp.model.params import MotorParams
from ocp.stream.options import StreamOptions
from ocp.stream.shaper import StreamShaper

FIELDS = ("t", "desired", "thrust", "omega", "omega_dot", "omega_ddot", "current", "voltage")


@dataclass(frozen=True)
class StreamTrace:
    """Shaper output on the input grid, every array shape (N,), SI (see :class:`StreamSample`).

    Attributes:
        saturated: bool (N,), the governor acted at that sample
    """

    t: np.ndarray
    desired: np.ndarray
    thrust: np.ndarray
    omega: np.ndarray
    omega_dot: np.ndarray
    omega_ddot: np.ndarray
    current: np.ndarray
    voltage: np.ndarray
    saturated: np.ndarray

    def tracking_rms(self) -> float:
        """RMS of ``thrust - desired`` [N] (the desired thrust delayed by the look-ahead)."""
        return float(np.sqrt(np.mean((self.thrust - self.desired) ** 2)))


def shape_profile(params: MotorParams, options: StreamOptions, t: np.ndarray, thrust: np.ndarray) -> StreamTrace:
    """Push the samples ``thrust`` (N,) [N] at ``t`` (N,) [s] through a fresh shaper, one by one."""
    t = np.asarray(t, dtype=float)
    thrust = np.asarray(thrust, dtype=float)
    if t.shape != thrust.shape or t.ndim != 1 or t.size < 1:
        raise MissionError("thrust", f"shape {thrust.shape} does not match t {t.shape} (1-D, non-empty)")
    sh = StreamShaper(params, options)
    rows = [sh.push(float(a), float(b)) for a, b in zip(t, thrust, strict=True)]
    cols = {name: np.array([getattr(r, name) for r in rows], dtype=float) for name in FIELDS}
    return StreamTrace(**cols, saturated=np.array([r.saturated for r in rows], dtype=bool))
