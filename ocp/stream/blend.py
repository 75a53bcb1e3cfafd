"""The alternative kept for comparison: analytic polynomial reversals blended in where the look-ahead sees
a crossing (the paper's Section IV-A construction applied online), with the static inverse elsewhere.

For the output at ``t`` (tracking ``tau = t - D``) the desired thrust is known up to ``t``; every sign
change ``t_c`` of ``F_d`` with ``|tau - t_c| < h`` (``h = 0.9 D``, so the crossing is seen at least
``0.1 D`` before its window starts) is replaced by ``alpha (tau - t_c)^p chi + (1 - chi) F_d``
(:func:`ocp.gallery.interaction.shape_reversals`), ``p = 2 q + 1`` with ``q`` the smallest of the
requested class (:func:`ocp.theory.reversal.min_sin_q`). Speed and its derivatives follow from the thrust by the
static inverse and the chain rule, ``F'`` and ``F''`` by central differences of the samples; current
and voltage by eqs. current_reference / voltage_reference. Nothing bounds them: this is what the
numbers in the README compare against the governed tracker.

:func:`blend_profile` evaluates a whole sampled profile at once; it is causal (the output at sample k
uses samples up to k only), which ``tests/test_stream.py`` checks on a truncated profile.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocp.gallery.interaction import shape_reversals
from ocp.model.params import MotorParams
from ocp.stream.inverse import Inverse
from ocp.stream.options import StreamOptions
from ocp.theory.crossings import sign_change_times
from ocp.theory.reversal import min_sin_q, sin_family_order


@dataclass(frozen=True)
class BlendTrace:
    """Output of :func:`blend_profile` on the input grid ``t`` (all shape (N,), SI)."""

    t: np.ndarray
    desired: np.ndarray
    thrust: np.ndarray
    omega: np.ndarray
    current: np.ndarray
    voltage: np.ndarray


def _speed(x: np.ndarray, dx: np.ndarray, ddx: np.ndarray, c_f: float) -> tuple[np.ndarray, ...]:
    """(omega, omega', omega'') of ``c_f omega|omega| = x`` (shapes of x); the limit 0 at exact zeros."""
    a = np.abs(x)
    root = np.sqrt(a / c_f)
    nz = a > 0
    safe = np.where(nz, a, 1.0)
    w1 = np.where(nz, dx / (2.0 * np.sqrt(c_f * safe)), 0.0)
    w2 = np.where(nz, ddx / (2.0 * np.sqrt(c_f * safe)) - np.sign(x) * dx * dx / (4.0 * np.sqrt(c_f) * safe**1.5), 0.0)
    return np.sign(x) * root, w1, w2


def blend_profile(params: MotorParams, options: StreamOptions, t: np.ndarray, f: np.ndarray) -> BlendTrace:
    """Blend-shaped reference of the desired thrust ``f`` (N,) [N] on the uniform grid ``t`` (N,) [s]."""
    n_d = options.preview
    dt = options.dt
    fd = np.concatenate([np.zeros(n_d), f[:-n_d] if n_d < f.size else np.zeros(0)])[: f.size]  # F_d(t - D)
    tau = t - options.delay
    p = sin_family_order(min_sin_q(options.regularity))
    h = 0.9 * options.delay
    crossings = [tc for tc in sign_change_times(t, f) if tc + 2 * dt <= t[-1]]
    k = [int(np.searchsorted(t, tc)) for tc in crossings]
    slopes = [(f[j] - f[j - 1]) / dt for j in k]  # uses samples up to t_c + dt
    dfd = np.gradient(fd, dt)
    xs, dxs = shape_reversals(tau, fd, dfd, tuple(crossings), tuple(slopes), p, 0.2 * h, 0.8 * h)
    ddxs = np.gradient(dxs, dt)
    w, w1, w2 = _speed(xs, dxs, ddxs, params.c_f)
    inv = Inverse(params)
    return BlendTrace(t=t, desired=fd, thrust=inv.thrust(w), omega=w, current=inv.current(w, w1),
                      voltage=inv.voltage(w, w1, w2))
