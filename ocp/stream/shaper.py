"""The causal streaming shaper: desired thrust in, sample by sample; shaped reference with its exact
feed-forward out, ``delay`` seconds behind.

At sample k the shaper has seen the desired thrust ``F_d`` up to ``t_k``; its output at ``t_k`` tracks
``F_d(t_k - D)`` and so knows the target ``N = D/dt`` samples ahead. Per sample (all O(N + 1)):

1. the new sample's target coordinate ``r = eta_T(F_d(t_k))`` enters a ring buffer
   (:func:`ocp.stream.inverse.target_coordinate`; before the stream started the target is 0, at rest);
2. the preview tracker (:mod:`ocp.stream.preview`) gives ``v = -K z + F . r[k+1..k+N]``;
3. the governor (:mod:`ocp.stream.governor`) clips ``v`` so the current and voltage stay in limits;
4. the output at ``t_k`` is the exact inverse of the shaping state (:mod:`ocp.stream.inverse`): thrust,
   omega, omega', omega'', current, voltage; then the state advances by one sample.

Because the output is a state of an integrator chain mapped through the plant inverse, the DC motor
driven by the returned voltage reproduces the returned thrust (no approximation but the sampling of the
voltage), and every reversal has the exponent of the requested class whatever the input does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocp.errors import MissionError
from ocp.model.params import MotorParams
from ocp.stream.governor import govern
from ocp.stream.inverse import Inverse, speed_derivatives, target_coordinate
from ocp.stream.options import StreamOptions
from ocp.stream.preview import design

JITTER = 0.01  # accepted relative deviation of an input sample period from dt


@dataclass(frozen=True)
class StreamSample:
    """One output sample at ``t`` [s] (SI: N, rad/s, rad/s^2, rad/s^3, A, V).

    Attributes:
        desired: the desired thrust the output tracks, ``F_d(t - delay)`` [N] (0 before the stream)
        saturated: True when the governor changed the tracker's decision at this sample
    """

    t: float
    thrust: float
    omega: float
    omega_dot: float
    omega_ddot: float
    current: float
    voltage: float
    desired: float
    saturated: bool


class StreamShaper:
    """One stream's shaper (see module doc). Not thread-safe: one instance per stream."""

    def __init__(self, params: MotorParams, options: StreamOptions) -> None:
        self.params, self.options = params, options
        self._inv = Inverse(params)
        self._m = options.speed_power
        self._foh = options.chain == 3
        g = design("foh" if self._foh else "zoh", options.dt, options.bandwidth, options.preview)
        # Python floats for the O(n) scalar parts of the step (numpy scalars cost ~10x per operation)
        self._A: list[list[float]] = g.A.tolist()
        self._B: list[float] = g.B.tolist()
        self._K: list[float] = g.K.tolist()
        self._F = g.F
        self._L = options.preview + 1
        self._r = np.zeros(2 * self._L)  # target coordinate, doubled ring buffer
        self._f = np.zeros(2 * self._L)  # raw desired thrust, same ring
        self._w = 0
        self._z = [0.0] * options.chain
        self._t_last: float | None = None
        imax, vmax = options.current * (1.0 - options.margin), options.voltage * (1.0 - options.margin)
        self._limits = (imax, vmax) if self._foh else (imax, vmax, vmax)
        self._is_voltage = (False, True) if self._foh else (False, True, True)
        self.samples = 0
        self.saturations = 0

    def _check(self, t: float, thrust: float) -> None:
        if not (math.isfinite(t) and math.isfinite(thrust)):
            raise MissionError("thrust" if math.isfinite(t) else "t", "must be a finite number")
        if self._t_last is not None:
            step = t - self._t_last
            if abs(step - self.options.dt) > JITTER * self.options.dt:
                raise MissionError("t", f"advances by {step:.6g} s; the stream's sample period is "
                                        f"{self.options.dt:.6g} s (within {JITTER:.0%})")

    def _push_target(self, thrust: float) -> None:
        w, L = self._w, self._L
        r = target_coordinate(thrust, self.params.c_f, self._m)
        self._r[w] = self._r[w + L] = r
        self._f[w] = self._f[w + L] = thrust
        self._w = (w + 1) % L

    def _advance(self, v: float) -> list[float]:
        """State at ``t_{k+1}`` for the decision ``v`` (the chain's A z + B v, unrolled: A is triangular)."""
        A, b, z = self._A, self._B, self._z
        if self._foh:
            return [z[0] + A[0][1] * z[1] + A[0][2] * z[2] + b[0] * v, z[1] + A[1][2] * z[2] + b[1] * v, v]
        return [z[0] + A[0][1] * z[1] + b[0] * v, z[1] + b[1] * v]

    def _limited(self, v: float) -> tuple[float, ...]:
        """(current at t_{k+1}, voltage at t_{k+1}[, voltage at t_k+ when eta'' is held]) for decision v."""
        inv, m = self._inv, self._m
        zn = self._advance(v)
        w, w1, w2 = speed_derivatives(zn[0], zn[1], v, m)
        out = (inv.current(w, w1), inv.voltage(w, w1, w2))
        if self._foh:
            return out
        z = self._z  # eta'' jumps to v at t_k, so V(t_k+) depends on v
        return (*out, inv.voltage(*speed_derivatives(z[0], z[1], v, m)))

    def push(self, t: float, thrust: float) -> StreamSample:
        """Feed the desired thrust ``thrust`` [N] at ``t`` [s]; returns the output sample at ``t``."""
        self._check(t, thrust)
        self._push_target(thrust)
        w, L, z = self._w, self._L, self._z
        win = self._r[w + 1:w + L]
        v = float(self._F @ win) - sum(k * x for k, x in zip(self._K, z, strict=True))
        eta2_now = z[2] if self._foh else None
        v, sat = govern(v, self._limited, self._limits, self._is_voltage)
        w0, w1, w2 = speed_derivatives(z[0], z[1], v if eta2_now is None else eta2_now, self._m)
        inv = self._inv
        out = StreamSample(t=t, thrust=inv.thrust(w0), omega=w0, omega_dot=w1, omega_ddot=w2,
                           current=inv.current(w0, w1), voltage=inv.voltage(w0, w1, w2),
                           desired=float(self._f[w]), saturated=sat)
        self._z = self._advance(v)
        self._t_last = t
        self.samples += 1
        self.saturations += sat
        return out
