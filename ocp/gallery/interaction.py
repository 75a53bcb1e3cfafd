"""Section IV-B of the seed paper: impedance and admittance thrust references on eq. motivating_plant.

The mass is commanded to follow ``x_r = 0.35 t`` under ``f_e = 0.6 sin(2 pi t + 5 pi/2)``. Assuming the
actuator reproduces the thrust exactly (``x2 = x2d``), the channel ``x0' = x1, x1' = x2d + f_e`` is
integrated with the controller's reference in the loop; the reference then crosses zero linearly and
the ideal input of eq. tracking_u_motiv is singular there (Theorem 1, r = 2).

**Actuator-aware version.** Each linear crossing ``t_s`` (slope ``a``) is replaced, on a signal level,
by a flat odd-order crossing: ``x~ = chi M + (1 - chi) x2d`` with ``M = alpha (t - t_s)^p``,
``alpha = a / h^(p-1)`` (so ``M = x2d`` to first order at ``|t - t_s| = h``), ``chi = 1`` for
``|t - t_s| <= flat`` falling smoothly (C-infinity) to 0 at ``flat + blend = h`` -- the local reversal
construction of Section IV-A with a smooth blend. ``M`` and ``x2d`` share their sign on each side of
``t_s``, so the blend adds no zero; the crossing order becomes ``p`` and the input stays bounded. The
interaction controller's state is not re-simulated under the shaped thrust (the shaping is a filter
between the interaction controller and the actuator).

Choices the paper leaves open (documented defaults of :class:`InteractionSetup`): normalised drag
``k = 0.5``; the mass and the compliant trajectory start at rest at the origin; horizon 4 s.
Quantities are normalised (paper Section II), so they carry no SI units.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ocp.errors import MissionError, SolverError


class Law(StrEnum):
    """Interaction law generating the thrust reference."""

    IMPEDANCE = "impedance"
    ADMITTANCE = "admittance"


@dataclass(frozen=True)
class InteractionSetup:
    """Constants of Section IV-B (paper values) and the choices it leaves open (documented here).

    Attributes:
        slope: reference velocity of ``x_r = slope t``
        force_amplitude, force_frequency, force_phase: ``f_e = a sin(2 pi f t + phase)``
        m_i, b_i, k_i: impedance mass, damping, stiffness (eq. motivating_imp)
        m_a, b_a, k_a, k_p, k_v: admittance model and inner-loop gains (eqs. motivating_adm*)
        k: normalised drag of eq. motivating_plant (not given in the paper; chosen)
        duration: horizon [normalised time]
        order: crossing order p of the shaped reversals (5: continuous voltage, Table I)
        flat, blend: half-width of the pure monomial and of the blend around each crossing
        u_bound: input bound of the figure, U = [-u_bound, u_bound]; above the ideal input's peak away
            from the reversals (about 3.7 impedance, 11.5 admittance at start-up), so only the
            reversals can violate it
    """

    slope: float = 0.35
    force_amplitude: float = 0.6
    force_frequency: float = 1.0
    force_phase: float = 2.5 * math.pi
    m_i: float = 0.65
    b_i: float = 3.5
    k_i: float = 5.0
    m_a: float = 0.60
    b_a: float = 3.0
    k_a: float = 4.5
    k_p: float = 7.0
    k_v: float = 5.5
    k: float = 0.5
    duration: float = 4.0
    order: int = 5
    flat: float = 0.02
    blend: float = 0.15
    u_bound: float = 12.0

    def force(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """(f_e, f_e') at ``t``."""
        w = 2.0 * math.pi * self.force_frequency
        arg = w * np.asarray(t, dtype=float) + self.force_phase
        return self.force_amplitude * np.sin(arg), self.force_amplitude * w * np.cos(arg)


def _impedance(s: InteractionSetup) -> Callable[[float, np.ndarray], tuple[list[float], float, float]]:
    """State (x0, x1) -> (state derivative, x2d, x2d')."""

    def f(t: float, x: np.ndarray) -> tuple[list[float], float, float]:
        x0, x1 = x
        fe, dfe = s.force(t)
        xr, dxr, ddxr = s.slope * t, s.slope, 0.0
        # eq:motivating_imp
        x2d = ddxr - s.b_i / s.m_i * (x1 - dxr) - s.k_i / s.m_i * (x0 - xr) + (1.0 / s.m_i - 1.0) * fe
        dx1 = x2d + fe  # eq:motivating_plant with x2 = x2d
        dx2d = -s.b_i / s.m_i * (dx1 - ddxr) - s.k_i / s.m_i * (x1 - dxr) + (1.0 / s.m_i - 1.0) * dfe
        return [x1, dx1], float(x2d), float(dx2d)

    return f


def _admittance(s: InteractionSetup) -> Callable[[float, np.ndarray], tuple[list[float], float, float]]:
    """State (x0, x1, xa, xa') -> (state derivative, x2d, x2d')."""

    def f(t: float, x: np.ndarray) -> tuple[list[float], float, float]:
        x0, x1, xa, va = x
        fe, dfe = s.force(t)
        xr, dxr, ddxr = s.slope * t, s.slope, 0.0
        # eq:motivating_adm_model
        aa = ddxr + (fe - s.b_a * (va - dxr) - s.k_a * (xa - xr)) / s.m_a
        ja = (dfe - s.b_a * (aa - ddxr) - s.k_a * (va - dxr)) / s.m_a
        # eq:motivating_adm
        x2d = aa - fe - s.k_v * (x1 - va) - s.k_p * (x0 - xa)
        dx1 = x2d + fe
        dx2d = ja - dfe - s.k_v * (dx1 - aa) - s.k_p * (x1 - va)
        return [x1, dx1, va, aa], float(x2d), float(dx2d)

    return f


@dataclass(frozen=True)
class InteractionReference:
    """Ideal and shaped references of one law on the grid ``t`` (all arrays shape (N,)).

    Attributes:
        x2d, dx2d: ideal thrust reference and its derivative
        u_ideal: eq. tracking_u_motiv along the ideal reference (+-inf where x2d = 0, x2d' != 0)
        x2s, dx2s, u_shaped: the same for the shaped reference
        crossings: zeros of x2d [time], refined to 1e-12
        slopes: x2d' at each crossing
        x2d_at: exact ideal (x2d, x2d') at any time (dense solution), for limits near crossings
    """

    law: Law
    t: np.ndarray
    x2d: np.ndarray
    dx2d: np.ndarray
    u_ideal: np.ndarray
    x2s: np.ndarray
    dx2s: np.ndarray
    u_shaped: np.ndarray
    crossings: tuple[float, ...]
    slopes: tuple[float, ...]
    x2d_at: Callable[[float], tuple[float, float]]


# eq:tracking_u_motiv
def tracking_input(x2d: np.ndarray, dx2d: np.ndarray, k: float) -> np.ndarray:
    """``u = k x2d + x2d' / (2 sqrt|x2d|)``; +-inf where ``x2d = 0`` and ``x2d' != 0``, 0 if both vanish."""
    x, dx = np.asarray(x2d, dtype=float), np.asarray(dx2d, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = k * x + dx / (2.0 * np.sqrt(np.abs(x)))
    return np.where((x == 0) & (dx == 0), 0.0, u)


def _smooth_step(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """C-infinity step psi(x) (0 for x <= 0, 1 for x >= 1) and psi'(x); shapes of ``x``."""

    def f(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        zz = np.where(z > 1e-3, z, 1.0)
        e = np.where(z > 1e-3, np.exp(-1.0 / zz), 0.0)
        return e, e / zz**2

    g, g1 = f(x)
    h, h1 = f(1.0 - x)
    return g / (g + h), (g1 * h + g * h1) / (g + h) ** 2


def shape_reversals(t: np.ndarray, x2d: np.ndarray, dx2d: np.ndarray, crossings: tuple[float, ...],
                    slopes: tuple[float, ...], order: int, flat: float, blend: float) -> tuple[np.ndarray, np.ndarray]:
    """Replace each linear crossing by ``alpha (t - t_s)^order`` blended in (module doc); returns (x~, x~')."""
    if order < 3 or order % 2 == 0:
        raise MissionError("order", "shaped reversals need an odd order >= 3 to change sign with bounded input")
    h = flat + blend
    if len(crossings) > 1 and np.min(np.diff(crossings)) <= 2.0 * h:
        raise MissionError("flat", f"reversal windows (+-{h}) overlap; reduce flat/blend")
    xs, dxs = np.array(x2d, dtype=float), np.array(dx2d, dtype=float)
    for ts, a in zip(crossings, slopes, strict=True):
        s = t - ts
        win = np.abs(s) < h
        alpha = a / h ** (order - 1)
        m, dm = alpha * s[win] ** order, alpha * order * s[win] ** (order - 1)
        psi, dpsi = _smooth_step((np.abs(s[win]) - flat) / blend)
        chi, dchi = 1.0 - psi, -dpsi * np.sign(s[win]) / blend
        xw, dxw = x2d[win], dx2d[win]
        xs[win] = chi * m + (1.0 - chi) * xw
        dxs[win] = dchi * (m - xw) + chi * dm + (1.0 - chi) * dxw
    return xs, dxs


def interaction_reference(law: Law, setup: InteractionSetup | None = None,
                          rate: float = 1000.0) -> InteractionReference:
    """Ideal and shaped thrust references of ``law`` sampled at ``rate`` [1/normalised time]."""
    from scipy.integrate import solve_ivp  # here: the server imports this module for ``Law`` (scipy: ~0.6 s)
    from scipy.optimize import brentq

    s = InteractionSetup() if setup is None else setup
    model = _impedance(s) if law is Law.IMPEDANCE else _admittance(s)
    x0 = np.zeros(2 if law is Law.IMPEDANCE else 4)  # at rest at the origin
    t = np.linspace(0.0, s.duration, round(s.duration * rate) + 1)
    sol = solve_ivp(lambda tt, x: model(tt, x)[0], (0.0, s.duration), x0, method="DOP853", t_eval=t,
                    dense_output=True, rtol=1e-11, atol=1e-12)
    if not sol.success:
        raise SolverError("interaction", f"integration failed: {sol.message}")

    def at(tt: float) -> tuple[float, float]:
        _, x2, dx2 = model(tt, sol.sol(tt))
        return x2, dx2

    pairs = [at(float(tt)) for tt in t]
    x2d, dx2d = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
    crossings = tuple(brentq(lambda tt: at(tt)[0], t[k], t[k + 1], xtol=1e-14)
                      for k in np.flatnonzero(x2d[:-1] * x2d[1:] < 0))
    slopes = tuple(at(ts)[1] for ts in crossings)
    x2s, dx2s = shape_reversals(t, x2d, dx2d, crossings, slopes, s.order, s.flat, s.blend)
    return InteractionReference(law=law, t=t, x2d=x2d, dx2d=dx2d, u_ideal=tracking_input(x2d, dx2d, s.k),
                                x2s=x2s, dx2s=dx2s, u_shaped=tracking_input(x2s, dx2s, s.k),
                                crossings=crossings, slopes=slopes, x2d_at=at)
