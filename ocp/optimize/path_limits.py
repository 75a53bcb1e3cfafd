"""The current limit held inside each collocation interval by construction (issue 14 item 1).

The collocation program bounds the current at its nodes. Between them, after the held voltage of a bounded
command jumps, the winding's current (time constant ``tau_e = L/R``, 0.67 ms for a 3 Ohm / 2 mH motor, against
intervals of ~17 ms) rises or falls quickly towards its quasi-static value and may pass the limit before the
next node: the simulated answer then exceeded the limit and a back-off round was needed.

Here the current inside each interval is written in closed form and bounded at points a few ``tau_e`` after
the interval's start, where that transient peaks. With the speed ``w`` and the voltage ``V`` the interval's
polynomials, the quasi-static current ``i_s(t) = (V - k_e w) / R`` (eq. dc_electrical with ``L i' = 0``) is
taken linear between the interval's start and the point, slope ``b``; then eq. dc_electrical,
``tau_e i' = i_s - i``, is solved exactly:

    i(t) = i_s(t) - b tau_e + (i(0) - i_s(0) + b tau_e) exp(-t / tau_e)

The bound is the mission's current limit shrunk by ``PATH_MARGIN`` (and by the interval's back-off, which
stays as the safety net for what this model leaves out: effects, curvature of ``i_s``).
"""

from __future__ import annotations

from typing import Any, cast

import casadi as ca
import numpy as np

from ocp.model.plant import DrivenPlant, Plant

#: check points after an interval's start [multiples of tau_e = L/R] (capped at the interval's end)
CHECK_TAU_E = (1.0, 2.0, 3.0, 4.5)
#: the in-interval current bound of a tracking mission is the limit times (1 - PATH_MARGIN): the model
#: underestimates the peak by up to ~2e-3 of the limit (the peak falls between check points). A min-time
#: mission takes none: there the limit sets the duration, and a margin would lengthen it by as much (its
#: back-off round, now rare, covers the rest)
PATH_MARGIN = 3e-3


def _basis(nodes: np.ndarray, tau: Any) -> list[Any]:
    """Lagrange polynomials on the interval's normalised nodes (D+1,) at the (symbolic) normalised time ``tau``."""
    out = []
    for j in range(nodes.size):
        v: Any = 1.0
        for r in range(nodes.size):
            if r != j:
                v = v * (tau - nodes[r]) / (nodes[j] - nodes[r])
        out.append(v)
    return out


def applies(plant: Plant, chain: int) -> bool:
    """Whether the program bounds the current inside its intervals: the plain DC motor (no effects: an effect
    may change the voltage that reaches the winding, a delay or a deadband, which this closed form does not
    know; such plants keep the back-off rounds) under a held voltage (``chain == 0``). A continuous voltage
    (``chain >= 1``) has no jumps, hence no transients between the nodes; there the extra inequalities bought
    nothing and made IPOPT's path erratic (the continuous-voltage reversal took 34 to 271 iterations depending
    on bounds that never became active)."""
    driven = cast(DrivenPlant, plant)  # the plant answers; no branch on its kind here
    return chain == 0 and driven.voltage_driven and driven.is_nominal and driven.voltage_plant() is not None


def current_terms(plant: Plant, nodes: np.ndarray, chain: int, npx: int, pts: ca.SX, uk: ca.SX, xs: ca.SX,
                  us: ca.SX, hn: ca.SX) -> ca.SX:
    """The current [scaled by ``xs[1]``] at the check points of one interval, shape (len(CHECK_TAU_E),).

    ``nodes`` (D+1,) the interval's normalised node times; ``pts`` (nx, D+1) scaled node values (speed row 0,
    current row 1, the input state row ``npx`` when ``chain >= 1``); ``uk`` the scaled control (the held
    voltage when ``chain == 0``); ``xs`` state scales, ``us`` control scale, ``hn`` the interval's length [s].
    """
    dc = cast(DrivenPlant, plant).voltage_plant()
    assert dc is not None, "current_terms needs a voltage-driven DC motor (see applies)"
    p = dc.params
    tau_e = p.L / p.R

    def w_v(b: list[Any]) -> tuple[Any, Any]:
        w = sum(b[j] * pts[0, j] for j in range(nodes.size)) * xs[0]
        v = uk * us if chain == 0 else sum(b[j] * pts[npx, j] for j in range(nodes.size)) * xs[npx]
        return w, v

    w0, v0 = w_v(_basis(nodes, 0.0))
    i_s0 = (v0 - p.k_e * w0) / p.R
    i0 = pts[1, 0] * xs[1]
    out = []
    for c in CHECK_TAU_E:
        t = ca.fmin(c * tau_e, hn)
        w, v = w_v(_basis(nodes, t / hn))
        # eq:dc_electrical  L i' = V - R i - k_e w, solved for i_s linear in t
        i_s = (v - p.k_e * w) / p.R
        b = (i_s - i_s0) / t
        out.append((i_s - b * tau_e + (i0 - i_s0 + b * tau_e) * ca.exp(-t / tau_e)) / xs[1])
    return ca.vertcat(*out)


def path_bounds(backoff: np.ndarray, margin: float = PATH_MARGIN) -> np.ndarray:
    """Bounds (|current| / limit) of the check points, per interval (P, N) -> (P*N*len(CHECK_TAU_E),)."""
    return np.repeat(np.ravel(backoff) * (1.0 - margin), len(CHECK_TAU_E))
